//! `spinvalence build`: target surface to deployed frame, its config file and bad input.

use std::sync::OnceLock;

use crate::util::{num, read_json, Dir, Output};

const FILES: [&str; 11] = [
    "bom.csv",
    "frame.json",
    "frame.obj",
    "mesh.obj",
    "nest.json",
    "report.html",
    "report.json",
    "sheets",
    "strips",
    "strips.json",
    "timings.json",
];

/// The nest stage's options of the tests' other builds and nests: a fixed work budget and a
/// time cap no busy test machine reaches, so that the sheets are the same on every run
/// however loaded the machine is.
pub const NEST_WORK: [&str; 4] = ["--nest-evaluations", "800000", "--nest-seconds", "3600"];

/// The nest stage's options in [`default_build`]: about the work budget the default 5 s
/// give the pavilion (timings.json `nest_search.work_budget`) and a time cap no busy test machine
/// reaches, so that the sheets are those the default build finds on a quiet machine.
pub const DEFAULT_NEST_WORK: [&str; 4] =
    ["--nest-evaluations", "1700000", "--nest-seconds", "3600"];

/// `spinvalence build` with every default but the nest stage's [`DEFAULT_NEST_WORK`] (the
/// pavilion into `./out`), run once per test run in `target/tmp/e2e-default-build` and
/// shared by the tests that read its output.
pub fn default_build() -> &'static (Dir, Output) {
    static BUILD: OnceLock<(Dir, Output)> = OnceLock::new();
    BUILD.get_or_init(|| {
        let dir = Dir::persistent("e2e-default-build");
        let mut args = vec!["build"];
        args.extend(DEFAULT_NEST_WORK);
        let out = dir.run(&args);
        (dir, out)
    })
}

/// `spinvalence build --target builtin:saddle` with the nest stage's [`NEST_WORK`], run once
/// per test run in `target/tmp/e2e-saddle-build` and shared by the tests that read its
/// output (the fold check's and the face marks').
pub fn saddle_build() -> &'static (Dir, Output) {
    static BUILD: OnceLock<(Dir, Output)> = OnceLock::new();
    BUILD.get_or_init(|| {
        let dir = Dir::persistent("e2e-saddle-build");
        let mut args = vec!["build", "--target", "builtin:saddle"];
        args.extend(NEST_WORK);
        let out = dir.run(&args);
        (dir, out)
    })
}

#[test]
fn default_build_writes_the_pavilion_into_out_and_checks_clean() {
    let (dir, out) = default_build();
    out.expect_code(0);
    assert_eq!(dir.entries("out"), FILES.to_vec(), "{out:?}");
    for row in [
        "units",
        "planarity max",
        "conical residual max",
        "distance to target max",
        "gap max",
        "gap sum",
        "hub overlap",
        "time secondary / primary",
        "strips",
        "sheets",
        "offcut",
        "search",
        "steel",
        "cut length / pierces",
        "welds",
        "report",
    ] {
        assert!(out.stdout.contains(row), "summary lacks {row}:{out:?}");
    }
    let timings = read_json(&dir.join("out/timings.json"));
    for stage in ["secondary", "primary", "strips", "nest", "report", "total"] {
        let t = num(&timings[stage], stage);
        assert!(t > 0.0 && t.is_finite(), "{stage}: {t}");
    }
    assert!(
        num(&timings["total"], "total")
            >= num(&timings["secondary"], "s") + num(&timings["primary"], "p")
    );
    let frame = read_json(&dir.join("out/frame.json"));
    let units = frame["units"].as_array().unwrap().len();
    assert!(units > 50, "{units} units");
    assert!(out.stdout.contains(&units.to_string()), "{out:?}");
    // the spin the hubs were built at, as frame.json has it
    let spins: Vec<f64> = frame["units"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| num(&u["spin"], "spin").to_degrees())
        .collect();
    let (lo, hi) = spins
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &s| {
            (a.min(s), b.max(s))
        });
    let spin_row = out
        .stdout
        .lines()
        .find(|l| l.starts_with("spin angle"))
        .expect("spin angle row");
    assert!(
        spin_row.contains(&format!(
            "45.0 deg asked; the hubs turned to {lo:.1} .. {hi:.1} deg"
        )),
        "{spin_row}"
    );
    let report = read_json(&dir.join("out/report.json"));
    assert_eq!(report["faces"].as_u64(), Some(units as u64));
    // the fold check of the parts as cut is in the report: every row holds on the default
    let fold = report["fold_check"]["rows"]
        .as_array()
        .expect("fold_check rows");
    assert!(fold.len() > 10, "{fold:?}");
    assert!(fold.iter().all(|r| r["ok"] == true), "{fold:?}");
    let html = std::fs::read_to_string(dir.join("out/report.html")).unwrap();
    assert!(html.contains("Every row holds: the parts as cut fold into the frame."));
    // the hub mesh on its own is a valid input of `solve`
    dir.run(&[
        "solve",
        "--mesh",
        "out/mesh.obj",
        "--out",
        "again",
        "--quiet",
    ])
    .expect_code(0);
    dir.run(&["check", "out/frame.json"]).expect_code(0);
    check_strips(dir, "out");
}

