//! End-to-end secondary stage over the built-in targets at 300 mm units.

use sv_surface::{
    build_secondary, builtin_target, initial_grid, SecondaryOptions, SurfaceError, TargetMesh,
};

fn run(name: &str) -> sv_surface::SecondaryReport {
    let target = builtin_target(name).unwrap();
    let opts = SecondaryOptions::default();
    let mut calls = 0;
    let (mesh, r) = build_secondary(&target, &opts, &mut |_, _| calls += 1)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(calls, r.iterations);
    assert_eq!(mesh.faces.len(), r.faces);
    assert!(r.faces > 100, "{name}: {} faces", r.faces);
    assert!(
        r.planarity_max <= 0.002,
        "{name}: planarity {}",
        r.planarity_max
    );
    assert!(
        r.conical_max_deg <= 0.5,
        "{name}: conical {}",
        r.conical_max_deg
    );
    assert!(
        r.closeness_max <= 0.05,
        "{name}: closeness {}",
        r.closeness_max
    );
    assert!(
        r.boundary_max <= 0.05,
        "{name}: boundary {}",
        r.boundary_max
    );
    assert!(r.coverage >= 0.85, "{name}: coverage {}", r.coverage);
    assert!(
        r.non_convex_faces.is_empty(),
        "{name}: non-convex {:?}",
        r.non_convex_faces
    );
    r
}

#[test]
fn flat_meets_all_goals() {
    let r = run("flat");
    assert!(r.edge_ratio_fraction >= 0.95, "{}", r.edge_ratio_fraction);
}

#[test]
fn vault_meets_all_goals() {
    let r = run("vault");
    assert!(r.edge_ratio_fraction >= 0.95, "{}", r.edge_ratio_fraction);
}

#[test]
fn dome_meets_all_goals() {
    let r = run("dome");
    assert!(r.edge_ratio_fraction >= 0.95, "{}", r.edge_ratio_fraction);
}

#[test]
fn saddle_meets_hard_goals() {
    // edge ratio reaches about 0.94 of faces here (goal 0.95): reported in `unmet`
    let r = run("saddle");
    assert!(r.edge_ratio_fraction >= 0.9, "{}", r.edge_ratio_fraction);
}

#[test]
fn pavilion_meets_all_goals() {
    let r = run("pavilion");
    assert!(r.edge_ratio_fraction >= 0.95, "{}", r.edge_ratio_fraction);
    assert!(r.unmet.is_empty(), "{:?}", r.unmet);
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
