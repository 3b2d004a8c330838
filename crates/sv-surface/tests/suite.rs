//! Issue 16 on the target suite in `fixtures/targets/` (written by `cargo run -p sv-surface
//! --example make_targets`): the automatic layout puts the irregular vertices a footprint
//! needs (a triangle's centre, an oval's O-grid, none on an L, a ring around a hole), and
//! every target comes back unfolded with each unmet goal named where it is worst. The
//! figures of every target at 300 and 150 mm are in docs/secondary.md ("The issue 16
//! suite"); `cargo run --release -p sv-surface --example pipeline -- 300
//! fixtures/targets/*.obj` prints them.

mod common;

use std::collections::HashMap;

use common::load;
use sv_frame::QuadMesh;
use sv_surface::{build_secondary, initial_grid, SecondaryOptions};

/// Every target file of the suite: the seven of issue 3 and the ten of issue 16.
const SUITE: [&str; 17] = [
    "dome_lens.obj",
    "cone_sector.obj",
    "trumpet_sector.obj",
    "bell_sector.obj",
    "cylinder_wave.obj",
    "hypar_pentagon.obj",
    "wavy_mixed.obj",
    "wave_canopy.obj",
    "egg_crate.obj",
    "arched_tent.obj",
    "skewed_vault.obj",
    "twisted_vault.obj",
    "torus_patch.obj",
    "l_footprint.obj",
    "rounded_triangle.obj",
    "oval_dome.obj",
    "annulus_roof.obj",
];

fn opts(unit: f64) -> SecondaryOptions {
    SecondaryOptions {
        unit_size: unit,
        ..Default::default()
    }
}

/// Faces at every vertex, whether it is on the boundary (an edge with one face), and the
/// number of boundary loops (components of the boundary edges).
struct Counts {
    faces: Vec<usize>,
    boundary: Vec<bool>,
    loops: usize,
}

fn counts(mesh: &QuadMesh) -> Counts {
    let nv = mesh.vertices.len();
    let mut faces = vec![0; nv];
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    for f in &mesh.faces {
        for k in 0..4 {
            faces[f[k]] += 1;
            let (a, b) = (f[k], f[(k + 1) % 4]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut boundary = vec![false; nv];
    let mut parent: Vec<usize> = (0..nv).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            x = p[x];
        }
        x
    }
    for (&(a, b), &n) in &edges {
        assert!(n <= 2, "edge {a}-{b} has {n} faces");
        if n == 1 {
            boundary[a] = true;
            boundary[b] = true;
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra] = rb;
        }
    }
    let loops = (0..nv)
        .filter(|&v| boundary[v] && root(&mut parent, v) == v)
        .count();
    Counts {
        faces,
        boundary,
        loops,
    }
}

/// (faces at the interior irregular vertices, sorted; boundary vertices with three faces)
fn singularities(mesh: &QuadMesh) -> (Vec<usize>, usize) {
    let c = counts(mesh);
    let mut interior: Vec<usize> = (0..mesh.vertices.len())
        .filter(|&v| !c.boundary[v] && c.faces[v] != 4)
        .map(|v| c.faces[v])
        .collect();
    interior.sort_unstable();
    let reflex = (0..mesh.vertices.len())
        .filter(|&v| c.boundary[v] && c.faces[v] == 3)
        .count();
    (interior, reflex)
}

#[test]
fn suite_has_the_targets_of_the_issue_and_they_are_valid() {
    for name in SUITE {
        let t = load(name);
        let loops = t.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(t.area() > 8e6, "{name}: area {}", t.area());
        let holes = usize::from(name == "annulus_roof.obj");
        assert_eq!(loops.len(), 1 + holes, "{name}");
    }
}

