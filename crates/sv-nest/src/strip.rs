//! Strip packing: fixed height, minimise the used length (ESICUP / jagua-rs `spp` instances).

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use jagua_rs::entities::Item;
use jagua_rs::io::export::int_to_ext_transformation;
use jagua_rs::io::import::Importer;
use jagua_rs::probs::spp::io::ext_repr::ExtSPInstance;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::engine::{rect, Bin, Budget, Rng64, CDE_CONFIG};
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
        Ok(Self {
            name: ext.name,
            height: ext.strip_height,
            min_item_separation: ext.min_item_separation,
            items: inst.items,
        })
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
    /// collision evaluations used
    pub evaluations: u64,
    /// the work budget of each search (`None` when the clock decided)
    pub work_budget: Option<u64>,
    /// whether the wall-clock cap stopped a search short of its work budget (the layout
    /// may then differ from a run on a faster or less busy machine)
    pub cut_by_time: bool,
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
        let mut cut = best.cut_by_time;
        for h in others {
            let r = h.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
            evaluations += r.evaluations;
            cut |= r.cut_by_time;
            if r.length < best.length {
                best = r;
            }
        }
        best.evaluations = evaluations;
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
    let mut budget = Budget::new(Instant::now(), opts.time_limit, opts.max_evaluations);
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
    for (inst_idx, item) in &copies {
        let x_limit = bin.used_x_max() + item.shape_cd().diameter();
        let dt = bin
            .blf_position(item, opts.construct_samples, x_limit, &mut rng, &mut budget)
            .or_else(|| bin.blf_position(item, 4000, f32::MAX, &mut rng, &mut budget))
            .expect("an item fits in the initial strip");
        bin.add(*inst_idx, item, dt);
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
        work_budget: budget.work(),
        cut_by_time: budget.was_cut(),
        elapsed_s: budget.elapsed().as_secs_f64(),
    }
}
