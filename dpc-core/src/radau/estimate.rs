//! The embedded local error estimate of Radau IIA (Hairer & Wanner, Section IV.8,
//! eq. (8.19)-(8.21); RADAU5's `ESTRAD`).
//!
//! The difference to the embedded order-3 formula, `ŷ_1 - y_1 = gamma_0 h y'_n + sum_i e_i Z_i`,
//! is not a usable estimate for stiff or algebraic components; it is filtered through the real
//! stage matrix `E_1 = dF/dy + (gamma/h) dF/dy'`:
//!
//! ```text
//! err = E_1^{-1} ( -F(t_n, y_n, -F_2) ),      F_2 = sum_i dd_i Z_i / h,   dd = gamma e,
//! ```
//!
//! which for `F = M y' - f(t, y)` is RADAU5's `E_1^{-1} (f(t_n, y_n) + M F_2)`. When the first
//! estimate fails on the first step or right after a rejection (where stiff components may
//! make it pessimistic), it is recomputed once with the residual at `y_n + err`
//! (Hairer & Wanner, eq. (8.21)): one more residual and one more real solve.

use super::linear::StageMatrices;
use super::newton::StageWork;
use super::tableau::Tableau;
use super::wrms;
use super::Stats;
use crate::linear_solver::LinearSolver;
use crate::ImplicitDae;

/// Work vectors of the estimate.
pub(crate) struct EstimateWork {
    /// `-F_2`, the derivative argument.
    yp: Vec<f64>,
    /// The estimate.
    pub err: Vec<f64>,
    /// `y_n + err`.
    y: Vec<f64>,
}

impl EstimateWork {
    pub fn new(n: usize) -> Self {
        Self {
            yp: vec![0.0; n],
            err: vec![0.0; n],
            y: vec![0.0; n],
        }
    }
}

/// A residual of the estimate was not finite: equation index.
pub(crate) struct NonFinite(pub usize);

/// The scaled error norm (at least `1e-10`), with the estimate left in `work.err`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn estimate<D: ImplicitDae, L: LinearSolver>(
    dae: &D,
    sm: &mut StageMatrices<L>,
    tab: &Tableau,
    stats: &mut Stats,
    t: f64,
    h: f64,
    y: &[f64],
    stages: &StageWork,
    w: &[f64],
    refine: bool,
    work: &mut EstimateWork,
) -> Result<f64, NonFinite> {
    let z = &stages.z;
    let d = tab.dd.map(|v| v / h);
    for (k, v) in work.yp.iter_mut().enumerate() {
        *v = -(d[0] * z[0][k] + d[1] * z[1][k] + d[2] * z[2][k]);
    }
    let mut solve_at = |ys: &[f64], err: &mut [f64], stats: &mut Stats| {
        dae.residual(t, ys, &work.yp, err);
        stats.residual_evaluations += 1;
        if let Some(i) = err.iter().position(|v| !v.is_finite()) {
            return Err(NonFinite(i));
        }
        err.iter_mut().for_each(|v| *v = -*v);
        sm.solve_real(err);
        stats.error_estimate_solves += 1;
        // A non-finite norm from finite residuals (an overflowing solve) counts as a failed
        // error test of unbounded size; `max` would turn a NaN into the floor.
        let e = wrms(err, w);
        Ok(if e.is_finite() {
            e.max(1e-10)
        } else {
            f64::INFINITY
        })
    };
    let mut e = solve_at(y, &mut work.err, stats)?;
    if e >= 1.0 && e.is_finite() && refine {
        for ((a, b), e) in work.y.iter_mut().zip(y).zip(&work.err) {
            *a = b + e;
        }
        e = solve_at(&work.y, &mut work.err, stats)?;
    }
    Ok(e)
}
