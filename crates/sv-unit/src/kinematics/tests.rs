use super::*;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

fn sides(d: &Deployed) -> [Real; 4] {
    std::array::from_fn(|i| (d.primary[i] - d.primary[(i + 1) % 4]).norm())
}

/// Rhombi from nearly square to 1:4, small and large, and the whole (theta, phi) domain
/// short of the degenerate end theta -> pi, including values near the boundary.
fn unit_case() -> impl Strategy<Value = (Rhombus, Deployment)> {
    let theta = prop_oneof![Just(0.0), 1e-9..1e-3f64, 0.0..2.8f64];
    let phi = prop_oneof![
        Just(0.0),
        Just(FRAC_PI_2),
        Just(-FRAC_PI_2),
        -FRAC_PI_2..FRAC_PI_2
    ];
    case_with(theta, phi)
}

/// Strictly inside the domain, where derivatives are bounded.
fn interior_case() -> impl Strategy<Value = (Rhombus, Deployment)> {
    case_with(0.05..1.3f64, prop_oneof![Just(0.0), -1.3..1.3f64])
}

fn case_with(
    theta: impl Strategy<Value = Real>,
    phi: impl Strategy<Value = Real>,
) -> impl Strategy<Value = (Rhombus, Deployment)> {
    let size = prop_oneof![1.0..10.0f64, 10.0..2000.0f64];
    let ratio = prop_oneof![Just(1.0), 0.25..4.0f64];
    let case = prop_oneof![
        Just(AxisCase::OrthogonalToR1),
        Just(AxisCase::OrthogonalToR2)
    ];
    let side = prop_oneof![Just(Side::HubPositive), Just(Side::HubNegative)];
    (size, ratio, theta, phi, case, side).prop_map(|(a, k, theta, phi, case, side)| {
        (
            Rhombus::new(a, a * k).unwrap(),
            Deployment {
                theta,
                phi,
                case,
                side,
            },
        )
    })
}