#[test]
fn automatic_layouts_put_the_irregular_vertices_the_footprint_needs() {
    for unit in [300.0, 150.0] {
        let mesh = |name: &str| {
            initial_grid(&load(name), &opts(unit)).unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        // a triangle: one face per corner around a valence-3 centre
        assert_eq!(
            singularities(&mesh("rounded_triangle.obj")),
            (vec![3], 0),
            "{unit}"
        );
        // an oval: an O-grid, four valence-3 vertices around the inner quad
        assert_eq!(
            singularities(&mesh("oval_dome.obj")),
            (vec![3, 3, 3, 3], 0),
            "{unit}"
        );
        // an L: three blocks meeting at the reflex corner, which has three faces
        assert_eq!(
            singularities(&mesh("l_footprint.obj")),
            (vec![], 1),
            "{unit}"
        );
        // a roof with a courtyard: a ring, two boundary loops, no irregular vertex
        let ring = mesh("annulus_roof.obj");
        assert_eq!(singularities(&ring), (vec![], 0), "{unit}");
        assert_eq!(counts(&ring).loops, 2, "{unit}");
        // four corners: the conformal grid, as before
        for name in ["wave_canopy.obj", "torus_patch.obj", "arched_tent.obj"] {
            assert_eq!(singularities(&mesh(name)), (vec![], 0), "{name} {unit}");
        }
        // the faces are near the unit size: mean side within 0.8-1.25 of it
        for name in ["rounded_triangle.obj", "oval_dome.obj", "l_footprint.obj"] {
            let m = mesh(name);
            let (sum, n) = m.faces.iter().fold((0.0, 0), |(s, n), f| {
                let side: f64 = (0..4)
                    .map(|k| (m.vertices[f[(k + 1) % 4]] - m.vertices[f[k]]).norm())
                    .sum();
                (s + side, n + 4)
            });
            let mean = sum / n as f64;
            assert!(
                (0.8 * unit..1.25 * unit).contains(&mean),
                "{name} {unit}: {mean}"
            );
        }
    }
}

/// The L, the lens-shaped dome and the torus patch meet every goal of the secondary stage
/// at both sizes, the face sides within 0.7-1.4 of the unit included, and their frames
/// pass the checks of `spinvalence check`.
#[test]
fn l_footprint_dome_lens_and_torus_patch_meet_every_goal_at_300_and_150() {
    for (name, unit) in ["l_footprint.obj", "dome_lens.obj", "torus_patch.obj"]
        .into_iter()
        .flat_map(|n| [(n, 300.0), (n, 150.0)])
    {
        let (mesh, r) = build_secondary(&load(name), &opts(unit), &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name} {unit}: {e}"));
        assert!(r.unmet.is_empty(), "{name} {unit}: {:?}", r.unmet);
        // the figures themselves, from the mesh
        for f in 0..mesh.faces.len() {
            let p = mesh.face_points(f);
            let side: Vec<f64> = (0..4).map(|k| (p[(k + 1) % 4] - p[k]).norm()).collect();
            let mean = side.iter().sum::<f64>() / 4.0;
            for s in &side {
                assert!(
                    (0.7 * unit..=1.4 * unit).contains(s),
                    "{name} {unit}: face {f}: {side:?}"
                );
            }
            let d = sv_geom::quad_diagonal_distance(&p);
            assert!(
                d <= 0.002 * mean,
                "{name} {unit}: face {f}: diagonal distance {d}"
            );
        }
        let solved = sv_frame::solve(&mesh, &sv_frame::SolveOptions::default(), &mut |_| {})
            .unwrap_or_else(|e| panic!("{name} {unit}: primary: {e}"));
        let checked = sv_frame::check_frame(&solved.to_frame_file(&mesh), &Default::default());
        assert!(checked.ok(), "{name} {unit}: {checked:?}");
    }
}

/// Every target of the suite at 300 mm: an unfolded mesh (convex faces facing up, no
/// collapsed edge) on the target, and every goal the report measures as missed named on
/// one line with its worst face or vertex.
#[test]
fn every_suite_target_comes_back_unfolded_with_its_unmet_goals_named() {
    for name in SUITE {
        let (mesh, r) = build_secondary(&load(name), &opts(300.0), &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(r.non_convex_faces.is_empty(), "{name}: {r:?}");
        for f in 0..mesh.faces.len() {
            let p = mesh.face_points(f);
            let n = (p[0] - p[2]).cross(&(p[1] - p[3]));
            assert!(n.z > 0.0, "{name}: face {f} faces down");
            for k in 0..4 {
                let e = (p[(k + 1) % 4] - p[k]).norm();
                assert!(e > 0.2 * r.mean_edge, "{name}: face {f} edge {e}");
            }
        }
        // where the goals conflict the stage returns the iterate nearest them, which
        // keeps every vertex on the target (5 % of the side)
        assert!(r.closeness_max <= 0.05, "{name}: {r:?}");
        let named = |goal: &str| r.unmet.iter().any(|l| l.starts_with(goal));
        assert_eq!(r.planarity_max > 0.002, named("planarity"), "{name}: {r:?}");
        assert_eq!(r.conical_max_deg > 0.5, named("conical"), "{name}: {r:?}");
        assert_eq!(
            r.side_min < 0.7 || r.side_max > 1.4,
            named("face sides"),
            "{name}: {r:?}"
        );
        for line in &r.unmet {
            assert!(!line.contains('\n'), "{name}: {line}");
            assert!(
                line.contains("face") || line.contains("vertex") || line.contains("iteration"),
                "{name}: {line}"
            );
        }
    }
}

/// Largest angle balance `|w0 - w1 + w2 - w3|` (degrees) over the interior vertices with
/// four faces: the corner angles of each vertex's faces, alternately signed in fan order.
fn worst_angle_balance(mesh: &QuadMesh) -> f64 {
    let c = counts(mesh);
    let mut corners: Vec<Vec<(usize, usize)>> = vec![Vec::new(); mesh.vertices.len()];
    for (f, face) in mesh.faces.iter().enumerate() {
        for k in 0..4 {
            corners[face[k]].push((f, k));
        }
    }
    let mut worst: f64 = 0.0;
    for (v, around) in corners.iter().enumerate() {
        if c.boundary[v] || around.len() != 4 {
            continue;
        }
        // the fan in order: each face's next vertex is the following face's previous one
        let next = |(f, k): (usize, usize)| mesh.faces[f][(k + 1) % 4];
        let prev = |(f, k): (usize, usize)| mesh.faces[f][(k + 3) % 4];
        let mut fan = vec![around[0]];
        while fan.len() < 4 {
            let out = next(fan[fan.len() - 1]);
            fan.push(
                *around
                    .iter()
                    .find(|&&a| prev(a) == out)
                    .expect("closed fan"),
            );
        }
        let p = mesh.vertices[v];
        let mut sum = 0.0;
        for (s, &(f, k)) in fan.iter().enumerate() {
            let a = mesh.vertices[mesh.faces[f][(k + 1) % 4]] - p;
            let b = mesh.vertices[mesh.faces[f][(k + 3) % 4]] - p;
            let sign = if s % 2 == 0 { 1.0 } else { -1.0 };
            sum += sign * a.angle(&b);
        }
        worst = worst.max(sum.abs().to_degrees());
    }
    worst
}

#[test]
fn the_oval_o_grids_sheared_faces_are_undone_in_a_few_iterations() {
    // the subdivided O-grid starts with faces sheared to about 30 degrees next to its
    // valence-3 vertices; the steps that undo them ask for moves of several mean edges,
    // and the step cap grows while they are taken whole
    let target = load("oval_dome.obj");
    let unit = 100.0;
    let start = initial_grid(&target, &opts(unit)).unwrap();
    let before = worst_angle_balance(&start);
    let few = SecondaryOptions {
        max_iterations: 20,
        ..opts(unit)
    };
    let (mesh, report) = build_secondary(&target, &few, &mut |_, _| {}).unwrap();
    let after = worst_angle_balance(&mesh);
    assert!(
        before > 150.0,
        "the O-grid at {unit} mm starts with a worst angle balance of {before:.1} deg (sheared faces expected)"
    );
    // with the cap fixed at 0.1 mean edge it was still 98 degrees after 20 iterations
    assert!(
        after < 0.5,
        "after {} iterations the worst angle balance is {after:.2} deg (from {before:.1})",
        report.iterations
    );
    assert!(
        report.unmet.iter().all(|u| !u.contains("folds")),
        "{:?}",
        report.unmet
    );
}

#[test]
fn a_run_that_cannot_meet_every_goal_stops_once_it_no_longer_gains() {
    // the oval at 250 mm is planar and conical after about 30 iterations, but its face
    // sides cannot all come within 0.7-1.4 of the unit (the faces next to a valence-3
    // vertex); the iterates then cycled between two meshes up to the iteration limit
    let target = load("oval_dome.obj");
    let (mesh, report) = build_secondary(&target, &opts(250.0), &mut |_, _| {}).unwrap();
    let limit = SecondaryOptions::default().max_iterations;
    assert!(
        report.unmet.iter().any(|u| u.starts_with("face sides")),
        "{:?}",
        report.unmet
    );
    assert!(
        report.planarity_max <= 0.002 && report.conical_max_deg <= 0.5,
        "planarity {} conical {}",
        report.planarity_max,
        report.conical_max_deg
    );
    assert!(
        report.iterations < limit,
        "{} iterations of {limit} on {} faces",
        report.iterations,
        mesh.faces.len()
    );
}

/// A footprint without corners whose centre lies outside its plan (horseshoe.obj: a
/// 1.5 m band bent round a half circle, half-round ends). The O-grid round that centre
/// folds; the four-corner grid drawn next faces up but leaves the legs' ends bare (its
/// corners are the footprint's extremes along the diagonals: it started covering 63 % at
/// 300 mm and ended with faces of 6.9 units); so the triangulated footprint is drawn, which
/// covers it.
/// Measured here in plan with this test's own code: the area of the target whose triangles'
/// centres lie under a face of the hub mesh.
#[test]
fn a_horseshoe_that_the_grids_leave_bare_gets_the_triangulated_footprint() {
    let target = load("horseshoe.obj");
    assert_eq!(target.validate().unwrap().len(), 1);
    for unit in [300.0, 150.0] {
        let initial = initial_grid(&target, &opts(unit)).unwrap();
        assert!(unfolded_and_over_the_target(&initial, &target), "{unit}");
        assert!(covered_in_plan(&initial, &target) > 0.95, "{unit}");
        let (mesh, r) = build_secondary(&target, &opts(unit), &mut |_, _| {}).unwrap();
        assert!(
            r.layout.starts_with("the footprint triangulated in plan"),
            "{unit}: {}",
            r.layout
        );
        assert!(unfolded_and_over_the_target(&mesh, &target), "{unit}");
        let covered = covered_in_plan(&mesh, &target);
        assert!(covered > 0.95, "{unit}: {covered}");
        assert!(r.non_convex_faces.is_empty(), "{unit}: {r:?}");
    }
}

/// The fraction of `target`'s area (in plan) whose triangles have their centre under a
/// face of `mesh` in plan (each face as two triangles), for targets that are one sheet
/// over the XY plane.
fn covered_in_plan(mesh: &QuadMesh, target: &sv_surface::TargetMesh) -> f64 {
    let xy = |q: &sv_geom::Point3| [q.x, q.y];
    let halves: Vec<[[f64; 2]; 3]> = (0..mesh.faces.len())
        .flat_map(|f| {
            let p = mesh.face_points(f).map(|q| xy(&q));
            [[p[0], p[1], p[2]], [p[0], p[2], p[3]]]
        })
        .collect();
    let (mut covered, mut total) = (0.0, 0.0);
    for t in &target.triangles {
        let p = t.map(|i| xy(&target.vertices[i]));
        let area = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
            - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]))
            .abs()
            / 2.0;
        let c = [
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ];
        total += area;
        if halves.iter().any(|&h| in_triangle(c, h)) {
            covered += area;
        }
    }
    covered / total
}

