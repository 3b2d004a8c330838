//! Bin packing of parts onto rectangular stock sheets (`nest.json`).

use std::sync::Arc;
use std::time::Duration;

use jagua_rs::entities::Item;
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::geometry::geo_enums::RotationRange;
use jagua_rs::geometry::primitives::{Point, SPolygon};
use jagua_rs::geometry::shape_modification::{offset_shape, ShapeModifyConfig, ShapeModifyMode};
use jagua_rs::geometry::{AllowedOrientations, DTransformation, OriginalShape};
use jagua_rs::io::import::centering_transformation;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::engine::{rect, rotated_bbox, Bin, Budget, Rng64};
use crate::part::polygon_area;
use crate::strip::Progress;
use crate::{NestError, Part, DEFAULT_FLATTEN_TOLERANCE};

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

/// Largest area growth (ratio) when jagua-rs simplifies an outline for collision checks;
/// simplification only adds area, so spacing still holds.
const SIMPLIFY_TOLERANCE: f32 = 0.001;

/// Pole surrogates of sheet parts: fewer poles than the strip-packing benchmark items get.
/// Fabrication parts have hundreds of vertices (a 19-unit strip at 110 mm: about 580), and
/// the poles cost about linear time each in the vertex count: 64 poles took 160 ms per
/// such part, more than a short nesting budget.
const SHEET_SURROGATE: SPSurrogateConfig = SPSurrogateConfig {
    n_pole_limits: [(24, 0.0), (12, 0.8), (6, 0.9)],
    ff_pole_area_ratio: 0.0,
    n_ff_piers: 0,
};

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
    /// wall-clock budget
    pub time_limit: Duration,
    /// optional cap on collision evaluations (deterministic budget)
    pub max_evaluations: Option<u64>,
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
}

/// Martello-Toth L2 and the area bound for item sizes `a` in bins of capacity `cap`.
pub fn lower_bounds(a: &[f64], cap: f64) -> LowerBounds {
    let eps = 1e-9 * cap;
    let total: f64 = a.iter().sum();
    let area = ((total / cap) - 1e-9).ceil().max(0.0) as usize;
    let mut ks: Vec<f64> = a.iter().copied().filter(|&x| x <= cap / 2.0).collect();
    ks.push(0.0);
    let mut best = 0;
    for &k in &ks {
        let j1 = a.iter().filter(|&&x| x > cap - k + eps).count();
        let j2: Vec<f64> = a
            .iter()
            .copied()
            .filter(|&x| x <= cap - k + eps && x > cap / 2.0 + eps)
            .collect();
        let j3: f64 = a
            .iter()
            .copied()
            .filter(|&x| x <= cap / 2.0 + eps && x >= k - eps)
            .sum();
        let free = j2.len() as f64 * cap - j2.iter().sum::<f64>();
        let extra = ((j3 - free) / cap - 1e-9).ceil().max(0.0) as usize;
        best = best.max(j1 + j2.len() + extra);
    }
    LowerBounds {
        area,
        martello_toth: best,
    }
}

struct Prepared {
    part: usize,
    item: Arc<Item>,
    /// centroid used by the pre-transform (f64)
    centre: [f64; 2],
    area: f64,
}

fn to_spolygon(pts: &[[f64; 2]]) -> Result<SPolygon, String> {
    SPolygon::new(
        pts.iter()
            .map(|p| Point(p[0] as f32, p[1] as f32))
            .collect(),
    )
    .map_err(|e| format!("{e:#}"))
}

