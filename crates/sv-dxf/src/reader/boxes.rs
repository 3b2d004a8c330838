//! Which boxes hold a point: uniform grids over axis-aligned boxes, so that a file of
//! thousands of contours finds the few that matter to each one (repeats, the contour
//! around it, the part an etched line lies on) without a pass over all of them.
//!
//! A box goes on the finest grid where it spans at most [`MAX_CELLS_PER_BOX`] cells; each
//! grid's cells are [`COARSER`] times wider than the one before. So a drawing border, or
//! thousands of overlapping copies of a large contour, sit on a coarse grid with few
//! cells, and a point is looked up in one cell per grid. [`BoxIndex::first_at`] tries them
//! in order and stops at the first that holds the point (the smallest contour around it,
//! when the boxes are in order of area), so thousands of nested copies of a contour are
//! not all tried for every point. [`SameBoxes`] finds the boxes nearly equal to a box,
//! for the repeats of a contour.

use std::collections::HashMap;

/// Boxes `(lo, hi)` on uniform grids; [`BoxIndex::at`] lists those that may hold a point.
pub(crate) struct BoxIndex {
    /// the grids, finest first
    grids: Vec<Grid>,
    /// boxes with a coordinate that is not finite: tried always
    unplaced: Vec<usize>,
}

/// One grid of [`BoxIndex`].
struct Grid {
    origin: [f64; 2],
    cell: f64,
    cols: usize,
    rows: usize,
    /// box indices per cell, row-major
    cells: Vec<Vec<usize>>,
}

/// Cells a box may span on a grid before it goes to a coarser one.
const MAX_CELLS_PER_BOX: usize = 64;

/// How much wider a grid's cells are than the finer grid's.
const COARSER: f64 = 8.0;

impl Grid {
    fn new(lo: [f64; 2], hi: [f64; 2], cell: f64) -> Self {
        let cols = (((hi[0] - lo[0]) / cell).floor() as usize + 1).max(1);
        let rows = (((hi[1] - lo[1]) / cell).floor() as usize + 1).max(1);
        Self {
            origin: lo,
            cell,
            cols,
            rows,
            cells: vec![Vec::new(); cols * rows],
        }
    }

    /// The cell holding `p`, clamped to the grid.
    fn cell_of(&self, p: [f64; 2]) -> (usize, usize) {
        let f = |v: f64, o: f64, n: usize| {
            let k = ((v - o) / self.cell).floor();
            if k.is_nan() || k < 0.0 {
                0
            } else {
                (k as usize).min(n - 1)
            }
        };
        (
            f(p[0], self.origin[0], self.cols),
            f(p[1], self.origin[1], self.rows),
        )
    }

    /// The cells from `lo` to `hi`, if they are at most [`MAX_CELLS_PER_BOX`].
    fn span(&self, lo: [f64; 2], hi: [f64; 2]) -> Option<((usize, usize), (usize, usize))> {
        let (c0, r0) = self.cell_of(lo);
        let (c1, r1) = self.cell_of(hi);
        (c1 >= c0 && r1 >= r0 && (c1 - c0 + 1) * (r1 - r0 + 1) <= MAX_CELLS_PER_BOX)
            .then_some(((c0, r0), (c1, r1)))
    }
}

impl BoxIndex {
    /// An index of `boxes`, each grown by `grow` on every side; the finest grid's cell is
    /// about the median box size, so a box spans a few cells.
    pub(crate) fn new(boxes: &[([f64; 2], [f64; 2])], grow: f64) -> Self {
        let finite = |b: &([f64; 2], [f64; 2])| b.0.iter().chain(&b.1).all(|v| v.is_finite());
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        let mut sizes: Vec<f64> = Vec::with_capacity(boxes.len());
        for b in boxes.iter().filter(|b| finite(b)) {
            for k in 0..2 {
                lo[k] = lo[k].min(b.0[k] - grow);
                hi[k] = hi[k].max(b.1[k] + grow);
            }
            sizes.push((b.1[0] - b.0[0]).max(b.1[1] - b.0[1]) + 2.0 * grow);
        }
        let mut index = Self {
            grids: Vec::new(),
            unplaced: Vec::new(),
        };
        if sizes.is_empty() {
            index.unplaced = (0..boxes.len()).collect();
            return index;
        }
        sizes.sort_by(f64::total_cmp);
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        // at most about 4 cells per box on average, and never a cell finer than the
        // extent allows for a grid of a few million cells
        let cap = (4 * boxes.len()).clamp(1, 1 << 22) as f64;
        let cell = sizes[sizes.len() / 2].max(span / cap.sqrt()).max(1e-9);
        for (i, b) in boxes.iter().enumerate() {
            if !finite(b) {
                index.unplaced.push(i);
                continue;
            }
            let (blo, bhi) = (
                [b.0[0] - grow, b.0[1] - grow],
                [b.1[0] + grow, b.1[1] + grow],
            );
            // the finest grid where it spans few cells (the coarsest grid has one cell, or
            // two across where a box meets its edge)
            let mut level = 0;
            let ((c0, r0), (c1, r1)) = loop {
                if level == index.grids.len() {
                    let coarser = cell * COARSER.powi(level as i32);
                    index.grids.push(Grid::new(lo, hi, coarser));
                }
                let grid = &index.grids[level];
                match grid.span(blo, bhi) {
                    Some(cells) => break cells,
                    None if grid.cols * grid.rows == 1 => break ((0, 0), (0, 0)),
                    None => level += 1,
                }
            };
            let grid = &mut index.grids[level];
            for r in r0..=r1 {
                for c in c0..=c1 {
                    grid.cells[r * grid.cols + c].push(i);
                }
            }
        }
        index
    }

