use super::*;

fn gaps_of(mesh: &QuadMesh, options: &SolveOptions) -> Solved {
    solve(mesh, options, &mut |_| {}).unwrap()
}

#[test]
fn flat_grid_has_zero_gaps_at_alpha() {
    let mesh = QuadMesh::grid(6, 5, 300.0);
    let s = gaps_of(&mesh, &SolveOptions::default());
    assert!(s.report.gap_max < 1e-6 * 300.0, "{:?}", s.report);
    for d in &s.deployments {
        assert!((d.theta - DEFAULT_SPIN_ANGLE).abs() < 1e-9);
        assert!(d.phi.abs() < 1e-9);
    }
    // hub corners pass each other by (sqrt(2) - 1) x side on a square grid
    for o in &s.evaluation.overlaps {
        assert!((o - (2f64.sqrt() - 1.0) * 300.0).abs() < 1e-9, "{o}");
    }
}

#[test]
fn solve_reduces_gaps_on_curved_meshes() {
    let cap = QuadMesh::sphere_cap(8, 8, 3000.0, 300.0);
    let saddle = QuadMesh::translational(8, 8, 300.0, |x| x * x / 8000.0, |y| -y * y / 8000.0);
    for mesh in [cap, saddle] {
        let s = gaps_of(&mesh, &SolveOptions::default());
        assert!(
            s.report.gap_sum < 0.5 * s.report.gap_sum_start,
            "{:?}",
            s.report
        );
        assert!(s.report.gap_max.is_finite());
        // every deployment stays in the feasible domain
        for d in &s.deployments {
            assert!(d.theta > 0.0 && d.phi.cos() > 0.0);
        }
    }
}

#[test]
fn concave_side_gives_smaller_gaps_on_a_sphere() {
    let cap = QuadMesh::sphere_cap(8, 8, 3000.0, 300.0);
    let concave = gaps_of(&cap, &SolveOptions::default());
    // auto puts every hub of a sphere cap (normals up/out) on the inside
    assert!(concave
        .deployments
        .iter()
        .all(|d| d.side == Side::HubNegative));
    let convex = gaps_of(
        &cap,
        &SolveOptions {
            side: SidePolicy::Normal,
            ..Default::default()
        },
    );
    assert!(
        concave.report.gap_max < convex.report.gap_max,
        "{} vs {}",
        concave.report.gap_max,
        convex.report.gap_max
    );
}

#[test]
fn bad_parameters_are_errors() {
    let mesh = QuadMesh::grid(2, 2, 300.0);
    for (spin, e) in [
        (0.0, 1.0),
        (std::f64::consts::FRAC_PI_2, 1.0),
        (f64::NAN, 1.0),
        (0.5, 0.9),
        (0.5, f64::INFINITY),
    ] {
        let o = SolveOptions {
            spin_angle: spin,
            expansion: e,
            ..Default::default()
        };
        assert!(matches!(
            solve(&mesh, &o, &mut |_| {}),
            Err(FrameError::Parameter { .. })
        ));
    }
}

#[test]
fn progress_is_reported() {
    let cap = QuadMesh::sphere_cap(5, 5, 3000.0, 300.0);
    let mut calls = 0;
    let s = solve(&cap, &SolveOptions::default(), &mut |p| {
        calls += 1;
        assert!(p.gap_sum.is_finite());
    })
    .unwrap();
    assert!(calls >= s.report.iterations);
}

#[test]
fn per_unit_axis_case_keeps_every_invariant() {
    let mesh = QuadMesh::translational(6, 6, 300.0, |x| x * x / 5000.0, |y| -y * y / 9000.0);
    let s = gaps_of(
        &mesh,
        &SolveOptions {
            axis_case: None,
            ..Default::default()
        },
    );
    assert!(s.report.gap_sum < s.report.gap_sum_start);
    let file = s.to_frame_file(&mesh);
    // a translational saddle is planar but not conical: hold every other invariant
    let options = crate::CheckOptions {
        conical_tolerance: f64::INFINITY,
        ..Default::default()
    };
    let report = crate::check_frame(&file, &options);
    assert!(report.ok(), "{report:#?}");
}
