//! Guided projection (Tang et al. 2014): Gauss-Newton on quadratic constraints with
//! auxiliary unit face normals, solved through the normal equations with a sparse Cholesky
//! factorisation whose symbolic part is reused every iteration. The hard goals (planarity,
//! conical vertices) gain weight while they are unmet and the mesh still follows the
//! target; barriers keep edges from collapsing and corners from folding, and a step that
//! would fold the mesh anyway is cut or, failing that, ends the run on the last unfolded
//! iterate with the place named in the report.

use sv_frame::QuadMesh;
use sv_geom::sparse::NormalEquations;
use sv_geom::{quad_diagonal_distance, Point3, Real, Vector3};

use crate::report::{measure, Goals, SecondaryReport};
use crate::target::TargetIndex;
use crate::topology::Topology;
use crate::{SecondaryOptions, SurfaceError, TargetMesh};

/// Shortest allowed edge, as a fraction of the initial mean edge.
const COLLAPSE_FRACTION: Real = 0.2;
/// Largest factor by which the planarity and conical weights grow during the run.
const HARD_GAIN_MAX: Real = 100.0;
/// Smallest factor they shrink to where the goals conflict with closeness.
const HARD_GAIN_MIN: Real = 0.1;
/// Growth of the hard-goal gain per iteration while planarity or conicality is unmet.
const HARD_GAIN_STEP: Real = 1.090_507_732_665_257_7; // 2^(1/8)
/// Stop once the hard goals hold and every vertex is within this fraction of the
/// closeness tolerance (margin for the final measurement).
const STOP_CLOSENESS: Real = 0.6;
/// Edge length (fraction of the initial mean edge) below which the edge barrier acts.
const EDGE_MIN: Real = 0.5;
/// Sine of the corner angle below which the corner barrier acts (about 20 and 160 deg).
const SINE_MIN: Real = 0.34;
/// Iterations over which the best iterate's distance from the goals must fall while some
/// goal is unmet, else the run stops (on that iterate).
const STALL_WINDOW: usize = 20;
/// Relative fall of that distance that counts.
const STALL_GAIN: Real = 0.02;
/// Weight of the barriers relative to the hard goals.
const BARRIER_WEIGHT: Real = 3.0;
/// The face-side barrier acts on sides shorter than this factor of the goal's shortest
/// side or longer than this factor of its longest (a margin for the final measurement).
const SIDE_BARRIER: (Real, Real) = (1.03, 0.98);
/// Weight of the face-side barrier.
const SIDE_WEIGHT: Real = 2.0;
/// A step that would move a vertex farther than this (fraction of the initial mean edge)
/// is undoing the layout (the sheared faces an O-grid starts with round its irregular
/// vertices ask for moves of 6-13 mean edges), not fitting it: while such steps are capped
/// and taken whole and the merit falls, the cap (`max_step`) grows by REACH_GROWTH per
/// iteration, up to REACH_MAX times `max_step`; otherwise it is `max_step`.
const FAR_MOVE: Real = 0.5;
const REACH_GROWTH: Real = 1.5;
const REACH_MAX: Real = 10.0;

/// The target's normal at the point of the target closest to each face's centre: which
/// way each face of `mesh` must face.
fn target_normals(index: &TargetIndex<'_>, mesh: &QuadMesh) -> Vec<Vector3> {
    (0..mesh.faces.len())
        .map(|f| {
            let q = mesh.face_points(f);
            let centre = Point3::from(q.iter().map(|p| p.coords).sum::<Vector3>() / 4.0);
            index.closest(&centre).normal
        })
        .collect()
}

/// Faces of `mesh` whose normal (the cross product of its diagonals) points away from
/// `reference` ([`target_normals`]): a mesh that starts with one cannot be optimised (the
/// optimiser keeps every face unfolded).
fn flipped_against(mesh: &QuadMesh, reference: &[Vector3]) -> Vec<usize> {
    (0..mesh.faces.len())
        .filter(|&f| {
            let q = mesh.face_points(f);
            (q[0] - q[2]).cross(&(q[1] - q[3])).dot(&reference[f]) <= 0.0
        })
        .collect()
}

/// How many of `mesh`'s faces `flipped` names and where the first one is, for a message:
/// `3 of 212 faces flipped, the first centred at (1200, -350, 640) mm`.
pub(crate) fn flipped_text(mesh: &QuadMesh, flipped: &[usize]) -> String {
    let at = flipped.first().map_or(String::new(), |&f| {
        let q = mesh.face_points(f);
        let c = q.iter().map(|p| p.coords).sum::<Vector3>() / 4.0;
        format!(
            ", the first centred at ({:.0}, {:.0}, {:.0}) mm",
            c.x, c.y, c.z
        )
    });
    format!(
        "{} of {} faces flipped{at}",
        flipped.len(),
        mesh.faces.len()
    )
}

