//! Guided projection (Tang et al. 2014): Gauss-Newton on quadratic constraints with
//! auxiliary unit face normals and cone axes, solved through the normal equations with
//! a sparse Cholesky factorisation whose symbolic part is reused every iteration.

use sv_frame::QuadMesh;
use sv_geom::{quad_diagonal_distance, Point3, Real, Vector3};

use crate::report::{conical_residuals, measure, Goals, SecondaryReport};
use crate::sparse::SpdSolver;
use crate::target::TargetIndex;
use crate::topology::Topology;
use crate::{SecondaryOptions, SurfaceError, TargetMesh};

/// Shortest allowed edge, as a fraction of the initial mean edge.
const COLLAPSE_FRACTION: Real = 0.2;
/// Largest factor by which the planarity and conical weights grow during the run.
const HARD_GAIN_MAX: Real = 100.0;

/// Normal equations `(J^T W J + eps I) dx = -J^T W r` assembled row by row in a fixed order.
struct System {
    n: usize,
    pattern: Vec<(usize, usize)>,
    values: Vec<Real>,
    rhs: Vec<Real>,
    first: bool,
    energy: Real,
}

impl System {
    fn new(n: usize) -> Self {
        Self {
            n,
            pattern: Vec::new(),
            values: Vec::new(),
            rhs: vec![0.0; n],
            first: true,
            energy: 0.0,
        }
    }

    fn reset(&mut self, regulariser: Real) {
        self.values.clear();
        self.rhs.iter_mut().for_each(|r| *r = 0.0);
        self.energy = 0.0;
        for i in 0..self.n {
            if self.first {
                self.pattern.push((i, i));
            }
            self.values.push(regulariser);
        }
    }

    /// One residual `r` with gradient `vals` over distinct columns `cols`, weight `w`.
    fn row(&mut self, cols: &[usize], vals: &[Real], r: Real, w: Real) {
        let w2 = w * w;
        self.energy += w2 * r * r;
        for a in 0..cols.len() {
            self.rhs[cols[a]] -= w2 * vals[a] * r;
            for b in a..cols.len() {
                if self.first {
                    self.pattern
                        .push((cols[a].min(cols[b]), cols[a].max(cols[b])));
                }
                self.values.push(w2 * vals[a] * vals[b]);
            }
        }
    }
}

fn push3(cols: &mut Vec<usize>, vals: &mut Vec<Real>, base: usize, v: &Vector3) {
    for k in 0..3 {
        cols.push(base + k);
        vals.push(v[k]);
    }
}