/// Whether `p` lies in the triangle `t` (in plan, either winding, edges included).
fn in_triangle(p: [f64; 2], t: [[f64; 2]; 3]) -> bool {
    let side =
        |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let s = [side(t[0], t[1]), side(t[1], t[2]), side(t[2], t[0])];
    s.iter().all(|&d| d >= 0.0) || s.iter().all(|&d| d <= 0.0)
}

/// Whether every face of `mesh` faces up (its diagonals' cross product), no edge is shorter
/// than a fifth of the mean edge (what the optimiser takes for collapsed), and every face
/// centre lies over `target` in plan (inside one of its triangles, not over a court).
fn unfolded_and_over_the_target(mesh: &QuadMesh, target: &sv_surface::TargetMesh) -> bool {
    let up = (0..mesh.faces.len()).all(|f| {
        let p = mesh.face_points(f);
        (p[0] - p[2]).cross(&(p[1] - p[3])).z > 0.0
    });
    let edges: Vec<f64> = mesh
        .faces
        .iter()
        .flat_map(|f| (0..4).map(|k| (mesh.vertices[f[k]] - mesh.vertices[f[(k + 1) % 4]]).norm()))
        .collect();
    let mean = edges.iter().sum::<f64>() / edges.len() as f64;
    let v = &target.vertices;
    let over = |x: f64, y: f64| {
        (target.triangles.iter()).any(|t| in_triangle([x, y], t.map(|i| [v[i].x, v[i].y])))
    };
    let centres_over = (0..mesh.faces.len()).all(|f| {
        let p = mesh.face_points(f);
        over(
            p.iter().map(|q| q.x).sum::<f64>() / 4.0,
            p.iter().map(|q| q.y).sum::<f64>() / 4.0,
        )
    });
    up && edges.iter().all(|&e| e >= 0.2 * mean) && centres_over
}

