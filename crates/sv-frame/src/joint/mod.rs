//! The joint solve: the hub mesh and every unit's deployment moved together so that the
//! parts as cut meet (docs/geometry.md, "Closing the joints").
//!
//! Unknowns: every mesh vertex, every unit's primary plate pose, hub spin and two tile
//! scales (half-diagonals), and where along each link its joint sits. The legs as cut are
//! stiff residuals during the solve and exact at the end ([`sv_unit::Linkage::settle`]).
//! Least squares, Levenberg-Marquardt on the sparse normal equations, on these residuals
//! (mm):
//! - **bridges** (consecutive units of a strip, one piece of steel): the facing primary
//!   sides meet (closest points coincide) and run along one line (no bend in the plates'
//!   plane, twist kept within its limit), so the joint is a fold about that line;
//! - **welds** (primary plates of neighbouring strips): the facing sides meet at a point,
//!   and neither plate passes through the other;
//! - **hub laps** of at least the weld minimum;
//! - the hub mesh: faces planar, vertices on the target's tangent plane (and boundary line)
//!   where they started, a light pull back along the surface.

mod piece;
mod problem;
mod unit;

use std::collections::HashMap;

use rayon::prelude::*;
use sv_geom::sparse::NormalEquations;
use sv_geom::{segment_closest, Point3, Real, Rotation3, Vector3};
use sv_unit::Deployment;

use crate::{
    evaluate, FrameError, FrameUnits, Hub, JointKind, JointLimits, JointRecord, Joints, LapGoal,
    QuadMesh, Solved, UnitPose, GOAL_PLANARITY,
};
use piece::{Join, Piece};
pub(crate) use problem::joint_record;
use problem::{diagonals, edge_ratio, side_links, stacking, Problem, MARGIN, UNIT_COLUMNS};
use unit::{Model, PlatePose, Shape, UnitFailure, UnitPoints};

/// The target surface the hub mesh stays on.
pub trait Surface: Sync {
    /// Where vertex `v`, now at `p`, must stay.
    fn anchor(&self, v: usize, p: &Point3) -> Anchor;
}

/// Where a mesh vertex must stay: on the target's tangent plane at `point` (normal
/// `normal`), and for a boundary vertex on the boundary's tangent line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// The target point nearest the vertex.
    pub point: Point3,
    /// The target's unit normal there.
    pub normal: Vector3,
    /// For a boundary vertex: the nearest boundary point and the boundary's unit tangent.
    pub boundary: Option<(Point3, Vector3)>,
}

/// Options of [`close_joints`].
#[derive(Clone, Debug, PartialEq)]
pub struct JointOptions {
    /// Largest number of Levenberg-Marquardt iterations.
    pub max_iterations: usize,
    /// Iterations of a round after the bridges the solve could not make are split (welded
    /// on site instead), or while welds are left open: only then, on top of
    /// `max_iterations`, each round polished again as the legs' polish of the budget (at
    /// most ten rounds, docs/geometry.md 6.6).
    pub split_iterations: usize,
    /// Largest distance of a vertex from its anchor plane (and line), as a fraction of the
    /// mean side.
    pub closeness: Real,
    /// The weld minimum of the hub laps (mm).
    pub min_overlap: Real,
    /// One hub lap for every link, so that one gauge block checks every hub joint on site;
    /// `None`: any lap above the minimum.
    pub overlap: Option<LapGoal>,
    /// The hub mesh's goal for every face side (mm, shortest and longest), held where a
    /// side would leave it; `None`: not held.
    pub face_sides: Option<(Real, Real)>,
    /// Pull the two hub plates of every lap together until they touch somewhere (the
    /// closest gap between them within what a weld bridges, `limits.weld_gap`), so that a
    /// lap weld needs no filler. It costs time and, on some frames, closure: off by
    /// default (docs/geometry.md 5.5).
    pub laps_touch: bool,
    /// What the joints must reach.
    pub limits: JointLimits,
    /// Width of a bridge along its joint (mm): turns are weighed as the offset they make at
    /// its edges.
    pub bridge_width: Real,
    /// How far a joint point stays from the ends of both facing sides (mm): room for a
    /// bridge and its fillets on the plates' straight edges.
    pub bridge_room: Real,
    /// Sheet thickness (mm): plates closer than this where they overlap collide.
    pub thickness: Real,
    /// The strip pieces as the strips stage plans them: none grows longer than its sheet
    /// lets it.
    pub pieces: Vec<PieceLength>,
    /// Give up ([`FrameError::PulledOff`]) where the hub faces are pulled far from planar
    /// with joints still open ([`PULLED_OFF`], [`FAR_FROM_PLANAR`]); on by default. Off,
    /// the solve runs to its end whatever it does to the faces (studies of single rows).
    pub give_up: bool,
}

