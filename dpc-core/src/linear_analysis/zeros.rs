//! Transmission zeros of a square invertible system.
//!
//! They are the finite eigenvalues of the Rosenbrock pencil `[-sI + A, B; C, D]`, which after
//! the row compression are those of `-Es + F`, i.e. the eigenvalues of `A_1` (Theorem 3.1 b).
//! [`rosenbrock_sigma_min`] gives an independent check: the Rosenbrock matrix loses rank at a
//! zero.

use nalgebra::DMatrix;
use num_complex::Complex;

use super::{LinearError, LinearSystem};

/// Transmission zeros as the eigenvalues of `A_1`, sorted.
pub fn transmission_zeros(a1: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, LinearError> {
    super::subspace::eigenvalues(a1)
}

/// Smallest singular value of the Rosenbrock matrix at `s`, relative to its largest one.
pub fn rosenbrock_sigma_min(sys: &LinearSystem, s: Complex<f64>) -> f64 {
    let (n, m) = (sys.n(), sys.m());
    let mut r = DMatrix::<Complex<f64>>::zeros(n + m, n + m);
    for i in 0..n {
        for j in 0..n {
            r[(i, j)] = Complex::from(sys.a[(i, j)]) - if i == j { s } else { Complex::from(0.0) };
        }
        for j in 0..m {
            r[(i, n + j)] = sys.b[(i, j)].into();
        }
    }
    for i in 0..m {
        for j in 0..n {
            r[(n + i, j)] = sys.c[(i, j)].into();
        }
        for j in 0..m {
            r[(n + i, n + j)] = sys.d[(i, j)].into();
        }
    }
    let sv = r.svd(false, false).singular_values;
    let smax = sv.iter().copied().fold(0.0, f64::max);
    let smin = sv.iter().copied().fold(f64::INFINITY, f64::min);
    smin / smax.max(f64::MIN_POSITIVE)
}
