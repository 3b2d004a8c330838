//! The joint solve's least-squares problem: its unknowns laid out in one vector, its
//! residual rows (weights per mm of residual) and their gradients, assembled into the
//! normal equations or summed into an energy ([`Sink`]).

use rayon::prelude::*;
use sv_geom::sparse::NormalEquations;
use sv_geom::{segment_closest, Point3, Real, Vector3};

use super::piece::Piece;
use super::unit::{Model, PlatePose, Shape, UnitFailure, UnitPoints, INPUTS};
use super::{Anchor, JointFigures, JointOptions};
use crate::plates::{
    edge_to_plate, facing_reach, hinge_turn, lap_heights, plate_as_cut, reach_into, reach_profile,
    tips_offset, REACH_ROWS,
};
use crate::solve::hub_overlap;
use crate::GOAL_PLANARITY;
use crate::{JointKind, JointRecord, Link};

/// Residual weights (per mm of residual).
pub(super) const W_BRIDGE: Real = 10.0;
pub(super) const W_WELD: Real = 3.0;
pub(super) const W_PLANAR: Real = 10.0;
pub(super) const W_CLOSE: Real = 0.3;
pub(super) const W_DRIFT: Real = 0.03;
pub(super) const W_LAP: Real = 10.0;
pub(super) const W_TURN: Real = 0.1;
pub(super) const W_LEG: Real = 1000.0;
pub(super) const W_COLLIDE: Real = 100.0;
/// The collision rows measure a facing side's depth inside the other plate's outline, seen
/// along its normal, at any height within this many thicknesses of its mid-plane (1 m of
/// 2.5 mm sheet: at any height a neighbour can be): plates that lie one over the other near
/// a joint (a weld holds them at its point only) put one plate's rim under the other's rim
/// neck, where that unit's leg leaves its plate towards the hub side and runs through it
/// (docs/geometry.md 5.5). With one thickness the pavilion had 27 legs through a
/// neighbour's rim; with this, none. A slab only a few thicknesses deep has an edge: the
/// solve pushed plates apart in height past it, and opened welds.
pub(super) const OVERLAP_SLAB: Real = 400.0;
pub(super) const W_SCALE: Real = 0.3;
pub(super) const W_LIFT: Real = 0.03;
pub(super) const W_STACK: Real = 10.0;
/// Columns of one unit after its face's vertices: its plate pose increment (6), spin (1),
/// tile scales (2) and hub lift (1).
pub(super) const UNIT_COLUMNS: usize = 10;
/// How far beyond one thickness apart the solve keeps lapping hub plates (mm). At 0.05
/// (until the eighth session) the pavilion and the dome at 200 mm kept a lap 0.104 and
/// 0.173 mm into its neighbour, against the check's 0.1 mm.
pub(super) const STACK_MARGIN: Real = 0.15;
pub(super) const W_LIMIT: Real = 100.0;
/// A one-sided limit starts pushing at this fraction of it.
pub(super) const MARGIN: Real = 0.8;
/// The largest factor on a joint's weight.
pub(super) const EMPHASIS_MAX: Real = 100.0;
/// Faces may grow more unequal than they start only up to this edge ratio (the hub mesh
/// goal is 1.25 on 95 % of faces).
pub(super) const EDGE_RATIO: Real = 1.2;
/// Face sides are held this share inside the hub mesh's goal (`JointOptions::face_sides`).
/// Without the row the dome at 300 mm with its hub laps held to one length (docs/config.md
/// `[frame] overlap`) stretched a face side to 1.41 of the unit size (goal 1.4).
pub(super) const SIDE_MARGIN: Real = 0.01;
/// Hub laps are pushed up to this much above the weld minimum (mm).
pub(super) const LAP_MARGIN: Real = 1.0;
/// The smallest a tile's half-diagonal may be scaled in the solve. Small units (150 mm)
/// were shrunk to less than half until their hub plates could not be cut (no room for a
/// label and its face mark); at 200-300 mm no scale falls below 0.87.
pub(super) const MIN_TILE_SCALE: Real = 0.8;

/// 1 where a one-sided residual acts, else 0 (its row stays, with weight 0, so that every
/// assembly has the same pattern).
pub(super) fn on(r: Real) -> Real {
    if r != 0.0 {
        1.0
    } else {
        0.0
    }
}

/// A row of the least-squares problem: residual `r`, weight `w`, gradient over `cols`.
pub(super) trait Sink {
    /// The rows that follow are of kind `c` (for a breakdown of the energy).
    fn kind(&mut self, _c: usize) {}
    fn gradient(&self) -> bool;
    fn row(&mut self, cols: &[usize], vals: &[Real], r: Real, w: Real);
    /// Rows over the same columns.
    fn block(&mut self, cols: &[usize], rows: &[(&[Real], Real, Real)]) {
        for &(v, r, w) in rows {
            self.row(cols, v, r, w);
        }
    }
}

impl Sink for NormalEquations {
    fn gradient(&self) -> bool {
        true
    }
    fn row(&mut self, cols: &[usize], vals: &[Real], r: Real, w: Real) {
        NormalEquations::row(self, cols, vals, r, w)
    }
    fn block(&mut self, cols: &[usize], rows: &[(&[Real], Real, Real)]) {
        NormalEquations::block(self, cols, rows)
    }
}

/// The energy `sum w^2 r^2` only, and its share per kind of row.
#[derive(Default)]
pub(super) struct Energy {
    total: Real,
    kinds: [Real; KINDS],
    kind: usize,
}

