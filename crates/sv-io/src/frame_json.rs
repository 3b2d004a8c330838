//! `frame.json` version 2 (docs/frame-format.md): writer and checking reader.

use serde::Deserialize;
use serde_json::Value;
use sv_frame::{
    FrameFile, FrameParams, LinkRecord, MeshData, SolveSummary, UnitRecord, FRAME_FORMAT,
};

use crate::IoError;

/// The `version` this build reads and writes.
pub use sv_frame::FRAME_VERSION;
/// The `length_unit` of every frame file.
pub const FRAME_LENGTH_UNIT: &str = "mm";

/// `file` as pretty-printed JSON (two-space indent, fields in the order of the
/// [`FrameFile`] structs, so the output is stable from run to run), ending with a newline.
/// Non-finite numbers are written as `null`, which [`frame_from_json`] rejects.
pub fn frame_to_json(file: &FrameFile) -> String {
    // FrameFile is plain data with string keys: serialising it cannot fail
    let text = serde_json::to_string_pretty(file)
        .expect("internal: a FrameFile always serialises to JSON");
    let mut text = inline_number_arrays(&text);
    text.push('\n');
    text
}

/// Put every array of plain numbers on one line (`[x, y, z]`) in pretty-printed JSON:
/// a 10,000-unit frame shrinks to about a third and reads point by point.
pub fn inline_number_arrays(pretty: &str) -> String {
    let lines: Vec<&str> = pretty.lines().collect();
    let mut out = String::with_capacity(pretty.len() / 2);
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        if line.ends_with('[') {
            // the elements up to the closing bracket, if every one is a number
            let mut j = i + 1;
            let mut items = Vec::new();
            while j < lines.len() {
                let item = lines[j].trim();
                if item.starts_with(']') {
                    break;
                }
                let bare = item.strip_suffix(',').unwrap_or(item);
                if bare.parse::<f64>().is_err() {
                    break;
                }
                items.push(bare);
                j += 1;
            }
            if j < lines.len() && lines[j].trim().starts_with(']') && !items.is_empty() {
                out.push_str(line);
                out.push_str(&items.join(", "));
                out.push_str(lines[j].trim());
                out.push('\n');
                i = j + 1;
                continue;
            }
        }
        out.push_str(line);
        out.push('\n');
        i += 1;
    }
    out.pop();
    out
}

/// Read and check a frame file. `name` is the file name used in messages.
///
/// Checks, in order: JSON syntax; `format == "spin-valence/frame"`, `version == 1`,
/// `length_unit == "mm"`; the shape of the coordinate and index arrays (points of 3
/// numbers, faces and corner lists of 4, `units`/`edge` pairs); the fields of every record;
/// every number finite; `mesh.faces`, unit `face`, link `units` and link `edge` indices in
/// range. Extra fields are accepted (and not kept).
///
/// # Errors
/// Syntax errors with line and column (`frame.json:12:5: expected ...`), other errors with
/// the JSON path of the value (`frame.json: units[3].hub[2]: expected [x, y, z], got 2
/// numbers`).
pub fn frame_from_json(text: &str, name: &str) -> Result<FrameFile, IoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(IoError::whole(
            name,
            "empty file (expected a frame.json object)",
        ));
    }
    let value: Value = serde_json::from_str(text).map_err(|e| syntax_error(&e, name))?;
    let Value::Object(root) = &value else {
        return Err(IoError::whole(
            name,
            format!(
                "expected a JSON object at the top level, got {}",
                kind(&value)
            ),
        ));
    };
    check_header(root, name)?;
    check_shapes(&value, name)?;
    let file = match FrameFile::deserialize(&value) {
        Ok(file) => file,
        Err(e) => {
            return Err(locate_record_error(&value, name)
                .unwrap_or_else(|| IoError::whole(name, e.to_string())))
        }
    };
    check_finite(&file, name)?;
    check_indices(&file, name)?;
    Ok(file)
}

/// A serde_json syntax error as `file:line:column: message`, the message lowercase and
/// without serde_json's own position suffix.
fn syntax_error(e: &serde_json::Error, name: &str) -> IoError {
    let full = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let message = full.strip_suffix(&suffix).unwrap_or(&full);
    let message = match message.strip_prefix("EOF") {
        Some(rest) => format!("unexpected end of file{rest}"),
        None => message.to_string(),
    };
    IoError::JsonSyntax {
        file: name.to_string(),
        line: e.line(),
        column: e.column().max(1),
        message,
    }
}

