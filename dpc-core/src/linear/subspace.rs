//! Orthonormal bases of ranges, null spaces and complements by the SVD, with rank decisions
//! relative to the largest singular value: `tol = factor * max(rows, cols) * eps * sigma_max`.
//!
//! Every decision is recorded in a [`RankDecision`] so that the analysis can report how
//! clear-cut it was (the gap between the smallest kept and the largest dropped singular value).

use nalgebra::DMatrix;
use num_complex::Complex;

use super::LinearError;

/// One numerical rank decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RankDecision {
    /// The rank chosen.
    pub rank: usize,
    /// Absolute tolerance: singular values `<= tol` count as zero.
    pub tol: f64,
    /// Smallest singular value kept, if any.
    pub smallest_kept: Option<f64>,
    /// Largest singular value dropped, if any.
    pub largest_dropped: Option<f64>,
}

impl RankDecision {
    /// `smallest_kept / largest_dropped` where both exist.
    pub fn gap(&self) -> Option<f64> {
        match (self.smallest_kept, self.largest_dropped) {
            (Some(k), Some(d)) => Some(k / d.max(f64::MIN_POSITIVE)),
            _ => None,
        }
    }
}

/// Left singular vectors (full, `rows x rows`) and singular values (descending) of any matrix.
///
/// nalgebra returns thin factors; padding a tall matrix with zero columns to a square one
/// yields a full orthogonal `U` without changing the singular values or left vectors.
pub(crate) fn svd_left(g: &DMatrix<f64>) -> Result<(DMatrix<f64>, Vec<f64>), LinearError> {
    let (r, c) = g.shape();
    let padded;
    let m = if r > c {
        let mut sq = DMatrix::zeros(r, r);
        sq.view_mut((0, 0), (r, c)).copy_from(g);
        padded = sq;
        &padded
    } else {
        g
    };
    let svd = nalgebra::SVD::try_new(m.clone(), true, false, f64::EPSILON, 200 * r.max(c).max(10))
        .ok_or(LinearError::NoConvergence { what: "SVD" })?;
    let sv = svd.singular_values.iter().take(r.min(c)).copied().collect();
    Ok((svd.u.expect("requested"), sv))
}

/// Right singular vectors (full, `cols x cols`) and singular values (descending) of any matrix.
pub(crate) fn svd_right(g: &DMatrix<f64>) -> Result<(DMatrix<f64>, Vec<f64>), LinearError> {
    let (r, c) = g.shape();
    let padded;
    let m = if r < c {
        let mut sq = DMatrix::zeros(c, c);
        sq.view_mut((0, 0), (r, c)).copy_from(g);
        padded = sq;
        &padded
    } else {
        g
    };
    let svd = nalgebra::SVD::try_new(m.clone(), false, true, f64::EPSILON, 200 * r.max(c).max(10))
        .ok_or(LinearError::NoConvergence { what: "SVD" })?;
    let sv = svd.singular_values.iter().take(r.min(c)).copied().collect();
    Ok((svd.v_t.expect("requested").transpose(), sv))
}

/// Decide the numerical rank of descending singular values.
pub(crate) fn decide(sv: &[f64], shape: (usize, usize), factor: f64) -> RankDecision {
    let smax = sv.first().copied().unwrap_or(0.0);
    let tol = factor * (shape.0.max(shape.1) as f64) * f64::EPSILON * smax;
    let rank = sv.iter().filter(|&&s| s > tol).count();
    RankDecision {
        rank,
        tol,
        smallest_kept: if rank > 0 { Some(sv[rank - 1]) } else { None },
        largest_dropped: sv.get(rank).copied(),
    }
}

/// Decide the rank with an absolute tolerance (used where the scale is not the matrix itself).
pub(crate) fn decide_abs(sv: &[f64], tol: f64) -> RankDecision {
    let rank = sv.iter().filter(|&&s| s > tol).count();
    RankDecision {
        rank,
        tol,
        smallest_kept: if rank > 0 { Some(sv[rank - 1]) } else { None },
        largest_dropped: sv.get(rank).copied(),
    }
}

