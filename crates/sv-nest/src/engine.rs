//! Optimiser core over one jagua-rs [`Layout`]: sampled bottom-left-fill insertion and an
//! overlap-minimising separator with guided local search (in the spirit of sparrow).

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use jagua_rs::collision_detection::hazards::collector::BasicHazardCollector;
use jagua_rs::collision_detection::hazards::filter::{HazardFilter, NoFilter};
use jagua_rs::collision_detection::hazards::{BasicHazardEntity, HazKey};
use jagua_rs::collision_detection::CDEConfig;
use jagua_rs::entities::{Container, Item, Layout, LayoutSnapshot, PItemKey};
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::geometry::geo_enums::RotationRange;
use jagua_rs::geometry::geo_traits::{CollidesWith, DistanceTo, TransformableFrom};
use jagua_rs::geometry::primitives::{Rect, SPolygon};
use jagua_rs::geometry::shape_modification::{ShapeModifyConfig, ShapeModifyMode};
use jagua_rs::geometry::{DTransformation, OriginalShape};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

pub(crate) type Rng64 = Xoshiro256PlusPlus;

/// Collision-engine settings used for every layout.
pub(crate) const CDE_CONFIG: CDEConfig = CDEConfig {
    quadtree_depth: 4,
    cd_threshold: 16,
    item_surrogate_config: SPSurrogateConfig {
        n_pole_limits: [(64, 0.0), (16, 0.8), (8, 0.9)],
        // the poles checked first, covering half the shape (sparrow's screening)
        ff_pole_area_ratio: 0.5,
        n_ff_piers: 0,
    },
};

/// Share of the time budget (what the set-up leaves of it) that the derived work budgets
/// fill on the reference machine (2 cores, nothing else running): the rest is headroom, so
/// that a machine twice as slow or twice as busy still finishes the same work, and so gives
/// the same layout, within the cap.
pub(crate) const WORK_SHARE_OF_TIME: f64 = 0.4;

/// Stop criterion shared by all phases of one search: a work budget (collision evaluations)
/// decides how far the search goes, so that its result is a function of the input, the
/// options and the seed; the wall clock only caps it. Without a work budget the clock
/// decides (for benchmarks at equal time: not reproducible).
///
/// An evaluation is one candidate placement of a shape tested against a layout (a sample
/// or a descent step of an insertion or a move), counted by [`Budget::spend`], which
/// refuses it once the work is spent: a search never does more evaluations than its
/// budget, even in the middle of a move (the candidates it refuses are not taken).
pub(crate) struct Budget {
    start: Instant,
    limit: Duration,
    work: Option<u64>,
    /// evaluations done (only [`Budget::spend`] and [`Budget::add_helpers`] count them)
    pub evals: u64,
    /// set when the clock, not the work budget, stopped the search
    cut: std::cell::Cell<bool>,
}

impl Budget {
    /// A budget whose clock started at `start` (the stage's clock: set-up included).
    pub fn new(start: Instant, limit: Duration, work: Option<u64>) -> Self {
        Self {
            start,
            limit,
            work,
            evals: 0,
            cut: std::cell::Cell::new(false),
        }
    }
    /// Whether the search must stop: its work is done, or the clock ran out (remembered as
    /// a cut when work was left).
    pub fn done(&self) -> bool {
        if self.work.is_some_and(|w| self.evals >= w) {
            return true;
        }
        if self.start.elapsed() >= self.limit {
            self.cut.set(self.work.is_some());
            return true;
        }
        false
    }
    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }
    /// Whether the clock passed `at` (from the start): a cut, when there is a work budget.
    pub fn clock_passed(&self, at: Duration) -> bool {
        let passed = self.start.elapsed() >= at;
        if passed && self.work.is_some() {
            self.cut.set(true);
        }
        passed
    }
    /// Share of the budget used, 0..1: of the work budget when there is one (never of the
    /// clock, which would make the phases depend on the machine), else of the time.
    pub fn fraction(&self) -> f32 {
        match self.work {
            Some(w) => (self.evals as f64 / w.max(1) as f64).min(1.0) as f32,
            None => {
                (self.start.elapsed().as_secs_f32() / self.limit.as_secs_f32().max(1e-9)).min(1.0)
            }
        }
    }
    /// The work budget, if the work decides.
    pub fn work(&self) -> Option<u64> {
        self.work
    }
    /// One evaluation: `true` and counted while the work budget has one left, `false` (and
    /// not counted) once it is spent. Without a work budget always `true`.
    pub fn spend(&mut self) -> bool {
        if self.work.is_some_and(|w| self.evals >= w) {
            return false;
        }
        self.evals += 1;
        true
    }
    /// Budgets for `n` helper threads of this search: the same clock, and the work this
    /// one has left split between them (the first ones get the remainder), so that their
    /// evaluations together never overrun it whatever each does; a share is a function of
    /// the work done, never of the threads' timing. Without a work budget none of their own.
    pub fn helpers(&self, n: usize) -> Vec<Budget> {
        let n = n.max(1) as u64;
        (0..n)
            .map(|k| {
                let share = self.work.map(|w| {
                    let left = w.saturating_sub(self.evals);
                    left / n + u64::from(k < left % n)
                });
                Budget::new(self.start, self.limit, share)
            })
            .collect()
    }
    /// Counts the evaluations of the helpers made by [`Budget::helpers`].
    pub fn add_helpers(&mut self, helper_evals: impl Iterator<Item = u64>) {
        self.evals += helper_evals.sum::<u64>();
    }
    /// Whether the clock cut the search short of its work budget.
    pub fn was_cut(&self) -> bool {
        self.cut.get()
    }
}

/// A rectangular container (no offset applied).
pub(crate) fn rect_container(r: Rect) -> Container {
    Container::new(
        OriginalShape {
            shape: SPolygon::from(r),
            pre_transform: DTransformation::empty(),
            modify_mode: ShapeModifyMode::Deflate,
            modify_config: ShapeModifyConfig::default(),
        },
        vec![],
        CDE_CONFIG,
    )
    .expect("rectangular container is valid")
}

pub(crate) fn rect(x0: f32, y0: f32, x1: f32, y1: f32) -> Rect {
    Rect::try_new(x0, y0, x1, y1).expect("valid rectangle")
}

/// One placed copy of an item.
#[derive(Clone)]
pub(crate) struct Member {
    /// caller's instance index
    pub inst: usize,
    pub item: Arc<Item>,
    pub pk: PItemKey,
    pub dt: DTransformation,
}

/// A layout with its members.
#[derive(Clone)]
pub(crate) struct Bin {
    pub layout: Layout,
    pub members: Vec<Member>,
    pub bounds: Rect,
    idx_of: HashMap<PItemKey, usize>,
    /// copies of the layout a separation moves items on at once (1: this one alone)
    pub workers: usize,
}

/// What one worker's move pass left: the overlapping pairs, their weighted sum, and the
/// evaluations it spent.
struct Pass {
    overlaps: Vec<(usize, usize, f32)>,
    loss: f32,
    evals: u64,
}

