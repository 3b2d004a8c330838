//! The primary-surface solve.
//!
//! Unknowns: `(theta_f, phi_f)` per unit. The paper's objective is the sum over links of
//! the closest distance between the facing sides of the two expanded primary tiles.
//! Each gap is the length of the residual vector `p(s*) - q(t*)` between the closest
//! points, whose derivative with `s*, t*` held fixed is exact where the closest points
//! are unique (envelope theorem), so the solve is Levenberg-Marquardt on those residuals
//! (least squares), followed by iteratively reweighted rounds (weights `1/gap`) that
//! move the optimum toward the paper's sum of gaps. Each iteration assembles the sparse
//! normal equations (2x2 blocks, one per unit and per link) and factors them with faer's
//! sparse Cholesky, whose symbolic analysis is done once.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Par};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sv_geom::{segment_closest, Point3, Real, Vector3};
use sv_unit::{AxisCase, CutWidths, Deployment, Side};

use crate::file::{
    FrameParams, JointLimits, JointRecord, LapGoal, LegPins, LinkRecord, MeshData, SolveSummary,
    UnitRecord, FRAME_FORMAT, FRAME_VERSION,
};
use crate::{
    hubs_from_mesh, FrameError, FrameFile, FrameUnits, Hub, Link, MeshChecks, QuadMesh, UnitPose,
};

/// Iterations over which [`SolveOptions::tolerance`] measures progress.
pub const STALL_WINDOW: usize = 5;

/// Default spin angle: 45 degrees, for a square grid.
pub const DEFAULT_SPIN_ANGLE: Real = std::f64::consts::FRAC_PI_4;

/// Which side of each hub its primary tile goes to (model.md, "Which side").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SidePolicy {
    /// Per unit, hubs on the concave side of the mesh (shorter distances there); flat
    /// regions keep the mesh orientation.
    #[default]
    Auto,
    /// Every hub on the side its face normal points to (the mesh orientation).
    Normal,
    /// Every hub on the side opposite to its face normal.
    Opposite,
}

/// Powers of the p-norm continuation of [`GapObjective::Max`]: `||gaps||_p` tends to the
/// largest gap as p grows (`max <= ||g||_p <= L^(1/p) max` for `L` links); each power starts
/// where the previous one ended.
const NORM_POWERS: [Real; 5] = [4.0, 8.0, 16.0, 32.0, 64.0];

/// Levenberg-Marquardt iterations per power of [`NORM_POWERS`].
const ITERATIONS_PER_POWER: usize = 10;

/// What the primary solve minimises (after a least-squares start).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum GapObjective {
    /// The largest link gap (min-max), by a continuation of smooth p-norms.
    #[default]
    Max,
    /// The sum of link gaps (the paper's objective, and the SLSQP baseline's).
    Sum,
}

/// Options of [`solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct SolveOptions {
    /// Spin angle alpha (rad), in (0, pi/2).
    pub spin_angle: Real,
    /// Expansion factor e >= 1 of the primary tiles, about their centroids.
    pub expansion: Real,
    /// Side choice.
    pub side: SidePolicy,
    /// What to minimise.
    pub objective: GapObjective,
    /// Axis case of every unit, or `None` to choose per unit: the two cases are the same
    /// motion at `phi = 0` (the start), so each unit takes the case whose tilt lowers the
    /// gaps fastest there. Default: the paper's case (`t . r1 = 0`) for every unit, which
    /// reached lower gap sums than the per-unit choice on sphere caps.
    pub axis_case: Option<AxisCase>,
    /// Largest number of Levenberg-Marquardt iterations.
    pub max_iterations: usize,
    /// Stop a phase when the cost fell by less than this fraction over the last
    /// [`STALL_WINDOW`] iterations. 1e-3 keeps 99.9% of what more iterations would gain
    /// on the meshes in the benchmarks at a third of the time; use 0 to run all iterations.
    pub tolerance: Real,
    /// Planarity tolerance for the input mesh (diagonal distance / mean edge).
    pub planarity_tolerance: Real,
    /// Where the cut goes in every unit: the units deploy as cut, on four legs pinned at
    /// their necks (docs/geometry.md, "The unit as cut"). `None`: the paper's zero-width
    /// unit (closed form, legs hinged at the tile corners).
    pub cut: Option<CutWidths>,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            spin_angle: DEFAULT_SPIN_ANGLE,
            expansion: 1.0,
            side: SidePolicy::Auto,
            objective: GapObjective::Max,
            axis_case: Some(AxisCase::OrthogonalToR1),
            max_iterations: 60,
            tolerance: 1e-3,
            planarity_tolerance: crate::MeshChecks::DEFAULT_PLANARITY_TOLERANCE,
            cut: None,
        }
    }
}

/// Progress of a running solve, for a progress bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Iteration number.
    pub iteration: usize,
    /// Largest iteration number.
    pub max_iterations: usize,
    /// Current sum of gaps (mm).
    pub gap_sum: Real,
    /// Current largest gap (mm).
    pub gap_max: Real,
}

/// What a solve reached.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    /// Sum of gaps at the start (theta = alpha, phi = 0).
    pub gap_sum_start: Real,
    /// Largest gap at the start.
    pub gap_max_start: Real,
    /// Largest gap after the least-squares phase (the start of the min-max phase).
    pub gap_max_least_squares: Real,
    /// Sum of gaps at the end (the paper's objective).
    pub gap_sum: Real,
    /// Largest gap at the end.
    pub gap_max: Real,
    /// Iterations used.
    pub iterations: usize,
    /// Sparse Cholesky factorisations (one per iteration plus one per rejected step).
    pub factorizations: usize,
}

