//! The secondary (hub) quad mesh.

use std::collections::HashMap;

use sv_geom::{is_finite_point, quad_diagonal_distance, Point3, Real, Vector3};

use crate::{Degeneracy, MeshError};

/// A quad mesh in mm. Faces list four vertex indices counter-clockwise seen from the
/// side the hub normals point to (`n = (v0 - v2) x (v1 - v3)`).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct QuadMesh {
    /// Vertex positions (mm).
    pub vertices: Vec<Point3>,
    /// Faces as vertex indices.
    pub faces: Vec<[usize; 4]>,
}

/// Tolerances for [`QuadMesh::validate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshChecks {
    /// Largest allowed diagonal distance / mean edge of a face. Meshes made planar in a
    /// CAD tool reach 1e-3 easily; the default 0.01 catches faces that were never planarised.
    pub planarity_tolerance: Real,
}

impl MeshChecks {
    /// Default planarity tolerance (diagonal distance / mean edge).
    pub const DEFAULT_PLANARITY_TOLERANCE: Real = 0.01;
}

impl Default for MeshChecks {
    fn default() -> Self {
        Self {
            planarity_tolerance: Self::DEFAULT_PLANARITY_TOLERANCE,
        }
    }
}

/// An interior edge shared by two faces, oriented as `faces[0]` lists it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link {
    /// The two faces (units).
    pub faces: [usize; 2],
    /// The edge `(v, w)` in the order `faces[0]` lists it.
    pub edge: [usize; 2],
    /// Position `k` of the edge in each face: face `f` lists it as `(f[k], f[k+1])`.
    /// Side `k` of a unit's primary tile and hub corner `k` face this link.
    pub slots: [usize; 2],
}

impl QuadMesh {
    /// A flat `nx` x `ny` grid of squares of side `spacing` in the XY plane, normals +Z.
    pub fn grid(nx: usize, ny: usize, spacing: Real) -> Self {
        Self::from_fn(nx, ny, |i, j| {
            Point3::new(i as Real * spacing, j as Real * spacing, 0.0)
        })
    }

