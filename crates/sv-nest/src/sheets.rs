//! Bin packing of parts onto rectangular stock sheets (`nest.json`).

use std::time::{Duration, Instant};

use std::sync::Arc;

use jagua_rs::entities::Item;
use jagua_rs::geometry::geo_enums::RotationRange;
use jagua_rs::geometry::DTransformation;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::engine::{rect, Bin, Budget, Rng64};
use crate::prepare::{Kind, PartInfo, Prepared, Setup};
use crate::shape::Rigid;
use crate::strip::{Progress, REFERENCE_CORES};
use crate::{ById, NestError, Part, DEFAULT_FLATTEN_TOLERANCE};

/// Default sheet width (mm).
pub const DEFAULT_SHEET_WIDTH: f64 = 3000.0;
/// Default sheet height (mm).
pub const DEFAULT_SHEET_HEIGHT: f64 = 1500.0;
/// Default sheet margin (mm).
pub const DEFAULT_MARGIN: f64 = 10.0;
/// Default part spacing (mm): kerf plus clearance.
pub const DEFAULT_SPACING: f64 = 6.0;

/// Allowed part rotations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case")]
pub enum RotationMode {
    /// listed angles in degrees
    Discrete {
        /// angles (degrees)
        angles: Vec<f64>,
    },
    /// multiples of `step` degrees
    Stepped {
        /// step (degrees), must divide 360
        step: f64,
    },
    /// any angle
    Continuous,
}

impl Default for RotationMode {
    fn default() -> Self {
        Self::Discrete {
            angles: vec![0.0, 180.0],
        }
    }
}

impl RotationMode {
    /// `Continuous` when `free`, else the default 0 and 180 degrees.
    pub fn free_or_default(free: bool) -> Self {
        if free {
            Self::Continuous
        } else {
            Self::default()
        }
    }

    fn range(&self) -> Result<RotationRange, NestError> {
        let angles: Vec<f64> = match self {
            Self::Continuous => return Ok(RotationRange::Continuous),
            Self::Discrete { angles } => angles.clone(),
            Self::Stepped { step } => {
                if !(step.is_finite() && *step > 0.0 && *step <= 360.0) {
                    return Err(NestError::Options(format!("rotation step {step}")));
                }
                let n = (360.0 / step).round() as usize;
                (0..n).map(|i| i as f64 * step).collect()
            }
        };
        if angles.is_empty() || angles.iter().any(|a| !a.is_finite()) {
            return Err(NestError::Options("rotation angles".into()));
        }
        let mut r: Vec<f32> = angles
            .iter()
            .map(|a| (a.rem_euclid(360.0).to_radians()) as f32)
            .collect();
        r.sort_by(f32::total_cmp);
        r.dedup();
        Ok(if r == [0.0] {
            RotationRange::None
        } else {
            RotationRange::Discrete(r)
        })
    }
}

/// A stock sheet size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StockSheet {
    /// x size (mm)
    pub width: f64,
    /// y size (mm)
    pub height: f64,
}

/// Options of [`nest_sheets`].
#[derive(Clone, Debug)]
pub struct NestOptions {
    /// stock sizes in order of preference (default: one 3000 x 1500 sheet size)
    pub sheets: Vec<StockSheet>,
    /// clear border along every sheet edge (mm)
    pub margin: f64,
    /// minimum distance between parts (mm), kerf plus clearance
    pub spacing: f64,
    /// allowed rotations (default 0 and 180 degrees)
    pub rotations: RotationMode,
    /// chord tolerance for arcs (mm); outlines are grown by it, so nesting stays safe
    pub flatten_tolerance: f64,
    /// RNG seed
    pub seed: u64,
    /// wall-clock cap of the whole call, set-up included; also what the work budget is
    /// derived from when `max_evaluations` is `None`
    pub time_limit: Duration,
    /// work budget (collision evaluations), which decides the layout: the same parts,
    /// options and seed give the same sheets on every machine unless the clock cuts the
    /// search first (then [`SearchReport::cut_by_time`] says so); `None`: derived from
    /// `time_limit` and the parts ([`sheet_work_budget`])
    pub max_evaluations: Option<u64>,
    /// the time the work budget is derived from when `max_evaluations` is `None`; `None`:
    /// `time_limit`. A caller that keeps part of its time box for work whose length follows
    /// the machine's load (drawing the sheets) shortens `time_limit` on a busy machine and
    /// keeps this, so that the budget, and with it the sheets, stays the same
    pub budget_time: Option<Duration>,
    /// samples per part in the constructive phase
    pub construct_samples: usize,
}

impl Default for NestOptions {
    fn default() -> Self {
        Self {
            sheets: vec![StockSheet {
                width: DEFAULT_SHEET_WIDTH,
                height: DEFAULT_SHEET_HEIGHT,
            }],
            margin: DEFAULT_MARGIN,
            spacing: DEFAULT_SPACING,
            rotations: RotationMode::default(),
            flatten_tolerance: DEFAULT_FLATTEN_TOLERANCE,
            seed: 0,
            time_limit: Duration::from_secs(10),
            max_evaluations: None,
            budget_time: None,
            construct_samples: 300,
        }
    }
}

/// `nest.json` `sheet` block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SheetSpec {
    /// first stock width (mm)
    pub width: f64,
    /// first stock height (mm)
    pub height: f64,
    /// margin (mm)
    pub margin: f64,
    /// spacing (mm)
    pub spacing: f64,
}

