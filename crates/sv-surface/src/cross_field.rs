//! A smooth cross field (4-RoSy direction field) on the target, aligned with the principal
//! curvature directions where the surface is anisotropic and with the boundary along it:
//! Knöppel, Crane, Pinkall, Schröder 2013, "Globally optimal direction fields", with
//! prescribed directions. One sparse linear solve (faer Cholesky).
//!
//! A cross (four directions 90 degrees apart) at a vertex is the unit complex number
//! `u = e^(4 i theta)` in the vertex's tangent frame, `theta` the angle of any of its four
//! arms. Minimised over the interior vertices, the boundary ones held along the boundary
//! tangent:
//!
//! ```text
//! sum over edges ij   w_ij |u_i - r_ij u_j|^2               (smoothness, cotangent weights)
//! + sum over vertices lambda A_i (dk_i)^2 |u_i - q_i|^2     (alignment)
//! ```
//!
//! `r_ij = e^(4 i rho_ij)` transports a cross from `j`'s frame to `i`'s (the discrete
//! Levi-Civita connection: the edge keeps its angle), `q_i` is the principal frame of the
//! vertex as a cross, `dk_i = |k1 - k2|` its anisotropy (1/mm, from a quadratic fit over
//! the vertex's two-ring) and `A_i` its area. Where the surface is nearly umbilic the
//! field only has to be smooth; where it is anisotropic it follows the curvature lines
//! (which a planar, conical hub mesh must follow, `docs/secondary.md`). The field's
//! singularities (index in quarter turns: +1 where a valence-3 vertex belongs, -1 a
//! valence-5 one) are read off per triangle.

use nalgebra::{Matrix2, Matrix5, Vector5};
use sv_geom::{Real, Vector3};

use crate::target::TargetIndex;
use crate::SurfaceError;
use sv_geom::sparse::SpdSolver;

/// Weight of the curvature alignment against smoothness (dimensionless: `lambda (dk)^2`
/// has units 1/mm^2 like the Dirichlet energy density, so the field bends toward the
/// curvature lines over lengths of about `1 / (sqrt(lambda) dk)`; with 400 that is 500 mm
/// at `dk = 1e-4 / mm`, a 10 m curvature difference, and the field is smooth on the unit
/// scale).
pub const DEFAULT_ALIGNMENT: Real = 400.0;

/// The cross field of a target (see the module documentation).
#[derive(Clone, Debug)]
pub struct CrossField {
    /// One arm of the cross at every target vertex (unit, tangent); the others are it
    /// turned by 90, 180 and 270 degrees about the vertex normal.
    pub directions: Vec<Vector3>,
    /// The principal direction of largest absolute curvature at every vertex (unit).
    pub principal: Vec<Vector3>,
    /// `|k1 - k2|` at every vertex (1/mm).
    pub anisotropy: Vec<Real>,
    /// Principal curvatures at every vertex (1/mm): along [`CrossField::principal`] and
    /// across it.
    pub curvatures: Vec<(Real, Real)>,
    /// Unit normal at every vertex.
    pub normals: Vec<Vector3>,
    /// Singular triangles: (triangle, index in quarter turns). +1 is where a valence-3
    /// vertex of a quad mesh along the field belongs, -1 a valence-5 one.
    pub singularities: Vec<(usize, i32)>,
}

impl CrossField {
    /// The arm of the cross at vertex `v` closest in direction to `d` (projected to the
    /// tangent plane; any sign).
    pub fn arm_along(&self, v: usize, d: &Vector3) -> Vector3 {
        let a = self.directions[v];
        let b = self.normals[v].cross(&a);
        if a.dot(d).abs() >= b.dot(d).abs() {
            a * a.dot(d).signum()
        } else {
            b * b.dot(d).signum()
        }
    }
}

/// Orthonormal tangent frame `(x, y)` at a vertex with normal `n`, `x` along the
/// projection of `hint`.
fn frame(n: &Vector3, hint: &Vector3) -> (Vector3, Vector3) {
    let x = (hint - n * n.dot(hint))
        .try_normalize(1e-12)
        .unwrap_or_else(|| {
            n.cross(&Vector3::x())
                .try_normalize(1e-12)
                .unwrap_or(Vector3::y())
        });
    (x, n.cross(&x))
}

/// Angle of `d` in the frame `(x, y)`.
fn angle(d: &Vector3, x: &Vector3, y: &Vector3) -> Real {
    d.dot(y).atan2(d.dot(x))
}

