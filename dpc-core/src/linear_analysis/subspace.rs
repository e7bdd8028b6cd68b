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

/// `(U, singular values, V)`.
type FullSvd = (DMatrix<f64>, Vec<f64>, DMatrix<f64>);

/// Full SVD by faer: `U` (`rows x rows`), singular values (descending), `V` (`cols x cols`).
///
/// nalgebra 0.35's SVD returns inaccurate left singular vectors for some rank-deficient
/// matrices (seen on a 3x2 rank-one product in the property tests), and rank decisions are
/// only as good as those vectors; faer's SVD is used instead.
fn faer_svd(g: &DMatrix<f64>) -> Result<FullSvd, LinearError> {
    let (r, c) = g.shape();
    let fm = faer::Mat::<f64>::from_fn(r, c, |i, j| g[(i, j)]);
    let svd = fm
        .svd()
        .map_err(|_| LinearError::NoConvergence { what: "SVD" })?;
    let u = svd.U();
    let v = svd.V();
    let s = svd.S().column_vector();
    let sv: Vec<f64> = (0..r.min(c)).map(|i| s[i]).collect();
    let u = DMatrix::from_fn(r, r, |i, j| u[(i, j)]);
    let v = DMatrix::from_fn(c, c, |i, j| v[(i, j)]);
    Ok((u, sv, v))
}

/// Left singular vectors (full, `rows x rows`) and singular values (descending).
pub(crate) fn svd_left(g: &DMatrix<f64>) -> Result<(DMatrix<f64>, Vec<f64>), LinearError> {
    if g.is_empty() {
        return Ok((DMatrix::identity(g.nrows(), g.nrows()), Vec::new()));
    }
    let (u, sv, _) = faer_svd(g)?;
    Ok((u, sv))
}

/// Right singular vectors (full, `cols x cols`) and singular values (descending).
pub(crate) fn svd_right(g: &DMatrix<f64>) -> Result<(DMatrix<f64>, Vec<f64>), LinearError> {
    if g.is_empty() {
        return Ok((DMatrix::identity(g.ncols(), g.ncols()), Vec::new()));
    }
    let (_, sv, v) = faer_svd(g)?;
    Ok((v, sv))
}

/// Singular values (descending) of any matrix.
pub(crate) fn singular_values(g: &DMatrix<f64>) -> Vec<f64> {
    if g.is_empty() {
        return Vec::new();
    }
    let (r, c) = g.shape();
    let fm = faer::Mat::<f64>::from_fn(r, c, |i, j| g[(i, j)]);
    match fm.singular_values() {
        Ok(sv) => sv,
        Err(_) => vec![f64::NAN],
    }
}

/// Singular values below `GAP_ZONE * scale` count as zero when the gap above them is at
/// least `MIN_GAP`, even if they exceed the `factor * max(rows, cols) * eps` tolerance: errors
/// accumulate over the Wong and `V*` recursions (about `||A||^k eps` after `k` steps), and a
/// clear gap is the better witness of a structural zero than a fixed multiple of `eps`.
pub const GAP_ZONE: f64 = 1.5e-8;
/// See [`GAP_ZONE`].
pub const MIN_GAP: f64 = 1e4;

/// Decide the numerical rank of descending singular values.
pub(crate) fn decide(sv: &[f64], shape: (usize, usize), factor: f64) -> RankDecision {
    let smax = sv.first().copied().unwrap_or(0.0);
    decide_scaled(sv, shape, factor, smax)
}

/// Decide the rank relative to a reference norm `scale`.
pub(crate) fn decide_scaled(
    sv: &[f64],
    shape: (usize, usize),
    factor: f64,
    scale: f64,
) -> RankDecision {
    let mut tol = factor * (shape.0.max(shape.1) as f64) * f64::EPSILON * scale;
    let mut rank = sv.iter().filter(|&&s| s > tol).count();
    // Gap rule: the first singular value inside the zone, if far below its predecessor.
    if let Some(k) = (0..rank).find(|&k| sv[k] <= GAP_ZONE * scale) {
        if k == 0 || sv[k - 1] >= MIN_GAP * sv[k] {
            rank = k;
            tol = tol.max(sv[k]);
        }
    }
    RankDecision {
        rank,
        tol,
        smallest_kept: if rank > 0 { Some(sv[rank - 1]) } else { None },
        largest_dropped: sv.get(rank).copied(),
    }
}

