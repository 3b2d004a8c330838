//! `spinvalence build` on targets whose goals cannot all be met (exit code 3, `--strict`),
//! with a designer's layout (`--layout`, `[surface] layout`), and on targets drawn in
//! metres or as an OBJ triangle soup.

use crate::fixtures;
use crate::util::{diagonals_cross, dot3, read_json, sub3, unmet_goals, Dir};

/// The wave canopy (z = 350 sin(x/1000) cos(y/1400), 6 x 4 m): its four-sided layout cannot
/// follow the curvature lines, so planarity is unmet (docs/secondary.md).
fn unmet() -> String {
    target("wave_canopy")
}

/// `fixtures/targets/NAME.obj` as a command-line argument.
fn target(name: &str) -> String {
    fixtures::path(&format!("targets/{name}.obj"))
        .display()
        .to_string()
}

#[test]
fn unmet_goals_still_build_everything_and_exit_3() {
    let dir = Dir::new();
    let target = unmet();
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
    let unmet = unmet_goals(&dir, "o");
    assert!(
        unmet.iter().any(|l| l.starts_with("planarity")),
        "{unmet:?}"
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

/// A hub mesh whose parts cannot be cut (here: a sheet too short for one tile) still gives
/// the user the hub mesh, the frame and the report to look at, with the strips stage's
/// reason among the unmet goals, and exit 3; nothing of an earlier build in the directory
/// is left to pass for this one's parts.
#[test]
fn parts_that_cannot_be_cut_leave_the_mesh_frame_and_report_and_exit_3() {
    let dir = Dir::new();
    std::fs::write(
        dir.join("short.toml"),
        "[joints]\nclose = false\n[strips]\nmax_length = 250\n",
    )
    .unwrap();
    // an earlier build's parts in the output directory
    std::fs::create_dir_all(dir.join("o/strips")).unwrap();
    std::fs::create_dir_all(dir.join("o/sheets")).unwrap();
    for f in [
        "strips/A01.dxf",
        "sheets/sheet-01.dxf",
        "strips.json",
        "nest.json",
        "bom.csv",
    ] {
        std::fs::write(dir.join(&format!("o/{f}")), "old").unwrap();
    }
    let out = dir.run(&[
        "build",
        "--config",
        "short.toml",
        "--target",
        "builtin:flat",
        "--out",
        "o",
    ]);
    out.expect_code(3);
    let warning = out
        .stderr
        .lines()
        .find(|l| l.starts_with("warning: ") && l.contains("exit code 3"))
        .unwrap_or_else(|| panic!("{out:?}"));
    assert!(
        warning.contains("no strips cut: strips: ")
            && warning.contains("more than max_length 250")
            && warning.contains("the hub mesh, the frame and the report were written"),
        "{warning}"
    );
    assert!(
        out.stdout.contains("none cut (see GOALS NOT MET)"),
        "{out:?}"
    );
    for f in [
        "mesh.obj",
        "frame.obj",
        "frame.json",
        "report.json",
        "report.html",
        "timings.json",
    ] {
        assert!(dir.join(&format!("o/{f}")).exists(), "{f} missing: {out:?}");
    }
    for f in ["strips.json", "nest.json", "bom.csv"] {
        assert!(!dir.join(&format!("o/{f}")).exists(), "{f} left: {out:?}");
    }
    for d in ["strips", "sheets"] {
        let left = std::fs::read_dir(dir.join(&format!("o/{d}")))
            .unwrap()
            .count();
        assert_eq!(left, 0, "{d}/ not empty");
    }
    // the files agree with each other: one unit per face of the hub mesh
    let mesh = std::fs::read_to_string(dir.join("o/mesh.obj")).unwrap();
    let faces = mesh.lines().filter(|l| l.starts_with("f ")).count();
    let frame = read_json(&dir.join("o/frame.json"));
    assert_eq!(frame["units"].as_array().unwrap().len(), faces);
    let unmet = unmet_goals(&dir, "o");
    assert!(
        unmet.iter().any(|l| l.starts_with("no strips cut: ")),
        "{unmet:?}"
    );
    // `check DIR` says where to look; the frame alone can be checked
    let check = dir.run(&["check", "o"]);
    check.expect_code(2);
    assert!(
        check.one_error_line().contains("that build cut no strips"),
        "{check:?}"
    );
    let html = std::fs::read_to_string(dir.join("o/report.html")).unwrap();
    assert!(
        html.contains("no strips cut: "),
        "the report does not say why"
    );
    assert!(!html.contains(">-0.0"), "a negative zero in the report");
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
fn a_layout_that_cannot_be_used_is_named_by_its_own_file() {
    let dir = Dir::new();
    let (text, _) = layout_obj();
    // two faces listing an edge the same way: the layout file is wrong, not the target
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let first_face = lines.iter().position(|l| l.starts_with("f ")).unwrap();
    let f: Vec<&str> = lines[first_face].split_whitespace().collect();
    lines[first_face] = format!("f {} {} {} {}", f[4], f[3], f[2], f[1]);
    dir.write("flipped.obj", lines.join("\n") + "\n");
    // the same layout drawn in metres: it does not lie on the target
    dir.write("metres.obj", crate::util::scale_obj(&text, 0.001));
    let run = |layout: &str| {
        let out = dir.run(&[
            "build",
            "--target",
            "builtin:dome",
            "--layout",
            layout,
            "--out",
            "t",
        ]);
        out.expect_code(2);
        out.one_error_line().to_string()
    };
    let flipped = run("flipped.obj");
    assert!(
        flipped.starts_with("error: flipped.obj: invalid layout: "),
        "{flipped}"
    );
    let metres = run("metres.obj");
    assert!(
        metres.starts_with("error: metres.obj: the layout's bounding box is from (-2.000, -2.000")
            && metres.contains("the target's from (-2000.000, -2000.000")
            && metres.contains(
                "its size is 9.96e-4 times the target's (layouts are read in millimetres"
            ),
        "{metres}"
    );
    assert!(!dir.join("t").exists());
}

#[test]
fn a_layout_vertex_far_out_is_named() {
    // a finite but absurd coordinate used to reach the build and fail there as "initial
    // face 0 is flipped"; the layout reader refuses it as the target reader does
    let dir = Dir::new();
    let (text, _) = layout_obj();
    let far = text.replacen(text.lines().next().unwrap(), "v 1e308 0 0", 1);
    dir.write("far.obj", far);
    let out = dir.run(&[
        "build",
        "--target",
        "builtin:dome",
        "--layout",
        "far.obj",
        "--out",
        "t",
    ]);
    out.expect_code(2);
    assert!(
        out.one_error_line().contains(
            "far.obj: vertex 1 at (1e308, 0, 0) is farther than 1e12 mm from the origin (a corrupt number, or not in mm?)"
        ),
        "{out:?}"
    );
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
fn a_target_needing_more_units_than_a_build_takes_is_refused_at_once() {
    let dir = Dir::new();
    // 10 x 8 km: about 8.9e8 units of 300 mm (the build once asked for 21.6 GB here)
    dir.write(
        "site.obj",
        "v 0 0 0\nv 1e7 0 0\nv 1e7 8e6 0\nv 0 8e6 0\nf 1 2 3\nf 1 3 4\n",
    );
    let out = dir.run(&["build", "--target", "site.obj", "--out", "o"]);
    out.expect_code(2);
    let line = out.one_error_line();
    assert!(
        line.contains("bounding box is 1.00e7 x 8.00e6 x 0 mm")
            && line.contains("needs about 888888889 units, more than the 100000 a build takes")
            && line.contains("at least 28285 mm"),
        "{out:?}"
    );
    assert!(!dir.join("o").exists());
    // the unit size it names is taken
    let near = dir.run(&[
        "build",
        "--target",
        "site.obj",
        "--unit-size",
        "28000",
        "--out",
        "o",
    ]);
    near.expect_code(2);
    assert!(
        near.one_error_line().contains("at least 28285 mm"),
        "{near:?}"
    );
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

/// Faces at every vertex of a quad OBJ (`v` and `f` lines), whether the vertex is on the
/// boundary (an edge with one face), and the number of boundary loops.
fn quad_obj_counts(text: &str) -> (Vec<usize>, Vec<bool>, usize) {
    let nv = text.lines().filter(|l| l.starts_with("v ")).count();
    let mut faces = vec![0usize; nv];
    let mut edges: std::collections::HashMap<(usize, usize), usize> = Default::default();
    for l in text.lines().filter(|l| l.starts_with("f ")) {
        let f: Vec<usize> = l[2..]
            .split_whitespace()
            .map(|s| s.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
            .collect();
        assert_eq!(f.len(), 4, "{l}");
        for k in 0..4 {
            faces[f[k]] += 1;
            let (a, b) = (f[k], f[(k + 1) % 4]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut boundary = vec![false; nv];
    let mut parent: Vec<usize> = (0..nv).collect();
    fn root(p: &[usize], mut x: usize) -> usize {
        while p[x] != x {
            x = p[x];
        }
        x
    }
    for (&(a, b), &n) in &edges {
        if n == 1 {
            boundary[a] = true;
            boundary[b] = true;
            let (ra, rb) = (root(&parent, a), root(&parent, b));
            parent[ra] = rb;
        }
    }
    let loops = (0..nv)
        .filter(|&v| boundary[v] && root(&parent, v) == v)
        .count();
    (faces, boundary, loops)
}

/// The automatic layout's irregular meshes go through every stage: a rounded triangle
/// (one face per corner around a valence-3 centre) and a roof with a courtyard (a ring,
/// two boundary loops) build with exit 0 or 3 as their report says, every unit is in
/// exactly one strip, every strip on one sheet, and `check` fails exactly when planarity
/// or conicality is reported unmet.
#[test]
fn automatic_layouts_build_through_to_the_sheets() {
    let dir = Dir::new();
    for (name, valence3, loops) in [("rounded_triangle", 1, 1), ("annulus_roof", 0, 2)] {
        let target = target(name);
        let out = dir.run(&[
            "build",
            "--target",
            &target,
            "--out",
            name,
            "--nest-evaluations",
            "100000",
            "--nest-seconds",
            "3600",
            "--quiet",
        ]);
        let unmet = unmet_goals(&dir, name);
        out.expect_code(if unmet.is_empty() { 0 } else { 3 });
        let mesh = std::fs::read_to_string(dir.join(&format!("{name}/mesh.obj"))).unwrap();
        let (faces, boundary, found_loops) = quad_obj_counts(&mesh);
        let irregular: Vec<usize> = (0..faces.len())
            .filter(|&v| !boundary[v] && faces[v] != 4)
            .collect();
        assert_eq!(irregular.len(), valence3, "{name}: {irregular:?}");
        assert!(irregular.iter().all(|&v| faces[v] == 3), "{name}");
        assert_eq!(found_loops, loops, "{name}");
        let units = mesh.lines().filter(|l| l.starts_with("f ")).count();
        let frame = read_json(&dir.join(&format!("{name}/frame.json")));
        assert_eq!(frame["units"].as_array().unwrap().len(), units, "{name}");
        // every unit in exactly one strip
        let strips = read_json(&dir.join(&format!("{name}/strips.json")));
        let mut seen = vec![0usize; units];
        let mut ids = Vec::new();
        for s in strips["strips"].as_array().unwrap() {
            ids.push(s["id"].as_str().unwrap().to_string());
            for u in s["units"].as_array().unwrap() {
                seen[u.as_u64().unwrap() as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{name}: {seen:?}");
        // every strip placed once
        let nest = read_json(&dir.join(&format!("{name}/nest.json")));
        assert!(nest["left_out"].as_array().unwrap().is_empty(), "{name}");
        let mut placed: Vec<String> = nest["sheets"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|s| s["placements"].as_array().unwrap().clone())
            .map(|p| p["strip"].as_str().unwrap().to_string())
            .collect();
        placed.sort();
        ids.sort();
        assert_eq!(placed, ids, "{name}");
        // `check` holds the goal tolerances
        let hub_goal = unmet
            .iter()
            .any(|l| l.starts_with("planarity") || l.starts_with("conical"));
        let check = dir.run(&["check", &format!("{name}/frame.json")]);
        if hub_goal {
            check.expect_code(1);
        }
    }
}

/// An open cylinder of radius 1500 mm and length 4000 mm as an OBJ triangle mesh (mm, 48
/// segments around, 16 along), its axis along x lying on the ground or along z standing.
fn tube_obj(standing: bool) -> String {
    let (around, along, radius, length) = (48, 16, 1500.0_f64, 4000.0);
    let mut obj = String::from("# open cylinder, r 1500 mm, 4000 mm long\n");
    for j in 0..=along {
        let t = length * j as f64 / along as f64;
        for i in 0..around {
            let a = std::f64::consts::TAU * i as f64 / around as f64;
            let (c, s) = (radius * a.cos(), radius * a.sin());
            let [x, y, z] = if standing {
                [c, s, t]
            } else {
                [t, c, s + radius]
            };
            obj += &format!("v {x:.4} {y:.4} {z:.4}\n");
        }
    }
    for j in 0..along {
        for i in 0..around {
            let at = |j: usize, i: usize| j * around + i % around + 1;
            let (a, b, c, d) = (at(j, i), at(j, i + 1), at(j + 1, i + 1), at(j + 1, i));
            obj += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
    obj
}

/// A tube (an open cylinder, standing or lying on its side: two boundary loops that are
/// not one inside the other in plan) is laid out as a ring of faces along its axis: its
/// hub mesh is all quads, every inner vertex of valence 4 and every boundary one of
/// valence 3 (no corner, no irregular vertex), one boundary loop at each rim, and the
/// faces run once round the tube. It failed with `initial face 85 is flipped against the
/// target` (the courtyard's ring joined points on opposite sides of the tube). The joints
/// are left open to keep the test short.
#[test]
fn a_tube_is_laid_out_as_a_ring_along_its_axis() {
    let dir = Dir::new();
    dir.write("open.toml", "[joints]\nclose = false\n");
    for (name, standing) in [("standing", true), ("lying", false)] {
        let target = format!("{name}.obj");
        dir.write(&target, tube_obj(standing));
        let out = dir.run(&[
            "build",
            "--config",
            "open.toml",
            "--target",
            &target,
            "--out",
            name,
            "--nest-evaluations",
            "20000",
            "--nest-seconds",
            "3600",
            "--quiet",
        ]);
        // every hub mesh goal met; the joints, left open as asked, fail the fold check of
        // the parts as cut, which is named (exit 3)
        out.expect_code(3);
        let unmet = unmet_goals(&dir, name);
        assert!(
            unmet.len() == 1
                && unmet[0].starts_with("fold check: ")
                && unmet[0].contains("weld: plates of neighbouring strips apart"),
            "{name}: {unmet:?}"
        );
        let mesh = std::fs::read_to_string(dir.join(&format!("{name}/mesh.obj"))).unwrap();
        assert!(
            mesh.lines()
                .filter(|l| l.starts_with("f "))
                .all(|l| l.split_whitespace().count() == 5),
            "{name}: a face that is not a quad"
        );
        let (faces_at, boundary, loops) = quad_obj_counts(&mesh);
        assert_eq!(loops, 2, "{name}");
        let odd: Vec<usize> = (0..faces_at.len())
            .filter(|&v| faces_at[v] != if boundary[v] { 2 } else { 4 })
            .collect();
        assert!(odd.is_empty(), "{name}: vertices {odd:?} not regular");
        // a ring of `around` columns and `rows` rows: (rows + 1) x around vertices, rows x
        // around faces, `around` on each rim
        let units = mesh.lines().filter(|l| l.starts_with("f ")).count();
        let rim = boundary.iter().filter(|&&b| b).count();
        let around = rim / 2;
        assert_eq!(faces_at.len() - units, around, "{name}");
        assert_eq!(units % around, 0, "{name}");
        // the hubs lie on the tube
        let radius = |p: [f64; 3]| {
            if standing {
                p[0].hypot(p[1])
            } else {
                p[1].hypot(p[2] - 1500.0)
            }
        };
        let points: Vec<[f64; 3]> = mesh
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
                [c[0], c[1], c[2]]
            })
            .collect();
        assert!(
            points.iter().all(|&p| (radius(p) - 1500.0).abs() < 30.0),
            "{name}: a hub off the tube"
        );
    }
}

/// The vertices and faces (0-based) of an OBJ's `v` and `f` lines.
fn obj_parts(text: &str) -> (Vec<[f64; 3]>, Vec<Vec<usize>>) {
    let vertices = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect();
    let faces = text
        .lines()
        .filter_map(|l| l.strip_prefix("f "))
        .map(|l| {
            l.split_whitespace()
                .map(|s| s.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                .collect()
        })
        .collect();
    (vertices, faces)
}

/// `spinvalence build` of `target` at 150 mm units into `o`, the nesting held to 20,000
/// evaluations (its result the same on any machine).
fn build_at_150(dir: &Dir, target: &str) -> crate::util::Output {
    dir.run(&[
        "build",
        "--target",
        target,
        "--unit-size",
        "150",
        "--out",
        "o",
        "--nest-evaluations",
        "20000",
        "--nest-seconds",
        "3600",
    ])
}

/// A courtyard that is not star-shaped about its centre (fixtures/targets/l_courtyard.obj:
/// an 8 x 5 m rectangle round an L-shaped court, from the layout probes) folded both rings
/// the automatic layout draws: it failed with a bare `initial face 176 is flipped against
/// the target` and no file, then with a line naming each ring and still no file. Its sides
/// run along two directions at right angles, so the lines through its corners cut it into
/// cells, and the build goes through to the sheets (exit 3 only for the laps no sheet
/// welds at 150 mm). From the files: the summary and report.json name the layout; the hub
/// mesh has the target's two boundary loops, no interior irregular vertex, three faces at
/// each of the court's five corners that reach into the roof and one at the other five
/// corners, every face up and none over the court, and meets the hub mesh goals; every
/// unit is in one strip and every strip on a sheet.
#[test]
fn a_courtyard_with_sides_at_right_angles_is_cut_into_cells_through_to_the_sheets() {
    let dir = Dir::new();
    let target = target("l_courtyard");
    let out = build_at_150(&dir, &target);
    out.expect_code(3);
    let row = out
        .stdout
        .lines()
        .find(|l| l.starts_with("layout "))
        .unwrap_or_else(|| panic!("{out:?}"));
    let report = read_json(&dir.join("o/report.json"));
    let line = report["layout"].as_str().unwrap();
    assert!(row.ends_with(line), "{row}");
    assert!(
        line.ends_with("cells cut by the lines through the corners (the sides run along two directions at right angles)"),
        "{line}"
    );
    let html = std::fs::read_to_string(dir.join("o/report.html")).unwrap();
    assert!(html.contains(&format!("<tr><th>layout</th><td>{line}</td></tr>")));
    // the laps, and the parts as cut with their joints left open: no hub mesh goal
    let unmet = unmet_goals(&dir, "o");
    assert!(
        unmet.len() == 2
            && unmet[0].starts_with("hub laps too short to weld")
            && unmet[1].starts_with("fold check: "),
        "{unmet:?}"
    );
    let mesh = std::fs::read_to_string(dir.join("o/mesh.obj")).unwrap();
    let (valence, boundary, loops) = quad_obj_counts(&mesh);
    assert_eq!(loops, 2);
    let count = |on: bool, faces: usize| {
        (0..valence.len())
            .filter(|&v| boundary[v] == on && valence[v] == faces)
            .count()
    };
    let interior_irregular = (0..valence.len())
        .filter(|&v| !boundary[v] && valence[v] != 4)
        .count();
    assert_eq!(interior_irregular, 0);
    assert_eq!((count(true, 3), count(true, 1)), (5, 5));
    over_the_target_through_to_the_sheets(&dir.join("o"), &target);
}

/// From the files in `out` of a build of `target`: every hub face up and its centre over
/// the target in plan (over none of its courts), every unit in exactly one strip of
/// strips.json and every strip placed on a sheet of nest.json.
fn over_the_target_through_to_the_sheets(out: &std::path::Path, target: &str) {
    let mesh = std::fs::read_to_string(out.join("mesh.obj")).unwrap();
    let (hub, faces) = obj_parts(&mesh);
    let (tv, tris) = obj_parts(&std::fs::read_to_string(target).unwrap());
    let over = |x: f64, y: f64| {
        tris.iter().any(|t| {
            let side = |a: usize, b: usize| {
                (tv[b][0] - tv[a][0]) * (y - tv[a][1]) - (tv[b][1] - tv[a][1]) * (x - tv[a][0])
            };
            let s = [side(t[0], t[1]), side(t[1], t[2]), side(t[2], t[0])];
            s.iter().all(|&d| d >= 0.0) || s.iter().all(|&d| d <= 0.0)
        })
    };
    for f in &faces {
        let p: Vec<[f64; 3]> = f.iter().map(|&i| hub[i]).collect();
        let (d1, d2) = (
            [p[2][0] - p[0][0], p[2][1] - p[0][1]],
            [p[3][0] - p[1][0], p[3][1] - p[1][1]],
        );
        assert!(
            d1[0] * d2[1] - d1[1] * d2[0] > 0.0,
            "a face turned over: {f:?}"
        );
        let c = |k: usize| p.iter().map(|q| q[k]).sum::<f64>() / 4.0;
        assert!(over(c(0), c(1)), "a face over the court: {f:?}");
    }
    // every unit in exactly one strip, every strip on a sheet
    let strips = read_json(&out.join("strips.json"));
    let mut seen = vec![0usize; faces.len()];
    let mut ids = Vec::new();
    for s in strips["strips"].as_array().unwrap() {
        ids.push(s["id"].as_str().unwrap().to_string());
        for u in s["units"].as_array().unwrap() {
            seen[u.as_u64().unwrap() as usize] += 1;
        }
    }
    assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    let nest = read_json(&out.join("nest.json"));
    assert!(nest["left_out"].as_array().unwrap().is_empty());
    let mut placed: Vec<String> = nest["sheets"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["placements"].as_array().unwrap().clone())
        .map(|p| p["strip"].as_str().unwrap().to_string())
        .collect();
    placed.sort();
    ids.sort();
    assert_eq!(placed, ids);
}

/// A roof round two round courts (fixtures/targets/round_courtyards.obj: three boundary
/// loops, no corner: neither the cells nor a ring follows it; it was refused) gets the
/// triangulated footprint and goes through to the sheets (exit 3: its irregular vertices
/// miss goals, and no sheet welds laps at 150 mm): three boundary loops and irregular
/// vertices in mesh.obj, checked through to the sheets as the courtyard's cells are.
#[test]
fn a_roof_round_two_round_courts_is_triangulated_through_to_the_sheets() {
    let dir = Dir::new();
    let target = target("round_courtyards");
    let out = build_at_150(&dir, &target);
    out.expect_code(3);
    let report = read_json(&dir.join("o/report.json"));
    let line = report["layout"].as_str().unwrap();
    assert!(
        line.starts_with("the footprint triangulated in plan"),
        "{line}"
    );
    let mesh = std::fs::read_to_string(dir.join("o/mesh.obj")).unwrap();
    let (valence, boundary, loops) = quad_obj_counts(&mesh);
    assert_eq!(loops, 3);
    assert!((0..valence.len()).any(|v| !boundary[v] && valence[v] == 3));
    over_the_target_through_to_the_sheets(&dir.join("o"), &target);
}

/// Where the joints are left open (here: laps no sheet can weld at 150 mm) and two units of
/// a strip face each other too little for a bridge (the arched tent's faces are far from
/// planar), the strip ends there instead of the build refusing the parts: the summary
/// names those units, and in frame.json they belong to different strips while every unit
/// is in exactly one strip of strips.json.
#[test]
fn a_bridge_that_cannot_be_cut_ends_its_strip() {
    let dir = Dir::new();
    let target = target("arched_tent");
    let out = build_at_150(&dir, &target);
    out.expect_code(3);
    let row = out
        .stdout
        .lines()
        .find(|l| l.starts_with("strips "))
        .unwrap_or_else(|| panic!("{out:?}"));
    let (_, named) = row
        .split_once("bridges could not be cut (facing sides overlap too little): the strips end there, welded on site (")
        .unwrap_or_else(|| panic!("{row}"));
    let frame = read_json(&dir.join("o/frame.json"));
    let strip_of = |id: &str| -> String {
        let unit = frame["units"]
            .as_array()
            .unwrap()
            .iter()
            .find(|u| u["id"] == id)
            .unwrap_or_else(|| panic!("no unit {id}"));
        unit["strip"].as_str().unwrap().to_string()
    };
    let pairs: Vec<(&str, &str)> = named
        .trim_end_matches(')')
        .split("; ")
        .filter(|p| *p != "...")
        .map(|p| p.split_once(" - ").unwrap())
        .collect();
    assert!(!pairs.is_empty(), "{row}");
    for (a, b) in pairs {
        assert_ne!(strip_of(a), strip_of(b), "{a} and {b} in one strip");
    }
    let strips = read_json(&dir.join("o/strips.json"));
    let mut seen = vec![0usize; frame["units"].as_array().unwrap().len()];
    for s in strips["strips"].as_array().unwrap() {
        for u in s["units"].as_array().unwrap() {
            seen[u.as_u64().unwrap() as usize] += 1;
        }
    }
    assert!(
        seen.iter().all(|&n| n == 1),
        "a unit not in exactly one strip"
    );
    assert!(dir.join("o/nest.json").exists());
}

/// A joint solve that pulls the hub faces far from planar while joints stay open gives up
/// where it does, in each strip direction, and the build keeps the frame it started from:
/// on the horseshoe's triangulated footprint at 300 mm the solve took planarity from 0.015
/// to 0.6 over 390-460 iterations before the build threw the result away; it now stops
/// after the first stage of 92. Measured with the test's own code: mesh.obj's faces are as
/// planar as the message says the solve started, far inside what it names as pulled.
#[test]
fn a_joint_solve_that_pulls_the_hub_faces_off_planar_gives_up_early() {
    let dir = Dir::new();
    let out = dir.run(&[
        "build",
        "--target",
        &target("horseshoe"),
        "--unit-size",
        "300",
        "--out",
        "o",
        "--nest-evaluations",
        "2000",
    ]);
    out.expect_code(3);
    let unmet = unmet_goals(&dir, "o");
    let line = unmet
        .iter()
        .find(|l| l.starts_with("joints not closed: "))
        .unwrap_or_else(|| panic!("{unmet:?}"))
        .to_string();
    // one reason per direction: (planarity pulled to, started at, iterations)
    let figures: Vec<(f64, f64, usize)> = line
        .split("(planarity ")
        .skip(1)
        .map(|s| {
            let (pulled, rest) = s.split_once(" against ").unwrap();
            let (start, rest) = rest.split_once(", after ").unwrap();
            let (its, _) = rest.split_once(" iterations").unwrap();
            (
                pulled.parse().unwrap(),
                start.parse().unwrap(),
                its.parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(figures.len(), 2, "{line}");
    assert!(line.contains("strips along u") && line.contains("strips along v"));
    let (vertices, faces) = obj_parts(&std::fs::read_to_string(dir.join("o/mesh.obj")).unwrap());
    let planarity = faces
        .iter()
        .map(|f| {
            let p: Vec<[f64; 3]> = f.iter().map(|&v| vertices[v]).collect();
            // the distance between the diagonals' lines over the mean side
            let n = diagonals_cross(&p);
            let distance = (dot3(sub3(p[1], p[0]), n) / dot3(n, n).sqrt()).abs();
            let side = |k: usize| {
                let e = sub3(p[(k + 1) % 4], p[k]);
                dot3(e, e).sqrt()
            };
            let mean = (0..4).map(side).sum::<f64>() / 4.0;
            distance / mean
        })
        .fold(0.0, f64::max);
    for (pulled, start, iterations) in figures {
        // the default budget is 250 iterations per direction, more with the rounds
        assert!(iterations < 250, "{line}");
        assert!(pulled > 0.1 && pulled > 2.0 * start.max(0.002), "{line}");
        assert!(
            (planarity - start).abs() < 1e-4,
            "mesh.obj {planarity} against {line}"
        );
    }
}
