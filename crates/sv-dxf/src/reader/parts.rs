//! Closed contours into parts: repeated contours removed, a drawing border recognised,
//! then outlines and holes by layer role and containment. A contour inside a hole (an
//! island) is a slug, not a part, unless asked for; an `INSIDE` contour in no outline is
//! left out by name; etching goes with the part it lies on.

use sv_geom::Contour;

use super::boxes::{BoxIndex, SameBoxes};
use super::chain::{Chained, Open};
use super::source::{Closed, Cut};

/// A contour to classify.
pub(crate) struct Candidate {
    pub(crate) contour: Contour,
    pub(crate) srcs: Vec<usize>,
    pub(crate) cut: Cut,
    area: f64,
    length: f64,
    bounds: ([f64; 2], [f64; 2]),
    probe: [f64; 2],
}

impl Candidate {
    fn new(contour: Contour, srcs: Vec<usize>, cut: Cut) -> Self {
        let area = contour.area();
        let length = contour.length();
        let bounds = contour.bounds().unwrap_or(([0.0; 2], [0.0; 2]));
        let probe = contour.segments().next().map_or([0.0; 2], |s| s.midpoint());
        Self {
            contour,
            srcs,
            cut,
            area,
            length,
            bounds,
            probe,
        }
    }

    fn holds(&self, p: [f64; 2]) -> bool {
        let (lo, hi) = self.bounds;
        p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && self.contour.contains(p)
    }
}

pub(crate) fn candidates(closed: Vec<Closed>, chained: Vec<Chained>) -> Vec<Candidate> {
    let mut out: Vec<Candidate> = closed
        .into_iter()
        .map(|c| Candidate::new(c.contour, vec![c.src], c.cut))
        .collect();
    out.extend(
        chained
            .into_iter()
            .map(|c| Candidate::new(c.contour, c.srcs, c.cut)),
    );
    // file order: by the first entity of each
    out.sort_by_key(|c| c.srcs.first().copied().unwrap_or(usize::MAX));
    out
}

/// What classification found.
#[derive(Default)]
pub(crate) struct Classified {
    /// (outline, holes, sources of the outline)
    pub(crate) parts: Vec<(Contour, Vec<Contour>, Vec<usize>)>,
    /// (sources, what) for the notes
    pub(crate) notes: Vec<(Vec<usize>, String)>,
    /// (sources, what) for contours left out
    pub(crate) rejected: Vec<(Vec<usize>, String)>,
    /// contour pairs compared (repeat and containment tests): the work done, which the
    /// tests bound
    pub(crate) comparisons: usize,
}

/// Whether `b` repeats `a` (the same contour within `tol`, either way round).
fn same(a: &Candidate, b: &Candidate, tol: f64) -> bool {
    let scale = a.area.max(b.area).max(1e-12);
    if (a.area - b.area).abs() > 1e-6 * scale + tol * a.length.max(b.length) {
        return false;
    }
    let close = |x: [f64; 2], y: [f64; 2]| (x[0] - y[0]).abs() <= tol && (x[1] - y[1]).abs() <= tol;
    if !(close(a.bounds.0, b.bounds.0) && close(a.bounds.1, b.bounds.1)) {
        return false;
    }
    let (fa, fb) = (a.contour.flatten(tol / 4.0), b.contour.flatten(tol / 4.0));
    let within = |pts: &[[f64; 2]], poly: &[[f64; 2]]| {
        pts.iter()
            .all(|&p| sv_geom::planar::boundary_distance(p, poly) <= tol)
    };
    within(&fa, &fb) && within(&fb, &fa)
}

/// Indices of `areas` from the smallest, ties in index (file) order.
fn by_area(areas: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..areas.len()).collect();
    order.sort_by(|&a, &b| areas[a].total_cmp(&areas[b]).then(a.cmp(&b)));
    order
}

/// Contours from the smallest (ties in file order), their boxes on a [`BoxIndex`] in that
/// order: the smallest contour around a point is the first that holds it, found without
/// trying every larger contour around it (thousands of nested copies of one contour).
struct BySize {
    /// contour indices, the smallest first
    order: Vec<usize>,
    /// their areas, in that order
    areas: Vec<f64>,
    /// their boxes, in that order
    index: BoxIndex,
}

