//! Weierstrass split of the regular pencil `-Es + F` (paper, (3.5)):
//! `M (-Es + F) Q = diag(-Is + A_1, -sN + I)` with `N` nilpotent of index `nu`.
//!
//! Rank-based, via the Wong sequences (Berger, Ilchmann, Trenn, "The quasi-Kronecker form for
//! matrix pencils", 2012):
//!
//! * `V_0 = R^n`, `V_{i+1} = F^-1(E V_i)` converges to the finite deflating subspace `V`;
//! * `W_0 = {0}`, `W_{i+1} = E^-1(F W_i)` converges to the infinite one `W`, and the number of
//!   steps until it stops growing is the nilpotency index of `N`.
//!
//! Then `Q = [V W]`, `M^-1 = [E V, F W]`. Each step is an SVD of an orthonormal basis times `E`
//! or `F`, so a defective infinite eigenvalue is never perturbed to `eps^(1/k)` as it is by
//! QZ; the decisions are rank decisions relative to `||E||` and `||F||`, and their gaps are
//! reported. The pencil is singular exactly when the two limits do not add up to `R^n`.

use nalgebra::DMatrix;

use super::subspace::{self, RankDecision};
use super::LinearError;

/// Result of the split.
#[derive(Debug, Clone)]
pub struct WeierstrassSplit {
    /// `Q = [V W]`, orthonormal bases of the finite and infinite deflating subspaces.
    pub q: DMatrix<f64>,
    /// `M = [E V, F W]^-1`.
    pub m: DMatrix<f64>,
    /// `M^-1 = [E V, F W]` (kept to solve with rather than multiply by `M`).
    pub m_inv: DMatrix<f64>,
    /// `A_1`, `n_f x n_f`.
    pub a1: DMatrix<f64>,
    /// `N`, nilpotent, `(n - n_f) x (n - n_f)`.
    pub n_mat: DMatrix<f64>,
    /// Dimension `n_f` of the finite part.
    pub finite_dim: usize,
    /// Nilpotency index `nu` of `N` (0 when there is no infinite part).
    pub index: usize,
    /// Dimensions of the Wong sequence `W_0, W_1, ...` (the Segre characteristic of infinity).
    pub infinite_chain: Vec<usize>,
    /// Every rank decision taken.
    pub decisions: Vec<RankDecision>,
    /// Largest off-diagonal residual of `M E Q`, `M F Q` relative to their norms.
    pub block_residual: f64,
    /// `||N^nu|| / max(1, ||N||)`, zero up to rounding.
    pub nilpotency_residual: f64,
    /// Condition number of `Q`.
    pub cond_q: f64,
    /// Condition number of `M^-1`.
    pub cond_m_inv: f64,
}