/// Snapshot of a [`Bin`].
#[derive(Clone)]
pub(crate) struct BinSnapshot {
    layout: LayoutSnapshot,
    members: Vec<Member>,
    bounds: Rect,
}

struct SkipPk(PItemKey);

impl HazardFilter<BasicHazardEntity> for SkipPk {
    fn is_irrelevant(&self, _: HazKey, e: &BasicHazardEntity) -> bool {
        matches!(e, BasicHazardEntity::PlacedItem { pk, .. } if *pk == self.0)
    }
}

/// Bounding box of `shape` rotated by `rot` about the origin.
pub(crate) fn rotated_bbox(shape: &SPolygon, rot: f32) -> Rect {
    let (s, c) = rot.sin_cos();
    let mut r = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
    for p in shape.vertices() {
        let x = c * p.0 - s * p.1;
        let y = s * p.0 + c * p.1;
        r[0] = r[0].min(x);
        r[1] = r[1].min(y);
        r[2] = r[2].max(x);
        r[3] = r[3].max(y);
    }
    Rect {
        x_min: r[0],
        y_min: r[1],
        x_max: r[2],
        y_max: r[3],
    }
}

/// Rotated bounding boxes of one shape, remembered for the last few rotations: the samples
/// and descent steps of one move or insertion come back to the same rotations, and each box
/// is a pass over every vertex.
struct RotBoxes<'a> {
    shape: &'a SPolygon,
    seen: Vec<(f32, Rect)>,
}

impl<'a> RotBoxes<'a> {
    fn new(shape: &'a SPolygon) -> Self {
        Self {
            shape,
            seen: Vec::with_capacity(8),
        }
    }
    fn get(&mut self, rot: f32) -> Rect {
        if let Some(&(_, rb)) = self.seen.iter().find(|s| s.0 == rot) {
            return rb;
        }
        let rb = rotated_bbox(self.shape, rot);
        if self.seen.len() == 8 {
            self.seen.remove(0);
        }
        self.seen.push((rot, rb));
        rb
    }
}

pub(crate) fn sample_rotation(item: &Item, rng: &mut Rng64) -> f32 {
    match item.allowed_orientations().rotations() {
        RotationRange::None => 0.0,
        RotationRange::Discrete(a) => a[rng.random_range(0..a.len())],
        RotationRange::Continuous => rng.random_range(0.0..std::f32::consts::TAU),
    }
}

/// A transformation with rotation `rot` and translation uniformly sampled so that the rotated
/// bounding box `rb` lies in `area`.
fn sample_in(rb: Rect, rot: f32, area: Rect, rng: &mut Rng64) -> Option<DTransformation> {
    let (x0, x1) = (area.x_min - rb.x_min, area.x_max - rb.x_max);
    let (y0, y1) = (area.y_min - rb.y_min, area.y_max - rb.y_max);
    if x1 < x0 || y1 < y0 {
        return None;
    }
    let tx = if x1 > x0 {
        rng.random_range(x0..=x1)
    } else {
        x0
    };
    let ty = if y1 > y0 {
        rng.random_range(y0..=y1)
    } else {
        y0
    };
    Some(DTransformation::new(rot, (tx, ty)))
}

/// A transformation with rotation `rot` whose translation (the item's reference point) is
/// uniform in `focus` (the item's current box) and keeps the rotated bbox `rb` inside
/// `area` (sparrow's focussed sampler); `None` when no such translation exists.
fn sample_around(
    rb: Rect,
    rot: f32,
    focus: Rect,
    area: Rect,
    rng: &mut Rng64,
) -> Option<DTransformation> {
    let (x0, x1) = (
        focus.x_min.max(area.x_min - rb.x_min),
        focus.x_max.min(area.x_max - rb.x_max),
    );
    let (y0, y1) = (
        focus.y_min.max(area.y_min - rb.y_min),
        focus.y_max.min(area.y_max - rb.y_max),
    );
    if x1 < x0 || y1 < y0 {
        return None;
    }
    Some(DTransformation::new(
        rot,
        (rng.random_range(x0..=x1), rng.random_range(y0..=y1)),
    ))
}

/// Clamps a transformation so the rotated bbox `rb` stays inside `area` where possible.
fn clamp_in(rb: Rect, rot: f32, t: (f32, f32), area: Rect) -> DTransformation {
    let cl = |v: f32, lo: f32, hi: f32| if hi < lo { lo } else { v.clamp(lo, hi) };
    DTransformation::new(
        rot,
        (
            cl(t.0, area.x_min - rb.x_min, area.x_max - rb.x_max),
            cl(t.1, area.y_min - rb.y_min, area.y_max - rb.y_max),
        ),
    )
}

/// `dt` with its rotation replaced by the nearest rotation the item allows.
fn closest_allowed(item: &Item, dt: DTransformation) -> DTransformation {
    let r = match item.allowed_orientations().rotations() {
        RotationRange::None => 0.0,
        RotationRange::Discrete(a) => a
            .iter()
            .copied()
            .min_by(|x, y| {
                let d = |r: f32| jagua_rs::geometry::normalize_rotation(dt.rotation() - r).abs();
                d(*x).total_cmp(&d(*y))
            })
            .unwrap_or(0.0),
        RotationRange::Continuous => dt.rotation(),
    };
    DTransformation::new(r, dt.translation())
}

/// [`pair_overlap_with`] loading `a`'s poles.
#[cfg(test)]
fn pair_overlap(a: &SPolygon, b: &SPolygon) -> f32 {
    let mut cols = PoleColumns::default();
    cols.load(a);
    pair_overlap_with(a, &cols, b)
}

/// The overlap of two shapes as in sparrow (Gardeyn & Wauters), with `a`'s poles in
/// columns (`cols`): a pole-based proxy of the overlap area, where pole pairs that just
/// touch or miss still count a little (penetration depth decayed below `eps` = 1 % of the
/// larger diameter), square-rooted and scaled by the geometric mean of the shapes' sizes,
/// so a collision between two big items weighs more than between two small ones and the
/// proxy never drops to zero while they collide.
fn pair_overlap_with(a: &SPolygon, cols: &PoleColumns, b: &SPolygon) -> f32 {
    let eps = a.diameter().max(b.diameter()) * 0.01;
    let proxy = std::f32::consts::PI * cols.overlap(b, eps) + eps * eps;
    proxy.sqrt() * size_penalty(a, b)
}

/// The scratch of a collision query: the hazards found and the queried shape's poles.
#[derive(Default)]
pub(crate) struct Probe {
    collector: BasicHazardCollector,
    poles: PoleColumns,
}

/// Lanes of [`PoleColumns`]: the pole pairs of two shapes are summed this many at a time.
const LANES: usize = 8;

/// One shape's poles as columns of centres and radii, padded to whole [`LANES`] with
/// poles of radius 0 (which add nothing), so that the sum over every pair of poles of two
/// shapes, the hot loop of the separator, runs on vector lanes.
#[derive(Default)]
pub(crate) struct PoleColumns {
    x: Vec<f32>,
    y: Vec<f32>,
    r: Vec<f32>,
}