    /// A `nx` x `ny` face grid whose vertex `(i, j)` (`0 <= i <= nx`, `0 <= j <= ny`) is
    /// `position(i, j)`; faces are counter-clockwise in `(i, j)`.
    pub fn from_fn(nx: usize, ny: usize, position: impl Fn(usize, usize) -> Point3) -> Self {
        let mut vertices = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                vertices.push(position(i, j));
            }
        }
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut faces = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Self { vertices, faces }
    }

    /// A translational surface `z = f(x) + g(y)` sampled on a square grid: its faces are
    /// exactly planar for any `f`, `g` (opposite edges are translates of each other).
    pub fn translational(
        nx: usize,
        ny: usize,
        spacing: Real,
        f: impl Fn(Real) -> Real,
        g: impl Fn(Real) -> Real,
    ) -> Self {
        let (x0, y0) = (nx as Real * spacing / 2.0, ny as Real * spacing / 2.0);
        Self::from_fn(nx, ny, |i, j| {
            let (x, y) = (i as Real * spacing - x0, j as Real * spacing - y0);
            Point3::new(x, y, f(x) + g(y))
        })
    }

    /// A cap of a sphere of radius `radius` around its top, meshed by its curvature lines
    /// (meridians and parallels of a band around an equator through the top), so faces are
    /// planar isosceles trapezoids and vertices conical. Edge length about `spacing`.
    pub fn sphere_cap(nx: usize, ny: usize, radius: Real, spacing: Real) -> Self {
        let step = spacing / radius;
        let (u0, v0) = (nx as Real * step / 2.0, ny as Real * step / 2.0);
        Self::from_fn(nx, ny, |i, j| {
            let lon = i as Real * step - u0;
            let lat = j as Real * step - v0;
            // point on the band around the equator in the XZ plane through the top
            let p = Vector3::new(lat.cos() * lon.sin(), lat.sin(), lat.cos() * lon.cos());
            Point3::from(p * radius - Vector3::new(0.0, 0.0, radius))
        })
    }

    /// Mean edge length over all face edges (each interior edge counted twice).
    pub fn mean_edge(&self) -> Real {
        let mut sum = 0.0;
        let mut n = 0usize;
        for f in &self.faces {
            for k in 0..4 {
                if let (Some(a), Some(b)) =
                    (self.vertices.get(f[k]), self.vertices.get(f[(k + 1) % 4]))
                {
                    sum += (a - b).norm();
                    n += 1;
                }
            }
        }
        if n == 0 {
            0.0
        } else {
            sum / n as Real
        }
    }

    /// The four corner positions of face `f` (indices must be valid).
    pub fn face_points(&self, f: usize) -> [Point3; 4] {
        self.faces[f].map(|v| self.vertices[v])
    }

    /// Per vertex: whether it lies on an edge of only one face (faces naming vertices
    /// past the end are skipped).
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let mut faces_on: HashMap<(usize, usize), usize> = HashMap::new();
        for f in &self.faces {
            for k in 0..4 {
                let (a, b) = (f[k], f[(k + 1) % 4]);
                *faces_on.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let mut boundary = vec![false; self.vertices.len()];
        for (&(a, b), _) in faces_on.iter().filter(|(_, &n)| n == 1) {
            for v in [a, b] {
                if let Some(x) = boundary.get_mut(v) {
                    *x = true;
                }
            }
        }
        boundary
    }

    /// Per vertex: a corner of the mesh, a boundary vertex with other than two faces (one
    /// at a convex corner, three or more at a reflex one). The optimisers hold these where
    /// they start.
    pub fn corners(&self) -> Vec<bool> {
        let mut faces_at = vec![0usize; self.vertices.len()];
        for &v in self.faces.iter().flatten() {
            if let Some(n) = faces_at.get_mut(v) {
                *n += 1;
            }
        }
        let boundary = self.boundary_vertices();
        (0..faces_at.len())
            .map(|v| boundary[v] && faces_at[v] != 2)
            .collect()
    }

    /// Interior edges with the two faces on them. Call after [`QuadMesh::validate`].
    pub fn links(&self) -> Vec<Link> {
        let mut by_edge: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
        let mut links = Vec::new();
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..4 {
                let (v, w) = (face[k], face[(k + 1) % 4]);
                if let Some(&(g, m)) = by_edge.get(&(w, v)) {
                    links.push(Link {
                        faces: [g, f],
                        edge: [w, v],
                        slots: [m, k],
                    });
                } else {
                    by_edge.insert((v, w), (f, k));
                }
            }
        }
        links.sort_by_key(|l| (l.faces[0], l.faces[1]));
        links
    }

    /// Planarity of every face: diagonal distance / mean edge of the face.
    pub fn planarity_residuals(&self) -> Vec<Real> {
        (0..self.faces.len())
            .map(|f| {
                let p = self.face_points(f);
                let mean = (0..4).map(|k| (p[k] - p[(k + 1) % 4]).norm()).sum::<Real>() / 4.0;
                quad_diagonal_distance(&p) / mean
            })
            .collect()
    }

    /// Conical residual (rad) at every interior vertex, with the faces around it in
    /// cyclic order:
    /// - four faces: `|w1 - w2 + w3 - w4|`, the face angles at the vertex (Pottmann and
    ///   Wallner's angle balance; zero exactly for a conical vertex);
    /// - three faces: always conical (three normals lie on a circle of the Gauss sphere), 0;
    /// - `n >= 5` faces: the face normals must lie on one circle of the Gauss sphere (a
    ///   cone of normals, `n - 3` conditions): the largest angle between a normal and the
    ///   best-fit cone (axis `a`, half-angle `acos c` minimising `sum (n_i . a - c)^2`).
    pub fn conical_residuals(&self) -> Vec<(usize, Real)> {
        let mut out: Vec<(usize, Real)> = self
            .interior_fans()
            .into_iter()
            .map(|(v, fan)| (v, self.fan_conical_residual(v, &fan)))
            .collect();
        out.sort_by_key(|&(v, _)| v);
        out
    }

    /// Every interior vertex with its closed fan of `(face, corner)` pairs in cyclic order
    /// (each face's outgoing neighbour is the next face's incoming one). Vertices on the
    /// boundary or with a fan that does not close are left out.
    pub fn interior_fans(&self) -> Vec<(usize, Vec<(usize, usize)>)> {
        let mut around: HashMap<usize, Vec<(usize, usize)>> = HashMap::new();
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..4 {
                around.entry(face[k]).or_default().push((f, k));
            }
        }
        let mut out = Vec::new();
        for (v, corners) in around {
            let next_of = |(f, k): (usize, usize)| self.faces[f][(k + 1) % 4];
            let prev_of = |(f, k): (usize, usize)| self.faces[f][(k + 3) % 4];
            let mut order = vec![corners[0]];
            while order.len() < corners.len() {
                let out_nb = next_of(*order.last().unwrap_or(&corners[0]));
                match corners.iter().find(|&&c| prev_of(c) == out_nb) {
                    Some(&c) if !order.contains(&c) => order.push(c),
                    _ => break,
                }
            }
            let closed = order.len() == corners.len()
                && next_of(order[order.len() - 1]) == prev_of(order[0]);
            if closed && order.len() >= 3 {
                out.push((v, order));
            }
        }
        out.sort_by_key(|(v, _)| *v);
        out
    }

    /// Conical residual at `v` with its closed fan (see [`QuadMesh::conical_residuals`]).
    fn fan_conical_residual(&self, v: usize, fan: &[(usize, usize)]) -> Real {
        let p = self.vertices[v];
        match fan.len() {
            3 => 0.0,
            4 => {
                let w: Vec<Real> = fan
                    .iter()
                    .map(|&(f, k)| {
                        let face = self.faces[f];
                        let a = self.vertices[face[(k + 3) % 4]] - p;
                        let b = self.vertices[face[(k + 1) % 4]] - p;
                        a.angle(&b)
                    })
                    .collect();
                (w[0] - w[1] + w[2] - w[3]).abs()
            }
            _ => {
                let normals: Vec<Vector3> = fan
                    .iter()
                    .map(|&(f, _)| {
                        let q = self.face_points(f);
                        (q[0] - q[2])
                            .cross(&(q[1] - q[3]))
                            .try_normalize(1e-300)
                            .unwrap_or_else(Vector3::zeros)
                    })
                    .collect();
                normal_cone_residual(&normals)
            }
        }
    }

    /// Check everything a frame needs: finite coordinates, indices in range, no degenerate
    /// faces, manifold and consistently oriented edges, planar faces, at least one link.
    pub fn validate(&self, checks: &MeshChecks) -> Result<(), MeshError> {
        if self.faces.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(v) = self.vertices.iter().position(|p| !is_finite_point(p)) {
            return Err(MeshError::NonFinite { vertex: v });
        }
        let count = self.vertices.len();
        for (f, face) in self.faces.iter().enumerate() {
            if let Some(&index) = face.iter().find(|&&i| i >= count) {
                return Err(MeshError::IndexOutOfRange {
                    face: f,
                    index,
                    count,
                });
            }
        }
        let scale = self.mean_edge();
        let eps = 1e-9 * scale.max(1e-300);
        for (f, face) in self.faces.iter().enumerate() {
            let p = self.face_points(f);
            for k in 0..4 {
                for m in (k + 1)..4 {
                    if face[k] == face[m] {
                        return Err(MeshError::DegenerateFace {
                            face: f,
                            why: Degeneracy::VertexTwice(face[k]),
                        });
                    }
                }
                if (p[k] - p[(k + 1) % 4]).norm() <= eps {
                    return Err(MeshError::DegenerateFace {
                        face: f,
                        why: Degeneracy::ZeroEdge(face[k], face[(k + 1) % 4]),
                    });
                }
            }
            let area2 = (p[0] - p[2]).cross(&(p[1] - p[3])).norm();
            if area2 <= 1e-6 * scale * scale {
                return Err(MeshError::DegenerateFace {
                    face: f,
                    why: Degeneracy::ZeroArea,
                });
            }
        }
        let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
        for face in &self.faces {
            for k in 0..4 {
                let e = (face[k], face[(k + 1) % 4]);
                *directed.entry(e).or_default() += 1;
            }
        }
        let mut keys: Vec<_> = directed.iter().collect();
        keys.sort();
        for (&(v, w), &n) in keys {
            if n > 1 {
                let faces: Vec<usize> = (0..self.faces.len())
                    .filter(|&f| {
                        (0..4).any(|k| self.faces[f][k] == v && self.faces[f][(k + 1) % 4] == w)
                    })
                    .collect();
                let corners = |f: usize| {
                    let mut c = self.faces[f];
                    c.sort_unstable();
                    c
                };
                let why = if faces.windows(2).any(|p| corners(p[0]) == corners(p[1])) {
                    "the same face is listed twice".to_string()
                } else if directed.contains_key(&(w, v)) {
                    "used by more than two faces".to_string()
                } else {
                    "two faces list it in the same direction (inconsistent orientation)".to_string()
                };
                return Err(MeshError::NonManifoldEdge { v, w, why, faces });
            }
        }
        for f in 0..self.faces.len() {
            let p = self.face_points(f);
            let mean = (0..4).map(|k| (p[k] - p[(k + 1) % 4]).norm()).sum::<Real>() / 4.0;
            let distance = quad_diagonal_distance(&p);
            let ratio = distance / mean;
            if ratio > checks.planarity_tolerance {
                return Err(MeshError::NonPlanar {
                    face: f,
                    distance,
                    ratio,
                    tolerance: checks.planarity_tolerance,
                });
            }
        }
        if self.links().is_empty() {
            return Err(MeshError::TooSmall {
                why: format!(
                    "{} face(s) and no interior edge; a frame needs at least two units that share an edge",
                    self.faces.len()
                ),
            });
        }
        Ok(())
    }
}

