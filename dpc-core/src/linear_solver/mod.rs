//! Linear solvers for the BDF iteration matrix `G = dF/dy + (alpha/h) dF/dy'`.
//!
//! One trait, [`LinearSolver`], with implementations chosen by type (and a run-time choice
//! among the faer ones and the banded LU):
//!
//! * [`NalgebraLu`]: fixed-size `SMatrix<f64, N, N>` with a partial-pivoting LU on the stack,
//!   for models generated with compile-time dimensions. Nothing allocates after construction,
//!   so an integrator step built on it is allocation-free.
//! * [`FaerDenseLu`]: partial-pivoting LU on a heap matrix, with the factors, permutation and
//!   scratch memory allocated once at construction, so it too is allocation-free per step
//!   (`tests/bdf_alloc.rs` checks both dense back ends). Up to [`UNBLOCKED_MAX_DIMENSION`] it
//!   uses the same unblocked elimination as [`NalgebraLu`], above it faer's blocked LU.
//! * [`FaerSparseLu`]: faer's sparse LU (symbolic analysis once, from
//!   [`crate::ImplicitDae::iteration_pattern`], numeric factorisation per Jacobian update).
//!   Factorisations and solves allocate their scratch memory (faer's high-level sparse API).
//! * [`BandLu`]: partial-pivoting LU within a band of half-bandwidths `kl`, `ku` (LAPACK's
//!   `dgbtrf` storage), for discretised PDEs and chains; allocation-free per step.
//! * [`FaerLu`]: one of the faer back ends or the banded LU, chosen at run time by
//!   [`FaerLu::for_dae`] from the density and bandwidth of the DAE's declared pattern.
//!
//! The integrator writes `G` into [`LinearSolver::matrix_mut`] after zeroing it, calls
//! [`LinearSolver::factor`], then solves as often as Newton needs with
//! [`LinearSolver::solve_in_place`].

mod auto;
pub(crate) mod band;
mod faer_dense;
pub(crate) mod faer_sparse;
mod nalgebra_lu;
mod unblocked;

pub use auto::{FaerLu, BAND_MAX_FILL, SPARSE_DENSITY, SPARSE_MIN_DIMENSION};
pub use band::{half_bandwidths, BandLu, BandMatrix};
pub use faer_dense::FaerDenseLu;
pub use faer_sparse::{FaerSparseLu, PatternMatrix};
pub use nalgebra_lu::NalgebraLu;
pub use unblocked::UNBLOCKED_MAX_DIMENSION;

use crate::sink::MatrixSink;

/// Why a factorisation failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FactorError {
    /// The matrix is (numerically or structurally) singular.
    ///
    /// `column` is the unknown whose pivot vanished, `row` an equation whose row of the matrix
    /// is entirely zero, when such a row exists (the usual cause: an equation that does not
    /// depend on any unknown at this `alpha/h`).
    #[error(
        "singular matrix ({}; {})",
        column.map_or("pivot not identified".to_string(), |c| format!("zero pivot in column {c}")),
        row.map_or("no zero row".to_string(), |r| format!("row {r} is zero"))
    )]
    Singular {
        /// Column (unknown) index whose pivot vanished, when known.
        column: Option<usize>,
        /// Row (equation) index that is entirely zero, when there is one.
        row: Option<usize>,
    },
    /// An entry of the matrix is NaN or infinite (the model's matrix at this point cannot be
    /// factorised; no pivot is to blame). The first such entry found.
    #[error("entry ({row}, {col}) is not finite")]
    NonFinite {
        /// Row (equation) of the entry.
        row: usize,
        /// Column (unknown) of the entry.
        col: usize,
    },
    /// The model wrote an entry outside the sparsity pattern it declared.
    #[error("entry ({row}, {col}) lies outside the declared sparsity pattern")]
    OutsidePattern {
        /// Row of the offending entry.
        row: usize,
        /// Column of the offending entry.
        col: usize,
    },
}

/// A linear solver for a square system whose matrix is written through a [`MatrixSink`].
pub trait LinearSolver {
    /// The storage the iteration matrix is written into.
    type Matrix: MatrixSink;

    /// Size `n` of the `n x n` system.
    fn dimension(&self) -> usize;

    /// The matrix storage, to be zeroed and filled before [`factor`](Self::factor). Every
    /// implementation keeps its factors apart from this storage, so its contents survive a
    /// factorisation: a caller whose model writes every structural entry on each call can zero
    /// it once (the controller does).
    fn matrix_mut(&mut self) -> &mut Self::Matrix;

    /// Factorise the matrix currently held in [`matrix_mut`](Self::matrix_mut).
    ///
    /// # Errors
    /// [`FactorError`] when the matrix is singular or was written outside its pattern.
    fn factor(&mut self) -> Result<(), FactorError>;

    /// Overwrite `b` (length [`dimension`](Self::dimension)) with the solution of `A x = b`
    /// for the last successfully factorised `A`.
    fn solve_in_place(&mut self, b: &mut [f64]);

    /// Row scales `out_i = max_j |A_ij| / w_j` of the matrix last written, for weights `w`
    /// (the change of equation `i` caused by moving one unknown by one unit `1/w_j`).
    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]);

    /// The half-bandwidths `(kl, ku)` the solver's matrix is confined to, when it is banded
    /// ([`BandLu`]): an integrator with a second system of the same structure (Radau's complex
    /// one) can then factorise that one in a band too. The default says not banded.
    fn band(&self) -> Option<(usize, usize)> {
        None
    }

    /// The fixed sparsity pattern of the solver's matrix in compressed-column form, when it
    /// has one ([`FaerSparseLu`]): `(col_ptr, row_idx)`, the rows of column `j` (ascending,
    /// without repeats) being `row_idx[col_ptr[j]..col_ptr[j + 1]]`. An integrator with a
    /// second system of the same structure (Radau's complex one) can then store and
    /// factorise that one in the pattern too. The default says not sparse.
    fn pattern(&self) -> Option<(&[usize], &[usize])> {
        None
    }
}

/// A mutable borrow of a solver is a solver, so one solver can serve several integrators in
/// turn (as in [`crate::bdf::FixedBdf::with_consistent_start`]).
impl<L: LinearSolver + ?Sized> LinearSolver for &mut L {
    type Matrix = L::Matrix;
    fn dimension(&self) -> usize {
        (**self).dimension()
    }
    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        (**self).matrix_mut()
    }
    fn factor(&mut self) -> Result<(), FactorError> {
        (**self).factor()
    }
    fn solve_in_place(&mut self, b: &mut [f64]) {
        (**self).solve_in_place(b);
    }
    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        (**self).scaled_row_norms(w, out);
    }
    fn band(&self) -> Option<(usize, usize)> {
        (**self).band()
    }
    fn pattern(&self) -> Option<(&[usize], &[usize])> {
        (**self).pattern()
    }
}

/// First row of a dense column-major accessor that is entirely zero, if any.
pub(crate) fn zero_row(n: usize, get: impl Fn(usize, usize) -> f64) -> Option<usize> {
    (0..n).find(|&i| (0..n).all(|j| get(i, j) == 0.0))
}
