//! The designer's layout: a coarse quad mesh with the irregular vertices where the designer
//! wants them (made in Rhino with QuadRemesh, or by hand), subdivided to the unit size and
//! laid onto the target.
//!
//! Every coarse edge is cut into the same number of segments as the edges opposite it
//! across each coarse face (the edges of one *chord*, the strip of faces a dual loop
//! crosses), so the subdivided faces meet edge to edge: `n = max(1, round(mean length /
//! unit))` per chord, the length measured along the target. Coarse vertices keep their
//! index and their faces, so the irregular vertices stay where the coarse mesh puts them;
//! every new vertex is regular. Points on coarse boundary edges go onto the target
//! boundary, the others onto the target (closest point); face interiors are Coons patches
//! of their four subdivided sides.

use std::collections::HashMap;

use sv_frame::QuadMesh;
use sv_geom::{Point3, Real, Vector3};

use crate::target::{loop_arc, loop_at, TargetIndex};
use crate::{SecondaryOptions, SurfaceError};

/// Union-find root of `x` (over the coarse edges here, over corners in `cell_layout.rs`).
pub(crate) fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// Check the coarse layout: finite, indices in range, distinct corners, manifold and
/// consistently oriented. Returns it with every face reversed when it is drawn with the
/// opposite winding to the target's normals (the hub side follows the target).
fn checked_layout(index: &TargetIndex<'_>, coarse: &QuadMesh) -> Result<QuadMesh, SurfaceError> {
    let bad = |s: String| Err(SurfaceError::InvalidLayout(s));
    let nv = coarse.vertices.len();
    if coarse.faces.is_empty() {
        return bad("the layout has no faces".into());
    }
    if let Some(v) = coarse
        .vertices
        .iter()
        .position(|p| !sv_geom::is_finite_point(p))
    {
        return bad(format!("vertex {} has a non-finite coordinate", v + 1));
    }
    let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
    for (f, face) in coarse.faces.iter().enumerate() {
        if let Some(&i) = face.iter().find(|&&i| i >= nv) {
            return bad(format!(
                "face {} uses vertex {}, but the layout has {nv} vertices",
                f + 1,
                i + 1
            ));
        }
        for k in 0..4 {
            if face[(k + 1)..].contains(&face[k]) {
                return bad(format!("face {} uses vertex {} twice", f + 1, face[k] + 1));
            }
        }
        for k in 0..4 {
            let e = (face[k], face[(k + 1) % 4]);
            if let Some(g) = directed.insert(e, f) {
                return bad(format!(
                    "faces {} and {} both list the edge {}-{} in the same direction (inconsistent orientation or more than two faces on an edge)",
                    g + 1,
                    f + 1,
                    e.0 + 1,
                    e.1 + 1
                ));
            }
        }
    }
    // winding against the target's normals, voted by face area
    let mut vote = 0.0;
    for face in &coarse.faces {
        let p = face.map(|v| coarse.vertices[v]);
        let n = (p[0] - p[2]).cross(&(p[1] - p[3]));
        let c = Point3::from(p.iter().map(|q| q.coords).sum::<Vector3>() / 4.0);
        vote += n.dot(&index.closest(&c).normal);
    }
    let mut out = coarse.clone();
    if vote < 0.0 {
        for f in &mut out.faces {
            f.reverse();
        }
    }
    Ok(out)
}

/// The designer's coarse layout subdivided to `opts.unit_size` on the target (see the
/// module documentation). Coarse vertex `i` is vertex `i` of the result.
pub fn layout_mesh(
    target: &crate::TargetMesh,
    coarse: &QuadMesh,
    opts: &SecondaryOptions,
) -> Result<QuadMesh, SurfaceError> {
    opts.check()?;
    let index = TargetIndex::new(target)?;
    layout_mesh_indexed(&index, coarse, opts)
}