impl BySize {
    fn new(bounds: &[([f64; 2], [f64; 2])], areas: &[f64]) -> Self {
        let order = by_area(areas);
        let boxes: Vec<_> = order.iter().map(|&i| bounds[i]).collect();
        Self {
            areas: order.iter().map(|&i| areas[i]).collect(),
            index: BoxIndex::new(&boxes, 0.0),
            order,
        }
    }

    /// The smallest contour of area over `above` whose box may hold `p` and that `holds`
    /// it (of equal areas, the first in file order); `holds` is asked about the contours
    /// from the smallest up, until it says yes.
    fn smallest_holding(
        &self,
        p: [f64; 2],
        above: f64,
        mut holds: impl FnMut(usize) -> bool,
    ) -> Option<usize> {
        let from = self.areas.partition_point(|&a| a <= above);
        let rank = self.index.first_at(p, from, |r| holds(self.order[r]))?;
        Some(self.order[rank])
    }
}

/// Each contour's parent (the smallest larger contour holding its probe point) and depth
/// (the contours around it); `tests` counts the containment tests made.
fn containment(cands: &[Candidate], tests: &mut usize) -> (Vec<Option<usize>>, Vec<usize>) {
    let bounds: Vec<_> = cands.iter().map(|c| c.bounds).collect();
    let areas: Vec<f64> = cands.iter().map(|c| c.area).collect();
    let by_size = BySize::new(&bounds, &areas);
    let mut parent = vec![None; cands.len()];
    let mut depth = vec![0; cands.len()];
    // the largest first: a parent is larger, its depth known
    for &i in by_size.order.iter().rev() {
        let p = cands[i].probe;
        parent[i] = by_size.smallest_holding(p, cands[i].area, |j| {
            *tests += 1;
            cands[j].holds(p)
        });
        depth[i] = parent[i].map_or(0, |j| depth[j] + 1);
    }
    (parent, depth)
}