impl PoleColumns {
    /// Loads `s`'s poles.
    fn load(&mut self, s: &SPolygon) {
        let poles = &s.surrogate().poles;
        let n = poles.len().div_ceil(LANES) * LANES;
        for v in [&mut self.x, &mut self.y, &mut self.r] {
            v.clear();
            v.resize(n, 0.0);
        }
        for (k, p) in poles.iter().enumerate() {
            self.x[k] = p.center.0;
            self.y[k] = p.center.1;
            self.r[k] = p.radius;
        }
    }

    /// The sum over every pole pair of these poles and `b`'s of the penetration depth
    /// (decayed below `eps`) times the smaller radius.
    fn overlap(&self, b: &SPolygon, eps: f32) -> f32 {
        let mut acc = [0.0f32; LANES];
        let lanes = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.r.chunks_exact(LANES));
        for q in &b.surrogate().poles {
            let (qx, qy, qr) = (q.center.0, q.center.1, q.radius);
            for ((x, y), r) in lanes.clone() {
                for l in 0..LANES {
                    let (dx, dy) = (x[l] - qx, y[l] - qy);
                    let pd = r[l] + qr - (dx * dx + dy * dy).sqrt();
                    let pd = if pd >= eps {
                        pd
                    } else {
                        eps * eps / (2.0 * eps - pd)
                    };
                    acc[l] += pd * r[l].min(qr);
                }
            }
        }
        acc.iter().sum()
    }
}

/// Geometric mean of the square roots of the convex hull areas.
fn size_penalty(a: &SPolygon, b: &SPolygon) -> f32 {
    (a.surrogate().convex_hull_area.sqrt() * b.surrogate().convex_hull_area.sqrt()).sqrt()
}

/// Overlap of a shape with the outside of the container: the bbox area outside it (or, when
/// entirely outside, its area plus the distance to the container).
fn ext_overlap(s: &SPolygon, b: Rect) -> f32 {
    let sb = s.bbox();
    let o = match Rect::intersection(sb, b) {
        Some(inside) => sb.area() - inside.area() + 1e-4 * sb.area(),
        None => sb.area() + sb.centroid().distance_to(&b.centroid()),
    };
    2.0 * o.max(0.0).sqrt() * size_penalty(s, s)
}

/// Up to `cap` best distinct samples of one move (closer than `unique` in translation and with
/// the same rotation counts as the same sample; the better one is kept).
struct BestSamples {
    cap: usize,
    unique: f32,
    v: Vec<(f32, DTransformation)>,
}

impl BestSamples {
    fn new(cap: usize, unique: f32) -> Self {
        Self {
            cap,
            unique,
            v: Vec::with_capacity(cap + 1),
        }
    }
    fn upper(&self) -> f32 {
        if self.v.len() < self.cap {
            f32::MAX
        } else {
            self.v.last().map_or(f32::MAX, |s| s.0)
        }
    }
    fn report(&mut self, dt: DTransformation, e: f32) {
        if e >= self.upper() {
            return;
        }
        let (tx, ty) = dt.translation();
        if let Some(k) = self.v.iter().position(|(_, o)| {
            let (ox, oy) = o.translation();
            o.rotation() == dt.rotation() && (ox - tx).hypot(oy - ty) < self.unique
        }) {
            if e >= self.v[k].0 {
                return;
            }
            self.v.remove(k);
        }
        let at = self.v.partition_point(|s| s.0 <= e);
        self.v.insert(at, (e, dt));
        self.v.truncate(self.cap);
    }
}

/// Step schedule of one coordinate descent (sparrow: steps grow x1.1 on success, halve on
/// failure, and the axis is redrawn after every failure).
#[derive(Clone, Copy)]
struct Descent {
    t0: f32,
    t_min: f32,
    r0: f32,
    r_min: f32,
    wiggle: bool,
}

/// Coordinate descent from `start` on the translation (and rotation when `wiggle`), with
/// candidates evaluated by `eval(dt, upper)`. Never returns a worse sample than `start`.
fn descend(
    start: (f32, DTransformation),
    cfg: Descent,
    eval: &mut dyn FnMut(DTransformation, f32) -> f32,
    rng: &mut Rng64,
) -> (f32, DTransformation) {
    let (mut e, mut pos) = start;
    let (mut sx, mut sy, mut sr) = (cfg.t0, cfg.t0, cfg.r0);
    let n_axes = if cfg.wiggle { 6 } else { 4 };
    let mut axis = rng.random_range(0..n_axes);
    for _ in 0..400 {
        if sx < cfg.t_min && sy < cfg.t_min && (!cfg.wiggle || sr < cfg.r_min) {
            break;
        }
        let (tx, ty) = pos.translation();
        let r = pos.rotation();
        let c = match axis {
            0 => [(tx + sx, ty, r), (tx - sx, ty, r)],
            1 => [(tx, ty + sy, r), (tx, ty - sy, r)],
            2 => [(tx + sx, ty + sy, r), (tx - sx, ty - sy, r)],
            3 => [(tx - sx, ty + sy, r), (tx + sx, ty - sy, r)],
            _ => [(tx, ty, r + sr), (tx, ty, r - sr)],
        }
        .map(|(x, y, r)| DTransformation::new(r, (x, y)));
        let e0 = eval(c[0], e);
        let e1 = eval(c[1], e);
        let (ce, cd) = if e0 <= e1 { (e0, c[0]) } else { (e1, c[1]) };
        let better = ce < e;
        if ce <= e {
            (e, pos) = (ce, cd);
        }
        let m: f32 = if better { 1.1 } else { 0.5 };
        match axis {
            0 => sx *= m,
            1 => sy *= m,
            2 | 3 => {
                sx *= m.sqrt();
                sy *= m.sqrt();
            }
            _ => sr *= m,
        }
        if !better {
            axis = rng.random_range(0..n_axes);
        }
    }
    (e, pos)
}

/// Guided-local-search weights per pair (index `n` = container exterior).
struct Gls {
    n: usize,
    w: Vec<f32>,
}

impl Gls {
    fn new(n: usize) -> Self {
        Self {
            n,
            w: vec![1.0; (n + 1) * (n + 1)],
        }
    }
    fn get(&self, i: usize, j: usize) -> f32 {
        self.w[i * (self.n + 1) + j]
    }
    fn set(&mut self, i: usize, j: usize, v: f32) {
        self.w[i * (self.n + 1) + j] = v;
        self.w[j * (self.n + 1) + i] = v;
    }
    /// Raises the weight of every colliding pair in `ov` by 1.2-2x (the most for the largest
    /// overlap; capped so weighted sums stay finite when a pair never separates) and decays
    /// all other weights by 0.95 towards 1.
    fn update(&mut self, ov: &[(usize, usize, f32)]) {
        let max_o = ov.iter().map(|o| o.2).fold(0.0, f32::max);
        let raised: Vec<(usize, usize, f32)> = ov
            .iter()
            .map(|&(i, j, o)| (i, j, (self.get(i, j) * (1.2 + 0.8 * o / max_o)).min(1e15)))
            .collect();
        for w in &mut self.w {
            *w = (*w * 0.95).max(1.0);
        }
        for (i, j, w) in raised {
            self.set(i, j, w);
        }
    }
}

