//! The set-up of a sheet job: every part's outline checked, congruent outlines grouped, and
//! one jagua-rs item made per group ([`crate::shape`]), on every core. The items are made in
//! the order the construction needs them, and the construction starts with the first one
//! ready ([`Prepared::item`] waits for, or makes, the one asked for), so placing overlaps
//! the set-up. Whoever makes an item, it is the same item: the result does not depend on
//! the threads.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};

use jagua_rs::entities::Item;
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::geometry::geo_enums::RotationRange;
use jagua_rs::geometry::primitives::{Point, SPolygon};
use jagua_rs::geometry::shape_modification::{ShapeModifyConfig, ShapeModifyMode};
use jagua_rs::geometry::{AllowedOrientations, DTransformation, OriginalShape};

use crate::engine::rotated_bbox;
use crate::part::polygon_area;
use crate::shape::{self, Congruence, Outline, Rigid, Signature};
use crate::Part;
use cavalier_contours::polyline::{PlineSource, Polyline};

/// Pole surrogates of the shapes the construction places: as few poles as jagua-rs makes
/// (two). Placing only asks whether a shape collides, which the poles play no part in, and
/// each pole is a search over the shape that costs milliseconds for a long strip.
const PLACING_SURROGATE: SPSurrogateConfig = SPSurrogateConfig {
    n_pole_limits: [(1, 0.0), (1, 0.0), (1, 0.0)],
    ff_pole_area_ratio: 0.0,
    n_ff_piers: 0,
};

/// Pole surrogates of the shapes the search moves (the parts of the few sheets it works
/// on): the separator's overlap measure is made of poles.
const SEARCH_SURROGATE: SPSurrogateConfig = SPSurrogateConfig {
    n_pole_limits: [(8, 0.0), (6, 0.8), (4, 0.9)],
    ff_pole_area_ratio: 0.0,
    n_ff_piers: 0,
};

/// Largest share of its area by which a collision shape may grow when it is simplified.
const SIMPLIFY: f64 = 0.001;

/// Outlines the same within this distance (mm) share a collision shape; it is part of the
/// growth, so the shared shape still holds each of them grown by half the spacing.
const CONGRUENT: f64 = 1e-4;

/// The geometry every part needs before nesting.
pub(crate) struct Setup {
    /// half the spacing plus the rounding allowance: the growth of the collision shapes
    pub grow: f64,
    /// chord tolerance of the arcs
    pub tolerance: f64,
    /// allowed rotations
    pub range: RotationRange,
    /// usable rectangle of each stock size `(x0, y0, x1, y1)`
    pub usable: Vec<(f64, f64, f64, f64)>,
    /// half the spacing (the growth of the lower bound's areas)
    pub half_spacing: f64,
}

/// One part as the nester sees it.
pub(crate) struct PartInfo {
    /// index in the caller's parts
    pub part: usize,
    /// its collision shape
    pub kind: usize,
    /// part coordinates to the shape's coordinates
    pub frame: Rigid,
    /// outline area (arcs exact)
    pub area: f64,
    /// the construction order: outline area x diameter of the outline's vertices
    pub key: f64,
    /// bounding box of the outline in the part's coordinates (arcs exact)
    pub bounds: ([f64; 2], [f64; 2]),
}

/// A collision shape shared by congruent parts.
pub(crate) struct Kind {
    /// the shape as the construction places it
    pub item: Arc<Item>,
    /// the same shape with the search's poles, made when the search needs it
    rich: OnceLock<Arc<Item>>,
    orig: OriginalShape,
    /// the outline grown by half the spacing: its area (for the lower bounds)
    pub lb_area: f64,
    /// the collision polygon's area
    pub area: f64,
    /// its bounding box sides, the shorter first
    pub sides: (f64, f64),
    /// the centre of the shape in the representative's coordinates (item coordinates are
    /// relative to it)
    pub centre: [f64; 2],
}

/// The parts of a job with their shapes being made.
pub(crate) struct Prepared {
    /// parts that can be nested, in the construction order (largest first)
    pub parts: Vec<PartInfo>,
    /// parts left out at once: (part index, reason)
    pub bad: Vec<(usize, String)>,
    /// the checked outline of each kind's representative part (which defines the shape)
    reps: Vec<Polyline<f64>>,
    kinds: Vec<OnceLock<Result<Kind, String>>>,
    /// kinds in the order the construction first needs them
    jobs: Vec<usize>,
    next_job: AtomicUsize,
    /// set when the construction is over: the workers make no more items
    stop: AtomicBool,
    done: Mutex<usize>,
    ready: Condvar,
}