fn point(v: &serde_json::Value, what: &str) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("{what}: not an array"))
        .iter()
        .map(|x| num(x, what))
        .collect()
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// `DIR/strips.json` against `DIR/frame.json`, recomputed from the files alone: a partition
/// of the units into strips, labels `<strip>-<nn>` in frame.json, every flat tile congruent
/// with its expanded 3D primary tile to 0.01 mm, one DXF (R2000, mm, one closed LWPOLYLINE
/// per contour) and one SVG per strip.
fn check_strips(dir: &crate::util::Dir, out: &str) {
    let frame = read_json(&dir.join(&format!("{out}/frame.json")));
    let strips = read_json(&dir.join(&format!("{out}/strips.json")));
    assert_eq!(strips["format"], "spin-valence/strips");
    assert_eq!(strips["version"], 1);
    assert_eq!(strips["length_unit"], "mm");
    let e = num(&frame["params"]["expansion"], "expansion");
    assert_eq!(num(&strips["params"]["expansion"], "e"), e);
    for key in ["thickness", "kerf", "min_web"] {
        assert!(num(&strips["params"][key], key) > 0.0, "{key}");
    }
    let units = frame["units"].as_array().unwrap();
    let mut seen = vec![0; units.len()];
    let mut files: Vec<String> = Vec::new();
    for strip in strips["strips"].as_array().unwrap() {
        let id = strip["id"].as_str().unwrap();
        files.push(format!("{id}.dxf"));
        files.push(format!("{id}.svg"));
        let list: Vec<usize> = strip["units"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| u.as_u64().unwrap() as usize)
            .collect();
        let flat = strip["flat"].as_array().unwrap();
        assert_eq!(flat.len(), list.len(), "{id}");
        for (j, (&u, tile)) in list.iter().zip(flat).enumerate() {
            seen[u] += 1;
            assert_eq!(
                units[u]["id"],
                format!("{id}-{:02}", j + 1),
                "label of unit {u}"
            );
            assert_eq!(units[u]["strip"], id);
            assert_eq!(tile["unit"].as_u64(), Some(u as u64));
            let p: Vec<Vec<f64>> = units[u]["primary"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| point(c, "primary"))
                .collect();
            let c: Vec<f64> = (0..3)
                .map(|k| p.iter().map(|q| q[k]).sum::<f64>() / 4.0)
                .collect();
            let p: Vec<Vec<f64>> = p
                .iter()
                .map(|q| (0..3).map(|k| c[k] + e * (q[k] - c[k])).collect())
                .collect();
            let f: Vec<Vec<f64>> = tile["primary"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| point(c, "flat"))
                .collect();
            for i in 0..4 {
                for k in (i + 1)..4 {
                    let d = (dist(&p[i], &p[k]) - dist(&f[i], &f[k])).abs();
                    assert!(d < 0.01, "{id} unit {u}: corners {i}-{k} off by {d} mm");
                }
            }
        }
        let area = num(&strip["area_mm2"], "area");
        assert!(area > 0.0, "{id}");
        let cuts = strip["cuts"].as_array().unwrap().len();
        assert_eq!(cuts, 4 * list.len(), "{id}: four slots per unit");
        let dxf = std::fs::read_to_string(dir.join(&format!("{out}/strips/{id}.dxf"))).unwrap();
        let lines: Vec<&str> = dxf.lines().map(str::trim).collect();
        let after = |key: &str| lines.iter().position(|l| *l == key).map(|i| lines[i + 2]);
        assert_eq!(after("$ACADVER"), Some("AC1015"), "{id}");
        assert_eq!(after("$INSUNITS"), Some("4"), "{id}");
        assert_eq!(lines.last(), Some(&"EOF"), "{id}");
        let closed_polylines = lines
            .windows(2)
            .filter(|w| w[0] == "0" && w[1] == "LWPOLYLINE")
            .count();
        assert!(closed_polylines > cuts, "{id}: outline, cuts and etching");
        let svg = std::fs::read_to_string(dir.join(&format!("{out}/strips/{id}.svg"))).unwrap();
        assert!(svg.contains(&format!("{id}-01")), "{id}: labels in the SVG");
    }
    assert!(
        seen.iter().all(|&n| n == 1),
        "every unit in exactly one strip"
    );
    files.sort();
    assert_eq!(dir.entries(&format!("{out}/strips")), files);
}