/// A strip piece as the strips stage plans it before the joints close.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PieceLength {
    /// Its units (faces) in strip order.
    pub units: Vec<usize>,
    /// Per join `j`: the facing sides of `units[j]` and `units[j + 1]` (side `k` runs from
    /// corner `k` to `k + 1` of the primary tile).
    pub sides: Vec<[usize; 2]>,
    /// How much longer the piece may grow: the longest flat pattern a sheet takes over the
    /// piece's flat length at the start.
    pub room: Real,
}

impl Default for JointOptions {
    fn default() -> Self {
        Self {
            max_iterations: 250,
            split_iterations: 50,
            closeness: 0.05,
            min_overlap: 0.0,
            overlap: None,
            face_sides: None,
            laps_touch: false,
            limits: JointLimits::default(),
            bridge_width: 7.5,
            bridge_room: 15.0,
            thickness: 2.5,
            pieces: Vec::new(),
            give_up: true,
        }
    }
}

/// The worst figures of a frame's joints.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointFigures {
    /// Largest distance between the facing sides at a bridge (mm).
    pub bridge_gap: Real,
    /// Largest bend of a bridge (rad).
    pub bridge_bend: Real,
    /// Largest twist of a bridge (rad).
    pub bridge_twist: Real,
    /// Largest distance between the facing sides at a weld (mm).
    pub weld_gap: Real,
    /// Deepest pass-through of facing primary plates (mm).
    pub collision: Real,
    /// Shortest hub lap (mm).
    pub lap_min: Real,
    /// Largest face planarity (diagonal distance / mean side).
    pub planarity: Real,
    /// Largest distance of a vertex from its anchor plane (mm).
    pub closeness: Real,
}

impl JointFigures {
    /// These figures with the joints and laps measured again: the joint figures from
    /// `records`, the shortest lap from `laps`.
    fn measured(mut self, records: &[JointRecord], laps: &[Real]) -> Self {
        let (mut bridge, mut weld) = ([0.0 as Real; 3], 0.0 as Real);
        self.collision = 0.0;
        for j in records {
            match j.kind {
                JointKind::Bridge => {
                    bridge[0] = bridge[0].max(j.gap);
                    bridge[1] = bridge[1].max(j.bend.abs());
                    bridge[2] = bridge[2].max(j.twist.abs());
                }
                JointKind::Weld => weld = weld.max(j.gap),
            }
            self.collision = self.collision.max(j.collision);
        }
        [self.bridge_gap, self.bridge_bend, self.bridge_twist] = bridge;
        self.weld_gap = weld;
        self.lap_min = laps.iter().copied().fold(Real::INFINITY, Real::min);
        self
    }
}

/// What [`close_joints`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct JointReport {
    /// Before.
    pub start: JointFigures,
    /// After.
    pub end: JointFigures,
    /// Iterations.
    pub iterations: usize,
    /// The bridges that could not be made and are welded instead, where the strips are
    /// split: `(link, the bridge as the solve left it)`.
    pub splits: Vec<(usize, JointRecord)>,
}

/// Largest move of a vertex or a chart angle (as an arc at the unit's size) per step, as
/// a fraction of the unit's side.
const MAX_STEP: Real = 0.02;
/// A relative fall of the energy below this in one step counts as a stall.
const STALL: Real = 1e-6;
/// The legs' weight factors of the polish at the end, and its iterations per factor.
const LEG_POLISH: [Real; 2] = [30.0, 1000.0];
const POLISH_ITERATIONS: usize = 10;
/// Rounds of splitting the bridges that cannot be made, or of closing the welds left
/// open, at most.
const ROUNDS: usize = 10;
/// A round for the welds follows one that narrowed the worst of them at least this much
/// (relative): where they stall, more rounds only cost time.
const WELD_PROGRESS: Real = 0.02;
/// The stages of [`Problem::stiffness`].
const STIFFNESS: [Real; 4] = [0.0, 0.03, 0.1, 0.3];
/// A solve that ends with the hub faces' planarity past this many times what it started
/// with (or the goal, where it started within it) and joints outside their limits gives
/// up: the shop cuts the hub plates flat, and its joints are open anyway.
const PULLED_OFF: Real = 2.0;
/// A solve whose hub faces are this far from planar (diagonal distance over mean side) at
/// the end of a stage or round, past [`PULLED_OFF`] too, with joints outside their limits,
/// gives up there instead of at its end. On the triangulated layouts of a boomerang, a
/// horseshoe and two round courts it passed 0.1 after 92-184 iterations and ended near 0.6.
/// Of the solves kept at their end, those that started within the goal passed 0.02 nowhere
/// (the cone sector's, which closes every weld, 0.018 on the way), the others twice their
/// start nowhere; of the rest none but those three passed 0.05 (docs/geometry.md 6.8).
const FAR_FROM_PLANAR: Real = 0.1;

