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
    if let Ok(svd) = fm.svd() {
        let (u, v) = (svd.U(), svd.V());
        let s = svd.S().column_vector();
        let sv: Vec<f64> = (0..r.min(c)).map(|i| s[i]).collect();
        let u = DMatrix::from_fn(r, r, |i, j| u[(i, j)]);
        let v = DMatrix::from_fn(c, c, |i, j| v[(i, j)]);
        return Ok((u, sv, v));
    }
    // faer 0.24's SVD reports no convergence on some ordinary matrices (a 9 x 7 one of O(1)
    // entries in the property tests, seed 2115862851735959728, and its transpose alike):
    // nalgebra's SVD then (without an iteration limit), its thin factors completed to full
    // orthonormal bases by a QR.
    let svd = nalgebra::linalg::SVD::try_new(g.clone(), true, true, f64::EPSILON, 0)
        .ok_or(LinearError::NoConvergence { what: "SVD" })?;
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(LinearError::NoConvergence { what: "SVD" });
    };
    // Descending singular values, with their vectors.
    let k = r.min(c);
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let sv: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
    let thin_u = DMatrix::from_fn(r, k, |i, j| u[(i, order[j])]);
    let thin_v = DMatrix::from_fn(c, k, |i, j| v_t[(order[j], i)]);
    Ok((complete(&thin_u), sv, complete(&thin_v)))
}

/// `q` (`n x k`, orthonormal columns) completed to an orthonormal `n x n` basis: the `Q` of a
/// QR of `[q | I]`, whose first `k` columns span `q`'s (signs fixed to `q`'s own).
fn complete(q: &DMatrix<f64>) -> DMatrix<f64> {
    let (n, k) = q.shape();
    let mut m = DMatrix::zeros(n, k + n);
    m.columns_mut(0, k).copy_from(q);
    m.columns_mut(k, n).copy_from(&DMatrix::identity(n, n));
    let full = m.qr().q();
    let mut basis = DMatrix::zeros(n, n);
    basis.columns_mut(0, k).copy_from(q);
    basis
        .columns_mut(k, n - k)
        .copy_from(&full.columns(k, n - k));
    basis
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

    #[test]
    #[allow(clippy::excessive_precision)]
    fn svd_where_faer_does_not_converge() {
        // The 9 x 7 matrix (column-major) on which faer's SVD and that of its transpose report
        // no convergence (the property tests' seed 2115862851735959728): the fallback's
        // factors are orthogonal and reproduce it, the values descending.
        let g = DMatrix::from_column_slice(
            9,
            7,
            &[
                -0.31144263749362827,
                0.04536256174748863,
                -0.739710149608096,
                0.17200287886370427,
                0.13686621322593445,
                0.12482005445253014,
                0.051836416249615984,
                0.28743241641955347,
                0.45229725999320336,
                -0.48995723396243335,
                0.3967218026160232,
                0.19623160911205323,
                0.27348998804896674,
                0.2240436894194981,
                0.2302337457295032,
                0.5259616392803225,
                -0.2822361825080828,
                -0.1724935972340077,
                -0.13442513411325863,
                -0.3630726212112869,
                0.15010551409997094,
                -0.4062466146107097,
                -0.4274585300067071,
                0.13355321237917567,
                0.5262273900705162,
                -0.07491186810036378,
                0.4236223180434602,
                0.1293873815511801,
                0.10949339660523041,
                0.2397027729538391,
                0.09969935137871591,
                -0.006733295138712658,
                -0.0979193661864336,
                0.363396635309758,
                0.8634357811473059,
                -0.12907640880654267,
                0.08427081301118287,
                -0.4798445544026767,
                -0.032137378202102905,
                0.7841518826406795,
                -0.004252870110641516,
                -0.9839794826586855,
                0.380092593255624,
                -0.2806274948092653,
                0.16300126222578326,
                -0.0855135109581455,
                0.9366199597205245,
                0.5283631046064486,
                -0.26238155628675963,
                0.007598729092089824,
                -0.34943428269547777,
                -0.37487194612907376,
                0.03434094137819743,
                0.9263456856850153,
                -0.7707781989974036,
                -0.021799607652711835,
                -0.07230345776740665,
                0.1496868851288926,
                -0.9794149663127258,
                0.11342882151025926,
                -0.43678995750726746,
                0.23015680640760544,
                -0.5348623180646593,
            ],
        );
        let fm = faer::Mat::<f64>::from_fn(9, 7, |i, j| g[(i, j)]);
        assert!(
            fm.svd().is_err(),
            "faer converges here now: the fallback may be obsolete"
        );
        let (u, sv, v) = faer_svd(&g).unwrap();
        assert!(orthonormal(&u) && u.ncols() == 9);
        assert!(orthonormal(&v) && v.ncols() == 7);
        assert!(sv.windows(2).all(|w| w[0] >= w[1]));
        let s = DMatrix::from_fn(9, 7, |i, j| if i == j { sv[i] } else { 0.0 });
        assert!((&u * s * v.transpose() - &g).amax() < 1e-13);
    }
}