/// Axis (unit, on the side of the normals' mean) and cosine of the cone that fits the unit
/// `normals` best: the eigenvector of the smallest eigenvalue of their covariance, and the
/// mean of `n . axis`.
pub fn normal_cone(normals: &[Vector3]) -> (Vector3, Real) {
    let mean = normals.iter().sum::<Vector3>() / normals.len().max(1) as Real;
    let mut cov = sv_geom::Matrix3::zeros();
    for n in normals {
        let d = n - mean;
        cov += d * d.transpose();
    }
    let eig = cov.symmetric_eigen();
    let k = (0..3)
        .min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))
        .unwrap_or(0);
    let mut axis: Vector3 = eig.eigenvectors.column(k).into();
    if axis.dot(&mean) < 0.0 {
        axis = -axis;
    }
    (axis, mean.dot(&axis))
}

/// Largest angle (rad) between a unit normal and the cone of normals that fits them best:
/// axis `a` (unit) and `c` minimising `sum (n_i . a - c)^2`, i.e. `a` the eigenvector of
/// the smallest eigenvalue of the normals' covariance and `c` the mean of `n_i . a`. Zero
/// exactly when the normals lie on one circle of the Gauss sphere.
pub fn normal_cone_residual(normals: &[Vector3]) -> Real {
    if normals.len() < 4 {
        return 0.0;
    }
    let (axis, c) = normal_cone(normals);
    let half = c.clamp(-1.0, 1.0).acos();
    normals
        .iter()
        .map(|n| (n.dot(&axis).clamp(-1.0, 1.0).acos() - half).abs())
        .fold(0.0, Real::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L of three faces: the five convex corners (one face each) and the reflex one
    /// (three faces, on the boundary) are corners; the two boundary vertices of two faces
    /// are not, and nothing past the L's faces is on its boundary.
    #[test]
    fn an_l_has_five_convex_corners_and_one_reflex_corner() {
        let vertices = (0..9)
            .map(|k| Point3::new((k % 3) as Real, (k / 3) as Real, 0.0))
            .collect();
        let at = |i: usize, j: usize| j * 3 + i;
        let faces = [(0, 0), (1, 0), (0, 1)]
            .map(|(i, j)| [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)])
            .to_vec();
        let mesh = QuadMesh { vertices, faces };
        let listed = |flags: Vec<bool>| -> Vec<usize> { (0..9).filter(|&v| flags[v]).collect() };
        assert_eq!(listed(mesh.corners()), vec![0, 2, 4, 5, 6, 7]);
        assert_eq!(
            listed(mesh.boundary_vertices()),
            vec![0, 1, 2, 3, 4, 5, 6, 7]
        );
    }

    #[test]
    fn grid_links_are_interior_edges() {
        let m = QuadMesh::grid(3, 2, 100.0);
        // interior edges of a 3x2 grid: 2*2 vertical + 3*1 horizontal
        assert_eq!(m.links().len(), 7);
        m.validate(&MeshChecks::default()).unwrap();
        for l in m.links() {
            let f = m.faces[l.faces[0]];
            let g = m.faces[l.faces[1]];
            assert_eq!([f[l.slots[0]], f[(l.slots[0] + 1) % 4]], l.edge);
            assert_eq!(
                [g[l.slots[1]], g[(l.slots[1] + 1) % 4]],
                [l.edge[1], l.edge[0]]
            );
        }
    }

    #[test]
    fn translational_and_sphere_faces_are_planar() {
        let saddle = QuadMesh::translational(8, 8, 300.0, |x| x * x / 6000.0, |y| -y * y / 6000.0);
        saddle
            .validate(&MeshChecks {
                planarity_tolerance: 1e-9,
            })
            .unwrap();
        let cap = QuadMesh::sphere_cap(8, 8, 3000.0, 300.0);
        cap.validate(&MeshChecks {
            planarity_tolerance: 1e-9,
        })
        .unwrap();
        // the cap bulges up: the middle is higher than the corners
        let top = cap.vertices[4 * 9 + 4].z;
        assert!(top > cap.vertices[0].z + 100.0);
    }

    #[test]
    fn sphere_net_is_conical_and_grid_is_planar() {
        let cap = QuadMesh::sphere_cap(6, 6, 3000.0, 300.0);
        let con = cap.conical_residuals();
        assert_eq!(con.len(), 25);
        assert!(con.iter().all(|&(_, r)| r < 1e-9), "{con:?}");
        // a translational saddle is planar but not conical
        let saddle = QuadMesh::translational(6, 6, 300.0, |x| x * x / 3000.0, |y| -y * y / 3000.0);
        assert!(saddle.planarity_residuals().iter().all(|&r| r < 1e-9));
        let worst = saddle
            .conical_residuals()
            .iter()
            .map(|c| c.1)
            .fold(0.0, f64::max);
        assert!(worst > 1e-3, "{worst}");
    }

    #[test]
    fn bad_meshes_say_what_and_where() {
        let mut m = QuadMesh::grid(2, 1, 100.0);
        m.vertices[3].y = f64::NAN;
        assert_eq!(
            m.validate(&Default::default()),
            Err(MeshError::NonFinite { vertex: 3 })
        );

        let mut m = QuadMesh::grid(2, 1, 100.0);
        m.faces[1][2] = 99;
        assert!(matches!(
            m.validate(&Default::default()),
            Err(MeshError::IndexOutOfRange {
                face: 1,
                index: 99,
                ..
            })
        ));

        let mut m = QuadMesh::grid(2, 1, 100.0);
        m.faces[0][3] = m.faces[0][0];
        assert!(matches!(
            m.validate(&Default::default()),
            Err(MeshError::DegenerateFace { face: 0, .. })
        ));

        let mut m = QuadMesh::grid(2, 1, 100.0);
        m.vertices[5].z = 30.0;
        assert!(matches!(
            m.validate(&Default::default()),
            Err(MeshError::NonPlanar { face: 1, .. })
        ));

        let mut m = QuadMesh::grid(2, 1, 100.0);
        m.faces[1].reverse();
        assert!(matches!(
            m.validate(&Default::default()),
            Err(MeshError::NonManifoldEdge { .. })
        ));

        let mut m = QuadMesh::grid(2, 1, 100.0);
        m.faces.push(m.faces[1]);
        assert!(matches!(
            m.validate(&Default::default()),
            Err(MeshError::NonManifoldEdge { .. })
        ));

        let m = QuadMesh::grid(1, 1, 100.0);
        assert!(matches!(
            m.validate(&Default::default()),
            Err(MeshError::TooSmall { .. })
        ));
        assert_eq!(
            QuadMesh::default().validate(&Default::default()),
            Err(MeshError::Empty)
        );
    }

    /// A vertex with `n` faces at the apex of a right cone: ring points and outer points
    /// on the cone, so every face normal makes the same angle with the axis.
    fn cone_star(n: usize) -> QuadMesh {
        let mut m = QuadMesh::default();
        m.vertices.push(Point3::new(0.0, 0.0, 300.0));
        let ang = |k: usize| 2.0 * std::f64::consts::PI * k as Real / n as Real;
        for k in 0..n {
            let (s, c) = ang(k).sin_cos();
            m.vertices.push(Point3::new(300.0 * c, 300.0 * s, 200.0));
        }
        for k in 0..n {
            let (s, c) = (ang(k) + std::f64::consts::PI / n as Real).sin_cos();
            let r = 300.0 / (std::f64::consts::PI / n as Real).cos();
            m.vertices.push(Point3::new(r * c, r * s, 200.0));
        }
        for k in 0..n {
            m.faces.push([0, 1 + k, 1 + n + k, 1 + (k + 1) % n]);
        }
        m
    }

    #[test]
    fn conical_residual_at_any_valence() {
        for n in [3, 4, 5, 6] {
            let mut m = cone_star(n);
            // a cone of revolution: conical at any valence (faces planar: the outer
            // point lies in the plane of apex and ring)
            let c = m.conical_residuals();
            assert_eq!(c.len(), 1, "valence {n}: {c:?}");
            assert_eq!(c[0].0, 0);
            assert!(c[0].1 < 1e-9, "valence {n}: {c:?}");
            // move one ring point: three normals still lie on a circle, more do not
            m.vertices[1].y += 80.0;
            m.vertices[1].z += 80.0;
            let r = m.conical_residuals()[0].1;
            if n == 3 {
                assert_eq!(r, 0.0);
            } else {
                assert!(r > 1e-3, "valence {n}: {r}");
            }
        }
        // boundary vertices have no conical condition
        assert!(QuadMesh::grid(1, 1, 100.0).conical_residuals().is_empty());
    }
}
