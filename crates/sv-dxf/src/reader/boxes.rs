//! Which boxes hold a point: a uniform grid over axis-aligned boxes, so that a file of
//! thousands of contours finds the few that matter to each one (repeats, the contour
//! around it, the part an etched line lies on) without a pass over all of them.

/// Boxes `(lo, hi)` on a uniform grid; [`BoxIndex::at`] lists those that may hold a point.
pub(crate) struct BoxIndex {
    origin: [f64; 2],
    cell: f64,
    cols: usize,
    rows: usize,
    /// box indices per cell, row-major
    cells: Vec<Vec<usize>>,
    /// boxes spanning too many cells to register in each (a drawing border): tried always
    wide: Vec<usize>,
}

/// Cells a box may span before it goes to [`BoxIndex::wide`].
const MAX_CELLS_PER_BOX: usize = 64;

impl BoxIndex {
    /// An index of `boxes`, each grown by `grow` on every side; the grid's cell is about
    /// the median box size, so a box spans a few cells.
    pub(crate) fn new(boxes: &[([f64; 2], [f64; 2])], grow: f64) -> Self {
        let finite = |b: &&([f64; 2], [f64; 2])| b.0.iter().chain(&b.1).all(|v| v.is_finite());
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        let mut sizes: Vec<f64> = Vec::with_capacity(boxes.len());
        for b in boxes.iter().filter(finite) {
            for k in 0..2 {
                lo[k] = lo[k].min(b.0[k] - grow);
                hi[k] = hi[k].max(b.1[k] + grow);
            }
            sizes.push((b.1[0] - b.0[0]).max(b.1[1] - b.0[1]) + 2.0 * grow);
        }
        let mut index = Self {
            origin: lo,
            cell: 1.0,
            cols: 1,
            rows: 1,
            cells: vec![Vec::new()],
            wide: Vec::new(),
        };
        if sizes.is_empty() {
            index.wide = (0..boxes.len()).collect();
            return index;
        }
        sizes.sort_by(f64::total_cmp);
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        // at most about 4 cells per box on average, and never a cell finer than the
        // extent allows for a grid of a few million cells
        let cap = (4 * boxes.len()).clamp(1, 1 << 22) as f64;
        let cell = sizes[sizes.len() / 2].max(span / cap.sqrt()).max(1e-9);
        index.cell = cell;
        index.cols = (((hi[0] - lo[0]) / cell).floor() as usize + 1).max(1);
        index.rows = (((hi[1] - lo[1]) / cell).floor() as usize + 1).max(1);
        index.cells = vec![Vec::new(); index.cols * index.rows];
        for (i, b) in boxes.iter().enumerate() {
            if !finite(&b) {
                index.wide.push(i);
                continue;
            }
            let (c0, r0) = index.cell_of([b.0[0] - grow, b.0[1] - grow]);
            let (c1, r1) = index.cell_of([b.1[0] + grow, b.1[1] + grow]);
            if c1 < c0 || r1 < r0 || (c1 - c0 + 1) * (r1 - r0 + 1) > MAX_CELLS_PER_BOX {
                index.wide.push(i);
                continue;
            }
            for r in r0..=r1 {
                for c in c0..=c1 {
                    index.cells[r * index.cols + c].push(i);
                }
            }
        }
        index
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

    /// The boxes (indices, ascending) that may hold `p` (grown boxes holding it, and
    /// perhaps a few more: the caller checks).
    pub(crate) fn at(&self, p: [f64; 2]) -> Vec<usize> {
        let (c, r) = self.cell_of(p);
        let mut out: Vec<usize> = self.cells[r * self.cols + c]
            .iter()
            .chain(&self.wide)
            .copied()
            .collect();
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

    #[test]
    fn no_boxes_and_non_finite_boxes_do_not_panic() {
        assert!(BoxIndex::new(&[], 0.1).at([1.0, 2.0]).is_empty());
        let index = BoxIndex::new(&[([f64::NAN, 0.0], [1.0, 1.0]), ([0.0; 2], [1.0; 2])], 0.0);
        assert_eq!(index.at([0.5, 0.5]), vec![0, 1]);
        assert_eq!(index.at([f64::NAN, 0.5]), vec![0, 1]);
    }
}