impl Bin {
    pub fn new(bounds: Rect) -> Self {
        Self {
            layout: Layout::new(rect_container(bounds)),
            members: Vec::new(),
            bounds,
            idx_of: HashMap::new(),
            workers: 1,
        }
    }

    pub fn save(&self) -> BinSnapshot {
        BinSnapshot {
            layout: self.layout.save(),
            members: self.members.clone(),
            bounds: self.bounds,
        }
    }

    pub fn restore(&mut self, s: &BinSnapshot) {
        if self.layout.restore(&s.layout).is_err() {
            self.layout = Layout::from_snapshot(&s.layout);
        }
        self.members.clone_from(&s.members);
        self.bounds = s.bounds;
        self.reindex();
    }

    fn reindex(&mut self) {
        self.idx_of = self
            .members
            .iter()
            .enumerate()
            .map(|(i, m)| (m.pk, i))
            .collect();
    }

    /// Changes the container rectangle, keeping the items where they are.
    pub fn set_bounds(&mut self, bounds: Rect) {
        self.layout.swap_container(rect_container(bounds));
        self.bounds = bounds;
    }

    pub fn add(&mut self, inst: usize, item: &Arc<Item>, dt: DTransformation) {
        let pk = self.layout.place_item(item, dt);
        self.idx_of.insert(pk, self.members.len());
        self.members.push(Member {
            inst,
            item: Arc::clone(item),
            pk,
            dt,
        });
    }

    /// Adds `item` at a random allowed rotation and a random place inside the bounds,
    /// overlaps and all (for a separation to resolve).
    pub fn add_anywhere(&mut self, inst: usize, item: &Arc<Item>, rng: &mut Rng64) {
        let rot = sample_rotation(item, rng);
        let rb = rotated_bbox(item.shape_cd(), rot);
        let dt = sample_in(rb, rot, self.bounds, rng)
            .unwrap_or_else(|| clamp_in(rb, rot, (0.0, 0.0), self.bounds));
        self.add(inst, item, dt);
    }

    pub fn remove(&mut self, i: usize) -> Member {
        self.layout.remove_item(self.members[i].pk);
        let m = self.members.swap_remove(i);
        self.reindex();
        m
    }

    pub fn relocate(&mut self, i: usize, dt: DTransformation) {
        let old = self.members[i].pk;
        self.layout.remove_item(old);
        self.idx_of.remove(&old);
        let pk = self.layout.place_item(&self.members[i].item, dt);
        self.members[i].pk = pk;
        self.members[i].dt = dt;
        self.idx_of.insert(pk, i);
    }

    pub fn placed_shape(&self, i: usize) -> &SPolygon {
        self.layout.placed_items()[self.members[i].pk].shape()
    }

    /// Largest x of the placed shapes (the bounds' x_min when empty).
    pub fn used_x_max(&self) -> f32 {
        (0..self.members.len())
            .map(|i| self.placed_shape(i).bbox().x_max)
            .fold(self.bounds.x_min, f32::max)
    }

    pub fn area(&self) -> f32 {
        self.members.iter().map(|m| m.item.area()).sum()
    }

    /// Bottom-left-fill insertion: `n_samples` random feasible positions scored by x then y,
    /// refined by a shrinking-step descent. Samples are drawn left of `x_limit`, then (when
    /// none was feasible) half as many anywhere.
    /// Returns the transformation, or `None` if no feasible position was found.
    pub fn blf_position(
        &self,
        item: &Arc<Item>,
        n_samples: usize,
        x_limit: f32,
        rng: &mut Rng64,
        budget: &mut Budget,
    ) -> Option<DTransformation> {
        self.blf_position_behind(item, n_samples, x_limit, None, rng, budget)
    }

    /// [`Bin::blf_position`] where, with `front` given, a place that does not reach right of
    /// `front` (the filled front of a sheet) costs nothing in x: of those the lowest wins,
    /// then the leftmost (scores `(max(x_max, front), y_max, x_max)` compared in order), so
    /// that a part slides down and sideways into the room behind the front instead of
    /// stopping on the first part below it. Without `front`: x first, then y.
    pub fn blf_position_behind(
        &self,
        item: &Arc<Item>,
        n_samples: usize,
        x_limit: f32,
        front: Option<f32>,
        rng: &mut Rng64,
        budget: &mut Budget,
    ) -> Option<DTransformation> {
        let mut buf: SPolygon = item.shape_cd().as_ref().clone();
        let height = (self.bounds.y_max - self.bounds.y_min).max(1e-6);
        let score = |rb: &Rect, t: (f32, f32)| -> (f32, f32, f32) {
            let (x, y) = (t.0 + rb.x_max, t.1 + rb.y_max);
            match front {
                Some(f) => (x.max(f), y, x),
                None => (x + 0.05 * y / height, 0.0, 0.0),
            }
        };
        let area = Rect {
            x_max: x_limit.clamp(self.bounds.x_min, self.bounds.x_max),
            ..self.bounds
        };
        let mut best: Option<((f32, f32, f32), DTransformation)> = None;
        let cde = self.layout.cde();
        let feasible = |dt: &DTransformation, buf: &mut SPolygon, budget: &mut Budget| {
            // a candidate the spent budget refuses is not taken
            if !budget.spend() {
                return false;
            }
            buf.transform_from(item.shape_cd(), &dt.compose());
            !cde.detect_poly_collision(buf, &NoFilter)
        };
        let mut boxes = RotBoxes::new(item.shape_cd());
        let mut area_try = area;
        let mut samples = n_samples;
        for attempt in 0..2 {
            for _ in 0..samples {
                let rot = sample_rotation(item, rng);
                let rb = boxes.get(rot);
                let Some(dt) = sample_in(rb, rot, area_try, rng) else {
                    continue;
                };
                let sc = score(&rb, dt.translation());
                if best.is_some_and(|(b, _)| sc >= b) {
                    continue;
                }
                if feasible(&dt, &mut buf, budget) {
                    best = Some((sc, dt));
                }
            }
            if best.is_some() || attempt == 1 || area_try == self.bounds {
                break;
            }
            // then anywhere, with fewer samples: the front is where a place usually is
            area_try = self.bounds;
            samples = n_samples / 2;
        }
        let (mut best_sc, mut best_dt) = best?;
        // refinement: slide left / down with shrinking steps, at the sampled rotation
        let diam = item.shape_cd().diameter();
        let rot = best_dt.rotation();
        let rb = boxes.get(rot);
        let mut step = 0.25 * diam;
        while step > 0.002 * diam {
            let mut improved = false;
            let (tx, ty) = best_dt.translation();
            for (dx, dy) in [
                (-step, 0.0),
                (0.0, -step),
                (-step, -step),
                (-step, step),
                (0.0, step),
                (step, -step),
            ] {
                let dt = DTransformation::new(rot, (tx + dx, ty + dy));
                let (nx, ny) = dt.translation();
                if nx + rb.x_min < self.bounds.x_min
                    || nx + rb.x_max > self.bounds.x_max
                    || ny + rb.y_min < self.bounds.y_min
                    || ny + rb.y_max > self.bounds.y_max
                {
                    continue;
                }
                let sc = score(&rb, (nx, ny));
                if sc < best_sc && feasible(&dt, &mut buf, budget) {
                    best_sc = sc;
                    best_dt = dt;
                    improved = true;
                    break;
                }
            }
            if !improved {
                step *= 0.5;
            }
        }
        Some(best_dt)
    }

