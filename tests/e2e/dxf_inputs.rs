//! Issue 18: DXF parts written the ways CAD programs write them, by another library than
//! ours (ezdxf, `dxf_inputs.py`), nested by `spinvalence nest`. For every case the sheets
//! must hold the right parts, checked from the sheet DXFs alone with this file's own
//! arithmetic (only the polygon area and point-to-polygon distance primitives come from
//! `sv_geom::planar`, unit-tested there): the part's area within 0.1 %, its hole count,
//! and its shape: the points
//! ezdxf's side put on each outline and hole, moved by the part's placement in
//! `nest.json`, lie on the sheet's contours (a mirrored or misread part puts them off).
//! Cases that cannot be read right are refused with one line; every repair is reported
//! (the words each case expects are in its notes in `nest.json`).

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use serde_json::Value;
use sv_geom::planar::{boundary_distance, polygon_area};

use crate::build::NEST_WORK;
use crate::ezdxf::{audit_foreign_sheets, venv_python};
use crate::sheets::{parts_of, SheetPart};
use crate::util::{dxf_entities, num, read_json, Dir};

/// How far (mm) an expected point may lie from the sheet contour: the reader's join
/// (half of 0.05 mm where a gap was closed) and arc (0.01 mm) tolerances and this
/// file's chords (0.01 mm).
const ON_CONTOUR: f64 = 0.06;

/// Writes the cases into `dir/in` (with `many` parts in the big one); returns cases.json.
fn generate(dir: &Dir, many: usize) -> Value {
    let out = dir.join("in");
    std::fs::create_dir_all(&out).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/e2e/dxf_inputs.py");
    let run = Command::new(venv_python())
        .arg(script)
        .arg(&out)
        .arg(many.to_string())
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    read_json(&out.join("cases.json"))
}

fn pt(v: &Value) -> [f64; 2] {
    [num(&v[0], "x"), num(&v[1], "y")]
}

fn points(v: &Value) -> Vec<[f64; 2]> {
    v.as_array().unwrap().iter().map(pt).collect()
}

/// A part read back from a sheet with its placement.
struct Placed {
    id: String,
    part: SheetPart,
    rotation_deg: f64,
    translation: [f64; 2],
}

/// Every part on the sheets of `dir/out`, in placement order, with nest.json.
fn placed(dir: &Dir, out: &str) -> (Vec<Placed>, Value) {
    let nest = read_json(&dir.join(&format!("{out}/nest.json")));
    let mut files: Vec<String> = dir
        .entries(&format!("{out}/sheets"))
        .into_iter()
        .filter(|f| f.ends_with(".dxf"))
        .collect();
    files.sort();
    let mut all = Vec::new();
    for (sheet, file) in nest["sheets"].as_array().unwrap().iter().zip(&files) {
        let text = std::fs::read_to_string(dir.join(&format!("{out}/sheets/{file}"))).unwrap();
        let parts = parts_of(file, &dxf_entities(&text));
        let placements = sheet["placements"].as_array().unwrap();
        assert_eq!(parts.len(), placements.len(), "{file}");
        for (part, p) in parts.into_iter().zip(placements) {
            all.push(Placed {
                id: p["strip"].as_str().unwrap().to_string(),
                part,
                rotation_deg: num(&p["rotation_deg"], "rotation"),
                translation: pt(&p["translation"]),
            });
        }
    }
    (all, nest)
}