/// Gaps and overlaps of a set of deployments.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Per link: closest distance of the facing expanded primary sides (mm).
    pub gaps: Vec<Real>,
    /// Per link: hub overlap (mm).
    pub overlaps: Vec<Real>,
}

/// The joints of a frame whose joints were closed.
#[derive(Clone, Debug, PartialEq)]
pub struct Joints {
    /// Per link.
    pub records: Vec<JointRecord>,
    /// Sheet thickness they were measured with (mm).
    pub thickness: Real,
    /// What they were to reach.
    pub limits: JointLimits,
    /// The one hub lap they were to hold, if any.
    pub hub_lap: Option<LapGoal>,
    /// Whether the plates of every hub lap were pulled together to touch.
    pub laps_touch: bool,
}

/// A solved frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Solved {
    /// Hubs, one per face.
    pub hubs: Vec<Hub>,
    /// Interior edges.
    pub links: Vec<Link>,
    /// One deployment per unit: the chart point of its pose (for a frame whose joints
    /// were closed, the chart coordinates of the pose the joint solve reached).
    pub deployments: Vec<Deployment>,
    /// One pose per unit: where its hub sits on its primary plate.
    pub poses: Vec<UnitPose>,
    /// One spin angle per unit (rad): the options' spin angle, or where the joint solve
    /// turned the hub in its face.
    pub spins: Vec<Real>,
    /// One tile scale per unit, `[along the hub's x, along its y]`: 1 unless the joint
    /// solve stretched the tile's half-diagonals away from the face's best-fit rhombus.
    pub scales: Vec<[Real; 2]>,
    /// One hub lift per unit (mm): how far the joint solve moved the hub off its face along
    /// the face's normal, so that lapping hubs lie one on the other; 0 before.
    pub lifts: Vec<Real>,
    /// How the primary plates meet at every link, when the joints were closed
    /// ([`crate::close_joints`]).
    pub joints: Option<Joints>,
    /// Gaps and overlaps at the end.
    pub evaluation: Evaluation,
    /// Figures.
    pub report: SolveReport,
    /// Options used.
    pub options: SolveOptions,
    /// The units (as cut or zero-width).
    pub units: FrameUnits,
}

/// Bounds kept by the solver: away from the flat state, where `P ~ sqrt(theta)` has
/// unbounded derivatives, and from theta = 90 degrees, where a square unit's translation
/// is not unique; `phi` as in the paper's SLSQP box.
const THETA_BOUNDS: (Real, Real) = (0.05, 1.5);
const PHI_BOUNDS: (Real, Real) = (-1.2, 1.2);

/// Largest theta the solver lets a unit reach: [`THETA_BOUNDS`], and short of the first
/// degenerate configuration `theta = 2 atan(min(a, b) / max(a, b))` of its rhombus, where
/// the deployment direction vanishes and the side flips (docs/geometry.md, 1.6).
fn theta_max(hub: &Hub) -> Real {
    let (a, b) = (hub.rhombus.a(), hub.rhombus.b());
    let k = a.min(b) / a.max(b);
    THETA_BOUNDS
        .1
        .min(2.0 * k.atan() - 0.02)
        .max(THETA_BOUNDS.0)
}