    /// Weighted overlap of member `i` if it had shape `shape` (early exit above `upper`).
    fn eval(
        &self,
        i: usize,
        shape: &SPolygon,
        gls: Option<&Gls>,
        upper: f32,
        probe: &mut Probe,
    ) -> f32 {
        let Probe { collector, poles } = probe;
        collector.clear();
        let mut acc = 0.0;
        let placed = self.layout.placed_items();
        let n = self.members.len();
        // the shape's poles in columns, loaded at its first collision
        let mut loaded = false;
        let mut add = |e: BasicHazardEntity| {
            match e {
                BasicHazardEntity::PlacedItem { pk, .. } => {
                    let j = self.idx_of[&pk];
                    let w = gls.map_or(1.0, |g| g.get(i, j));
                    if !loaded {
                        poles.load(shape);
                        loaded = true;
                    }
                    acc += w * pair_overlap_with(shape, poles, placed[pk].shape());
                }
                BasicHazardEntity::Exterior => {
                    let w = gls.map_or(1.0, |g| g.get(i, n));
                    acc += w * ext_overlap(shape, self.bounds);
                }
                _ => {}
            }
            acc > upper
        };
        let skip = SkipPk(self.members[i].pk);
        let cde = self.layout.cde();
        // the largest poles first (sparrow): a deep overlap is found, and the sample given
        // up, before the edges are traced
        if !cde.collect_surrogate_collisions_until(shape, &skip, collector, &mut add) {
            let _ = cde.collect_poly_collisions_until(shape, &skip, collector, &mut add);
        }
        acc
    }

    /// Per-pair overlaps `(i, j, overlap)` with `j == n` for the exterior.
    fn overlaps(&self, probe: &mut Probe) -> Vec<(usize, usize, f32)> {
        let Probe { collector, poles } = probe;
        let n = self.members.len();
        let placed = self.layout.placed_items();
        let mut out = Vec::new();
        for i in 0..n {
            let shape = self.placed_shape(i);
            collector.clear();
            self.layout.cde().collect_poly_collisions(
                shape,
                &SkipPk(self.members[i].pk),
                collector,
            );
            for (_, e) in collector.iter() {
                match e {
                    BasicHazardEntity::PlacedItem { pk, .. } => {
                        let j = self.idx_of[pk];
                        if j > i {
                            poles.load(shape);
                            out.push((i, j, pair_overlap_with(shape, poles, placed[*pk].shape())));
                        }
                    }
                    BasicHazardEntity::Exterior => {
                        out.push((i, n, ext_overlap(shape, self.bounds)));
                    }
                    _ => {}
                }
            }
        }
        out
    }

    /// [`Bin::overlaps`] after the members marked in `moved` moved from a layout whose
    /// overlaps were `before`: the pairs of two unmoved members keep their overlap, only
    /// the moved members' collisions are looked up (sparrow's collision tracker updates
    /// per move likewise), so a pass costs a query per moved item, not one per item.
    /// The same pairs and overlaps as [`Bin::overlaps`], sorted by pair.
    fn overlaps_after_moves(
        &self,
        before: &[(usize, usize, f32)],
        moved: &[bool],
        probe: &mut Probe,
    ) -> Vec<(usize, usize, f32)> {
        let Probe { collector, poles } = probe;
        let n = self.members.len();
        let placed = self.layout.placed_items();
        let mut out: Vec<(usize, usize, f32)> = before
            .iter()
            .copied()
            .filter(|&(i, j, _)| !moved[i] && (j == n || !moved[j]))
            .collect();
        for i in (0..n).filter(|&i| moved[i]) {
            let shape = self.placed_shape(i);
            collector.clear();
            self.layout.cde().collect_poly_collisions(
                shape,
                &SkipPk(self.members[i].pk),
                collector,
            );
            let mut loaded = false;
            for (_, e) in collector.iter() {
                match e {
                    BasicHazardEntity::PlacedItem { pk, .. } => {
                        let j = self.idx_of[pk];
                        // each pair measured from its lower index, as `overlaps` does; a
                        // pair of two moved members once
                        let other = placed[*pk].shape();
                        if j > i {
                            if !loaded {
                                poles.load(shape);
                                loaded = true;
                            }
                            out.push((i, j, pair_overlap_with(shape, poles, other)));
                        } else if !moved[j] {
                            poles.load(other);
                            loaded = false;
                            out.push((j, i, pair_overlap_with(other, poles, shape)));
                        }
                    }
                    BasicHazardEntity::Exterior => {
                        out.push((i, n, ext_overlap(shape, self.bounds)));
                    }
                    _ => {}
                }
            }
        }
        out.sort_by_key(|x| (x.0, x.1));
        #[cfg(debug_assertions)]
        {
            let mut all = self.overlaps(&mut Probe::default());
            all.sort_by_key(|x| (x.0, x.1));
            debug_assert_eq!(all.len(), out.len(), "pairs {all:?} vs {out:?}");
            for (a, b) in all.iter().zip(&out) {
                debug_assert!(
                    a.0 == b.0 && a.1 == b.1 && (a.2 - b.2).abs() <= 1e-3 * a.2.abs().max(1e-6),
                    "{a:?} vs {b:?}"
                );
            }
        }
        out
    }