/// A part placement: `p_sheet = R(rotation_deg) * p_part + translation`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartPlacement {
    /// part id
    pub strip: String,
    /// translation (mm) applied after the rotation
    pub translation: [f64; 2],
    /// rotation about the part's own origin (degrees, counter-clockwise, in [0, 360))
    pub rotation_deg: f64,
}

/// One used sheet.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SheetReport {
    /// stock width (mm)
    pub width: f64,
    /// stock height (mm)
    pub height: f64,
    /// placements on this sheet
    pub placements: Vec<PartPlacement>,
    /// sum of part outline areas / sheet area
    pub utilisation: f64,
}

/// Reusable remainder of the last sheet, as one rectangle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Offcut {
    /// sheet index
    pub sheet: usize,
    /// left edge (mm)
    pub x: f64,
    /// bottom edge (mm)
    pub y: f64,
    /// width (mm)
    pub width: f64,
    /// height (mm)
    pub height: f64,
}

/// Lower bounds on the number of sheets.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LowerBounds {
    /// ceil(sum of part areas grown by half the spacing / usable sheet area)
    pub area: usize,
    /// Martello-Toth L2 on the same areas (counts parts too large to share a sheet)
    pub martello_toth: usize,
}

/// A part that was not nested.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeftOut {
    /// part id
    pub part: String,
    /// reason (the error message)
    pub reason: String,
}

/// How far the search went: the work budget, the work done, whether the clock cut it.
/// A record of the run, not of the layout: on a busy machine the clock may cut the search
/// and still leave the same sheets, so it is not in `nest.json` (which the same parts,
/// options and work budget make byte for byte the same on every run) but in the command's
/// `timings.json` (`nest_search`), beside the stage's seconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SearchReport {
    /// the work budget (collision evaluations) of the search after the construction, which
    /// decides the layout: an evaluation is one candidate placement of a part tested
    /// against a sheet's layout (a sample or a descent step)
    pub work_budget: u64,
    /// collision evaluations the search did (all searches together): never more than
    /// `work_budget`, the construction's not included
    pub evaluations: u64,
    /// collision evaluations of the construction before the search, counted apart from the
    /// work budget (not cut short by the work: every part is placed once)
    pub construction_evaluations: u64,
    /// whether the wall-clock cap stopped the search before its work budget was spent, or
    /// the construction before every part was placed: the layout may then differ from a
    /// run on a faster or less busy machine
    pub cut_by_time: bool,
    /// whether the wall-clock cap stopped the construction: the parts it had not placed
    /// went onto sheets of their own in rows of bounding boxes, and there was no search
    pub construction_cut: bool,
    /// parts placed in rows of bounding boxes after a construction cut
    pub parts_in_rows: usize,
}

impl SearchReport {
    /// Share of the work budget done (1 when it was spent).
    pub fn done_fraction(&self) -> f64 {
        (self.evaluations as f64 / self.work_budget.max(1) as f64).min(1.0)
    }
}

/// `nest.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NestReport {
    /// sheet parameters
    pub sheet: SheetSpec,
    /// used sheets
    pub sheets: Vec<SheetReport>,
    /// max of the bounds below
    pub lower_bound_sheets: usize,
    /// both bounds
    pub lower_bounds: LowerBounds,
    /// parts that were not nested, with the reason
    pub left_out: Vec<LeftOut>,
    /// offcut of the last sheet
    pub offcut: Option<Offcut>,
    /// the work budget and what was done of it: not written to `nest.json` (see
    /// [`SearchReport`])
    #[serde(skip)]
    pub search: SearchReport,
}

/// Martello-Toth L2 and the area bound for item sizes `a` in bins of capacity `cap`.
///
/// L2 is the best over every threshold `k` (0 and each size up to `cap / 2`) of: the items
/// above `cap - k` (a bin each), those above `cap / 2` (a bin each too), plus the bins the
/// items between `k` and `cap / 2` need beyond the room the second group leaves. The sizes
/// are sorted once, so each threshold costs a few binary searches (70,000 small parts: a
/// few milliseconds rather than minutes).
pub fn lower_bounds(a: &[f64], cap: f64) -> LowerBounds {
    let eps = 1e-9 * cap;
    let total: f64 = a.iter().sum();
    let area = ((total / cap) - 1e-9).ceil().max(0.0) as usize;
    let mut sorted = a.to_vec();
    sorted.sort_by(f64::total_cmp);
    // prefix[i]: the sum of the i smallest
    let mut prefix = Vec::with_capacity(sorted.len() + 1);
    prefix.push(0.0);
    for &x in &sorted {
        prefix.push(prefix[prefix.len() - 1] + x);
    }
    let n = sorted.len();
    // the first index whose size is above `t` / at least `t`
    let above = |t: f64| sorted.partition_point(|&x| x <= t);
    let from = |t: f64| sorted.partition_point(|&x| x < t);
    let big = above(cap / 2.0 + eps);
    let mut ks: Vec<f64> = sorted.iter().copied().filter(|&x| x <= cap / 2.0).collect();
    ks.push(0.0);
    ks.dedup();
    let mut best = 0;
    for &k in &ks {
        let over = above(cap - k + eps).max(big);
        let j1 = n - over;
        let j2 = over - big;
        let lo = from(k - eps).min(big);
        let j3 = prefix[big] - prefix[lo];
        let free = j2 as f64 * cap - (prefix[over] - prefix[big]);
        let extra = ((j3 - free) / cap - 1e-9).ceil().max(0.0) as usize;
        best = best.max(j1 + j2 + extra);
    }
    LowerBounds {
        area,
        martello_toth: best,
    }
}