/// Optimise `initial` toward a planar, conical, nearly square mesh on `target`.
/// `progress(iteration, energy)` is called after every iteration.
pub fn optimise(
    target: &TargetMesh,
    initial: QuadMesh,
    opts: &SecondaryOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(QuadMesh, SecondaryReport), SurfaceError> {
    opts.check()?;
    let index = TargetIndex::new(target)?;
    optimise_indexed(&index, initial, opts, progress)
}

pub(crate) fn optimise_indexed(
    index: &TargetIndex<'_>,
    initial: QuadMesh,
    opts: &SecondaryOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(QuadMesh, SecondaryReport), SurfaceError> {
    let topo = Topology::new(&initial)?;
    if initial.faces.is_empty() {
        return Err(SurfaceError::InvalidParameter(
            "the initial mesh has no faces".into(),
        ));
    }
    if let Some(v) = initial
        .vertices
        .iter()
        .position(|p| !sv_geom::is_finite_point(p))
    {
        return Err(SurfaceError::InvalidParameter(format!(
            "initial vertex {v} is not finite"
        )));
    }
    let scale = initial.mean_edge();
    let centre = sv_geom::centroid(&initial.vertices).unwrap_or_else(Point3::origin);
    let nv = initial.vertices.len();
    let nf = initial.faces.len();
    let faces = initial.faces.clone();
    let initial_vertices = initial.vertices.clone();
    let to_world =
        |x: &[Real], v: usize| centre + Vector3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]) * scale;
    let nbase = 3 * nv;
    let n = nbase + 3 * nf;
    let mut x = vec![0.0; n];
    for (v, p) in initial.vertices.iter().enumerate() {
        let d = (p - centre) / scale;
        x[3 * v..3 * v + 3].copy_from_slice(d.as_slice());
    }
    let pos = |x: &[Real], v: usize| Vector3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
    let face_normal = |x: &[Real], f: usize| {
        let q = faces[f].map(|v| pos(x, v));
        (q[0] - q[2]).cross(&(q[1] - q[3]))
    };
    // orientation reference: the target normal at each face
    let reference: Vec<Vector3> = (0..nf)
        .map(|f| {
            let c = faces[f]
                .iter()
                .map(|&v| initial.vertices[v].coords)
                .sum::<Vector3>()
                / 4.0;
            index.closest(&Point3::from(c)).normal
        })
        .collect();
    for f in 0..nf {
        let g = face_normal(&x, f);
        if g.dot(&reference[f]) <= 0.0 {
            return Err(SurfaceError::Folded(format!(
                "initial face {f} is flipped against the target"
            )));
        }
        let nrm = g.normalize();
        x[nbase + 3 * f..nbase + 3 * f + 3].copy_from_slice(nrm.as_slice());
    }

    let mut system = System::new(n);
    let mut solver: Option<SpdSolver> = None;
    let mut iterations = 0;
    let (mut cols, mut vals) = (Vec::with_capacity(16), Vec::with_capacity(16));
    for it in 0..opts.max_iterations {
        iterations = it + 1;
        let decay = (0.5f64).powf(it as Real / 10.0).max(0.1);
        let w_fair = opts.fairness_weight * decay;
        let w_edge = opts.edge_weight;
        // continuation: the hard goals (planarity, conicality) gain weight over time
        let hard = (2.0f64).powf(it as Real / 8.0).min(HARD_GAIN_MAX);
        let w_plan = opts.planarity_weight * hard;
        let w_cone = opts.conical_weight * hard;
        system.reset(opts.regulariser);
        // planarity
        for (f, face) in faces.iter().enumerate() {
            let nf_ = Vector3::new(x[nbase + 3 * f], x[nbase + 3 * f + 1], x[nbase + 3 * f + 2]);
            for k in 0..4 {
                let (i, j) = (face[k], face[(k + 1) % 4]);
                let e = pos(&x, j) - pos(&x, i);
                cols.clear();
                vals.clear();
                push3(&mut cols, &mut vals, nbase + 3 * f, &e);
                push3(&mut cols, &mut vals, 3 * j, &nf_);
                push3(&mut cols, &mut vals, 3 * i, &(-nf_));
                system.row(&cols, &vals, nf_.dot(&e), w_plan);
            }
            cols.clear();
            vals.clear();
            push3(&mut cols, &mut vals, nbase + 3 * f, &(nf_ * 2.0));
            system.row(&cols, &vals, nf_.norm_squared() - 1.0, w_plan);
        }
        // conical: angle balance w0 - w1 + w2 - w3 = 0 at interior valence-4 vertices
        for star in &topo.stars {
            let v = star.vertex;
            let nb = star.faces.map(|(f, k)| faces[f][(k + 1) % 4]);
            let pv = pos(&x, v);
            cols.clear();
            vals.clear();
            let mut gv = Vector3::zeros();
            let mut g = [Vector3::zeros(); 4];
            let mut r = 0.0;
            for s in 0..4 {
                // angle of corner s between nb[s] and nb[s-1]
                let (i, j) = (s, (s + 3) % 4);
                let a = pos(&x, nb[i]) - pv;
                let b = pos(&x, nb[j]) - pv;
                let sign = if s % 2 == 0 { 1.0 } else { -1.0 };
                r += sign * a.angle(&b);
                let (la, lb) = (a.norm(), b.norm());
                let (ah, bh) = (a / la, b / lb);
                let ga = -(bh - ah * ah.dot(&bh))
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::zeros)
                    / la;
                let gb = -(ah - bh * bh.dot(&ah))
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::zeros)
                    / lb;
                g[i] += ga * sign;
                g[j] += gb * sign;
                gv -= (ga + gb) * sign;
            }
            push3(&mut cols, &mut vals, 3 * v, &gv);
            for s in 0..4 {
                push3(&mut cols, &mut vals, 3 * nb[s], &g[s]);
            }
            system.row(&cols, &vals, r, w_cone);
        }
        // closeness and boundary
        let mut far = 0.0f64;
        for v in 0..nv {
            let p = to_world(&x, v);
            let cp = index.closest(&p);
            let d = (p - cp.point) / scale;
            far = far.max(d.norm());
            cols.clear();
            vals.clear();
            push3(&mut cols, &mut vals, 3 * v, &cp.normal);
            system.row(&cols, &vals, cp.normal.dot(&d), opts.closeness_weight);
            if topo.boundary[v] {
                let b = index.closest_on_boundary(&p);
                let d = (p - b.point) / scale;
                far = far.max(d.norm());
                let u1 = b
                    .tangent
                    .cross(&cp.normal)
                    .try_normalize(1e-12)
                    .unwrap_or_else(|| b.tangent.cross(&Vector3::z()).normalize());
                let u2 = b.tangent.cross(&u1);
                for u in [u1, u2] {
                    cols.clear();
                    vals.clear();
                    push3(&mut cols, &mut vals, 3 * v, &u);
                    system.row(&cols, &vals, u.dot(&d), opts.boundary_weight);
                }
                // grid corners (one face) stay where the boundary turns most: pinned
                if topo.corner[v] {
                    let d = (p - initial_vertices[v]) / scale;
                    for k in 0..3 {
                        system.row(&[3 * v + k], &[1.0], d[k], 5.0 * opts.boundary_weight);
                    }
                }
            }
        }
        // fairness
        for t in &topo.triples {
            // boundary polylines keep their full fairness weight: it spaces them evenly
            let w_fair = if topo.boundary[t[1]] {
                opts.fairness_weight
            } else {
                w_fair
            };
            let r = pos(&x, t[0]) - pos(&x, t[1]) * 2.0 + pos(&x, t[2]);
            for k in 0..3 {
                system.row(
                    &[3 * t[0] + k, 3 * t[1] + k, 3 * t[2] + k],
                    &[1.0, -2.0, 1.0],
                    r[k],
                    w_fair,
                );
            }
        }
        // equal edges and equal diagonals within each face
        for face in &faces {
            let p = face.map(|v| pos(&x, v));
            for k in 0..3 {
                let (a, b, c) = (face[k], face[k + 1], face[(k + 2) % 4]);
                let e1 = p[k + 1] - p[k];
                let e2 = p[(k + 2) % 4] - p[k + 1];
                cols.clear();
                vals.clear();
                push3(&mut cols, &mut vals, 3 * a, &(-e1 * 2.0));
                push3(&mut cols, &mut vals, 3 * b, &((e1 + e2) * 2.0));
                push3(&mut cols, &mut vals, 3 * c, &(-e2 * 2.0));
                system.row(&cols, &vals, e1.norm_squared() - e2.norm_squared(), w_edge);
            }
            let d0 = p[2] - p[0];
            let d1 = p[3] - p[1];
            cols.clear();
            vals.clear();
            push3(&mut cols, &mut vals, 3 * face[2], &(d0 * 2.0));
            push3(&mut cols, &mut vals, 3 * face[0], &(-d0 * 2.0));
            push3(&mut cols, &mut vals, 3 * face[3], &(-d1 * 2.0));
            push3(&mut cols, &mut vals, 3 * face[1], &(d1 * 2.0));
            system.row(&cols, &vals, d0.norm_squared() - d1.norm_squared(), w_edge);
        }
        if system.first {
            solver = Some(SpdSolver::new(n, &system.pattern)?);
            system.first = false;
            system.pattern = Vec::new();
        }
        let Some(solver) = solver.as_mut() else {
            return Err(SurfaceError::Internal("solver missing".into()));
        };
        let mut dx = system.rhs.clone();
        if !solver.solve(&system.values, &mut dx)? {
            return Err(SurfaceError::Internal(format!(
                "normal equations not positive definite at iteration {it}"
            )));
        }
        let max_move = (0..nv).map(|v| pos(&dx, v).norm()).fold(0.0, Real::max);
        let mut step = if max_move > opts.max_step {
            opts.max_step / max_move
        } else {
            1.0
        };
        let mut accepted = None;
        for _ in 0..6 {
            let mut trial: Vec<Real> = x.iter().zip(&dx).map(|(a, d)| a + step * d).collect();
            for f in 0..nf {
                let i = nbase + 3 * f;
                let nrm = Vector3::new(trial[i], trial[i + 1], trial[i + 2]).normalize();
                trial[i..i + 3].copy_from_slice(nrm.as_slice());
            }
            match fold(&trial, &faces, &reference) {
                None => {
                    accepted = Some(trial);
                    break;
                }
                Some(why) => {
                    if step < 1e-3 {
                        return Err(SurfaceError::Folded(format!("{why} at iteration {it}; the goals conflict there (try a different unit size or weights)")));
                    }
                    accepted = None;
                    step *= 0.3;
                    if step < 1e-3 {
                        return Err(SurfaceError::Folded(format!("{why} at iteration {it}; the goals conflict there (try a different unit size or weights)")));
                    }
                }
            }
        }
        let Some(trial) = accepted else {
            return Err(SurfaceError::Folded(format!(
                "no unfolded step found at iteration {it}"
            )));
        };
        x = trial;
        progress(it, system.energy);
        // convergence on the hard goals
        let mesh = QuadMesh {
            vertices: (0..nv).map(|v| to_world(&x, v)).collect(),
            faces: faces.clone(),
        };
        let plan = (0..nf)
            .map(|f| {
                let p = mesh.face_points(f);
                let mean = (0..4).map(|k| (p[(k + 1) % 4] - p[k]).norm()).sum::<Real>() / 4.0;
                quad_diagonal_distance(&p) / mean
            })
            .fold(0.0, Real::max);
        let cone = conical_residuals(&mesh, &topo)
            .into_iter()
            .fold(0.0, Real::max)
            .to_degrees();
        if it >= 5
            && plan <= opts.planarity_tolerance
            && cone <= opts.conical_tolerance_deg
            && far <= 0.5 * opts.closeness_tolerance
            && step * max_move < 1e-3
        {
            break;
        }
    }
    let mesh = QuadMesh {
        vertices: (0..nv).map(|v| to_world(&x, v)).collect(),
        faces,
    };
    let report = measure(&mesh, &topo, index, iterations, &Goals::default());
    Ok((mesh, report))
}

/// A collapsed edge or a flipped face in the normalised positions, if any.
fn fold(x: &[Real], faces: &[[usize; 4]], reference: &[Vector3]) -> Option<String> {
    let pos = |v: usize| Vector3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
    for (f, face) in faces.iter().enumerate() {
        let p = face.map(pos);
        for k in 0..4 {
            if (p[(k + 1) % 4] - p[k]).norm() < COLLAPSE_FRACTION {
                return Some(format!(
                    "edge ({}, {}) of face {f} collapses",
                    face[k],
                    face[(k + 1) % 4]
                ));
            }
        }
        if (p[0] - p[2]).cross(&(p[1] - p[3])).dot(&reference[f]) <= 0.0 {
            return Some(format!("face {f} flips"));
        }
    }
    None
}
