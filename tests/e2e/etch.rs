//! Which face is up (issue 14, item 5), read from the files with our own code: every unit
//! of every strip DXF carries on `ETCH` a circle with a dot (its hub comes out of the etched
//! face, `+z` of the DXF) or with a cross (out of the back), clear of every cut, and the mark
//! says what the poses of `frame.json` say; `strips.json` and `bom.csv` say the same; every
//! etched label reads upright in the strip DXFs and, after the nest's rotation, on the
//! sheets. Only the point-in-polygon and segment-distance primitives come from the library
//! (unit-tested there).

use std::collections::HashMap;
use std::fs;

use serde_json::Value;
use sv_geom::planar::segment_distance;
use sv_nest::part::point_in_polygon;

use crate::build::{default_build, saddle_build};
use crate::report::parse_csv;
use crate::sheets::flatten;
use crate::util::{diagonals_cross, dot3, dxf_entities, num, read_json, sub3, Dir, DxfEntity};

type P = [f64; 2];

fn dist(a: P, b: P) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn corners(v: &Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let c = c.as_array().unwrap();
            [num(&c[0], "x"), num(&c[1], "y"), num(&c[2], "z")]
        })
        .collect()
}

/// Whether the hub of `unit` (a `frame.json` record) comes out towards whoever looks at
/// its flat tile `flat` (corners in frame order, as drawn) from `+z`: the side of the
/// primary tile's plane the hub's centre lies on, against the way round the flat tile runs
/// (counter-clockwise seen from `+z` when it is laid with its normal up, the normal being
/// the one the 3D corners run counter-clockwise about).
fn hub_towards_viewer(unit: &Value, flat: &[P]) -> bool {
    let (p, h) = (corners(&unit["primary"]), corners(&unit["hub"]));
    let n = diagonals_cross(&p);
    let mean = |q: &[[f64; 3]]| {
        let s = q
            .iter()
            .fold([0.0; 3], |a, c| [a[0] + c[0], a[1] + c[1], a[2] + c[2]]);
        s.map(|x| x / q.len() as f64)
    };
    let height = dot3(sub3(mean(&h), mean(&p)), n) / dot3(n, n).sqrt();
    let area: f64 = (0..flat.len())
        .map(|i| {
            let (a, b) = (flat[i], flat[(i + 1) % flat.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    assert!(height.abs() > 1.0 && area.abs() > 1.0, "{height} {area}");
    (height > 0.0) == (area > 0.0)
}

/// A closed ring of many points at one distance from their centre: `(centre, radius)`.
fn ring(e: &DxfEntity) -> Option<(P, f64)> {
    let v: Vec<P> = e.vertices.iter().map(|p| [p[0], p[1]]).collect();
    if v.len() < 25 || dist(v[0], v[v.len() - 1]) > 1e-6 {
        return None;
    }
    let pts = &v[..v.len() - 1];
    let s = pts
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
    let c = [s[0] / pts.len() as f64, s[1] / pts.len() as f64];
    let r = dist(pts[0], c);
    pts.iter()
        .all(|&p| (dist(p, c) - r).abs() < 1e-6)
        .then_some((c, r))
}

/// One face mark read from the ETCH layer.
#[derive(Debug)]
struct Mark {
    at: P,
    radius: f64,
    /// A dot (true) or a cross (false).
    dot: bool,
}

/// The face marks among `etch`: rings with a smaller ring at their centre (a dot) or two
/// bars crossing at their centre inside them (a cross); every ring is one or the other,
/// or the dot of another.
fn marks(name: &str, etch: &[&DxfEntity]) -> Vec<Mark> {
    let rings: Vec<(P, f64)> = etch.iter().filter_map(|e| ring(e)).collect();
    let bars: Vec<(P, P)> = etch
        .iter()
        .filter(|e| e.vertices.len() == 2)
        .map(|e| {
            let v = &e.vertices;
            ([v[0][0], v[0][1]], [v[1][0], v[1][1]])
        })
        .collect();
    let mut out = Vec::new();
    let mut dots = 0;
    for &(c, r) in &rings {
        let is_dot = rings
            .iter()
            .any(|&(c2, r2)| r2 > 2.0 * r && dist(c, c2) < 1e-6);
        if is_dot {
            dots += 1;
            continue;
        }
        let dot = rings
            .iter()
            .any(|&(c2, r2)| r2 < 0.5 * r && dist(c, c2) < 1e-6);
        let crossing = bars
            .iter()
            .filter(|&&(a, b)| {
                let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                dist(mid, c) < 1e-6 && dist(a, c) < r && dist(a, b) > r
            })
            .count();
        assert!(
            dot != (crossing == 2),
            "{name}: the ring at {c:?} has a dot: {dot}, {crossing} bars"
        );
        out.push(Mark {
            at: c,
            radius: r,
            dot,
        });
    }
    assert_eq!(dots, out.iter().filter(|m| m.dot).count(), "{name}");
    out
}

/// Smallest distance from `p` to the closed polyline `q`.
fn to_contour(p: P, q: &[P]) -> f64 {
    (0..q.len())
        .map(|i| segment_distance(p, p, q[i], q[(i + 1) % q.len()]))
        .fold(f64::INFINITY, f64::min)
}

/// Per unit of `dir/out`'s strips, whether its mark says "towards you" (a dot), after
/// checking every strip DXF: one mark per unit on its own tile, clear of every cut by its
/// radius and a minimum web, agreeing with `frame.json` and `strips.json`. Returns
/// `(units marked towards the viewer, units marked away)`.
fn check_face_marks(dir: &Dir) -> (usize, usize) {
    let out = dir.join("out");
    let frame = read_json(&out.join("frame.json"));
    let strips = read_json(&out.join("strips.json"));
    let min_web = num(&strips["params"]["min_web"], "min_web");
    let units = &frame["units"];
    let (mut towards, mut away) = (0, 0);
    let mut marked = 0;
    for strip in strips["strips"].as_array().unwrap() {
        let id = strip["id"].as_str().unwrap();
        let text = fs::read_to_string(out.join(format!("strips/{id}.dxf"))).unwrap();
        let entities = dxf_entities(&text);
        let layer = |l: &str| -> Vec<&DxfEntity> {
            entities
                .iter()
                .filter(|e| e.kind == "LWPOLYLINE" && e.layer == l)
                .collect()
        };
        // the nominal tiles on INFO, in strip order
        let tiles: Vec<Vec<P>> = layer("INFO")
            .into_iter()
            .filter(|e| e.closed && e.vertices.len() == 4)
            .map(|e| e.vertices.iter().map(|p| [p[0], p[1]]).collect())
            .collect();
        let ids: Vec<usize> = strip["units"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| u.as_u64().unwrap() as usize)
            .collect();
        assert_eq!(tiles.len(), ids.len(), "{id}: tiles on INFO");
        let cuts: Vec<Vec<P>> = layer("INSIDE")
            .into_iter()
            .chain(layer("OUTSIDE"))
            .map(|e| flatten(&e.vertices))
            .collect();
        let mut per_unit: Vec<Option<bool>> = vec![None; ids.len()];
        for m in marks(id, &layer("ETCH")) {
            let j = tiles
                .iter()
                .position(|t| point_in_polygon(m.at, t))
                .unwrap_or_else(|| panic!("{id}: a face mark off every tile: {m:?}"));
            assert!(per_unit[j].is_none(), "{id}: two face marks on unit {j}");
            per_unit[j] = Some(m.dot);
            // on material, clear of every cut by its radius and a minimum web
            let clear = cuts
                .iter()
                .map(|c| to_contour(m.at, c))
                .fold(f64::INFINITY, f64::min);
            assert!(
                clear >= m.radius + min_web - 1e-6,
                "{id}: the mark of unit {j} is {clear} mm from a cut (radius {})",
                m.radius
            );
            assert!(m.radius >= 3.0, "{id}: {m:?}");
        }
        for (j, (&u, dot)) in ids.iter().zip(&per_unit).enumerate() {
            let dot = dot.unwrap_or_else(|| panic!("{id}: unit {j} carries no face mark"));
            let want = hub_towards_viewer(&units[u], &tiles[j]);
            assert_eq!(
                dot,
                want,
                "{id}: unit {u} ({}) is marked {} but its hub comes out {}",
                units[u]["id"],
                if dot { "towards you" } else { "away" },
                if want { "towards you" } else { "away" },
            );
            // strips.json says the same
            let face = strip["flat"][j]["hub_face"].as_str();
            assert_eq!(face, Some(if want { "etched" } else { "back" }), "{id}");
            if want {
                towards += 1;
            } else {
                away += 1;
            }
            marked += 1;
        }
    }
    assert_eq!(marked, units.as_array().unwrap().len());
    // bom.csv: the strip's face in its last column
    let bom = parse_csv(&fs::read_to_string(out.join("bom.csv")).unwrap());
    assert_eq!(bom[0].last().map(String::as_str), Some("hub_face"));
    for (row, strip) in bom[1..].iter().zip(strips["strips"].as_array().unwrap()) {
        let faces: Vec<&str> = strip["flat"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t["hub_face"].as_str().unwrap())
            .collect();
        let last = row.last().unwrap();
        if faces.iter().all(|f| *f == faces[0]) {
            assert_eq!(last, faces[0], "{row:?}");
        } else {
            assert!(last.starts_with("mixed: "), "{row:?}");
        }
    }
    (towards, away)
}

/// The baseline direction of the etched `label` (a `strips.json` label, its centre moved
/// to `at`) among the 2-point strokes of `etch`: the single-stroke font draws '-' left to
/// right at half the cap height, so the label's hyphen is the stroke a third of the cap
/// height long whose midpoint lies where the text puts it along its own direction.
fn baseline(etch: &[&DxfEntity], label: &Value, at: P) -> Option<P> {
    let text = label["text"].as_str().unwrap();
    let k = num(&label["height"], "height") / 6.0;
    let n = text.chars().count() as f64;
    let i = text.chars().position(|c| c == '-')? as f64;
    // the hyphen's midpoint along the baseline from the centre (advance 5, glyph "1333")
    let along = -(5.0 * n - 1.0) * k / 2.0 + 5.0 * i * k + 2.0 * k;
    let found: Vec<P> = etch
        .iter()
        .filter(|e| e.vertices.len() == 2)
        .filter_map(|e| {
            let (a, b) = (e.vertices[0], e.vertices[1]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            let d = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let want = [at[0] + along * d[0], at[1] + along * d[1]];
            ((len - 2.0 * k).abs() < 1e-6 && dist(mid, want) < 1e-6).then_some(d)
        })
        .collect();
    assert!(found.len() <= 1, "{text}: {found:?}");
    found.first().copied()
}

/// Whether a baseline direction reads upright: within (-90, 90] degrees of +x.
fn upright(d: P) -> bool {
    d[0] > 1e-9 || (d[0].abs() <= 1e-9 && d[1] > 0.0)
}

/// Every label of `dir/out` read upright in its strip DXF and on its sheet. Returns the
/// number of labels checked on the sheets that the nest turned half round.
fn check_labels_upright(dir: &Dir) -> (usize, usize) {
    let out = dir.join("out");
    let strips = read_json(&out.join("strips.json"));
    let nest = read_json(&out.join("nest.json"));
    let etch_of = |text: &str| -> Vec<DxfEntity> {
        dxf_entities(text)
            .into_iter()
            .filter(|e| e.kind == "LWPOLYLINE" && e.layer == "ETCH")
            .collect()
    };
    let by_id: HashMap<&str, &Value> = strips["strips"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| (s["id"].as_str().unwrap(), s))
        .collect();
    for (id, strip) in &by_id {
        let etch = etch_of(&fs::read_to_string(out.join(format!("strips/{id}.dxf"))).unwrap());
        let etch: Vec<&DxfEntity> = etch.iter().collect();
        for l in strip["labels"].as_array().unwrap() {
            let at = [num(&l["at"][0], "x"), num(&l["at"][1], "y")];
            let d = baseline(&etch, l, at)
                .unwrap_or_else(|| panic!("{id}: label {} not found on ETCH", l["text"]));
            assert!(upright(d), "{id}: label {} reads along {d:?}", l["text"]);
        }
    }
    let mut files = fs::read_dir(out.join("sheets"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.ends_with(".dxf"))
        .collect::<Vec<_>>();
    files.sort();
    let (mut turned, mut half_turned) = (0, 0);
    let sheets = nest["sheets"].as_array().unwrap();
    assert_eq!(files.len(), sheets.len());
    for (sheet, file) in sheets.iter().zip(&files) {
        let etch = etch_of(&fs::read_to_string(out.join(format!("sheets/{file}"))).unwrap());
        let etch: Vec<&DxfEntity> = etch.iter().collect();
        for p in sheet["placements"].as_array().unwrap() {
            let id = p["strip"].as_str().unwrap();
            let rot = num(&p["rotation_deg"], "rotation").to_radians();
            let t = [
                num(&p["translation"][0], "x"),
                num(&p["translation"][1], "y"),
            ];
            let (s, c) = rot.sin_cos();
            if c < 0.0 {
                half_turned += 1;
            }
            for l in by_id[id]["labels"].as_array().unwrap() {
                let [x, y] = [num(&l["at"][0], "x"), num(&l["at"][1], "y")];
                let at = [c * x - s * y + t[0], s * x + c * y + t[1]];
                let d = baseline(&etch, l, at).unwrap_or_else(|| {
                    panic!("{file}: label {} of {id} not found on ETCH", l["text"])
                });
                assert!(upright(d), "{file}: label {} reads along {d:?}", l["text"]);
                // the strip frame's baseline, turned by the placement, reads upside down
                let a = num(&l["angle"], "angle") + rot;
                if !upright([a.cos(), a.sin()]) {
                    turned += 1;
                }
            }
        }
    }
    (turned, half_turned)
}

#[test]
fn every_unit_of_the_default_build_marks_the_face_its_hub_comes_out_of() {
    let (dir, out) = default_build();
    out.expect_code(0);
    let (towards, away) = check_face_marks(dir);
    eprintln!("pavilion: {towards} hubs out of the etched face, {away} out of the back");
    assert!(towards + away > 200);
}

#[test]
fn the_saddle_marks_its_hubs_too() {
    // the saddle's build shared with the fold check's test
    let (dir, out) = saddle_build();
    out.expect_code(0);
    let (towards, away) = check_face_marks(dir);
    eprintln!("saddle: {towards} hubs out of the etched face, {away} out of the back");
    assert!(towards + away > 100);
    check_labels_upright(dir);
}

#[test]
fn labels_read_upright_in_the_strips_and_on_the_sheets() {
    let (dir, out) = default_build();
    out.expect_code(0);
    let (turned, half_turned) = check_labels_upright(dir);
    // where the nest turns strips half round, their labels were turned back upright
    eprintln!("{turned} labels turned upright on the {half_turned} strips turned half round");
    assert_eq!(
        turned > 0,
        half_turned > 0,
        "{turned} labels, {half_turned} strips"
    );
}