/// Searches of [`nest_sheets`], side by side (one per core of the reference machine; a
/// constant, so that the sheets do not depend on the machine).
const DEFAULT_SEARCHES: usize = REFERENCE_CORES;

/// A used sheet: its stock size (index into [`NestOptions::sheets`]) and its layout.
type Sheet = (usize, Bin);

/// Nests `parts` onto sheets. Bad parts are reported in `left_out`; the others are nested.
///
/// The set-up (outlines checked, congruent outlines grouped, one collision shape per group)
/// runs on every core while the construction places the parts, largest first, sheet after
/// sheet. Then [`DEFAULT_SEARCHES`] searches side by side, each from the construction with
/// its own seed and an equal share of the work budget, try to empty the last sheet into the
/// others and to compact it towards the left; the best wins (fewest sheets, then the
/// largest offcut, then the first search), so the result does not depend on the threads.
pub fn nest_sheets(
    parts: &[Part],
    opts: &NestOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<NestReport, NestError> {
    if opts.sheets.is_empty()
        || opts.sheets.iter().any(|s| {
            !(s.width > 0.0 && s.height > 0.0 && s.width.is_finite() && s.height.is_finite())
        })
    {
        return Err(NestError::Options("sheet sizes must be positive".into()));
    }
    if !(opts.margin >= 0.0 && opts.spacing >= 0.0 && opts.flatten_tolerance > 0.0) {
        return Err(NestError::Options(
            "margin and spacing must be >= 0, flatten tolerance > 0".into(),
        ));
    }
    if let Err(why) = margin_leaves_room(&opts.sheets, opts.margin) {
        return Err(NestError::Options(format!(
            "margin {} mm {why}",
            opts.margin
        )));
    }
    // the clock starts here: the set-up is part of the budget
    let started = Instant::now();
    let (m, s) = (opts.margin, opts.spacing);
    let setup = Setup {
        // half the spacing, an allowance for f32 coordinates and for congruent parts
        // sharing a shape
        grow: s / 2.0 + 1e-3 + s * 1e-3,
        tolerance: opts.flatten_tolerance,
        range: opts.rotations.range()?,
        // grown parts inside [m - s/2, W - m + s/2]
        usable: opts
            .sheets
            .iter()
            .map(|st| {
                (
                    m - s / 2.0,
                    m - s / 2.0,
                    st.width - m + s / 2.0,
                    st.height - m + s / 2.0,
                )
            })
            .collect(),
        half_spacing: s / 2.0,
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let prepared = Prepared::new(parts);
    let mut left_out: Vec<LeftOut> = prepared
        .bad
        .iter()
        .map(|(i, reason)| LeftOut {
            part: parts[*i].id.clone(),
            reason: reason.clone(),
        })
        .collect();
    let mut rng = Rng64::seed_from_u64(opts.seed);
    let mut budget = Budget::new(started, opts.time_limit, None);
    let deadline = opts.time_limit.mul_f64(CONSTRUCTION_SHARE);
    // the set-up on the other cores while this one places
    let (mut bins, late) = std::thread::scope(|scope| {
        for _ in 1..threads.min(prepared.kind_count()) {
            scope.spawn(|| prepared.work(&setup));
        }
        let built = construct(
            parts,
            &prepared,
            &setup,
            opts,
            deadline,
            &mut rng,
            &mut budget,
            &mut left_out,
        );
        prepared.stop();
        built
    });
    // the parts the clock left: in rows of bounding boxes on sheets of their own (no
    // collision shape needed); one that no row takes goes onto a sheet the usual way
    let construction_cut = !late.is_empty();
    let (rows, wide) = in_rows(&prepared, &setup, &late);
    for pi in wide {
        match new_sheet(parts, &prepared, &setup, opts, pi, &mut rng, &mut budget) {
            Ok(sheet) => bins.push(sheet),
            Err(l) => left_out.push(l),
        }
    }
    let parts_in_rows: usize = rows.iter().map(|r| r.parts.len()).sum();
    let kind = |k: usize| -> &Kind {
        prepared
            .kind(k, &setup)
            .as_ref()
            .expect("placed parts have a shape")
    };
    let construction_evaluations = budget.evals;
    let placed: Vec<&PartInfo> = bins
        .iter()
        .flat_map(|(_, b)| b.members.iter().map(|mm| &prepared.parts[mm.inst]))
        .collect();
    // a part in a row may have no collision shape: its outline area (smaller than the
    // grown one) keeps the bound a bound
    let lb_sizes: Vec<f64> = placed
        .iter()
        .map(|p| kind(p.kind).lb_area)
        .chain(
            rows.iter()
                .flat_map(|r| r.parts.iter().map(|q| prepared.parts[q.0].area)),
        )
        .collect();
    let cap = setup
        .usable
        .iter()
        .map(|u| (u.2 - u.0) * (u.3 - u.1))
        .fold(0.0, f64::max);
    let lbs = lower_bounds(&lb_sizes, cap);
    let lb = lbs.area.max(lbs.martello_toth);
    let mean_vertices = placed
        .iter()
        .map(|p| kind(p.kind).item.shape_cd().vertices().len() as f64)
        .sum::<f64>()
        / placed.len().max(1) as f64;
    let shape_vertices: usize = prepared
        .kinds_made()
        .map(|k| k.item.shape_cd().vertices().len())
        .sum();
    let fixed = fixed_seconds(shape_vertices, construction_evaluations);
    let work = opts.max_evaluations.unwrap_or_else(|| {
        let time = opts.budget_time.unwrap_or(opts.time_limit);
        sheet_work_budget(mean_vertices, time, fixed)
    });
    let area_of = |inst: usize| prepared.parts[inst].area;
    let sheet_area = |st: usize| opts.sheets[st].width * opts.sheets[st].height;
    // the search works on the emptiest sheets (the cost of a search does not grow with
    // the job); their parts get the search's shapes, made on every core
    let [rest, window] = split_window(bins);
    let in_window: Vec<usize> = {
        let mut k: Vec<usize> = window
            .iter()
            .flat_map(|(_, b)| b.members.iter().map(|m| prepared.parts[m.inst].kind))
            .collect();
        k.sort_unstable();
        k.dedup();
        k
    };
    // (each one only while the clock allows: without them there is no search)
    let rich: Vec<Option<Arc<Item>>> = if construction_cut {
        Vec::new()
    } else {
        crate::prepare::parallel_map(in_window.len(), |i| {
            (started.elapsed() < opts.time_limit).then(|| kind(in_window[i]).rich())
        })
    };
    let searching = !construction_cut && rich.iter().all(Option::is_some);
    let window: Vec<Sheet> = if searching {
        window
            .into_iter()
            .map(|(st, b)| {
                let mut nb = Bin::new(b.bounds);
                for m in &b.members {
                    let k = prepared.parts[m.inst].kind;
                    let item = rich[in_window.binary_search(&k).expect("a window kind")]
                        .as_ref()
                        .expect("made");
                    nb.add(m.inst, item, m.dt);
                }
                (st, nb)
            })
            .collect()
    } else {
        window
    };
    let rest_used: f64 = rest.iter().map(|(st, _)| sheet_area(*st)).sum();
    let rest_area: f64 = rest
        .iter()
        .flat_map(|(_, b)| b.members.iter().map(|m| area_of(m.inst)))
        .sum();
    let report_progress =
        |window: &[Sheet], budget: &Budget, progress: &mut dyn FnMut(&Progress)| {
            let used: f64 = rest_used + window.iter().map(|(st, _)| sheet_area(*st)).sum::<f64>();
            let area: f64 = rest_area
                + window
                    .iter()
                    .flat_map(|(_, b)| b.members.iter().map(|m| area_of(m.inst)))
                    .sum::<f64>();
            progress(&Progress {
                elapsed_s: budget.elapsed().as_secs_f64(),
                evaluations: budget.evals,
                work_fraction: f64::from(budget.fraction()),
                best: (rest.len() + window.len()) as f64,
                density: if used > 0.0 { area / used } else { 0.0 },
            });
        };
    // the searches, side by side; each gets its share of the work (the first ones the
    // remainder), so that together they do at most `work` evaluations
    let searches = DEFAULT_SEARCHES as u64;
    let share = |k: u64| work / searches + u64::from(k < work % searches);
    let others = rest.len();
    let results: Vec<Searched> = if !searching {
        // the clock ran out before the search could start
        vec![(window, 0, work > 0)]
    } else {
        std::thread::scope(|scope| {
            let handles: Vec<_> = (1..searches)
                .map(|k| {
                    let mut mine = window.clone();
                    let seed = opts.seed ^ k.wrapping_mul(0x9E37_79B9_7F4A_7C15);
                    scope.spawn(move || {
                        let mut b = Budget::new(started, opts.time_limit, Some(share(k)));
                        let mut r = Rng64::seed_from_u64(seed);
                        improve(&mut mine, others, lb, &mut r, &mut b, opts, &mut |_, _| {});
                        (mine, b.evals, b.was_cut())
                    })
                })
                .collect();
            let mut first = window.clone();
            let mut b = Budget::new(started, opts.time_limit, Some(share(0)));
            improve(
                &mut first,
                others,
                lb,
                &mut rng,
                &mut b,
                opts,
                &mut |w, b| report_progress(w, b, progress),
            );
            let mut all = vec![(first, b.evals, b.was_cut())];
            for h in handles {
                all.push(h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
            }
            all
        })
    };
    let evaluations: u64 = results.iter().map(|r| r.1).sum();
    let cut = results.iter().any(|r| r.2);
    let (window, _, _) = results
        .into_iter()
        .enumerate()
        .min_by(|(i, a), (j, b)| {
            a.0.len()
                .cmp(&b.0.len())
                .then(last_x(&a.0).total_cmp(&last_x(&b.0)))
                .then(i.cmp(j))
        })
        .map(|(_, r)| r)
        .expect("one search at least");
    let mut bins = rest;
    bins.extend(window);

    // report
    let mut sheets = Vec::new();
    for (stock, bin) in &bins {
        let st = opts.sheets[*stock];
        let mut placements: Vec<(usize, PartPlacement)> = bin
            .members
            .iter()
            .map(|mem| {
                let info = &prepared.parts[mem.inst];
                let k = kind(info.kind);
                // part -> representative -> shape (centred) -> sheet
                let to_shape = Rigid {
                    rotation: 0.0,
                    translation: [-k.centre[0], -k.centre[1]],
                }
                .after(&info.frame);
                let (tx, ty) = mem.dt.translation();
                let on_sheet = Rigid {
                    rotation: f64::from(mem.dt.rotation()),
                    translation: [f64::from(tx), f64::from(ty)],
                }
                .after(&to_shape);
                (
                    info.part,
                    PartPlacement {
                        strip: parts[info.part].id.clone(),
                        translation: on_sheet.translation,
                        rotation_deg: on_sheet.rotation.to_degrees().rem_euclid(360.0),
                    },
                )
            })
            .collect();
        placements.sort_by_key(|p| p.0);
        let area: f64 = bin.members.iter().map(|mm| area_of(mm.inst)).sum();
        sheets.push(SheetReport {
            width: st.width,
            height: st.height,
            placements: placements.into_iter().map(|p| p.1).collect(),
            utilisation: area / (st.width * st.height),
        });
    }
    for row in &rows {
        let st = opts.sheets[row.stock];
        let mut placements: Vec<(usize, PartPlacement)> = row
            .parts
            .iter()
            .map(|&(inst, rotation_deg, translation)| {
                let part = prepared.parts[inst].part;
                (
                    part,
                    PartPlacement {
                        strip: parts[part].id.clone(),
                        translation,
                        rotation_deg,
                    },
                )
            })
            .collect();
        placements.sort_by_key(|p| p.0);
        let area: f64 = row.parts.iter().map(|q| area_of(q.0)).sum();
        sheets.push(SheetReport {
            width: st.width,
            height: st.height,
            placements: placements.into_iter().map(|p| p.1).collect(),
            utilisation: area / (st.width * st.height),
        });
    }
    // the right end of the grown outlines on the last sheet
    let last_end = match rows.last() {
        Some(r) => Some((r.stock, r.x_max)),
        None => bins
            .last()
            .map(|(stock, bin)| (*stock, f64::from(bin.used_x_max()))),
    };
    let offcut = last_end.map(|(stock, end)| {
        let st = opts.sheets[stock];
        // the true part edge is `grow` inside the grown outline
        let x = (end - setup.grow + s).min(st.width);
        Offcut {
            sheet: sheets.len() - 1,
            x,
            y: 0.0,
            width: (st.width - x).max(0.0),
            height: st.height,
        }
    });
    // in the order of the parts given
    let order = ById::new(parts, |p| &p.id);
    left_out.sort_by_key(|l| order.position(&l.part));
    Ok(NestReport {
        sheet: SheetSpec {
            width: opts.sheets[0].width,
            height: opts.sheets[0].height,
            margin: m,
            spacing: s,
        },
        sheets,
        lower_bound_sheets: lb,
        lower_bounds: lbs,
        left_out,
        offcut,
        search: SearchReport {
            work_budget: work,
            evaluations,
            construction_evaluations,
            cut_by_time: cut || construction_cut,
            construction_cut,
            parts_in_rows,
        },
    })
}

/// What one search ends with: its sheets, its evaluations, whether the clock cut it.
type Searched = (Vec<Sheet>, u64, bool);

/// Right end of the parts on the last sheet (the smaller, the larger the offcut).
fn last_x(bins: &[Sheet]) -> f32 {
    bins.last().map_or(0.0, |(_, b)| b.used_x_max())
}

/// Sheets a part's failure closes: after this many parts in a row that did not fit, a sheet
/// is full (the remaining, smaller parts go on the next ones; the search repacks the end).
const FAILURES_TO_CLOSE: usize = 12;

/// Whether `margin` (mm) along every edge leaves room on each stock size: `Err` with the
/// reason (`leaves no usable area on the 3000 x 1500 mm sheet (2 x 760 mm >= 1500 mm)`)
/// where twice the margin reaches the sheet's width or height. Callers name their flag or
/// key before it; [`nest_sheets`] refuses such options up front.
pub fn margin_leaves_room(sheets: &[StockSheet], margin: f64) -> Result<(), String> {
    for st in sheets {
        let side = st.width.min(st.height);
        if 2.0 * margin >= side {
            return Err(format!(
                "leaves no usable area on the {} x {} mm sheet (2 x {margin} mm >= {side} mm)",
                st.width, st.height
            ));
        }
    }
    Ok(())
}

/// Share of [`NestOptions::time_limit`] the construction may take: the parts it has not
/// placed by then go in rows of bounding boxes ([`in_rows`]), so that the stage holds its
/// time box at any size (the rest of the time is for the report).
const CONSTRUCTION_SHARE: f64 = 0.95;

/// The construction: parts largest first onto sheets filled one after another. A sheet
/// takes every remaining part that fits, until [`FAILURES_TO_CLOSE`] parts in a row did not
/// fit; a part is not tried on a sheet whose free area is smaller, nor when a part no larger
/// (in area and both sides of its bounding box) did not fit there. A new sheet takes the
/// first stock size that holds its first part. Each try samples positions near the sheet's
/// filled front first, and a place behind the front (not reaching right of the parts
/// there) costs nothing in x, so the lowest of those wins: a strip nearly as long as the
/// sheet slides sideways into the teeth of the one below instead of stopping on them
/// ([`Bin::blf_position_behind`]). When the clock passes `deadline` (from the stage's start) the
/// construction stops: it returns its sheets and the parts it did not place (in
/// construction order; none when the clock did not stop it).
#[allow(clippy::too_many_arguments)]
fn construct(
    parts: &[Part],
    prepared: &Prepared,
    setup: &Setup,
    opts: &NestOptions,
    deadline: Duration,
    rng: &mut Rng64,
    budget: &mut Budget,
    left_out: &mut Vec<LeftOut>,
) -> (Vec<Sheet>, Vec<usize>) {
    let mut bins: Vec<Sheet> = Vec::new();
    let mut remaining: Vec<usize> = (0..prepared.parts.len()).collect();
    while !remaining.is_empty() {
        let mut later = Vec::new();
        let mut open: Option<Sheet> = None;
        let mut free = 0.0;
        // (area, shorter side, longer side) of the shapes that did not fit
        let mut failed: Vec<(f64, f64, f64)> = Vec::new();
        let mut in_a_row = 0;
        let mut late = false;
        for (n, &pi) in remaining.iter().enumerate() {
            if budget.elapsed() >= deadline {
                later.extend_from_slice(&remaining[n..]);
                late = true;
                break;
            }
            let info = &prepared.parts[pi];
            let kind = match prepared.kind(info.kind, setup) {
                Ok(k) => k,
                Err(reason) => {
                    left_out.push(LeftOut {
                        part: parts[info.part].id.clone(),
                        reason: reason.clone(),
                    });
                    continue;
                }
            };
            if in_a_row >= FAILURES_TO_CLOSE {
                later.extend_from_slice(&remaining[n..]);
                break;
            }
            let Some((_, bin)) = open.as_mut() else {
                match new_sheet(parts, prepared, setup, opts, pi, rng, budget) {
                    Ok(sheet) => {
                        let u = setup.usable[sheet.0];
                        free = (u.2 - u.0) * (u.3 - u.1) - kind.area;
                        open = Some(sheet);
                    }
                    Err(l) => left_out.push(l),
                }
                continue;
            };
            let (a, s0, s1) = (kind.area, kind.sides.0, kind.sides.1);
            if a > free || failed.iter().any(|f| a >= f.0 && s0 >= f.1 && s1 >= f.2) {
                later.push(pi);
                continue;
            }
            let filled = bin.used_x_max();
            let front = filled + kind.item.shape_cd().diameter();
            match bin.blf_position_behind(
                &kind.item,
                opts.construct_samples,
                front,
                Some(filled),
                rng,
                budget,
            ) {
                Some(dt) => {
                    bin.add(pi, &kind.item, dt);
                    free -= kind.area;
                    in_a_row = 0;
                }
                None => {
                    failed.push((a, s0, s1));
                    later.push(pi);
                    in_a_row += 1;
                }
            }
        }
        if let Some(b) = open {
            bins.push(b);
        }
        if late {
            return (bins, later);
        }
        remaining = later;
    }
    (bins, Vec::new())
}

/// A new sheet holding part `pi` (of the prepared parts): the first stock size that holds
/// it, else the part is left out.
fn new_sheet(
    parts: &[Part],
    prepared: &Prepared,
    setup: &Setup,
    opts: &NestOptions,
    pi: usize,
    rng: &mut Rng64,
    budget: &mut Budget,
) -> Result<Sheet, LeftOut> {
    let info = &prepared.parts[pi];
    let id = &parts[info.part].id;
    let kind = prepared
        .kind(info.kind, setup)
        .as_ref()
        .map_err(|reason| LeftOut {
            part: id.clone(),
            reason: reason.clone(),
        })?;
    for stock in 0..setup.usable.len() {
        let u = setup.usable[stock];
        let mut bin = Bin::new(rect(u.0 as f32, u.1 as f32, u.2 as f32, u.3 as f32));
        let samples = opts.construct_samples.max(200);
        if let Some(dt) = bin.blf_position(&kind.item, samples, f32::MAX, rng, budget) {
            bin.add(pi, &kind.item, dt);
            return Ok((stock, bin));
        }
    }
    Err(LeftOut {
        part: id.clone(),
        reason: "no feasible position found on an empty sheet".into(),
    })
}

/// A sheet of parts in rows of their bounding boxes: its stock size, per part its
/// instance (of the prepared parts), rotation (degrees) and translation, and the right
/// end of the grown boxes.
struct RowSheet {
    stock: usize,
    parts: Vec<(usize, f64, [f64; 2])>,
    x_max: f64,
}

/// The allowed rotations that are multiples of 90 degrees (0 and 90 for free rotation).
fn right_angles(range: &RotationRange) -> Vec<f64> {
    match range {
        RotationRange::None => vec![0.0],
        RotationRange::Continuous => vec![0.0, 90.0],
        RotationRange::Discrete(r) => r
            .iter()
            .map(|a| f64::from(*a).to_degrees())
            .filter_map(|d| {
                let q = (d / 90.0).round();
                ((d - 90.0 * q).abs() < 1e-3).then_some((90.0 * q).rem_euclid(360.0))
            })
            .collect(),
    }
}

/// The box of the box `lo`-`hi` turned by `deg` (a multiple of 90) about the origin.
fn turned_box(lo: [f64; 2], hi: [f64; 2], deg: f64) -> ([f64; 2], [f64; 2]) {
    match (deg / 90.0).round() as i64 {
        1 => ([-hi[1], lo[0]], [-lo[1], hi[0]]),
        2 => ([-hi[0], -hi[1]], [-lo[0], -lo[1]]),
        3 => ([lo[1], -hi[0]], [hi[1], -lo[0]]),
        _ => (lo, hi),
    }
}

/// The parts `late` (of the prepared parts) on sheets of the first stock size in rows of
/// their bounding boxes grown by the collision shapes' growth, tallest first, each turned
/// by the allowed right angle that makes it lowest (next fit: a row is full when the next
/// box does not fit its length, a sheet when the next row does not fit its height). No
/// collision shape is needed, so this takes no time; disjoint grown boxes keep the parts
/// the spacing apart. Returns the sheets and the parts no row takes (wider or taller than
/// the sheet in every right angle).
fn in_rows(prepared: &Prepared, setup: &Setup, late: &[usize]) -> (Vec<RowSheet>, Vec<usize>) {
    let g = setup.grow;
    let u = setup.usable[0];
    let angles = right_angles(&setup.range);
    // (instance, rotation, width, height, lower left of the turned box)
    let mut boxes: Vec<(usize, f64, f64, f64, [f64; 2])> = Vec::new();
    let mut wide = Vec::new();
    for &pi in late {
        let (lo, hi) = prepared.parts[pi].bounds;
        let mut best: Option<(f64, f64, f64, [f64; 2])> = None;
        for &a in &angles {
            let (rlo, rhi) = turned_box(lo, hi, a);
            let (w, h) = (rhi[0] - rlo[0] + 2.0 * g, rhi[1] - rlo[1] + 2.0 * g);
            if w <= u.2 - u.0 && h <= u.3 - u.1 && best.is_none_or(|b| h < b.2) {
                best = Some((a, w, h, rlo));
            }
        }
        match best {
            Some((a, w, h, rlo)) => boxes.push((pi, a, w, h, rlo)),
            None => wide.push(pi),
        }
    }
    boxes.sort_by(|a, b| b.3.total_cmp(&a.3).then(a.0.cmp(&b.0)));
    let mut sheets: Vec<RowSheet> = Vec::new();
    let (mut x, mut y, mut row) = (u.0, u.1, 0.0f64);
    for (pi, a, w, h, rlo) in boxes {
        if x + w > u.2 {
            // the next row
            (x, y, row) = (u.0, y + row, 0.0);
        }
        if sheets.is_empty() || y + h > u.3 {
            sheets.push(RowSheet {
                stock: 0,
                parts: Vec::new(),
                x_max: u.0,
            });
            (x, y, row) = (u.0, u.1, 0.0);
        }
        let sheet = sheets.last_mut().expect("a sheet");
        sheet.parts.push((pi, a, [x + g - rlo[0], y + g - rlo[1]]));
        sheet.x_max = sheet.x_max.max(x + w);
        x += w;
        row = row.max(h);
    }
    (sheets, wide)
}

/// The sheets the search works on: the [`WINDOW`] emptiest (ties: the later), split from
/// the others; both keep their order.
fn split_window(bins: Vec<Sheet>) -> [Vec<Sheet>; 2] {
    let mut by_area: Vec<usize> = (0..bins.len()).collect();
    by_area.sort_by(|&a, &b| {
        bins[a]
            .1
            .area()
            .total_cmp(&bins[b].1.area())
            .then(b.cmp(&a))
    });
    let mut chosen = vec![false; bins.len()];
    for &i in by_area.iter().take(WINDOW) {
        chosen[i] = true;
    }
    let (mut rest, mut window) = (Vec::new(), Vec::new());
    for (i, b) in bins.into_iter().enumerate() {
        if chosen[i] {
            window.push(b);
        } else {
            rest.push(b);
        }
    }
    [rest, window]
}

/// Hears of the sheets of the search's window and its budget.
type Reporter<'a> = &'a mut dyn FnMut(&[Sheet], &Budget);

/// Sheets the search works on (the emptiest ones).
const WINDOW: usize = 7;

/// Failed tries in a row to empty the emptiest sheet that end the first phase of the search
/// (the rest of its work goes to the compaction): a sheet of parts that the others have no
/// room for, such as strips nearly as long as the sheet, fails every try, and each one
/// separates those large parts, the search's dearest work.
const EMPTYING_TRIES: usize = 4;

/// Failed shrinks in a row that end the compaction of the last sheet (the shrink falls from
/// 5 % to its least, 0.2 %, in seven): parts that span the sheet, such as strips nearly as
/// long as it, leave nothing to compact, and separating them is the search's dearest work.
const COMPACTION_FAILURES: usize = 10;

/// The search on `window` (the emptiest sheets; `others` more are not touched): while there
/// are more sheets than the lower bound, half the work is not spent and fewer than
/// [`EMPTYING_TRIES`] tries in a row failed, try to empty the emptiest sheet into the others
/// (each part into the first of the emptiest sheets that takes it, by bottom-left fill
/// behind its filled front, else inserted with overlap into the emptiest one and separated;
/// a sheet with less free area than the part is not tried); then move the emptiest sheet
/// last and compact it towards the left so that the offcut is one rectangle (until the
/// work is spent or [`COMPACTION_FAILURES`] shrinks in a row failed).
/// `report` hears of every sheet saved.
fn improve(
    window: &mut Vec<Sheet>,
    others: usize,
    lb: usize,
    rng: &mut Rng64,
    budget: &mut Budget,
    opts: &NestOptions,
    report: Reporter<'_>,
) {
    let work = budget.work().unwrap_or(u64::MAX);
    let phase1_done = |b: &Budget| b.done() || b.evals >= work / 2;
    let emptiest_last = |w: &mut Vec<Sheet>| {
        if let Some(k) =
            (0..w.len()).min_by(|&a, &b| w[a].1.area().total_cmp(&w[b].1.area()).then(b.cmp(&a)))
        {
            let b = w.remove(k);
            w.push(b);
        }
    };
    emptiest_last(window);
    let mut tries = 0;
    while window.len() >= 2
        && others + window.len() > lb.max(1)
        && !phase1_done(budget)
        && tries < EMPTYING_TRIES
    {
        let (last_stock, mut last) = window.pop().expect("non-empty");
        let mut targets: Vec<usize> = (0..window.len()).collect();
        targets.sort_by(|&a, &b| {
            window[a]
                .1
                .area()
                .total_cmp(&window[b].1.area())
                .then(a.cmp(&b))
        });
        let saved: Vec<_> = targets.iter().map(|&t| window[t].1.save()).collect();
        let saved_last = last.save();
        let mut ok = true;
        while let Some(mem) = last.members.last().cloned() {
            let idx = last.members.len() - 1;
            let mut moved = false;
            for &t in &targets {
                let bin = &mut window[t].1;
                if mem.item.area() > room(bin) {
                    continue;
                }
                let filled = bin.used_x_max();
                if let Some(dt) = bin.blf_position_behind(
                    &mem.item,
                    opts.construct_samples,
                    f32::MAX,
                    Some(filled),
                    rng,
                    budget,
                ) {
                    bin.add(mem.inst, &mem.item, dt);
                    moved = true;
                    break;
                }
            }
            if !moved && mem.item.area() <= room(&window[targets[0]].1) {
                // insert with overlap into the emptiest sheet and separate
                let bin = &mut window[targets[0]].1;
                let snap = bin.save();
                bin.add_anywhere(mem.inst, &mem.item, rng);
                if bin.separate(rng, budget, 2, 25) {
                    moved = true;
                } else {
                    bin.restore(&snap);
                }
            }
            if !moved {
                ok = false;
                break;
            }
            last.remove(idx);
            if phase1_done(budget) && !last.members.is_empty() {
                ok = false;
                break;
            }
        }
        if ok && last.members.is_empty() {
            tries = 0;
            emptiest_last(window);
            report(window, budget);
        } else {
            last.restore(&saved_last);
            for (&t, sn) in targets.iter().zip(&saved) {
                window[t].1.restore(sn);
            }
            window.push((last_stock, last));
            tries += 1;
        }
    }
    // compact the last sheet towards x_min so the offcut is one rectangle
    if let Some((_, last)) = window.last_mut() {
        let full = last.bounds;
        let slack = |x: f32| x + (x.abs() * 1e-5).max(1e-5);
        let mut best_x = slack(last.used_x_max());
        last.set_bounds(rect(full.x_min, full.y_min, best_x, full.y_max));
        let mut best = last.save();
        let mut ratio = 0.05f32;
        let mut failures = 0;
        while !budget.done() && last.members.len() > 1 && failures < COMPACTION_FAILURES {
            let target = full.x_min + (best_x - full.x_min) * (1.0 - ratio);
            last.set_bounds(rect(full.x_min, full.y_min, target, full.y_max));
            for i in 0..last.members.len() {
                let sb = last.placed_shape(i).bbox();
                if sb.x_max > target {
                    let dt = last.members[i].dt;
                    let (tx, ty) = dt.translation();
                    last.relocate(
                        i,
                        DTransformation::new(dt.rotation(), (tx - (sb.x_max - target), ty)),
                    );
                }
            }
            if last.separate(rng, budget, 2, 30) {
                best_x = slack(last.used_x_max());
                last.set_bounds(rect(full.x_min, full.y_min, best_x, full.y_max));
                best = last.save();
                failures = 0;
            } else {
                last.restore(&best);
                ratio = (ratio * 0.6).max(0.002);
                failures += 1;
            }
        }
        last.restore(&best);
        last.set_bounds(full);
    }
    report(window, budget);
}

/// Free area of a sheet: its bounds less the area of its parts' shapes.
fn room(bin: &Bin) -> f32 {
    let r = bin.bounds;
    (r.x_max - r.x_min) * (r.y_max - r.y_min) - bin.area()
}

/// Seconds per collision evaluation of the sheet search on the reference machine (2 cores)
/// for parts of `vertices` collision vertices on average: a fixed part and a part per
/// vertex, fitted to the CPU time of the pavilion and the dome (docs/nesting.md).
fn sheet_seconds_per_evaluation(vertices: f64) -> f64 {
    1.0e-6 + 0.045e-6 * vertices
}

/// Wall seconds of the set-up and the construction on the reference machine, from what
/// they did: jagua-rs's two pole searches per shape (about linear in its vertices, on both
/// cores) and the construction's evaluations (on one).
fn fixed_seconds(shape_vertices: usize, construction_evaluations: u64) -> f64 {
    35e-6 * shape_vertices as f64 + 3e-6 * construction_evaluations as f64
}

/// The work budget of [`nest_sheets`] when none is given: what the searches (one per core)
/// do on the reference machine in a share of the time the set-up and construction leave
/// (`fixed` seconds: the set-up and the construction), scaled with the parts (shapes of `mean_vertices`
/// vertices). The rest is headroom, so that a busy machine still finishes the same work.
pub fn sheet_work_budget(mean_vertices: f64, time: Duration, fixed: f64) -> u64 {
    let searches = DEFAULT_SEARCHES as f64;
    let seconds = crate::engine::WORK_SHARE_OF_TIME * (time.as_secs_f64() - fixed).max(0.0);
    (seconds * searches / sheet_seconds_per_evaluation(mean_vertices)) as u64
}