/// Solve the primary surface of a quad mesh of hubs. The mesh is validated first.
pub fn solve(
    mesh: &QuadMesh,
    options: &SolveOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Solved, FrameError> {
    check_options(options)?;
    mesh.validate(&MeshChecks {
        planarity_tolerance: options.planarity_tolerance,
    })?;
    let hubs = hubs_from_mesh(mesh, options.spin_angle)?;
    let links = mesh.links();
    let sides = choose_sides(&hubs, &links, options.side);
    let n = hubs.len();
    let mut deployments: Vec<Deployment> = (0..n)
        .map(|f| Deployment {
            theta: options
                .spin_angle
                .clamp(THETA_BOUNDS.0, theta_max(&hubs[f])),
            phi: 0.0,
            case: options.axis_case.unwrap_or_default(),
            side: sides[f],
        })
        .collect();
    let units = FrameUnits::new(&hubs, options.expansion, options.cut.as_ref())?;
    let problem = Problem {
        hubs: &hubs,
        links: &links,
        units: &units,
    };
    if options.axis_case.is_none() {
        choose_cases(&problem, &mut deployments)?;
    }
    let start = problem.gaps(&deployments)?;
    let gap_sum_start: Real = start.iter().sum();
    let gap_max_start = start.iter().copied().fold(0.0, Real::max);
    let mut lm = Lm::new(&problem)?;
    let total = options.max_iterations;
    let scale = hubs.iter().map(|h| h.rhombus.side()).sum::<Real>() / n as Real;
    let mut report_progress = |iteration: usize, gaps: &[Real]| {
        progress(Progress {
            iteration,
            max_iterations: total,
            gap_sum: gaps.iter().sum(),
            gap_max: gaps.iter().copied().fold(0.0, Real::max),
        })
    };
    // least squares first, to get into the basin
    let warm = (total / 4).max(1).min(total);
    let mut iterations = lm.run(
        &mut deployments,
        Objective::LeastSquares,
        warm,
        options.tolerance.max(1e-2),
        &mut |it, _, gaps| report_progress(it, gaps),
    )?;
    let after_ls = problem.gaps(&deployments)?;
    let gap_max_least_squares = after_ls.iter().copied().fold(0.0, Real::max);
    match options.objective {
        GapObjective::Sum => {
            iterations += lm.run(
                &mut deployments,
                Objective::SumOfGaps {
                    floor: 1e-4 * scale,
                },
                total - iterations,
                options.tolerance,
                &mut |it, _, gaps| report_progress(iterations + it, gaps),
            )?;
        }
        GapObjective::Max => {
            // continuation in p toward the largest gap; keep the best point seen
            let mut best = (gap_max_least_squares, deployments.clone());
            for p in NORM_POWERS {
                let now = problem.gaps(&deployments)?;
                let s = now.iter().copied().fold(0.0, Real::max);
                let budget = ITERATIONS_PER_POWER.min(total.saturating_sub(iterations));
                if budget == 0 || s <= 1e-9 * scale {
                    break;
                }
                let base = iterations;
                iterations += lm.run(
                    &mut deployments,
                    Objective::Norm {
                        p,
                        scale: s,
                        quad: 1.0 / links.len() as Real,
                    },
                    budget,
                    options.tolerance,
                    &mut |it, deps, gaps| {
                        let m = gaps.iter().copied().fold(0.0, Real::max);
                        if m < best.0 {
                            best = (m, deps.to_vec());
                        }
                        report_progress(base + it, gaps)
                    },
                )?;
            }
            deployments = best.1;
        }
    }
    let poses = problem.poses(&deployments)?;
    let evaluation = evaluate(&hubs, &links, &poses, &units)?;
    let report = SolveReport {
        gap_sum_start,
        gap_max_start,
        gap_max_least_squares,
        gap_sum: evaluation.gaps.iter().sum(),
        gap_max: evaluation.gaps.iter().copied().fold(0.0, Real::max),
        iterations,
        factorizations: lm.factorizations,
    };
    progress(Progress {
        iteration: total,
        max_iterations: total,
        gap_sum: report.gap_sum,
        gap_max: report.gap_max,
    });
    Ok(Solved {
        hubs,
        links,
        deployments,
        poses,
        spins: vec![options.spin_angle; n],
        scales: vec![[1.0, 1.0]; n],
        lifts: vec![0.0; n],
        joints: None,
        evaluation,
        report,
        options: options.clone(),
        units,
    })
}

fn check_options(o: &SolveOptions) -> Result<(), FrameError> {
    let bad = |name, value, why| Err(FrameError::Parameter { name, value, why });
    let half_pi = std::f64::consts::FRAC_PI_2;
    if !(o.spin_angle.is_finite() && o.spin_angle > 0.0 && o.spin_angle < half_pi) {
        return bad(
            "spin_angle",
            o.spin_angle.to_degrees(),
            "must be in (0, 90) degrees",
        );
    }
    if !(o.expansion.is_finite() && o.expansion >= 1.0) {
        return bad("expansion", o.expansion, "must be a finite number >= 1");
    }
    if !(o.planarity_tolerance.is_finite() && o.planarity_tolerance > 0.0) {
        return bad(
            "planarity_tolerance",
            o.planarity_tolerance,
            "must be a finite number > 0",
        );
    }
    if !(o.tolerance.is_finite() && o.tolerance >= 0.0) {
        return bad("tolerance", o.tolerance, "must be a finite number >= 0");
    }
    Ok(())
}

/// Per unit: hubs on the concave side (model.md, "Which side"). The normal curvature of
/// the hub centres along both mesh directions tells whether a unit sits in a dome or a
/// bowl (both of one sign: the concave side is clear) or in a saddle (no preferred side).
/// Units in clearly dome- or bowl-like regions (smoothed) take their concave side; the
/// rest take the side of the whole surface (the mesh orientation where that is flat),
/// so that sides change only between regions, never in a checkerboard.
fn choose_sides(hubs: &[Hub], links: &[Link], policy: SidePolicy) -> Vec<Side> {
    match policy {
        SidePolicy::Normal => vec![Side::HubPositive; hubs.len()],
        SidePolicy::Opposite => vec![Side::HubNegative; hubs.len()],
        SidePolicy::Auto => {
            let n = hubs.len();
            // neighbour across each side k of each unit
            let mut across = vec![[None::<usize>; 4]; n];
            let mut neighbours = vec![Vec::new(); n];
            for l in links {
                let [f, g] = l.faces;
                across[f][l.slots[0]] = Some(g);
                across[g][l.slots[1]] = Some(f);
                neighbours[f].push(g);
                neighbours[g].push(f);
            }
            // normal curvature along each mesh direction from the two opposite neighbours;
            // only dome- or bowl-like units (both of the same sign) have a concave side
            let mut pull: Vec<Real> = (0..n)
                .map(|f| {
                    let c = hubs[f].centre;
                    let nf = hubs[f].normal();
                    let kappa = |a: usize, b: usize| -> Option<Real> {
                        let (ca, cb) = (hubs[a].centre, hubs[b].centre);
                        let h2 = ((ca - c).norm_squared() + (cb - c).norm_squared()) / 2.0;
                        Some(((ca - c) + (cb - c)).dot(&nf) / h2.max(1e-300))
                    };
                    let k0 = across[f][0]
                        .zip(across[f][2])
                        .and_then(|(a, b)| kappa(a, b));
                    let k1 = across[f][1]
                        .zip(across[f][3])
                        .and_then(|(a, b)| kappa(a, b));
                    match (k0, k1) {
                        (Some(a), Some(b)) if a * b > 0.0 => a.signum() * a.abs().min(b.abs()),
                        _ => 0.0,
                    }
                })
                .collect();
            for _ in 0..2 {
                pull = (0..n)
                    .map(|f| {
                        let sum: Real = neighbours[f].iter().map(|&g| pull[g]).sum();
                        (pull[f] + sum) / (1 + neighbours[f].len()) as Real
                    })
                    .collect();
            }
            let total: Real = pull.iter().sum();
            let global = if total < 0.0 {
                Side::HubNegative
            } else {
                Side::HubPositive
            };
            let strongest = pull.iter().map(|b| b.abs()).fold(0.0, Real::max);
            pull.iter()
                .zip(hubs)
                .map(|(&b, h)| {
                    // clearly curved regions take their concave side, the rest the overall one
                    if b.abs() > 0.5 * strongest && b.abs() > 1e-6 / h.rhombus.side() {
                        if b < 0.0 {
                            Side::HubNegative
                        } else {
                            Side::HubPositive
                        }
                    } else {
                        global
                    }
                })
                .collect()
        }
    }
}

/// At `phi = 0` both axis cases give the same unit; their tilts differ. Give each unit
/// the case whose tilt has the larger least-squares gradient, i.e. the tilt that closes
/// its gaps fastest.
fn choose_cases(problem: &Problem, deps: &mut [Deployment]) -> Result<(), FrameError> {
    let n = deps.len();
    let weights = vec![[1.0, 0.0, 0.0]; problem.links.len()];
    let mut slope = [vec![0.0; n], vec![0.0; n]];
    for (c, case) in [AxisCase::OrthogonalToR1, AxisCase::OrthogonalToR2]
        .into_iter()
        .enumerate()
    {
        let trial: Vec<Deployment> = deps
            .iter()
            .map(|d| Deployment {
                case,
                phi: 0.0,
                ..*d
            })
            .collect();
        let mut grad = vec![0.0; 2 * n];
        let mut grad2 = vec![0.0; 2 * n];
        let mut diag = vec![[0.0; 3]; n];
        let mut off = vec![[0.0; 4]; problem.links.len()];
        problem.linearise(
            &trial,
            &weights,
            [&mut grad, &mut grad2],
            &mut diag,
            &mut off,
        )?;
        // gradient scaled by the curvature along phi: the decrease a Newton step would give
        for u in 0..n {
            slope[c][u] = grad[2 * u + 1] * grad[2 * u + 1] / diag[u][2].max(1e-300);
        }
    }
    for (u, d) in deps.iter_mut().enumerate() {
        if d.phi == 0.0 && slope[1][u] > slope[0][u] {
            d.case = AxisCase::OrthogonalToR2;
        }
    }
    Ok(())
}

struct Problem<'a> {
    hubs: &'a [Hub],
    links: &'a [Link],
    units: &'a FrameUnits,
}