/// A boomerang (fixtures/targets/boomerang.obj: three sharp tips, a round inner bend):
/// one face per corner puts the centre by the bend, where its faces are slivers, and the
/// four-corner grid has an edge as short there. The optimiser cannot move a mesh with an
/// edge under a fifth of the mean (it returned it untouched, and the primary solve failed
/// naming a unit). Both are named with what is wrong and where (by the bend, x = 0), and
/// the last layout, the footprint triangulated, is drawn: it starts unfolded with no
/// collapsed edge and its irregular vertices where the triangulation put them.
#[test]
fn a_layout_that_starts_with_collapsed_edges_gives_way_to_the_triangulated_footprint() {
    let target = load("boomerang.obj");
    let start = initial_grid(&target, &opts(300.0)).unwrap();
    assert!(unfolded_and_over_the_target(&start, &target));
    assert!(!singularities(&start).0.is_empty());
    let (mesh, r) = build_secondary(&target, &opts(300.0), &mut |_, _| {}).unwrap();
    assert!(unfolded_and_over_the_target(&mesh, &target), "{r:?}");
    let why = &r.layout;
    assert!(
        why.starts_with("the footprint triangulated in plan"),
        "{why}"
    );
    assert!(
        why.contains("after one face per corner (3 corners"),
        "{why}"
    );
    assert!(why.contains("then the four-corner grid"), "{why}");
    assert!(
        why.contains("edges shorter than 0.2 of the mean edge"),
        "{why}"
    );
    assert!(why.contains("--layout COARSE.obj"), "{why}");
    // the shortest edge of each layout tried lies by the inner bend, on the plan's axis
    let places: Vec<f64> = why
        .split("), the shortest ")
        .skip(1)
        .map(|rest| {
            let at = &rest[rest.find("at (").unwrap() + 4..];
            at[..at.find(',').unwrap()].parse().unwrap()
        })
        .collect();
    assert_eq!(places.len(), 2, "{why}");
    assert!(places.iter().all(|x| x.abs() < 100.0), "{why}");
}