/// Kinds of rows: planarity, anchors, laps, bridge points, weld points, bridge turns,
/// collisions, legs.
pub(super) const KINDS: usize = 8;

impl Sink for Energy {
    fn kind(&mut self, c: usize) {
        self.kind = c;
    }
    fn gradient(&self) -> bool {
        false
    }
    fn row(&mut self, _: &[usize], _: &[Real], r: Real, w: Real) {
        self.total += w * w * r * r;
        self.kinds[self.kind] += w * w * r * r;
    }
}

/// Rows of a link's primary plates: the joint point's offset (3), its room on both sides
/// (2), bend, twist, turn beyond the limits, and the reach of each side into the other
/// plate (at a bridge across its joint slot) at every sample and at its deepest.
pub(super) const ROWS: usize = 8 + 2 * REACH_ROWS;

/// One link's rows over its columns (both units' inputs and its joint parameter), with
/// their gradients along those columns.
pub(super) struct LinkBlock {
    cols: Vec<usize>,
    rows: Vec<LinkRow>,
    /// The rows' gradients along `cols`, row after row (empty without gradients).
    vals: Vec<Real>,
}

/// A point of a link's units: its unit (0 for the link's first, 1 for its second) and its
/// index in that unit's [`UnitPoints::points`].
type UnitPoint = (usize, usize);

/// The primary plates' corners, the link's first unit's then its second's.
const PRIMARY: [UnitPoint; 8] = [
    (0, 0),
    (0, 1),
    (0, 2),
    (0, 3),
    (1, 0),
    (1, 1),
    (1, 2),
    (1, 3),
];

/// The hub plates' corners, the link's first unit's then its second's.
const HUB_PLATES: [UnitPoint; 8] = [
    (0, 4),
    (0, 5),
    (0, 6),
    (0, 7),
    (1, 4),
    (1, 5),
    (1, 6),
    (1, 7),
];

/// One residual of a link: its value, weight, gradient along the units' points and along
/// the joint's parameter.
pub(super) struct LinkRow {
    kind: usize,
    r: Real,
    w: Real,
    /// The points the gradient is along (at most 8; a point may come twice).
    at: [UnitPoint; 8],
    /// The gradient along each of those points.
    grads: [Vector3; 8],
    ds: Real,
}

/// Central-difference Jacobian of `f` (`R` values) over `K` points (mm), step `h`:
/// `out[r][p]` is the gradient of value `r` along point `p`.
pub(super) fn fd_jac<const K: usize, const R: usize>(
    pts: &[Point3; K],
    h: Real,
    f: impl Fn(&[Point3; K]) -> [Real; R],
) -> [[Vector3; K]; R] {
    let mut out = [[Vector3::zeros(); K]; R];
    for p in 0..K {
        for c in 0..3 {
            let mut a = *pts;
            let mut b = *pts;
            a[p][c] += h;
            b[p][c] -= h;
            let (fa, fb) = (f(&a), f(&b));
            for r in 0..R {
                out[r][p][c] = (fa[r] - fb[r]) / (2.0 * h);
            }
        }
    }
    out
}

/// The joint problem at one point.
pub(super) struct Problem<'a> {
    pub(super) faces: &'a [[usize; 4]],
    pub(super) links: &'a [Link],
    pub(super) bridges: Vec<bool>,
    /// Per face and side: the link across it.
    pub(super) side_links: Vec<[Option<usize>; 4]>,
    /// Per link: its first unit's hub plate lies on top of its second's at their lap.
    pub(super) on_top: Vec<bool>,
    pub(super) anchors: Vec<Anchor>,
    /// Per vertex: a corner of the mesh (a boundary vertex with one face, or with three or
    /// more at a reflex corner), held where it starts.
    pub(super) corners: Vec<bool>,
    pub(super) start: Vec<Point3>,
    pub(super) model: Model,
    pub(super) options: &'a JointOptions,
    pub(super) nv: usize,
    /// Largest closeness (mm).
    pub(super) near: Real,
    /// Per link: the column of its joint point's parameter along the first unit's side.
    pub(super) joint_columns: Vec<usize>,
    /// Per face: its edge ratio (longest / shortest) at the start.
    pub(super) edge_ratios: Vec<Real>,
    /// Per strip piece: the piece, and the longest its flat length may grow to (mm): it
    /// stays on its sheet.
    pub(super) pieces: Vec<(Piece, Real)>,
    /// Units that meet at a vertex only ([`diagonals`]): no joint joins them, but their
    /// plates must not lie over each other there either.
    pub(super) diagonals: Vec<[usize; 2]>,
    /// Per link: the weight of its joint, raised where the joint stays outside its limits.
    pub(super) emphasis: Vec<Real>,
    /// How far the plates' no-collision rows weigh (0 to 1): they come in
    /// gradually, once the joints have closed, so that they do not lock the start.
    pub(super) stiffness: Real,
    /// A factor on the legs' weight: raised at the end, so that the legs hold to far below
    /// a micrometre with the joints where the solve put them.
    pub(super) legs: Real,
}

/// A block's gradients along its `m` columns, one row after another, from its rows'
/// gradients along their units' points (`idx`: where each unit's inputs went); rows that do
/// not weigh are left at zero (the assembly skips them). Empty without gradients.
fn block_values(
    rows: &[LinkRow],
    units: [&UnitPoints; 2],
    idx: &[[usize; INPUTS]; 2],
    m: usize,
    grad: bool,
) -> Vec<Real> {
    let mut vals = vec![0.0; if grad { rows.len() * m } else { 0 }];
    for (r, v) in rows.iter().zip(vals.chunks_exact_mut(m.max(1))) {
        if r.w == 0.0 {
            continue;
        }
        for (&(side, p), gv) in r.at.iter().zip(&r.grads) {
            if let Some(d) = &units[side].d {
                for i in 0..INPUTS {
                    v[idx[side][i]] += gv.dot(&d[p][i]);
                }
            }
        }
    }
    vals
}