impl Problem<'_> {
    fn unit_error(&self, f: usize, e: sv_unit::UnitError) -> FrameError {
        FrameError::Unit {
            unit: f,
            face: f,
            cause: e,
        }
    }

    /// Every unit's pose (on every core; the first unit in order that fails names the
    /// error, so the result does not depend on the threads).
    fn poses(&self, deps: &[Deployment]) -> Result<Vec<UnitPose>, FrameError> {
        let all: Vec<Result<UnitPose, FrameError>> = deps
            .par_iter()
            .enumerate()
            .map(|(f, d)| {
                self.units
                    .pose(f, &self.hubs[f], d)
                    .map_err(|e| self.unit_error(f, e))
            })
            .collect();
        all.into_iter().collect()
    }

    fn corners(&self, deps: &[Deployment]) -> Result<Vec<[Point3; 4]>, FrameError> {
        Ok(self.corners_at(&self.poses(deps)?))
    }

    fn corners_at(&self, poses: &[UnitPose]) -> Vec<[Point3; 4]> {
        poses
            .iter()
            .zip(self.hubs)
            .map(|(p, hub)| self.units.primary_world(hub, p, self.units.expansion()))
            .collect()
    }

    /// Gradient and Gauss-Newton blocks at `deps` of an objective `sum_l h_l(r_l)` whose
    /// per-link Hessian in the residual is `w_l I + v_l r_l r_l^T` and whose gradient is
    /// `w_l r_l` (`weights[l] = [w_l, v_l]`; least squares is `[1, 0]`): gradient
    /// `sum w_l J_l^T r_l`, blocks `sum w_l J_l^T J_l + v_l (J_l^T r_l)(J_l^T r_l)^T`. Per unit
    /// the upper triangle of its 2x2 diagonal block, per link its off-diagonal 2x2 block
    /// (rows of the smaller unit index).
    fn linearise(
        &self,
        deps: &[Deployment],
        weights: &[[Real; 3]],
        [grad, grad2]: [&mut [Real]; 2],
        diag: &mut [[Real; 3]],
        off: &mut [[Real; 4]],
    ) -> Result<(), FrameError> {
        let p = self;
        // corners and their Jacobians, on every core (the first failing unit in order
        // names the error)
        let jac: Vec<Result<_, FrameError>> = deps
            .par_iter()
            .enumerate()
            .map(|(f, d)| {
                let hub = &p.hubs[f];
                p.units
                    .primary_in_hub_frame(f, hub, d)
                    .map(|j| {
                        (
                            j.corners.map(|q| hub.to_world(&q)),
                            j.d_theta.map(|v| hub.frame * v),
                            j.d_phi.map(|v| hub.frame * v),
                        )
                    })
                    .map_err(|e| p.unit_error(f, e))
            })
            .collect();
        let jac: Vec<_> = jac.into_iter().collect::<Result<_, _>>()?;
        grad.iter_mut().for_each(|g| *g = 0.0);
        grad2.iter_mut().for_each(|g| *g = 0.0);
        diag.iter_mut().for_each(|d| *d = [0.0; 3]);
        for (li, l) in p.links.iter().enumerate() {
            let [f, g] = l.faces;
            let [k, m] = l.slots;
            let (cf, tf, pf) = &jac[f];
            let (cg, tg, pg) = &jac[g];
            let c = segment_closest(&cf[k], &cf[(k + 1) % 4], &cg[m], &cg[(m + 1) % 4]);
            let (s, t) = (c.s, c.t);
            let (dp, dq) = (cf[(k + 1) % 4] - cf[k], cg[(m + 1) % 4] - cg[m]);
            let r: Vector3 = (cf[k] + dp * s) - (cg[m] + dq * t);
            let lerp = |a: &Vector3, b: &Vector3, u: Real| a * (1.0 - u) + b * u;
            // Variable projection (Kaufman): the closest points slide along the sides
            // where their parameters are free, so the directions they can slide in
            // are projected out of the residual's Jacobian.
            let basis = sliding_basis(&[(s, dp), (t, dq)]);
            let project = |v: Vector3| basis.iter().fold(v, |v, e| v - e * e.dot(&v));
            // columns: theta_f, phi_f, theta_g, phi_g
            let cols = [
                project(lerp(&tf[k], &tf[(k + 1) % 4], s)),
                project(lerp(&pf[k], &pf[(k + 1) % 4], s)),
                project(-lerp(&tg[m], &tg[(m + 1) % 4], t)),
                project(-lerp(&pg[m], &pg[(m + 1) % 4], t)),
            ];
            let r = project(r);
            let [w, v, w2] = weights[li];
            let var = [2 * f, 2 * f + 1, 2 * g, 2 * g + 1];
            let jr = cols.map(|c| c.dot(&r));
            for a in 0..4 {
                grad[var[a]] += w * jr[a];
                grad2[var[a]] += w2 * jr[a];
            }
            let jj = |a: usize, b: usize| w * cols[a].dot(&cols[b]) + v * jr[a] * jr[b];
            diag[f][0] += jj(0, 0);
            diag[f][1] += jj(0, 1);
            diag[f][2] += jj(1, 1);
            diag[g][0] += jj(2, 2);
            diag[g][1] += jj(2, 3);
            diag[g][2] += jj(3, 3);
            // off-diagonal block rows of the smaller index
            off[li] = if f < g {
                [jj(0, 2), jj(0, 3), jj(1, 2), jj(1, 3)]
            } else {
                [jj(2, 0), jj(2, 1), jj(3, 0), jj(3, 1)]
            };
        }
        Ok(())
    }

    fn gaps(&self, deps: &[Deployment]) -> Result<Vec<Real>, FrameError> {
        let c = self.corners(deps)?;
        Ok(self
            .links
            .iter()
            .map(|l| link_gap(&c, l).distance)
            .collect())
    }
}