/// Footprints whose sides run along two directions at right angles (a U plan; a T plan,
/// whose sides the tilt of its plan turns by 100 mm over 2 m; a notch whose corners lie
/// closer than the other layouts look for corners; a roof round two rectangular courts,
/// three boundary loops) are cut into cells by the lines through their corners: no interior irregular vertex, one face at every convex corner and three
/// at every reflex one, and every goal of the hub mesh met at 300 and 150 mm. The U plan
/// had the four-corner grid across its reflex corners (coverage 0.82, a boundary 216 mm
/// off); the courts were refused (the automatic layout took one or two loops).
#[test]
fn footprints_with_sides_at_right_angles_are_cut_into_cells() {
    for (name, loops, convex, reflex) in [
        ("u_plan.obj", 1, 6, 2),
        ("t_plan.obj", 1, 6, 2),
        ("notch_plan.obj", 1, 6, 2),
        ("two_courtyards.obj", 3, 4, 8),
    ] {
        let target = load(name);
        assert_eq!(target.validate().unwrap().len(), loops, "{name}");
        for unit in [300.0, 150.0] {
            let start = initial_grid(&target, &opts(unit)).unwrap();
            let c = counts(&start);
            assert_eq!(c.loops, loops, "{name}");
            assert_eq!(singularities(&start), (vec![], reflex), "{name} {unit}");
            let corners = (0..start.vertices.len())
                .filter(|&v| c.boundary[v] && c.faces[v] == 1)
                .count();
            assert_eq!(corners, convex, "{name} {unit}");
            assert!(
                unfolded_and_over_the_target(&start, &target),
                "{name} {unit}"
            );
            let (mesh, r) = build_secondary(&target, &opts(unit), &mut |_, _| {}).unwrap();
            assert!(
                unfolded_and_over_the_target(&mesh, &target),
                "{name} {unit}"
            );
            assert!(
                r.layout
                    .contains("cells cut by the lines through the corners"),
                "{name} {unit}: {}",
                r.layout
            );
            assert!(r.unmet.is_empty(), "{name} {unit}: {:?}", r.unmet);
        }
    }
}