impl Prepared {
    /// Checks every outline (on every core) and groups congruent ones; no item is made
    /// yet.
    pub fn new(parts: &[Part]) -> Self {
        let checked: Vec<Result<(Outline, Signature), String>> = parallel_map(parts.len(), |i| {
            let p = shape::outline(&parts[i].outer)?;
            let sig = Signature::new(&p);
            Ok((Outline::new(p), sig))
        });
        let mut bad = Vec::new();
        let mut sigs = Vec::new();
        let mut outlines = Vec::new();
        let mut owners = Vec::new();
        for (i, c) in checked.into_iter().enumerate() {
            match c {
                Ok((o, s)) => {
                    outlines.push(o);
                    sigs.push(s);
                    owners.push(i);
                }
                Err(reason) => bad.push((i, reason)),
            }
        }
        let mut groups = Congruence::new(CONGRUENT);
        let mut reps = Vec::new();
        let mut kind_of_rep = Vec::new();
        let mut infos = Vec::with_capacity(outlines.len());
        for k in 0..outlines.len() {
            let (kind, motion) = match groups.classify(k, &sigs) {
                Some((r, m)) => (kind_of_rep[r], m),
                None => {
                    reps.push(outlines[k].pline.clone());
                    kind_of_rep.resize(k + 1, usize::MAX);
                    kind_of_rep[k] = reps.len() - 1;
                    (reps.len() - 1, Rigid::IDENTITY)
                }
            };
            kind_of_rep.resize(k + 1, usize::MAX);
            infos.push(PartInfo {
                part: owners[k],
                kind,
                // the part is motion(rep): back to the representative's frame; the shape's
                // own centring is added once the shape is made
                frame: motion.inverse(),
                area: outlines[k].area,
                key: outlines[k].key,
                bounds: outlines[k].bounds,
            });
        }
        infos.sort_by(|a, b| b.key.total_cmp(&a.key).then(a.part.cmp(&b.part)));
        let mut jobs = Vec::with_capacity(reps.len());
        let mut queued = vec![false; reps.len()];
        for p in &infos {
            if !queued[p.kind] {
                queued[p.kind] = true;
                jobs.push(p.kind);
            }
        }
        Self {
            parts: infos,
            bad,
            kinds: (0..reps.len()).map(|_| OnceLock::new()).collect(),
            reps,
            jobs,
            next_job: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
            done: Mutex::new(0),
            ready: Condvar::new(),
        }
    }

    /// Number of distinct collision shapes.
    pub fn kind_count(&self) -> usize {
        self.reps.len()
    }

    /// The shapes made so far (all of them once the construction is done).
    pub fn kinds_made(&self) -> impl Iterator<Item = &Kind> {
        self.kinds.iter().filter_map(|k| k.get()?.as_ref().ok())
    }

    /// Makes items until none is left or [`Prepared::stop`] is called (a worker thread's
    /// loop).
    pub fn work(&self, setup: &Setup) {
        while !self.stop.load(Ordering::Relaxed) {
            if !self.make_next(setup) {
                break;
            }
        }
    }

    /// Tells the workers to make no more items (the construction is over: the items of
    /// the parts it placed are made; those of the parts the clock left are not needed).
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    /// Makes the next item in line; `false` when all are taken.
    fn make_next(&self, setup: &Setup) -> bool {
        let j = self.next_job.fetch_add(1, Ordering::Relaxed);
        let Some(&kind) = self.jobs.get(j) else {
            return false;
        };
        let made = make_kind(&self.reps[kind], kind, setup);
        let _ = self.kinds[kind].set(made);
        let mut done = self.done.lock().unwrap_or_else(|e| e.into_inner());
        *done += 1;
        self.ready.notify_all();
        true
    }

    /// The shape of `kind`, made by this thread when it is next in line, else waited for.
    pub fn kind(&self, kind: usize, setup: &Setup) -> &Result<Kind, String> {
        loop {
            if let Some(k) = self.kinds[kind].get() {
                return k;
            }
            if !self.make_next(setup) {
                let done = self.done.lock().unwrap_or_else(|e| e.into_inner());
                if self.kinds[kind].get().is_none() {
                    // another thread is making it
                    let _unused = self
                        .ready
                        .wait_while(done, |_| self.kinds[kind].get().is_none())
                        .unwrap_or_else(|e| e.into_inner());
                }
            }
        }
    }
}

impl Kind {
    /// The shape with the search's poles (made once; the same shape as [`Kind::item`]).
    pub fn rich(&self) -> Arc<Item> {
        Arc::clone(self.rich.get_or_init(|| {
            let it = &self.item;
            Arc::new(
                Item::new(
                    it.idx(),
                    it.external_id(),
                    self.orig.clone(),
                    it.allowed_orientations().clone(),
                    None,
                    SEARCH_SURROGATE,
                )
                .unwrap_or_else(|_| it.as_ref().clone()),
            )
        }))
    }
}

/// `f(0..n)` on every core, in order.
pub(crate) fn parallel_map<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    use rayon::prelude::*;
    (0..n).into_par_iter().map(f).collect()
}