/// Nests `parts` onto sheets. Bad parts are reported in `left_out`; the others are nested.
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
    // the clock starts here: preparing the parts (outlines, surrogates) is part of the budget
    let mut budget = Budget::new(opts.time_limit, opts.max_evaluations);
    let range = opts.rotations.range()?;
    let (m, s) = (opts.margin, opts.spacing);
    let grow = s / 2.0 + opts.flatten_tolerance + 1e-3 + s * 1e-3;
    // containers: inflated parts inside [m - s/2, W - m + s/2]
    let usable: Vec<(f64, f64, f64, f64)> = opts
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
        .collect();
    // outlines, collision shapes and surrogates: the costly part of the set-up, so it runs
    // on every core; results are gathered in part order (deterministic)
    let prepare = |pi: usize| -> Result<(Prepared, f64), LeftOut> {
        let part = &parts[pi];
        let bad = |reason: String| LeftOut {
            part: part.id.clone(),
            reason,
        };
        let pts = part
            .validated_outline(opts.flatten_tolerance)
            .map_err(|e| bad(e.to_string()))?;
        let shape = to_spolygon(&pts).map_err(|e| bad(format!("part {}: {e}", part.id)))?;
        let pre = centering_transformation(&shape);
        let (cx, cy) = pre.translation();
        let orig = OriginalShape {
            shape: shape.clone(),
            pre_transform: pre,
            modify_mode: ShapeModifyMode::Inflate,
            modify_config: ShapeModifyConfig {
                offset: Some(grow as f32),
                // conservative (the outline only grows): 0.1 % of the area at most
                simplify_tolerance: Some(SIMPLIFY_TOLERANCE),
                ..ShapeModifyConfig::default()
            },
        };
        let item = AllowedOrientations::new(range.clone(), vec![])
            .and_then(|ao| Item::new(pi, pi as u64, orig, ao, None, SHEET_SURROGATE))
            .map(Arc::new)
            .map_err(|e| bad(format!("part {}: {e:#}", part.id)))?;
        // fits some sheet in some rotation?
        let rots: Vec<f32> = match &range {
            RotationRange::None => vec![0.0],
            RotationRange::Discrete(r) => r.clone(),
            RotationRange::Continuous => (0..360).map(|d| (d as f32).to_radians()).collect(),
        };
        let fits = usable.iter().any(|u| {
            rots.iter().any(|&r| {
                let b = rotated_bbox(item.shape_cd(), r);
                f64::from(b.x_max - b.x_min) <= u.2 - u.0
                    && f64::from(b.y_max - b.y_min) <= u.3 - u.1
            })
        });
        if !fits {
            let (lo, hi) = crate::part::bbox(&pts);
            return Err(bad(NestError::TooLarge {
                part: part.id.clone(),
                width: hi[0] - lo[0] + s,
                height: hi[1] - lo[1] + s,
            }
            .to_string()));
        }
        let area = polygon_area(&pts).abs();
        let lb_area = if s > 0.0 {
            offset_shape(&shape, ShapeModifyMode::Inflate, (s / 2.0) as f32)
                .map(|sp| f64::from(sp.area()))
                .unwrap_or(area)
        } else {
            area
        };
        let p = Prepared {
            part: pi,
            item,
            centre: [-f64::from(cx), -f64::from(cy)],
            area,
        };
        Ok((p, lb_area))
    };
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, parts.len().max(1));
    let mut results: Vec<Option<Result<(Prepared, f64), LeftOut>>> =
        (0..parts.len()).map(|_| None).collect();
    std::thread::scope(|scope| {
        let prepare = &prepare;
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    (t..parts.len())
                        .step_by(threads)
                        .map(|pi| (pi, prepare(pi)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            // a panic in a worker is a bug; re-raise it here
            for (pi, r) in h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)) {
                results[pi] = Some(r);
            }
        }
    });
    let mut left_out = Vec::new();
    let mut prepared = Vec::new();
    let mut lb_sizes = Vec::new();
    for r in results.into_iter().flatten() {
        match r {
            Ok((p, lb_area)) => {
                lb_sizes.push(lb_area);
                prepared.push(p);
            }
            Err(l) => left_out.push(l),
        }
    }
    let cap = usable
        .iter()
        .map(|u| (u.2 - u.0) * (u.3 - u.1))
        .fold(0.0, f64::max);
    let lbs = lower_bounds(&lb_sizes, cap);
    let lb = lbs.area.max(lbs.martello_toth);

    let mut rng = Rng64::seed_from_u64(opts.seed);
    let mut order: Vec<usize> = (0..prepared.len()).collect();
    let key = |p: &Prepared| {
        let sh = p.item.shape_cd();
        sh.surrogate().convex_hull_area * sh.diameter()
    };
    order.sort_by(|&a, &b| {
        key(&prepared[b])
            .total_cmp(&key(&prepared[a]))
            .then(a.cmp(&b))
    });
    let mk_bin = |stock: usize| {
        let u = usable[stock];
        Bin::new(rect(u.0 as f32, u.1 as f32, u.2 as f32, u.3 as f32))
    };
    let mut bins: Vec<(usize, Bin)> = Vec::new();
    for &pi in &order {
        let item = &prepared[pi].item;
        let mut placed = false;
        for (_, bin) in bins.iter_mut() {
            if let Some(dt) = bin.blf_position(
                item,
                opts.construct_samples,
                f32::MAX,
                &mut rng,
                &mut budget,
            ) {
                bin.add(pi, item, dt);
                placed = true;
                break;
            }
        }
        if !placed {
            for stock in 0..usable.len() {
                let mut bin = mk_bin(stock);
                if let Some(dt) = bin.blf_position(
                    item,
                    opts.construct_samples.max(200),
                    f32::MAX,
                    &mut rng,
                    &mut budget,
                ) {
                    bin.add(pi, item, dt);
                    bins.push((stock, bin));
                    placed = true;
                    break;
                }
            }
        }
        if !placed {
            left_out.push(LeftOut {
                part: parts[prepared[pi].part].id.clone(),
                reason: format!(
                    "part {}: no feasible position found on an empty sheet",
                    parts[prepared[pi].part].id
                ),
            });
        }
    }
    let report_progress =
        |bins: &[(usize, Bin)], budget: &Budget, progress: &mut dyn FnMut(&Progress)| {
            let used: f64 = bins
                .iter()
                .map(|(st, _)| opts.sheets[*st].width * opts.sheets[*st].height)
                .sum();
            let area: f64 = bins
                .iter()
                .flat_map(|(_, b)| b.members.iter().map(|m| prepared[m.inst].area))
                .sum();
            progress(&Progress {
                elapsed_s: budget.elapsed().as_secs_f64(),
                evaluations: budget.evals,
                best: bins.len() as f64,
                density: if used > 0.0 { area / used } else { 0.0 },
            });
        };
    report_progress(&bins, &budget, progress);

    // phase 1: try to empty the last sheet into the others
    let phase1_evals = opts.max_evaluations.map(|e| e / 2);
    let phase1_time = opts.time_limit / 2;
    let phase1_done = |b: &Budget| {
        b.done() || phase1_evals.is_some_and(|e| b.evals >= e) || b.elapsed() >= phase1_time
    };
    while bins.len() > lb.max(1) && !phase1_done(&budget) {
        let saved: Vec<_> = bins.iter().map(|(_, b)| b.save()).collect();
        let (last_stock, mut last) = bins.pop().expect("non-empty");
        let mut ok = true;
        while let Some(mem) = last.members.last().cloned() {
            let idx = last.members.len() - 1;
            let mut moved = false;
            for (_, bin) in bins.iter_mut() {
                if let Some(dt) = bin.blf_position(
                    &mem.item,
                    opts.construct_samples,
                    f32::MAX,
                    &mut rng,
                    &mut budget,
                ) {
                    bin.add(mem.inst, &mem.item, dt);
                    moved = true;
                    break;
                }
            }
            if !moved {
                // insert with overlap into the emptiest sheet and separate
                let target = (0..bins.len())
                    .min_by(|&a, &b| bins[a].1.area().total_cmp(&bins[b].1.area()))
                    .expect("at least one sheet");
                let bin = &mut bins[target].1;
                let snap = bin.save();
                let rot = crate::engine::sample_rotation(&mem.item, &mut rng);
                let rb = rotated_bbox(mem.item.shape_cd(), rot);
                let b = bin.bounds;
                let tx = b.x_min - rb.x_min
                    + rand::Rng::random_range(&mut rng, 0.0..=1.0f32)
                        * ((b.x_max - rb.x_max) - (b.x_min - rb.x_min)).max(0.0);
                let ty = b.y_min - rb.y_min
                    + rand::Rng::random_range(&mut rng, 0.0..=1.0f32)
                        * ((b.y_max - rb.y_max) - (b.y_min - rb.y_min)).max(0.0);
                bin.add(mem.inst, &mem.item, DTransformation::new(rot, (tx, ty)));
                if bin.separate(&mut rng, &mut budget, 2, 25) {
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
            if phase1_done(&budget) && !last.members.is_empty() {
                ok = false;
                break;
            }
        }
        if ok && last.members.is_empty() {
            report_progress(&bins, &budget, progress);
        } else {
            bins.push((last_stock, last));
            for ((_, b), sn) in bins.iter_mut().zip(&saved) {
                b.restore(sn);
            }
        }
    }

    // phase 2: compact the last sheet towards x_min so the offcut is one rectangle
    if let Some((_, last)) = bins.last_mut() {
        let full = last.bounds;
        let slack = |x: f32| x + (x.abs() * 1e-5).max(1e-5);
        let mut best_x = slack(last.used_x_max());
        last.set_bounds(rect(full.x_min, full.y_min, best_x, full.y_max));
        let mut best = last.save();
        let mut ratio = 0.05f32;
        while !budget.done() && last.members.len() > 1 {
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
            if last.separate(&mut rng, &mut budget, 2, 30) {
                best_x = slack(last.used_x_max());
                last.set_bounds(rect(full.x_min, full.y_min, best_x, full.y_max));
                best = last.save();
            } else {
                last.restore(&best);
                ratio = (ratio * 0.6).max(0.002);
            }
        }
        last.restore(&best);
        last.set_bounds(full);
    }
    report_progress(&bins, &budget, progress);

    // report
    let mut sheets = Vec::new();
    for (stock, bin) in &bins {
        let st = opts.sheets[*stock];
        let mut placements: Vec<(usize, PartPlacement)> = bin
            .members
            .iter()
            .map(|mem| {
                let p = &prepared[mem.inst];
                let rot = f64::from(mem.dt.rotation());
                let (tx, ty) = mem.dt.translation();
                let (sn, cs) = rot.sin_cos();
                let [cx, cy] = p.centre;
                // p_sheet = R (p - c) + t
                let t = [
                    f64::from(tx) - (cs * cx - sn * cy),
                    f64::from(ty) - (sn * cx + cs * cy),
                ];
                (
                    p.part,
                    PartPlacement {
                        strip: parts[p.part].id.clone(),
                        translation: t,
                        rotation_deg: rot.to_degrees().rem_euclid(360.0),
                    },
                )
            })
            .collect();
        placements.sort_by_key(|p| p.0);
        let area: f64 = bin.members.iter().map(|mm| prepared[mm.inst].area).sum();
        sheets.push(SheetReport {
            width: st.width,
            height: st.height,
            placements: placements.into_iter().map(|p| p.1).collect(),
            utilisation: area / (st.width * st.height),
        });
    }
    let offcut = bins.last().map(|(stock, bin)| {
        let st = opts.sheets[*stock];
        // used_x_max is on grown outlines; the true part edge is `grow` inside it
        let x = (f64::from(bin.used_x_max()) - grow + s).min(st.width);
        Offcut {
            sheet: bins.len() - 1,
            x,
            y: 0.0,
            width: (st.width - x).max(0.0),
            height: st.height,
        }
    });
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
    })
}