/// A roof round two round courts (fixtures/targets/round_courtyards.obj: three boundary
/// loops, no corner), which neither the cells nor a ring follows (it was refused: "the
/// automatic layout handles one or two"): the triangulated footprint covers it, with three
/// boundary loops, no face over a court, every face up and its goals measured.
#[test]
fn a_roof_round_two_round_courts_gets_the_triangulated_footprint() {
    let target = load("round_courtyards.obj");
    assert_eq!(target.validate().unwrap().len(), 3);
    for unit in [300.0, 150.0] {
        let start = initial_grid(&target, &opts(unit)).unwrap();
        assert_eq!(counts(&start).loops, 3);
        assert!(unfolded_and_over_the_target(&start, &target), "{unit}");
        let (mesh, r) = build_secondary(&target, &opts(unit), &mut |_, _| {}).unwrap();
        assert_eq!(counts(&mesh).loops, 3);
        assert!(
            unfolded_and_over_the_target(&mesh, &target),
            "{unit}: {r:?}"
        );
        assert!(
            r.layout.starts_with("the footprint triangulated in plan"),
            "{}",
            r.layout
        );
        assert!(
            r.layout
                .contains("the rings and grids (for one or two boundary loops; the target has 3)"),
            "{}",
            r.layout
        );
        assert!(r.coverage > 0.9, "{unit}: {r:?}");
        assert!(!r.irregular_vertices.is_empty(), "{unit}");
    }
}