/// What keeps the optimiser from moving `mesh` at all, for a message: faces flipped
/// against the target ([`flipped_text`]), else edges shorter than [`COLLAPSE_FRACTION`] of
/// the mean edge (every step it tries would collapse them further or leave them so: the
/// optimiser returns the mesh untouched, and the primary solve then fails on its slivers).
pub(crate) fn start_fault(index: &TargetIndex<'_>, mesh: &QuadMesh) -> Option<String> {
    let flipped = flipped_against(mesh, &target_normals(index, mesh));
    if !flipped.is_empty() {
        return Some(flipped_text(mesh, &flipped));
    }
    // every edge once, measured against the optimiser's own scale
    let mut edges = std::collections::BTreeSet::new();
    for f in &mesh.faces {
        for k in 0..4 {
            let (a, b) = (f[k], f[(k + 1) % 4]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    let mean = mesh.mean_edge();
    let short: Vec<(Real, Point3)> = edges
        .iter()
        .map(|&(a, b)| {
            let (p, q) = (mesh.vertices[a], mesh.vertices[b]);
            ((q - p).norm(), Point3::from((p.coords + q.coords) / 2.0))
        })
        .filter(|e| e.0 < COLLAPSE_FRACTION * mean)
        .collect();
    let (length, at) = short.iter().min_by(|a, b| a.0.total_cmp(&b.0))?;
    Some(format!(
        "{} of {} edges shorter than {COLLAPSE_FRACTION} of the mean edge ({mean:.0} mm), the \
         shortest {length:.0} mm at ({:.0}, {:.0}, {:.0}) mm",
        short.len(),
        edges.len(),
        at.x,
        at.y,
        at.z
    ))
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
    optimise_indexed(&index, initial, opts, Pins::Corners, progress)
}

/// Which vertices stay where they start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pins {
    /// Boundary vertices with other than two faces (the corners of the layout).
    Corners,
    /// Those and the interior vertices with other than four faces: a designer's layout
    /// puts its irregular vertices where they are wanted.
    CornersAndIrregular,
}

pub(crate) fn optimise_indexed(
    index: &TargetIndex<'_>,
    initial: QuadMesh,
    opts: &SecondaryOptions,
    pins: Pins,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(QuadMesh, SecondaryReport), SurfaceError> {
    let topo = Topology::new(&initial)?;
    let mut pinned = topo.corner.clone();
    if pins == Pins::CornersAndIrregular {
        for s in topo.stars.iter().filter(|s| s.faces.len() != 4) {
            pinned[s.vertex] = true;
        }
    }
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
    // vertices with five or more faces carry a cone of normals: axis (3) and cosine (1)
    let cones: Vec<&crate::topology::Star> =
        topo.stars.iter().filter(|s| s.faces.len() >= 5).collect();
    let cbase = nbase + 3 * nf;
    let n = cbase + 4 * cones.len();
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
    let reference = target_normals(index, &initial);
    let flipped = flipped_against(&initial, &reference);
    if let Some(&f) = flipped.first() {
        return Err(SurfaceError::Folded(format!(
            "initial face {f} is flipped against the target ({})",
            flipped_text(&initial, &flipped)
        )));
    }
    for f in 0..nf {
        let g = face_normal(&x, f);
        let nrm = g.normalize();
        x[nbase + 3 * f..nbase + 3 * f + 3].copy_from_slice(nrm.as_slice());
    }
    for (c, star) in cones.iter().enumerate() {
        let normals: Vec<Vector3> = star
            .faces
            .iter()
            .map(|&(f, _)| Vector3::from_column_slice(&x[nbase + 3 * f..nbase + 3 * f + 3]))
            .collect();
        let (axis, cosine) = sv_frame::normal_cone(&normals);
        x[cbase + 4 * c..cbase + 4 * c + 3].copy_from_slice(axis.as_slice());
        x[cbase + 4 * c + 3] = cosine;
    }

    let mut system = NormalEquations::new(n);
    let mut iterations = 0;
    let mut stopped: Option<String> = None;
    let mut hints: Vec<Option<usize>> = vec![None; nv];
    let (mut cols, mut vals) = (Vec::with_capacity(16), Vec::with_capacity(16));
    let mut dx = vec![0.0; n];
    let mut hard: Real = 1.0;
    let goals = Goals::default();
    // planarity max and conical max (degrees) of the iterate
    let hard_of = |x: &[Real]| {
        let mesh = QuadMesh {
            vertices: (0..nv).map(|v| to_world(x, v)).collect(),
            faces: faces.clone(),
        };
        let plan = (0..nf)
            .map(|f| {
                let p = mesh.face_points(f);
                let mean = (0..4).map(|k| (p[(k + 1) % 4] - p[k]).norm()).sum::<Real>() / 4.0;
                quad_diagonal_distance(&p) / mean
            })
            .fold(0.0, Real::max);
        let cone = mesh
            .conical_residuals()
            .into_iter()
            .map(|(_, r)| r)
            .fold(0.0, Real::max)
            .to_degrees();
        (plan, cone)
    };
    // fraction of nearly square faces and the shortest and longest side / unit
    let shape_of = |x: &[Real]| {
        let (mut good, mut short, mut long, mut sum) = (0usize, Real::INFINITY, 0.0 as Real, 0.0);
        for f in &faces {
            let p = f.map(|v| pos(x, v));
            if edge_ratio(&p) <= crate::EDGE_RATIO_LIMIT {
                good += 1;
            }
            for k in 0..4 {
                let e = (p[(k + 1) % 4] - p[k]).norm();
                sum += e;
                short = short.min(e * scale / opts.unit_size);
                long = long.max(e * scale / opts.unit_size);
            }
        }
        let mean = sum / (4 * nf) as Real;
        (good as Real / nf as Real, short, long, mean)
    };
    // how far an iterate is from the goals: (goals missed, summed relative excess)
    let merit = |(plan, cone): (Real, Real), far: Real, x: &[Real]| {
        let (square, short, long, mean) = shape_of(x);
        let ratios = [
            plan / goals.planarity,
            cone / goals.conical_deg,
            // `far` is in initial mean edges, the goal in the iterate's
            far / mean.max(1e-9) / goals.closeness,
            goals.edge_ratio_fraction / square.max(1e-9),
            (goals.side_range.0 / short.max(1e-9)).max(long / goals.side_range.1),
        ];
        // logarithmic excess, so that no goal's scale dominates; leaving the target
        // (which also uncovers it) counts three times
        let weight = [1.0, 1.0, 3.0, 1.0, 1.0];
        ratios
            .iter()
            .zip(weight)
            .map(|(&r, w)| w * r.max(1.0).ln())
            .sum::<Real>()
    };
    let mut current_hard = hard_of(&x);
    // the best iterate so far by `merit`: where the goals conflict the run ends on it
    let mut best: Option<(Real, Vec<Real>)> = None;
    // the iteration at which the merit last fell below (1 - STALL_GAIN) of its value at
    // the previous such iteration
    let mut improved_at = 0usize;
    // ... and its value then
    let mut mark = Real::INFINITY;
    // the face-side barrier's range, in the normalised lengths; it keeps the sides of a
    // mesh that starts with all of them in the goal's range in it (where some start
    // outside, the rows cannot grow or end there and pushing them in breaks the rest)
    let side_lo = SIDE_BARRIER.0 * goals.side_range.0 * opts.unit_size / scale;
    let side_hi = SIDE_BARRIER.1 * goals.side_range.1 * opts.unit_size / scale;
    let sides_in = faces.iter().all(|f| {
        (0..4).all(|k| {
            let e = (pos(&x, f[(k + 1) % 4]) - pos(&x, f[k])).norm() * scale / opts.unit_size;
            (goals.side_range.0..=goals.side_range.1).contains(&e)
        })
    });
    let w_side = if sides_in { SIDE_WEIGHT } else { 0.0 };
    // the cap on a vertex's move in a step (see FAR_MOVE) and the merit of the last iterate
    let mut reach = opts.max_step;
    let mut last_merit = Real::INFINITY;
    for it in 0..opts.max_iterations {
        iterations = it + 1;
        let decay = (0.5f64).powf(it as Real / 10.0).max(0.1);
        let w_fair = opts.fairness_weight * decay;
        let w_edge = opts.edge_weight;
        // continuation: the hard goals (planarity, conicality) gain weight while unmet
        let w_plan = opts.planarity_weight * hard;
        let w_cone = opts.conical_weight * hard;
        let w_bar = BARRIER_WEIGHT * hard;
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
        for star in topo.stars.iter().filter(|s| s.faces.len() == 4) {
            let v = star.vertex;
            let nb: Vec<usize> = star
                .faces
                .iter()
                .map(|&(f, k)| faces[f][(k + 1) % 4])
                .collect();
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
        // conical at five or more faces: the face normals on one circle of the Gauss
        // sphere, n_f . a = c with |a| = 1 (valence 3 is always conical)
        for (c, star) in cones.iter().enumerate() {
            let ia = cbase + 4 * c;
            let axis = pos(&x[ia..], 0);
            let cosine = x[ia + 3];
            for &(f, _) in &star.faces {
                let nf_ = pos(&x[nbase..], f);
                cols.clear();
                vals.clear();
                push3(&mut cols, &mut vals, nbase + 3 * f, &axis);
                push3(&mut cols, &mut vals, ia, &nf_);
                cols.push(ia + 3);
                vals.push(-1.0);
                system.row(&cols, &vals, nf_.dot(&axis) - cosine, w_cone);
            }
            cols.clear();
            vals.clear();
            push3(&mut cols, &mut vals, ia, &(axis * 2.0));
            system.row(&cols, &vals, axis.norm_squared() - 1.0, w_cone);
        }
        // closeness and boundary
        let mut far = 0.0f64;
        for v in 0..nv {
            let p = to_world(&x, v);
            let cp = index.closest_near(&p, hints[v]);
            hints[v] = Some(cp.triangle);
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
            }
            // layout corners stay where the boundary turns most, a designer's irregular
            // vertices where they were put: pinned
            if pinned[v] {
                let d = (p - initial_vertices[v]) / scale;
                for k in 0..3 {
                    system.row(&[3 * v + k], &[1.0], d[k], 5.0 * opts.boundary_weight);
                }
            }
        }
        let m = merit(current_hard, far, &x);
        if m > last_merit {
            reach = opts.max_step;
        }
        last_merit = m;
        if m < (1.0 - STALL_GAIN) * mark {
            improved_at = it;
            mark = m;
        }
        if best.as_ref().is_none_or(|b| m <= b.0) {
            best = Some((m, x.clone()));
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
        // barriers, active only near a fold: short edges and corner angles near 0 or
        // 180 degrees (sine of the corner angle about the face normal below SINE_MIN)
        for (f, face) in faces.iter().enumerate() {
            let p = face.map(|v| pos(&x, v));
            let nrm = Vector3::new(x[nbase + 3 * f], x[nbase + 3 * f + 1], x[nbase + 3 * f + 2]);
            for k in 0..4 {
                let (i, j) = (face[k], face[(k + 1) % 4]);
                let e = p[(k + 1) % 4] - p[k];
                let len = e.norm();
                let (r, w) = if len < EDGE_MIN && len > 0.0 {
                    (EDGE_MIN - len, w_bar)
                } else {
                    (0.0, 0.0)
                };
                let u = if len > 0.0 { e / len } else { Vector3::zeros() };
                cols.clear();
                vals.clear();
                push3(&mut cols, &mut vals, 3 * j, &(-u));
                push3(&mut cols, &mut vals, 3 * i, &u);
                system.row(&cols, &vals, r, w);
                // the face-side goal: sides within 0.7-1.4 of the requested unit
                let (r, w) = if len < side_lo {
                    (side_lo - len, w_side)
                } else if len > side_hi {
                    (side_hi - len, w_side)
                } else {
                    (0.0, 0.0)
                };
                system.row(&cols, &vals, r, w);
                // corner k between the edges to k+1 and k-1
                let (prev, next) = (face[(k + 3) % 4], face[(k + 1) % 4]);
                let a = p[(k + 1) % 4] - p[k];
                let b = p[(k + 3) % 4] - p[k];
                let (la, lb) = (a.norm(), b.norm());
                let s = if la > 0.0 && lb > 0.0 {
                    a.cross(&b).dot(&nrm) / (la * lb)
                } else {
                    0.0
                };
                let (r, w) = if s < SINE_MIN && la > 0.0 && lb > 0.0 {
                    (SINE_MIN - s, w_bar)
                } else {
                    (0.0, 0.0)
                };
                let (ga, gb) = if w > 0.0 {
                    (
                        -(b.cross(&nrm) / (la * lb) - a * (s / (la * la))),
                        -(nrm.cross(&a) / (la * lb) - b * (s / (lb * lb))),
                    )
                } else {
                    (Vector3::zeros(), Vector3::zeros())
                };
                cols.clear();
                vals.clear();
                push3(&mut cols, &mut vals, 3 * next, &ga);
                push3(&mut cols, &mut vals, 3 * prev, &gb);
                push3(&mut cols, &mut vals, 3 * face[k], &(-(ga + gb)));
                system.row(&cols, &vals, r, w);
            }
        }
        if !system.solve(&mut dx)? {
            return Err(SurfaceError::Internal(format!(
                "normal equations not positive definite at iteration {it}"
            )));
        }
        let max_move = (0..nv).map(|v| pos(&dx, v).norm()).fold(0.0, Real::max);
        let capped = max_move > reach;
        let whole = if capped { reach / max_move } else { 1.0 };
        let mut step = whole;
        let mut accepted = None;
        let mut why = String::new();
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
                Some(w) => {
                    why = w;
                    step *= 0.3;
                }
            }
        }
        reach = if capped && max_move > FAR_MOVE && accepted.is_some() && step == whole {
            (reach * REACH_GROWTH).min(REACH_MAX * opts.max_step)
        } else {
            opts.max_step
        };
        let Some(trial) = accepted else {
            // the goals conflict here: keep the last unfolded iterate and say where
            stopped = Some(format!(
                "optimisation stopped at iteration {it}: any further step folds the mesh ({why}); the goals conflict there"
            ));
            break;
        };
        x = trial;
        progress(it, system.energy);
        // convergence on the hard goals
        let (plan, cone) = hard_of(&x);
        current_hard = (plan, cone);
        let hard_met = plan <= opts.planarity_tolerance && cone <= opts.conical_tolerance_deg;
        // the hard gain grows while the hard goals are unmet and the mesh still follows
        // the target; where they cannot be met without leaving it (the goals conflict)
        // it backs off, so the result stays on the target and `unmet` names the faces
        if far > opts.closeness_tolerance {
            hard = (hard / HARD_GAIN_STEP).max(HARD_GAIN_MIN);
        } else if !hard_met {
            hard = (hard * HARD_GAIN_STEP).min(HARD_GAIN_MAX);
        }
        let square = faces
            .iter()
            .filter(|f| edge_ratio(&f.map(|v| pos(&x, v))) <= crate::EDGE_RATIO_LIMIT)
            .count() as Real
            / nf as Real;
        let soft_met =
            far <= STOP_CLOSENESS * opts.closeness_tolerance && square >= goals.edge_ratio_fraction;
        // stalled: tiny steps while the hard weights no longer grow
        let stalled = step * max_move < 1e-3
            && max_move <= opts.max_step
            && (hard_met || hard >= HARD_GAIN_MAX || hard <= HARD_GAIN_MIN);
        // no longer falling: the best iterate's distance from the goals has not fallen
        // by STALL_GAIN for STALL_WINDOW iterations (the goals conflict; also where the
        // hard goals hold and the iterates cycle short of the others)
        let flat = best.as_ref().is_some_and(|b| b.0 > 0.0) && it >= improved_at + STALL_WINDOW;
        if it >= 5 && ((hard_met && soft_met) || stalled || flat) {
            break;
        }
    }
    // the last iterate, or an earlier one nearer the goals (where they conflict the
    // residuals wander)
    if let Some((m, bx)) = best {
        let mut far = 0.0f64;
        for v in 0..nv {
            let p = to_world(&x, v);
            let cp = index.closest_near(&p, hints[v]);
            far = far.max(((p - cp.point) / scale).norm());
            if topo.boundary[v] {
                let b = index.closest_on_boundary(&p);
                far = far.max(((p - b.point) / scale).norm());
            }
        }
        if merit(current_hard, far, &x) > m {
            x = bx;
        }
    }
    let mesh = QuadMesh {
        vertices: (0..nv).map(|v| to_world(&x, v)).collect(),
        faces,
    };
    let mut report = measure(
        &mesh,
        &topo,
        index,
        iterations,
        opts.unit_size,
        &Goals::default(),
    );
    if let Some(s) = stopped {
        report.unmet.push(s);
    }
    Ok((mesh, report))
}

/// Longest over shortest edge of a quad.
fn edge_ratio(p: &[Vector3; 4]) -> Real {
    let e = [0, 1, 2, 3].map(|k| (p[(k + 1) % 4] - p[k]).norm());
    let max = e.iter().copied().fold(0.0, Real::max);
    let min = e.iter().copied().fold(Real::INFINITY, Real::min);
    if min > 0.0 {
        max / min
    } else {
        Real::INFINITY
    }
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
