//! `spinvalence nest`: DXF parts onto sheets, a benchmark instance, and bad input.

use crate::util::{num, read_json, Dir};

/// An ASCII DXF with one LWPOLYLINE outline per part (closed, optional bulges) and a circle hole.
fn dxf(parts: &[(f64, f64, f64)]) -> String {
    let mut s = String::from("0\nSECTION\n2\nENTITIES\n");
    for &(x, w, h) in parts {
        // a w x h plate with a half-round right end and a 10 mm hole
        s += &format!(
            "0\nLWPOLYLINE\n8\nOUTSIDE\n90\n4\n70\n1\n10\n{x}\n20\n0\n42\n0\n10\n{}\n20\n0\n42\n1\n10\n{}\n20\n{h}\n42\n0\n10\n{x}\n20\n{h}\n",
            x + w,
            x + w
        );
        s += &format!(
            "0\nCIRCLE\n8\nINSIDE\n10\n{}\n20\n{}\n40\n10\n",
            x + 30.0,
            h / 2.0
        );
    }
    s + "0\nENDSEC\n0\nEOF\n"
}

#[test]
fn dxf_parts_nest_inside_the_sheet_and_open_contours_are_left_out() {
    let dir = Dir::new();
    dir.write("a.dxf", dxf(&[(0.0, 400.0, 150.0), (1000.0, 300.0, 120.0)]));
    dir.write("b.dxf", dxf(&[(0.0, 500.0, 200.0)]));
    // an open polyline is not a part
    dir.write(
        "open.dxf",
        "0\nSECTION\n2\nENTITIES\n0\nLWPOLYLINE\n70\n0\n10\n0\n20\n0\n10\n100\n20\n0\n10\n100\n20\n50\n0\nENDSEC\n0\nEOF\n",
    );
    let out = dir.run(&[
        "nest",
        "a.dxf",
        "b.dxf",
        "open.dxf",
        "--sheet",
        "1200x600",
        "--nest-evaluations",
        "100000",
        "--nest-seconds",
        "3600",
        "--out",
        "n",
    ]);
    out.expect_code(0);
    assert!(out.stdout.contains("left out"), "{out:?}");
    let report = read_json(&dir.join("n/nest.json"));
    let sheet = &report["sheet"];
    let (w, h, margin) = (
        num(&sheet["width"], "w"),
        num(&sheet["height"], "h"),
        num(&sheet["margin"], "m"),
    );
    assert_eq!((w, h), (1200.0, 600.0));
    let placed: usize = report["sheets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["placements"].as_array().unwrap().len())
        .sum();
    assert_eq!(placed, 3, "every part placed exactly once");
    // how far the search went is a record of the run: timings.json, not nest.json
    assert!(report.get("search").is_none(), "{report}");
    let timings = read_json(&dir.join("n/timings.json"));
    assert_eq!(timings["nest_search"]["work_budget"], 100_000, "{timings}");
    assert_eq!(timings["nest_search"]["cut_by_time"], false, "{timings}");
    // the budget is the search's and holds; the construction's evaluations are apart
    let searched = timings["nest_search"]["evaluations"].as_u64().unwrap();
    let constructed = timings["nest_search"]["construction_evaluations"]
        .as_u64()
        .unwrap();
    assert!(searched <= 100_000 && constructed > 0, "{timings}");
    // counts from 100,000 up in millions, smaller ones whole (thousands grouped)
    let said = |n: u64| {
        if n >= 100_000 {
            format!("{:.2} M", n as f64 / 1e6)
        } else {
            let d = n.to_string();
            let head = d.len() % 3;
            let mut groups: Vec<&str> = if head > 0 { vec![&d[..head]] } else { vec![] };
            groups.extend((head..d.len()).step_by(3).map(|i| &d[i..i + 3]));
            groups.join(",")
        }
    };
    assert!(
        out.stdout.contains(&format!(
            "{} evaluations (work budget 0.10 M, the construction's {} apart",
            said(searched),
            said(constructed)
        )),
        "{}",
        out.stdout
    );
    assert!(num(&timings["total"], "total") >= num(&timings["nest"], "nest"));
    let lb = report["lower_bound_sheets"].as_u64().unwrap();
    assert!(lb as usize <= report["sheets"].as_array().unwrap().len());
    for s in report["sheets"].as_array().unwrap() {
        let u = num(&s["utilisation"], "utilisation");
        assert!(u > 0.0 && u <= 1.0);
        for p in s["placements"].as_array().unwrap() {
            // the original outline's extent (plate + half-round end), moved as placed
            let (x0, pw, ph) = match p["strip"].as_str().unwrap() {
                "a#1" => (0.0, 400.0, 150.0),
                "a#2" => (1000.0, 300.0, 120.0),
                "b" => (0.0, 500.0, 200.0),
                other => panic!("unknown part {other}"),
            };
            let t = p["translation"].as_array().unwrap();
            let (tx, ty) = (num(&t[0], "x"), num(&t[1], "y"));
            let a = num(&p["rotation_deg"], "rotation").to_radians();
            for (x, y) in [
                (x0, 0.0),
                (x0 + pw + ph / 2.0, 0.0),
                (x0, ph),
                (x0 + pw + ph / 2.0, ph),
            ] {
                let (sx, sy) = (
                    a.cos() * x - a.sin() * y + tx,
                    a.sin() * x + a.cos() * y + ty,
                );
                assert!(
                    sx >= margin - 1e-6 && sx <= w - margin + 1e-6,
                    "{p}: x {sx}"
                );
                assert!(
                    sy >= margin - 1e-6 && sy <= h - margin + 1e-6,
                    "{p}: y {sy}"
                );
            }
        }
    }
    let left = report["left_out"].as_array().unwrap();
    assert!(
        left.iter()
            .any(|l| l["reason"].as_str().unwrap().contains("open")),
        "{left:?}"
    );
    // one DXF and one SVG preview per sheet
    assert_eq!(
        dir.entries("n/sheets").len(),
        2 * report["sheets"].as_array().unwrap().len()
    );
}

/// `spinvalence nest` on the strip-packing benchmark instance `name` (shared/datasets) with
/// a work budget of `evaluations` and a time cap no busy machine reaches, into `dir/name`:
/// the run and its strip.json.
fn nest_spp(dir: &Dir, name: &str, evaluations: &str) -> (crate::util::Output, serde_json::Value) {
    let instance = format!(
        "{}/../../../shared/datasets/nesting/spp/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = dir.run(&[
        "nest",
        &instance,
        "--nest-evaluations",
        evaluations,
        "--nest-seconds",
        "600",
        "--out",
        name,
    ]);
    out.expect_code(0);
    let strip = read_json(&dir.join(&format!("{name}/strip.json")));
    (out, strip)
}

