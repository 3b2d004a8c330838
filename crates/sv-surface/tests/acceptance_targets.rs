//! Issue 3 acceptance on the target files in `fixtures/targets/` (positive, zero, negative
//! and mixed Gaussian curvature, non-rectangular boundaries; written by
//! `cargo run -p sv-surface --example make_targets`): the secondary goals, then the
//! primary solve of `sv_frame` on the hub mesh and the checks of `spinvalence check`.
//! Three files cannot meet every goal (their boundaries cut across the curvature lines,
//! docs/secondary.md): there the stage must return an unfolded mesh and name what is unmet.

mod common;

use common::load;
use sv_surface::{build_secondary, SecondaryOptions};

/// Runs both stages at `unit` mm, asserts every secondary goal and the frame checks;
/// returns the largest link gap / unit side.
fn accept(name: &str, unit: f64) -> f64 {
    let target = load(name);
    let opts = SecondaryOptions {
        unit_size: unit,
        ..Default::default()
    };
    let (mesh, r) =
        build_secondary(&target, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
    // dome_lens at 300 mm: 11 x 9 faces, the counts that keep every side within
    // 0.7-1.4 of the unit
    assert!(r.faces >= 90, "{name}: {} faces", r.faces);
    // the grid counts are chosen so that every side is within 0.7-1.4 of the unit (the
    // face-side goal); dome_lens at 300 mm then has a mean edge of 1.22 units
    assert!(
        (0.8 * unit..1.25 * unit).contains(&r.mean_edge),
        "{name}: mean edge {} at unit {unit}",
        r.mean_edge
    );
    assert!(r.planarity_max <= 0.002, "{name} {unit}: {r:?}");
    assert!(r.conical_max_deg <= 0.5, "{name} {unit}: {r:?}");
    assert!(r.closeness_max <= 0.05, "{name} {unit}: {r:?}");
    assert!(r.boundary_max <= 0.05, "{name} {unit}: {r:?}");
    assert!(r.coverage >= 0.85, "{name} {unit}: {r:?}");
    assert!(r.edge_ratio_fraction >= 0.95, "{name} {unit}: {r:?}");
    assert!(r.non_convex_faces.is_empty(), "{name} {unit}: {r:?}");
    // every goal of issue 3 holds; issue 16's face-side goal (every side within 0.7-1.4 of
    // the unit) is not always met by the structured conformal grid, whose faces grow and
    // shrink with the conformal factor (sectors, corners; docs/secondary.md): where it is
    // not, it is the only unmet goal, named with its worst face
    for line in &r.unmet {
        assert!(
            line.starts_with("face sides") && line.contains("at face"),
            "{name} {unit}: {:?}",
            r.unmet
        );
    }
    // the library's conical figure is the one `spinvalence check` uses (radians there)
    let check = mesh
        .conical_residuals()
        .iter()
        .map(|c| c.1.to_degrees())
        .fold(0.0, f64::max);
    assert!((check - r.conical_max_deg).abs() < 1e-9, "{check} vs {r:?}");
    let solved = sv_frame::solve(&mesh, &sv_frame::SolveOptions::default(), &mut |_| {})
        .unwrap_or_else(|e| panic!("{name}: primary: {e}"));
    let frame = solved.to_frame_file(&mesh);
    let checked = sv_frame::check_frame(&frame, &Default::default());
    assert!(checked.ok(), "{name} {unit}: {checked:?}");
    solved.report.gap_max / r.mean_edge
}

/// Targets whose boundaries meet every secondary goal.
const FEASIBLE: [&str; 4] = [
    "dome_lens.obj",
    "cone_sector.obj",
    "trumpet_sector.obj",
    "bell_sector.obj",
];

/// Targets whose boundaries cut across their curvature lines.
const CONFLICTING: [&str; 3] = ["cylinder_wave.obj", "hypar_pentagon.obj", "wavy_mixed.obj"];

#[test]
fn target_files_are_valid_small_discs() {
    for name in FEASIBLE.iter().chain(&CONFLICTING) {
        let t = load(name);
        t.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(t.area() > 8e6, "{name}: area {}", t.area());
    }
}

#[test]
fn positive_zero_negative_and_mixed_targets_meet_every_goal_at_300() {
    for name in FEASIBLE {
        let gap = accept(name, 300.0);
        // issue 3: every link gap <= 5 % of the side (the min-max primary solve)
        assert!(gap <= 0.05, "{name}: gap max {gap:.3} of the unit side");
    }
}

#[test]
fn positive_zero_negative_and_mixed_targets_meet_every_goal_at_150() {
    for name in FEASIBLE {
        let gap = accept(name, 150.0);
        assert!(gap <= 0.05, "{name}: gap max {gap:.3} of the unit side");
    }
}

/// Where the goals cannot all be met, the stage says which and where instead of returning
/// a folded mesh (issue 3): the mesh comes back unfolded (every edge longer than a fifth
/// of the mean, every face convex and facing the same side as the target), planarity is
/// reported unmet, and every unmet line names its worst face or vertex.
#[test]
fn conflicting_targets_report_unmet_goals_on_an_unfolded_mesh() {
    for name in CONFLICTING {
        let target = load(name);
        let opts = SecondaryOptions {
            unit_size: 300.0,
            ..Default::default()
        };
        let (mesh, r) = build_secondary(&target, &opts, &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(r.non_convex_faces.is_empty(), "{name}: {r:?}");
        let shortest = (0..mesh.faces.len())
            .flat_map(|f| {
                let p = mesh.face_points(f);
                (0..4).map(move |k| (p[(k + 1) % 4] - p[k]).norm())
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            shortest > 0.2 * r.mean_edge,
            "{name}: shortest edge {shortest}"
        );
        for f in 0..mesh.faces.len() {
            let p = mesh.face_points(f);
            let n = (p[0] - p[2]).cross(&(p[1] - p[3]));
            assert!(n.z > 0.0, "{name}: face {f} faces down");
        }
        assert!(
            r.unmet.iter().any(|l| l.starts_with("planarity")),
            "{name}: {:?}",
            r.unmet
        );
        for line in &r.unmet {
            assert!(!line.contains('\n'), "{name}: {line}");
            assert!(
                line.contains("face") || line.contains("vertex"),
                "{name}: {line}"
            );
        }
    }
}
