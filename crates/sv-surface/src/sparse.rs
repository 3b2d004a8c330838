//! Sparse symmetric positive definite solves with a fixed sparsity pattern: the
//! symbolic Cholesky factorisation is computed once and reused for every numeric
//! factorisation (Gauss-Newton iterations keep the pattern of `J^T J`). Values are
//! scattered straight into the compressed columns through a precomputed position map,
//! so an iteration costs one pass over the entries and one numeric factorisation.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::SurfaceError;

/// A symmetric matrix pattern given as a list of upper-triangle entries `(row, col)`,
/// `row <= col`, duplicates allowed (they are summed).
pub(crate) struct SpdSolver {
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
    pub(crate) fn new(n: usize, entries: &[(usize, usize)]) -> Result<Self, SurfaceError> {
        if entries.len() >= u32::MAX as usize {
            return Err(SurfaceError::Internal("sparse pattern too large".into()));
        }
        let key = |k: usize| {
            let (r, c) = entries[k];
            (r.max(c), r.min(c))
        };
        if let Some(&(r, c)) = entries.iter().find(|&&(r, c)| r.max(c) >= n) {
            return Err(SurfaceError::Internal(format!(
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
        .map_err(|e| SurfaceError::Internal(format!("symbolic cholesky: {e:?}")))?;
        let l_values = vec![0.0; cholesky.len_val()];
        let req = cholesky
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(cholesky.solve_in_place_scratch::<f64>(1, Par::Seq));
        let buffer = MemBuffer::try_new(req)
            .map_err(|_| SurfaceError::Internal("out of memory for cholesky".into()))?;
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
    pub(crate) fn positions(&self) -> &[u32] {
        &self.pos
    }

    /// The compressed values, to be filled through [`SpdSolver::positions`].
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Set the values from a list in pattern order (duplicates summed).
    pub(crate) fn set_values(&mut self, entries: &[f64]) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for (k, &v) in entries.iter().enumerate() {
            self.values[self.pos[k] as usize] += v;
        }
    }

    /// Factorise the current values and solve `A x = rhs` in place. Returns false when
    /// the matrix is not positive definite.
    pub(crate) fn solve(&mut self, rhs: &mut [f64]) -> Result<bool, SurfaceError> {
        if rhs.len() != self.n {
            return Err(SurfaceError::Internal(format!(
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
}