/// The pairs of faces that share one vertex and no side: round a vertex, the units across
/// it from each other.
pub(super) fn diagonals(faces: &[[usize; 4]], vertices: usize) -> Vec<[usize; 2]> {
    let mut round = vec![Vec::new(); vertices];
    for (f, face) in faces.iter().enumerate() {
        for &v in face {
            round[v].push(f);
        }
    }
    let mut pairs: Vec<[usize; 2]> = round
        .iter()
        .flat_map(|fs| {
            fs.iter()
                .flat_map(move |&f| fs.iter().filter(move |&&g| g > f).map(move |&g| [f, g]))
        })
        .filter(|[f, g]| faces[*f].iter().filter(|v| faces[*g].contains(v)).count() == 1)
        .collect();
    // found once each (at the one vertex they share), in face order
    pairs.sort_unstable();
    pairs
}

/// Per face and side: the link across it.
pub(super) fn side_links(links: &[Link], faces: usize) -> Vec<[Option<usize>; 4]> {
    let mut at = vec![[None; 4]; faces];
    for (li, l) in links.iter().enumerate() {
        for (f, k) in l.faces.into_iter().zip(l.slots) {
            at[f][k] = Some(li);
        }
    }
    at
}

/// Per link: whether its first unit's hub lies on top of its second's where they lap. The
/// units are coloured in two (breadth first over the links) and the first colour's hubs
/// lie on the second's, so that each hub is on top of all its neighbours or under all of
/// them; where a mesh cannot be coloured in two (an odd cycle of faces), the link's
/// lower-numbered unit lies on top.
pub(super) fn stacking(links: &[Link], faces: usize) -> Vec<bool> {
    let mut next: Vec<Vec<usize>> = vec![Vec::new(); faces];
    for l in links {
        let [f, g] = l.faces;
        next[f].push(g);
        next[g].push(f);
    }
    let mut colour: Vec<Option<bool>> = vec![None; faces];
    for start in 0..faces {
        if colour[start].is_some() {
            continue;
        }
        colour[start] = Some(true);
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(f) = queue.pop_front() {
            for &g in &next[f] {
                if colour[g].is_none() {
                    colour[g] = colour[f].map(|c| !c);
                    queue.push_back(g);
                }
            }
        }
    }
    links
        .iter()
        .map(|l| {
            let [f, g] = l.faces;
            match (colour[f], colour[g]) {
                (Some(a), Some(b)) if a != b => a,
                _ => f < g,
            }
        })
        .collect()
}

/// One gradient row under construction: columns merged.
#[derive(Default)]
pub(super) struct Row {
    cols: Vec<usize>,
    vals: Vec<Real>,
}

impl Row {
    pub(super) fn clear(&mut self) {
        self.cols.clear();
        self.vals.clear();
    }
    pub(super) fn add(&mut self, col: usize, v: Real) {
        match self.cols.iter().position(|&c| c == col) {
            Some(i) => self.vals[i] += v,
            None => {
                self.cols.push(col);
                self.vals.push(v);
            }
        }
    }
    pub(super) fn vertex(&mut self, v: usize, g: &Vector3) {
        for c in 0..3 {
            self.add(3 * v + c, g[c]);
        }
    }
}

