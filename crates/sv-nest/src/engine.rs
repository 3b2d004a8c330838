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
use jagua_rs::geometry::geo_traits::TransformableFrom;
use jagua_rs::geometry::primitives::{Rect, SPolygon};
use jagua_rs::geometry::shape_modification::{ShapeModifyConfig, ShapeModifyMode};
use jagua_rs::geometry::{DTransformation, OriginalShape};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_xoshiro::Xoshiro256PlusPlus;

pub(crate) type Rng64 = Xoshiro256PlusPlus;

/// Collision-engine settings used for every layout.
pub(crate) const CDE_CONFIG: CDEConfig = CDEConfig {
    quadtree_depth: 4,
    cd_threshold: 16,
    item_surrogate_config: SPSurrogateConfig {
        n_pole_limits: [(64, 0.0), (16, 0.8), (8, 0.9)],
        ff_pole_area_ratio: 0.0,
        n_ff_piers: 0,
    },
};

/// Stop criterion shared by all phases: wall time and number of collision queries.
pub(crate) struct Budget {
    start: Instant,
    limit: Duration,
    max_evals: u64,
    pub evals: u64,
}

impl Budget {
    pub fn new(limit: Duration, max_evals: Option<u64>) -> Self {
        Self {
            start: Instant::now(),
            limit,
            max_evals: max_evals.unwrap_or(u64::MAX),
            evals: 0,
        }
    }
    pub fn done(&self) -> bool {
        self.evals >= self.max_evals || self.start.elapsed() >= self.limit
    }
    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
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

pub(crate) fn sample_rotation(item: &Item, rng: &mut Rng64) -> f32 {
    match item.allowed_orientations().rotations() {
        RotationRange::None => 0.0,
        RotationRange::Discrete(a) => a[rng.random_range(0..a.len())],
        RotationRange::Continuous => rng.random_range(0.0..std::f32::consts::TAU),
    }
}

/// A transformation with rotation `rot` and translation uniformly sampled so that the rotated
/// bounding box lies in `area`.
fn sample_in(item: &Item, rot: f32, area: Rect, rng: &mut Rng64) -> Option<DTransformation> {
    let rb = rotated_bbox(item.shape_cd(), rot);
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

/// Clamps a transformation so the rotated bbox stays inside `area` where possible.
fn clamp_in(item: &Item, rot: f32, t: (f32, f32), area: Rect) -> DTransformation {
    let rb = rotated_bbox(item.shape_cd(), rot);
    let cl = |v: f32, lo: f32, hi: f32| if hi < lo { lo } else { v.clamp(lo, hi) };
    DTransformation::new(
        rot,
        (
            cl(t.0, area.x_min - rb.x_min, area.x_max - rb.x_max),
            cl(t.1, area.y_min - rb.y_min, area.y_max - rb.y_max),
        ),
    )
}

/// Overlap proxy of two shapes: summed pole penetration plus a small constant.
fn pair_overlap(a: &SPolygon, b: &SPolygon) -> f32 {
    let (pa, pb) = (&a.surrogate().poles, &b.surrogate().poles);
    let mut s = 0.0;
    for p in pa {
        for q in pb {
            let dx = p.center.0 - q.center.0;
            let dy = p.center.1 - q.center.1;
            let o = p.radius + q.radius - (dx * dx + dy * dy).sqrt();
            if o > 0.0 {
                s += o.min(2.0 * p.radius.min(q.radius));
            }
        }
    }
    s + 0.01 * a.diameter().min(b.diameter())
}

fn ext_overlap(s: &SPolygon, b: Rect) -> f32 {
    let sb = s.bbox();
    let dx = (b.x_min - sb.x_min).max(0.0) + (sb.x_max - b.x_max).max(0.0);
    let dy = (b.y_min - sb.y_min).max(0.0) + (sb.y_max - b.y_max).max(0.0);
    2.0 * (dx + dy) + 0.01 * s.diameter()
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
}

impl Bin {
    pub fn new(bounds: Rect) -> Self {
        Self {
            layout: Layout::new(rect_container(bounds)),
            members: Vec::new(),
            bounds,
            idx_of: HashMap::new(),
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
    /// refined by a shrinking-step descent. Samples are drawn left of `x_limit`.
    /// Returns the transformation, or `None` if no feasible position was found.
    pub fn blf_position(
        &self,
        item: &Arc<Item>,
        n_samples: usize,
        x_limit: f32,
        rng: &mut Rng64,
        budget: &mut Budget,
    ) -> Option<DTransformation> {
        let mut buf: SPolygon = item.shape_cd().as_ref().clone();
        let height = (self.bounds.y_max - self.bounds.y_min).max(1e-6);
        let score = |rb: &Rect, t: (f32, f32)| (t.0 + rb.x_max) + 0.05 * (t.1 + rb.y_max) / height;
        let area = Rect {
            x_max: x_limit.clamp(self.bounds.x_min, self.bounds.x_max),
            ..self.bounds
        };
        let mut best: Option<(f32, DTransformation)> = None;
        let cde = self.layout.cde();
        let feasible = |dt: &DTransformation, buf: &mut SPolygon, budget: &mut Budget| {
            budget.evals += 1;
            buf.transform_from(item.shape_cd(), &dt.compose());
            !cde.detect_poly_collision(buf, &NoFilter)
        };
        let mut area_try = area;
        for attempt in 0..2 {
            for _ in 0..n_samples {
                let rot = sample_rotation(item, rng);
                let Some(dt) = sample_in(item, rot, area_try, rng) else {
                    continue;
                };
                let rb = rotated_bbox(item.shape_cd(), rot);
                let sc = score(&rb, dt.translation());
                if best.is_some_and(|(b, _)| sc >= b) {
                    continue;
                }
                if feasible(&dt, &mut buf, budget) {
                    best = Some((sc, dt));
                }
            }
            if best.is_some() || attempt == 1 {
                break;
            }
            area_try = self.bounds;
        }
        let (mut best_sc, mut best_dt) = best?;
        // refinement: slide left / down with shrinking steps, and try other rotations nearby
        let diam = item.shape_cd().diameter();
        let mut step = 0.25 * diam;
        while step > 0.002 * diam {
            let mut improved = false;
            let rot = best_dt.rotation();
            let (tx, ty) = best_dt.translation();
            for (dx, dy) in [
                (-step, 0.0),
                (0.0, -step),
                (-step, -step),
                (-step, step),
                (0.0, step),
            ] {
                let dt = DTransformation::new(rot, (tx + dx, ty + dy));
                let rb = rotated_bbox(item.shape_cd(), rot);
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
        collector: &mut BasicHazardCollector,
    ) -> f32 {
        collector.clear();
        let mut acc = 0.0;
        let placed = self.layout.placed_items();
        let n = self.members.len();
        let _ = self.layout.cde().collect_poly_collisions_until(
            shape,
            &SkipPk(self.members[i].pk),
            collector,
            |e| {
                match e {
                    BasicHazardEntity::PlacedItem { pk, .. } => {
                        let j = self.idx_of[&pk];
                        let w = gls.map_or(1.0, |g| g.get(i, j));
                        acc += w * pair_overlap(shape, placed[pk].shape());
                    }
                    BasicHazardEntity::Exterior => {
                        let w = gls.map_or(1.0, |g| g.get(i, n));
                        acc += w * ext_overlap(shape, self.bounds);
                    }
                    _ => {}
                }
                acc > upper
            },
        );
        acc
    }

    /// Per-pair overlaps `(i, j, overlap)` with `j == n` for the exterior.
    fn overlaps(&self, collector: &mut BasicHazardCollector) -> Vec<(usize, usize, f32)> {
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
                            out.push((i, j, pair_overlap(shape, placed[*pk].shape())));
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

    /// Moves member `i` to the position of least weighted overlap found by sampling.
    fn move_item(
        &mut self,
        i: usize,
        gls: &Gls,
        rng: &mut Rng64,
        budget: &mut Budget,
        collector: &mut BasicHazardCollector,
    ) {
        let item = Arc::clone(&self.members[i].item);
        let cur = self.members[i].dt;
        let cur_cost = self.eval(i, self.placed_shape(i), Some(gls), f32::MAX, collector);
        if cur_cost <= 0.0 {
            return;
        }
        let mut buf: SPolygon = item.shape_cd().as_ref().clone();
        let mut best = (cur_cost, cur);
        let mut try_dt = |dt: DTransformation, best: &mut (f32, DTransformation)| {
            budget.evals += 1;
            buf.transform_from(item.shape_cd(), &dt.compose());
            let c = self.eval(i, &buf, Some(gls), best.0, collector);
            if c < best.0 {
                *best = (c, dt);
            }
        };
        let diam = item.shape_cd().diameter();
        let continuous = matches!(
            item.allowed_orientations().rotations(),
            RotationRange::Continuous
        );
        for _ in 0..48 {
            let rot = sample_rotation(&item, rng);
            if let Some(dt) = sample_in(&item, rot, self.bounds, rng) {
                try_dt(dt, &mut best);
            }
        }
        for k in 0..48 {
            let s = if k < 24 { 0.25 * diam } else { 0.05 * diam };
            let (tx, ty) = best.1.translation();
            let rot = if continuous {
                best.1.rotation() + rng.random_range(-0.1f32..0.1)
            } else if rng.random_bool(0.15) {
                sample_rotation(&item, rng)
            } else {
                best.1.rotation()
            };
            let t = (tx + rng.random_range(-s..=s), ty + rng.random_range(-s..=s));
            try_dt(clamp_in(&item, rot, t, self.bounds), &mut best);
        }
        let mut step = 0.02 * diam;
        while step > 0.0005 * diam && best.0 > 0.0 {
            let (tx, ty) = best.1.translation();
            let rot = best.1.rotation();
            let before = best.0;
            for (dx, dy) in [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)] {
                try_dt(
                    clamp_in(&item, rot, (tx + dx, ty + dy), self.bounds),
                    &mut best,
                );
                if best.0 < before {
                    break;
                }
            }
            if best.0 >= before {
                step *= 0.5;
            }
        }
        if best.1 != cur {
            self.relocate(i, best.1);
        }
    }

    /// Overlap-minimising separation with guided local search. Returns `true` when the
    /// layout is collision-free; otherwise the least-overlapping state found is kept.
    pub fn separate(
        &mut self,
        rng: &mut Rng64,
        budget: &mut Budget,
        max_strikes: usize,
        max_no_improve: usize,
    ) -> bool {
        let n = self.members.len();
        let mut gls = Gls::new(n);
        let mut collector = BasicHazardCollector::new();
        let mut ov = self.overlaps(&mut collector);
        if ov.is_empty() {
            return true;
        }
        let mut best_total: f32 = ov.iter().map(|o| o.2).sum();
        let mut best_snap = self.save();
        let (mut strikes, mut no_imp) = (0, 0);
        loop {
            if budget.done() {
                self.restore(&best_snap);
                return false;
            }
            let mut colliding: Vec<usize> = ov
                .iter()
                .flat_map(|&(i, j, _)| [i, j])
                .filter(|&k| k < n)
                .collect();
            colliding.sort_unstable();
            colliding.dedup();
            colliding.shuffle(rng);
            for &i in &colliding {
                self.move_item(i, &gls, rng, budget, &mut collector);
            }
            ov = self.overlaps(&mut collector);
            if ov.is_empty() {
                return true;
            }
            let total: f32 = ov.iter().map(|o| o.2).sum();
            let max_o = ov.iter().map(|o| o.2).fold(0.0, f32::max);
            let mut hit = vec![false; (n + 1) * (n + 1)];
            for &(i, j, o) in &ov {
                let w = gls.get(i, j) * (1.2 + 0.8 * o / max_o);
                gls.set(i, j, w);
                hit[i * (n + 1) + j] = true;
                hit[j * (n + 1) + i] = true;
            }
            for (k, w) in gls.w.iter_mut().enumerate() {
                if !hit[k] {
                    *w = (*w * 0.95).max(1.0);
                }
            }
            if total < best_total * 0.999 {
                best_total = total;
                best_snap = self.save();
                no_imp = 0;
            } else {
                no_imp += 1;
                if no_imp > max_no_improve {
                    strikes += 1;
                    self.restore(&best_snap);
                    if strikes >= max_strikes {
                        return false;
                    }
                    ov = self.overlaps(&mut collector);
                    no_imp = 0;
                }
            }
        }
    }

    /// Whether the layout is collision-free according to the engine.
    pub fn is_feasible(&self) -> bool {
        self.layout.is_collision_free()
    }
}
