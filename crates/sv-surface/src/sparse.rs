//! Sparse symmetric positive definite solves with a fixed sparsity pattern: the
//! symbolic Cholesky factorisation is computed once and reused for every numeric
//! factorisation (Gauss-Newton iterations keep the pattern of `J^T J`).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::SurfaceError;

/// A symmetric matrix pattern given as a list of upper-triangle entries `(row, col)`,
/// `row <= col`, duplicates allowed (they are summed). Values are supplied in the same
/// order on every call to [`SpdSolver::solve`].
pub(crate) struct SpdSolver {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    cholesky: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
}

impl SpdSolver {
    /// Analyse the pattern (`entries` upper-triangle positions, with duplicates).
    pub(crate) fn new(n: usize, entries: &[(usize, usize)]) -> Result<Self, SurfaceError> {
        let pairs: Vec<Pair<usize, usize>> = entries
            .iter()
            .map(|&(r, c)| Pair::new(r.min(c), r.max(c)))
            .collect();
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs)
            .map_err(|e| SurfaceError::Internal(format!("sparse pattern: {e:?}")))?;
        let cholesky = factorize_symbolic_cholesky(
            symbolic.as_ref(),
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
        Ok(Self {
            n,
            symbolic,
            argsort,
            cholesky,
            l_values,
            buffer,
        })
    }

    /// Factorise the matrix with `values` (same order as the pattern entries) and solve
    /// `A x = rhs` in place. Returns false when the matrix is not positive definite.
    pub(crate) fn solve(&mut self, values: &[f64], rhs: &mut [f64]) -> Result<bool, SurfaceError> {
        debug_assert_eq!(rhs.len(), self.n);
        let matrix = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, values)
            .map_err(|e| SurfaceError::Internal(format!("sparse values: {e:?}")))?;
        let llt = match self.cholesky.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            matrix.as_ref(),
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
        // A = [[4, 1, 0], [1, 3, 1], [0, 1, 2]], upper entries with a duplicate split.
        let pattern = [(0, 0), (0, 1), (1, 1), (1, 2), (2, 2), (1, 1)];
        let mut solver = SpdSolver::new(3, &pattern).unwrap();
        for scale in [1.0, 2.0] {
            let values = [4.0 * scale, scale, 2.0 * scale, scale, 2.0 * scale, scale];
            let mut x = [1.0, 2.0, 3.0];
            assert!(solver.solve(&values, &mut x).unwrap());
            let a = [[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]];
            for (i, row) in a.iter().enumerate() {
                let ax: f64 = row.iter().zip(&x).map(|(a, x)| a * x * scale).sum();
                assert!((ax - [1.0, 2.0, 3.0][i]).abs() < 1e-12);
            }
        }
    }
}