fn link_gap(corners: &[[Point3; 4]], l: &Link) -> sv_geom::SegmentClosest {
    let [f, g] = l.faces;
    let [k, m] = l.slots;
    segment_closest(
        &corners[f][k],
        &corners[f][(k + 1) % 4],
        &corners[g][m],
        &corners[g][(m + 1) % 4],
    )
}

/// Gaps and hub overlaps of units at `poses` (one per hub, in face order), measured on
/// the units' plates (as cut when the units are).
pub fn evaluate(
    hubs: &[Hub],
    links: &[Link],
    poses: &[UnitPose],
    units: &FrameUnits,
) -> Result<Evaluation, FrameError> {
    let problem = Problem { hubs, links, units };
    let corners = problem.corners_at(poses);
    let gaps = links
        .iter()
        .map(|l| link_gap(&corners, l).distance)
        .collect();
    let overlaps = links
        .iter()
        .map(|l| {
            let [f, g] = l.faces;
            hub_overlap(
                &hubs[f].centre,
                &units.hub_plate(f, &hubs[f])[l.slots[0]],
                &hubs[g].centre,
                &units.hub_plate(g, &hubs[g])[l.slots[1]],
            )
        })
        .collect();
    Ok(Evaluation { gaps, overlaps })
}

/// How far two facing hub corners pass each other along the line between the hub
/// centres: `(tip_f - tip_g) . e`, `e` the unit vector from `c_f` to `c_g`.
pub(crate) fn hub_overlap(cf: &Point3, tip_f: &Point3, cg: &Point3, tip_g: &Point3) -> Real {
    let e = (cg - cf).normalize();
    (tip_f - tip_g).dot(&e)
}

/// Orthonormal basis of the directions in which the closest points can slide: the side
/// directions whose closest-point parameter is strictly inside `(0, 1)`.
fn sliding_basis(sides: &[(Real, Vector3); 2]) -> Vec<Vector3> {
    let mut basis: Vec<Vector3> = Vec::with_capacity(2);
    for (u, d) in sides {
        if *u <= 0.0 || *u >= 1.0 {
            continue;
        }
        let v = basis.iter().fold(*d, |v, e| v - e * e.dot(&v));
        // nearly parallel sides span one direction only
        if v.norm() > 1e-6 * d.norm() {
            basis.push(v.normalize());
        }
    }
    basis
}

/// What a Levenberg-Marquardt run decreases.
#[derive(Clone, Copy, Debug)]
enum Objective {
    /// `sum gap^2 / 2`: smooth, a good start.
    LeastSquares,
    /// `sum gap` (the paper's objective) by iteratively reweighted least squares; gaps
    /// below `floor` (mm) are weighted as `floor`.
    SumOfGaps { floor: Real },
    /// `scale ||gap / scale||_p + quad sum gap^2 / (2 scale)`: the p-norm of the gaps, a
    /// smooth stand-in for the largest gap (`max <= ||g||_p <= L^(1/p) max` for `L`
    /// links), plus a small least-squares term that keeps the other gaps low. Newton steps
    /// on the Gauss-Newton model of the norm itself (not of its p-th power): see
    /// [`Objective::rank_one`].
    Norm { p: Real, scale: Real, quad: Real },
}