#[test]
fn config_file_sets_parameters_and_flags_override_it() {
    let dir = Dir::new();
    dir.write(
        "build.toml",
        "target = \"builtin:dome\"\nout = \"from-config\"\n[secondary]\nunit_size = 400.0\n[primary]\nspin_angle_deg = 40.0\n",
    );
    dir.run(&["build", "--config", "build.toml", "--quiet"])
        .expect_code(0);
    let frame = read_json(&dir.join("from-config/frame.json"));
    let spin = num(&frame["params"]["spin_angle"], "spin_angle");
    assert!((spin - 40f64.to_radians()).abs() < 1e-12);
    let coarse = frame["units"].as_array().unwrap().len();
    // a smaller unit on the command line wins over the file: more units
    dir.run(&[
        "build",
        "--config",
        "build.toml",
        "--unit-size",
        "300",
        "--out",
        "fine",
        "--quiet",
    ])
    .expect_code(0);
    let fine = read_json(&dir.join("fine/frame.json"))["units"]
        .as_array()
        .unwrap()
        .len();
    assert!(fine > coarse, "{fine} vs {coarse}");
    assert!(dir.entries("").contains(&"from-config".to_string()));
}

#[test]
fn print_config_round_trips_through_build() {
    let dir = Dir::new();
    let out = dir.run(&["build", "--print-config"]);
    out.expect_code(0);
    assert!(
        out.stdout.contains("[secondary]") && out.stdout.contains("unit_size"),
        "{out:?}"
    );
    let config = out.stdout.replace("unit_size = 300.0", "unit_size = 500.0");
    dir.write("c.toml", config);
    dir.run(&[
        "build",
        "--config",
        "c.toml",
        "--target",
        "builtin:vault",
        "--out",
        "v",
        "--quiet",
    ])
    .expect_code(0);
    dir.run(&["check", "v/frame.json"]).expect_code(0);
}