impl Problem<'_> {
    pub(super) fn quad(&self, x: &[Real], f: usize) -> [Point3; 4] {
        self.faces[f].map(|v| Point3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]))
    }

    /// Unit `f`'s plate pose moved by its increments in `x`.
    pub(super) fn pose(&self, x: &[Real], f: usize, poses: &[PlatePose]) -> PlatePose {
        let i = self.pose_column(f);
        let w = Vector3::new(x[i], x[i + 1], x[i + 2]) / self.model.scale;
        poses[f].moved(&w, &Vector3::new(x[i + 3], x[i + 4], x[i + 5]))
    }

    pub(super) fn pose_column(&self, f: usize) -> usize {
        3 * self.nv + UNIT_COLUMNS * f
    }

    /// Unit `f`'s spin and tile scales: the model's plus their changes in `x`.
    pub(super) fn shape(&self, x: &[Real], f: usize) -> Shape {
        let c = self.pose_column(f);
        let k = self.model.scale;
        Shape {
            spin: self.model.spin + x[c + 6] / k,
            scale: [1.0 + x[c + 7] / k, 1.0 + x[c + 8] / k],
            lift: x[c + 9],
        }
    }

    pub(super) fn units(
        &self,
        x: &[Real],
        poses: &[PlatePose],
        jacobian: bool,
    ) -> Result<Vec<UnitPoints>, (usize, UnitFailure)> {
        (0..self.faces.len())
            .into_par_iter()
            .map(|f| {
                let q = self.quad(x, f);
                let p = self.pose(x, f, poses);
                let shape = self.shape(x, f);
                self.model
                    .points(&q, &p, shape, jacobian)
                    .map_err(|e| (f, e))
            })
            .collect()
    }

    pub(super) fn column(&self, f: usize, i: usize) -> usize {
        if i < 12 {
            3 * self.faces[f][i / 3] + i % 3
        } else {
            self.pose_column(f) + i - 12
        }
    }

    /// Every residual at `x` into `sink`.
    pub(super) fn visit(&self, x: &[Real], units: &[UnitPoints], sink: &mut dyn Sink) {
        let grad = sink.gradient();
        let scale = self.model.scale;
        let h = 1e-4;
        let mut row = Row::default();
        // the faces: planar (held below MARGIN of the goal), edges no more unequal than
        // they started or EDGE_RATIO, sides within the hub mesh's goal (held SIDE_MARGIN
        // inside it)
        sink.kind(0);
        let (shortest, longest) = self
            .options
            .face_sides
            .map_or((0.0, Real::INFINITY), |(a, b)| {
                (a * (1.0 + SIDE_MARGIN), b * (1.0 - SIDE_MARGIN))
            });
        for f in 0..self.faces.len() {
            let q = self.quad(x, f);
            let goal = MARGIN * GOAL_PLANARITY;
            let ratio = self.edge_ratios[f].max(EDGE_RATIO);
            let face = |q: &[Point3; 4]| -> [Real; 4] {
                let m = (q[2] - q[0]).cross(&(q[3] - q[1]));
                let planar = (q[1] - q[0]).dot(&m) / m.norm().max(1e-300);
                let e = [0, 1, 2, 3].map(|k| (q[(k + 1) % 4] - q[k]).norm());
                let (lo, hi) = e.iter().fold((Real::INFINITY, 0.0 as Real), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
                let mean = (e[0] + e[1] + e[2] + e[3]) / 4.0;
                [
                    planar,
                    (planar.abs() - goal * mean).max(0.0),
                    (hi - ratio * lo).max(0.0),
                    (hi - longest).max(0.0) + (shortest - lo).max(0.0),
                ]
            };
            let now = face(&q);
            let grads = if grad {
                fd_jac(&q, h, face)
            } else {
                [[Vector3::zeros(); 4]; 4]
            };
            let weights = [
                W_PLANAR,
                W_LIMIT * on(now[1]),
                W_LIMIT * on(now[2]),
                W_LIMIT * on(now[3]),
            ];
            for i in 0..4 {
                row.clear();
                for k in 0..4 {
                    row.vertex(self.faces[f][k], &grads[i][k]);
                }
                sink.row(&row.cols, &row.vals, now[i], weights[i]);
            }
        }
        // legs as cut
        sink.kind(7);
        for (f, u) in units.iter().enumerate() {
            for j in 0..4 {
                row.clear();
                if let Some(dl) = &u.dl {
                    for i in 0..INPUTS {
                        row.add(self.column(f, i), dl[j][i]);
                    }
                }
                sink.row(&row.cols, &row.vals, u.legs[j], W_LEG * self.legs);
            }
            // the tile's scales and the hub's lift: free, but not for nothing; a tile no
            // smaller than MIN_TILE_SCALE, so that its hub plate can still be cut
            let c = self.pose_column(f);
            for i in 7..9 {
                sink.row(&[c + i], &[1.0], x[c + i], W_SCALE);
                let short = ((MIN_TILE_SCALE - 1.0) * scale - x[c + i]).max(0.0);
                sink.row(&[c + i], &[-1.0], short, W_LIMIT * on(short));
            }
            sink.row(&[c + 9], &[1.0], x[c + 9], W_LIFT);
        }
        // strip pieces no longer than their sheets let them be
        for (piece, cap) in &self.pieces {
            row.clear();
            let over = (self.piece_length(piece, x, units) - cap).max(0.0);
            if grad {
                // the gradient only where the row weighs; its columns always (one pattern)
                self.piece_gradient(piece, x, units, over > 0.0, &mut row);
            }
            sink.row(&row.cols, &row.vals, over, W_LIMIT * on(over));
        }
        // vertices on the target
        sink.kind(1);
        for (v, a) in self.anchors.iter().enumerate() {
            let p = Point3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
            let one = |sink: &mut dyn Sink, row: &mut Row, dir: &Vector3, r: Real, w: Real| {
                row.clear();
                if grad {
                    row.vertex(v, dir);
                }
                sink.row(&row.cols, &row.vals, r, w);
            };
            let d = (p - a.point).dot(&a.normal);
            one(sink, &mut row, &a.normal, d, W_CLOSE);
            let over = (d.abs() - MARGIN * self.near).max(0.0);
            one(
                sink,
                &mut row,
                &(a.normal * d.signum()),
                over,
                W_LIMIT * on(over),
            );
            // the pull back along the surface, and the boundary line
            let drift = p - self.start[v];
            let (u1, u2) = tangents(&a.normal);
            if self.corners[v] {
                // a corner of the mesh stays where it started
                for axis in [Vector3::x(), Vector3::y(), Vector3::z()] {
                    one(sink, &mut row, &axis, drift.dot(&axis), W_LIMIT);
                }
                continue;
            }
            match a.boundary {
                Some((b, t)) => {
                    // the distance from the boundary line, whichever way the vertex left it
                    let away = (p - b) - t * t.dot(&(p - b));
                    let off = away
                        .try_normalize(1e-12)
                        .unwrap_or_else(|| t.cross(&a.normal).try_normalize(1e-12).unwrap_or(u1));
                    let r = away.dot(&off);
                    one(sink, &mut row, &off, r, W_CLOSE);
                    let over = (r.abs() - MARGIN * self.near).max(0.0);
                    one(
                        sink,
                        &mut row,
                        &(off * r.signum()),
                        over,
                        W_LIMIT * on(over),
                    );
                    one(sink, &mut row, &t, drift.dot(&t), W_DRIFT);
                }
                None => {
                    one(sink, &mut row, &u1, drift.dot(&u1), W_DRIFT);
                    one(sink, &mut row, &u2, drift.dot(&u2), W_DRIFT);
                }
            }
        }
        // links: one block each, over both units' inputs and the joint's parameter (built
        // on every core, assembled in link order)
        let blocks: Vec<LinkBlock> = self
            .links
            .par_iter()
            .enumerate()
            .map(|(li, l)| {
                let [f, g] = l.faces;
                let col = self.joint_columns[li];
                let (cols, idx) = self.link_columns(f, g, col);
                let s = x[col] / scale;
                let mut rows = self.link_rows(li, s, [&units[f], &units[g]], grad);
                for r in rows.iter_mut().filter(|r| r.kind != 2) {
                    r.w *= self.emphasis[li];
                }
                let m = cols.len();
                let mut vals = block_values(&rows, [&units[f], &units[g]], &idx, m, grad);
                for (r, v) in rows.iter().zip(vals.chunks_exact_mut(m)) {
                    if r.w != 0.0 {
                        v[m - 1] += r.ds / scale;
                    }
                }
                LinkBlock { cols, rows, vals }
            })
            .collect();
        // units across a vertex from each other: neither plate lies over the other there
        // either (no joint joins them; docs/geometry.md 5.5)
        let across: Vec<LinkBlock> = self
            .diagonals
            .par_iter()
            .map(|&[f, g]| self.diagonal_block(f, g, units, grad))
            .collect();
        for LinkBlock { cols, rows, vals } in blocks.iter().chain(&across) {
            if grad {
                let block: Vec<(&[Real], Real, Real)> = rows
                    .iter()
                    .zip(vals.chunks_exact(cols.len()))
                    .map(|(r, v)| (v, r.r, r.w))
                    .collect();
                sink.block(cols, &block);
            } else {
                for r in rows {
                    sink.kind(r.kind);
                    sink.row(&[], &[], r.r, r.w);
                }
            }
        }
    }

    /// The columns of a link's block: unit `f`'s inputs, `g`'s that are not `f`'s (they
    /// share two vertices), the joint's parameter last; and where each unit's inputs went.
    pub(super) fn link_columns(
        &self,
        f: usize,
        g: usize,
        joint: usize,
    ) -> (Vec<usize>, [[usize; INPUTS]; 2]) {
        let (mut cols, idx) = self.pair_columns(f, g);
        cols.push(joint);
        (cols, idx)
    }

    /// The rows of units `f` and `g` that meet at a vertex only: each side of either plate
    /// as cut, how deep it lies inside the other's outline at any height ([`reach_into`] in
    /// the slab of [`OVERLAP_SLAB`]: only the deepest point, not the samples the links'
    /// rows take), weighed as the collision rows.
    fn diagonal_block(&self, f: usize, g: usize, units: &[UnitPoints], grad: bool) -> LinkBlock {
        let (cols, idx) = self.pair_columns(f, g);
        let insets = [self.cut_inset(f), self.cut_inset(g)];
        let slab = OVERLAP_SLAB * self.options.thickness;
        let measure = |p: &[Point3; 8]| -> [Real; 8] {
            let a = plate_as_cut(&[p[0], p[1], p[2], p[3]], insets[0]);
            let b = plate_as_cut(&[p[4], p[5], p[6], p[7]], insets[1]);
            std::array::from_fn(|i| {
                let (into, from, k) = if i < 4 { (&a, &b, i) } else { (&b, &a, i - 4) };
                reach_into(into, &from[k], &from[(k + 1) % 4], slab)
            })
        };
        let pts: [Point3; 8] = std::array::from_fn(|i| units[[f, g][i / 4]].points[i % 4]);
        let now = measure(&pts);
        let weigh = self.stiffness > 0.0 && now.iter().any(|&r| r > 0.0);
        // the gradients only where a row weighs (one pattern: the rows are always there)
        let grads = if grad && weigh {
            fd_jac(&pts, 1e-4, measure)
        } else {
            [[Vector3::zeros(); 8]; 8]
        };
        let rows: Vec<LinkRow> = (0..8)
            .map(|i| LinkRow {
                kind: 6,
                r: now[i],
                w: W_COLLIDE * self.stiffness * on(now[i]),
                at: PRIMARY,
                grads: grads[i],
                ds: 0.0,
            })
            .collect();
        let vals = block_values(&rows, [&units[f], &units[g]], &idx, cols.len(), grad);
        LinkBlock { cols, rows, vals }
    }

    /// The columns of two units' inputs: `f`'s, then `g`'s that are not `f`'s; and where
    /// each unit's inputs went.
    fn pair_columns(&self, f: usize, g: usize) -> (Vec<usize>, [[usize; INPUTS]; 2]) {
        let mut cols: Vec<usize> = Vec::with_capacity(2 * INPUTS + 1);
        let mut idx = [[0; INPUTS]; 2];
        for (side, u) in [f, g].into_iter().enumerate() {
            for i in 0..INPUTS {
                let c = self.column(u, i);
                idx[side][i] = match cols.iter().position(|&x| x == c) {
                    Some(p) => p,
                    None => {
                        cols.push(c);
                        cols.len() - 1
                    }
                };
            }
        }
        (cols, idx)
    }

    /// The residuals of one link at the joint parameter `s`, with their gradients along the
    /// units' points (`(0 or 1 for the link's first or second unit, point, gradient)`) and
    /// along `s`.
    pub(super) fn link_rows(
        &self,
        li: usize,
        s: Real,
        units: [&UnitPoints; 2],
        grad: bool,
    ) -> Vec<LinkRow> {
        let (l, bridge) = (&self.links[li], self.bridges[li]);
        let [k, m] = l.slots;
        let (k1, m1) = ((k + 1) % 4, (m + 1) % 4);
        let h = 1e-4;
        let o = self.options;
        let mut out = Vec::with_capacity(12);
        // the hub plates: their lap at least the weld minimum (or all of one length), and one
        // lying on the other, a thickness apart over all their lap
        let pts: [Point3; 8] = std::array::from_fn(|i| units[i / 4].points[4 + i % 4]);
        let laps = o.min_overlap > 0.0 || o.overlap.is_some();
        let (t, top) = (o.thickness, self.on_top[li]);
        let touch = MARGIN * o.limits.weld_gap;
        let hub_rows = |p: &[Point3; 8]| {
            let (a, b) = ([p[0], p[1], p[2], p[3]], [p[4], p[5], p[6], p[7]]);
            let lap = hub_overlap(&centroid4(&a), &a[k], &centroid4(&b), &b[m]);
            let short = match o.overlap {
                // anywhere in the band (held within MARGIN of it, as a limit): a gauge
                // block checks within its tolerance, and the band is the joints' to use
                Some(goal) => {
                    let off = goal.length - lap;
                    (off.abs() - MARGIN * goal.tolerance).max(0.0).copysign(off)
                }
                None if laps => (o.min_overlap + LAP_MARGIN - lap).max(0.0),
                None => 0.0,
            };
            // the tips may pass each other offset sideways until the plates no longer
            // overlap while the lap, along the line of centres, stays (the default saddle
            // had 6 such laps, the vault 1, the dome with its laps held to one length 31):
            // the lap less the tips' offset, which is how far right-angled tips overlap
            // along that line, at least half the weld minimum. Measured: with the overlap
            // itself (`lap_overlap_length`) held instead, welds stayed open on the vault or
            // the saddle (docs/geometry.md 5.5). Hubs that miss each other count as
            // meeting here: the lap's own row brings them together, and this one must not
            // pull against it (on hub meshes far from planar, the annulus at 300 mm, laps
            // of -40 mm made it pull the faces out of shape). Without a weld minimum
            // (studies: hubs that may miss each other) there is no lap to keep in line
            let aligned = if o.min_overlap > 0.0 {
                let lap = lap.max(0.0);
                (0.5 * o.min_overlap - (lap - tips_offset(&a, k, &b, m))).max(0.0)
            } else {
                0.0
            };
            // the mid-planes' distance where the two plates come closest, the upper one's
            // over the lower one's: at least a thickness (and a margin), and at most a
            // thickness and what a weld bridges, so that the plates touch somewhere
            let [into, apart] = lap_heights(&a, &b).map_or([0.0; 2], |(low, high)| {
                let nearest = if top { low } else { -high };
                [
                    (t + STACK_MARGIN - nearest).max(0.0),
                    (nearest - t - touch).max(0.0),
                ]
            });
            [short, into, apart, aligned]
        };
        let now = hub_rows(&pts);
        let lap_weight = if o.overlap.is_some() { W_LIMIT } else { W_LAP };
        // pulled together, the plates would rather touch than stand apart, but must not
        // pass through each other: that row is then a limit
        let (into_weight, apart_weight) = if o.laps_touch {
            (W_LIMIT, W_STACK)
        } else {
            (W_STACK, 0.0)
        };
        let weights = [
            lap_weight * on(now[0]),
            into_weight * on(now[1]),
            apart_weight * on(now[2]),
            W_STACK * on(now[3]),
        ];
        let grads = if grad && weights.iter().any(|&w| w > 0.0) {
            fd_jac(&pts, h, hub_rows)
        } else {
            [[Vector3::zeros(); 8]; 4]
        };
        for i in 0..4 {
            out.push(LinkRow {
                kind: 2,
                r: now[i],
                w: weights[i],
                at: HUB_PLATES,
                grads: grads[i],
                ds: 0.0,
            });
        }
        // the primary plates: the joint at `s` along f's side, inside both sides by the
        // bridge's room; at a bridge g's side runs through it (the fold line) without
        // turning in f's plane and twisting within its limit; at a weld the two plates touch
        // there (edge to edge or edge on face, thickness included); either way the plates as
        // cut reach nowhere into each other
        let pts: [Point3; 8] = std::array::from_fn(|i| units[i / 4].points[i % 4]);
        let room = if bridge { o.bridge_room } else { 0.0 };
        let th = o.thickness;
        let width = o.bridge_width;
        let (bend_lim, twist_lim) = (MARGIN * o.limits.bend, MARGIN * o.limits.twist);
        let stiff = self.stiffness > 0.0;
        let insets = [self.cut_inset(l.faces[0]), self.cut_inset(l.faces[1])];
        let measures = |p: &[Point3; 8], s: Real| -> [Real; ROWS] {
            let (a, b) = ([p[0], p[1], p[2], p[3]], [p[4], p[5], p[6], p[7]]);
            let fv = a[k1] - a[k];
            let w = a[k] + fv * s;
            let gv = b[m1] - b[m];
            let len = gv.norm();
            let gh = gv / len;
            let t = (w - b[m]).dot(&gh);
            // g's side passes through the joint point: the fold line of a bridge, the line
            // the two plates of a weld meet along
            let off = (w - b[m]) - gh * t;
            let flen = fv.norm();
            let fh = fv / flen;
            // the plates are cut back half the joint slot where bridges join (their sides'
            // ends move in): a weld's joint point stays on both plates as cut, a bridge's
            // on its tiles' sides (the fold line)
            let as_cut = || (plate_as_cut(&a, insets[0]), plate_as_cut(&b, insets[1]));
            let (ac, bc) = if bridge { (a, b) } else { as_cut() };
            let (f_lo, f_hi) = ((ac[k] - a[k]).dot(&fh), (a[k1] - ac[k1]).dot(&fh));
            let (g_lo, g_hi) = ((bc[m] - b[m]).dot(&gh), (b[m1] - bc[m1]).dot(&gh));
            let out_f = (room + f_lo - s * flen)
                .max(s * flen - (flen - room - f_hi))
                .max(0.0);
            let out_g = (room + g_lo - t).max(t - (len - room - g_hi)).max(0.0);
            let (bend, twist) = hinge_turn(&a, k, &b, m);
            let beyond = |v: Real, lim: Real| (v.abs() - lim).max(0.0) * v.signum();
            let mut r = [0.0; ROWS];
            r[..8].copy_from_slice(&[
                off.x,
                off.y,
                off.z,
                out_f,
                out_g,
                width * bend,
                width * if bridge { twist } else { 0.0 },
                width
                    * if bridge {
                        beyond(bend, bend_lim).hypot(beyond(twist, twist_lim))
                    } else {
                        0.0
                    },
            ]);
            // no plate reaches into the other, nor lies over it: at a weld anywhere, at a
            // bridge across the joint slot (turned in their plane, the rims meet at the end
            // away from it)
            if stiff {
                let (pa, pb) = if bridge { as_cut() } else { (ac, bc) };
                let slab = OVERLAP_SLAB * th;
                r[8..8 + REACH_ROWS].copy_from_slice(&reach_profile(&pa, &pb[m], &pb[m1], slab));
                r[8 + REACH_ROWS..].copy_from_slice(&reach_profile(&pb, &pa[k], &pa[k1], slab));
            }
            r
        };
        let now = measures(&pts, s);
        let hs = 1e-6;
        let (grads, up, down) = if grad {
            (
                fd_jac(&pts, h, |p| measures(p, s)),
                measures(&pts, s + hs),
                measures(&pts, s - hs),
            )
        } else {
            ([[Vector3::zeros(); 8]; ROWS], now, now)
        };
        let (joint, turn) = if bridge { (3, 5) } else { (4, 4) };
        let weight = if bridge { W_BRIDGE } else { W_WELD };
        for i in 0..ROWS {
            let (kind, w) = match i {
                0..=2 => (joint, weight),
                3 | 4 => (joint, weight * on(now[i])),
                5 => (turn, if bridge { W_TURN } else { 0.0 }),
                6 => (turn, W_TURN),
                7 => (turn, W_LIMIT * on(now[i])),
                _ => (6, W_COLLIDE * self.stiffness * on(now[i])),
            };
            out.push(LinkRow {
                kind,
                r: now[i],
                w,
                at: PRIMARY,
                grads: grads[i],
                ds: (up[i] - down[i]) / (2.0 * hs),
            });
        }
        out
    }

    /// Every link's joint at `x`.
    pub(super) fn records(&self, x: &[Real], units: &[UnitPoints]) -> Vec<JointRecord> {
        (0..self.links.len())
            .map(|li| {
                let [f, g] = self.links[li].faces;
                self.record(li, &units[f].primary(), &units[g].primary(), x)
            })
            .collect()
    }

    /// How far the worst weld of `records` (every link's joint, [`Problem::records`]) is
    /// from its limits, as a multiple of them (its plates apart or into each other; 0
    /// without welds). Beyond [`MARGIN`] it counts as open for the weld rounds: within its
    /// limits, but so near them that another solve's round-off could take it past.
    pub(super) fn weld_excess(&self, records: &[JointRecord]) -> Real {
        (records.iter().enumerate())
            .filter(|(li, _)| !self.bridges[*li])
            .map(|(_, j)| self.options.limits.excess(j))
            .fold(0.0, Real::max)
    }

    /// The links of `records` still bridges whose joints are outside a bridge's limits.
    pub(super) fn failing_bridges(&self, records: &[JointRecord]) -> Vec<(usize, JointRecord)> {
        (records.iter().enumerate())
            .filter(|(li, j)| self.bridges[*li] && !self.options.limits.bridge_holds(j))
            .map(|(li, j)| (li, *j))
            .collect()
    }

    /// Link `li`'s joint at its joint point in `x`, its units' primary plates at `a` and `b`.
    pub(super) fn record(
        &self,
        li: usize,
        a: &[Point3; 4],
        b: &[Point3; 4],
        x: &[Real],
    ) -> JointRecord {
        let l = &self.links[li];
        let kind = if self.bridges[li] {
            JointKind::Bridge
        } else {
            JointKind::Weld
        };
        let s = x[self.joint_columns[li]] / self.model.scale;
        let [f, g] = l.faces;
        joint_record(
            [a, b],
            [self.cut_inset(f), self.cut_inset(g)],
            l.slots,
            s,
            kind,
            self.options.thickness,
        )
    }

    /// How far face `f`'s primary plate is cut back from its tile's sides: half the joint
    /// slot where a bridge joins the next unit of its strip.
    pub(super) fn cut_inset(&self, f: usize) -> [Real; 4] {
        let half = self.model.cut.map_or(0.0, |c| c.plate_inset());
        self.side_links[f].map(|l| match l {
            Some(li) if self.bridges[li] => half,
            _ => 0.0,
        })
    }

    /// Raise the weight of every joint outside its limits (margin included); false when
    /// none is, or every such joint's weight is at its cap.
    pub(super) fn emphasise(&mut self, x: &[Real], units: &[UnitPoints]) -> bool {
        let lim = self.options.limits.within(MARGIN);
        let mut raised = false;
        for (li, j) in self.records(x, units).iter().enumerate() {
            if !lim.holds(j) && self.emphasis[li] < EMPHASIS_MAX {
                self.emphasis[li] = (self.emphasis[li] * 3.0).min(EMPHASIS_MAX);
                raised = true;
            }
        }
        raised
    }

    pub(super) fn energy(&self, x: &[Real], units: &[UnitPoints]) -> Real {
        self.energies(x, units).total
    }

    pub(super) fn energies(&self, x: &[Real], units: &[UnitPoints]) -> Energy {
        let mut e = Energy::default();
        self.visit(x, units, &mut e);
        e
    }

    /// The largest diagonal distance of a hub face at `x` over its mean side.
    pub(super) fn planarity(&self, x: &[Real]) -> Real {
        (0..self.faces.len())
            .map(|f| {
                let q = self.quad(x, f);
                let mean = (0..4).map(|k| (q[(k + 1) % 4] - q[k]).norm()).sum::<Real>() / 4.0;
                sv_geom::quad_diagonal_distance(&q) / mean
            })
            .fold(0.0, Real::max)
    }

    pub(super) fn figures(&self, x: &[Real], units: &[UnitPoints]) -> JointFigures {
        let mut fig = JointFigures {
            planarity: self.planarity(x),
            ..JointFigures::default()
        };
        for (v, a) in self.anchors.iter().enumerate() {
            let p = Point3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
            fig.closeness = fig.closeness.max((p - a.point).dot(&a.normal).abs());
        }
        let laps: Vec<Real> = self
            .links
            .iter()
            .map(|l| {
                let ([f, g], [k, m]) = (l.faces, l.slots);
                let (hf, hg) = (units[f].hub_plate(), units[g].hub_plate());
                hub_overlap(&centroid4(&hf), &hf[k], &centroid4(&hg), &hg[m])
            })
            .collect();
        fig.measured(&self.records(x, units), &laps)
    }
}

