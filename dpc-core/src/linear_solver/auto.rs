//! faer LU chosen at run time from the DAE's declared pattern: sparse or dense.

use super::{FactorError, FaerDenseLu, FaerSparseLu, LinearSolver};
use crate::sink::MatrixSink;
use crate::ImplicitDae;

/// Density (non-zeros over `n^2`) below which [`FaerLu::for_dae`] picks the sparse LU.
pub const SPARSE_DENSITY: f64 = 0.1;
/// Dimension below which [`FaerLu::for_dae`] always picks the dense LU.
pub const SPARSE_MIN_DIMENSION: usize = 32;

/// faer LU for models whose size is known only at run time: [`FaerSparseLu`] when the DAE
/// declares a pattern that is sparse enough, [`FaerDenseLu`] otherwise.
///
/// It is its own [`MatrixSink`]: entries go to whichever storage the chosen back end uses.
#[derive(Debug)]
pub enum FaerLu {
    /// Dense partial-pivoting LU.
    Dense(FaerDenseLu),
    /// Sparse LU on the declared pattern.
    Sparse(Box<FaerSparseLu>),
}

impl FaerLu {
    /// Sparse LU when `dae.iteration_pattern()` is given, the dimension is at least
    /// [`SPARSE_MIN_DIMENSION`] and the density is below [`SPARSE_DENSITY`]; dense otherwise
    /// (also when faer's symbolic analysis rejects the pattern).
    pub fn for_dae<D: ImplicitDae + ?Sized>(dae: &D) -> Self {
        let n = dae.dimension();
        if n >= SPARSE_MIN_DIMENSION {
            if let Some(p) = dae.iteration_pattern() {
                if (p.len() as f64) < SPARSE_DENSITY * (n * n) as f64 {
                    if let Ok(s) = FaerSparseLu::new(n, &p) {
                        return Self::Sparse(Box::new(s));
                    }
                }
            }
        }
        Self::Dense(FaerDenseLu::new(n))
    }

    /// Whether the sparse LU was chosen.
    pub fn is_sparse(&self) -> bool {
        matches!(self, Self::Sparse(_))
    }
}

impl MatrixSink for FaerLu {
    fn rows(&self) -> usize {
        self.dimension()
    }
    fn cols(&self) -> usize {
        self.dimension()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        match self {
            Self::Dense(d) => d.matrix_mut().set(row, col, value),
            Self::Sparse(s) => s.matrix_mut().set(row, col, value),
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        match self {
            Self::Dense(d) => d.matrix_mut().add(row, col, value),
            Self::Sparse(s) => s.matrix_mut().add(row, col, value),
        }
    }
    fn fill_zero(&mut self) {
        match self {
            Self::Dense(d) => d.matrix_mut().fill_zero(),
            Self::Sparse(s) => s.matrix_mut().fill_zero(),
        }
    }
}

impl LinearSolver for FaerLu {
    type Matrix = Self;

    fn dimension(&self) -> usize {
        match self {
            Self::Dense(d) => d.dimension(),
            Self::Sparse(s) => s.dimension(),
        }
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        self
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        match self {
            Self::Dense(d) => d.factor(),
            Self::Sparse(s) => s.factor(),
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        match self {
            Self::Dense(d) => d.solve_in_place(b),
            Self::Sparse(s) => s.solve_in_place(b),
        }
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        match self {
            Self::Dense(d) => d.scaled_row_norms(w, out),
            Self::Sparse(s) => s.scaled_row_norms(w, out),
        }
    }
}
