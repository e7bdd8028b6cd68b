//! The largest output-nulling controlled-invariant subspace `V*` of `(A, B, C, D)` by the
//! standard recursion (Wonham, *Linear Multivariable Control*, 1979, Sec. 4.3; with
//! feedthrough as in Silverman 1976, Sec. III.A):
//!
//! `V_0 = R^n`, `V_{k+1} = {x : exists u, A x + B u in V_k, C x + D u = 0}`.
//!
//! With `P_k` an orthonormal basis of `V_k`'s complement, `V_{k+1}` is the `x` part of the null
//! space of `[P_k^T A, P_k^T B; C, D]`. Theorem 3.1 c) says `V*` is the span of the finite part
//! of `Q`.

use nalgebra::DMatrix;

use super::subspace::{self, RankDecision};
use super::{LinearError, LinearSystem};

/// `V*` as an orthonormal basis, with the dimensions of the recursion and its decisions.
#[derive(Debug, Clone)]
pub struct VStar {
    /// Orthonormal basis (columns).
    pub basis: DMatrix<f64>,
    /// `dim V_0, dim V_1, ...` until the sequence stops shrinking.
    pub dims: Vec<usize>,
    /// Rank decisions taken.
    pub decisions: Vec<RankDecision>,
}

/// Run the recursion.
pub fn vstar(sys: &LinearSystem, tol_factor: f64) -> Result<VStar, LinearError> {
    let (n, m) = (sys.n(), sys.m());
    let mut abcd = DMatrix::zeros(n + m, n + m);
    abcd.view_mut((0, 0), (n, n)).copy_from(&sys.a);
    abcd.view_mut((0, n), (n, m)).copy_from(&sys.b);
    abcd.view_mut((n, 0), (m, n)).copy_from(&sys.c);
    abcd.view_mut((n, n), (m, m)).copy_from(&sys.d);
    let scale = subspace::norm2(&abcd);
    let mut basis = DMatrix::<f64>::identity(n, n);
    let mut dims = vec![n];
    let mut decisions = Vec::new();
    for _ in 0..=n {
        let comp = subspace::complement(&basis)?;
        let k = comp.ncols();
        let mut g = DMatrix::zeros(k + m, n + m);
        g.view_mut((0, 0), (k, n))
            .copy_from(&(comp.transpose() * &sys.a));
        g.view_mut((0, n), (k, m))
            .copy_from(&(comp.transpose() * &sys.b));
        g.view_mut((k, 0), (m, n)).copy_from(&sys.c);
        g.view_mut((k, n), (m, m)).copy_from(&sys.d);
        let (null, d1) = subspace::null_space(&g, tol_factor, Some(scale))?;
        decisions.push(d1);
        let xpart = null.rows(0, n).into_owned();
        let (next, d2) = subspace::range(&xpart, tol_factor, Some(1.0))?;
        decisions.push(d2);
        let shrank = next.ncols() < basis.ncols();
        basis = next;
        if !shrank {
            break;
        }
        dims.push(basis.ncols());
    }
    Ok(VStar {
        basis,
        dims,
        decisions,
    })
}