    /// Moves member `i` to the position of least weighted overlap found by sampling (sparrow's
    /// search): 25 samples around its current place and 50 anywhere in the container, the 3 best
    /// distinct ones refined by a coarse coordinate descent, the best of those by a fine one.
    fn move_item(
        &mut self,
        i: usize,
        gls: &Gls,
        rng: &mut Rng64,
        budget: &mut Budget,
        probe: &mut Probe,
    ) {
        let item = Arc::clone(&self.members[i].item);
        let cur = self.members[i].dt;
        let cur_cost = self.eval(i, self.placed_shape(i), Some(gls), f32::MAX, probe);
        if cur_cost <= 0.0 {
            return;
        }
        let focus = self.placed_shape(i).bbox();
        let bounds = self.bounds;
        let ib = item.shape_cd().bbox();
        let min_dim = (ib.x_max - ib.x_min).min(ib.y_max - ib.y_min).max(1e-6);
        let wiggle = matches!(
            item.allowed_orientations().rotations(),
            RotationRange::Continuous
        );
        let mut buf: SPolygon = item.shape_cd().as_ref().clone();
        let mut boxes = RotBoxes::new(item.shape_cd());
        // a place partly outside the container is evaluated as it is: the exterior's
        // overlap keeps the descent inside (sparrow)
        let mut evaluate = |dt: DTransformation, upper: f32| {
            // a candidate the spent budget refuses costs too much to be taken
            if !budget.spend() {
                return f32::INFINITY;
            }
            buf.transform_from(item.shape_cd(), &dt.compose());
            self.eval(i, &buf, Some(gls), upper, probe)
        };
        let mut best = BestSamples::new(3, 0.05 * min_dim);
        best.report(cur, cur_cost);
        for k in 0..75 {
            let rot = sample_rotation(&item, rng);
            let rb = boxes.get(rot);
            let dt = if k < 25 {
                sample_around(rb, rot, focus, bounds, rng)
            } else {
                sample_in(rb, rot, bounds, rng)
            };
            if let Some(dt) = dt {
                let e = evaluate(dt, best.upper());
                best.report(dt, e);
            }
        }
        let coarse = Descent {
            t0: 0.25 * min_dim,
            t_min: 0.02 * min_dim,
            r0: 5f32.to_radians(),
            r_min: 1f32.to_radians(),
            wiggle,
        };
        let fine = Descent {
            t0: 0.01 * min_dim,
            t_min: 0.001 * min_dim,
            r0: 0.5f32.to_radians(),
            r_min: 0.05f32.to_radians(),
            wiggle,
        };
        for s in best.v.clone() {
            let (e, dt) = descend(s, coarse, &mut evaluate, rng);
            best.report(dt, e);
        }
        let Some(&start) = best.v.first() else {
            return;
        };
        let (e, dt) = descend(start, fine, &mut evaluate, rng);
        if e < cur_cost && dt != cur {
            self.relocate(i, dt);
        }
    }

    /// Overlap-minimising separation with guided local search (sparrow's separator): every
    /// colliding item is moved to its place of least weighted overlap, the pair weights of the
    /// remaining collisions grow, until the layout is collision-free or `max_strikes` rounds
    /// of `max_no_improve` iterations in a row bring no substantial progress. Returns
    /// `true` when the layout is collision-free; otherwise the least-overlapping state found
    /// is kept.
    pub fn separate(
        &mut self,
        rng: &mut Rng64,
        budget: &mut Budget,
        max_strikes: usize,
        max_no_improve: usize,
    ) -> bool {
        self.separate_loss(rng, budget, max_strikes, max_no_improve) == 0.0
    }

    /// [`Bin::separate`] returning the least total overlap reached: 0 exactly when the layout
    /// is collision-free (the overlap of a colliding pair is always positive).
    pub fn separate_loss(
        &mut self,
        rng: &mut Rng64,
        budget: &mut Budget,
        max_strikes: usize,
        max_no_improve: usize,
    ) -> f32 {
        let n = self.members.len();
        let mut gls = Gls::new(n);
        let mut probe = Probe::default();
        // the other workers' copies of the layout, made at the first pass
        let mut copies: Vec<Bin> = Vec::new();
        let mut ov = self.overlaps(&mut probe);
        if ov.is_empty() {
            return 0.0;
        }
        let total = |ov: &[(usize, usize, f32)]| ov.iter().map(|o| o.2).sum::<f32>();
        let mut min_loss = total(&ov);
        let mut best_snap = self.save();
        let mut strikes = 0;
        while strikes < max_strikes && !budget.done() {
            let strike_start = total(&ov);
            let mut no_imp = 0;
            while no_imp < max_no_improve && !budget.done() {
                let mut colliding: Vec<usize> = ov
                    .iter()
                    .flat_map(|&(i, j, _)| [i, j])
                    .filter(|&k| k < n)
                    .collect();
                colliding.sort_unstable();
                colliding.dedup();
                ov = if self.workers <= 1 {
                    colliding.shuffle(rng);
                    for &i in &colliding {
                        self.move_item(i, &gls, rng, budget, &mut probe);
                    }
                    self.overlaps(&mut probe)
                } else {
                    if copies.is_empty() {
                        copies = (1..self.workers).map(|_| self.clone()).collect();
                    }
                    self.move_pass_on_workers(&mut copies, &colliding, &ov, &gls, rng, budget)
                };
                if ov.is_empty() {
                    return 0.0;
                }
                let loss = total(&ov);
                if loss < min_loss {
                    if loss < 0.98 * min_loss {
                        no_imp = 0;
                    }
                    min_loss = loss;
                    best_snap = self.save();
                } else {
                    no_imp += 1;
                }
                gls.update(&ov);
            }
            if strike_start * 0.98 <= min_loss {
                strikes += 1;
            } else {
                strikes = 0;
            }
            // every round ends in the least-overlapping state (also when it is the last)
            self.restore(&best_snap);
            ov = self.overlaps(&mut probe);
        }
        min_loss
    }

    /// One move pass on [`Bin::workers`] copies of the layout at once (sparrow's
    /// separator workers): each moves the colliding items in its own random order, and the
    /// copy with the least weighted overlap is kept (ties: the first, this one), so the
    /// result does not depend on the threads. Returns its overlaps.
    fn move_pass_on_workers(
        &mut self,
        copies: &mut [Bin],
        colliding: &[usize],
        before: &[(usize, usize, f32)],
        gls: &Gls,
        rng: &mut Rng64,
        budget: &mut Budget,
    ) -> Vec<(usize, usize, f32)> {
        let seeds: Vec<u64> = (0..self.workers).map(|_| rng.random()).collect();
        let n = self.members.len();
        let run = move |bin: &mut Bin, seed: u64, mut b: Budget| {
            let mut rng = <Rng64 as rand::SeedableRng>::seed_from_u64(seed);
            let mut probe = Probe::default();
            let mut order = colliding.to_vec();
            order.shuffle(&mut rng);
            let start: Vec<DTransformation> = bin.members.iter().map(|m| m.dt).collect();
            for &i in &order {
                bin.move_item(i, gls, &mut rng, &mut b, &mut probe);
            }
            let moved: Vec<bool> = bin
                .members
                .iter()
                .zip(&start)
                .map(|(m, dt)| m.dt != *dt)
                .collect();
            let overlaps = bin.overlaps_after_moves(before, &moved, &mut probe);
            let loss = overlaps
                .iter()
                .map(|&(i, j, o)| gls.get(i, j.min(n)) * o)
                .sum();
            Pass {
                overlaps,
                loss,
                evals: b.evals,
            }
        };
        // the copies follow this layout: only the items that differ move
        for c in copies.iter_mut() {
            c.follow(self);
        }
        // on the thread pool (no thread started per pass); in worker order
        let budgets = budget.helpers(self.workers);
        let mut bins: Vec<&mut Bin> = std::iter::once(&mut *self)
            .chain(copies.iter_mut())
            .collect();
        let mut passes: Vec<Pass> = bins
            .par_iter_mut()
            .zip(seeds.par_iter())
            .zip(budgets.into_par_iter())
            .map(|((bin, &seed), b)| run(bin, seed, b))
            .collect();
        drop(bins);
        budget.add_helpers(passes.iter().map(|p| p.evals));
        let best = (1..passes.len()).fold(0, |b, k| {
            if passes[k].loss < passes[b].loss {
                k
            } else {
                b
            }
        });
        if best > 0 {
            std::mem::swap(self, &mut copies[best - 1]);
        }
        passes.swap_remove(best).overlaps
    }