/// The joint at `s` along tile `a`'s side `k`, facing tile `b`'s side `m`
/// (`[a, b]`, `[k, m]`), measured; at a weld on the plates as cut (`plate_as_cut` with
/// `insets`): the gap from the joint point to `b`'s plate, and how far either plate's side
/// reaches into the other.
pub(crate) fn joint_record(
    [a, b]: [&[Point3; 4]; 2],
    insets: [[Real; 4]; 2],
    [k, m]: [usize; 2],
    s: Real,
    kind: JointKind,
    thickness: Real,
) -> JointRecord {
    let (k1, m1) = ((k + 1) % 4, (m + 1) % 4);
    let w = a[k] + (a[k1] - a[k]) * s;
    let on_b = segment_closest(&w, &w, &b[m], &b[m1]);
    let (bend, twist) = hinge_turn(a, k, b, m);
    let (ac, bc) = (plate_as_cut(a, insets[0]), plate_as_cut(b, insets[1]));
    let collision = facing_reach(&ac, k, &bc, m, thickness);
    let gap = match kind {
        JointKind::Bridge => on_b.distance,
        JointKind::Weld => edge_to_plate(&ac, &w, &bc, thickness).norm(),
    };
    JointRecord {
        kind,
        along: [s, on_b.t],
        gap,
        bend,
        twist,
        collision,
    }
}

