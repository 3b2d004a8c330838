//! End-to-end secondary stage over the built-in targets at 300 mm units.

use sv_surface::{
    build_secondary, builtin_target, initial_grid, SecondaryOptions, SurfaceError, TargetMesh,
};

/// The largest link gap of the primary solve on `mesh` (default options: min-max) as a
/// fraction of the mean edge; also solves with the sum objective and checks that min-max
/// leaves no larger worst gap (up to 0.1 % of the side: where both close every link, as on
/// the flat target, either may end a few hundredths of a millimetre ahead).
fn worst_gap(name: &str, mesh: &sv_frame::QuadMesh, mean_edge: f64) -> f64 {
    let max = sv_frame::solve(mesh, &sv_frame::SolveOptions::default(), &mut |_| {})
        .unwrap_or_else(|e| panic!("{name}: primary: {e}"));
    let sum_options = sv_frame::SolveOptions {
        objective: sv_frame::GapObjective::Sum,
        ..Default::default()
    };
    let sum = sv_frame::solve(mesh, &sum_options, &mut |_| {}).unwrap();
    assert!(
        max.report.gap_max <= sum.report.gap_max + 1e-3 * mean_edge,
        "{name}: min-max {} vs sum {}",
        max.report.gap_max,
        sum.report.gap_max
    );
    let frame = max.to_frame_file(mesh);
    let checked = sv_frame::check_frame(&frame, &Default::default());
    assert!(checked.ok(), "{name}: {checked:?}");
    max.report.gap_max / mean_edge
}

fn run(name: &str, unit: f64) -> (sv_frame::QuadMesh, sv_surface::SecondaryReport) {
    let target = builtin_target(name).unwrap();
    let opts = SecondaryOptions {
        unit_size: unit,
        ..Default::default()
    };
    let mut calls = 0;
    let (mesh, r) = build_secondary(&target, &opts, &mut |_, _| calls += 1)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(calls, r.iterations);
    assert!(
        r.iterations < opts.max_iterations,
        "{name} {unit}: no convergence"
    );
    assert_eq!(mesh.faces.len(), r.faces);
    assert!(r.faces > 100, "{name}: {} faces", r.faces);
    assert!(
        r.planarity_max <= 0.002,
        "{name} {unit}: planarity {}",
        r.planarity_max
    );
    assert!(
        r.conical_max_deg <= 0.5,
        "{name} {unit}: conical {}",
        r.conical_max_deg
    );
    assert!(
        r.closeness_max <= 0.05,
        "{name} {unit}: closeness {}",
        r.closeness_max
    );
    assert!(
        r.boundary_max <= 0.05,
        "{name} {unit}: boundary {}",
        r.boundary_max
    );
    assert!(r.coverage >= 0.85, "{name} {unit}: coverage {}", r.coverage);
    assert!(
        r.edge_ratio_fraction >= 0.95,
        "{name} {unit}: edge ratio {}",
        r.edge_ratio_fraction
    );
    assert!(
        r.non_convex_faces.is_empty(),
        "{name} {unit}: non-convex {:?}",
        r.non_convex_faces
    );
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
    (mesh, r)
}

#[test]
fn every_builtin_meets_every_goal_at_300() {
    for name in sv_surface::BUILTIN_NAMES {
        let (mesh, r) = run(name, 300.0);
        // square corners: corner faces are rhombi too (the worst face fits its rhombus
        // within a tenth of the side)
        assert!(r.rhombus_fit_max < 0.1, "{name}: fit {}", r.rhombus_fit_max);
        // issue 3: every link gap <= 5 % of the unit side
        let gap = worst_gap(name, &mesh, r.mean_edge);
        assert!(gap <= 0.05, "{name} 300: gap max {gap:.4} of the side");
    }
}

#[test]
fn every_builtin_meets_every_goal_at_150() {
    for name in sv_surface::BUILTIN_NAMES {
        let (mesh, r) = run(name, 150.0);
        let gap = worst_gap(name, &mesh, r.mean_edge);
        assert!(gap <= 0.05, "{name} 150: gap max {gap:.4} of the side");
    }
}

#[test]
fn hypar_like_saddle_meets_every_goal_at_110() {
    // the issue's ~1,000-unit benchmark build (1,190 faces: the grid counts keep every
    // side within 0.7-1.4 of the unit; 1,444 before)
    let (mesh, r) = run("saddle", 110.0);
    assert!(r.faces > 1000, "{} faces", r.faces);
    let gap = worst_gap("saddle", &mesh, r.mean_edge);
    assert!(gap <= 0.05, "saddle 110: gap max {gap:.4} of the side");
}

#[test]
fn initial_grid_boundary_follows_target() {
    let target = builtin_target("dome").unwrap();
    let grid = initial_grid(&target, &SecondaryOptions::default()).unwrap();
    let edge = grid.mean_edge();
    assert!((250.0..350.0).contains(&edge), "mean edge {edge}");
}

#[test]
fn bad_parameters_and_targets_are_errors() {
    let target = builtin_target("flat").unwrap();
    for unit in [0.0, -1.0, f64::NAN] {
        let opts = SecondaryOptions {
            unit_size: unit,
            ..Default::default()
        };
        assert!(matches!(
            build_secondary(&target, &opts, &mut |_, _| {}),
            Err(SurfaceError::InvalidParameter(_))
        ));
    }
    let opts = SecondaryOptions {
        unit_size: 3000.0,
        ..Default::default()
    };
    assert!(matches!(
        build_secondary(&target, &opts, &mut |_, _| {}),
        Err(SurfaceError::TooSmall(_))
    ));
    let err = build_secondary(
        &TargetMesh::default(),
        &SecondaryOptions::default(),
        &mut |_, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("no triangles"), "{err}");
}