/// `angle` wrapped into `(-pi, pi]`.
fn wrap(a: Real) -> Real {
    let t = std::f64::consts::TAU;
    a - t * ((a + std::f64::consts::PI) / t).floor()
}

/// The cross field of `index`'s target; `alignment` weighs the principal directions
/// against smoothness ([`DEFAULT_ALIGNMENT`]).
pub fn cross_field(index: &TargetIndex<'_>, alignment: Real) -> Result<CrossField, SurfaceError> {
    if !(alignment.is_finite() && alignment >= 0.0) {
        return Err(SurfaceError::InvalidParameter(format!(
            "field alignment must be finite and >= 0, got {alignment}"
        )));
    }
    let mesh = index.mesh;
    let v = &mesh.vertices;
    let nv = v.len();
    // neighbours, vertex areas (a third of each triangle), normals
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); nv];
    let mut area = vec![0.0; nv];
    let mut normals = vec![Vector3::zeros(); nv];
    for t in &mesh.triangles {
        let n = (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]]));
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !nb[a].contains(&b) {
                nb[a].push(b);
            }
            if !nb[b].contains(&a) {
                nb[b].push(a);
            }
            area[a] += n.norm() / 6.0;
            normals[a] += n;
        }
    }
    for n in &mut normals {
        *n = n.try_normalize(1e-300).unwrap_or(Vector3::z());
    }
    let frames: Vec<(Vector3, Vector3)> = (0..nv)
        .map(|i| frame(&normals[i], &(v[nb[i][0]] - v[i])))
        .collect();
    // principal directions and anisotropy from a quadratic fit over the two-ring
    let mut principal = vec![Vector3::zeros(); nv];
    let mut anisotropy = vec![0.0; nv];
    let mut curvatures = vec![(0.0, 0.0); nv];
    let mut q = vec![(1.0, 0.0); nv];
    for i in 0..nv {
        let (x, y) = frames[i];
        let n = normals[i];
        let mut ring: Vec<usize> = nb[i].clone();
        for &j in &nb[i] {
            for &k in &nb[j] {
                if k != i && !ring.contains(&k) {
                    ring.push(k);
                }
            }
        }
        let mut ata = Matrix5::zeros();
        let mut atb = Vector5::zeros();
        for &j in &ring {
            let d = v[j] - v[i];
            let (a, b, h) = (d.dot(&x), d.dot(&y), d.dot(&n));
            let row = Vector5::new(a * a / 2.0, a * b, b * b / 2.0, a, b);
            ata += row * row.transpose();
            atb += row * h;
        }
        let Some(c) = ata.lu().solve(&atb) else {
            continue;
        };
        let e = Matrix2::new(c[0], c[1], c[1], c[2]).symmetric_eigen();
        let (k0, k1) = (e.eigenvalues[0], e.eigenvalues[1]);
        let m = if k0.abs() >= k1.abs() { 0 } else { 1 };
        let dir = e.eigenvectors.column(m);
        let theta = dir[1].atan2(dir[0]);
        principal[i] = x * theta.cos() + y * theta.sin();
        anisotropy[i] = (k0 - k1).abs();
        curvatures[i] = if m == 0 { (k0, k1) } else { (k1, k0) };
        q[i] = ((4.0 * theta).cos(), (4.0 * theta).sin());
    }
    // boundary vertices hold the boundary tangent (at a corner the mean of the two
    // sides' crosses; where they cancel, the vertex is left free)
    let mut fixed: Vec<Option<(Real, Real)>> = vec![None; nv];
    for lp in &index.loops {
        let m = lp.len();
        for k in 0..m {
            let (prev, here, next) = (lp[(k + m - 1) % m], lp[k], lp[(k + 1) % m]);
            let (x, y) = frames[here];
            let (a, b) = (
                4.0 * angle(&(v[here] - v[prev]), &x, &y),
                4.0 * angle(&(v[next] - v[here]), &x, &y),
            );
            let (c, s) = (a.cos() + b.cos(), a.sin() + b.sin());
            let r = c.hypot(s);
            if r > 0.5 {
                fixed[here] = Some((c / r, s / r));
            }
        }
    }
    let mut col = vec![usize::MAX; nv];
    let mut n = 0;
    for i in 0..nv {
        if fixed[i].is_none() {
            col[i] = n;
            n += 2;
        }
    }
    // transport r_ij (4-fold angle) along every edge, cotangent weights
    let mut weight: std::collections::HashMap<(usize, usize), Real> = Default::default();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (i, j, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (a, b) = (v[i] - v[o], v[j] - v[o]);
            let cot = a.dot(&b) / a.cross(&b).norm().max(1e-300);
            *weight.entry((i.min(j), i.max(j))).or_insert(0.0) += 0.5 * cot;
        }
    }
    let transport = |i: usize, j: usize| {
        let e = v[j] - v[i];
        let (xi, yi) = frames[i];
        let (xj, yj) = frames[j];
        4.0 * (angle(&e, &xi, &yi) - angle(&e, &xj, &yj))
    };
    let mut pattern = Vec::new();
    let mut values = Vec::new();
    let mut rhs = vec![0.0; n];
    let mut edges: Vec<((usize, usize), Real)> = weight.into_iter().collect();
    edges.sort_by_key(|e| e.0);
    for ((i, j), w) in edges {
        // keep the energy positive definite on meshes with obtuse triangles
        let w = w.max(1e-3);
        let rho = transport(i, j);
        let (c, s) = (rho.cos(), rho.sin());
        // u_i ~ R u_j with R the rotation by rho
        let rot = [[c, -s], [s, c]];
        for (p, fp) in [(i, j), (j, i)] {
            if col[p] != usize::MAX {
                block(
                    &mut pattern,
                    &mut values,
                    col[p],
                    col[p],
                    [[w, 0.0], [0.0, w]],
                );
                if let Some((a, b)) = fixed[fp] {
                    // p's neighbour is held: its transported cross goes to the right side
                    let (tc, ts) = if p == i { (c, s) } else { (c, -s) };
                    rhs[col[p]] += w * (tc * a - ts * b);
                    rhs[col[p] + 1] += w * (ts * a + tc * b);
                }
            }
        }
        if col[i] != usize::MAX && col[j] != usize::MAX {
            // -w R between i and j (the upper triangle only)
            let m = rot.map(|row| row.map(|x| -w * x));
            if col[i] < col[j] {
                block(&mut pattern, &mut values, col[i], col[j], m);
            } else {
                let mt = [[m[0][0], m[1][0]], [m[0][1], m[1][1]]];
                block(&mut pattern, &mut values, col[j], col[i], mt);
            }
        }
    }
    for i in 0..nv {
        if col[i] == usize::MAX {
            continue;
        }
        let w = alignment * area[i] * anisotropy[i] * anisotropy[i] + 1e-9;
        block(
            &mut pattern,
            &mut values,
            col[i],
            col[i],
            [[w, 0.0], [0.0, w]],
        );
        rhs[col[i]] += w * q[i].0;
        rhs[col[i] + 1] += w * q[i].1;
    }
    if n > 0 {
        let mut solver = SpdSolver::new(n, &pattern)?;
        solver.set_values(&values);
        if !solver.solve(&mut rhs)? {
            return Err(SurfaceError::Internal(
                "cross field system is not positive definite".into(),
            ));
        }
    }
    let four: Vec<Real> = (0..nv)
        .map(|i| match fixed[i] {
            Some((a, b)) => b.atan2(a),
            None => rhs[col[i] + 1].atan2(rhs[col[i]]),
        })
        .collect();
    let directions: Vec<Vector3> = (0..nv)
        .map(|i| {
            let (x, y) = frames[i];
            let t = four[i] / 4.0;
            x * t.cos() + y * t.sin()
        })
        .collect();
    // singularities: the cross turns by a multiple of 90 degrees around a triangle
    let mut singularities = Vec::new();
    for (ti, t) in mesh.triangles.iter().enumerate() {
        // (the transport around a triangle closes up to its angle defect, far below a
        // quarter turn on these meshes)
        let turn: Real = (0..3)
            .map(|k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                // b's cross in a's frame, against a's
                wrap(four[b] + transport(a, b) - four[a])
            })
            .sum();
        let index = (turn / std::f64::consts::TAU).round() as i32;
        if index != 0 {
            singularities.push((ti, index));
        }
    }
    Ok(CrossField {
        directions,
        principal,
        anisotropy,
        curvatures,
        normals,
        singularities,
    })
}

/// A 2 x 2 block `m` of the symmetric system at rows `r..r+2`, columns `c..c+2` (its
/// upper-triangle entries only).
fn block(
    pattern: &mut Vec<(usize, usize)>,
    values: &mut Vec<Real>,
    r: usize,
    c: usize,
    m: [[Real; 2]; 2],
) {
    for (a, row) in m.iter().enumerate() {
        for (b, &x) in row.iter().enumerate() {
            if r + a <= c + b {
                pattern.push((r + a, c + b));
                values.push(x);
            }
        }
    }
}