pub(crate) fn layout_mesh_indexed(
    index: &TargetIndex<'_>,
    coarse: &QuadMesh,
    opts: &SecondaryOptions,
) -> Result<QuadMesh, SurfaceError> {
    let coarse = checked_layout(index, coarse)?;
    let h = opts.unit_size;
    let nv = coarse.vertices.len();
    // undirected coarse edges, and which are on the layout's boundary
    let mut edge_id: HashMap<(usize, usize), usize> = HashMap::new();
    let mut edges: Vec<(usize, usize)> = Vec::new();
    let mut directed = std::collections::HashSet::new();
    for face in &coarse.faces {
        for k in 0..4 {
            let (a, b) = (face[k], face[(k + 1) % 4]);
            directed.insert((a, b));
            edge_id.entry((a.min(b), a.max(b))).or_insert_with(|| {
                edges.push((a.min(b), a.max(b)));
                edges.len() - 1
            });
        }
    }
    let on_boundary: Vec<bool> = edges
        .iter()
        .map(|&(a, b)| !(directed.contains(&(a, b)) && directed.contains(&(b, a))))
        .collect();
    let mut boundary_vertex = vec![false; nv];
    for (e, &(a, b)) in edges.iter().enumerate() {
        if on_boundary[e] {
            boundary_vertex[a] = true;
            boundary_vertex[b] = true;
        }
    }
    // onto the target, then (boundary points) onto its boundary
    let project = |p: &Point3, on_rim: bool| {
        let q = index.closest(p).point;
        if on_rim {
            index.closest_on_boundary(&q).point
        } else {
            q
        }
    };
    let mut faces_at = vec![0usize; nv];
    for face in &coarse.faces {
        for &v in face {
            faces_at[v] += 1;
        }
    }
    let turning = boundary_turning(index, h);
    let corners: Vec<Point3> = (0..nv)
        .map(|v| {
            let q = project(&coarse.vertices[v], boundary_vertex[v]);
            if boundary_vertex[v] && faces_at[v] != 2 {
                // a corner of the layout goes to the sharpest turn of the target boundary
                // near it
                snap_to_corner(index, &turning, &q, h)
            } else {
                q
            }
        })
        .collect();
    // chords: opposite edges of every face share a count
    let eid = |a: usize, b: usize| edge_id[&(a.min(b), a.max(b))];
    let mut parent: Vec<usize> = (0..edges.len()).collect();
    for face in &coarse.faces {
        for k in 0..2 {
            let e1 = find(&mut parent, eid(face[k], face[k + 1]));
            let e2 = find(&mut parent, eid(face[k + 2], face[(k + 3) % 4]));
            parent[e1] = e2;
        }
    }
    // length of a coarse edge along the target: its chord sampled and projected
    let length = |e: usize| {
        let (a, b) = edges[e];
        let samples = 8;
        let mut prev = corners[a];
        let mut sum = 0.0;
        for i in 1..=samples {
            let t = i as Real / samples as Real;
            let q = project(
                &(corners[a] + (corners[b] - corners[a]) * t),
                on_boundary[e],
            );
            sum += (q - prev).norm();
            prev = q;
        }
        sum
    };
    let mut total: HashMap<usize, (Real, usize)> = HashMap::new();
    for e in 0..edges.len() {
        let r = find(&mut parent, e);
        let t = total.entry(r).or_insert((0.0, 0));
        t.0 += length(e);
        t.1 += 1;
    }
    let count: Vec<usize> = (0..edges.len())
        .map(|e| {
            let (sum, n) = total[&find(&mut parent, e)];
            ((sum / n as Real / h).round() as usize).max(1)
        })
        .collect();
    // points along every coarse edge, from its lower to its higher vertex index
    let mut vertices = corners.clone();
    let mut along: Vec<Vec<usize>> = Vec::with_capacity(edges.len());
    for (e, &(a, b)) in edges.iter().enumerate() {
        let n = count[e];
        let mut ids = vec![a];
        for i in 1..n {
            let t = i as Real / n as Real;
            let q = project(
                &(corners[a] + (corners[b] - corners[a]) * t),
                on_boundary[e],
            );
            vertices.push(q);
            ids.push(vertices.len() - 1);
        }
        ids.push(b);
        along.push(ids);
    }
    // the points of side (a -> b), in that direction
    let side = |a: usize, b: usize| -> Vec<usize> {
        let ids = &along[eid(a, b)];
        if a < b {
            ids.clone()
        } else {
            ids.iter().rev().copied().collect()
        }
    };
    let mut faces = Vec::new();
    for face in &coarse.faces {
        let [c0, c1, c2, c3] = *face;
        let bottom = side(c0, c1); // s from c0 to c1
        let right = side(c1, c2); // t from c1 to c2
        let top = side(c3, c2); // s from c3 to c2
        let left = side(c0, c3); // t from c0 to c3
        let (n, m) = (bottom.len() - 1, left.len() - 1);
        if top.len() - 1 != n || right.len() - 1 != m {
            return Err(SurfaceError::Internal(
                "chord counts of opposite sides differ".into(),
            ));
        }
        let mut grid = vec![vec![0usize; m + 1]; n + 1];
        for i in 0..=n {
            grid[i][0] = bottom[i];
            grid[i][m] = top[i];
        }
        grid[0].copy_from_slice(&left);
        grid[n].copy_from_slice(&right);
        let pt = |v: usize, vs: &[Point3]| vs[v].coords;
        for i in 1..n {
            for j in 1..m {
                let (s, t) = (i as Real / n as Real, j as Real / m as Real);
                let vs = &vertices;
                let coons = pt(bottom[i], vs) * (1.0 - t)
                    + pt(top[i], vs) * t
                    + pt(left[j], vs) * (1.0 - s)
                    + pt(right[j], vs) * s
                    - (pt(c0, vs) * ((1.0 - s) * (1.0 - t))
                        + pt(c1, vs) * (s * (1.0 - t))
                        + pt(c2, vs) * (s * t)
                        + pt(c3, vs) * ((1.0 - s) * t));
                let q = index.closest(&Point3::from(coons)).point;
                vertices.push(q);
                grid[i][j] = vertices.len() - 1;
            }
        }
        for i in 0..n {
            for j in 0..m {
                faces.push([
                    grid[i][j],
                    grid[i + 1][j],
                    grid[i + 1][j + 1],
                    grid[i][j + 1],
                ]);
            }
        }
    }
    Ok(QuadMesh { vertices, faces })
}

