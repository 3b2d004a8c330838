//! Sparse least squares: the normal equations of a Gauss-Newton step assembled row by row
//! ([`NormalEquations`]) and solved by a sparse Cholesky factorisation ([`SpdSolver`])
//! whose symbolic part is computed once and reused for every iteration (Gauss-Newton
//! iterations keep the pattern of `J^T J`). Values are scattered straight into the
//! compressed columns through a precomputed position map, so an iteration costs one pass
//! over the entries and one numeric factorisation.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// A failure of the sparse solver's set-up (a pattern outside the matrix, no memory): a
/// defect of the caller, not of the input.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SparseError(pub String);

impl std::fmt::Display for SparseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SparseError {}

/// A symmetric matrix pattern given as a list of upper-triangle entries `(row, col)`,
/// `row <= col`, duplicates allowed (they are summed).
pub struct SpdSolver {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// compressed position of every pattern entry
    pos: Vec<u32>,
    /// compressed values (upper triangle, column major)
    values: Vec<f64>,
    cholesky: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
}

impl SpdSolver {
    /// Analyse the pattern (`entries` upper-triangle positions, with duplicates).
    pub fn new(n: usize, entries: &[(usize, usize)]) -> Result<Self, SparseError> {
        if entries.len() >= u32::MAX as usize {
            return Err(SparseError("sparse pattern too large".into()));
        }
        let key = |k: usize| {
            let (r, c) = entries[k];
            (r.max(c), r.min(c))
        };
        if let Some(&(r, c)) = entries.iter().find(|&&(r, c)| r.max(c) >= n) {
            return Err(SparseError(format!(
                "sparse entry ({r}, {c}) outside a {n} x {n} matrix"
            )));
        }
        let mut order: Vec<u32> = (0..entries.len() as u32).collect();
        order.sort_unstable_by_key(|&k| key(k as usize));
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::new();
        let mut pos = vec![0u32; entries.len()];
        let mut last = None;
        for &k in &order {
            let (c, r) = key(k as usize);
            if last != Some((c, r)) {
                row_idx.push(r);
                col_ptr[c + 1] += 1;
                last = Some((c, r));
            }
            pos[k as usize] = (row_idx.len() - 1) as u32;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let symbolic = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let cholesky = factorize_symbolic_cholesky(
            symbolic,
            Side::Upper,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| SparseError(format!("symbolic cholesky: {e:?}")))?;
        let l_values = vec![0.0; cholesky.len_val()];
        let req = cholesky
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(cholesky.solve_in_place_scratch::<f64>(1, Par::Seq));
        let buffer = MemBuffer::try_new(req)
            .map_err(|_| SparseError("out of memory for cholesky".into()))?;
        let values = vec![0.0; row_idx.len()];
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            pos,
            values,
            cholesky,
            l_values,
            buffer,
        })
    }

    /// Compressed position of pattern entry `k` (in the order given to [`SpdSolver::new`]).
    pub fn positions(&self) -> &[u32] {
        &self.pos
    }

    /// The compressed values, to be filled through [`SpdSolver::positions`].
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Damp the current values: every diagonal entry `d` becomes `d (1 + lambda) + lambda
    /// floor`, where `floor` is `floor_fraction` of the mean diagonal (Marquardt's scaling,
    /// with Levenberg's term for columns the residuals hardly see). Every column of the
    /// pattern must hold its diagonal (the last entry of its column of the upper triangle).
    pub fn damp_diagonal(&mut self, lambda: f64, floor_fraction: f64) {
        let diag = |c: usize| {
            let end = self.col_ptr[c + 1];
            (end > self.col_ptr[c] && self.row_idx[end - 1] == c).then_some(end - 1)
        };
        let sum: f64 = (0..self.n).filter_map(diag).map(|i| self.values[i]).sum();
        let floor = floor_fraction * sum / self.n.max(1) as f64;
        for c in 0..self.n {
            if let Some(i) = diag(c) {
                self.values[i] = self.values[i] * (1.0 + lambda) + lambda * floor;
            }
        }
    }

    /// Set the values from a list in pattern order (duplicates summed).
    pub fn set_values(&mut self, entries: &[f64]) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for (k, &v) in entries.iter().enumerate() {
            self.values[self.pos[k] as usize] += v;
        }
    }

    /// Factorise the current values and solve `A x = rhs` in place. Returns false when
    /// the matrix is not positive definite.
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<bool, SparseError> {
        if rhs.len() != self.n {
            return Err(SparseError(format!(
                "right-hand side of length {} for a {} x {} system",
                rhs.len(),
                self.n,
                self.n
            )));
        }
        let symbolic = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let matrix = SparseColMatRef::new(symbolic, &self.values);
        let llt = match self.cholesky.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            matrix,
            Side::Upper,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.buffer),
            Default::default(),
        ) {
            Ok(llt) => llt,
            Err(_) => return Ok(false),
        };
        let n = self.n;
        let rhs_mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        llt.solve_in_place_with_conj(Conj::No, rhs_mat, Par::Seq, MemStack::new(&mut self.buffer));
        Ok(true)
    }
}

