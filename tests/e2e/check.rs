//! `spinvalence check` on good, tampered and unreadable frame files.

use serde_json::Value;

use crate::fixtures;
use crate::util::{num, read_json, Dir};

/// A directory with `out/frame.json` solved from the sphere cap.
fn solved() -> Dir {
    let dir = Dir::new();
    let mesh = fixtures::path("sphere_cap.obj");
    dir.run(&[
        "solve",
        "-q",
        "--mesh",
        mesh.to_str().unwrap(),
        "--out",
        "out",
    ])
    .expect_code(0);
    dir
}

fn rewrite(dir: &Dir, edit: impl FnOnce(&mut Value)) {
    let path = dir.join("out/frame.json");
    let mut frame = read_json(&path);
    edit(&mut frame);
    std::fs::write(&path, serde_json::to_string_pretty(&frame).unwrap()).unwrap();
}

#[test]
fn good_frame_prints_a_table_of_passed_checks() {
    let dir = solved();
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(0);
    assert!(out.stderr.is_empty(), "{out:?}");
    let lines: Vec<&str> = out.stdout.lines().collect();
    assert!(lines.len() >= 3, "a header and rows:{out:?}");
    assert!(lines[0].starts_with("check"), "{out:?}");
    for row in &lines[1..] {
        assert!(row.ends_with("ok") || row.ends_with("info"), "{out:?}");
    }
}

#[test]
fn moved_hub_corner_fails_and_names_the_unit() {
    let dir = solved();
    let mut id = String::new();
    rewrite(&dir, |frame| {
        let units = frame["units"].as_array_mut().unwrap();
        let k = units.len() / 2 + 3;
        let unit = &mut units[k];
        id = unit["id"].as_str().unwrap().to_string();
        let x = num(&unit["hub"][1][0], "hub x");
        unit["hub"][1][0] = (x + 5.0).into();
    });
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(1);
    let failed: Vec<&str> = out.stdout.lines().filter(|l| l.ends_with("FAIL")).collect();
    assert!(!failed.is_empty(), "{out:?}");
    assert!(
        failed.iter().any(|l| l.contains(&id)),
        "a failed row must name unit {id}:{out:?}"
    );
    assert!(out.one_error_line().contains("frame.json"), "{out:?}");
}

#[test]
fn wrong_gap_fails_and_names_the_link() {
    let dir = solved();
    rewrite(&dir, |frame| {
        let g = num(&frame["links"][5]["primary_gap"], "gap");
        frame["links"][5]["primary_gap"] = (g + 1.0).into();
    });
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(1);
    assert!(
        out.stdout
            .lines()
            .any(|l| l.ends_with("FAIL") && l.contains("link 5")),
        "{out:?}"
    );
}

#[test]
fn wrong_format_is_unreadable_input() {
    let dir = solved();
    rewrite(&dir, |frame| frame["format"] = "something/else".into());
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("frame.json"), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
}

#[test]
fn future_version_is_unreadable_input() {
    let dir = solved();
    rewrite(&dir, |frame| frame["version"] = 3.into());
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("frame.json"), "{out:?}");
    // a version 1 file (the zero-width units) is refused with the reason
    rewrite(&dir, |frame| frame["version"] = 1.into());
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("zero-width"), "{out:?}");
}

#[test]
fn truncated_json_names_line_and_column() {
    let dir = solved();
    let text = std::fs::read_to_string(dir.join("out/frame.json")).unwrap();
    dir.write("out/frame.json", &text[..text.len() / 2]);
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(2);
    let line = out.one_error_line();
    assert!(line.contains("out/frame.json:"), "{out:?}");
}

#[test]
fn missing_and_binary_files_are_unreadable_input() {
    let dir = Dir::new();
    let out = dir.run(&["check", "nowhere/frame.json"]);
    out.expect_code(2);
    assert!(
        out.one_error_line().contains("nowhere/frame.json"),
        "{out:?}"
    );
    dir.write("binary.json", [0u8, 159, 146, 150, 255, 0, 1]);
    let out = dir.run(&["check", "binary.json"]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("binary.json"), "{out:?}");
}

/// A frame that lost its units and links, or got a unit twice, passed with every row ok:
/// each face must be one unit with its own id (what `serve` refuses).
#[test]
fn a_face_without_exactly_one_unit_fails_and_is_named() {
    let dir = solved();
    rewrite(&dir, |frame| {
        frame["units"] = Value::Array(Vec::new());
        frame["links"] = Value::Array(Vec::new());
    });
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(1);
    let line = out.one_error_line();
    assert!(line.contains("the frame has no units"), "{out:?}");

    let dir = solved();
    let mut id = String::new();
    rewrite(&dir, |frame| {
        let units = frame["units"].as_array_mut().unwrap();
        id = units[0]["id"].as_str().unwrap().to_string();
        let first = units[0].clone();
        units.push(first);
    });
    let out = dir.run(&["check", "out/frame.json"]);
    out.expect_code(1);
    let line = out.one_error_line();
    assert!(
        line.contains(&format!("face 0 has 2 units ({id}, {id})")),
        "{out:?}"
    );
    assert!(
        out.stdout
            .lines()
            .any(|l| l.starts_with("faces without exactly one unit") && l.ends_with("FAIL")),
        "{out:?}"
    );
}

/// `--min-overlap=-5` passed hub plates that miss each other by up to 5 mm as welds.
#[test]
fn a_weld_minimum_at_or_below_zero_is_refused() {
    let dir = solved();
    for bad in ["-5", "0", "nan"] {
        let out = dir.run(&["check", "out/frame.json", &format!("--min-overlap={bad}")]);
        out.expect_code(2);
        assert!(
            out.one_error_line().contains("--min-overlap")
                && out.one_error_line().contains("must be a length > 0"),
            "{out:?}"
        );
    }
    dir.run(&["check", "out/frame.json", "--min-overlap=25"])
        .expect_code(0);
}