/// Longest edge / shortest edge of a quad.
pub(super) fn edge_ratio(q: &[Point3; 4]) -> Real {
    let e = [0, 1, 2, 3].map(|k| (q[(k + 1) % 4] - q[k]).norm());
    let lo = e.iter().copied().fold(Real::INFINITY, Real::min);
    e.iter().copied().fold(0.0, Real::max) / lo.max(1e-300)
}

pub(super) fn centroid4(p: &[Point3]) -> Point3 {
    Point3::from(p.iter().fold(Vector3::zeros(), |a, q| a + q.coords) / p.len() as Real)
}

/// Two unit vectors spanning the plane normal to `n`.
pub(super) fn tangents(n: &Vector3) -> (Vector3, Vector3) {
    let helper = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u1 = n.cross(&helper).normalize();
    (u1, n.cross(&u1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The faces of an `n x n` grid of quads, row by row.
    fn grid(n: usize) -> Vec<[usize; 4]> {
        let v = |i: usize, j: usize| j * (n + 1) + i;
        (0..n)
            .flat_map(|j| (0..n).map(move |i| [v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]))
            .collect()
    }

    #[test]
    fn the_units_across_each_inner_vertex_are_its_two_diagonal_pairs() {
        // 3 x 3 faces: 4 inner vertices, each with the two pairs across it
        let faces = grid(3);
        let pairs = diagonals(&faces, 16);
        assert_eq!(pairs.len(), 8, "{pairs:?}");
        for [f, g] in &pairs {
            let shared = faces[*f].iter().filter(|v| faces[*g].contains(v)).count();
            assert_eq!(shared, 1, "{f} {g}");
            // across the vertex: one row and one column apart
            assert_eq!(((f % 3) as i64 - (g % 3) as i64).abs(), 1);
            assert_eq!(((f / 3) as i64 - (g / 3) as i64).abs(), 1);
        }
        // the centre face meets the four corner faces across its corners
        assert_eq!(pairs.iter().filter(|p| p.contains(&4)).count(), 4);
    }
}
