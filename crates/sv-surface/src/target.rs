//! The target surface: a triangulated disc-like patch, its validation, closest-point
//! queries and its boundary curve.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};
use sv_geom::{is_finite_point, Point3, Real, Vector3};

use crate::SurfaceError;

/// A triangle mesh in mm, Z up: the design surface the hub mesh must follow.
///
/// Same shape as `sv_io::TriMesh` (the CLI converts field by field). A usable target is one
/// connected, manifold, consistently oriented patch without handles, with one or more
/// boundary loops (a disc, or a disc with holes); see [`TargetMesh::validate`].
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct TargetMesh {
    /// Vertex positions (mm).
    pub vertices: Vec<Point3>,
    /// Triangles as vertex indices, counter-clockwise seen from the side normals point to.
    pub triangles: Vec<[usize; 3]>,
}

/// Triangle corner closest to a query, with its interpolated unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// Closest point on the mesh.
    pub point: Point3,
    /// Interpolated (smooth) unit normal there.
    pub normal: Vector3,
    /// Triangle index.
    pub triangle: usize,
}

/// Closest point on the boundary curve with its unit tangent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundaryPoint {
    /// Closest point on the boundary polyline.
    pub point: Point3,
    /// Unit tangent of the boundary there (direction of the loop).
    pub tangent: Vector3,
    /// Arc length from the first boundary vertex.
    pub arc: Real,
}

impl TargetMesh {
    /// Total area (mm^2).
    pub fn area(&self) -> Real {
        self.triangles
            .iter()
            .map(|t| triangle_area(&self.vertices, t))
            .sum()
    }

    /// Check that the mesh is a usable target: non-empty, finite, indices in range, no
    /// degenerate triangles, manifold, consistently oriented, one connected component, at
    /// least one boundary loop (not closed) and no handles (a disc with any number of
    /// holes). Returns the boundary loops as ordered vertex indices (each with the surface
    /// on its left), the longest first (the outer boundary of a roof with courtyards).
    pub fn validate(&self) -> Result<Vec<Vec<usize>>, SurfaceError> {
        let bad = |s: String| Err(SurfaceError::InvalidTarget(s));
        if self.triangles.is_empty() || self.vertices.is_empty() {
            return bad("the mesh has no triangles".into());
        }
        if let Some(v) = self.vertices.iter().position(|p| !is_finite_point(p)) {
            return bad(format!("vertex {v} has a non-finite coordinate"));
        }
        let n = self.vertices.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i >= n) {
                return bad(format!(
                    "triangle {t} uses vertex {i}, but there are only {n} vertices"
                ));
            }
        }
        let (lo, hi) = bounding_box(&self.vertices);
        let diag = (hi - lo).norm();
        for (t, tri) in self.triangles.iter().enumerate() {
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return bad(format!("triangle {t} is degenerate (repeated vertex)"));
            }
            if triangle_area(&self.vertices, tri) <= 1e-12 * diag * diag {
                return bad(format!("triangle {t} is degenerate (zero area)"));
            }
        }
        let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let e = (tri[k], tri[(k + 1) % 3]);
                if let Some(&other) = directed.get(&e) {
                    return bad(format!(
                        "edge ({}, {}) of triangle {t} is also listed in the same direction by triangle {other} (non-manifold or inconsistent orientation)",
                        e.0, e.1
                    ));
                }
                directed.insert(e, t);
            }
        }
        // boundary edges: directed edges without a twin
        let mut next: HashMap<usize, usize> = HashMap::new();
        let mut boundary_edges: Vec<(usize, usize)> = directed
            .keys()
            .filter(|&&(a, b)| !directed.contains_key(&(b, a)))
            .copied()
            .collect();
        boundary_edges.sort_unstable();
        for &(a, b) in &boundary_edges {
            if next.insert(a, b).is_some() {
                return bad(format!(
                    "vertex {a} is non-manifold (several boundary fans meet there)"
                ));
            }
        }
        // connected components over triangles
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for tri in &self.triangles {
            let r0 = find(&mut parent, tri[0]);
            for &v in &tri[1..] {
                let r = find(&mut parent, v);
                parent[r] = r0;
            }
        }
        let root = find(&mut parent, self.triangles[0][0]);
        for (t, tri) in self.triangles.iter().enumerate() {
            if find(&mut parent, tri[0]) != root {
                return bad(format!(
                    "triangle {t} is not connected to triangle 0 (the target must be one connected patch)"
                ));
            }
        }
        if boundary_edges.is_empty() {
            return bad(
                "the surface is closed (no boundary loop); a target must be a disc-like patch"
                    .into(),
            );
        }
        let mut loops: Vec<Vec<usize>> = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for &(start, _) in &boundary_edges {
            if !seen.insert(start) {
                continue;
            }
            let mut lp = vec![start];
            let mut v = next[&start];
            while v != start {
                if !seen.insert(v) {
                    return Err(SurfaceError::Internal("boundary walk did not close".into()));
                }
                lp.push(v);
                v = match next.get(&v) {
                    Some(&w) => w,
                    None => return bad(format!("boundary is open at vertex {v}")),
                };
            }
            loops.push(lp);
        }
        let length = |lp: &Vec<usize>| -> Real {
            (0..lp.len())
                .map(|k| (self.vertices[lp[(k + 1) % lp.len()]] - self.vertices[lp[k]]).norm())
                .sum()
        };
        loops.sort_by(|a, b| length(b).total_cmp(&length(a)));
        // Euler characteristic of a disc with h holes is 1 - h (rules out handles)
        let used: std::collections::HashSet<usize> =
            self.triangles.iter().flatten().copied().collect();
        let edges = directed.len() - (directed.len() - boundary_edges.len()) / 2;
        let chi = used.len() as i64 - edges as i64 + self.triangles.len() as i64;
        let expected = 2 - loops.len() as i64;
        if chi != expected {
            return bad(format!(
                "the surface has handles (Euler characteristic {chi} with {} boundary loop(s), expected {expected}); a target must be a disc, possibly with holes",
                loops.len()
            ));
        }
        Ok(loops)
    }
}

