//! faer LU chosen at run time from the DAE's declared pattern: banded, sparse or dense.

use super::band::half_bandwidths;
use super::{BandLu, FactorError, FaerDenseLu, FaerSparseLu, LinearSolver};
use crate::sink::MatrixSink;
use crate::ImplicitDae;

/// Density (non-zeros over `n^2`) below which [`FaerLu::for_dae`] picks a sparse or banded LU.
pub const SPARSE_DENSITY: f64 = 0.1;
/// Dimension below which [`FaerLu::for_dae`] always picks the dense LU.
pub const SPARSE_MIN_DIMENSION: usize = 32;
/// [`FaerLu::for_dae`] picks the banded LU over the sparse one when the band's storage with
/// the interchanges' fill-in, `n (2 kl + ku + 1)` entries, is at most this many times the
/// declared pattern's entries: the band then holds few zeros beyond what a sparse LU fills in
/// anyway, and its elimination runs over contiguous columns without index lists. On the heat
/// equation on an `m x m` grid the band took 0.43-0.66 of the sparse LU's time up to a ratio
/// of 47 and more than twice it from 50 (docs/integrators.md); 32 keeps a margin below.
pub const BAND_MAX_FILL: usize = 32;

/// LU for models whose size is known only at run time: [`BandLu`] when the DAE declares a
/// pattern that lies in a narrow band, faer's [`FaerSparseLu`] when it is sparse otherwise,
/// [`FaerDenseLu`] when it is neither.
///
/// It is its own [`MatrixSink`]: entries go to whichever storage the chosen back end uses.
#[derive(Debug)]
pub enum FaerLu {
    /// Dense partial-pivoting LU.
    Dense(FaerDenseLu),
    /// Sparse LU on the declared pattern.
    Sparse(Box<FaerSparseLu>),
    /// Banded partial-pivoting LU on the declared pattern's band.
    Band(BandLu),
}

impl FaerLu {
    /// For a DAE that declares `dae.iteration_pattern()`, of dimension at least
    /// [`SPARSE_MIN_DIMENSION`] and density below [`SPARSE_DENSITY`]: the banded LU when the
    /// band costs at most [`BAND_MAX_FILL`] times the pattern's entries in storage, else the
    /// sparse LU (the dense one when faer's symbolic analysis rejects the pattern). Dense
    /// otherwise.
    pub fn for_dae<D: ImplicitDae + ?Sized>(dae: &D) -> Self {
        let n = dae.dimension();
        if n >= SPARSE_MIN_DIMENSION {
            if let Some(p) = dae.iteration_pattern() {
                if (p.len() as f64) < SPARSE_DENSITY * (n * n) as f64 {
                    if let Ok((kl, ku)) = half_bandwidths(n, &p) {
                        if n * (2 * kl + ku + 1) <= BAND_MAX_FILL * p.len() {
                            return Self::Band(BandLu::new(n, kl, ku));
                        }
                    }
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

    /// Whether the banded LU was chosen.
    pub fn is_band(&self) -> bool {
        matches!(self, Self::Band(_))
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
            Self::Band(b) => b.matrix_mut().set(row, col, value),
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        match self {
            Self::Dense(d) => d.matrix_mut().add(row, col, value),
            Self::Sparse(s) => s.matrix_mut().add(row, col, value),
            Self::Band(b) => b.matrix_mut().add(row, col, value),
        }
    }
    fn fill_zero(&mut self) {
        match self {
            Self::Dense(d) => d.matrix_mut().fill_zero(),
            Self::Sparse(s) => s.matrix_mut().fill_zero(),
            Self::Band(b) => b.matrix_mut().fill_zero(),
        }
    }
}

impl LinearSolver for FaerLu {
    type Matrix = Self;

    fn dimension(&self) -> usize {
        match self {
            Self::Dense(d) => d.dimension(),
            Self::Sparse(s) => s.dimension(),
            Self::Band(b) => b.dimension(),
        }
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        self
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        match self {
            Self::Dense(d) => d.factor(),
            Self::Sparse(s) => s.factor(),
            Self::Band(b) => b.factor(),
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        match self {
            Self::Dense(d) => d.solve_in_place(b),
            Self::Sparse(s) => s.solve_in_place(b),
            Self::Band(l) => l.solve_in_place(b),
        }
    }

    fn band(&self) -> Option<(usize, usize)> {
        match self {
            Self::Band(b) => b.band(),
            _ => None,
        }
    }

    fn pattern(&self) -> Option<(&[usize], &[usize])> {
        match self {
            Self::Sparse(s) => s.pattern(),
            _ => None,
        }
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        match self {
            Self::Dense(d) => d.scaled_row_norms(w, out),
            Self::Sparse(s) => s.scaled_row_norms(w, out),
            Self::Band(b) => b.scaled_row_norms(w, out),
        }
    }
}
