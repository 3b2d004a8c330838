//! `spinvalence build` on targets whose goals cannot all be met (exit code 3, `--strict`),
//! with a designer's layout (`--layout`, `[surface] layout`), and on targets drawn in
//! metres or as an OBJ triangle soup.

use crate::fixtures;
use crate::util::{read_json, Dir};

/// The hypar with a gable: three of its sides are rulings of the surface, along which no
/// planar quad can have an edge (docs/secondary.md), so planarity is unmet.
fn hypar() -> String {
    fixtures::path("targets/hypar_pentagon.obj")
        .display()
        .to_string()
}

#[test]
fn unmet_goals_still_build_everything_and_exit_3() {
    let dir = Dir::new();
    let target = hypar();
    let out = dir.run(&[
        "build",
        "--target",
        &target,
        "--out",
        "o",
        "--nest-evaluations",
        "100000",
        "--nest-seconds",
        "3600",
    ]);
    out.expect_code(3);
    for f in [
        "mesh.obj",
        "frame.json",
        "report.json",
        "report.html",
        "strips.json",
        "nest.json",
    ] {
        assert!(dir.join(&format!("o/{f}")).exists(), "{f} missing:{out:?}");
    }
    // the summary names the unmet goals with their worst place and size
    assert!(out.stdout.contains("GOALS NOT MET"), "{out:?}");
    assert!(
        out.stdout.contains("planarity") && out.stdout.contains("% of the side"),
        "{out:?}"
    );
    let warning: Vec<&str> = out
        .stderr
        .lines()
        .filter(|l| l.starts_with("warning: "))
        .collect();
    assert_eq!(warning.len(), 1, "{out:?}");
    assert!(warning[0].contains("exit code 3"), "{out:?}");
    let report = read_json(&dir.join("o/report.json"));
    let unmet = report["unmet"].as_array().unwrap();
    assert!(
        unmet
            .iter()
            .any(|l| l.as_str().unwrap().starts_with("planarity")),
        "{report}"
    );
    // the 3D view can show where
    let html = std::fs::read_to_string(dir.join("o/report.html")).unwrap();
    assert!(html.contains("value=\"goals\""), "no unmet-goals view");
    assert!(html.contains("\"goals\":[["), "no per-unit goal flags");
    // `check` holds the goal tolerances: the planarity row fails
    let check = dir.run(&["check", "o/frame.json"]);
    check.expect_code(1);
    assert!(
        check
            .stdout
            .lines()
            .any(|l| l.starts_with("face planarity") && l.ends_with("FAIL")),
        "{check:?}"
    );
    // --strict: an error, the files still there to look at
    let strict = dir.run(&[
        "build",
        "--target",
        &target,
        "--out",
        "s",
        "--nest-evaluations",
        "100000",
        "--nest-seconds",
        "3600",
        "--quiet",
        "--strict",
    ]);
    strict.expect_code(2);
    let line = strict.one_error_line();
    assert!(
        line.contains("--strict") && line.contains("planarity"),
        "{strict:?}"
    );
    assert!(dir.join("s/mesh.obj").exists());
}

/// The coarse layout of `sv-surface/tests/layout.rs` as an OBJ: a 3 x 3 grid on the
/// built-in dome with one edge turned. Returns the text and the interior vertices
/// (0-based) that get three, three and five faces.
fn layout_obj() -> (String, Vec<usize>) {
    let id = |i: usize, j: usize| j * 4 + i;
    let cell = 4000.0 / 3.0;
    let mut v = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let mut x = -2000.0 + i as f64 * cell;
            let y = -2000.0 + j as f64 * cell;
            if (i, j) == (1, 1) {
                x -= 0.2 * cell;
            }
            if (i, j) == (2, 1) {
                x += 0.2 * cell;
            }
            let z = (16e6 - x * x - y * y).sqrt() - 4000.0;
            v.push(format!("v {x} {y} {z}"));
        }
    }
    let mut faces = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            if i == 1 && j < 2 {
                continue;
            }
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    faces.push([id(1, 0), id(2, 0), id(1, 2), id(1, 1)]);
    faces.push([id(2, 0), id(2, 1), id(2, 2), id(1, 2)]);
    let mut text = v.join("\n") + "\n";
    for f in faces {
        text += &format!("f {} {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1, f[3] + 1);
    }
    // interior vertices with three, three and five faces
    (text, vec![id(1, 1), id(2, 1), id(1, 2)])
}