/// Per-link coefficients of [`Problem::linearise`] and the rank-one correction of a step.
struct Model {
    /// Per link `[w, v, w2]`: Hessian `w I + v r r^T` and gradient `w r` of the link's term
    /// in its residual `r`; `w2 r` is the link's share of the vector `u` below.
    weights: Vec<[Real; 3]>,
    /// The step solves `(H - beta u u^T) dx = -grad` (Sherman-Morrison), `beta >= 0`.
    beta: Real,
}

impl Objective {
    /// The model at the current gaps.
    fn model(&self, gaps: &[Real], out: &mut Model) {
        out.beta = 0.0;
        match *self {
            Objective::LeastSquares => out.weights.iter_mut().for_each(|w| *w = [1.0, 0.0, 0.0]),
            // majorisation: fixed weights 1 / gap_k
            Objective::SumOfGaps { floor } => {
                for (w, &g) in out.weights.iter_mut().zip(gaps) {
                    *w = [1.0 / g.max(floor), 0.0, 0.0];
                }
            }
            // F = s N^(1/p), N = sum (g/s)^p. In the residual r of a link, with x = g/s:
            // grad N = p x^(p-2) / s^2 r, Hess N = p x^(p-2) / s^2 I + p (p-2) x^(p-4) / s^4 r r^T;
            // grad F = a grad N and Hess F = a (Hess N - (1 - 1/p) / N grad N grad N^T),
            // a = (s/p) N^(1/p - 1). The last term couples every link (a dense rank-one
            // matrix), so it goes into beta and the vector u = grad N.
            Objective::Norm { p, scale, quad } => {
                let s = scale;
                let n: Real = gaps.iter().map(|g| (g / s).powf(p)).sum();
                if n <= 0.0 {
                    out.weights
                        .iter_mut()
                        .for_each(|w| *w = [quad / s, 0.0, 0.0]);
                    return;
                }
                let a = (s / p) * n.powf(1.0 / p - 1.0);
                for (w, &g) in out.weights.iter_mut().zip(gaps) {
                    let x = g / s;
                    let wn = p * x.powf(p - 2.0) / (s * s);
                    let vn = p * (p - 2.0) * x.powf(p - 4.0) / s.powi(4);
                    // p < 4 and a closed link: the rank-one term vanishes with |r|^2
                    let vn = if vn.is_finite() { vn } else { 0.0 };
                    *w = [a * wn + quad / s, a * vn, wn];
                }
                out.beta = a * (1.0 - 1.0 / p) / n;
            }
        }
    }

    /// The function the steps must lower, given the model taken at the current point:
    /// the objective itself, or the majorant for the reweighted sum of gaps.
    fn merit(&self, gaps: &[Real], model: &Model) -> Real {
        match *self {
            Objective::LeastSquares => gaps.iter().map(|g| 0.5 * g * g).sum(),
            Objective::SumOfGaps { .. } => gaps
                .iter()
                .zip(&model.weights)
                .map(|(g, w)| 0.5 * w[0] * g * g)
                .sum(),
            Objective::Norm { p, scale, quad } => {
                let s = scale;
                let n: Real = gaps.iter().map(|g| (g / s).powf(p)).sum();
                s * n.powf(1.0 / p) + quad * gaps.iter().map(|g| g * g).sum::<Real>() / (2.0 * s)
            }
        }
    }

    /// What the stall test watches: a figure that falls with the objective.
    fn progress_measure(&self, gaps: &[Real], model: &Model) -> Real {
        match *self {
            Objective::SumOfGaps { .. } => gaps.iter().sum(),
            _ => self.merit(gaps, model),
        }
    }
}

/// What [`Lm::run`] calls at every accepted point: iteration, deployments, gaps.
type Visit<'a> = dyn FnMut(usize, &[Deployment], &[Real]) + 'a;

/// Levenberg-Marquardt state: the sparsity pattern and its symbolic factorisation.
struct Lm<'a> {
    problem: &'a Problem<'a>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: faer::sparse::Argsort<usize>,
    llt_symbolic: SymbolicCholesky<usize>,
    /// Values of the Cholesky factor and scratch space, reused by every factorisation.
    factor: Vec<Real>,
    scratch: MemBuffer,
    /// Per unit `(theta_min, theta_max)`.
    theta_bounds: Vec<(Real, Real)>,
    factorizations: usize,
}