    /// The boxes (indices, ascending) that may hold `p` (grown boxes holding it, and
    /// perhaps a few more: the caller checks).
    pub(crate) fn at(&self, p: [f64; 2]) -> Vec<usize> {
        let mut out: Vec<usize> = self.lists(p).concat();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The first box from index `from` on, in ascending order, that may hold `p` and for
    /// which `hit` is true: the boxes after it are not tried. A box is on one grid, and a
    /// point in one cell of each, so each box comes once.
    pub(crate) fn first_at(
        &self,
        p: [f64; 2],
        from: usize,
        mut hit: impl FnMut(usize) -> bool,
    ) -> Option<usize> {
        // one ascending list per grid, merged
        let mut lists: Vec<&[usize]> = self
            .lists(p)
            .into_iter()
            .map(|l| &l[l.partition_point(|&i| i < from)..])
            .collect();
        loop {
            let (k, &i) = lists
                .iter()
                .enumerate()
                .filter_map(|(k, l)| l.first().map(|i| (k, i)))
                .min_by_key(|&(_, i)| *i)?;
            if hit(i) {
                return Some(i);
            }
            lists[k] = &lists[k][1..];
        }
    }

    /// The lists of boxes that may hold `p`, each ascending: the unplaced ones and one
    /// cell of every grid.
    fn lists(&self, p: [f64; 2]) -> Vec<&[usize]> {
        let mut lists = vec![self.unplaced.as_slice()];
        for grid in &self.grids {
            let (c, r) = grid.cell_of(p);
            lists.push(&grid.cells[r * grid.cols + c]);
        }
        lists
    }
}

/// Boxes by their four sides rounded to a step: [`SameBoxes::near`] lists those whose
/// sides may each be within half a step of a box's (repeats of a contour), without the
/// boxes that only share a corner with it (copies of a contour scaled about its corner).
pub(crate) struct SameBoxes {
    step: f64,
    cells: HashMap<[i64; 4], Vec<usize>>,
}

impl SameBoxes {
    /// `boxes` keyed by their sides in units of `2 tol`, so that sides within `tol` of
    /// each other are in the same or the next unit (float rounding included).
    pub(crate) fn new(boxes: &[([f64; 2], [f64; 2])], tol: f64) -> Self {
        let mut index = Self {
            step: 2.0 * tol,
            cells: HashMap::new(),
        };
        for (i, b) in boxes.iter().enumerate() {
            index.cells.entry(index.key(b)).or_default().push(i);
        }
        index
    }

    fn key(&self, b: &([f64; 2], [f64; 2])) -> [i64; 4] {
        // `as` saturates (and takes NaN to 0): far-out boxes share a key, never go amiss
        [b.0[0], b.0[1], b.1[0], b.1[1]].map(|v| (v / self.step).floor() as i64)
    }