#[test]
fn layout_flag_and_config_key_read_the_designers_layout() {
    // the library test (crates/sv-surface/tests/layout.rs) checks that the layout's
    // irregular vertices are kept; here: both ways of naming it reach the reader, whose
    // errors name the layout file and line
    let dir = Dir::new();
    let (text, _) = layout_obj();
    dir.write("layout.obj", text);
    dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    dir.write(
        "b.toml",
        "target = \"builtin:dome\"\n[surface]\nlayout = \"tri.obj\"\n",
    );
    let out = dir.run(&[
        "build",
        "--target",
        "builtin:dome",
        "--layout",
        "tri.obj",
        "--out",
        "t",
    ]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("tri.obj:4"), "{out:?}");
    let out = dir.run(&["build", "--config", "b.toml", "--out", "t"]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("tri.obj:4"), "{out:?}");
    let out = dir.run(&[
        "build",
        "--target",
        "builtin:dome",
        "--layout",
        "nowhere.obj",
        "--out",
        "t",
    ]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("nowhere.obj"), "{out:?}");
    assert!(!dir.join("t").exists());
}

#[test]
fn a_target_in_metres_is_named_with_its_bounding_box() {
    let dir = Dir::new();
    // 6 x 4 m drawn in metres
    dir.write(
        "m.obj",
        "v 0 0 0\nv 6 0 0\nv 6 4 0.3\nv 0 4 0.3\nf 1 2 3\nf 1 3 4\n",
    );
    let out = dir.run(&["build", "--target", "m.obj", "--out", "o"]);
    out.expect_code(2);
    let line = out.one_error_line();
    assert!(
        line.contains("6.000 x 4.000 x 0.300 mm")
            && line.contains("if it is in metres it is 6.000 x 4.000 x 0.300 m"),
        "{out:?}"
    );
    assert!(!dir.join("o").exists());
}

#[test]
fn an_obj_triangle_soup_with_mixed_orientation_builds() {
    let dir = Dir::new();
    // a 3 x 2 m flat plate, every triangle with its own corners, every other one reversed
    let (nx, ny, h) = (6usize, 4usize, 500.0);
    let mut text = String::new();
    let mut n = 0;
    for j in 0..ny {
        for i in 0..nx {
            let p =
                |a: usize, b: usize| format!("v {} {} 0\n", (i + a) as f64 * h, (j + b) as f64 * h);
            for (k, tri) in [[(0, 0), (1, 0), (1, 1)], [(0, 0), (1, 1), (0, 1)]]
                .iter()
                .enumerate()
            {
                for &(a, b) in tri {
                    text += &p(a, b);
                }
                if (i + j + k) % 2 == 0 {
                    text += &format!("f {} {} {}\n", n + 1, n + 2, n + 3);
                } else {
                    text += &format!("f {} {} {}\n", n + 1, n + 3, n + 2);
                }
                n += 3;
            }
        }
    }
    dir.write("soup.obj", text);
    let out = dir.run(&[
        "build",
        "--target",
        "soup.obj",
        "--out",
        "o",
        "--nest-evaluations",
        "100000",
        "--nest-seconds",
        "3600",
    ]);
    out.expect_code(0);
    assert!(
        out.stderr.contains("note: soup.obj: welded") && out.stderr.contains("turned 24 triangles"),
        "{out:?}"
    );
}
