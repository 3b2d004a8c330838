//! Strip packing: fixed height, minimise the used length (ESICUP / jagua-rs `spp` instances).

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use jagua_rs::entities::Item;
use jagua_rs::geometry::geo_enums::RotationRange;
use jagua_rs::geometry::primitives::Rect;
use jagua_rs::geometry::DTransformation;
use jagua_rs::io::export::int_to_ext_transformation;
use jagua_rs::io::import::Importer;
use jagua_rs::probs::spp::io::ext_repr::ExtSPInstance;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::engine::{rect, rotated_bbox, Bin, Budget, Rng64, CDE_CONFIG};
use crate::NestError;

/// A strip-packing instance: items with demands and a fixed strip height.
#[derive(Clone, Debug)]
pub struct StripInstance {
    /// instance name
    pub name: String,
    /// strip height (y extent)
    pub height: f32,
    /// minimum distance between items and from the strip border
    pub min_item_separation: f32,
    /// items (jagua-rs, already inflated by half the separation) and their demands
    pub items: Vec<(Arc<Item>, usize)>,
}

impl StripInstance {
    /// Parses a jagua-rs >= 1.0 `ExtSPInstance` JSON string.
    pub fn from_json(text: &str) -> Result<Self, NestError> {
        let ext: ExtSPInstance =
            serde_json::from_str(text).map_err(|e| NestError::Instance(e.to_string()))?;
        // conservative simplification for collision checks (shapes only grow), as sparrow does
        let importer = Importer::new(CDE_CONFIG, Some(0.001), Some((0.01, 0.01)));
        let inst = jagua_rs::probs::spp::io::import_instance(&importer, &ext)
            .map_err(|e| NestError::Instance(format!("{}: {e:#}", ext.name)))?;
        let inst = Self {
            name: ext.name,
            height: ext.strip_height,
            min_item_separation: ext.min_item_separation,
            items: inst.items,
        };
        inst.check()?;
        Ok(inst)
    }