/// The normal equations `(J^T W J + eps I) dx = -J^T W r` of a least-squares problem,
/// assembled one residual at a time ([`NormalEquations::row`]) in the same order every
/// iteration. The first assembly records the pattern and analyses it; later ones scatter
/// each product straight to its compressed position (rows of weight 0 are skipped in O(1)).
/// Every assembly's rows must name the same columns in the same order as the first's
/// (checked: a fingerprint of the columns).
pub struct NormalEquations {
    n: usize,
    first: bool,
    pattern: Vec<(usize, usize)>,
    first_values: Vec<f64>,
    pos: Vec<u32>,
    cursor: usize,
    /// the columns of the current assembly's rows, and of the first's
    columns: u64,
    pattern_columns: u64,
    values: Vec<f64>,
    solver: Option<SpdSolver>,
    /// `-J^T W r`, the right-hand side of the current assembly.
    pub rhs: Vec<f64>,
    /// `sum w^2 r^2` of the current assembly.
    pub energy: f64,
}

impl NormalEquations {
    /// Normal equations over `n` unknowns.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            first: true,
            pattern: Vec::new(),
            first_values: Vec::new(),
            pos: Vec::new(),
            cursor: 0,
            columns: 0,
            pattern_columns: 0,
            values: Vec::new(),
            solver: None,
            rhs: vec![0.0; n],
            energy: 0.0,
        }
    }

    /// Start an assembly: every entry zero but the diagonal, `regulariser`.
    pub fn reset(&mut self, regulariser: f64) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        self.rhs.iter_mut().for_each(|r| *r = 0.0);
        self.energy = 0.0;
        self.cursor = 0;
        self.columns = 0;
        for i in 0..self.n {
            self.entry(i, i, regulariser);
        }
    }

    #[inline]
    fn entry(&mut self, a: usize, b: usize, v: f64) {
        if self.first {
            self.pattern.push((a.min(b), a.max(b)));
            self.first_values.push(v);
        } else {
            self.values[self.pos[self.cursor] as usize] += v;
        }
        self.cursor += 1;
    }

    /// Fold a row's columns into [`NormalEquations::columns`] (FNV-1a over the indices
    /// and a row end).
    fn fingerprint(&mut self, cols: &[usize]) {
        const PRIME: u64 = 0x0000_0100_0000_01b3;
        let mut h = self.columns ^ 0xcbf2_9ce4_8422_2325;
        for &c in cols.iter().chain(&[usize::MAX]) {
            h = (h ^ c as u64).wrapping_mul(PRIME);
        }
        self.columns = h;
    }

    /// One residual `r` with gradient `vals` over distinct columns `cols`, weight `w`.
    pub fn row(&mut self, cols: &[usize], vals: &[f64], r: f64, w: f64) {
        self.fingerprint(cols);
        let m = cols.len();
        if w == 0.0 && !self.first {
            self.cursor += m * (m + 1) / 2;
            return;
        }
        let w2 = w * w;
        self.energy += w2 * r * r;
        for a in 0..m {
            self.rhs[cols[a]] -= w2 * vals[a] * r;
            for b in a..m {
                self.entry(cols[a], cols[b], w2 * vals[a] * vals[b]);
            }
        }
    }

    /// A block of residuals over the same distinct columns `cols`: each row `(vals, r, w)`
    /// as in [`NormalEquations::row`], `vals` one value per column. One pass over the
    /// block's `m (m + 1) / 2` entries, however many rows it has.
    pub fn block(&mut self, cols: &[usize], rows: &[(&[f64], f64, f64)]) {
        self.fingerprint(cols);
        let m = cols.len();
        // the Gram matrix of the rows that weigh, upper triangle, row by row
        let mut gram = vec![0.0; m * m];
        for &(vals, r, w) in rows {
            let w2 = w * w;
            if w2 == 0.0 {
                continue;
            }
            self.energy += w2 * r * r;
            for a in 0..m {
                let va = w2 * vals[a];
                if va == 0.0 {
                    continue;
                }
                self.rhs[cols[a]] -= va * r;
                let line = &mut gram[a * m..(a + 1) * m];
                for b in a..m {
                    line[b] += va * vals[b];
                }
            }
        }
        for a in 0..m {
            for b in a..m {
                self.entry(cols[a], cols[b], gram[a * m + b]);
            }
        }
    }

    /// Solve the assembled equations into `dx`. `Ok(false)` when they are not positive
    /// definite. The first call analyses the pattern.
    pub fn solve(&mut self, dx: &mut [f64]) -> Result<bool, SparseError> {
        self.solve_damped(0.0, dx)
    }

    /// Solve the assembled equations damped by `lambda` ([`SpdSolver::damp_diagonal`],
    /// Levenberg-Marquardt); the assembly is kept, so several `lambda` can be tried.
    pub fn solve_damped(&mut self, lambda: f64, dx: &mut [f64]) -> Result<bool, SparseError> {
        if self.first {
            let mut solver = SpdSolver::new(self.n, &self.pattern)?;
            solver.set_values(&self.first_values);
            self.pos = solver.positions().to_vec();
            self.values = solver.values_mut().to_vec();
            self.pattern_columns = self.columns;
            self.first = false;
            self.pattern = Vec::new();
            self.first_values = Vec::new();
            self.solver = Some(solver);
        } else if self.cursor != self.pos.len() || self.columns != self.pattern_columns {
            return Err(SparseError(format!(
                "assembly of {} entries does not match the pattern of {} (rows over other columns than the first assembly's)",
                self.cursor,
                self.pos.len()
            )));
        }
        let Some(solver) = self.solver.as_mut() else {
            return Err(SparseError("sparse solver missing".into()));
        };
        solver.values_mut().copy_from_slice(&self.values);
        if lambda != 0.0 {
            solver.damp_diagonal(lambda, 1e-3);
        }
        dx.copy_from_slice(&self.rhs);
        solver.solve(dx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_small_spd_system_twice() {
        // A = [[4, 1, 0], [1, 3, 1], [0, 1, 2]], upper entries with a duplicate split and
        // one entry given as (col, row).
        let pattern = [(0, 0), (1, 0), (1, 1), (1, 2), (2, 2), (1, 1)];
        let mut solver = SpdSolver::new(3, &pattern).unwrap();
        for scale in [1.0, 2.0] {
            let values = [4.0 * scale, scale, 2.0 * scale, scale, 2.0 * scale, scale];
            solver.set_values(&values);
            let mut x = [1.0, 2.0, 3.0];
            assert!(solver.solve(&mut x).unwrap());
            let a = [[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]];
            for (i, row) in a.iter().enumerate() {
                let ax: f64 = row.iter().zip(&x).map(|(a, x)| a * x * scale).sum();
                assert!((ax - [1.0, 2.0, 3.0][i]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn indefinite_matrix_is_reported() {
        let mut solver = SpdSolver::new(2, &[(0, 0), (0, 1), (1, 1)]).unwrap();
        solver.set_values(&[1.0, 2.0, 1.0]);
        let mut x = [1.0, 1.0];
        assert!(!solver.solve(&mut x).unwrap());
        assert!(SpdSolver::new(2, &[(0, 2)]).is_err());
    }

    #[test]
    fn an_assembly_over_other_columns_is_refused() {
        // the same number of entries, the rows' columns swapped: the first pattern's
        // positions would put each product in the other's place
        let mut ne = NormalEquations::new(2);
        let mut dx = [0.0; 2];
        for (k, cols) in [[0, 1], [0, 1], [1, 0]].iter().enumerate() {
            ne.reset(0.0);
            ne.row(&[cols[0]], &[1.0], 1.0, 1.0);
            ne.row(&[cols[1]], &[2.0], 1.0, 1.0);
            let solved = ne.solve(&mut dx);
            if k < 2 {
                assert!(solved.unwrap(), "assembly {k}");
            } else {
                let e = solved.unwrap_err().0;
                assert!(e.contains("does not match the pattern"), "{e}");
            }
        }
    }

    #[test]
    fn normal_equations_solve_a_small_least_squares_problem_twice() {
        // residuals x0 - 1, x1 - 2, x0 + x1 - 4 (weights 1): the normal equations give
        // x = (4/3, 7/3); the second assembly reuses the pattern
        let mut ne = NormalEquations::new(2);
        for _ in 0..2 {
            ne.reset(0.0);
            let x = [0.0, 0.0];
            ne.row(&[0], &[1.0], x[0] - 1.0, 1.0);
            ne.row(&[1], &[1.0], x[1] - 2.0, 1.0);
            ne.row(&[0, 1], &[1.0, 1.0], x[0] + x[1] - 4.0, 1.0);
            let mut dx = [0.0; 2];
            assert!(ne.solve(&mut dx).unwrap());
            assert!((dx[0] - 4.0 / 3.0).abs() < 1e-12 && (dx[1] - 7.0 / 3.0).abs() < 1e-12);
            assert!((ne.energy - 21.0).abs() < 1e-12);
            // damped: (diag(2, 2) * 2 + 0.002 + [[0, 1], [1, 0]]) dx = (5, 6)
            assert!(ne.solve_damped(1.0, &mut dx).unwrap());
            let d = 4.002;
            let det = d * d - 1.0;
            let (x0, x1) = ((5.0 * d - 6.0) / det, (6.0 * d - 5.0) / det);
            assert!((dx[0] - x0).abs() < 1e-12 && (dx[1] - x1).abs() < 1e-12);
        }
    }
}