/// Turning angle of the target boundary at every boundary vertex (radians, between the
/// chords to the points `0.75 h` before and after along its loop), by loop.
fn boundary_turning(index: &TargetIndex<'_>, h: Real) -> Vec<Vec<Real>> {
    let v = &index.mesh.vertices;
    index
        .loops
        .iter()
        .map(|lp| {
            let m = lp.len();
            let arc = loop_arc(v, lp);
            let at = |s: Real| loop_at(v, lp, &arc, s);
            (0..m)
                .map(|k| {
                    let p = v[lp[k]];
                    let a = p - at(arc[k] - 0.75 * h);
                    let b = at(arc[k] + 0.75 * h) - p;
                    if a.norm() > 0.0 && b.norm() > 0.0 {
                        a.angle(&b)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect()
}

/// The boundary vertex within half a unit of `q` (or the nearest, when none is) where the
/// boundary turns most.
fn snap_to_corner(index: &TargetIndex<'_>, turning: &[Vec<Real>], q: &Point3, h: Real) -> Point3 {
    let v = &index.mesh.vertices;
    let mut best: Option<(Real, Point3)> = None;
    let mut nearest: Option<(Real, Point3)> = None;
    for (lp, turn) in index.loops.iter().zip(turning) {
        for (k, &b) in lp.iter().enumerate() {
            let d = (v[b] - q).norm();
            if nearest.is_none_or(|n| d < n.0) {
                nearest = Some((d, v[b]));
            }
            if d <= 0.5 * h && best.is_none_or(|x| turn[k] > x.0) {
                best = Some((turn[k], v[b]));
            }
        }
    }
    best.or(nearest).map_or(*q, |x| x.1)
}