    /// What the packing needs of an instance, checked before any work: every item fits the
    /// strip's height in some rotation it allows, the copies are not too many
    /// ([`MAX_STRIP_COPIES`]), and f32 coordinates along the strip the construction may
    /// fill stay fine against the items ([`F32_SPACING_OF_ITEM`]). One line naming the
    /// item and the numbers.
    pub fn check(&self) -> Result<(), NestError> {
        let sep = self.min_item_separation;
        // the collision shapes are grown by half the separation, the strip shrunk by it
        let usable = self.height - sep;
        for (item, _) in &self.items {
            let (rot, cd_h) = lowest_rotation(item);
            if cd_h < usable {
                continue;
            }
            let orig = rotated_bbox(&item.shape_orig().shape, rot);
            let h = orig.y_max - orig.y_min;
            let allowed = match item.allowed_orientations().rotations() {
                RotationRange::None => "no rotation allowed".to_string(),
                RotationRange::Continuous => "any rotation allowed".to_string(),
                RotationRange::Discrete(a) => format!(
                    "rotations allowed: {} degrees",
                    a.iter()
                        .map(|r| fmt_num(f64::from(r.to_degrees())))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            };
            let mut why = format!(
                "item {} ({} high at best, rotated by {} degrees; {allowed}) does not fit the \
                 strip height {}",
                item.external_id(),
                fmt_num(f64::from(h)),
                fmt_num(f64::from(rot.to_degrees())),
                fmt_num(f64::from(self.height)),
            );
            if sep > 0.0 {
                why += &format!(
                    " less the separation {} above and below",
                    fmt_num(f64::from(sep))
                );
            }
            if h + sep < usable {
                why += &format!(
                    " (its collision shape, grown by half the separation and simplified \
                     outward, is {} high)",
                    fmt_num(f64::from(cd_h))
                );
            }
            return Err(NestError::Instance(why));
        }
        let copies: u128 = self.items.iter().map(|(_, q)| *q as u128).sum();
        if copies > MAX_STRIP_COPIES as u128 {
            let (big, q) = self
                .items
                .iter()
                .max_by_key(|(_, q)| *q)
                .map(|(i, q)| (i.external_id(), *q))
                .unwrap_or_default();
            return Err(NestError::Instance(format!(
                "{copies} item copies in all (item {big} demands {q}): at most {MAX_STRIP_COPIES} \
                 are packed"
            )));
        }
        // the construction's strip is as long as every copy's diameter end to end; the
        // spacing of f32 numbers at its far end must stay far below the smallest item
        let length: f64 = self
            .items
            .iter()
            .map(|(i, q)| f64::from(i.shape_cd().diameter()) * *q as f64)
            .sum::<f64>()
            + f64::from(sep);
        let (small_id, small) = self
            .items
            .iter()
            .map(|(i, _)| {
                let b = i.shape_cd().bbox();
                (i.external_id(), (b.x_max - b.x_min).min(b.y_max - b.y_min))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 1.0));
        let spacing = f32_spacing(length);
        if spacing > F32_SPACING_OF_ITEM * f64::from(small) {
            return Err(NestError::Instance(format!(
                "{copies} item copies need a construction strip up to {} long, where f32 \
                 coordinates are {} apart: more than {F32_SPACING_OF_ITEM} of the smallest item \
                 side ({} of item {small_id}); lower the demands",
                fmt_num(length),
                fmt_num(spacing),
                fmt_num(f64::from(small)),
            )));
        }
        Ok(())
    }

    /// Reads an instance file.
    pub fn read(path: &Path) -> Result<Self, NestError> {
        let text = std::fs::read_to_string(path).map_err(|e| NestError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_json(&text)
    }

    /// Total item area (original shapes, with demands).
    pub fn item_area(&self) -> f64 {
        self.items
            .iter()
            .map(|(i, q)| f64::from(i.area()) * *q as f64)
            .sum()
    }
}

/// Most item copies (demands summed) a strip-packing instance may ask for: the packing
/// keeps every copy's shape and placement, and a demand of 10^8 took 1.6 GB before the
/// strip ran out of f32 precision.
pub const MAX_STRIP_COPIES: usize = 100_000;

/// Largest spacing of f32 numbers at the far end of the construction's strip, as a share
/// of the smallest item's shorter side: jagua-rs collides shapes in f32, so beyond it the
/// placed shapes are rounded by a visible share of their size.
pub const F32_SPACING_OF_ITEM: f64 = 1e-3;

/// The spacing of f32 numbers at `x` (the unit in the last place).
fn f32_spacing(x: f64) -> f64 {
    let x = x.abs().min(f64::from(f32::MAX)) as f32;
    f64::from(f32::from_bits(x.to_bits() + 1) - x)
}

/// A number for messages: integers and large numbers without decimals, else at most three.
fn fmt_num(v: f64) -> String {
    if (v == v.round() || v.abs() >= 1e4) && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The allowed rotation in which `item`'s collision shape is lowest, and that height. Any
/// rotation allowed: the lowest is with an edge of the convex hull level (the width of a
/// convex polygon is least across one of its edges).
fn lowest_rotation(item: &Item) -> (f32, f32) {
    let shape = item.shape_cd();
    let height = |rot: f32| {
        let b = rotated_bbox(shape, rot);
        b.y_max - b.y_min
    };
    let candidates: Vec<f32> = match item.allowed_orientations().rotations() {
        RotationRange::None => vec![0.0],
        RotationRange::Discrete(a) => a.clone(),
        RotationRange::Continuous => {
            let hull = &shape.surrogate().convex_hull_indices;
            let pts: Vec<_> = hull.iter().map(|&i| shape.vertex(i)).collect();
            (0..pts.len())
                .map(|k| {
                    let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
                    -(b.1 - a.1).atan2(b.0 - a.0)
                })
                .chain(std::iter::once(0.0))
                .collect()
        }
    };
    candidates
        .into_iter()
        .map(|r| (r, height(r)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0.0, height(0.0)))
}

/// Options of [`nest_strip`].
#[derive(Clone, Debug)]
pub struct StripOptions {
    /// RNG seed; the same seed and work budget give the same layout on every machine
    pub seed: u64,
    /// wall-clock cap of each search; also what the work budget is derived from when
    /// `max_evaluations` is `None`
    pub time_limit: Duration,
    /// work budget of each search (collision evaluations), which decides the layout; `None`:
    /// derived from `time_limit` and the instance ([`strip_work_budget`])
    pub max_evaluations: Option<u64>,
    /// let the clock alone decide, without a work budget (benchmarks at equal time only:
    /// the layout then depends on the machine's speed and load)
    pub clock_decides: bool,
    /// samples per item in the constructive phase
    pub construct_samples: usize,
    /// independent searches run side by side (seeds derived from `seed`), the best kept
    pub searches: usize,
    /// copies of the layout each search's separator moves items on at once, the best kept
    /// (sparrow's separator workers; a thread each). Searches and workers are fixed
    /// numbers, not the machine's core count, so the layout is the same everywhere
    pub workers: usize,
}

/// Share of the budget spent exploring (the rest compresses the best layout).
const EXPLORE_SHARE: f32 = 0.8;
/// Relative shrink after each successful separation while exploring.
const EXPLORE_SHRINK: f32 = 0.002;

/// |N(0, 1)| by the Box-Muller transform.
fn half_normal(rng: &mut Rng64) -> f32 {
    let u1: f32 = rng.random_range(f32::EPSILON..1.0);
    let u2: f32 = rng.random_range(0.0..1.0);
    ((-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()).abs()
}

/// Default wall-clock budget of [`StripOptions`].
pub const DEFAULT_STRIP_SECONDS: u64 = 10;

/// Threads of a search by default: one per core of the reference machine (2 cores). A
/// constant, so that the layout does not depend on the machine it runs on. One search on
/// two workers got 1.3 pp more density than two searches of one worker at the same total
/// work (6 ESICUP instances x 2 seeds, docs/nesting.md).
pub const REFERENCE_CORES: usize = 2;

/// Seconds per collision evaluation of one search on the reference machine (2 cores) for
/// items of `vertices` collision vertices on average: a fixed part and a part per vertex,
/// fitted to the CPU time of the 13 ESICUP instances (docs/nesting.md; within about 25 %).
fn strip_seconds_per_evaluation(vertices: f64) -> f64 {
    0.9e-6 + 0.11e-6 * vertices
}

/// The work budget of each search of [`nest_strip`] when none is given: what one search (on
/// both cores of the reference machine) does in `time`, scaled with the instance (more
/// vertices per item, slower evaluations), at a share of the time that leaves room for a
/// busy machine.
pub fn strip_work_budget(inst: &StripInstance, time: Duration) -> u64 {
    let (n, v) = inst.items.iter().fold((0.0, 0.0), |(n, v), (it, q)| {
        (
            n + *q as f64,
            v + *q as f64 * it.shape_cd().vertices().len() as f64,
        )
    });
    let per_item = if n > 0.0 { v / n } else { 10.0 };
    (crate::engine::WORK_SHARE_OF_TIME * time.as_secs_f64() * REFERENCE_CORES as f64
        / strip_seconds_per_evaluation(per_item)) as u64
}

impl Default for StripOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            time_limit: Duration::from_secs(DEFAULT_STRIP_SECONDS),
            max_evaluations: None,
            clock_decides: false,
            construct_samples: 400,
            searches: 1,
            workers: REFERENCE_CORES,
        }
    }
}

/// Progress report passed to the caller's callback.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Progress {
    /// seconds since start
    pub elapsed_s: f64,
    /// collision evaluations so far
    pub evaluations: u64,
    /// share of the work budget used (of the time when the clock decides), 0..1
    pub work_fraction: f64,
    /// best objective so far (strip length, or number of sheets)
    pub best: f64,
    /// density / utilisation of the best solution
    pub density: f64,
}