proptest! {
    // fixed seed: a failure reproduces on every machine
    #![proptest_config(ProptestConfig {
        cases: 4000,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_5eed),
        ..ProptestConfig::default()
    })]

    #[test]
    fn legs_equal_sides((rh, dep) in unit_case()) {
        match deploy(&rh, &dep) {
            Ok(d) => {
                let s = sides(&d);
                for i in 0..4 {
                    let leg = (d.hub[i] - d.primary[(i + 1) % 4]).norm();
                    prop_assert!((leg - s[i]).abs() <= 1e-9 * s[i], "leg {i}: {leg} vs side {}", s[i]);
                }
            }
            // P is only non-unique where the two linear constraints coincide
            Err(UnitError::Degenerate { .. }) => prop_assert!(dep.theta > 1.0),
            Err(e) => prop_assert!(false, "unexpected {e}"),
        }
    }

    #[test]
    fn hub_congruent_to_primary((rh, dep) in unit_case()) {
        if let Ok(d) = deploy(&rh, &dep) {
            // a proper rotation
            prop_assert!((d.rotation.transpose() * d.rotation - Matrix3::identity()).norm() < 1e-12);
            prop_assert!((d.rotation.determinant() - 1.0).abs() < 1e-12);
            for i in 0..4 {
                for j in 0..4 {
                    let dp = (d.primary[i] - d.primary[j]).norm();
                    let dh = (d.hub[i] - d.hub[j]).norm();
                    prop_assert!((dp - dh).abs() <= 1e-9 * rh.side());
                }
            }
            // eq. 8/11: |P|^2 = 2 (R r1).r2
            let g = depth_squared(&rh, dep.theta, dep.phi);
            prop_assert!((d.translation.norm_squared() - g).abs() <= 1e-9 * rh.a() * rh.b());
        }
    }

    #[test]
    fn axis_is_orthogonal_to_a_diagonal((rh, dep) in unit_case()) {
        if let Ok(d) = deploy(&rh, &dep) {
            let [r1, r2, _, _] = rh.corners();
            let off = match dep.case {
                AxisCase::OrthogonalToR1 => d.axis.dot(&r1),
                AxisCase::OrthogonalToR2 => d.axis.dot(&r2),
            };
            prop_assert!(off.abs() <= 1e-12 * rh.side());
            prop_assert!((d.axis.norm() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn p_vanishes_exactly_when_axis_in_tile_plane((rh, dep) in unit_case()) {
        if let Ok(d) = deploy(&rh, &dep) {
            let in_plane = d.axis.z.abs() < 1e-12;
            let p = d.translation.norm();
            if dep.theta.sin() > 1e-6 {
                if in_plane {
                    prop_assert!(p <= 1e-6 * rh.side(), "axis in plane but |P| = {p}");
                } else if dep.phi.cos() > 1e-3 {
                    prop_assert!(p > 1e-5 * rh.side(), "axis out of plane but |P| = {p}");
                }
            }
        }
    }

    #[test]
    fn infeasible_domain_is_rejected(theta in 0.01..3.1f64, phi in (FRAC_PI_2 + 0.01)..3.1f64) {
        let rh = Rhombus::new(100.0, 80.0).unwrap();
        prop_assert!(depth_squared(&rh, theta, phi) < 0.0);
        let infeasible = matches!(
            deploy(&rh, &Deployment::new(theta, phi)),
            Err(UnitError::Infeasible { .. })
        );
        prop_assert!(infeasible);
        let infeasible_negative = matches!(
            deploy(&rh, &Deployment::new(-theta, 0.3)),
            Err(UnitError::Infeasible { .. })
        );
        prop_assert!(infeasible_negative);
    }

    #[test]
    fn inverse_recovers_parameters((rh, dep) in interior_case()) {
        let Ok(d) = deploy(&rh, &dep) else { return Ok(()) };
        // place the unit somewhere in space
        let rot = rotation(&Vector3::new(0.3, -0.5, 0.8).normalize(), 1.1);
        let off = Vector3::new(1000.0, -250.0, 40.0);
        let place = |p: &Point3| Point3::from(rot * p.coords + off);
        let inv = inverse(&d.hub.map(|p| place(&p)), &d.primary.map(|p| place(&p)), 1e-6 * rh.side()).unwrap();
        let got = inv.deployment;
        prop_assert!((got.theta - dep.theta).abs() < 1e-7, "theta {} vs {}", got.theta, dep.theta);
        if dep.phi.abs() > 1e-6 {
            prop_assert_eq!(got.case, dep.case);
        }
        prop_assert!((got.phi - dep.phi).abs() < 1e-7, "phi {} vs {}", got.phi, dep.phi);
        prop_assert_eq!(got.side, dep.side);
    }

    /// The analytic Jacobian agrees with central differences inside the domain.
    #[test]
    fn derivatives_match_finite_differences((rh, dep) in interior_case(), e in 1.0..1.3f64) {
        let j = primary_in_hub_frame(&rh, &dep, e).unwrap();
        let h = 1e-6;
        let at = |th: Real, ph: Real| {
            primary_in_hub_frame(&rh, &Deployment { theta: th, phi: ph, ..dep }, e).unwrap().corners
        };
        let (tp, tm) = (at(dep.theta + h, dep.phi), at(dep.theta - h, dep.phi));
        let (pp, pm) = (at(dep.theta, dep.phi + h), at(dep.theta, dep.phi - h));
        for i in 0..4 {
            let fd_t = (tp[i] - tm[i]) / (2.0 * h);
            let fd_p = (pp[i] - pm[i]) / (2.0 * h);
            // central differences are accurate to about 1e-6 of the derivative's own size
            let tol_t = 1e-5 * rh.side().max(j.d_theta[i].norm());
            let tol = 1e-5 * rh.side().max(j.d_phi[i].norm());
            prop_assert!((fd_t - j.d_theta[i]).norm() < tol_t, "d/dtheta {i}: {fd_t:?} vs {:?}", j.d_theta[i]);
            prop_assert!((fd_p - j.d_phi[i]).norm() < tol, "d/dphi {i}: {fd_p:?} vs {:?}", j.d_phi[i]);
        }
    }
}

#[test]
fn theta_zero_is_the_flat_state() {
    let rh = Rhombus::new(120.0, 90.0).unwrap();
    for phi in [-1.5, -0.4, 0.0, 0.7, 1.5] {
        for case in [AxisCase::OrthogonalToR1, AxisCase::OrthogonalToR2] {
            let d = deploy(&rh, &Deployment::new(0.0, phi).with_case(case)).unwrap();
            for i in 0..4 {
                assert!((d.hub[i] - d.primary[i]).norm() < 1e-12);
            }
        }
    }
}

/// Four units of a flat square grid at theta = alpha = 45 degrees: the primary tiles,
/// seen from hubs spun by alpha, are the grid squares themselves (moved down by the
/// depth), so neighbours share whole edges.
#[test]
fn flat_square_grid_tiles_without_gaps() {
    let side: Real = 300.0;
    let half_diag = side / 2f64.sqrt();
    let rh = Rhombus::new(half_diag, half_diag).unwrap();
    let dep = Deployment::new(FRAC_PI_4, 0.0);
    let j = primary_in_hub_frame(&rh, &dep, 1.0).unwrap();
    // The hub of the unit centred at c is its grid square (corners at 45, 135, ...
    // degrees) spun by alpha = 45 degrees, so hub corner 0 points along +x and the hub
    // frame is the world frame shifted to c.
    let depth = (2.0 * FRAC_PI_4.sin()).sqrt() * half_diag;
    let mut corners = Vec::new();
    for (cx, cy) in [(0.0, 0.0), (side, 0.0), (0.0, side), (side, side)] {
        for (i, q) in j.corners.iter().enumerate() {
            let angle = -FRAC_PI_4 + i as Real * FRAC_PI_2;
            let expected = Vector3::new(
                cx + half_diag * angle.cos(),
                cy + half_diag * angle.sin(),
                -depth,
            );
            let got = Vector3::new(cx, cy, 0.0) + q.coords;
            assert!(
                (got - expected).norm() < 1e-9,
                "corner {i}: {got:?} vs {expected:?}"
            );
            corners.push(got);
        }
    }
    // the shared vertex (side/2, -side/2) is a corner of all four tiles
    let mid = Vector3::new(side / 2.0, side / 2.0, -depth);
    let touching = corners.iter().filter(|c| (*c - mid).norm() < 1e-9).count();
    assert_eq!(touching, 4);
}

#[test]
fn degenerate_square_at_right_angle_is_an_error() {
    let rh = Rhombus::new(100.0, 100.0).unwrap();
    assert!(matches!(
        deploy(&rh, &Deployment::new(FRAC_PI_2, 0.0)),
        Err(UnitError::Degenerate { .. })
    ));
}

#[test]
fn bad_rhombus_and_nan_are_errors() {
    assert!(Rhombus::new(0.0, 1.0).is_err());
    assert!(Rhombus::new(f64::NAN, 1.0).is_err());
    let rh = Rhombus::new(1.0, 1.0).unwrap();
    assert!(deploy(&rh, &Deployment::new(f64::NAN, 0.0)).is_err());
    assert!(deploy(&rh, &Deployment::new(0.5, f64::INFINITY)).is_err());
}

#[test]
fn inverse_rejects_a_non_unit() {
    let rh = Rhombus::new(100.0, 100.0).unwrap();
    let d = deploy(&rh, &Deployment::new(0.7, 0.2)).unwrap();
    let mut hub = d.hub;
    hub[0].z += 5.0;
    assert!(matches!(
        inverse(&hub, &d.primary, 1e-6),
        Err(UnitError::NotAUnit(_))
    ));
}
