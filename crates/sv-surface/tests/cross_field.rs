//! The cross field (`sv_surface::cross_field`): along the boundary and the principal
//! curvature directions, smooth, with the singularities a quad mesh of the footprint needs
//! (their indices add up to four times the Euler characteristic) near the umbilics.

mod common;

use common::load;
use sv_geom::{Real, Vector3};
use sv_surface::{builtin_target, cross_field, TargetIndex, DEFAULT_ALIGNMENT};

/// Angle (degrees) between the cross at a vertex and the nearest of `d`'s four turns.
fn off(field: &sv_surface::CrossField, v: usize, d: &Vector3) -> Real {
    let arm = field.arm_along(v, d);
    let n = field.normals[v];
    let d = (d - n * n.dot(d)).normalize();
    arm.dot(&d).clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn on_a_barrel_vault_the_field_follows_the_rulings_and_has_no_singularity() {
    // builtin vault: a cylinder with its axis along X on a rectangle: the boundary and the
    // curvature lines agree, so the field is the grid of the rulings and the arches
    let target = builtin_target("vault").unwrap();
    let index = TargetIndex::new(&target).unwrap();
    let field = cross_field(&index, DEFAULT_ALIGNMENT).unwrap();
    assert!(field.singularities.is_empty(), "{:?}", field.singularities);
    // (the boundary vertices at the rounded corners hold the corner's mean tangent)
    let on_boundary: std::collections::HashSet<usize> =
        index.loops().iter().flatten().copied().collect();
    let worst = (0..target.vertices.len())
        .filter(|v| !on_boundary.contains(v))
        .map(|v| off(&field, v, &Vector3::x()))
        .fold(0.0, Real::max);
    assert!(
        worst < 1.0,
        "the cross leaves the rulings by {worst} degrees"
    );
    // the principal direction of largest curvature runs across the rulings (1 / 2500 mm)
    let centre = (0..target.vertices.len())
        .min_by(|&a, &b| {
            let (pa, pb) = (target.vertices[a], target.vertices[b]);
            (pa.x.hypot(pa.y)).total_cmp(&pb.x.hypot(pb.y))
        })
        .unwrap();
    assert!(
        field.principal[centre].x.abs() < 0.05,
        "{:?}",
        field.principal[centre]
    );
    assert!((field.anisotropy[centre] * 2500.0 - 1.0).abs() < 0.05);
}

#[test]
fn singularities_add_up_to_the_footprint() {
    // index sum = 4 x (2 - loops): an oval has four +1 (where an O-grid's valence-3
    // vertices go), a triangle's rounded corners and centre +1 each, an annulus 0
    for (name, sum, count) in [
        ("oval_dome.obj", 4, 4),
        ("rounded_triangle.obj", 4, 4),
        ("annulus_roof.obj", 0, 4),
        ("dome_lens.obj", 0, 0),
        ("torus_patch.obj", 0, 0),
    ] {
        let target = load(name);
        let index = TargetIndex::new(&target).unwrap();
        let field = cross_field(&index, DEFAULT_ALIGNMENT).unwrap();
        let total: i32 = field.singularities.iter().map(|s| s.1).sum();
        assert_eq!(total, sum, "{name}: {:?}", field.singularities);
        assert_eq!(field.singularities.len(), count, "{name}");
    }
}

#[test]
fn the_oval_domes_singularities_sit_near_its_umbilics() {
    // an ellipsoid with semi-axes 3600, 2600, 1200 mm has its umbilics at
    // x = +-3600 sqrt((3600^2 - 2600^2) / (3600^2 - 1200^2)) = +-2641 mm, y = 0: the
    // curvature lines circle them, so the field's four +1 singularities pair up there
    let target = load("oval_dome.obj");
    let index = TargetIndex::new(&target).unwrap();
    let field = cross_field(&index, DEFAULT_ALIGNMENT).unwrap();
    for &(t, k) in &field.singularities {
        assert_eq!(k, 1);
        let c = target.triangles[t]
            .iter()
            .map(|&i| target.vertices[i].coords)
            .sum::<Vector3>()
            / 3.0;
        let d = (c.x.abs() - 2641.0).hypot(c.y);
        assert!(d < 600.0, "singularity at ({:.0}, {:.0})", c.x, c.y);
    }
}

#[test]
fn a_negative_alignment_is_refused() {
    let target = builtin_target("flat").unwrap();
    let index = TargetIndex::new(&target).unwrap();
    let e = cross_field(&index, -1.0).unwrap_err().to_string();
    assert!(e.contains("alignment"), "{e}");
}