/// Orthonormal basis of the null space of `g` (columns), with the decision.
///
/// When a reference norm is given, the tolerance is relative to it instead of `||g||`: that
/// keeps the decision meaningful when `g` is a projection of a larger matrix.
pub(crate) fn null_space(
    g: &DMatrix<f64>,
    factor: f64,
    reference_norm: Option<f64>,
) -> Result<(DMatrix<f64>, RankDecision), LinearError> {
    let (r, c) = g.shape();
    if r == 0 || c == 0 {
        return Ok((
            DMatrix::identity(c, c),
            RankDecision {
                rank: 0,
                tol: 0.0,
                smallest_kept: None,
                largest_dropped: None,
            },
        ));
    }
    let (v, sv) = svd_right(g)?;
    let dec = match reference_norm {
        Some(nrm) => decide_abs(&sv, factor * (r.max(c) as f64) * f64::EPSILON * nrm),
        None => decide(&sv, (r, c), factor),
    };
    Ok((v.columns(dec.rank, c - dec.rank).into_owned(), dec))
}

/// Orthonormal basis of the range of `g` (columns), with the decision.
pub(crate) fn range(
    g: &DMatrix<f64>,
    factor: f64,
    reference_norm: Option<f64>,
) -> Result<(DMatrix<f64>, RankDecision), LinearError> {
    let (r, c) = g.shape();
    if r == 0 || c == 0 {
        return Ok((
            DMatrix::zeros(r, 0),
            RankDecision {
                rank: 0,
                tol: 0.0,
                smallest_kept: None,
                largest_dropped: None,
            },
        ));
    }
    let (u, sv) = svd_left(g)?;
    let dec = match reference_norm {
        Some(nrm) => decide_abs(&sv, factor * (r.max(c) as f64) * f64::EPSILON * nrm),
        None => decide(&sv, (r, c), factor),
    };
    Ok((u.columns(0, dec.rank).into_owned(), dec))
}

/// Orthonormal basis of the orthogonal complement of the span of the orthonormal columns `s`.
pub(crate) fn complement(s: &DMatrix<f64>) -> Result<DMatrix<f64>, LinearError> {
    let (n, k) = s.shape();
    if k == 0 {
        return Ok(DMatrix::identity(n, n));
    }
    let (u, _) = svd_left(s)?;
    Ok(u.columns(k, n - k).into_owned())
}

/// Spectral norm.
pub(crate) fn norm2(g: &DMatrix<f64>) -> f64 {
    if g.is_empty() {
        return 0.0;
    }
    g.clone()
        .svd(false, false)
        .singular_values
        .iter()
        .copied()
        .fold(0.0, f64::max)
}

/// 2-norm condition number of a square matrix (infinite if singular).
pub(crate) fn cond(g: &DMatrix<f64>) -> f64 {
    if g.is_empty() {
        return 1.0;
    }
    let sv = g.clone().svd(false, false).singular_values;
    let smax = sv.iter().copied().fold(0.0, f64::max);
    let smin = sv.iter().copied().fold(f64::INFINITY, f64::min);
    if smin == 0.0 {
        f64::INFINITY
    } else {
        smax / smin
    }
}

/// Sine of the largest principal angle between the spans of two orthonormal bases of equal
/// dimension: `||(I - P_a) b||_2`.
pub(crate) fn subspace_distance(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    if b.ncols() == 0 {
        return 0.0;
    }
    let proj = a * (a.transpose() * b);
    norm2(&(b - proj))
}

/// Eigenvalues of a real square matrix by the real Schur form, sorted by real part then
/// imaginary part so that reports are reproducible.
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, LinearError> {
    let n = a.nrows();
    if n == 0 {
        return Ok(Vec::new());
    }
    let schur = nalgebra::Schur::try_new(a.clone(), f64::EPSILON, 1000 * n.max(10)).ok_or(
        LinearError::NoConvergence {
            what: "real Schur form",
        },
    )?;
    let mut ev: Vec<Complex<f64>> = schur.complex_eigenvalues().iter().copied().collect();
    sort_eigenvalues(&mut ev);
    Ok(ev)
}

/// Sort by real part, then imaginary part (total order, NaN last).
pub(crate) fn sort_eigenvalues(ev: &mut [Complex<f64>]) {
    ev.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
}

/// Solve `g x = rhs` for square `g` by LU with full pivoting; `None` if numerically singular.
pub(crate) fn solve(g: &DMatrix<f64>, rhs: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if g.nrows() == 0 {
        return Some(DMatrix::zeros(0, rhs.ncols()));
    }
    g.clone().full_piv_lu().solve(rhs)
}