/// One placed item of a strip solution (transformation of the item's original coordinates).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct StripPlacement {
    /// external item id from the instance
    pub item_id: u64,
    /// rotation (degrees, counter-clockwise, about the original origin)
    pub rotation_deg: f64,
    /// translation applied after the rotation
    pub translation: [f64; 2],
}

/// Result of [`nest_strip`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StripResult {
    /// instance name
    pub name: String,
    /// strip height
    pub height: f64,
    /// used strip length
    pub length: f64,
    /// item area / (height x length)
    pub density: f64,
    /// one placement per demanded item copy
    pub placements: Vec<StripPlacement>,
    /// collision evaluations of the search (all searches together; never more than the
    /// work budget of each times the searches), the construction's not included
    pub evaluations: u64,
    /// collision evaluations of the construction (all searches together), counted apart
    /// from the work budget: it places every copy once, unless the clock stops it
    #[serde(default)]
    pub construction_evaluations: u64,
    /// the work budget of each search after the construction, in collision evaluations
    /// (candidate placements tested; `None` when the clock decided)
    pub work_budget: Option<u64>,
    /// whether the wall-clock cap stopped a search short of its work budget (the layout
    /// may then differ from a run on a faster or less busy machine)
    pub cut_by_time: bool,
    /// copies the clock left to the construction's columns of bounding boxes (0 unless
    /// `cut_by_time`)
    #[serde(default)]
    pub items_in_columns: usize,
    /// seconds used
    pub elapsed_s: f64,
}