    /// Moves the members that are placed differently in `master` (a copy of this bin whose
    /// members have moved since) to their places there: a copy kept in step with a few
    /// moves instead of a clone of the whole layout.
    fn follow(&mut self, master: &Bin) {
        debug_assert_eq!(self.members.len(), master.members.len());
        if self.bounds != master.bounds {
            self.set_bounds(master.bounds);
        }
        for i in 0..master.members.len() {
            let dt = master.members[i].dt;
            if self.members[i].dt != dt {
                self.relocate(i, dt);
            }
        }
    }

    /// Moves the container's right edge to `x_max`: the items whose bbox centre is right of
    /// `split` move left by the difference, creating overlaps around `split` (sparrow).
    pub fn shrink_at(&mut self, split: f32, x_max: f32) {
        let delta = x_max - self.bounds.x_max;
        for i in 0..self.members.len() {
            let sb = self.placed_shape(i).bbox();
            if 0.5 * (sb.x_min + sb.x_max) > split {
                let dt = self.members[i].dt;
                let (tx, ty) = dt.translation();
                self.relocate(i, DTransformation::new(dt.rotation(), (tx + delta, ty)));
            }
        }
        self.set_bounds(Rect {
            x_max,
            ..self.bounds
        });
    }

    /// Perturbs the layout by swapping two large items (among those holding the largest 75 %
    /// of the convex hull area; the second one differing in size from the first where
    /// possible), as sparrow's exploration does after a failed separation. Items lying mostly
    /// inside a swapped item's old place travel with it.
    pub fn disrupt(&mut self, rng: &mut Rng64) {
        let n = self.members.len();
        if n < 2 {
            return;
        }
        let cha = |m: &Member| m.item.shape_cd().surrogate().convex_hull_area;
        let mut areas: Vec<f32> = self.members.iter().map(cha).collect();
        areas.sort_by(|a, b| b.total_cmp(a));
        let total: f32 = areas.iter().sum();
        let mut acc = 0.0;
        let mut cutoff = 0.0;
        for a in &areas {
            acc += a;
            if acc > 0.75 * total {
                cutoff = *a;
                break;
            }
        }
        let large: Vec<usize> = (0..n)
            .filter(|&k| cha(&self.members[k]) >= cutoff)
            .collect();
        let a = large[rng.random_range(0..large.len())];
        let (aa, ad) = (
            self.members[a].item.area(),
            self.members[a].item.shape_cd().diameter(),
        );
        let differ: Vec<usize> = large
            .iter()
            .copied()
            .filter(|&k| {
                let it = &self.members[k].item;
                (it.area() - aa).abs() > 0.01 * aa
                    && (it.shape_cd().diameter() - ad).abs() > 0.01 * ad
            })
            .collect();
        let b = if differ.is_empty() {
            let k = rng.random_range(0..n - 1);
            if k >= a {
                k + 1
            } else {
                k
            }
        } else {
            differ[rng.random_range(0..differ.len())]
        };
        let (da, db) = (self.members[a].dt, self.members[b].dt);
        // items whose pole of inaccessibility lies in a swapped item's old shape follow it
        let riders = |bin: &Bin, k: usize| -> Vec<usize> {
            let shape = bin.placed_shape(k);
            (0..n)
                .filter(|&j| j != a && j != b)
                .filter(|&j| shape.collides_with(&bin.placed_shape(j).poi().center))
                .collect()
        };
        let na = closest_allowed(&self.members[a].item, db);
        let nb = closest_allowed(&self.members[b].item, da);
        let (ra, rb) = (riders(self, a), riders(self, b));
        self.relocate(a, na);
        self.relocate(b, nb);
        for (list, old, new) in [(ra, da, na), (rb, db, nb)] {
            let carry = old.compose().inverse().transform(&new.compose());
            for j in list {
                let moved = self.members[j].dt.compose().transform(&carry).decompose();
                let moved = closest_allowed(&self.members[j].item, moved);
                self.relocate(j, moved);
            }
        }
    }