/// What kind of JSON value `v` is, for messages.
fn kind(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => format!("the string {}", Value::String(s.chars().take(40).collect())),
        Value::Array(a) => format!("an array of {}", a.len()),
        Value::Object(_) => "an object".into(),
    }
}

fn check_header(root: &serde_json::Map<String, Value>, name: &str) -> Result<(), IoError> {
    let expect_str = |key: &str, want: &str| match root.get(key) {
        Some(Value::String(s)) if s == want => Ok(()),
        Some(other) => Err(IoError::value(
            name,
            key,
            format!("expected \"{want}\", got {}", kind(other)),
        )),
        None => Err(IoError::value(
            name,
            key,
            format!("missing; a frame file has \"{key}\": \"{want}\""),
        )),
    };
    expect_str("format", FRAME_FORMAT)?;
    match root.get("version") {
        Some(Value::Number(n)) if n.as_u64() == Some(u64::from(FRAME_VERSION)) => {}
        Some(Value::Number(n)) if n.as_u64() == Some(1) => {
            return Err(IoError::value(
                name,
                "version",
                format!(
                    "version 1 describes the paper's zero-width units, not the parts as cut; \
                     rebuild the frame with this build (it reads version {FRAME_VERSION})"
                ),
            ))
        }
        Some(other) => {
            return Err(IoError::value(
                name,
                "version",
                format!("unsupported version {other} (this build reads version {FRAME_VERSION})"),
            ))
        }
        None => {
            return Err(IoError::value(
                name,
                "version",
                format!("missing; expected {FRAME_VERSION}"),
            ))
        }
    }
    expect_str("length_unit", FRAME_LENGTH_UNIT)
}

/// Look up `a.b` in an object tree; `None` when any step is missing.
fn get<'v>(v: &'v Value, keys: &[&str]) -> Option<&'v Value> {
    keys.iter().try_fold(v, |v, k| v.get(k))
}

/// If `v` is an array, check it has `len` elements that are numbers (or, with `index`,
/// non-negative integers). Other types are left to the typed reader.
fn check_tuple(
    v: &Value,
    path: &str,
    len: usize,
    what: &str,
    index: bool,
    name: &str,
) -> Result<(), IoError> {
    let Value::Array(items) = v else {
        return Ok(());
    };
    if items.len() != len {
        return Err(IoError::value(
            name,
            path,
            format!("expected {what}, got {} elements", items.len()),
        ));
    }
    for (k, item) in items.iter().enumerate() {
        let ok = if index {
            item.as_u64().is_some()
        } else {
            item.is_number()
        };
        if !ok {
            let want = if index {
                "a non-negative integer index"
            } else {
                "a number"
            };
            return Err(IoError::value(
                name,
                format!("{path}[{k}]"),
                format!("expected {want}, got {}", kind(item)),
            ));
        }
    }
    Ok(())
}

/// Array lengths and element types of the coordinate and index arrays, with paths.
fn check_shapes(root: &Value, name: &str) -> Result<(), IoError> {
    let elements = |keys: &[&str]| -> &[Value] {
        get(root, keys)
            .and_then(Value::as_array)
            .map_or(&[], Vec::as_slice)
    };
    for (i, p) in elements(&["mesh", "vertices"]).iter().enumerate() {
        check_tuple(
            p,
            &format!("mesh.vertices[{i}]"),
            3,
            "[x, y, z]",
            false,
            name,
        )?;
    }
    for (i, f) in elements(&["mesh", "faces"]).iter().enumerate() {
        check_tuple(
            f,
            &format!("mesh.faces[{i}]"),
            4,
            "4 vertex indices",
            true,
            name,
        )?;
    }
    for (i, unit) in elements(&["units"]).iter().enumerate() {
        for key in ["hub", "primary"] {
            let Some(Value::Array(corners)) = unit.get(key) else {
                continue;
            };
            let path = format!("units[{i}].{key}");
            if corners.len() != 4 {
                return Err(IoError::value(
                    name,
                    path,
                    format!("expected 4 corners, got {}", corners.len()),
                ));
            }
            for (c, p) in corners.iter().enumerate() {
                check_tuple(p, &format!("{path}[{c}]"), 3, "[x, y, z]", false, name)?;
            }
        }
    }
    for (i, link) in elements(&["links"]).iter().enumerate() {
        for key in ["units", "edge"] {
            if let Some(v) = link.get(key) {
                check_tuple(v, &format!("links[{i}].{key}"), 2, "2 indices", true, name)?;
            }
        }
    }
    Ok(())
}