pub(crate) fn triangle_area(v: &[Point3], t: &[usize; 3]) -> Real {
    0.5 * (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]])).norm()
}

pub(crate) fn bounding_box(points: &[Point3]) -> (Point3, Point3) {
    let mut lo = Point3::new(Real::INFINITY, Real::INFINITY, Real::INFINITY);
    let mut hi = -lo;
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Closest point on triangle `abc` to `p`, with barycentric coordinates (Ericson, RTCD 5.1.5).
pub(crate) fn closest_on_triangle(
    p: &Point3,
    a: &Point3,
    b: &Point3,
    c: &Point3,
) -> (Point3, [Real; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Arc length at every vertex of a loop (`len + 1` values, the last the perimeter).
pub(crate) fn loop_arc(points: &[Point3], lp: &[usize]) -> Vec<Real> {
    let m = lp.len();
    let mut arc = vec![0.0; m + 1];
    for k in 0..m {
        arc[k + 1] = arc[k] + (points[lp[(k + 1) % m]] - points[lp[k]]).norm();
    }
    arc
}

/// Point of the loop at arc length `s` (wrapped).
pub(crate) fn loop_at(points: &[Point3], lp: &[usize], arc: &[Real], s: Real) -> Point3 {
    let m = lp.len();
    let s = s.rem_euclid(arc[m]);
    let k = arc
        .partition_point(|&a| a <= s)
        .saturating_sub(1)
        .min(m - 1);
    let len = arc[k + 1] - arc[k];
    let t = if len > 0.0 { (s - arc[k]) / len } else { 0.0 };
    points[lp[k]] + (points[lp[(k + 1) % m]] - points[lp[k]]) * t
}

/// A validated target with acceleration structures for closest-point queries (to the
/// surface and to its boundary loops), for the optimiser, the report and any later stage
/// that moves hub vertices on the target.
pub struct TargetIndex<'a> {
    pub(crate) mesh: &'a TargetMesh,
    /// The outer (longest) boundary loop.
    pub(crate) boundary: Vec<usize>,
    /// Every boundary loop, the outer one first.
    pub(crate) loops: Vec<Vec<usize>>,
    /// cumulative arc length at boundary vertex k (k = 0..=len, last = perimeter)
    pub(crate) boundary_arc: Vec<Real>,
    vertex_normals: Vec<Vector3>,
    lo: Point3,
    cell: Real,
    dims: [usize; 3],
    cells: Vec<Vec<u32>>,
}

impl<'a> TargetIndex<'a> {
    /// Validate `mesh` ([`TargetMesh::validate`]) and index it.
    pub fn new(mesh: &'a TargetMesh) -> Result<Self, SurfaceError> {
        let loops = mesh.validate()?;
        let boundary = loops[0].clone();
        let v = &mesh.vertices;
        let mut vertex_normals = vec![Vector3::zeros(); v.len()];
        let mut edge_sum = 0.0;
        for t in &mesh.triangles {
            let nrm = (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]]));
            for &i in t {
                vertex_normals[i] += nrm;
            }
            edge_sum += (v[t[1]] - v[t[0]]).norm()
                + (v[t[2]] - v[t[1]]).norm()
                + (v[t[0]] - v[t[2]]).norm();
        }
        for n in &mut vertex_normals {
            let l = n.norm();
            if l > 0.0 {
                *n /= l;
            }
        }
        let mean_edge = edge_sum / (3 * mesh.triangles.len()) as Real;
        let (mut lo, mut hi) = bounding_box(v);
        let pad = Vector3::repeat(1e-6 * (hi - lo).norm() + 1e-9);
        lo -= pad;
        hi += pad;
        let ext = hi - lo;
        let mut cell = (2.0 * mean_edge).max(1e-9);
        // at most ~2 million cells
        while (ext.x / cell + 1.0) * (ext.y / cell + 1.0) * (ext.z / cell + 1.0) > 2e6 {
            cell *= 1.5;
        }
        let dims = [0, 1, 2].map(|k| ((ext[k] / cell).floor() as usize + 1).max(1));
        let mut cells = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        for (ti, t) in mesh.triangles.iter().enumerate() {
            let (tlo, thi) = bounding_box(&[v[t[0]], v[t[1]], v[t[2]]]);
            let a =
                [0, 1, 2].map(|k| (((tlo[k] - lo[k]) / cell).floor() as usize).min(dims[k] - 1));
            let b =
                [0, 1, 2].map(|k| (((thi[k] - lo[k]) / cell).floor() as usize).min(dims[k] - 1));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        cells[(z * dims[1] + y) * dims[0] + x].push(ti as u32);
                    }
                }
            }
        }
        let mut boundary_arc = vec![0.0];
        for k in 0..boundary.len() {
            let d = (v[boundary[(k + 1) % boundary.len()]] - v[boundary[k]]).norm();
            boundary_arc.push(boundary_arc[k] + d);
        }
        Ok(Self {
            mesh,
            boundary,
            loops,
            boundary_arc,
            vertex_normals,
            lo,
            cell,
            dims,
            cells,
        })
    }

    /// The target this index answers for.
    pub fn mesh(&self) -> &TargetMesh {
        self.mesh
    }

    /// The boundary loops as target vertex indices, the outer (longest) first, each with
    /// the surface on its left.
    pub fn loops(&self) -> &[Vec<usize>] {
        &self.loops
    }

    /// Perimeter of the outer boundary loop.
    pub(crate) fn perimeter(&self) -> Real {
        *self.boundary_arc.last().unwrap_or(&0.0)
    }

    /// Closest point on the mesh (expanding shell search over the uniform grid).
    pub fn closest(&self, p: &Point3) -> ClosestPoint {
        self.closest_near(p, None)
    }

    /// Closest point on the mesh; `hint` is a triangle expected to be near (the answer
    /// for a nearby query): its distance bounds the search to the cells within that
    /// distance, which is exact and much cheaper than the shell search when it is small.
    pub fn closest_near(&self, p: &Point3, hint: Option<usize>) -> ClosestPoint {
        let v = &self.mesh.vertices;
        let dims = self.dims;
        let mut best = (Real::INFINITY, *p, [0.0; 3], 0usize);
        let test = |ti: usize, best: &mut (Real, Point3, [Real; 3], usize)| {
            let t = self.mesh.triangles[ti];
            let (q, bary) = closest_on_triangle(p, &v[t[0]], &v[t[1]], &v[t[2]]);
            let d = (q - p).norm_squared();
            if d < best.0 {
                *best = (d, q, bary, ti);
            }
        };
        let cell_of = |x: Real, k: usize| {
            (((x - self.lo[k]) / self.cell).floor()).clamp(0.0, (dims[k] - 1) as Real) as usize
        };
        let mut done = false;
        if let Some(h) = hint.filter(|&h| h < self.mesh.triangles.len()) {
            test(h, &mut best);
            let r = best.0.sqrt();
            if r <= 2.0 * self.cell {
                let a = [0, 1, 2].map(|k| cell_of(p[k] - r, k));
                let b = [0, 1, 2].map(|k| cell_of(p[k] + r, k));
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            for &ti in &self.cells[(z * dims[1] + y) * dims[0] + x] {
                                test(ti as usize, &mut best);
                            }
                        }
                    }
                }
                done = true;
            }
        }
        if !done {
            let c = [0, 1, 2].map(|k| cell_of(p[k], k) as i64);
            // distance from p to the grid box (to bound the shells)
            let mut outside = 0.0;
            for k in 0..3 {
                let hi = self.lo[k] + dims[k] as Real * self.cell;
                let d = (self.lo[k] - p[k]).max(p[k] - hi).max(0.0);
                outside += d * d;
            }
            let outside = outside.sqrt();
            let max_r = dims.iter().copied().max().unwrap_or(1) as i64;
            for r in 0..=max_r {
                for z in (c[2] - r).max(0)..=(c[2] + r).min(dims[2] as i64 - 1) {
                    for y in (c[1] - r).max(0)..=(c[1] + r).min(dims[1] as i64 - 1) {
                        for x in (c[0] - r).max(0)..=(c[0] + r).min(dims[0] as i64 - 1) {
                            let on_shell = (x - c[0]).abs() == r
                                || (y - c[1]).abs() == r
                                || (z - c[2]).abs() == r;
                            if !on_shell {
                                continue;
                            }
                            let idx = ((z as usize) * dims[1] + y as usize) * dims[0] + x as usize;
                            for &ti in &self.cells[idx] {
                                test(ti as usize, &mut best);
                            }
                        }
                    }
                }
                if best.0.is_finite() && best.0.sqrt() <= r as Real * self.cell - outside {
                    break;
                }
            }
        }
        let t = self.mesh.triangles[best.3];
        let n = self.vertex_normals[t[0]] * best.2[0]
            + self.vertex_normals[t[1]] * best.2[1]
            + self.vertex_normals[t[2]] * best.2[2];
        let n = if n.norm() > 1e-12 {
            n.normalize()
        } else {
            (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]])).normalize()
        };
        ClosestPoint {
            point: best.1,
            normal: n,
            triangle: best.3,
        }
    }

    /// Closest point on the boundary polylines (brute force over their segments); the
    /// arc length is measured along the loop the point is on.
    pub fn closest_on_boundary(&self, p: &Point3) -> BoundaryPoint {
        let v = &self.mesh.vertices;
        let mut best = (Real::INFINITY, *p, Vector3::x(), 0.0);
        for lp in &self.loops {
            let m = lp.len();
            let mut arc = 0.0;
            for k in 0..m {
                let a = v[lp[k]];
                let b = v[lp[(k + 1) % m]];
                let ab = b - a;
                let len2 = ab.norm_squared();
                let len = len2.sqrt();
                let s = if len2 > 0.0 {
                    ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let q = a + ab * s;
                let d = (q - p).norm_squared();
                if d < best.0 {
                    let t = if len2 > 0.0 { ab / len } else { Vector3::x() };
                    best = (d, q, t, arc + s * len);
                }
                arc += len;
            }
        }
        BoundaryPoint {
            point: best.1,
            tangent: best.2,
            arc: best.3,
        }
    }

    /// Point of the boundary at arc length `s` (wrapped into `[0, perimeter)`).
    pub(crate) fn boundary_at(&self, s: Real) -> Point3 {
        let v = &self.mesh.vertices;
        let per = self.perimeter();
        let s = s.rem_euclid(per);
        let m = self.boundary.len();
        let k = match self
            .boundary_arc
            .binary_search_by(|a| a.partial_cmp(&s).unwrap_or(std::cmp::Ordering::Less))
        {
            Ok(k) => k.min(m - 1),
            Err(k) => k.saturating_sub(1).min(m - 1),
        };
        let a = v[self.boundary[k]];
        let b = v[self.boundary[(k + 1) % m]];
        let len = self.boundary_arc[k + 1] - self.boundary_arc[k];
        let t = if len > 0.0 {
            (s - self.boundary_arc[k]) / len
        } else {
            0.0
        };
        a + (b - a) * t.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(n: usize) -> TargetMesh {
        let mut m = TargetMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.vertices.push(Point3::new(i as Real, j as Real, 0.0));
            }
        }
        let id = |i: usize, j: usize| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        m
    }

    fn err(m: &TargetMesh) -> String {
        m.validate().unwrap_err().to_string()
    }

    #[test]
    fn square_is_valid_with_one_loop() {
        let m = square(4);
        let lp = m.validate().unwrap();
        assert_eq!(lp.len(), 1);
        assert_eq!(lp[0].len(), 16);
        assert!((m.area() - 16.0).abs() < 1e-12);
    }

    #[test]
    fn bad_targets_name_the_culprit() {
        let mut m = square(2);
        m.vertices[3].y = f64::NAN;
        assert!(err(&m).contains("vertex 3"), "{}", err(&m));
        let mut m = square(2);
        m.triangles[5][1] = 99;
        assert!(err(&m).contains("triangle 5"), "{}", err(&m));
        let mut m = square(2);
        m.triangles[2] = [1, 1, 2];
        assert!(err(&m).contains("triangle 2"), "{}", err(&m));
        let mut m = square(2);
        m.triangles.push(m.triangles[0]);
        assert!(err(&m).contains("non-manifold"), "{}", err(&m));
        // two components
        let mut m = square(2);
        let k = m.vertices.len();
        m.vertices.extend([
            Point3::new(10.0, 0.0, 0.0),
            Point3::new(11.0, 0.0, 0.0),
            Point3::new(10.0, 1.0, 0.0),
        ]);
        m.triangles.push([k, k + 1, k + 2]);
        assert!(err(&m).contains("not connected"), "{}", err(&m));
        // a hole (the two centre triangles of a 3 x 3 square removed) is a second loop
        let mut m = square(3);
        m.triangles.drain(8..10);
        let loops = m.validate().unwrap();
        assert_eq!(loops.iter().map(Vec::len).collect::<Vec<_>>(), [12, 4]);
        let idx = TargetIndex::new(&m).unwrap();
        let b = idx.closest_on_boundary(&Point3::new(1.5, 1.4, 0.0));
        assert!(
            (b.point - Point3::new(1.5, 1.0, 0.0)).norm() < 1e-12,
            "{b:?}"
        );
        // closed: tetrahedron
        let m = TargetMesh {
            vertices: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
                Point3::new(0.0, 0.0, 1.0),
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        };
        assert!(err(&m).contains("closed"), "{}", err(&m));
        assert!(err(&TargetMesh::default()).contains("no triangles"));
    }

    #[test]
    fn closest_point_matches_brute_force() {
        let mut m = square(10);
        for p in &mut m.vertices {
            p.z = 0.1 * (p.x * 0.7).sin() * p.y;
        }
        let idx = TargetIndex::new(&m).unwrap();
        for k in 0..50 {
            let q = Point3::new(
                (k as Real * 0.37) % 12.0 - 1.0,
                (k as Real * 0.71) % 12.0 - 1.0,
                (k as Real * 0.13) % 3.0 - 1.5,
            );
            let c = idx.closest(&q);
            let brute = m
                .triangles
                .iter()
                .map(|t| {
                    let (p, _) = closest_on_triangle(
                        &q,
                        &m.vertices[t[0]],
                        &m.vertices[t[1]],
                        &m.vertices[t[2]],
                    );
                    (p - q).norm()
                })
                .fold(Real::INFINITY, Real::min);
            assert!(((c.point - q).norm() - brute).abs() < 1e-9, "query {k}");
            // any hint, near or far, gives the same distance
            for hint in [c.triangle, (c.triangle + 7) % m.triangles.len(), 0] {
                let h = idx.closest_near(&q, Some(hint));
                assert!(
                    ((h.point - q).norm() - brute).abs() < 1e-9,
                    "query {k} hint {hint}"
                );
            }
        }
        let b = idx.closest_on_boundary(&Point3::new(5.0, -2.0, 0.0));
        assert!((b.point - Point3::new(5.0, 0.0, 0.0)).norm() < 1e-12);
        assert!(
            idx.perimeter() > 40.0 && idx.perimeter() < 42.0,
            "{}",
            idx.perimeter()
        );
    }
}
