//! Modified Newton iteration on `G(y) = F(t, y, y'_pred + cj (y - y_pred)) = 0`, shared by the
//! variable-step and fixed-step integrators.
//!
//! The iteration matrix `dF/dy + cj dF/dy'` is kept across steps and refactorised only when
//! Newton fails with a stale matrix or `cj` drifts beyond the window `[0.6, 1.67]` of the value
//! it was factorised with (IDA's `XRATE = 0.25`); in between, updates are scaled by
//! `2 / (1 + cj/cj_old)` to compensate (Brenan, Campbell & Petzold 1989, Section 5.2.2).
//! Convergence is declared from the rate estimate `s = rho / (1 - rho)`:
//! `s |delta| <= epcon` in the weighted RMS norm (IDA's `IDANewtonIter`).

use super::{BdfError, Options, Stats};
use crate::linear_solver::{FactorError, LinearSolver};
use crate::ImplicitDae;

/// State of the iteration matrix and its factorisation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct JacState {
    /// `cj` the matrix was formed with.
    pub cj_factored: f64,
    /// The matrix was formed in the current step attempt (a retry cannot help).
    pub current: bool,
    /// A valid factorisation exists.
    pub valid: bool,
    /// Convergence-rate factor `s` carried between steps.
    pub ss: f64,
    /// `cj` of the previous Newton solve.
    pub cj_last: f64,
}

impl Default for JacState {
    fn default() -> Self {
        Self {
            cj_factored: 0.0,
            current: false,
            valid: false,
            ss: 20.0,
            cj_last: 0.0,
        }
    }
}

/// Why an attempt failed; recoverable by a smaller step in the variable-step integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum NewtonFailure {
    /// Slow or diverging iteration.
    Convergence,
    /// Singular iteration matrix (pivot column, zero row).
    Singular(Option<usize>, Option<usize>),
    /// Non-finite residual in this equation.
    NonFinite(usize),
    /// Matrix entry outside the declared pattern: not recoverable.
    OutsidePattern(usize, usize),
}

impl NewtonFailure {
    /// The typed error to report when this failure is final.
    pub fn into_error<D: ImplicitDae>(self, dae: &D, t: f64, h: f64) -> BdfError {
        match self {
            Self::Convergence => BdfError::NewtonFailed { t, h },
            Self::Singular(col, row) => BdfError::SingularMatrix {
                t,
                unknown: col.map(|c| dae.unknown_name(c)),
                equation: row.map(|r| dae.equation_name(r)),
            },
            Self::NonFinite(i) => BdfError::NonFiniteResidual {
                t,
                equation: dae.equation_name(i),
            },
            Self::OutsidePattern(r, c) => BdfError::OutsidePattern {
                equation: dae.equation_name(r),
                unknown: dae.unknown_name(c),
            },
        }
    }
}

/// Weighted RMS norm `sqrt(sum (v_i w_i)^2 / n)`.
#[inline]
pub(crate) fn wrms(v: &[f64], w: &[f64]) -> f64 {
    let n = v.len().max(1) as f64;
    let s: f64 = v.iter().zip(w).map(|(a, b)| (a * b) * (a * b)).sum();
    (s / n).sqrt()
}

/// Error weights `1 / (rtol_i |y_i| + atol_i)`.
pub(crate) fn error_weights(opts: &Options, y: &[f64], w: &mut [f64]) -> Result<(), BdfError> {
    for (i, (wi, yi)) in w.iter_mut().zip(y).enumerate() {
        let d = opts.rtol.get(i) * yi.abs() + opts.atol.get(i);
        if !(d > 0.0 && d.is_finite()) {
            return Err(BdfError::InvalidTolerance {
                which: "error weight",
                component: i,
                value: d,
            });
        }
        *wi = 1.0 / d;
    }
    Ok(())
}

/// First index of a non-finite entry.
#[inline]
pub(crate) fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}

/// Form and factorise `dF/dy + cj dF/dy'` at `(t, y, yp)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn setup<D: ImplicitDae, L: LinearSolver>(
    dae: &D,
    ls: &mut L,
    jac: &mut JacState,
    stats: &mut Stats,
    t: f64,
    y: &[f64],
    yp: &[f64],
    cj: f64,
) -> Result<(), NewtonFailure> {
    use crate::MatrixSink;
    let m = ls.matrix_mut();
    m.fill_zero();
    dae.iteration_matrix(t, y, yp, cj, m);
    stats.jacobian_evaluations += 1;
    stats.factorisations += 1;
    jac.cj_factored = cj;
    jac.current = true;
    jac.ss = 20.0;
    match ls.factor() {
        Ok(()) => {
            jac.valid = true;
            Ok(())
        }
        Err(FactorError::Singular { column, row }) => {
            jac.valid = false;
            Err(NewtonFailure::Singular(column, row))
        }
        Err(FactorError::OutsidePattern { row, col }) => {
            jac.valid = false;
            Err(NewtonFailure::OutsidePattern(row, col))
        }
    }
}

/// The inputs of one Newton solve; the predictor and the weights are in the
/// [`Corrector`].
pub(crate) struct NewtonProblem {
    pub t: f64,
    pub cj: f64,
    pub max_iterations: usize,
    pub epcon: f64,
    /// When finite: the scaled residual `max_i |F_i| / max_j (|G_ij| / w_j)` at the solution
    /// must not exceed this.
    pub residual_tolerance: f64,
    /// Force a fresh iteration matrix before the first iteration.
    pub force_setup: bool,
}