/// Strip packing: constructive bottom-left-fill, then repeatedly shrink the strip and separate
/// the overlapping items (guided local search); the best feasible layout is kept (anytime).
/// With `searches > 1`, as many independent searches run at once (the first with `seed`,
/// the others with seeds derived from it), each with the whole budget; the densest wins
/// (ties: the first), so a fixed evaluation budget still gives the same layout every run.
/// Progress is reported by the first search.
pub fn nest_strip(
    inst: &StripInstance,
    opts: &StripOptions,
    progress: &mut dyn FnMut(&Progress),
) -> StripResult {
    let searches = opts.searches.max(1);
    if searches == 1 {
        let one = StripOptions {
            max_evaluations: work_of(inst, opts),
            ..opts.clone()
        };
        return nest_strip_one(inst, &one, progress);
    }
    let opts = &StripOptions {
        max_evaluations: work_of(inst, opts),
        ..opts.clone()
    };
    std::thread::scope(|scope| {
        let others: Vec<_> = (1..searches as u64)
            .map(|k| {
                let o = StripOptions {
                    seed: opts.seed ^ k.wrapping_mul(0x9E37_79B9_7F4A_7C15),
                    ..opts.clone()
                };
                scope.spawn(move || nest_strip_one(inst, &o, &mut |_| {}))
            })
            .collect();
        let mut best = nest_strip_one(inst, opts, progress);
        let mut evaluations = best.evaluations;
        let mut construction_evaluations = best.construction_evaluations;
        let mut cut = best.cut_by_time;
        for h in others {
            let r = h.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
            evaluations += r.evaluations;
            construction_evaluations += r.construction_evaluations;
            cut |= r.cut_by_time;
            if r.length < best.length {
                best = r;
            }
        }
        best.evaluations = evaluations;
        best.construction_evaluations = construction_evaluations;
        best.cut_by_time = cut;
        best
    })
}

/// The work budget of each search: given, derived from the time, or none (the clock decides).
fn work_of(inst: &StripInstance, opts: &StripOptions) -> Option<u64> {
    if opts.clock_decides {
        None
    } else {
        Some(
            opts.max_evaluations
                .unwrap_or_else(|| strip_work_budget(inst, opts.time_limit)),
        )
    }
}