/// Classifies `cands` (see the module doc); `texts` are TEXT positions (a title block).
pub(crate) fn classify(
    mut cands: Vec<Candidate>,
    texts: &[[f64; 2]],
    tol: f64,
    islands: bool,
) -> Classified {
    let mut out = Classified::default();
    // zero-size contours
    cands.retain(|c| {
        let keep = c.area > 1e-9 && c.contour.vertices.len() >= 2;
        if !keep {
            let why = if c.contour.self_intersects() {
                "self-intersecting closed contour (its areas cancel)"
            } else {
                "closed contour of zero area"
            };
            out.rejected.push((c.srcs.clone(), why.into()));
        }
        keep
    });
    // repeated contours: the later copy goes. A repeat's box is within `tol` of the
    // contour's on every side
    let boxes: Vec<_> = cands.iter().map(|c| c.bounds).collect();
    let index = SameBoxes::new(&boxes, tol);
    let order = by_area(&cands.iter().map(|c| c.area).collect::<Vec<_>>());
    let mut rank = vec![0; cands.len()];
    for (k, &i) in order.iter().enumerate() {
        rank[i] = k;
    }
    let mut gone = vec![false; cands.len()];
    for &i in &order {
        if gone[i] {
            continue;
        }
        let mut near: Vec<usize> = index
            .near(&cands[i].bounds)
            .into_iter()
            .filter(|&j| rank[j] > rank[i])
            .collect();
        near.sort_by_key(|&j| rank[j]);
        out.comparisons += near.len();
        for j in near {
            if !gone[j] && same(&cands[i], &cands[j], tol) {
                let (keep, drop) = if i < j { (i, j) } else { (j, i) };
                gone[drop] = true;
                let mut srcs = cands[drop].srcs.clone();
                srcs.extend(&cands[keep].srcs);
                out.notes
                    .push((srcs, "a contour drawn twice: the copy removed".into()));
                if drop == i {
                    break;
                }
            }
        }
    }
    let mut cands: Vec<Candidate> = cands
        .into_iter()
        .zip(gone)
        .filter_map(|(c, g)| (!g).then_some(c))
        .collect();
    let (mut parent, mut depth) = containment(&cands, &mut out.comparisons);
    // a drawing border: a polygon around every other contour that holds a title block
    // (text or lines inside it) or contours inside holes
    if cands.len() > 1 {
        let roots: Vec<usize> = (0..cands.len()).filter(|&i| parent[i].is_none()).collect();
        if let [r] = roots[..] {
            let c = &cands[r];
            let polygon = c.contour.vertices.iter().all(|v| v.bulge == 0.0);
            let text = texts.iter().any(|&t| c.holds(t));
            let deep = depth.iter().any(|&d| d >= 2);
            if polygon && c.cut == Cut::Either && (text || deep) {
                let why = if text {
                    "text inside it"
                } else {
                    "contours inside holes inside it"
                };
                out.notes.push((
                    c.srcs.clone(),
                    format!("read as a drawing border (a polygon around every other contour, with {why}): not a part"),
                ));
                cands.remove(r);
                (parent, depth) = containment(&cands, &mut out.comparisons);
            }
        }
    }
    // kinds, from the roots down
    #[derive(Clone, Copy, PartialEq)]
    enum Kind {
        Outline,
        Hole(usize),
        Slug,
        Orphan,
    }
    let n = cands.len();
    let mut kind: Vec<Option<Kind>> = vec![None; n];
    let mut depth_order: Vec<usize> = (0..n).collect();
    depth_order.sort_by_key(|&i| (depth[i], i));
    for &i in &depth_order {
        let k = match (
            parent[i].and_then(|p| kind[p].map(|k| (p, k))),
            cands[i].cut,
        ) {
            (_, Cut::Outside) => Kind::Outline,
            (None, Cut::Either) => Kind::Outline,
            (None, Cut::Inside) => Kind::Orphan,
            (Some((p, Kind::Outline)), _) => Kind::Hole(p),
            (Some((_, Kind::Hole(o))), Cut::Inside) => Kind::Hole(o),
            (Some((_, Kind::Hole(_))), Cut::Either) => {
                if islands {
                    Kind::Outline
                } else {
                    Kind::Slug
                }
            }
            (Some((_, Kind::Slug | Kind::Orphan)), _) => Kind::Slug,
        };
        kind[i] = Some(k);
    }
    let mut index = vec![usize::MAX; n];
    for i in 0..n {
        match kind[i] {
            Some(Kind::Outline) => {
                index[i] = out.parts.len();
                out.parts
                    .push((cands[i].contour.clone(), Vec::new(), cands[i].srcs.clone()));
            }
            Some(Kind::Orphan) => out.rejected.push((
                cands[i].srcs.clone(),
                "an INSIDE contour within no OUTSIDE outline (nor any other outline)".into(),
            )),
            Some(Kind::Slug) => {
                let top = parent[i].filter(|&p| kind[p] != Some(Kind::Slug));
                if top.is_some() {
                    out.notes.push((
                        cands[i].srcs.clone(),
                        "a contour inside a hole: the slug that falls out, not nested (--islands nests it as a part)".into(),
                    ));
                }
            }
            _ => {}
        }
    }
    for i in 0..n {
        if let Some(Kind::Hole(o)) = kind[i] {
            let k = index[o];
            out.parts[k].1.push(cands[i].contour.clone());
        }
    }
    out
}

/// Etched lines to the smallest part whose outline holds their first point.
pub(crate) fn etch_of(
    parts: &[(Contour, Vec<Contour>, Vec<usize>)],
    etch: Vec<(Vec<[f64; 2]>, usize)>,
    notes: &mut Vec<(Vec<usize>, String)>,
) -> Vec<Vec<Vec<[f64; 2]>>> {
    let boxes: Vec<([f64; 2], [f64; 2])> = parts
        .iter()
        .map(|p| p.0.bounds().unwrap_or(([0.0; 2], [0.0; 2])))
        .collect();
    let areas: Vec<f64> = parts.iter().map(|p| p.0.area()).collect();
    let by_size = BySize::new(&boxes, &areas);
    let mut out = vec![Vec::new(); parts.len()];
    for (line, src) in etch {
        let p = line[0];
        let on = by_size.smallest_holding(p, f64::NEG_INFINITY, |k| {
            let (lo, hi) = boxes[k];
            p[0] >= lo[0]
                && p[0] <= hi[0]
                && p[1] >= lo[1]
                && p[1] <= hi[1]
                && parts[k].0.contains(p)
        });
        match on {
            Some(k) => out[k].push(line),
            None => notes.push((vec![src], "etching on no part: not etched".into())),
        }
    }
    out
}