#[test]
fn strip_instance_reaches_a_real_density() {
    let dir = Dir::new();
    let (_, r) = nest_spp(&dir, "fu", "150000");
    let density = num(&r["density"], "density");
    // above the jagua-rs lbf reference (70.32 %) in best_known_spp.csv
    assert!(density > 0.7032 && density < 1.0, "{density}");
    assert_eq!(r["placements"].as_array().unwrap().len(), 12);
}

/// Two files with one stem in two directories: each file's parts are named by the stem
/// and the directory (`a/part`, `b/part#1`, `b/part#2`), whatever the order of the files
/// on the command line (the second file's parts were named by its path, `b/part.dxf#1`,
/// and the first's by the stem alone, so that a file's ids hung on the order).
#[test]
fn files_that_share_a_stem_get_unique_ids_by_their_directory() {
    let dir = Dir::new();
    dir.write("a/part.dxf", dxf(&[(0.0, 400.0, 150.0)]));
    dir.write(
        "b/part.dxf",
        dxf(&[(0.0, 300.0, 120.0), (1000.0, 500.0, 200.0)]),
    );
    let ids = |files: [&str; 2], out: &str| -> Vec<String> {
        let args = [
            "nest",
            files[0],
            files[1],
            "--sheet",
            "1200x600",
            "--nest-evaluations",
            "20000",
            "--nest-seconds",
            "3600",
            "--out",
            out,
            "--quiet",
        ];
        dir.run(&args).expect_code(0);
        let report = read_json(&dir.join(&format!("{out}/nest.json")));
        let mut ids: Vec<String> = report["sheets"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|s| s["placements"].as_array().unwrap().iter())
            .map(|p| p["strip"].as_str().unwrap().to_string())
            .collect();
        ids.sort();
        ids
    };
    let expected = ["a/part", "b/part#1", "b/part#2"];
    assert_eq!(ids(["a/part.dxf", "b/part.dxf"], "ab"), expected);
    assert_eq!(ids(["b/part.dxf", "a/part.dxf"], "ba"), expected);
}