fn unit_error(f: usize, e: UnitFailure) -> FrameError {
    match e {
        UnitFailure::NoHub => FrameError::Mesh(crate::MeshError::DegenerateFace {
            face: f,
            why: crate::Degeneracy::Other(
                "no best-fit rhombus (diagonals parallel or reversed)".into(),
            ),
        }),
        UnitFailure::Cut(why) => FrameError::Cut { unit: f, why },
    }
}

/// The joint solve between its rounds: where it is (the vertices and unit numbers `x`, the
/// plates at `poses`), the normal equations (the same problem's every time, so that their
/// pattern and its analysis are kept from one round to the next), how the anchors are
/// taken, and the iterations used so far (progress is reported from there).
struct Descent<'s> {
    ne: NormalEquations,
    x: Vec<Real>,
    poses: Vec<PlatePose>,
    anchors_at: &'s (dyn Fn(&[Real]) -> Vec<Anchor> + Sync),
    iterations: usize,
    progress: &'s mut dyn FnMut(usize, Real),
}

impl Descent<'_> {
    /// Levenberg-Marquardt on `problem` for at most `budget` iterations: steps within a
    /// trust region of MAX_STEP of the side, the anchors taken again after every step;
    /// where it stalls, the joints outside their limits weigh more and it goes on. Returns
    /// the units at the end.
    fn run(
        &mut self,
        problem: &mut Problem<'_>,
        budget: usize,
    ) -> Result<Vec<UnitPoints>, FrameError> {
        let Self {
            ne,
            x,
            poses,
            anchors_at,
            iterations: done,
            progress,
        } = self;
        let nf = problem.faces.len();
        let moves = 3 * problem.nv + UNIT_COLUMNS * nf;
        let scale = problem.model.scale;
        let mut units = problem
            .units(x, poses, true)
            .map_err(|(f, e)| unit_error(f, e))?;
        let mut energy = problem.energy(x, &units);
        let mut dx = vec![0.0; x.len()];
        let mut lambda = 1e-4;
        let mut iterations = 0;
        while iterations < budget {
            iterations += 1;
            ne.reset(1e-9);
            problem.visit(x, &units, ne);
            let mut accepted = None;
            for _ in 0..40 {
                if !ne
                    .solve_damped(lambda, &mut dx)
                    .map_err(|e| FrameError::Linear(e.0))?
                {
                    lambda *= 10.0;
                    continue;
                }
                // a trust region in the problem's own sizes: vertices and plates (turns as
                // arcs at the unit's size) move at most MAX_STEP of the side per step (the joint
                // points slide freely along their sides: not counted, only clamped)
                let largest = dx[..moves].iter().fold(0.0, |m: Real, v| m.max(v.abs()));
                let k = (MAX_STEP * scale / largest.max(1e-300)).min(1.0);
                let mut trial: Vec<Real> = x.iter().zip(&dx).map(|(a, b)| a + k * b).collect();
                for &col in &problem.joint_columns {
                    trial[col] = trial[col].clamp(0.0, scale);
                }
                if let Ok(u) = problem.units(&trial, poses, false) {
                    let e = problem.energy(&trial, &u);
                    if e < energy {
                        accepted = Some((trial, e));
                        break;
                    }
                }
                lambda *= 4.0;
            }
            let gain = match accepted {
                Some((next, e)) => {
                    let gain = (energy - e) / energy.max(1e-300);
                    // the plates take their increments; the increments start from zero again
                    *poses = (0..nf).map(|f| problem.pose(&next, f, poses)).collect();
                    *x = next;
                    for f in 0..nf {
                        let c = problem.pose_column(f);
                        x[c..c + 6].iter_mut().for_each(|v| *v = 0.0);
                    }
                    // the vertices moved: their anchors follow
                    problem.anchors = anchors_at(x);
                    lambda = (lambda / 3.0).max(1e-9);
                    units = problem
                        .units(x, poses, true)
                        .map_err(|(f, e)| unit_error(f, e))?;
                    energy = problem.energy(x, &units);
                    progress(*done + iterations, energy);
                    gain
                }
                None => 0.0,
            };
            if gain < STALL {
                // stalled: the joints still outside their limits weigh more, and on
                if !problem.emphasise(x, &units) {
                    break;
                }
                energy = problem.energy(x, &units);
                lambda = 1e-4;
            }
        }
        *done += iterations;
        Ok(units)
    }
}

/// How far the hub faces may leave planarity in the joint solve: `cap` at its end
/// ([`PULLED_OFF`] times `start`, where it began, or the goal), `far` on the way
/// ([`FAR_FROM_PLANAR`], or `cap` where that is more).
struct Planarity {
    start: Real,
    cap: Real,
    far: Real,
}

impl Planarity {
    fn new(start: Real) -> Self {
        let cap = PULLED_OFF * start.max(GOAL_PLANARITY);
        Self {
            start,
            cap,
            far: cap.max(FAR_FROM_PLANAR),
        }
    }