fn nest_strip_one(
    inst: &StripInstance,
    opts: &StripOptions,
    progress: &mut dyn FnMut(&Progress),
) -> StripResult {
    let mut rng = Rng64::seed_from_u64(opts.seed);
    let started = Instant::now();
    // the construction places every copy once, whatever the work: its evaluations are
    // counted apart from the search's work budget (the clock alone caps it)
    let mut construction = Budget::new(started, opts.time_limit, None);
    let mut in_columns = 0;
    let sep = inst.min_item_separation;
    let h = inst.height;
    // copies, largest (convex hull area x diameter) first
    let mut copies: Vec<(usize, Arc<Item>)> = inst
        .items
        .iter()
        .flat_map(|(it, q)| std::iter::repeat_n(Arc::clone(it), *q))
        .enumerate()
        .collect();
    let key = |it: &Item| {
        let s = it.shape_cd();
        s.surrogate().convex_hull_area * s.diameter()
    };
    copies.sort_by(|a, b| key(&b.1).total_cmp(&key(&a.1)).then(a.0.cmp(&b.0)));
    let total_len: f32 = copies
        .iter()
        .map(|(_, it)| it.shape_cd().diameter())
        .sum::<f32>()
        + sep;
    let inset = sep / 2.0;
    let mut bin = Bin::new(rect(inset, inset, total_len, h - inset));
    bin.workers = opts.workers.max(1);
    // the right end of the placed shapes (kept as they are placed: a pass over them per
    // item made the construction grow with the square of the copies)
    let mut front = inset;
    let deadline = opts.time_limit.mul_f64(CONSTRUCTION_SHARE);
    let mut columns = Columns::new(inset, h - inset);
    for (n, (inst_idx, item)) in copies.iter().enumerate() {
        if construction.clock_passed(deadline) {
            // the clock caps the construction: the copies left go in columns of their
            // bounding boxes right of the others, which takes no collision test
            for (inst_idx, item) in &copies[n..] {
                columns.add(&mut bin, &mut front, *inst_idx, item);
            }
            in_columns = copies.len() - n;
            break;
        }
        let x_limit = front + item.shape_cd().diameter();
        let dt = bin
            .blf_position(
                item,
                opts.construct_samples,
                x_limit,
                &mut rng,
                &mut construction,
            )
            .or_else(|| bin.blf_position(item, 4000, f32::MAX, &mut rng, &mut construction));
        match dt {
            Some(dt) => {
                bin.add(*inst_idx, item, dt);
                let last = bin.members.len() - 1;
                front = front.max(bin.placed_shape(last).bbox().x_max);
            }
            // the item fits the height (checked with the instance) at a rotation the
            // sampling missed: a column of its own right of the others
            None => {
                columns.close();
                columns.add(&mut bin, &mut front, *inst_idx, item);
                columns.close();
            }
        }
    }
    let item_area = inst.item_area();
    let density_of = |len: f32| item_area / (f64::from(h) * f64::from(len));
    let fit = |bin: &mut Bin| {
        // a hair of slack: touching the container edge counts as a collision in jagua-rs
        let x = bin.used_x_max();
        let x = x + (x.abs() * 1e-5).max(1e-5);
        bin.set_bounds(rect(inset, inset, x, h - inset));
        x + inset
    };
    let mut best_len = fit(&mut bin);
    let mut best = bin.save();
    let mut budget = Budget::new(started, opts.time_limit, opts.max_evaluations);
    let report = |len: f32, budget: &Budget, progress: &mut dyn FnMut(&Progress)| {
        progress(&Progress {
            elapsed_s: budget.elapsed().as_secs_f64(),
            evaluations: budget.evals,
            work_fraction: f64::from(budget.fraction()),
            best: f64::from(len),
            density: density_of(len),
        });
    };
    report(best_len, &budget, progress);
    // exploration (sparrow): shrink a little after each success; after a failure, restart
    // from one of the failed layouts at the same length (the less overlap, the likelier),
    // disrupted by swapping two large items
    let mut pool: Vec<(f32, crate::engine::BinSnapshot)> = Vec::new();
    while !budget.done() && budget.fraction() < EXPLORE_SHARE {
        let loss = bin.separate_loss(&mut rng, &mut budget, 3, 200);
        if loss == 0.0 {
            let used = fit(&mut bin);
            let width = used - inset;
            if used < best_len {
                best_len = used;
                best = bin.save();
                report(best_len, &budget, progress);
            }
            pool.clear();
            let next = inset + (width - inset) * (1.0 - EXPLORE_SHRINK);
            bin.shrink_at(inset + 0.5 * (width - inset), next);
        } else if !budget.done() {
            let at = pool.partition_point(|p| p.0 <= loss);
            pool.insert(at, (loss, bin.save()));
            let k = ((half_normal(&mut rng) * 0.25).min(0.999) * pool.len() as f32) as usize;
            bin.restore(&pool[k].1);
            bin.disrupt(&mut rng);
        }
    }
    // compression: from the best layout, shrink at a random place by a ratio falling from
    // 0.05 % to 0.001 % over the rest of the budget
    let start = budget.fraction();
    bin.restore(&best);
    while !budget.done() {
        let t = ((budget.fraction() - start) / (1.0 - start).max(1e-6)).clamp(0.0, 1.0);
        let r = 5e-4 + t * (1e-5 - 5e-4);
        let len = best_len - inset;
        let split = rng.random_range(inset..len.max(inset + 1e-6));
        bin.shrink_at(split, inset + (len - inset) * (1.0 - r));
        if bin.separate(&mut rng, &mut budget, 5, 100) {
            best_len = fit(&mut bin);
            best = bin.save();
            report(best_len, &budget, progress);
        } else {
            bin.restore(&best);
        }
    }
    bin.restore(&best);
    debug_assert!(bin.is_feasible());
    let mut placements: Vec<(usize, StripPlacement)> = bin
        .members
        .iter()
        .map(|m| {
            let ext = int_to_ext_transformation(&m.dt, &m.item.shape_orig().pre_transform);
            let (tx, ty) = ext.translation();
            (
                m.inst,
                StripPlacement {
                    item_id: m.item.external_id(),
                    rotation_deg: f64::from(ext.rotation().to_degrees()),
                    translation: [f64::from(tx), f64::from(ty)],
                },
            )
        })
        .collect();
    placements.sort_by_key(|p| p.0);
    StripResult {
        name: inst.name.clone(),
        height: f64::from(h),
        length: f64::from(best_len),
        density: density_of(best_len),
        placements: placements.into_iter().map(|p| p.1).collect(),
        evaluations: budget.evals,
        construction_evaluations: construction.evals,
        work_budget: budget.work(),
        // (with a work budget, a construction the clock stopped cut the run short too)
        cut_by_time: budget.was_cut() || (in_columns > 0 && budget.work().is_some()),
        items_in_columns: in_columns,
        elapsed_s: budget.elapsed().as_secs_f64(),
    }
}