/// Orthonormal basis of the null space of `g` (columns), with the decision.
///
/// Computed as the orthogonal complement of the row space: only singular vectors of nonzero
/// singular values are used, since those belonging to (near) zero singular values are not
/// reliably orthogonal in nalgebra's SVD of rank-deficient matrices.
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
    let (rows, dec) = range(&g.transpose(), factor, reference_norm)?;
    Ok((complement(&rows)?, dec))
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
        Some(nrm) => decide_scaled(&sv, (r, c), factor, nrm),
        None => decide(&sv, (r, c), factor),
    };
    Ok((u.columns(0, dec.rank).into_owned(), dec))
}

/// Orthonormal basis of the orthogonal complement of the span of the orthonormal columns `s`.
///
/// Eigenvectors of the projector `I - s s^T` for the eigenvalue 1: the symmetric eigensolver
/// returns an orthogonal eigenvector matrix even for the multiple eigenvalues 0 and 1.
pub(crate) fn complement(s: &DMatrix<f64>) -> Result<DMatrix<f64>, LinearError> {
    let (n, k) = s.shape();
    if k == 0 {
        return Ok(DMatrix::identity(n, n));
    }
    if k >= n {
        return Ok(DMatrix::zeros(n, 0));
    }
    let p = DMatrix::identity(n, n) - s * s.transpose();
    let eig = nalgebra::SymmetricEigen::try_new(p, f64::EPSILON, 200 * n.max(10)).ok_or(
        LinearError::NoConvergence {
            what: "symmetric eigen",
        },
    )?;
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let cols: Vec<_> = idx[..n - k]
        .iter()
        .map(|&i| eig.eigenvectors.column(i).into_owned())
        .collect();
    Ok(DMatrix::from_columns(&cols))
}

/// Spectral norm.
pub(crate) fn norm2(g: &DMatrix<f64>) -> f64 {
    singular_values(g).first().copied().unwrap_or(0.0)
}

/// 2-norm condition number of a square matrix (infinite if singular).
pub(crate) fn cond(g: &DMatrix<f64>) -> f64 {
    let sv = singular_values(g);
    match (sv.first(), sv.last()) {
        (Some(&smax), Some(&smin)) if smin > 0.0 => smax / smin,
        (Some(_), Some(_)) => f64::INFINITY,
        _ => 1.0,
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

/// Eigenvalues of a real square matrix (faer's real Schur based eigensolver), sorted by real
/// part then imaginary part so that reports are reproducible.
///
/// nalgebra 0.35's `complex_eigenvalues` returned NaN imaginary parts for 2x2 Schur blocks of
/// nearly repeated eigenvalues in the property tests; faer's solver is used instead.
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, LinearError> {
    let n = a.nrows();
    if n == 0 {
        return Ok(Vec::new());
    }
    let fm = faer::Mat::<f64>::from_fn(n, n, |i, j| a[(i, j)]);
    let ev = fm.eigenvalues().map_err(|_| LinearError::NoConvergence {
        what: "eigenvalues",
    })?;
    let mut ev: Vec<Complex<f64>> = ev.iter().map(|z| Complex::new(z.re, z.im)).collect();
    if ev.iter().any(|z| !z.re.is_finite() || !z.im.is_finite()) {
        return Err(LinearError::NoConvergence {
            what: "eigenvalues",
        });
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn orthonormal(q: &DMatrix<f64>) -> bool {
        (q.transpose() * q - DMatrix::identity(q.ncols(), q.ncols())).amax() < 1e-12
    }

    #[test]
    fn null_space_and_complement_are_orthonormal_and_right() {
        let g = DMatrix::from_row_slice(2, 4, &[1.0, 2.0, 3.0, 4.0, 2.0, 4.0, 6.0, 8.0]);
        let (nb, d) = null_space(&g, 100.0, None).unwrap();
        assert_eq!(d.rank, 1);
        assert_eq!(nb.ncols(), 3);
        assert!(orthonormal(&nb));
        assert!((&g * &nb).amax() < 1e-12);
        let tall = g.transpose();
        let (nb, d) = null_space(&tall, 100.0, None).unwrap();
        assert_eq!((d.rank, nb.ncols()), (1, 1));
        assert!((&tall * &nb).amax() < 1e-12);
        let (r, _) = range(&tall, 100.0, None).unwrap();
        assert_eq!(r.ncols(), 1);
        let c = complement(&r).unwrap();
        assert_eq!(c.ncols(), 3);
        assert!(orthonormal(&c));
        assert!((r.transpose() * &c).amax() < 1e-12);
    }
}