/// Everything Newton works in, allocated once for an integrator: the linear solver with its
/// factorised iteration matrix and the state of that matrix, the predictor it starts from,
/// the weights of its convergence test, the iterate and its work vectors.
pub(crate) struct Corrector<L: LinearSolver> {
    /// The linear solver holding the iteration matrix.
    pub ls: L,
    /// What the factorised matrix was formed with.
    pub jac: JacState,
    /// The predicted `y` and `y'` the iteration starts from.
    pub y_pred: Vec<f64>,
    pub yp_pred: Vec<f64>,
    /// Weights of the convergence test.
    pub w: Vec<f64>,
    /// The iterate `y`, `y' = y'_pred + cj (y - y_pred)` and the correction `ee = y - y_pred`.
    pub y: Vec<f64>,
    pub yp: Vec<f64>,
    pub ee: Vec<f64>,
    /// The residual and the Newton update (also scratch for the caller between solves).
    pub res: Vec<f64>,
    pub delta: Vec<f64>,
}

impl<L: LinearSolver> Corrector<L> {
    /// Work vectors of dimension `n` around the solver `ls`.
    pub fn new(ls: L, n: usize) -> Self {
        Self {
            ls,
            jac: JacState::default(),
            y_pred: vec![0.0; n],
            yp_pred: vec![0.0; n],
            w: vec![0.0; n],
            y: vec![0.0; n],
            yp: vec![0.0; n],
            ee: vec![0.0; n],
            res: vec![0.0; n],
            delta: vec![0.0; n],
        }
    }

    /// Solve for `y`, `yp` (and the correction `ee = y - y_pred`) from the predictor. On
    /// failure with a stale matrix the attempt is repeated once with a fresh one, as IDA does.
    pub fn solve<D: ImplicitDae>(
        &mut self,
        dae: &D,
        stats: &mut Stats,
        p: &NewtonProblem,
    ) -> Result<usize, NewtonFailure> {
        self.jac.current = false;
        // A changed cj makes the carried rate estimate unreliable: start pessimistic (IDA).
        if p.cj != self.jac.cj_last {
            self.jac.ss = 100.0;
            self.jac.cj_last = p.cj;
        }
        let mut need_setup = p.force_setup || !self.jac.valid || {
            let r = p.cj / self.jac.cj_factored;
            !(0.6..=1.0 / 0.6).contains(&r)
        };
        loop {
            self.y.copy_from_slice(&self.y_pred);
            self.yp.copy_from_slice(&self.yp_pred);
            self.ee.fill(0.0);
            if need_setup {
                setup(
                    dae,
                    &mut self.ls,
                    &mut self.jac,
                    stats,
                    p.t,
                    &self.y,
                    &self.yp,
                    p.cj,
                )?;
            }
            match self.iterate(dae, stats, p) {
                Ok(m) => return Ok(m),
                Err(NewtonFailure::Convergence | NewtonFailure::NonFinite(_))
                    if !self.jac.current =>
                {
                    need_setup = true;
                }
                Err(e) => return Err(e),
            }
        }
    }

    fn iterate<D: ImplicitDae>(
        &mut self,
        dae: &D,
        stats: &mut Stats,
        p: &NewtonProblem,
    ) -> Result<usize, NewtonFailure> {
        let Self {
            ls,
            jac,
            w,
            y,
            yp,
            ee,
            res,
            delta,
            ..
        } = self;
        let cjratio = p.cj / jac.cj_factored;
        let scale = if cjratio == 1.0 {
            1.0
        } else {
            2.0 / (1.0 + cjratio)
        };
        let mut oldnrm = 0.0;
        let mut m = 0;
        loop {
            dae.residual(p.t, y, yp, res);
            stats.residual_evaluations += 1;
            if let Some(i) = first_non_finite(res) {
                return Err(NewtonFailure::NonFinite(i));
            }
            delta.copy_from_slice(res);
            ls.solve_in_place(delta);
            stats.newton_iterations += 1;
            if scale != 1.0 {
                delta.iter_mut().for_each(|d| *d *= scale);
            }
            for i in 0..y.len() {
                y[i] -= delta[i];
                ee[i] -= delta[i];
                yp[i] -= p.cj * delta[i];
            }
            let delnrm = wrms(delta, w);
            if !delnrm.is_finite() {
                return Err(NewtonFailure::Convergence);
            }
            let mut converged = false;
            if m == 0 {
                oldnrm = delnrm;
                if delnrm <= 1e-4 * p.epcon {
                    converged = true;
                }
            } else {
                let ratio = delnrm / oldnrm;
                let rate = if m == 1 {
                    ratio
                } else {
                    ratio.powf(1.0 / m as f64)
                };
                if rate > 0.9 {
                    return Err(NewtonFailure::Convergence);
                }
                jac.ss = rate / (1.0 - rate);
            }
            if converged || jac.ss * delnrm <= p.epcon {
                if p.residual_tolerance.is_finite() {
                    dae.residual(p.t, y, yp, res);
                    stats.residual_evaluations += 1;
                    if let Some(i) = first_non_finite(res) {
                        return Err(NewtonFailure::NonFinite(i));
                    }
                    // Scaled residual: each equation relative to the change one tolerance unit
                    // of the unknowns causes in it (absolute where a row of the matrix is
                    // empty).
                    ls.scaled_row_norms(w, delta);
                    let rn = res.iter().zip(delta.iter()).fold(0.0f64, |a, (r, s)| {
                        a.max(if *s > 0.0 { r.abs() / s } else { r.abs() })
                    });
                    if rn <= p.residual_tolerance {
                        return Ok(m + 1);
                    }
                } else {
                    return Ok(m + 1);
                }
            }
            m += 1;
            if m >= p.max_iterations {
                return Err(NewtonFailure::Convergence);
            }
        }
    }
}