/// Whether the sheet part `p` is the expected part `e` (area, holes, shape).
fn matches(p: &Placed, e: &Value) -> Result<(), String> {
    let holes = e["holes"].as_u64().unwrap() as usize;
    if p.part.holes.len() != holes {
        return Err(format!("{} holes, expected {holes}", p.part.holes.len()));
    }
    let area = polygon_area(&p.part.outline).abs()
        - p.part
            .holes
            .iter()
            .map(|h| polygon_area(h).abs())
            .sum::<f64>();
    let want = num(&e["area"], "area");
    if (area - want).abs() > 1e-3 * want {
        return Err(format!("area {area:.3} mm^2, expected {want:.3}"));
    }
    let (s, c) = p.rotation_deg.to_radians().sin_cos();
    let place = |q: [f64; 2]| {
        [
            c * q[0] - s * q[1] + p.translation[0],
            s * q[0] + c * q[1] + p.translation[1],
        ]
    };
    let worst = points(&e["outline"])
        .into_iter()
        .map(|q| boundary_distance(place(q), &p.part.outline))
        .fold(0.0, f64::max);
    if worst > ON_CONTOUR {
        return Err(format!(
            "an outline point {worst:.3} mm off the sheet's outline"
        ));
    }
    for (k, h) in e["hole_points"].as_array().unwrap().iter().enumerate() {
        let worst = points(h)
            .into_iter()
            .map(|q| {
                p.part
                    .holes
                    .iter()
                    .map(|sheet_hole| boundary_distance(place(q), sheet_hole))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        if worst > ON_CONTOUR {
            return Err(format!("a point of hole {k} {worst:.3} mm off every hole"));
        }
    }
    Ok(())
}

/// The parts of `case` on the sheets are its expected parts, each once; its notes hold
/// the words it expects.
fn check_case(case: &Value, all: &[Placed], nest: &Value) {
    let file = case["file"].as_str().unwrap();
    let stem = file.trim_end_matches(".dxf");
    let mine: Vec<&Placed> = all
        .iter()
        .filter(|p| p.id == stem || p.id.strip_prefix(stem).is_some_and(|r| r.starts_with('#')))
        .collect();
    let expected = case["parts"].as_array().unwrap();
    assert_eq!(mine.len(), expected.len(), "{file}: parts on the sheets");
    let mean = |v: &[[f64; 2]]| {
        let n = v.len() as f64;
        v.iter()
            .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n])
    };
    let centres: Vec<[f64; 2]> = expected
        .iter()
        .map(|e| mean(&points(&e["outline"])))
        .collect();
    let mut used = vec![false; expected.len()];
    for p in &mine {
        // the expected parts about where this one came from (its centre moved back)
        let c = mean(&p.part.outline);
        let (s, k) = p.rotation_deg.to_radians().sin_cos();
        let (dx, dy) = (c[0] - p.translation[0], c[1] - p.translation[1]);
        let back = [k * dx + s * dy, -s * dx + k * dy];
        let reach = p
            .part
            .outline
            .iter()
            .map(|q| (q[0] - c[0]).hypot(q[1] - c[1]))
            .fold(0.0, f64::max);
        let mut why = Vec::new();
        let hit = (0..expected.len()).find(|&k| {
            !used[k]
                && (centres[k][0] - back[0]).hypot(centres[k][1] - back[1]) <= reach
                && match matches(p, &expected[k]) {
                    Ok(()) => true,
                    Err(w) => {
                        why.push(format!("part {k}: {w}"));
                        false
                    }
                }
        });
        match hit {
            Some(k) => used[k] = true,
            None => panic!("{file}: {} is none of the expected parts: {why:?}", p.id),
        }
    }
    let notes: Vec<String> = nest["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|n| n["file"].as_str().unwrap().ends_with(file))
        .map(|n| n.to_string())
        .collect();
    for word in case["notes"].as_array().unwrap() {
        let word = word.as_str().unwrap();
        assert!(
            notes.iter().any(|n| n.contains(word)),
            "{file}: no note says {word:?}: {notes:?}"
        );
    }
}

#[test]
fn foreign_dxf_parts_nest_as_drawn_or_are_refused_in_one_line() {
    let dir = Dir::new();
    let cases = generate(&dir, 1);
    let cases = cases["cases"].as_array().unwrap();
    let together: Vec<&Value> = cases
        .iter()
        .filter(|c| !c["alone"].as_bool().unwrap())
        .collect();
    // a fixed work budget: the clock never cuts the search (its warning would be on stderr)
    let mut args: Vec<String> = ["nest", "--out", "n"]
        .iter()
        .chain(&NEST_WORK)
        .map(|s| s.to_string())
        .collect();
    args.extend(
        together
            .iter()
            .map(|c| format!("in/{}", c["file"].as_str().unwrap())),
    );
    let argv: Vec<&str> = args.iter().map(String::as_str).collect();
    let run = dir.run(&argv);
    run.expect_code(0);
    // nothing is left out: every case of the run is read right
    assert!(run.stderr.is_empty(), "{run:?}");
    let (all, nest) = placed(&dir, "n");
    assert!(
        nest["left_out"].as_array().unwrap().is_empty(),
        "{}",
        nest["left_out"]
    );
    for case in &together {
        check_case(case, &all, &nest);
    }
    // the sheets, foreign parts and all: ezdxf's audit clean (0 errors, 0 fixes), every
    // contour in the documented direction, the etching first, the text inside the extents
    let sheets: Vec<std::path::PathBuf> = dir
        .entries("n/sheets")
        .into_iter()
        .filter(|f| f.ends_with(".dxf"))
        .map(|f| dir.join(&format!("n/sheets/{f}")))
        .collect();
    audit_foreign_sheets(&sheets);
    // every note is on stdout too, once
    for n in nest["notes"].as_array().unwrap() {
        let what = n["what"].as_str().unwrap();
        assert!(run.stdout.contains(what), "{what}: {run:?}");
    }
    // the refusals, each alone: exit code 2 and one line that says why
    for case in cases.iter().filter(|c| c["expect"] == "refuse") {
        let file = format!("in/{}", case["file"].as_str().unwrap());
        let run = dir.run(&["nest", &file, "--out", "r"]);
        run.expect_code(2);
        let line = run.one_error_line();
        assert!(
            line.contains(case["message"].as_str().unwrap())
                && line.contains(case["file"].as_str().unwrap()),
            "{line}"
        );
        assert!(!dir.join("r/nest.json").exists());
    }
}

#[test]
fn two_thousand_parts_in_one_file_all_nest_once() {
    let dir = Dir::new();
    let cases = generate(&dir, 2000);
    let case = cases["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["file"] == "many_parts.dxf")
        .unwrap()
        .clone();
    let run = dir.run(&[
        "nest",
        "in/many_parts.dxf",
        "--nest-seconds",
        "1",
        "--quiet",
        "--out",
        "n",
    ]);
    run.expect_code(0);
    let (all, nest) = placed(&dir, "n");
    assert_eq!(all.len(), 2000);
    let ids: HashMap<&str, usize> = all.iter().map(|p| (p.id.as_str(), 0)).collect();
    assert_eq!(ids.len(), 2000, "every part once");
    check_case(&case, &all, &nest);
}