/// The first section or record that does not deserialise, as a path error.
fn locate_record_error(root: &Value, name: &str) -> Option<IoError> {
    fn first<'v, T: Deserialize<'v>>(v: &'v Value, path: &str, name: &str) -> Option<IoError> {
        T::deserialize(v)
            .err()
            .map(|e| IoError::value(name, path, e.to_string()))
    }
    for key in ["params", "mesh", "units", "links"] {
        if root.get(key).is_none() {
            return Some(IoError::value(name, key, "missing"));
        }
    }
    let params = &root["params"];
    let mesh = &root["mesh"];
    first::<FrameParams>(params, "params", name)
        .or_else(|| first::<MeshData>(mesh, "mesh", name))
        .or_else(|| {
            let units = root["units"].as_array()?;
            units
                .iter()
                .enumerate()
                .find_map(|(i, u)| first::<UnitRecord>(u, &format!("units[{i}]"), name))
        })
        .or_else(|| {
            let links = root["links"].as_array()?;
            links
                .iter()
                .enumerate()
                .find_map(|(i, l)| first::<LinkRecord>(l, &format!("links[{i}]"), name))
        })
        .or_else(|| first::<Option<SolveSummary>>(root.get("solve")?, "solve", name))
        .or_else(|| {
            ["units", "links"]
                .into_iter()
                .find(|k| !root[*k].is_array())
                .map(|k| {
                    IoError::value(
                        name,
                        k,
                        format!("expected an array, got {}", kind(&root[k])),
                    )
                })
        })
}

/// Every number of `file` finite, with the path of the first that is not.
pub(crate) fn check_finite(file: &FrameFile, name: &str) -> Result<(), IoError> {
    let bad = |path: String| Err(IoError::value(name, path, "not a finite number"));
    let p = &file.params;
    for (key, x) in [("spin_angle", p.spin_angle), ("expansion", p.expansion)] {
        if !x.is_finite() {
            return bad(format!("params.{key}"));
        }
    }
    for (i, v) in file.mesh.vertices.iter().enumerate() {
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return bad(format!("mesh.vertices[{i}][{k}]"));
        }
    }
    for (i, u) in file.units.iter().enumerate() {
        for (key, x) in [
            ("theta", u.theta),
            ("phi", u.phi),
            ("depth", u.depth.unwrap_or(0.0)),
        ] {
            if !x.is_finite() {
                return bad(format!("units[{i}].{key}"));
            }
        }
        for (key, corners) in [("hub", &u.hub), ("primary", &u.primary)] {
            for (c, p) in corners.iter().enumerate() {
                if p.iter().any(|x| !x.is_finite()) {
                    return bad(format!("units[{i}].{key}[{c}]"));
                }
            }
        }
    }
    for (i, l) in file.links.iter().enumerate() {
        for (key, x) in [
            ("primary_gap", l.primary_gap),
            ("hub_overlap", l.hub_overlap),
        ] {
            if !x.is_finite() {
                return bad(format!("links[{i}].{key}"));
            }
        }
    }
    if let Some(s) = &file.solve {
        let fields = [
            ("gap_sum_start", s.gap_sum_start),
            ("gap_sum", s.gap_sum),
            ("gap_max", s.gap_max),
            ("planarity_max", s.planarity_max),
            ("conical_max", s.conical_max),
        ];
        for (key, x) in fields {
            if !x.is_finite() {
                return bad(format!("solve.{key}"));
            }
        }
    }
    Ok(())
}