    /// Whether the layout is collision-free according to the engine.
    pub fn is_feasible(&self) -> bool {
        self.layout.is_collision_free()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jagua_rs::geometry::primitives::Point;
    use jagua_rs::geometry::AllowedOrientations;
    use rand::SeedableRng;

    /// An L-shaped item (not symmetric, so a turn by 180 degrees is a different placement).
    fn l_item(id: usize, s: f32, rotations: RotationRange) -> Arc<Item> {
        l_item_with(id, s, rotations, CDE_CONFIG.item_surrogate_config)
    }

    fn l_item_with(
        id: usize,
        s: f32,
        rotations: RotationRange,
        surrogate: SPSurrogateConfig,
    ) -> Arc<Item> {
        let pts = [
            (0.0, 0.0),
            (s, 0.0),
            (s, 0.4 * s),
            (0.4 * s, 0.4 * s),
            (0.4 * s, s),
            (0.0, s),
        ];
        let shape = SPolygon::new(pts.iter().map(|&(x, y)| Point(x, y)).collect()).unwrap();
        let orig = OriginalShape {
            shape,
            pre_transform: DTransformation::empty(),
            modify_mode: ShapeModifyMode::Inflate,
            modify_config: ShapeModifyConfig::default(),
        };
        let ao = AllowedOrientations::new(rotations, vec![]).unwrap();
        Arc::new(Item::new(id, id as u64, orig, ao, None, surrogate).unwrap())
    }

    fn placed(item: &Arc<Item>, x: f32, y: f32) -> SPolygon {
        let mut s = item.shape_cd().as_ref().clone();
        s.transform_from(
            item.shape_cd(),
            &DTransformation::new(0.0, (x, y)).compose(),
        );
        s
    }

    #[test]
    fn overlap_grows_with_penetration_and_never_vanishes() {
        let it = l_item(0, 10.0, RotationRange::None);
        let a = placed(&it, 0.0, 0.0);
        let o: Vec<f32> = [9.5, 8.0, 6.0, 4.0, 2.0, 0.0]
            .iter()
            .map(|&x| pair_overlap(&a, &placed(&it, x, 0.0)))
            .collect();
        assert!(o.iter().all(|v| v.is_finite() && *v > 0.0), "{o:?}");
        assert!(o.windows(2).all(|w| w[0] < w[1]), "not increasing: {o:?}");
        // a big pair weighs more than a small pair at the same relative penetration
        let big = l_item(1, 20.0, RotationRange::None);
        let ob = pair_overlap(&placed(&big, 0.0, 0.0), &placed(&big, 8.0, 0.0));
        assert!(ob > o[4], "{ob} vs {}", o[4]);
        // outside the container: more outside, more overlap; inside, none counted
        let cont = rect(0.0, 0.0, 30.0, 30.0);
        let e1 = ext_overlap(&placed(&it, 25.0, 0.0), cont);
        let e2 = ext_overlap(&placed(&it, 28.0, 0.0), cont);
        let e3 = ext_overlap(&placed(&it, 40.0, 0.0), cont);
        assert!(0.0 < e1 && e1 < e2 && e2 < e3, "{e1} {e2} {e3}");
    }

    /// The pole pairs summed in lanes (padded with poles of radius 0) give the sum of the
    /// plain double loop over the poles of both shapes.
    #[test]
    fn pole_columns_sum_every_pole_pair() {
        // five poles each: the lanes are padded
        let five = SPSurrogateConfig {
            n_pole_limits: [(5, 0.0); 3],
            ff_pole_area_ratio: 0.0,
            n_ff_piers: 0,
        };
        let a = l_item_with(0, 10.0, RotationRange::None, five);
        let b = l_item_with(1, 7.0, RotationRange::None, five);
        let (pa, pb) = (placed(&a, 0.0, 0.0), placed(&b, 3.0, 1.0));
        let n = pa.surrogate().poles.len();
        assert!(
            n > 1 && n % LANES != 0,
            "{n} poles: the padding is not tried"
        );
        let eps = 0.1;
        let mut plain = 0.0f64;
        for p in &pa.surrogate().poles {
            for q in &pb.surrogate().poles {
                let d =
                    f64::from(p.center.0 - q.center.0).hypot(f64::from(p.center.1 - q.center.1));
                let pd = f64::from(p.radius + q.radius) - d;
                let e = f64::from(eps);
                let pd = if pd >= e { pd } else { e * e / (2.0 * e - pd) };
                plain += pd * f64::from(p.radius.min(q.radius));
            }
        }
        let mut cols = PoleColumns::default();
        cols.load(&pa);
        let lanes = f64::from(cols.overlap(&pb, eps));
        assert!((lanes - plain).abs() <= 1e-5 * plain, "{lanes} vs {plain}");
    }

    #[test]
    fn best_samples_keep_the_best_distinct_ones() {
        let mut b = BestSamples::new(3, 1.0);
        let dt = |x: f32| DTransformation::new(0.0, (x, 0.0));
        for (x, e) in [
            (0.0, 5.0),
            (0.5, 4.0),
            (10.0, 3.0),
            (20.0, 6.0),
            (30.0, 1.0),
        ] {
            b.report(dt(x), e);
        }
        let got: Vec<(f32, f32)> = b.v.iter().map(|s| (s.0, s.1.translation().0)).collect();
        // (0, 5) was replaced by its better neighbour (0.5, 4); (20, 6) did not make the cut
        assert_eq!(got, vec![(1.0, 30.0), (3.0, 10.0), (4.0, 0.5)]);
        assert_eq!(b.upper(), 4.0);
    }

    #[test]
    fn descent_finds_the_bottom_of_a_bowl_and_never_worsens() {
        let mut rng = Rng64::seed_from_u64(3);
        let mut f = |dt: DTransformation, _upper: f32| {
            let (x, y) = dt.translation();
            (x - 3.0).powi(2) + 2.0 * (y + 1.0).powi(2) + 0.5 * (dt.rotation() - 0.2).powi(2)
        };
        let start_dt = DTransformation::new(0.0, (0.0, 0.0));
        let start = (f(start_dt, f32::MAX), start_dt);
        let cfg = Descent {
            t0: 1.0,
            t_min: 1e-3,
            r0: 0.1,
            r_min: 1e-3,
            wiggle: true,
        };
        let (e, dt) = descend(start, cfg, &mut f, &mut rng);
        assert!(e <= start.0);
        let (x, y) = dt.translation();
        assert!((x - 3.0).abs() < 0.05 && (y + 1.0).abs() < 0.05, "{x} {y}");
        assert!((dt.rotation() - 0.2).abs() < 0.05, "{}", dt.rotation());
    }

    #[test]
    fn separation_pulls_apart_items_dropped_on_one_spot() {
        let rots = RotationRange::Discrete(vec![0.0, std::f32::consts::PI]);
        let mut bin = Bin::new(rect(0.0, 0.0, 40.0, 25.0));
        for k in 0..6 {
            bin.add(
                k,
                &l_item(k, 10.0, rots.clone()),
                DTransformation::new(0.0, (15.0, 8.0)),
            );
        }
        assert!(!bin.is_feasible());
        let mut rng = Rng64::seed_from_u64(1);
        let mut budget = Budget::new(Instant::now(), Duration::from_secs(60), Some(2_000_000));
        let loss = bin.separate_loss(&mut rng, &mut budget, 3, 200);
        assert_eq!(loss, 0.0);
        assert!(bin.is_feasible(), "the engine still sees a collision");
        for m in &bin.members {
            let r = m.dt.rotation();
            assert!(
                r.abs() < 1e-6 || (r.abs() - std::f32::consts::PI).abs() < 1e-5,
                "{r}"
            );
        }
    }

    #[test]
    fn disrupt_swaps_large_items_and_keeps_every_item_with_an_allowed_rotation() {
        let rots = RotationRange::Discrete(vec![0.0, std::f32::consts::PI]);
        let mut bin = Bin::new(rect(0.0, 0.0, 100.0, 30.0));
        let sizes = [20.0, 12.0, 6.0, 6.0, 5.0];
        let mut x = 0.0;
        for (k, s) in sizes.iter().enumerate() {
            let rot = if k % 2 == 0 {
                0.0
            } else {
                std::f32::consts::PI
            };
            let t = if rot == 0.0 { (x, 0.0) } else { (x + s, *s) };
            bin.add(
                k,
                &l_item(k, *s, rots.clone()),
                DTransformation::new(rot, t),
            );
            x += s + 1.0;
        }
        let before: Vec<(usize, DTransformation)> =
            bin.members.iter().map(|m| (m.inst, m.dt)).collect();
        let mut rng = Rng64::seed_from_u64(7);
        bin.disrupt(&mut rng);
        let mut insts: Vec<usize> = bin.members.iter().map(|m| m.inst).collect();
        insts.sort_unstable();
        assert_eq!(insts, vec![0, 1, 2, 3, 4]);
        let moved: Vec<usize> = bin
            .members
            .iter()
            .filter(|m| before.iter().any(|(i, dt)| *i == m.inst && *dt != m.dt))
            .map(|m| m.inst)
            .collect();
        assert!(moved.len() >= 2, "moved {moved:?}");
        // the two largest hold 75 % of the hull area: they are the ones swapped
        assert!(moved.contains(&0) && moved.contains(&1), "moved {moved:?}");
        let pos = |k: usize| bin.members.iter().find(|m| m.inst == k).unwrap().dt;
        let old = |k: usize| before.iter().find(|(i, _)| *i == k).unwrap().1;
        assert_eq!(pos(0).translation(), old(1).translation());
        assert_eq!(pos(1).translation(), old(0).translation());
        for m in &bin.members {
            let r = m.dt.rotation();
            assert!(
                r.abs() < 1e-6 || (r.abs() - std::f32::consts::PI).abs() < 1e-5,
                "{r}"
            );
        }
    }
}
