//! Dense LU with partial pivoting (faer), workspace allocated once.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Mat, MatMut, Par};

use super::unblocked::{self, Breakdown, UNBLOCKED_MAX_DIMENSION};
use super::{zero_row, FactorError, LinearSolver};

/// Dense `n x n` LU with partial pivoting on a faer [`Mat`], for models whose size is known
/// only at run time.
///
/// Up to [`UNBLOCKED_MAX_DIMENSION`] the factors are computed by the unblocked elimination
/// shared with [`super::NalgebraLu`] in a contiguous copy of the matrix (faster than a
/// blocked LU at these sizes); above it by faer's blocked LU. The matrix, its factors, the
/// row permutation and faer's scratch memory are allocated in [`FaerDenseLu::new`];
/// factorisations and solves reuse them.
pub struct FaerDenseLu {
    matrix: Mat<f64>,
    factors: Factors,
    factored: bool,
}

/// The factors of the last factorisation and their work memory.
enum Factors {
    /// `n <= UNBLOCKED_MAX_DIMENSION`: column-major factors and LAPACK-style interchanges.
    Unblocked { lu: Vec<f64>, pivots: Vec<usize> },
    /// Larger: faer's blocked LU.
    Blocked {
        lu: Mat<f64>,
        perm: Vec<usize>,
        perm_inv: Vec<usize>,
        mem: MemBuffer,
    },
}

impl FaerDenseLu {
    /// A solver for `n x n` systems.
    pub fn new(n: usize) -> Self {
        let factors = if n <= UNBLOCKED_MAX_DIMENSION {
            Factors::Unblocked {
                lu: vec![0.0; n * n],
                pivots: vec![0; n],
            }
        } else {
            let par = Par::Seq;
            let req = factor::lu_in_place_scratch::<usize, f64>(n, n, par, Default::default())
                .or(solve::solve_in_place_scratch::<usize, f64>(n, 1, par));
            Factors::Blocked {
                lu: Mat::zeros(n, n),
                perm: vec![0; n],
                perm_inv: vec![0; n],
                mem: MemBuffer::new(req),
            }
        };
        Self {
            matrix: Mat::zeros(n, n),
            factors,
            factored: false,
        }
    }

    /// The typed error for a vanished pivot in `column`.
    fn singular(&self, column: usize) -> FactorError {
        let m = &self.matrix;
        FactorError::Singular {
            column: Some(column),
            row: zero_row(m.nrows(), |i, j| m[(i, j)]),
        }
    }
}

impl LinearSolver for FaerDenseLu {
    type Matrix = Mat<f64>;

    fn dimension(&self) -> usize {
        self.matrix.nrows()
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        &mut self.matrix
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        let n = self.matrix.nrows();
        self.factored = false;
        let vanished = match &mut self.factors {
            Factors::Unblocked { lu, pivots } => {
                for (j, col) in lu.chunks_exact_mut(n.max(1)).enumerate() {
                    col.copy_from_slice(self.matrix.col_as_slice(j));
                }
                if let Err(e) = unblocked::factor_dispatched(lu, n, pivots) {
                    let m = &self.matrix;
                    return Err(e.into_factor_error(n, |i, j| m[(i, j)]));
                }
                None
            }
            Factors::Blocked {
                lu,
                perm,
                perm_inv,
                mem,
            } => {
                let columns = (0..n).flat_map(|j| self.matrix.col_as_slice(j));
                if let Some(e) = Breakdown::non_finite(columns, n) {
                    return Err(e.into_factor_error(n, |_, _| 0.0));
                }
                lu.copy_from(&self.matrix);
                factor::lu_in_place(
                    lu.as_mut(),
                    perm,
                    perm_inv,
                    Par::Seq,
                    MemStack::new(mem),
                    Default::default(),
                );
                (0..n).find(|&k| lu[(k, k)] == 0.0 || !lu[(k, k)].is_finite())
            }
        };
        if let Some(column) = vanished {
            return Err(self.singular(column));
        }
        self.factored = true;
        Ok(())
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (j, wj) in w.iter().enumerate() {
            for (i, o) in out.iter_mut().enumerate() {
                *o = o.max(self.matrix[(i, j)].abs() / wj);
            }
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        if !self.factored {
            return;
        }
        let n = self.matrix.nrows();
        match &mut self.factors {
            Factors::Unblocked { lu, pivots } => unblocked::solve_dispatched(lu, n, pivots, b),
            Factors::Blocked {
                lu,
                perm,
                perm_inv,
                mem,
            } => {
                let perm = PermRef::new_checked(perm, perm_inv, n);
                let rhs = MatMut::from_column_major_slice_mut(&mut b[..n], n, 1);
                solve::solve_in_place(
                    lu.as_ref(),
                    lu.as_ref(),
                    perm,
                    rhs,
                    Par::Seq,
                    MemStack::new(mem),
                );
            }
        }
    }
}

impl core::fmt::Debug for FaerDenseLu {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FaerDenseLu")
            .field("n", &self.matrix.nrows())
            .field(
                "unblocked",
                &matches!(self.factors, Factors::Unblocked { .. }),
            )
            .field("factored", &self.factored)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MatrixSink;

    /// The same system through the unblocked path (n <= the limit) and faer's blocked one.
    #[test]
    fn both_paths_solve_a_diagonally_dominant_system() {
        for n in [3, UNBLOCKED_MAX_DIMENSION, UNBLOCKED_MAX_DIMENSION + 1, 40] {
            let mut ls = FaerDenseLu::new(n);
            let entry = |i: usize, j: usize| {
                if i == j {
                    4.0 + i as f64
                } else {
                    1.0 / (1.0 + (i + 2 * j) as f64)
                }
            };
            let m = ls.matrix_mut();
            m.fill_zero();
            for i in 0..n {
                for j in 0..n {
                    m.set(i, j, entry(i, j));
                }
            }
            ls.factor().expect("regular");
            let x: Vec<f64> = (0..n).map(|i| 1.0 - 0.1 * i as f64).collect();
            let mut b: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|j| entry(i, j) * x[j]).sum())
                .collect();
            ls.solve_in_place(&mut b);
            for (got, want) in b.iter().zip(&x) {
                assert!((got - want).abs() <= 1e-13, "n = {n}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn a_zero_row_is_named_on_both_paths() {
        for n in [4, UNBLOCKED_MAX_DIMENSION + 2] {
            let mut ls = FaerDenseLu::new(n);
            let m = ls.matrix_mut();
            m.fill_zero();
            for i in 0..n {
                if i != 2 {
                    m.set(i, i, 1.0);
                }
            }
            match ls.factor() {
                Err(FactorError::Singular { row, .. }) => assert_eq!(row, Some(2), "n = {n}"),
                other => panic!("n = {n}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_non_finite_entry_is_named_on_both_paths() {
        for n in [4, 9, UNBLOCKED_MAX_DIMENSION + 2] {
            for bad in [f64::NAN, f64::INFINITY] {
                let mut ls = FaerDenseLu::new(n);
                let m = ls.matrix_mut();
                m.fill_zero();
                for i in 0..n {
                    m.set(i, i, 1.0);
                }
                m.set(3, 2, bad);
                match ls.factor() {
                    Err(FactorError::NonFinite { row, col }) => {
                        assert_eq!((row, col), (3, 2), "n = {n}")
                    }
                    other => panic!("n = {n}: {other:?}"),
                }
            }
        }
    }
}
