//! Issue 3 acceptance on the four target files in `fixtures/targets/` (positive, zero,
//! negative and mixed Gaussian curvature, non-rectangular boundaries; written by
//! `cargo run -p sv-surface --example make_targets`): the secondary goals, then the
//! primary solve of `sv_frame` on the hub mesh.

use std::path::PathBuf;

use sv_geom::Point3;
use sv_surface::{build_secondary, SecondaryOptions, TargetMesh};

/// The OBJ subset the generator writes: `v x y z` and `f a b c` (1-based).
fn load(name: &str) -> TargetMesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/targets")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut m = TargetMesh::default();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.map(|s| s.parse().unwrap()).collect();
                m.vertices.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let i: Vec<usize> = it.map(|s| s.parse::<usize>().unwrap() - 1).collect();
                m.triangles.push([i[0], i[1], i[2]]);
            }
            _ => {}
        }
    }
    m
}

/// Runs both stages at `unit` mm; returns the largest link gap / unit side.
fn accept(name: &str, unit: f64) -> f64 {
    let target = load(name);
    let opts = SecondaryOptions {
        unit_size: unit,
        ..Default::default()
    };
    let (mesh, r) =
        build_secondary(&target, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(r.faces >= 100, "{name}: {} faces", r.faces);
    assert!(r.planarity_max <= 0.002, "{name}: {r:?}");
    assert!(r.conical_max_deg <= 0.5, "{name}: {r:?}");
    assert!(r.closeness_max <= 0.05, "{name}: {r:?}");
    assert!(r.boundary_max <= 0.05, "{name}: {r:?}");
    assert!(r.coverage >= 0.85, "{name}: {r:?}");
    assert!(r.edge_ratio_fraction >= 0.95, "{name}: {r:?}");
    assert!(r.non_convex_faces.is_empty(), "{name}: {r:?}");
    // the library's conical figure is the one `spinvalence check` uses (radians there)
    let check = mesh
        .conical_residuals()
        .iter()
        .map(|c| c.1.to_degrees())
        .fold(0.0, f64::max);
    assert!((check - r.conical_max_deg).abs() < 1e-9, "{check} vs {r:?}");
    let solved = sv_frame::solve(&mesh, &sv_frame::SolveOptions::default(), &mut |_| {})
        .unwrap_or_else(|e| panic!("{name}: primary: {e}"));
    solved.report.gap_max / r.mean_edge
}

const FILES: [&str; 4] = [
    "dome_lens.obj",
    "cylinder_wave.obj",
    "hypar_pentagon.obj",
    "wavy_mixed.obj",
];

#[test]
fn target_files_are_valid_small_discs() {
    for name in FILES {
        let t = load(name);
        t.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(t.area() > 8e6, "{name}: area {}", t.area());
    }
}

#[test]
fn dome_lens_meets_every_goal_at_300() {
    let gap = accept("dome_lens.obj", 300.0);
    assert!(gap <= 0.05, "gap max {gap:.3} of the unit side");
}

/// Where the goals cannot all be met, the stage says which and where instead of returning
/// a folded mesh (issue 3). The gable of the hypar and the wavy boundary still fold (see
/// "Known gaps" in docs/secondary.md); when they do, the error must name the place, and
/// when they build, the mesh must be unfolded and planar.
#[test]
fn unmet_goals_are_reported_not_hidden() {
    for name in ["hypar_pentagon.obj", "wavy_mixed.obj", "cylinder_wave.obj"] {
        let target = load(name);
        let opts = SecondaryOptions {
            unit_size: 300.0,
            ..Default::default()
        };
        match build_secondary(&target, &opts, &mut |_, _| {}) {
            Ok((_, r)) => {
                assert!(r.non_convex_faces.is_empty(), "{name}: {r:?}");
                assert!(r.planarity_max <= 0.002, "{name}: {r:?}");
                // every goal missed is named with its worst face or vertex
                for line in &r.unmet {
                    assert!(
                        line.contains("face") || line.contains("vertex"),
                        "{name}: {line}"
                    );
                }
            }
            Err(e) => {
                let text = e.to_string();
                assert!(!text.contains('\n'), "{name}: {text}");
                assert!(
                    text.contains("face") || text.contains("edge"),
                    "{name}: {text}"
                );
            }
        }
    }
}