/// Share of [`StripOptions::time_limit`] the construction may take: the copies it has not
/// placed by then go in columns of their bounding boxes ([`Columns`]), so that the packing
/// holds its time cap at any number of copies.
const CONSTRUCTION_SHARE: f64 = 0.95;

/// Copies placed in columns of their bounding boxes (each at its lowest allowed rotation),
/// left to right from the placed shapes' right end, each column filled bottom to top:
/// a layout without a collision test, so its cost is the copies', whatever the clock.
struct Columns {
    y_min: f32,
    y_max: f32,
    /// left end of the open column and the height filled in it
    x: f32,
    y: f32,
    /// whether a column is open
    open: bool,
    /// lowest rotation and its box per item (by the item's index)
    rotations: HashMap<usize, (f32, Rect)>,
}

impl Columns {
    fn new(y_min: f32, y_max: f32) -> Self {
        Self {
            y_min,
            y_max,
            x: y_min,
            y: y_min,
            open: false,
            rotations: HashMap::new(),
        }
    }

    /// Ends the open column: the next copy starts one right of the placed shapes.
    fn close(&mut self) {
        self.open = false;
    }

    /// Places a copy of `item` at the top of the open column, or at the bottom of a new
    /// one right of `front`; the strip is lengthened where the column passes its end.
    fn add(&mut self, bin: &mut Bin, front: &mut f32, inst: usize, item: &Arc<Item>) {
        let (rot, rb) = *self.rotations.entry(item.idx()).or_insert_with(|| {
            let (rot, _) = lowest_rotation(item);
            (rot, rotated_bbox(item.shape_cd(), rot))
        });
        let (w, hb) = (rb.x_max - rb.x_min, rb.y_max - rb.y_min);
        let room = self.y_max - self.y_min;
        // apart by a hair: shapes that touch collide in jagua-rs
        let gap = |x: f32| 1e-4 * room + 4.0 * f32_spacing(f64::from(x)) as f32;
        if !(self.open && self.y + hb + 2.0 * gap(self.x) < self.y_max) {
            self.x = *front + gap(*front);
            self.y = self.y_min;
            self.open = true;
        }
        // a copy that fills the height on its own sits in the middle of it
        let y0 = if hb + 2.0 * gap(self.x) < room {
            self.y + gap(self.x)
        } else {
            self.y_min + 0.5 * (room - hb)
        };
        let dt = DTransformation::new(rot, (self.x - rb.x_min, y0 - rb.y_min));
        self.y = y0 + hb;
        let right = self.x + w;
        if right + gap(right) >= bin.bounds.x_max {
            let b = bin.bounds;
            let longer = right + gap(right) + (b.x_max - b.x_min) * 0.25;
            bin.set_bounds(rect(b.x_min, b.y_min, longer, b.y_max));
        }
        bin.add(inst, item, dt);
        *front = front.max(right);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip-packing instance of one `w` x `h` rectangle item (id 7) with `rotation` (the
    /// jagua-rs JSON object) and `demand` copies.
    fn rectangles(strip: f32, w: f32, h: f32, rotation: &str, demand: u64) -> String {
        format!(
            r#"{{"name": "t", "strip_height": {strip}, "items": [{{"id": 7, "demand": {demand},
            "orientation": {{"rotation": {rotation}}}, "shape": {{"type": "simple_polygon",
            "data": [[0, 0], [{w}, 0], [{w}, {h}], [0, {h}]]}}}}]}}"#
        )
    }

    /// The one-line refusal of an instance.
    fn refused(json: &str) -> String {
        StripInstance::from_json(json).unwrap_err().to_string()
    }

    const FIXED: &str = r#"{"mode": "discrete", "angles": [0]}"#;
    const QUARTERS: &str = r#"{"mode": "stepped", "step": 90}"#;
    const ANY: &str = r#"{"mode": "continuous"}"#;

    #[test]
    fn an_item_higher_than_the_strip_is_refused_by_name_unless_a_rotation_fits() {
        // 300 high, the strip 200: refused, naming the item, its height and the strip's
        let e = refused(&rectangles(200.0, 100.0, 300.0, FIXED, 2));
        assert!(
            e.contains("item 7 (300 high at best")
                && e.contains("does not fit the strip height 200")
                && !e.contains('\n'),
            "{e}"
        );
        // turned by 90 degrees it is 100 high, and packs
        let inst = StripInstance::from_json(&rectangles(200.0, 100.0, 300.0, QUARTERS, 2))
            .expect("fits turned");
        let opts = StripOptions {
            max_evaluations: Some(2_000),
            time_limit: Duration::from_secs(600),
            ..StripOptions::default()
        };
        let r = nest_strip(&inst, &opts, &mut |_| {});
        assert_eq!(r.placements.len(), 2);
        assert!(r
            .placements
            .iter()
            .all(|p| (p.rotation_deg.abs() - 90.0).abs() < 1e-3
                || (p.rotation_deg.abs() - 270.0).abs() < 1e-3));
        // any rotation: a 10 x 300 rectangle fits a strip 12 high only level (its least
        // width, across a hull edge), a strip 9 high not at all
        assert!(StripInstance::from_json(&rectangles(12.0, 300.0, 10.0, ANY, 1)).is_ok());
        let e = refused(&rectangles(9.0, 10.0, 300.0, ANY, 1));
        assert!(
            e.contains("item 7 (10 high at best") && e.contains("any rotation"),
            "{e}"
        );
        // the separation counts: 100 high with 60 above and below leaves less than 200
        let sep = rectangles(200.0, 300.0, 100.0, FIXED, 1).replace(
            r#""name": "t","#,
            r#""name": "t", "min_item_separation": 60,"#,
        );
        let e = refused(&sep);
        assert!(e.contains("less the separation 60"), "{e}");
    }

    #[test]
    fn demands_past_what_f32_and_memory_hold_are_refused_with_the_numbers() {
        let e = refused(&rectangles(5000.0, 3000.0, 2000.0, FIXED, 100_000_000));
        assert!(
            e.contains("100000000 item copies") && e.contains("at most 100000"),
            "{e}"
        );
        // 20,000 copies of a 3 x 2 m plate: the construction's strip is 7.2e7 long, where
        // f32 numbers are 8 apart, 4e-3 of the plate's 2000
        let e = refused(&rectangles(5000.0, 3000.0, 2000.0, FIXED, 20_000));
        assert!(
            e.contains("20000 item copies") && e.contains("are 8 apart"),
            "{e}"
        );
        // 2,000 of them are fine (1 apart at 7.2e6)
        assert!(
            StripInstance::from_json(&rectangles(5000.0, 3000.0, 2000.0, FIXED, 2_000)).is_ok()
        );
        assert_eq!(f32_spacing(1.0), f64::from(f32::EPSILON));
        assert_eq!(f32_spacing(7.2e7), 8.0);
    }

    #[test]
    fn the_clock_caps_the_construction_and_the_rest_go_in_columns_without_a_test() {
        // 3,000 copies and no time at all: before, the construction tested every copy
        // (hundreds of collision tests each, growing with the copies placed: 5,000 copies
        // of a large plate took 24 s against a 1 s cap); now not one test, every copy
        // placed in columns, in the strip and clear of the others
        let n = 3_000;
        let inst = StripInstance::from_json(&rectangles(100.0, 30.0, 10.0, QUARTERS, n)).unwrap();
        let r = nest_strip(
            &inst,
            &StripOptions {
                time_limit: Duration::ZERO,
                max_evaluations: Some(1_000_000),
                ..StripOptions::default()
            },
            &mut |_| {},
        );
        assert_eq!(r.evaluations, 0);
        assert!(r.cut_by_time);
        assert_eq!(r.items_in_columns, n as usize);
        assert_eq!(r.placements.len(), n as usize);
        // the rectangles as placed (original coordinates), each inside the strip
        let mut boxes: Vec<[f64; 4]> = r
            .placements
            .iter()
            .map(|p| {
                let (s, c) = p.rotation_deg.to_radians().sin_cos();
                let pts = [[0.0, 0.0], [30.0, 0.0], [30.0, 10.0], [0.0, 10.0]].map(|[x, y]| {
                    [
                        c * x - s * y + p.translation[0],
                        s * x + c * y + p.translation[1],
                    ]
                });
                let f = |k: usize, min: bool| {
                    pts.iter()
                        .map(|q| q[k])
                        .fold(if min { f64::MAX } else { f64::MIN }, |a, b| {
                            if min {
                                a.min(b)
                            } else {
                                a.max(b)
                            }
                        })
                };
                [f(0, true), f(1, true), f(0, false), f(1, false)]
            })
            .collect();
        for b in &boxes {
            assert!(
                b[0] >= 0.0 && b[1] >= 0.0 && b[2] <= r.length && b[3] <= 100.0,
                "{b:?}"
            );
            // at its lowest rotation: 10 high
            assert!((b[3] - b[1] - 10.0).abs() < 1e-3, "{b:?}");
        }
        // no two overlap (sorted by x, each against those starting before it ends)
        boxes.sort_by(|a, b| a[0].total_cmp(&b[0]));
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if boxes[j][0] >= boxes[i][2] {
                    break;
                }
                let apart = boxes[j][1] >= boxes[i][3] || boxes[i][1] >= boxes[j][3];
                assert!(apart, "{:?} {:?}", boxes[i], boxes[j]);
            }
        }
        // 9 to a column of 100
        assert!(r.length < 30.5 * (n as f64 / 9.0).ceil(), "{}", r.length);
    }
}