/// The collision shape of a kind from its representative's outline `p`, as a jagua-rs item in coordinates
/// centred on the shape, with the lower bound's area and a check that it fits some sheet.
/// The grown outline is simplified outward (rounds become sharp corners, notches are
/// filled), which can make it a little longer than the part: where that stand-in fits no
/// sheet, the outline as flattened is tried, then with every round kept, so that a part as
/// long as the sheet's margins allow is not refused for its stand-in.
fn make_kind(p: &Polyline<f64>, kind: usize, setup: &Setup) -> Result<Kind, String> {
    let lb_area = shape::grown(p, setup.half_spacing).area();
    let g = shape::grown(p, setup.grow);
    // the rounds of grown corners become sharp corners when that adds little
    let tiny = 1e-4 * g.area();
    let flattened = shape::flatten_outside(&g, setup.tolerance, tiny);
    let budget = SIMPLIFY * polygon_area(&flattened);
    let filled = shape::simplify_outside(&flattened, budget);
    let first = if shape::is_simple(&filled) {
        filled
    } else {
        flattened.clone()
    };
    for poly in [Some(first), Some(flattened), None] {
        let poly = poly.unwrap_or_else(|| shape::flatten_outside(&g, setup.tolerance, 0.0));
        let poly = if shape::is_simple(&poly) {
            poly
        } else {
            // the grown outline nearly touches itself (a gap narrower than the chord
            // tolerance): its convex hull is simple and still holds it
            shape::convex_hull(&poly)
        };
        if let Some(made) = stand_in(&poly, kind, setup, lb_area)? {
            return Ok(made);
        }
    }
    let (olo, ohi) = p
        .extents()
        .map(|e| ([e.min_x, e.min_y], [e.max_x, e.max_y]))
        .unwrap_or(([0.0; 2], [0.0; 2]));
    let s = 2.0 * setup.half_spacing;
    // what it was compared with: each stock size inside its margins, with spacing too
    let usable: Vec<String> = setup
        .usable
        .iter()
        .map(|u| format!("{:.1} x {:.1}", u.2 - u.0, u.3 - u.1))
        .collect();
    Err(format!(
        "larger than every sheet ({:.1} x {:.1} mm with spacing; usable inside the margins, \
         with spacing: {} mm)",
        ohi[0] - olo[0] + s,
        ohi[1] - olo[1] + s,
        usable.join(", ")
    ))
}

/// [`make_kind`] with the grown outline `poly`; `None` where it fits no sheet.
fn stand_in(
    poly: &[[f64; 2]],
    kind: usize,
    setup: &Setup,
    lb_area: f64,
) -> Result<Option<Kind>, String> {
    let c = centroid(poly);
    let (lo, hi) = crate::part::bbox(poly);
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    let mut pts: Vec<Point> = poly
        .iter()
        .map(|q| Point((q[0] - c[0]) as f32, (q[1] - c[1]) as f32))
        .collect();
    // vertices closer than f32 tells apart are one
    pts.dedup();
    while pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    let shape = SPolygon::new(pts).map_err(|e| format!("{e:#}"))?;
    let area = f64::from(shape.area());
    // already grown and simplified: jagua-rs takes it as it is
    let orig = OriginalShape {
        shape,
        pre_transform: DTransformation::empty(),
        modify_mode: ShapeModifyMode::Inflate,
        modify_config: ShapeModifyConfig::default(),
    };
    let item = AllowedOrientations::new(setup.range.clone(), vec![])
        .and_then(|ao| Item::new(kind, kind as u64, orig.clone(), ao, None, PLACING_SURROGATE))
        .map_err(|e| format!("{e:#}"))?;
    let rots: Vec<f32> = match &setup.range {
        RotationRange::None => vec![0.0],
        RotationRange::Discrete(r) => r.clone(),
        RotationRange::Continuous => (0..360).map(|d| (d as f32).to_radians()).collect(),
    };
    let fits = setup.usable.iter().any(|u| {
        rots.iter().any(|&r| {
            let b = rotated_bbox(item.shape_cd(), r);
            f64::from(b.x_max - b.x_min) <= u.2 - u.0 && f64::from(b.y_max - b.y_min) <= u.3 - u.1
        })
    });
    if !fits {
        return Ok(None);
    }
    Ok(Some(Kind {
        item: Arc::new(item),
        rich: OnceLock::new(),
        orig,
        sides: (w.min(h), w.max(h)),
        lb_area,
        area,
        centre: c,
    }))
}

/// Area centroid of a polygon.
fn centroid(pts: &[[f64; 2]]) -> [f64; 2] {
    let n = pts.len();
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (p, q) = (pts[i], pts[(i + 1) % n]);
        let w = p[0] * q[1] - q[0] * p[1];
        a += w;
        cx += (p[0] + q[0]) * w;
        cy += (p[1] + q[1]) * w;
    }
    if a.abs() < 1e-12 {
        return pts[0];
    }
    [cx / (3.0 * a), cy / (3.0 * a)]
}