/// Open runs split into those whose loose ends all lie on a contour (lines drawn up to a
/// contour: bend, construction or title-block lines, not cut) and the rest; the rest is one
/// message naming the smallest gap between loose ends, so that the user can set the join
/// tolerance.
pub(crate) fn open_runs(
    open: Vec<Open>,
    contours: &[&Contour],
    tol: f64,
) -> (Vec<Open>, Option<(Vec<usize>, String)>) {
    if open.is_empty() {
        return (open, None);
    }
    let boxes: Vec<([f64; 2], [f64; 2])> = contours
        .iter()
        .map(|c| c.bounds().unwrap_or(([0.0; 2], [0.0; 2])))
        .collect();
    let index = BoxIndex::new(&boxes, tol);
    // each contour flattened once, when a loose end first comes near it
    let flat: Vec<std::cell::OnceCell<Vec<[f64; 2]>>> = contours
        .iter()
        .map(|_| std::cell::OnceCell::new())
        .collect();
    let on_contour = |p: [f64; 2]| {
        index.at(p).into_iter().any(|k| {
            let (lo, hi) = boxes[k];
            p[0] >= lo[0] - tol
                && p[1] >= lo[1] - tol
                && p[0] <= hi[0] + tol
                && p[1] <= hi[1] + tol
                && sv_geom::planar::boundary_distance(
                    p,
                    flat[k].get_or_init(|| contours[k].flatten(tol / 4.0)),
                ) <= tol * 1.25
        })
    };
    let (attached, loose): (Vec<Open>, Vec<Open>) = open
        .into_iter()
        .partition(|o| !o.loose.is_empty() && o.loose.iter().all(|&p| on_contour(p)));
    if loose.is_empty() {
        return (attached, None);
    }
    let ends: Vec<[f64; 2]> = loose.iter().flat_map(|o| o.loose.iter().copied()).collect();
    let best = nearest_pair(&ends).map(|(d, i, _)| (d, ends[i]));
    let srcs: Vec<usize> = loose.iter().flat_map(|o| o.srcs.iter().copied()).collect();
    let why = match best {
        Some((d, p)) => format!(
            "open contour: {} loose ends; the nearest two are {d:.3} mm apart at ({:.3}, {:.3}), more than the join tolerance {tol} mm",
            ends.len(),
            p[0],
            p[1]
        ),
        None => "open contour".into(),
    };
    (attached, Some((srcs, why)))
}