impl<'a> Lm<'a> {
    fn new(problem: &'a Problem<'a>) -> Result<Self, FrameError> {
        let n = problem.hubs.len();
        let mut idx = Vec::with_capacity(3 * n + 4 * problem.links.len());
        for u in 0..n {
            idx.push(Pair::new(2 * u, 2 * u));
            idx.push(Pair::new(2 * u, 2 * u + 1));
            idx.push(Pair::new(2 * u + 1, 2 * u + 1));
        }
        for l in problem.links {
            let (a, b) = (l.faces[0].min(l.faces[1]), l.faces[0].max(l.faces[1]));
            for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                idx.push(Pair::new(2 * a + i, 2 * b + j));
            }
        }
        let lin = |e: &dyn std::fmt::Debug| FrameError::Linear(format!("{e:?}"));
        let (symbolic, argsort) =
            SymbolicSparseColMat::try_new_from_indices(2 * n, 2 * n, &idx).map_err(|e| lin(&e))?;
        let threshold = SupernodalThreshold::FORCE_SUPERNODAL;
        let llt_symbolic = factorize_symbolic_cholesky(
            symbolic.as_ref(),
            faer::Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                ..Default::default()
            },
        )
        .map_err(|e| lin(&e))?;
        let req = StackReq::any_of(&[
            llt_symbolic.factorize_numeric_llt_scratch::<Real>(Par::Seq, Default::default()),
            llt_symbolic.solve_in_place_scratch::<Real>(2, Par::Seq),
        ]);
        let scratch = MemBuffer::try_new(req).map_err(|e| lin(&e))?;
        Ok(Self {
            problem,
            symbolic,
            argsort,
            factor: vec![0.0; llt_symbolic.len_val()],
            llt_symbolic,
            scratch,
            theta_bounds: problem
                .hubs
                .iter()
                .map(|h| (THETA_BOUNDS.0, theta_max(h)))
                .collect(),
            factorizations: 0,
        })
    }

    /// Box of variable `i` (`2u`: theta of unit `u`, `2u + 1`: its phi).
    fn bounds(&self, i: usize) -> (Real, Real) {
        if i.is_multiple_of(2) {
            self.theta_bounds[i / 2]
        } else {
            PHI_BOUNDS
        }
    }

    /// Run up to `max_iterations` LM steps; returns the number of iterations used.
    /// `visit` sees every accepted point with its gaps.
    fn run(
        &mut self,
        deps: &mut [Deployment],
        objective: Objective,
        max_iterations: usize,
        tolerance: Real,
        visit: &mut Visit<'_>,
    ) -> Result<usize, FrameError> {
        let p = self.problem;
        let n = p.hubs.len();
        let mut lambda = 1e-3;
        let mut model = Model {
            weights: vec![[1.0, 0.0, 0.0]; p.links.len()],
            beta: 0.0,
        };
        let mut gaps = p.gaps(deps)?;
        let mut grad = vec![0.0; 2 * n];
        let mut grad2 = vec![0.0; 2 * n];
        let mut diag = vec![[0.0; 3]; n];
        let mut off = vec![[0.0; 4]; p.links.len()];
        let mut fixed = vec![false; 2 * n];
        let mut history = Vec::with_capacity(max_iterations);
        for it in 0..max_iterations {
            visit(it, deps, &gaps);
            objective.model(&gaps, &mut model);
            let cost = objective.merit(&gaps, &model);
            let measure = objective.progress_measure(&gaps, &model);
            if cost <= 0.0 || !cost.is_finite() {
                return Ok(it);
            }
            history.push(measure);
            if it >= STALL_WINDOW && history[it - STALL_WINDOW] - measure <= tolerance * measure {
                return Ok(it);
            }
            p.linearise(
                deps,
                &model.weights,
                [&mut grad, &mut grad2],
                &mut diag,
                &mut off,
            )?;
            // Projected Newton (Bertsekas): a variable on a bound whose gradient pushes it
            // further out is held there for this step, so that clamping does not spoil it.
            for (i, f) in fixed.iter_mut().enumerate() {
                let x = if i % 2 == 0 {
                    deps[i / 2].theta
                } else {
                    deps[i / 2].phi
                };
                let (lo, hi) = self.bounds(i);
                let eps = 1e-9 * (hi - lo);
                *f = (x <= lo + eps && grad[i] > 0.0) || (x >= hi - eps && grad[i] < 0.0);
            }
            let gnorm = grad
                .iter()
                .zip(&fixed)
                .filter(|(_, f)| !**f)
                .map(|(g, _)| g.abs())
                .fold(0.0, Real::max);
            if gnorm <= 1e-14 * (1.0 + cost) {
                return Ok(it);
            }
            // damped steps until the merit decreases
            let mut accepted = false;
            for _ in 0..12 {
                let mut vals = Vec::with_capacity(3 * n + 4 * p.links.len());
                let dmax = diag
                    .iter()
                    .map(|d| d[0].max(d[2]))
                    .fold(0.0, Real::max)
                    .max(1e-300);
                for (u, d) in diag.iter().enumerate() {
                    let (ft, fp) = (fixed[2 * u], fixed[2 * u + 1]);
                    vals.push(d[0] * (1.0 + lambda) + 1e-12 * dmax);
                    vals.push(if ft || fp { 0.0 } else { d[1] });
                    vals.push(d[2] * (1.0 + lambda) + 1e-12 * dmax);
                }
                for (o, l) in off.iter().zip(p.links) {
                    let (a, b) = (l.faces[0].min(l.faces[1]), l.faces[0].max(l.faces[1]));
                    for (k, (i, j)) in [(0, 0), (0, 1), (1, 0), (1, 1)].into_iter().enumerate() {
                        let keep = !fixed[2 * a + i] && !fixed[2 * b + j];
                        vals.push(if keep { o[k] } else { 0.0 });
                    }
                }
                let mat =
                    SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &vals)
                        .map_err(|e| FrameError::Linear(format!("{e:?}")))?;
                self.factorizations += 1;
                let stack = MemStack::new(&mut self.scratch);
                let Ok(llt) = self.llt_symbolic.factorize_numeric_llt(
                    &mut self.factor,
                    mat.as_ref(),
                    faer::Side::Upper,
                    Default::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                ) else {
                    lambda *= 10.0;
                    continue;
                };
                // columns: -grad and u (zero on held variables)
                let mut rhs = faer::Mat::<Real>::from_fn(2 * n, 2, |i, j| match (fixed[i], j) {
                    (true, _) => 0.0,
                    (false, 0) => -grad[i],
                    (false, _) => grad2[i],
                });
                llt.solve_in_place_with_conj(Conj::No, rhs.as_mut(), Par::Seq, stack);
                // Sherman-Morrison: (H - beta u u^T)^-1 b = x0 + beta x1 (u.x0) / (1 - beta u.x1)
                if model.beta > 0.0 {
                    let (mut ux0, mut ux1) = (0.0, 0.0);
                    for (i, u) in grad2.iter().enumerate() {
                        if !fixed[i] {
                            ux0 += u * rhs[(i, 0)];
                            ux1 += u * rhs[(i, 1)];
                        }
                    }
                    let denom = 1.0 - model.beta * ux1;
                    // NaN included: no usable rank-one correction, damp harder
                    if denom.is_nan() || denom <= 1e-9 {
                        lambda *= 4.0;
                        continue;
                    }
                    let c = model.beta * ux0 / denom;
                    for i in 0..2 * n {
                        rhs[(i, 0)] += c * rhs[(i, 1)];
                    }
                }
                // Backtrack along this step before damping more: a rejected full step is
                // usually a closest point jumping to another end of a side, and a shorter
                // step along the same direction costs no new factorisation.
                for fraction in [1.0, 0.5, 0.25] {
                    let trial: Vec<Deployment> = deps
                        .iter()
                        .enumerate()
                        .map(|(u, d)| {
                            let (lo, hi) = self.bounds(2 * u);
                            Deployment {
                                theta: (d.theta + fraction * rhs[(2 * u, 0)]).clamp(lo, hi),
                                phi: (d.phi + fraction * rhs[(2 * u + 1, 0)])
                                    .clamp(PHI_BOUNDS.0, PHI_BOUNDS.1),
                                ..*d
                            }
                        })
                        .collect();
                    let step_ok = trial
                        .iter()
                        .all(|d| d.theta.is_finite() && d.phi.is_finite());
                    let new = if step_ok { p.gaps(&trial).ok() } else { None };
                    if let Some(g) = new.filter(|g| objective.merit(g, &model) < cost) {
                        deps.copy_from_slice(&trial);
                        gaps = g;
                        lambda = if fraction == 1.0 {
                            (lambda / 3.0).max(1e-12)
                        } else {
                            lambda * 2.0
                        };
                        accepted = true;
                        break;
                    }
                }
                if accepted {
                    break;
                }
                lambda *= 4.0;
            }
            if !accepted {
                visit(it + 1, deps, &gaps);
                return Ok(it + 1);
            }
        }
        visit(max_iterations, deps, &gaps);
        Ok(max_iterations)
    }
}