/// A strip-packing instance whose construction does more evaluations than the whole work
/// budget (161 copies, 2,000 evaluations): they are counted apart, and the search after it
/// spends its budget exactly, as strip.json and the summary's search row say.
#[test]
fn a_strip_search_spends_its_budget_apart_from_the_construction() {
    let dir = Dir::new();
    let (out, r) = nest_spp(&dir, "gardeyn6", "2000");
    assert_eq!(r["evaluations"], 2000, "{r}");
    assert_eq!(r["work_budget"], 2000, "{r}");
    assert_eq!(r["cut_by_time"], false, "{r}");
    let constructed = r["construction_evaluations"].as_u64().unwrap();
    assert!(constructed > 2000, "{constructed}");
    let row = out
        .stdout
        .lines()
        .find(|l| l.starts_with("search"))
        .unwrap_or_else(|| panic!("{}", out.stdout));
    // the counts whole where they are small (2,000 read "0.00 M")
    assert!(
        row.contains("2,000 evaluations (work budget 2,000, the construction's ")
            && row.ends_with(" apart; the same layout on every machine)"),
        "{row}"
    );
}

#[test]
fn bad_nest_input_is_one_line() {
    let dir = Dir::new();
    dir.write("a.dxf", dxf(&[(0.0, 400.0, 150.0)]));
    dir.write("garbage.dxf", [0u8, 1, 2, 3, 250, 251]);
    // a header date the DXF parser cannot hold: it panics inside, and the panic's own
    // message must not reach stderr beside the error
    dir.write(
        "date.dxf",
        "0\nSECTION\n2\nHEADER\n9\n$TDCREATE\n40\n1e300\n0\nENDSEC\n0\nEOF\n",
    );
    for (args, needle) in [
        (vec!["a.dxf", "--sheet", "3000"], "--sheet"),
        (vec!["a.dxf", "--sheet", "0x100"], "--sheet"),
        (vec!["a.dxf", "--sheet", "0x1500"], "--sheet \"0x1500\""),
        (vec!["a.dxf", "--sheet", "-5x10"], "--sheet \"-5x10\""),
        (
            vec!["a.dxf", "--sheet", "3000x1500,-1x2"],
            "--sheet \"-1x2\"",
        ),
        (vec!["a.dxf", "--margin", "-1"], "--margin"),
        // a margin that leaves nothing of the sheet, refused before any part is read
        (
            vec!["a.dxf", "--margin", "760"],
            "invalid --margin 760: leaves no usable area on the 3000 x 1500 mm sheet (2 x 760 mm >= 1500 mm)",
        ),
        (vec!["a.dxf", "--nest-seconds", "0"], "--nest-seconds"),
        // a cap past the clock's range panicked
        (
            vec!["a.dxf", "--nest-seconds", "1e20"],
            "--nest-seconds 100000000000000000000: must be > 0 and at most a day",
        ),
        (vec!["garbage.dxf"], "nothing to nest"),
        (
            vec!["date.dxf"],
            "a value it cannot hold, such as a date out of range",
        ),
        (vec!["missing.dxf"], "missing.dxf"),
    ] {
        let mut argv = vec!["nest"];
        argv.extend(args.iter());
        argv.extend(["--out", "o"]);
        let out = dir.run(&argv);
        out.expect_code(2);
        assert!(out.one_error_line().contains(needle), "{needle}: {out:?}");
        assert!(!dir.join("o/nest.json").exists());
    }
}

/// Copies of one part too long for the sheet: one warning line for them all, each named in
/// nest.json with a reason that names no other part; when no part fits, an error after
/// nest.json is written.
#[test]
fn parts_left_out_for_one_reason_are_one_line() {
    let dir = Dir::new();
    // six plates 1,500 mm long (the sheet is 1,200) and one that fits
    let mut plates: Vec<(f64, f64, f64)> =
        (0..6).map(|k| (2000.0 * k as f64, 1500.0, 80.0)).collect();
    plates.push((20_000.0, 300.0, 100.0));
    dir.write("long.dxf", dxf(&plates));
    let args = |file: &'static str, out: &'static str| {
        [
            "nest",
            file,
            "--sheet",
            "1200x600",
            "--nest-evaluations",
            "20000",
            "--nest-seconds",
            "3600",
            "--out",
            out,
        ]
    };
    let out = dir.run(&args("long.dxf", "n"));
    out.expect_code(0);
    let warnings: Vec<&str> = out
        .stderr
        .lines()
        .filter(|l| l.contains("left out"))
        .collect();
    assert_eq!(warnings.len(), 1, "{}", out.stderr);
    assert!(
        warnings[0].starts_with("warning: 6 parts (long#1, long#2, long#3, ..., long#6) left out: larger than every sheet"),
        "{}",
        warnings[0]
    );
    let report = read_json(&dir.join("n/nest.json"));
    let left = report["left_out"].as_array().unwrap();
    let named: Vec<&str> = left.iter().map(|l| l["part"].as_str().unwrap()).collect();
    assert_eq!(
        named,
        ["long#1", "long#2", "long#3", "long#4", "long#5", "long#6"]
    );
    for l in left {
        let reason = l["reason"].as_str().unwrap();
        assert!(reason.starts_with("larger than every sheet"), "{reason}");
        assert!(!reason.contains("long#"), "{reason}");
    }
    assert_eq!(report["sheets"].as_array().unwrap().len(), 1);

    // nothing fits: exit 2, with nest.json naming every part
    dir.write("longer.dxf", dxf(&plates[..6]));
    let out = dir.run(&args("longer.dxf", "m"));
    out.expect_code(2);
    assert!(
        out.stderr
            .contains("nothing nested: all 6 part(s) were left out"),
        "{}",
        out.stderr
    );
    let report = read_json(&dir.join("m/nest.json"));
    assert_eq!(report["left_out"].as_array().unwrap().len(), 6);
    assert!(report["sheets"].as_array().unwrap().is_empty());
}