/// The two nearest of `points` (finite): their distance and indices, the one first in x
/// (then y) first; `None` for fewer than two. A sweep in x keeping the points within the
/// best distance so far in a tree ordered by y: `n log n` for any layout (loose ends
/// stacked on one vertical line too).
fn nearest_pair(points: &[[f64; 2]]) -> Option<(f64, usize, usize)> {
    // an integer key with the order of the f64 (finite values)
    let key = |v: f64| {
        let b = v.to_bits() as i64;
        b ^ (((b >> 63) as u64) >> 1) as i64
    };
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        (points[a][0], points[a][1])
            .partial_cmp(&(points[b][0], points[b][1]))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut best: Option<(f64, usize, usize)> = None;
    // (y key, index) of the points less than the best distance behind in x
    let mut band = std::collections::BTreeSet::new();
    let mut left = 0;
    for &j in &order {
        let q = points[j];
        if let Some((d, _, _)) = best {
            while points[order[left]][0] < q[0] - d {
                band.remove(&(key(points[order[left]][1]), order[left]));
                left += 1;
            }
        }
        let (lo, hi) = match best {
            Some((0.0, _, _)) => break,
            Some((d, _, _)) => (key(q[1] - d), key(q[1] + d)),
            None => (i64::MIN, i64::MAX),
        };
        for &(_, i) in band.range((lo, 0)..=(hi, usize::MAX)) {
            let p = points[i];
            let d = (p[0] - q[0]).hypot(p[1] - q[1]);
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, i, j));
            }
        }
        band.insert((key(q[1]), j));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `n` concentric squares, sides 1 to `n` mm, in file order from the smallest.
    fn nested_squares(n: usize) -> Vec<Candidate> {
        (1..=n)
            .map(|k| {
                let h = k as f64 / 2.0;
                let square = Contour::polygon(&[[-h, -h], [h, -h], [h, h], [-h, h]]);
                Candidate::new(square, vec![k - 1], Cut::Either)
            })
            .collect()
    }

    /// 2 to 50 loose ends: on one vertical column, on a small grid with repeats, over
    /// mixed scales, or anywhere.
    fn loose_ends() -> impl Strategy<Value = Vec<[f64; 2]>> {
        let column = (0.0..100.0f64).prop_map(|y| [3.0, y.round()]);
        let grid = (0..6i32, 0..6i32).prop_map(|(x, y)| [f64::from(x), f64::from(y)]);
        let scales = (-1e4..0.0f64, 0.0..1e-3f64).prop_map(|(x, y)| [x, y]);
        let anywhere = (-500.0..500.0f64, -500.0..500.0f64).prop_map(|(x, y)| [x, y]);
        prop_oneof![
            prop::collection::vec(column, 2..50),
            prop::collection::vec(grid, 2..50),
            prop::collection::vec(scales, 2..50),
            prop::collection::vec(anywhere, 2..50),
        ]
    }

    proptest! {
        #[test]
        fn the_nearest_pair_is_that_of_every_pair(pts in loose_ends()) {
            let mut every = f64::INFINITY;
            for i in 0..pts.len() {
                for j in i + 1..pts.len() {
                    every = every.min((pts[i][0] - pts[j][0]).hypot(pts[i][1] - pts[j][1]));
                }
            }
            let (d, i, j) = nearest_pair(&pts).unwrap();
            prop_assert_eq!(d, every, "{:?}", pts);
            prop_assert_eq!(d, (pts[i][0] - pts[j][0]).hypot(pts[i][1] - pts[j][1]));
            prop_assert_ne!(i, j);
        }
    }

    #[test]
    fn one_loose_end_has_no_nearest_pair() {
        assert_eq!(nearest_pair(&[[1.0, 2.0]]), None);
    }

    /// Thousands of nested copies of one contour (a block inserting itself scaled): each
    /// is compared with a few others, not with every copy around it (3,000 squares took
    /// 4.5 million comparisons); the classification is the same: the outermost a drawing
    /// border, then outline, hole, island outline, hole, ... with `--islands`.
    #[test]
    fn thousands_of_nested_contours_are_compared_a_few_times_each() {
        let n = 3000;
        let found = classify(nested_squares(n), &[], 0.05, true);
        assert!(
            found.comparisons <= 3 * n,
            "{} comparisons for {n} contours",
            found.comparisons
        );
        assert_eq!(found.notes.len(), 1, "the border");
        assert_eq!(found.notes[0].0, vec![n - 1]);
        assert_eq!(found.parts.len(), (n - 1).div_ceil(2));
        for (k, (outline, holes, srcs)) in found.parts.iter().enumerate() {
            // file order: the smallest first; each outline holds the next smaller square
            assert_eq!(srcs, &vec![n - 2 - 2 * (found.parts.len() - 1 - k)]);
            assert_eq!(holes.len(), usize::from(srcs[0] > 0), "part {k}");
            if let Some(hole) = holes.first() {
                assert!((outline.area() - hole.area()).abs() > 0.0);
                assert!((hole.area().sqrt() - srcs[0] as f64).abs() < 1e-9);
            }
        }
        // without islands: one part, a hole, and slugs
        let found = classify(nested_squares(n), &[], 0.05, false);
        assert_eq!(found.parts.len(), 1);
        assert_eq!(found.parts[0].1.len(), 1);
        assert!(found.comparisons <= 3 * n);
    }
}