/// Every index of `file` in range, with the path of the first that is not.
fn check_indices(file: &FrameFile, name: &str) -> Result<(), IoError> {
    let (nv, nf, nu) = (
        file.mesh.vertices.len(),
        file.mesh.faces.len(),
        file.units.len(),
    );
    let out = |path: String, index: usize, n: usize, what: &str| {
        Err(IoError::value(
            name,
            path,
            format!("index {index} out of range (file has {n} {what})"),
        ))
    };
    for (i, f) in file.mesh.faces.iter().enumerate() {
        if let Some(k) = f.iter().position(|&v| v >= nv) {
            return out(format!("mesh.faces[{i}][{k}]"), f[k], nv, "vertices");
        }
    }
    for (i, u) in file.units.iter().enumerate() {
        if u.face >= nf {
            return out(format!("units[{i}].face"), u.face, nf, "faces");
        }
    }
    for (i, l) in file.links.iter().enumerate() {
        if let Some(k) = l.units.iter().position(|&u| u >= nu) {
            return out(format!("links[{i}].units[{k}]"), l.units[k], nu, "units");
        }
        if let Some(k) = l.edge.iter().position(|&v| v >= nv) {
            return out(format!("links[{i}].edge[{k}]"), l.edge[k], nv, "vertices");
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn number_arrays_go_on_one_line_and_parse_the_same() {
        let v = serde_json::json!({"a": [[1.5, -2.0e-7, 3], [4, 5, 6]], "b": ["x", "y"], "c": [], "d": {"e": [7]}});
        let pretty = serde_json::to_string_pretty(&v).unwrap();
        let inline = inline_number_arrays(&pretty);
        assert!(
            inline.contains("[\n    [1.5, -2e-7, 3],\n    [4, 5, 6]\n  ]"),
            "{inline}"
        );
        assert!(inline.contains("\"e\": [7]"), "{inline}");
        // strings stay one per line
        assert!(inline.contains("\"x\",\n"), "{inline}");
        let back: serde_json::Value = serde_json::from_str(&inline).unwrap();
        assert_eq!(back, v);
    }

    /// A small, hand-made frame: two flat units side by side, primary tiles 50 mm below.
    pub(crate) fn two_units() -> FrameFile {
        let square = |x0: f64, z: f64| {
            [
                [x0, 0.0, z],
                [x0 + 100.0, 0.0, z],
                [x0 + 100.0, 100.0, z],
                [x0, 100.0, z],
            ]
        };
        let unit = |i: usize| UnitRecord {
            id: format!("A{i}"),
            face: i,
            strip: "A".into(),
            theta: std::f64::consts::FRAC_PI_4,
            phi: 0.0,
            hub: square(100.0 * i as f64, 0.0),
            primary: square(100.0 * i as f64, -50.0),
            axis_case: None,
            side: None,
            depth: Some(50.0),
            hub_plate: None,
            pins: None,
            spin: None,
            tile_scale: None,
            hub_lift: None,
        };
        FrameFile {
            format: FRAME_FORMAT.into(),
            version: FRAME_VERSION,
            length_unit: "mm".into(),
            params: FrameParams {
                thickness: None,
                joint_limits: None,
                hub_lap: None,
                hub_laps_touch: false,
                spin_angle: std::f64::consts::FRAC_PI_4,
                expansion: 1.0,
                cut: None,
            },
            mesh: MeshData {
                vertices: vec![
                    [0.0, 0.0, 0.0],
                    [100.0, 0.0, 0.0],
                    [200.0, 0.0, 0.0],
                    [0.0, 100.0, 0.0],
                    [100.0, 100.0, 0.0],
                    [200.0, 100.0, 0.0],
                ],
                faces: vec![[0, 1, 4, 3], [1, 2, 5, 4]],
            },
            units: vec![unit(0), unit(1)],
            links: vec![LinkRecord {
                units: [0, 1],
                edge: [1, 4],
                primary_gap: 0.0,
                hub_overlap: 1.0 / 3.0,
                slots: Some([1, 3]),
                joint: None,
            }],
            solve: None,
        }
    }

    /// Assert that reading `text` fails with exactly `want`.
    fn check(text: &str, want: &str) {
        match frame_from_json(text, "frame.json") {
            Ok(_) => panic!("expected {want:?}, got a frame"),
            Err(e) => assert_eq!(e.to_string(), want),
        }
    }

    /// `two_units()` as JSON with `edit` applied to the value tree.
    fn edited(edit: impl FnOnce(&mut Value)) -> String {
        let mut v = serde_json::to_value(two_units()).unwrap();
        edit(&mut v);
        serde_json::to_string_pretty(&v).unwrap()
    }

    #[test]
    fn round_trip_is_exact_and_stable() {
        let file = two_units();
        let text = frame_to_json(&file);
        let back = frame_from_json(&text, "frame.json").unwrap();
        assert_eq!(back, file);
        assert_eq!(frame_to_json(&back), text);
        let order = [
            "\"format\"",
            "\"version\"",
            "\"length_unit\"",
            "\"params\"",
            "\"mesh\"",
            "\"units\"",
            "\"links\"",
        ];
        let at: Vec<usize> = order.iter().map(|k| text.find(k).unwrap()).collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{at:?}");
        assert!(text.starts_with("{\n  \"format\": \"spin-valence/frame\",\n  \"version\": 2,\n"));
    }

    #[test]
    fn round_trip_of_a_solved_frame() {
        let mesh = sv_frame::QuadMesh::grid(2, 2, 300.0);
        let solved = sv_frame::solve(&mesh, &Default::default(), &mut |_| {}).unwrap();
        let file = solved.to_frame_file(&mesh);
        let back = frame_from_json(&frame_to_json(&file), "frame.json").unwrap();
        // bit for bit, including values such as -2.8421709430404014e-14 that serde_json's
        // default (not float_roundtrip) parser reads 1 ulp off
        assert_eq!(back, file);
    }

    #[test]
    fn extra_fields_are_accepted() {
        let text = edited(|v| {
            v["generator"] = "another tool".into();
            v["units"][0]["mass_kg"] = 1.5.into();
        });
        assert_eq!(frame_from_json(&text, "frame.json").unwrap(), two_units());
    }

    #[test]
    fn header_errors_name_the_field() {
        check(
            &edited(|v| v["format"] = "other".into()),
            "frame.json: format: expected \"spin-valence/frame\", got the string \"other\"",
        );
        check(
            &edited(|v| v["version"] = 3.into()),
            "frame.json: version: unsupported version 3 (this build reads version 2)",
        );
        check(
            &edited(|v| v["length_unit"] = "in".into()),
            "frame.json: length_unit: expected \"mm\", got the string \"in\"",
        );
        check(
            &edited(|v| {
                v.as_object_mut().unwrap().remove("format");
            }),
            "frame.json: format: missing; a frame file has \"format\": \"spin-valence/frame\"",
        );
        check(
            "[1, 2]",
            "frame.json: expected a JSON object at the top level, got an array of 2",
        );
        check(
            "  \n",
            "frame.json: empty file (expected a frame.json object)",
        );
    }

    #[test]
    fn shape_errors_name_the_path() {
        check(
            &edited(|v| v["units"][1]["hub"][2] = serde_json::json!([1.0, 2.0])),
            "frame.json: units[1].hub[2]: expected [x, y, z], got 2 elements",
        );
        check(
            &edited(|v| v["units"][1]["hub"][2][1] = "y".into()),
            "frame.json: units[1].hub[2][1]: expected a number, got the string \"y\"",
        );
        check(
            &edited(|v| {
                v["units"][0]["primary"]
                    .as_array_mut()
                    .unwrap()
                    .pop()
                    .map(drop)
                    .unwrap()
            }),
            "frame.json: units[0].primary: expected 4 corners, got 3",
        );
        check(
            &edited(|v| v["mesh"]["faces"][1] = serde_json::json!([1, 2, 5])),
            "frame.json: mesh.faces[1]: expected 4 vertex indices, got 3 elements",
        );
        check(&edited(|v| v["mesh"]["faces"][0][2] = (-1).into()), "frame.json: mesh.faces[0][2]: expected a non-negative integer index, got the number -1");
        check(
            &edited(|v| v["mesh"]["vertices"][5][0] = serde_json::Value::Null),
            "frame.json: mesh.vertices[5][0]: expected a number, got null",
        );
        check(
            &edited(|v| v["links"][0]["edge"] = serde_json::json!([1, 4, 5])),
            "frame.json: links[0].edge: expected 2 indices, got 3 elements",
        );
    }

    #[test]
    fn record_errors_name_the_record() {
        check(
            &edited(|v| {
                v["units"][1].as_object_mut().unwrap().remove("strip");
            }),
            "frame.json: units[1]: missing field `strip`",
        );
        check(
            &edited(|v| v["units"][0]["theta"] = "45".into()),
            "frame.json: units[0]: invalid type: string \"45\", expected f64",
        );
        check(
            &edited(|v| v["params"]["expansion"] = true.into()),
            "frame.json: params: invalid type: boolean `true`, expected f64",
        );
        check(
            &edited(|v| {
                v.as_object_mut().unwrap().remove("links");
            }),
            "frame.json: links: missing",
        );
        check(
            &edited(|v| v["links"] = 3.into()),
            "frame.json: links: expected an array, got the number 3",
        );
        check(
            &edited(|v| v["solve"] = 3.into()),
            "frame.json: solve: invalid type: integer `3`, expected struct SolveSummary",
        );
    }

    #[test]
    fn index_errors_name_the_path() {
        check(
            &edited(|v| v["units"][1]["face"] = 2.into()),
            "frame.json: units[1].face: index 2 out of range (file has 2 faces)",
        );
        check(
            &edited(|v| v["links"][0]["units"][1] = 7.into()),
            "frame.json: links[0].units[1]: index 7 out of range (file has 2 units)",
        );
        check(
            &edited(|v| v["links"][0]["edge"][0] = 6.into()),
            "frame.json: links[0].edge[0]: index 6 out of range (file has 6 vertices)",
        );
        check(
            &edited(|v| v["mesh"]["faces"][1][3] = 60.into()),
            "frame.json: mesh.faces[1][3]: index 60 out of range (file has 6 vertices)",
        );
    }

    #[test]
    fn syntax_errors_have_line_and_column() {
        let text = frame_to_json(&two_units());
        let nan = text.replacen("\"expansion\": 1.0", "\"expansion\": NaN", 1);
        let line = 1 + nan[..nan.find("NaN").unwrap()].matches('\n').count();
        let e = frame_from_json(&nan, "frame.json").unwrap_err();
        assert!(
            matches!(e, IoError::JsonSyntax { line: l, .. } if l == line),
            "{e:?}"
        );
        assert!(
            e.to_string().starts_with(&format!("frame.json:{line}:")),
            "{e}"
        );
        assert!(e.to_string().ends_with(": expected value"), "{e}");

        let huge = text.replacen("\"expansion\": 1.0", "\"expansion\": 1e400", 1);
        let e = frame_from_json(&huge, "frame.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!("frame.json:{line}:")) && e.contains("out of range"),
            "{e}"
        );

        let cut = &text[..text.len() / 2];
        let e = frame_from_json(cut, "frame.json").unwrap_err().to_string();
        assert!(e.contains(": unexpected end of file while parsing"), "{e}");
        assert!(!e.contains(" at line "), "{e}");
    }

    #[test]
    fn non_finite_values_name_the_path() {
        let mut file = two_units();
        file.units[1].hub[2][1] = f64::INFINITY;
        assert_eq!(
            check_finite(&file, "frame.json").unwrap_err().to_string(),
            "frame.json: units[1].hub[2]: not a finite number"
        );
        let mut file = two_units();
        file.links[0].hub_overlap = f64::NAN;
        assert_eq!(
            check_finite(&file, "frame.json").unwrap_err().to_string(),
            "frame.json: links[0].hub_overlap: not a finite number"
        );
        // written as null, which the reader refuses with the path
        let mut file = two_units();
        file.mesh.vertices[2][1] = f64::NAN;
        check(
            &frame_to_json(&file),
            "frame.json: mesh.vertices[2][1]: expected a number, got null",
        );
    }

    #[test]
    fn mutated_files_never_panic() {
        let text = frame_to_json(&two_units());
        let bytes = text.as_bytes();
        for cut in 0..text.trim_end().len() {
            let t = String::from_utf8_lossy(&bytes[..cut]);
            let e = frame_from_json(&t, "cut.json").unwrap_err();
            assert!(e.to_string().starts_with("cut.json"), "{e}");
        }
        let step = (bytes.len() / 300).max(1);
        for at in (0..bytes.len()).step_by(step) {
            for r in ["", "-", "9", "]", "\"", "null", "1e999", "{}"] {
                let mut m = text.clone();
                if m.is_char_boundary(at) && m.is_char_boundary(at + 1) {
                    m.replace_range(at..at + 1, r);
                    if let Err(e) = frame_from_json(&m, "m.json") {
                        assert!(e.to_string().starts_with("m.json"), "{e}");
                    }
                }
            }
        }
    }
}
