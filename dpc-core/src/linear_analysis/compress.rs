//! Row compression of `[B; D]` (paper, Section 3, before (3.4)): an invertible `V` with
//! `V [B; D] = [0; I]`, which turns the system pencil into `[-Es + F, 0; -Hs + J, I]`.
//!
//! Built from the SVD of `[B; D]` (range `U_1`, left null space `U_2`): the top block rows are `U_2^T` (an orthonormal
//! basis of the left null space), the bottom rows the left inverse `R^-1 U_1^T` with `R = U_1^T [B; D]`, so
//! `V = diag(I, R^-1) [U_2 U_1]^T` is as well conditioned as `[B; D]` itself.

use nalgebra::DMatrix;

use super::subspace::{self, RankDecision};
use super::{LinearError, LinearSystem};

/// The blocks of `V` and the pencil data `E, F, H, J` of (3.4).
#[derive(Debug, Clone)]
pub struct RowCompression {
    /// `V_1` (`n x n`).
    pub v1: DMatrix<f64>,
    /// `V_2` (`n x m`).
    pub v2: DMatrix<f64>,
    /// `V_3` (`m x n`).
    pub v3: DMatrix<f64>,
    /// `V_4` (`m x m`).
    pub v4: DMatrix<f64>,
    /// `E = V_1`.
    pub e: DMatrix<f64>,
    /// `F = V_1 A + V_2 C`.
    pub f: DMatrix<f64>,
    /// `H = V_3`.
    pub h: DMatrix<f64>,
    /// `J = V_3 A + V_4 C`.
    pub j: DMatrix<f64>,
    /// The rank decision on `[B; D]`.
    pub decision: RankDecision,
}

/// Compute the row compression of `[B; D]`; fails if `[B; D]` has rank `< m`.
pub fn compress(sys: &LinearSystem, tol_factor: f64) -> Result<RowCompression, LinearError> {
    let (n, m) = (sys.n(), sys.m());
    let mut g = DMatrix::zeros(n + m, m);
    g.view_mut((0, 0), (n, m)).copy_from(&sys.b);
    g.view_mut((n, 0), (m, m)).copy_from(&sys.d);
    let (u, sv) = subspace::svd_left(&g)?;
    let decision = subspace::decide(&sv, g.shape(), tol_factor);
    if decision.rank < m {
        return Err(LinearError::NotInvertible {
            rank: decision.rank,
            m,
            tol: decision.tol,
            singular_values: sv,
        });
    }
    let u1 = u.columns(0, m);
    let u2 = subspace::complement(&u1.into_owned())?;
    let u1 = u.columns(0, m);
    // G = U_1 R with R = U_1^T G (m x m, as well conditioned as G): the bottom rows R^-1 U_1^T
    // are a left inverse of G.
    let r = u1.transpose() * &g;
    let bottom =
        subspace::solve(&r, &u1.transpose().into_owned()).ok_or(LinearError::NotInvertible {
            rank: decision.rank,
            m,
            tol: decision.tol,
            singular_values: sv.clone(),
        })?;
    let top = u2.transpose();
    let v1 = top.columns(0, n).into_owned();
    let v2 = top.columns(n, m).into_owned();
    let v3 = bottom.columns(0, n).into_owned();
    let v4 = bottom.columns(n, m).into_owned();
    let e = v1.clone();
    let f = &v1 * &sys.a + &v2 * &sys.c;
    let h = v3.clone();
    let j = &v3 * &sys.a + &v4 * &sys.c;
    Ok(RowCompression {
        v1,
        v2,
        v3,
        v4,
        e,
        f,
        h,
        j,
        decision,
    })
}