    /// The solve given up, with the figures, where the hub faces at `x` are past the limit
    /// (`cap` at the `end`, else `far`) and any of the joints `records` is outside its
    /// limits, after `iterations`.
    fn check(
        &self,
        problem: &Problem<'_>,
        x: &[Real],
        records: &[JointRecord],
        (iterations, end): (usize, bool),
    ) -> Result<(), FrameError> {
        if !problem.options.give_up {
            return Ok(());
        }
        let planarity = problem.planarity(x);
        if planarity <= if end { self.cap } else { self.far } {
            return Ok(());
        }
        let open = (records.iter())
            .filter(|j| !problem.options.limits.holds(j))
            .count();
        if open > 0 {
            return Err(FrameError::PulledOff {
                open,
                planarity,
                start: self.start,
                iterations,
            });
        }
        Ok(())
    }
}

/// The chart coordinates of a pose: the rotation's angle `theta` and its axis' tilt `phi`
/// from the tile normal toward the diagonal it is not orthogonal to (the axis case). For
/// the zero-width unit these are the closed form's own; for the unit as cut, the
/// rotation's.
fn chart_of(pose: &UnitPose, side: sv_unit::Side) -> Deployment {
    let r = Rotation3::from_matrix_unchecked(pose.rotation);
    let (axis, theta) = r
        .axis_angle()
        .map(|(a, t)| (a.into_inner(), t))
        .unwrap_or((Vector3::z(), 0.0));
    let (t, theta) = if axis.z < 0.0 {
        (-axis, -theta)
    } else {
        (axis, theta)
    };
    let (case, phi) = if t.x.abs() <= t.y.abs() {
        (sv_unit::AxisCase::OrthogonalToR1, t.y.atan2(t.z))
    } else {
        (sv_unit::AxisCase::OrthogonalToR2, t.x.atan2(t.z))
    };
    Deployment {
        theta,
        phi,
        case,
        side,
    }
}

/// Each unit's primary plate pose in the world from a solve: tile point `r` at `q r + t`.
fn plate_poses(solved: &Solved) -> Vec<PlatePose> {
    solved
        .hubs
        .iter()
        .zip(&solved.poses)
        .map(|(hub, p)| {
            let q = hub.frame * p.rotation.transpose();
            PlatePose {
                q,
                t: hub.centre.coords - q * p.translation,
            }
        })
        .collect()
}