/// Split the pencil `-Es + F`.
///
/// `scale_e` and `scale_f` are the norms rank decisions on `E` and `F` are relative to. They
/// must not be `||E||`, `||F||` themselves: `E` can be zero up to rounding (a system with
/// feedthrough), and a tolerance relative to `||E|| ~ 1e-17` would count rounding as rank.
/// [`super::dpc_law`] passes `||[V_1 V_2]|| = 1` and `||[A; C]||`.
pub fn split(
    e: &DMatrix<f64>,
    f: &DMatrix<f64>,
    tol_factor: f64,
    scale_e: f64,
    scale_f: f64,
) -> Result<WeierstrassSplit, LinearError> {
    let n = e.nrows();
    let ne = subspace::norm2(e).max(scale_e);
    let nf = subspace::norm2(f).max(scale_f);
    let mut decisions = Vec::new();

    // Finite part: V_{i+1} = {x : F x in E V_i}.
    let mut v = DMatrix::<f64>::identity(n, n);
    for _ in 0..=n {
        let (ev, d1) = subspace::range(&(e * &v), tol_factor, Some(ne))?;
        decisions.push(d1);
        let comp = subspace::complement(&ev)?;
        let (next, d2) = subspace::null_space(&(comp.transpose() * f), tol_factor, Some(nf))?;
        if comp.ncols() > 0 {
            decisions.push(d2);
        }
        let done = next.ncols() == v.ncols();
        v = next;
        if done {
            break;
        }
    }

    // Infinite part: W_{i+1} = {x : E x in F W_i}.
    let mut w = DMatrix::<f64>::zeros(n, 0);
    let mut chain = vec![0usize];
    for _ in 0..=n {
        let (fw, d1) = subspace::range(&(f * &w), tol_factor, Some(nf))?;
        if w.ncols() > 0 {
            decisions.push(d1);
        }
        let comp = subspace::complement(&fw)?;
        let (next, d2) = subspace::null_space(&(comp.transpose() * e), tol_factor, Some(ne))?;
        if comp.ncols() > 0 {
            decisions.push(d2);
        }
        let grew = next.ncols() > w.ncols();
        w = next;
        if !grew {
            break;
        }
        chain.push(w.ncols());
    }
    let index = chain.len() - 1;

    let finite_dim = v.ncols();
    let mut q = DMatrix::zeros(n, finite_dim + w.ncols());
    q.view_mut((0, 0), (n, finite_dim)).copy_from(&v);
    q.view_mut((0, finite_dim), (n, w.ncols())).copy_from(&w);
    let qtol = tol_factor * (n.max(1) as f64) * f64::EPSILON * 2.0;
    let singular = |sigma_min: f64| LinearError::SingularPencil {
        finite_dim,
        infinite_dim: w.ncols(),
        n,
        sigma_min,
        tol: qtol,
    };
    if q.ncols() != n {
        let sigma_min = if q.ncols() == 0 {
            0.0
        } else {
            let (_, sv) = subspace::svd_left(&q)?;
            sv.last().copied().unwrap_or(0.0)
        };
        return Err(singular(sigma_min));
    }
    if n > 0 {
        let (_, sv) = subspace::svd_left(&q)?;
        // Columns are orthonormal in two blocks, so ||Q|| <= sqrt 2.
        let sigma_min = sv.last().copied().unwrap_or(0.0);
        if sigma_min <= qtol {
            return Err(singular(sigma_min));
        }
    }

    let mut m_inv = DMatrix::zeros(n, n);
    m_inv.view_mut((0, 0), (n, finite_dim)).copy_from(&(e * &v));
    m_inv
        .view_mut((0, finite_dim), (n, n - finite_dim))
        .copy_from(&(f * &w));
    let eq = e * &q;
    let fq = f * &q;
    let meq = subspace::solve(&m_inv, &eq).ok_or_else(|| singular(0.0))?;
    let mfq = subspace::solve(&m_inv, &fq).ok_or_else(|| singular(0.0))?;
    let m = subspace::solve(&m_inv, &DMatrix::identity(n, n)).ok_or_else(|| singular(0.0))?;
    let ni = n - finite_dim;
    let a1 = mfq.view((0, 0), (finite_dim, finite_dim)).into_owned();
    let n_mat = meq.view((finite_dim, finite_dim), (ni, ni)).into_owned();

    // Residuals of the block structure: M E Q = diag(I, N), M F Q = diag(A_1, I).
    let mut target_e = DMatrix::zeros(n, n);
    target_e
        .view_mut((0, 0), (finite_dim, finite_dim))
        .fill_with_identity();
    target_e
        .view_mut((finite_dim, finite_dim), (ni, ni))
        .copy_from(&n_mat);
    let mut target_f = DMatrix::zeros(n, n);
    target_f
        .view_mut((0, 0), (finite_dim, finite_dim))
        .copy_from(&a1);
    target_f
        .view_mut((finite_dim, finite_dim), (ni, ni))
        .fill_with_identity();
    let block_residual = ((&meq - target_e).amax() / meq.amax().max(1.0))
        .max((&mfq - target_f).amax() / mfq.amax().max(1.0));

    let mut power = DMatrix::identity(ni, ni);
    for _ in 0..index {
        power = &power * &n_mat;
    }
    let nilpotency_residual = if ni == 0 {
        0.0
    } else {
        subspace::norm2(&power) / subspace::norm2(&n_mat).max(1.0).powi(index as i32)
    };

    Ok(WeierstrassSplit {
        cond_q: subspace::cond(&q),
        cond_m_inv: subspace::cond(&m_inv),
        q,
        m,
        m_inv,
        a1,
        n_mat,
        finite_dim,
        index,
        infinite_chain: chain,
        decisions,
        block_residual,
        nilpotency_residual,
    })
}
