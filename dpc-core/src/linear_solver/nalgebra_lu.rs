//! Fixed-size dense LU on the stack (nalgebra storage), allocation-free after construction.

use nalgebra::SMatrix;

use super::unblocked;
use super::{FactorError, LinearSolver};

/// Dense `N x N` LU with partial (row) pivoting in stack storage.
///
/// The matrix is an `SMatrix<f64, N, N>` (the sink the generated code writes into); the
/// factors overwrite a second `SMatrix` and the row interchanges are a `[usize; N]`.
/// Construction, factorisation and solves never touch the heap. The elimination is the
/// unblocked one shared with [`super::FaerDenseLu`]'s small sizes (`linear_solver/unblocked.rs`): a
/// pivot at most `N eps max |a_ij|` is reported as [`FactorError::Singular`].
#[derive(Debug, Clone)]
pub struct NalgebraLu<const N: usize> {
    matrix: SMatrix<f64, N, N>,
    /// The factors (from [`unblocked::SPLIT_FROM`] on: `L` below the diagonal, zeros on and
    /// above it).
    lu: SMatrix<f64, N, N>,
    /// From [`unblocked::SPLIT_FROM`] on: `U` above the diagonal (zeros on and below it).
    upper: SMatrix<f64, N, N>,
    /// From [`unblocked::SPLIT_FROM`] on: the diagonal of `U`.
    diag: [f64; N],
    pivots: [usize; N],
    factored: bool,
}

impl<const N: usize> NalgebraLu<N> {
    /// A solver for `N x N` systems.
    pub fn new() -> Self {
        Self {
            matrix: SMatrix::zeros(),
            lu: SMatrix::zeros(),
            upper: SMatrix::zeros(),
            diag: [0.0; N],
            pivots: [0; N],
            factored: false,
        }
    }
}

impl<const N: usize> Default for NalgebraLu<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> LinearSolver for NalgebraLu<N> {
    type Matrix = SMatrix<f64, N, N>;

    fn dimension(&self) -> usize {
        N
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        &mut self.matrix
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        self.factored = false;
        self.lu = self.matrix;
        let factored = if N >= unblocked::SPLIT_FROM {
            unblocked::factor_split_fixed::<N>(
                self.lu.as_mut_slice(),
                &mut self.pivots,
                self.upper.as_mut_slice(),
                &mut self.diag,
            )
        } else {
            unblocked::factor_columns::<N>(&mut self.lu.data.0, &mut self.pivots)
        };
        if let Err(e) = factored {
            let m = &self.matrix;
            return Err(e.into_factor_error(N, |i, j| m[(i, j)]));
        }
        self.factored = true;
        Ok(())
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = (0..N).fold(0.0, |m: f64, j| m.max(self.matrix[(i, j)].abs() / w[j]));
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        if self.factored {
            if N >= unblocked::SPLIT_FROM {
                unblocked::solve_split_fixed::<N>(
                    self.lu.as_slice(),
                    self.upper.as_slice(),
                    &self.diag,
                    &self.pivots,
                    b,
                );
            } else {
                unblocked::solve(self.lu.as_slice(), N, &self.pivots, b);
            }
        }
    }
}