#[test]
fn obj_target_file_builds() {
    let dir = Dir::new();
    // a gently curved 2.4 x 1.8 m patch, triangulated
    let (nx, ny) = (24, 18);
    let mut text = String::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (i as f64 * 100.0, j as f64 * 100.0);
            let z = 0.00005 * ((x - 1200.0).powi(2) + (y - 900.0).powi(2));
            text += &format!("v {x} {y} {z}\n");
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i + 1;
    for j in 0..ny {
        for i in 0..nx {
            text += &format!("f {} {} {}\n", id(i, j), id(i + 1, j), id(i + 1, j + 1));
            text += &format!("f {} {} {}\n", id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    }
    dir.write("bowl.obj", text);
    dir.run(&[
        "build",
        "--target",
        "bowl.obj",
        "--unit-size",
        "300",
        "--out",
        "b",
        "--quiet",
    ])
    .expect_code(0);
    dir.run(&["check", "b/frame.json"]).expect_code(0);
}

#[test]
fn bad_build_input_is_one_line_and_writes_nothing() {
    let dir = Dir::new();
    dir.write("empty.obj", "");
    dir.write("garbage.stl", [0u8, 159, 146, 150, 7, 7, 7]);
    dir.write("typo.toml", "[secondary]\nunit_sise = 250.0\n");
    dir.write("neck.toml", "[profile]\nneck_width = 25.0\n");
    dir.write("slot.toml", "[profile]\nslot_width = 1.0\n");
    dir.write("thin.toml", "[profile]\nthickness = 0.0\n");
    dir.write("nan.obj", "v 0 0 0\nv 1000 0 nan\nv 0 1000 0\nf 1 2 3\n");
    // a closed tetrahedron: no boundary
    dir.write(
        "closed.obj",
        "v 0 0 0\nv 1000 0 0\nv 0 1000 0\nv 0 0 1000\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    );
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--target", "empty.obj"], "empty.obj"),
        (vec!["--target", "garbage.stl"], "garbage.stl"),
        (vec!["--target", "missing.stl"], "missing.stl"),
        (vec!["--target", "nan.obj"], "nan.obj"),
        (vec!["--target", "closed.obj"], "closed.obj"),
        (vec!["--target", "builtin:nope"], "nope"),
        (vec!["--config", "typo.toml"], "typo.toml:2"),
        (vec!["--config", "neck.toml"], "neck_width"),
        (vec!["--config", "slot.toml"], "slot_width"),
        (vec!["--config", "thin.toml"], "thickness"),
        (vec!["--strip-direction", "w"], "strip direction"),
        (
            vec!["--unit-size", "0"],
            "secondary.unit_size (--unit-size) 0",
        ),
        (vec!["--unit-size", "-300"], "--unit-size"),
        (vec!["--unit-size", "nan"], "--unit-size"),
        (
            vec!["--spin-angle", "90"],
            "primary.spin_angle_deg (--spin-angle) 90",
        ),
        (vec!["--spin-angle", "0"], "--spin-angle"),
        (
            vec!["--expansion", "0.5"],
            "primary.expansion (--expansion) 0.5",
        ),
        // a target smaller than one unit
        (
            vec!["--target", "builtin:flat", "--unit-size", "100000"],
            "",
        ),
    ];
    for (args, needle) in cases {
        let mut argv = vec!["build", "--out", "o"];
        argv.extend(args.iter());
        let out = dir.run(&argv);
        out.expect_code(2);
        let line = out.one_error_line();
        assert!(line.contains(needle), "{needle}: {out:?}");
        assert!(dir.entries("o").is_empty(), "partial output for {args:?}");
    }
}

/// `[nest]` in the config file: stock sizes, margin, clearance, seed, time box; the
/// `--nest-seconds` flag overrides the file, and bad values stop the build by key.
#[test]
fn nest_section_sets_the_sheets_and_bad_values_name_the_key() {
    let dir = Dir::new();
    dir.write(
        "n.toml",
        "target = \"builtin:vault\"\n[secondary]\nunit_size = 500.0\n[nest]\nsheets = [\"2000x1000\", \"3200x1600\"]\nmargin = 15.0\nclearance = 2.0\nseconds = 600.0\nevaluations = 20000\nseed = 7\n",
    );
    dir.run(&[
        "build",
        "--config",
        "n.toml",
        "--nest-seconds",
        "1",
        "--out",
        "o",
        "--quiet",
    ])
    .expect_code(0);
    let nest = read_json(&dir.join("o/nest.json"));
    let spec = &nest["sheet"];
    assert_eq!(num(&spec["width"], "width"), 2000.0);
    assert_eq!(num(&spec["margin"], "margin"), 15.0);
    // spacing = profile kerf (1.3) + clearance
    assert!(
        (num(&spec["spacing"], "spacing") - 3.3).abs() < 1e-9,
        "{spec}"
    );
    // the file's work budget decides the layout
    assert!(
        nest.get("search").is_none(),
        "a record of the run: timings.json"
    );
    let timings = read_json(&dir.join("o/timings.json"));
    let search = &timings["nest_search"];
    assert_eq!(search["work_budget"], 20_000, "{search}");
    let files = dir.entries("o/sheets");
    for (i, sheet) in nest["sheets"].as_array().unwrap().iter().enumerate() {
        let (w, h) = (num(&sheet["width"], "w"), num(&sheet["height"], "h"));
        assert!([(2000.0, 1000.0), (3200.0, 1600.0)].contains(&(w, h)));
        let stem = format!("sheet-{:02}_{w}x{h}mm_t2.5mm", i + 1);
        assert!(files.contains(&format!("{stem}.dxf")), "{stem}: {files:?}");
    }
    for (toml, key) in [
        ("[nest]\nsheets = [\"0x1500\"]\n", "nest.sheets"),
        ("[nest]\nsheets = [\"-5x10\"]\n", "nest.sheets"),
        ("[nest]\nsheets = []\n", "nest.sheets"),
        ("[nest]\nmargin = -1.0\n", "nest.margin"),
        ("[nest]\nseconds = 0.0\n", "nest.seconds"),
    ] {
        dir.write("bad.toml", toml);
        let out = dir.run(&["build", "--config", "bad.toml", "--out", "bad"]);
        out.expect_code(2);
        assert!(out.one_error_line().contains(key), "{key}:{out:?}");
        assert!(!dir.join("bad").exists(), "{key}: nothing written");
    }
    let out = dir.run(&["build", "--nest-seconds", "-1", "--out", "bad"]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("seconds"), "{out:?}");
}

#[test]
fn frame_overlap_is_read_or_refused_in_one_line_before_anything_is_written() {
    let dir = Dir::new();
    for toml in [
        "[frame]\noverlap = \"sometimes\"\n",
        "[frame]\noverlap = 10.0\n",
        "[frame]\noverlap = -30\n",
        "[frame]\noverlap = \"constant\"\n[joints]\nclose = false\n",
        // the band must be a length, and reach no lower than the weld minimum (25 mm)
        "[frame]\noverlap = \"constant\"\noverlap_tolerance = 0\n",
        "[frame]\noverlap = \"constant\"\noverlap_tolerance = nan\n",
        "[frame]\noverlap = 25.5\n",
    ] {
        dir.write("bad.toml", toml);
        let out = dir.run(&["build", "--config", "bad.toml", "--out", "bad"]);
        out.expect_code(2);
        assert!(out.one_error_line().contains("overlap"), "{toml}: {out:?}");
        assert!(!dir.join("bad").exists(), "{toml}: nothing written");
    }
    // a length the welds take, and the rule, are read: the file fails at its next key
    for toml in [
        "[frame]\noverlap = 40\n",
        "[frame]\noverlap = \"constant\"\n",
    ] {
        dir.write("good.toml", format!("{toml}[nest]\nmargin = -1.0\n"));
        let out = dir.run(&["build", "--config", "good.toml", "--out", "bad"]);
        out.expect_code(2);
        assert!(
            out.one_error_line().contains("nest.margin"),
            "{toml}: {out:?}"
        );
    }
}