impl Solved {
    /// The frame file for this solve (docs/frame-format.md, `frame.json` v2).
    pub fn to_frame_file(&self, mesh: &QuadMesh) -> FrameFile {
        let arr = |p: Point3| [p.x, p.y, p.z];
        let units = self
            .hubs
            .iter()
            .zip(self.deployments.iter().zip(&self.poses))
            .enumerate()
            .map(|(f, (hub, (dep, pose)))| {
                let primary = self.units.primary_world(hub, pose, 1.0);
                let depth = Some(pose.translation.norm());
                UnitRecord {
                    id: format!("U{f:04}"),
                    face: f,
                    strip: String::new(),
                    theta: dep.theta,
                    phi: dep.phi,
                    hub: hub.corners().map(arr),
                    primary: primary.map(arr),
                    hub_plate: Some(self.units.hub_plate(f, hub).map(arr)),
                    pins: {
                        let (h, r) = self.units.pins_world(f, hub, pose);
                        Some(LegPins {
                            hub: h.map(arr),
                            rim: r.map(arr),
                            length: self.units.legs(f, hub).length,
                        })
                    },
                    axis_case: Some(dep.case),
                    side: Some(dep.side),
                    depth,
                    spin: ((self.spins[f] - self.options.spin_angle).abs() > 1e-12)
                        .then_some(self.spins[f]),
                    tile_scale: (self.scales[f] != [1.0, 1.0]).then_some(self.scales[f]),
                    hub_lift: (self.lifts[f] != 0.0).then_some(self.lifts[f]),
                }
            })
            .collect();
        let links = self
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| LinkRecord {
                units: l.faces,
                edge: l.edge,
                primary_gap: self.evaluation.gaps[i],
                hub_overlap: self.evaluation.overlaps[i],
                slots: Some(l.slots),
                joint: self.joints.as_ref().map(|j| j.records[i]),
            })
            .collect();
        FrameFile {
            format: FRAME_FORMAT.into(),
            version: FRAME_VERSION,
            length_unit: "mm".into(),
            params: FrameParams {
                spin_angle: self.options.spin_angle,
                expansion: self.options.expansion,
                cut: self.options.cut,
                thickness: self.joints.as_ref().map(|j| j.thickness),
                joint_limits: self.joints.as_ref().map(|j| j.limits),
                hub_lap: self.joints.as_ref().and_then(|j| j.hub_lap),
                hub_laps_touch: self.joints.as_ref().is_some_and(|j| j.laps_touch),
            },
            mesh: MeshData {
                vertices: mesh.vertices.iter().map(|p| arr(*p)).collect(),
                faces: mesh.faces.clone(),
            },
            units,
            links,
            solve: Some(SolveSummary {
                gap_sum_start: self.report.gap_sum_start,
                gap_sum: self.report.gap_sum,
                gap_max: self.report.gap_max,
                iterations: self.report.iterations,
                planarity_max: mesh.planarity_residuals().into_iter().fold(0.0, Real::max),
                conical_max: mesh
                    .conical_residuals()
                    .into_iter()
                    .map(|(_, r)| r)
                    .fold(0.0, Real::max),
            }),
        }
    }
}

#[cfg(test)]
mod tests;