    /// The boxes (indices, ascending) whose sides may each be within `tol` of `b`'s, and
    /// perhaps a few more: the caller checks.
    pub(crate) fn near(&self, b: &([f64; 2], [f64; 2])) -> Vec<usize> {
        let key = self.key(b);
        let mut out = Vec::new();
        for around in 0..81 {
            let mut k = key;
            let mut code = around;
            for side in &mut k {
                *side = side.saturating_add(code % 3 - 1);
                code /= 3;
            }
            if let Some(list) = self.cells.get(&k) {
                out.extend_from_slice(list);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every box that holds a point is listed, wide ones and far-off points included.
    #[test]
    fn every_box_holding_a_point_is_listed() {
        let mut boxes: Vec<([f64; 2], [f64; 2])> = (0..400)
            .map(|k| {
                let (x, y) = (60.0 * (k % 20) as f64, 40.0 * (k / 20) as f64);
                ([x, y], [x + 40.0, y + 25.0])
            })
            .collect();
        boxes.push(([-5.0, -5.0], [1300.0, 900.0])); // a border
        boxes.push(([10.0, 10.0], [10.0, 10.0])); // a point
        let grow = 0.05;
        let index = BoxIndex::new(&boxes, grow);
        let holds = |b: &([f64; 2], [f64; 2]), p: [f64; 2]| {
            (0..2).all(|k| p[k] >= b.0[k] - grow && p[k] <= b.1[k] + grow)
        };
        for p in [
            [0.0, 0.0],
            [10.0, 10.0],
            [39.99, 24.99],
            [40.04, 25.04],
            [59.97, 12.0],
            [1199.0, 799.0],
            [5000.0, -300.0],
        ] {
            let got = index.at(p);
            for (i, b) in boxes.iter().enumerate() {
                if holds(b, p) {
                    assert!(
                        got.contains(&i),
                        "{p:?}: box {i} {b:?} missing from {got:?}"
                    );
                }
            }
        }
        // a point inside one plate lists a few boxes, not all of them
        assert!(
            index.at([70.0, 50.0]).len() <= 8,
            "{:?}",
            index.at([70.0, 50.0])
        );
    }

    /// Large boxes spread over the drawing (copies of a big contour) sit on coarser grids:
    /// a point lists the few whose cells it is in, not all of them (the one list of wide
    /// boxes every lookup went through made a file of thousands of them quadratic).
    #[test]
    fn large_boxes_spread_out_are_not_listed_everywhere() {
        // 10,000 plates of 10 mm 100 mm apart, 200 boxes of 2 m over them (each 40 cells
        // across on the finest grid)
        let mut boxes: Vec<([f64; 2], [f64; 2])> = Vec::new();
        for k in 0..10_000 {
            let (x, y) = (100.0 * (k % 100) as f64, 100.0 * (k / 100) as f64);
            boxes.push(([x, y], [x + 10.0, y + 10.0]));
        }
        for k in 0..200u64 {
            let (x, y) = ((k * 7919 % 8000) as f64, (k * 104_729 % 8000) as f64);
            boxes.push(([x, y], [x + 2000.0, y + 2000.0]));
        }
        let index = BoxIndex::new(&boxes, 0.0);
        let mut longest = 0;
        for k in 0..400u64 {
            let p = [
                (k * 613 % 10_000) as f64 + 0.5,
                (k * 997 % 10_000) as f64 + 0.5,
            ];
            let got = index.at(p);
            for (i, b) in boxes.iter().enumerate() {
                if (0..2).all(|j| p[j] >= b.0[j] && p[j] <= b.1[j]) {
                    assert!(got.contains(&i), "{p:?}: box {i} missing");
                }
            }
            longest = longest.max(got.len());
        }
        assert!(longest <= 60, "a point lists up to {longest} boxes");
    }

    /// `first_at` tries the boxes holding a point in ascending order from `from` and stops
    /// at the first hit; `near` lists every box whose sides are all within `tol`, and not
    /// a box that only shares its corner (a copy scaled about it).
    #[test]
    fn first_hits_and_near_boxes_are_found() {
        let tol = 0.05;
        let mut boxes: Vec<([f64; 2], [f64; 2])> = (1..=200)
            .map(|k| ([0.0, 0.0], [k as f64, k as f64]))
            .collect();
        // copies of box 9 (sides 10) moved by up to `tol`, a side exactly `tol` off too
        for (k, d) in [0.0, 0.01, -0.03, 0.049_999, tol, -tol].iter().enumerate() {
            let e = if k % 2 == 0 { *d } else { -*d };
            boxes.push(([*d, e], [10.0 + e, 10.0 + *d]));
        }
        let index = BoxIndex::new(&boxes, 0.0);
        let mut tried = Vec::new();
        let hit = index.first_at([5.0, 5.0], 20, |i| {
            tried.push(i);
            i >= 30
        });
        assert_eq!(hit, Some(30));
        assert_eq!(tried, (20..=30).collect::<Vec<_>>());
        // boxes whose cells hold the point are tried: the caller says which hold it
        let holds =
            |i: usize, p: [f64; 2]| (0..2).all(|k| p[k] >= boxes[i].0[k] && p[k] <= boxes[i].1[k]);
        assert_eq!(
            index.first_at([150.0, 5.0], 0, |i| holds(i, [150.0, 5.0])),
            Some(149)
        );
        assert_eq!(index.first_at([150.0, 5.0], 0, |_| false), None);
        let same = SameBoxes::new(&boxes, tol);
        let near = same.near(&boxes[9]);
        for (i, b) in boxes.iter().enumerate() {
            let within = (0..2).all(|k| {
                (b.0[k] - boxes[9].0[k]).abs() <= tol && (b.1[k] - boxes[9].1[k]).abs() <= tol
            });
            if within {
                assert!(near.contains(&i), "box {i} {b:?}");
            }
        }
        // of the boxes sharing its corner, only itself
        assert_eq!(near.iter().filter(|&&i| i < 200).collect::<Vec<_>>(), [&9]);
    }

    #[test]
    fn no_boxes_and_non_finite_boxes_do_not_panic() {
        assert!(BoxIndex::new(&[], 0.1).at([1.0, 2.0]).is_empty());
        let index = BoxIndex::new(&[([f64::NAN, 0.0], [1.0, 1.0]), ([0.0; 2], [1.0; 2])], 0.0);
        assert_eq!(index.at([0.5, 0.5]), vec![0, 1]);
        assert_eq!(index.at([f64::NAN, 0.5]), vec![0, 1]);
        assert_eq!(index.first_at([f64::NAN, 0.5], 1, |_| true), Some(1));
        let same = SameBoxes::new(&[([f64::NAN, 0.0], [1.0, 1.0]), ([0.0; 2], [1.0; 2])], 0.1);
        assert!(same.near(&([0.0; 2], [1.0; 2])).contains(&1));
    }
}