/// Close the joints of a solved frame: move the hub mesh `mesh` (whose vertices stay on
/// `surface`) and every unit's primary plate together, the legs as cut held. `bridges[l]`
/// says whether link `l` joins two consecutive units of a strip. Returns the new mesh and
/// frame.
pub fn close_joints(
    mesh: &QuadMesh,
    solved: &Solved,
    surface: &dyn Surface,
    bridges: &[bool],
    options: &JointOptions,
    progress: &mut dyn FnMut(usize, Real),
) -> Result<(QuadMesh, Solved, JointReport), FrameError> {
    let nv = mesh.vertices.len();
    let nf = solved.hubs.len();
    if bridges.len() != solved.links.len() {
        return Err(FrameError::Parameter {
            name: "bridges",
            value: bridges.len() as Real,
            why: "one bridge flag per link",
        });
    }
    let anchors_at = |x: &[Real]| -> Vec<Anchor> {
        (0..nv)
            .into_par_iter()
            .map(|v| surface.anchor(v, &Point3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2])))
            .collect()
    };
    let scale = solved.hubs.iter().map(|h| h.rhombus.side()).sum::<Real>() / nf.max(1) as Real;
    let links = solved.links.len();
    let mut problem = Problem {
        edge_ratios: (0..nf).map(|f| edge_ratio(&mesh.face_points(f))).collect(),
        pieces: Vec::new(),
        emphasis: vec![1.0; links],
        diagonals: diagonals(&mesh.faces, nv),
        stiffness: STIFFNESS[0],
        legs: 1.0,
        joint_columns: (0..links).map(|l| 3 * nv + UNIT_COLUMNS * nf + l).collect(),
        faces: &mesh.faces,
        links: &solved.links,
        bridges: bridges.to_vec(),
        side_links: side_links(&solved.links, nf),
        on_top: stacking(&solved.links, nf),
        anchors: anchors_at(&{
            let mut x = vec![0.0; 3 * nv];
            for (v, p) in mesh.vertices.iter().enumerate() {
                x[3 * v..3 * v + 3].copy_from_slice(p.coords.as_slice());
            }
            x
        }),
        corners: mesh.corners(),
        start: mesh.vertices.clone(),
        model: Model {
            spin: solved.options.spin_angle,
            expansion: solved.options.expansion,
            cut: solved.options.cut,
            scale,
        },
        options,
        nv,
        near: options.closeness * scale,
    };
    let poses = plate_poses(solved);
    let n = 3 * nv + UNIT_COLUMNS * nf + links;
    let mut x = vec![0.0; n];
    for (v, p) in mesh.vertices.iter().enumerate() {
        x[3 * v..3 * v + 3].copy_from_slice(p.coords.as_slice());
    }
    let mut units = problem
        .units(&x, &poses, true)
        .map_err(|(f, e)| unit_error(f, e))?;
    // the strip pieces the strips stage plans: one unit or more, linked, on real sides
    if let Some(p) = options.pieces.iter().find(|p| {
        !p.room.is_finite()
            || p.room <= 0.0
            || p.units.is_empty()
            || p.sides.len() + 1 != p.units.len()
            || p.units.iter().any(|&f| f >= nf)
            || p.sides.iter().flatten().any(|&k| k >= 4)
    }) {
        return Err(FrameError::Parameter {
            name: "pieces",
            value: p.room,
            why: "a strip piece names a unit or side the frame does not have, or no room",
        });
    }
    // joint points start where the facing sides come closest
    for (l, &col) in solved.links.iter().zip(&problem.joint_columns) {
        let [f, g] = l.faces;
        let [k, m] = l.slots;
        let (pf, pg) = (units[f].primary(), units[g].primary());
        let c = segment_closest(&pf[k], &pf[(k + 1) % 4], &pg[m], &pg[(m + 1) % 4]);
        x[col] = c.s * scale;
    }
    // each strip piece's flat length may grow as much as its sheet lets it
    let link_of: HashMap<[usize; 2], usize> = solved
        .links
        .iter()
        .enumerate()
        .map(|(l, link)| (link.faces, l))
        .collect();
    for p in &options.pieces {
        let joins = p
            .units
            .windows(2)
            .zip(&p.sides)
            .map(|(w, &sides)| {
                let (forward, link) = match (link_of.get(&[w[0], w[1]]), link_of.get(&[w[1], w[0]]))
                {
                    (Some(&l), _) => (true, l),
                    (None, Some(&l)) => (false, l),
                    (None, None) => {
                        return Err(FrameError::Parameter {
                            name: "pieces",
                            value: w[0] as Real,
                            why: "two consecutive units of a strip piece are not linked",
                        })
                    }
                };
                Ok(Join {
                    link,
                    sides,
                    forward,
                    s: 0.0,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let piece = Piece {
            units: p.units.clone(),
            joins,
        };
        let now = problem.piece_length(&piece, &x, &units);
        problem.pieces.push((piece, now * p.room));
    }
    let start = problem.figures(&x, &units);
    let pulled_off = Planarity::new(start.planarity);
    // one set of normal equations for every round: the rows keep their columns whatever
    // their weights, so the pattern and its analysis are the same throughout
    let mut descent = Descent {
        ne: NormalEquations::new(n),
        x,
        poses,
        anchors_at: &anchors_at,
        iterations: 0,
        progress,
    };
    let mut demoted = Vec::new();
    // the iterations of the stages; the rest are the legs' polish
    let polish = (LEG_POLISH.len() * POLISH_ITERATIONS).min(options.max_iterations / 4);
    let closing = options.max_iterations - polish;
    for (stage, &stiffness) in STIFFNESS.iter().enumerate() {
        // the first stage (the joints closing) gets 40 % of the iterations, each later one
        // its share of the rest
        let budget = if stage == 0 {
            closing * 2 / 5
        } else {
            problem.stiffness = stiffness;
            closing.saturating_sub(descent.iterations) / (STIFFNESS.len() - stage)
        };
        units = descent.run(&mut problem, budget)?;
        let records = problem.records(&descent.x, &units);
        pulled_off.check(&problem, &descent.x, &records, (descent.iterations, false))?;
    }
    let mut rounds = 0;
    // the worst weld's excess when the last round for the welds began
    let mut weld_excess = Real::INFINITY;
    loop {
        // the legs made stiffer step by step, the rest as it was: where a unit sits near a
        // singular pose (a nearly symmetric tile) its legs' last micrometre would otherwise
        // cost a millimetre of plate move in the projection onto them
        for legs in LEG_POLISH {
            problem.legs = legs;
            units = descent.run(&mut problem, polish / LEG_POLISH.len())?;
        }
        // the bridges the solve could not make (its iterations used up): the strips are
        // split there, and the welds that take their place get a round of their own, polished
        // again (a few rounds, as a round may leave a bridge beside them outside its limits).
        let records = problem.records(&descent.x, &units);
        pulled_off.check(&problem, &descent.x, &records, (descent.iterations, false))?;
        let failing = problem.failing_bridges(&records);
        if options.split_iterations == 0 || rounds == ROUNDS {
            break;
        }
        // every bridge made (or split in an earlier round), but welds left open or within
        // a fifth of their limits (MARGIN): a round for them, polished again, as long as the
        // last one narrowed them (only then: a frame that closes with room to spare is the
        // same)
        if failing.is_empty() {
            let excess = problem.weld_excess(&records);
            if excess <= MARGIN || excess > (1.0 - WELD_PROGRESS) * weld_excess {
                break;
            }
            weld_excess = excess;
        } else {
            weld_excess = Real::INFINITY;
        }
        rounds += 1;
        for (li, j) in failing {
            problem.bridges[li] = false;
            demoted.push((li, j));
        }
        problem.legs = 1.0;
        units = descent.run(&mut problem, options.split_iterations)?;
    }
    let Descent {
        x,
        poses,
        iterations,
        ..
    } = descent;
    let end = problem.figures(&x, &units);
    // the new frame: hubs from the new mesh, each unit's pose on its hub projected onto its
    // legs as cut exactly
    let mut out = mesh.clone();
    for (v, p) in out.vertices.iter_mut().enumerate() {
        *p = Point3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
    }
    let shapes: Vec<Shape> = (0..nf).map(|f| problem.shape(&x, f)).collect();
    let spins: Vec<Real> = shapes.iter().map(|s| s.spin).collect();
    let scales: Vec<[Real; 2]> = shapes.iter().map(|s| s.scale).collect();
    let lifts: Vec<Real> = shapes.iter().map(|s| s.lift).collect();
    let hubs = (0..nf)
        .map(|f| {
            let degenerate = |why: &str| {
                FrameError::Mesh(crate::MeshError::DegenerateFace {
                    face: f,
                    why: crate::Degeneracy::Other(why.into()),
                })
            };
            let mut hub = Hub::fit(&out.face_points(f), spins[f]).ok_or_else(|| {
                degenerate("no best-fit rhombus (diagonals parallel or reversed)")
            })?;
            hub.rhombus = hub
                .rhombus
                .scaled(scales[f])
                .map_err(|_| degenerate("tile scaled to nothing"))?;
            hub.centre += hub.normal() * shapes[f].lift;
            Ok(hub)
        })
        .collect::<Result<Vec<Hub>, FrameError>>()?;
    let units_out = FrameUnits::new(&hubs, solved.options.expansion, solved.options.cut.as_ref())?;
    let mut unit_poses = Vec::with_capacity(nf);
    for (f, (hub, plate)) in hubs.iter().zip(&poses).enumerate() {
        let rotation = plate.q.transpose() * hub.frame;
        let translation = plate.q.transpose() * (hub.centre.coords - plate.t);
        let (rotation, translation) = units_out
            .legs(f, hub)
            .settle(&rotation, &translation)
            .map_err(|cause| FrameError::Unit {
                unit: f,
                face: f,
                cause,
            })?;
        unit_poses.push(UnitPose {
            rotation,
            translation,
        });
    }
    // the joints, measured on the plates as they are now
    let corners: Vec<[Point3; 4]> = hubs
        .iter()
        .zip(&unit_poses)
        .map(|(hub, p)| units_out.primary_world(hub, p, solved.options.expansion))
        .collect();
    let joints: Vec<JointRecord> = solved
        .links
        .iter()
        .enumerate()
        .map(|(li, l)| problem.record(li, &corners[l.faces[0]], &corners[l.faces[1]], &x))
        .collect();
    let deployments: Vec<Deployment> = unit_poses
        .iter()
        .zip(&solved.deployments)
        .map(|(p, d)| chart_of(p, d.side))
        .collect();
    let evaluation = evaluate(&hubs, &solved.links, &unit_poses, &units_out)?;
    pulled_off.check(&problem, &x, &joints, (iterations, true))?;
    // the joints as they are on the plates as cut, after the projection onto the legs
    let end = end.measured(&joints, &evaluation.overlaps);
    let mut report = solved.report.clone();
    report.gap_sum = evaluation.gaps.iter().sum();
    report.gap_max = evaluation.gaps.iter().copied().fold(0.0, Real::max);
    let frame = Solved {
        hubs,
        links: solved.links.clone(),
        deployments,
        poses: unit_poses,
        spins,
        scales,
        lifts,
        joints: Some(Joints {
            records: joints,
            thickness: options.thickness,
            limits: options.limits,
            hub_lap: options.overlap,
            laps_touch: options.laps_touch,
        }),
        evaluation,
        report,
        options: solved.options.clone(),
        units: units_out,
    };
    Ok((
        out,
        frame,
        JointReport {
            start,
            end,
            iterations,
            splits: demoted,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{solve, SolveOptions};

    /// A solved 4 x 4 sphere cap as cut, its anchors (the start) and bridges along rows.
    fn cap() -> (QuadMesh, Solved, Vec<Anchor>, Vec<bool>) {
        let mesh = QuadMesh::sphere_cap(4, 4, 3000.0, 300.0);
        let opts = SolveOptions {
            cut: Some(sv_unit::CutWidths::STEEL_3MM),
            ..Default::default()
        };
        let solved = solve(&mesh, &opts, &mut |_| {}).unwrap();
        let c = Point3::new(0.0, 0.0, -3000.0);
        let anchors = mesh
            .vertices
            .iter()
            .map(|p| Anchor {
                point: *p,
                normal: (p - c).normalize(),
                boundary: None,
            })
            .collect();
        let bridges = solved.links.iter().map(|l| l.slots[0] % 2 == 0).collect();
        (mesh, solved, anchors, bridges)
    }

    /// The joint problem on `mesh` as `solved`, held to `anchors`, strips along `bridges`,
    /// every row at full weight, the hub mesh's start where it is.
    fn problem_on<'a>(
        mesh: &'a QuadMesh,
        solved: &'a Solved,
        anchors: &[Anchor],
        bridges: &[bool],
        options: &'a JointOptions,
    ) -> Problem<'a> {
        let (nv, nf) = (mesh.vertices.len(), solved.hubs.len());
        Problem {
            faces: &mesh.faces,
            links: &solved.links,
            bridges: bridges.to_vec(),
            side_links: side_links(&solved.links, nf),
            on_top: stacking(&solved.links, nf),
            anchors: anchors.to_vec(),
            corners: vec![false; nv],
            start: mesh.vertices.clone(),
            model: Model {
                spin: solved.options.spin_angle,
                expansion: 1.0,
                cut: solved.options.cut,
                scale: 300.0,
            },
            options,
            nv,
            near: 15.0,
            joint_columns: (0..solved.links.len())
                .map(|l| 3 * nv + UNIT_COLUMNS * nf + l)
                .collect(),
            edge_ratios: vec![1.0; nf],
            pieces: Vec::new(),
            emphasis: vec![1.0; solved.links.len()],
            diagonals: diagonals(&mesh.faces, nv),
            stiffness: 1.0,
            legs: 1.0,
        }
    }

    /// The hub mesh's vertices, then zeros for the other unknowns of `problem`.
    fn start_of(mesh: &QuadMesh, problem: &Problem<'_>) -> Vec<Real> {
        let n = 3 * problem.nv + UNIT_COLUMNS * problem.faces.len() + problem.links.len();
        let mut x = vec![0.0; n];
        for (v, p) in mesh.vertices.iter().enumerate() {
            x[3 * v..3 * v + 3].copy_from_slice(p.coords.as_slice());
        }
        x
    }

    /// The solve gives up where the hub faces leave planarity with joints open: at its end
    /// past twice its start (or the goal: the cap starts planar), on the way only past a
    /// tenth of the side; with every joint holding it never does.
    #[test]
    fn the_solve_gives_up_where_the_faces_leave_planarity_with_joints_open() {
        let (mesh, solved, anchors, bridges) = cap();
        let options = JointOptions::default();
        let problem = problem_on(&mesh, &solved, &anchors, &bridges, &options);
        let x = start_of(&mesh, &problem);
        let poses = plate_poses(&solved);
        let records = problem.records(&x, &problem.units(&x, &poses, true).unwrap());
        assert!(records.iter().any(|j| !options.limits.holds(j)));
        let limits = Planarity::new(problem.planarity(&x));
        assert!(limits.start < 1e-9, "{}", limits.start);
        // a vertex of the middle face lifted off the sphere by `d` mm: that face leaves
        // planarity as the lift grows
        let v = mesh.faces[mesh.faces.len() / 2][0];
        let (mut at_end, mut on_the_way) = (0, 0);
        for d in [
            0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 5.0, 10.0, 20.0, 40.0, 80.0, 120.0,
        ] {
            let mut y = x.clone();
            y[3 * v + 2] += d;
            let planarity = problem.planarity(&y);
            let end = limits.check(&problem, &y, &records, (0, true));
            let way = limits.check(&problem, &y, &records, (0, false));
            assert_eq!(
                end.is_err(),
                planarity > 2.0 * GOAL_PLANARITY,
                "{d} mm: {end:?}"
            );
            assert_eq!(way.is_err(), planarity > 0.1, "{d} mm: {way:?}");
            if let Err(FrameError::PulledOff { planarity: p, .. }) = end {
                assert_eq!(p, planarity);
            }
            at_end += end.is_err() as usize;
            on_the_way += way.is_err() as usize;
            assert!(limits.check(&problem, &y, &[], (0, true)).is_ok());
        }
        // both limits fall inside the lifts tried
        assert!(
            at_end > on_the_way && on_the_way > 0 && at_end < 12,
            "{at_end} {on_the_way}"
        );
    }

    #[test]
    fn the_assembled_gradient_is_the_energy_gradient() {
        let (mesh, solved, anchors, bridges) = cap();
        let options = JointOptions {
            min_overlap: 200.0, // every lap short: the lap rows act
            ..Default::default()
        };
        let mut problem = problem_on(&mesh, &solved, &anchors, &bridges, &options);
        problem.start = (mesh.vertices.iter())
            .map(|p| p + Vector3::new(3.0, -2.0, 1.0))
            .collect();
        // a two-unit strip piece on a sheet far too short: its length row acts
        problem.pieces = vec![(
            Piece {
                units: solved.links[0].faces.to_vec(),
                joins: vec![Join {
                    link: 0,
                    sides: solved.links[0].slots,
                    forward: true,
                    s: 0.0,
                }],
            },
            10.0,
        )];
        // link 0's second plate slid 15 mm in under the first's side and a thickness lower:
        // the legs' ends at that side's corners reach into it
        let mut poses = plate_poses(&solved);
        let [f, g] = solved.links[0].faces;
        let (cf, cg) = (solved.hubs[f].centre, solved.hubs[g].centre);
        poses[g].t += (cf - cg).normalize() * 15.0 - solved.hubs[g].normal() * 2.5;
        let mut x = start_of(&mesh, &problem);
        for c in &problem.joint_columns {
            x[*c] = 0.4 * problem.model.scale;
        }
        let units = problem.units(&x, &poses, true).unwrap();
        let mut ne = NormalEquations::new(x.len());
        ne.reset(0.0);
        problem.visit(&x, &units, &mut ne);
        let grad: Vec<Real> = ne.rhs.iter().map(|r| -2.0 * r).collect();
        let energy = |x: &[Real]| problem.energy(x, &problem.units(x, &poses, false).unwrap());
        // directional derivatives along a few fixed directions
        for seed in 0..4u64 {
            let dir: Vec<Real> = (0..x.len())
                .map(|i| (((i as u64 + 1) * (seed + 7) * 2654435761) % 1000) as Real / 500.0 - 1.0)
                .collect();
            let h = 1e-4;
            let plus: Vec<Real> = x.iter().zip(&dir).map(|(a, d)| a + h * d).collect();
            let minus: Vec<Real> = x.iter().zip(&dir).map(|(a, d)| a - h * d).collect();
            let fd = (energy(&plus) - energy(&minus)) / (2.0 * h);
            let an: Real = grad.iter().zip(&dir).map(|(g, d)| g * d).sum();
            assert!(
                (fd - an).abs() <= 1e-4 * fd.abs().max(an.abs()).max(1.0),
                "direction {seed}: finite difference {fd} vs assembled {an}"
            );
        }
    }

    /// Two 300 mm tiles of one strip side by side in one plane, joined by a bridge 15 mm
    /// from the end of their common side; the second turned by `deg` in the plane about
    /// the bridge. Their plates are cut back 1.875 mm (half a 3.75 mm joint slot) there.
    fn rims_into_each_other(deg: Real) -> Real {
        let a = [(0.0, 0.0), (300.0, 0.0), (300.0, 300.0), (0.0, 300.0)]
            .map(|(x, y)| Point3::new(x, y, 0.0));
        let w = Point3::new(300.0, 15.0, 0.0);
        let (s, c) = deg.to_radians().sin_cos();
        let b = [(300.0, 0.0), (600.0, 0.0), (600.0, 300.0), (300.0, 300.0)].map(|(x, y)| {
            let (dx, dy) = (x - w.x, y - w.y);
            Point3::new(w.x + c * dx - s * dy, w.y + s * dx + c * dy, 0.0)
        });
        let half = 1.875;
        let r = problem::joint_record(
            [&a, &b],
            [[0.0, half, 0.0, 0.0], [0.0, 0.0, 0.0, half]],
            [1, 3],
            0.05,
            JointKind::Bridge,
            2.5,
        );
        assert!(r.gap < 1e-9, "the bridge spans its joint: {r:?}");
        r.collision
    }

    #[test]
    fn a_bridge_turned_in_its_plane_is_clear_until_its_slot_closes_at_the_far_end() {
        // the far end of the side is 285 mm from the bridge: the 3.75 mm slot closes at
        // atan(3.75 / 285) = 0.75 deg turned towards the first tile
        assert_eq!(rims_into_each_other(0.0), 0.0);
        assert_eq!(rims_into_each_other(0.7), 0.0);
        // beyond, the rims overlap in one plane, the far corner as deep as it passed the
        // closed slot (285 sin 0.8 deg - 3.75 = 0.23 mm), at most a whole thickness
        let just = rims_into_each_other(0.8);
        assert!(0.1 < just && just < 0.3, "{just}");
        assert!((rims_into_each_other(2.0) - 2.5).abs() < 1e-9);
        // turned the other way the slot opens there
        assert_eq!(rims_into_each_other(-2.0), 0.0);
    }
}
