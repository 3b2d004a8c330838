//! The designer's layout (`--layout COARSE.obj`): a coarse quad mesh with irregular
//! vertices, subdivided to the unit size and optimised on the target. The singular
//! vertices must stay where the coarse mesh puts them.

use sv_frame::QuadMesh;
use sv_geom::{Point3, Real};
use sv_surface::{build_secondary_with_layout, builtin_target, layout_mesh, SecondaryOptions};

/// A 3 x 3 coarse grid over the built-in dome (4 x 4 m) in which the edge between the
/// faces of column 1, rows 0 and 1 is turned: vertices F = (1, 1) and C = (2, 1) get three
/// faces, E = (1, 2) five, and the boundary vertex B = (2, 0) three.
fn coarse_layout() -> (QuadMesh, [usize; 3]) {
    let id = |i: usize, j: usize| j * 4 + i;
    let cell = 4000.0 / 3.0;
    let mut vertices = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            vertices.push(Point3::new(
                -2000.0 + i as Real * cell,
                -2000.0 + j as Real * cell,
                0.0,
            ));
        }
    }
    let (a, b, c, d, e, f) = (id(1, 0), id(2, 0), id(2, 1), id(2, 2), id(1, 2), id(1, 1));
    vertices[f].x -= 0.2 * cell;
    vertices[c].x += 0.2 * cell;
    // drawn on the dome (sphere of radius 4 m, top at z = 0)
    for p in &mut vertices {
        p.z = (16e6 - p.x * p.x - p.y * p.y).sqrt() - 4000.0;
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
    faces.push([a, b, e, f]);
    faces.push([b, c, d, e]);
    (QuadMesh { vertices, faces }, [f, c, e])
}

fn faces_at(mesh: &QuadMesh, v: usize) -> usize {
    mesh.faces.iter().filter(|f| f.contains(&v)).count()
}

#[test]
fn layout_singularities_stay_where_the_coarse_mesh_puts_them() {
    let target = builtin_target("dome").unwrap();
    let (coarse, [f, c, e]) = coarse_layout();
    let opts = SecondaryOptions {
        unit_size: 300.0,
        ..Default::default()
    };
    let fine = layout_mesh(&target, &coarse, &opts).unwrap();
    // every coarse vertex keeps its index and its faces; every new interior vertex is regular
    for v in 0..coarse.vertices.len() {
        assert_eq!(faces_at(&fine, v), faces_at(&coarse, v), "vertex {v}");
    }
    assert_eq!((faces_at(&fine, f), faces_at(&fine, c)), (3, 3));
    assert_eq!(faces_at(&fine, e), 5);
    // about (4 m / 0.3 m)^2 faces on the dome
    assert!(
        (120..260).contains(&fine.faces.len()),
        "{}",
        fine.faces.len()
    );
    let (mesh, report) =
        build_secondary_with_layout(&target, &coarse, &opts, &mut |_, _| {}).unwrap();
    let mut want = vec![f, c, e];
    want.sort_unstable();
    assert_eq!(report.irregular_vertices, want, "{report:?}");
    // the singular vertices moved less than half a unit from the coarse points
    for v in want {
        let moved = (mesh.vertices[v] - coarse.vertices[v]).norm();
        assert!(moved < 0.5 * opts.unit_size, "vertex {v} moved {moved} mm");
    }
    // the mesh comes back unfolded, and what this skewed layout cannot meet (its turned
    // faces are 1.3 x 2.4 m) is named; the conical figure at the valence-5 vertex is the
    // normal-circle measure of `spinvalence check`
    assert!(report.non_convex_faces.is_empty(), "{report:?}");
    let cone5 = mesh
        .conical_residuals()
        .into_iter()
        .find(|&(v, _)| v == e)
        .map(|(_, r)| r.to_degrees())
        .unwrap();
    assert!(cone5 <= report.conical_max_deg + 1e-9);
    assert_eq!(
        report.unmet.iter().any(|l| l.starts_with("conical")),
        report.conical_max_deg > 0.5,
        "{report:?}"
    );
}

#[test]
fn broken_layouts_are_named_with_one_based_indices() {
    let target = builtin_target("dome").unwrap();
    let opts = SecondaryOptions::default();
    let (mut coarse, _) = coarse_layout();
    coarse.faces[2] = [0, 1, 1, 4];
    let e = layout_mesh(&target, &coarse, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("face 3 uses vertex 2 twice"), "{e}");
    let (mut coarse, _) = coarse_layout();
    coarse.faces[4].reverse();
    let e = layout_mesh(&target, &coarse, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("same direction"), "{e}");
    // drawn upside down: reversed as a whole and accepted
    let (mut coarse, _) = coarse_layout();
    for face in &mut coarse.faces {
        face.reverse();
    }
    let fine = layout_mesh(&target, &coarse, &opts).unwrap();
    let p = fine.face_points(0);
    assert!((p[0] - p[2]).cross(&(p[1] - p[3])).z > 0.0);
}