/// What the reader skipped is in the error when nothing is left to nest: the first notes in
/// the one line (they were counted, "1 notes on what was skipped", and shown nowhere), and
/// an open contour that a skipped entity on its layer may have closed says so.
#[test]
fn nothing_to_nest_names_what_the_reader_skipped() {
    let dir = Dir::new();
    let header = "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n";
    let end = "0\nENDSEC\n0\nEOF\n";
    // an INSERT of a block the file does not define
    dir.write(
        "missing_block.dxf",
        format!("{header}0\nINSERT\n8\n0\n2\nNOPE\n10\n0\n20\n0\n30\n0\n{end}"),
    );
    // a SPLINE with zero weights (skipped) that closed the contour of a LINE
    let mut spline = String::from(
        "0\nSPLINE\n100\nAcDbEntity\n8\n0\n100\nAcDbSpline\n70\n8\n71\n3\n72\n8\n73\n4\n74\n0\n",
    );
    for w in [0, 0, 0, 0] {
        spline += &format!("41\n{w}\n");
    }
    for k in [0, 0, 0, 0, 1, 1, 1, 1] {
        spline += &format!("40\n{k}\n");
    }
    for (x, y) in [(0, 0), (100, -50), (200, 0), (200, 100)] {
        spline += &format!("10\n{x}\n20\n{y}\n30\n0.0\n");
    }
    dir.write(
        "spline_weights_zero.dxf",
        format!("{header}{spline}0\nLINE\n8\n0\n10\n200\n20\n100\n30\n0.0\n11\n0\n21\n0\n31\n0.0\n{end}"),
    );
    for (file, needles) in [
        (
            "missing_block.dxf",
            vec![
                "no closed contours to cut (1 notes on what was skipped: ",
                "block \"NOPE\" is not in the file: layer 0: INSERT #1)",
            ],
        ),
        (
            "spline_weights_zero.dxf",
            vec![
                "open contour: 2 loose ends",
                "an entity skipped on its layer may have closed it (1 note: skipped: SPLINE",
                "layer 0: SPLINE #1)",
            ],
        ),
    ] {
        let out = dir.run(&["nest", file, "--out", "o"]);
        out.expect_code(2);
        let line = out.one_error_line();
        for needle in needles {
            assert!(line.contains(needle), "{needle}: {line}");
        }
        assert!(!dir.join("o/nest.json").exists());
    }
}

/// A strip-packing instance that cannot be packed is one line and exit 2, before any work:
/// an item higher than the strip in every allowed rotation panicked, a demand of 10^8 took
/// 1.6 GB and panicked in jagua-rs.
#[test]
fn a_strip_instance_that_cannot_be_packed_is_one_line() {
    let dir = Dir::new();
    let inst = |height: f64, demand: u64| {
        format!(
            r#"{{"name": "t", "strip_height": {height}, "items": [{{"id": 3, "demand": {demand},
            "orientation": {{"rotation": {{"mode": "stepped", "step": 180}}}},
            "shape": {{"type": "simple_polygon", "data": [[0, 0], [3000, 0], [3000, 2260], [0, 2260]]}}}}]}}"#
        )
    };
    dir.write("low.json", inst(1000.0, 2));
    dir.write("many.json", inst(4900.0, 100_000_000));
    dir.write("far.json", inst(4900.0, 20_000));
    for (file, needle) in [
        (
            "low.json",
            "low.json: instance: item 3 (2260 high at best, rotated by 0 degrees; rotations allowed: 0, 180 degrees) does not fit the strip height 1000",
        ),
        (
            "many.json",
            "100000000 item copies in all (item 3 demands 100000000): at most 100000",
        ),
        ("far.json", "where f32 coordinates are 8 apart"),
    ] {
        let out = dir.run(&["nest", file, "--nest-seconds", "1", "--out", "o"]);
        out.expect_code(2);
        assert!(out.one_error_line().contains(needle), "{needle}: {out:?}");
        assert!(!dir.join("o/strip.json").exists());
    }
}
