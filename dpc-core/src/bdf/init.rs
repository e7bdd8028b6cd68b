//! Consistent initial values for index-1 DAEs.
//!
//! Given the differential components of `y` (those with [`ImplicitDae::is_differential`]),
//! solve `F(t0, y, y') = 0` for the algebraic components of `y` and the derivatives of the
//! differential ones, keeping the given differential values and the algebraic entries of `y'`.
//! This is the problem IDA's `IDACalcIC` solves with `IDA_YA_YDP_INIT` (Brown, Hindmarsh &
//! Petzold, SIAM J. Sci. Comput. 19, 1998). The Jacobian with respect to the unknowns
//! `(y'_d, y_a)` has columns `dF/dy'_i` (differential) and `dF/dy_i` (algebraic); it is taken
//! from two calls of the model's iteration matrix `dF/dy + c dF/dy'`, with `c = C` (scaled by
//! `1/C`) and `c = 0` (subtracted), so that singularity of this Jacobian (the problem is not
//! index 1 in the given split) is detected rather than hidden by an `O(1/C)` perturbation.
//! Newton's method is damped by backtracking on the residual norm; after a full step that
//! shrank the residual a hundredfold the next iteration reuses the factorisation (simplified
//! Newton), so a plant made consistent again after a jump of its inputs costs one
//! factorisation, not two.

use super::newton::{error_weights, first_non_finite, wrms};
use super::{BdfError, Options, Stats};
use crate::linear_solver::{FactorError, LinearSolver};
use crate::{ImplicitDae, MatrixSink};

/// A power of two, so the scalings by `1/C_BIG` are exact.
const C_BIG: f64 = 134_217_728.0;

/// A full Newton step that shrinks the residual's 2-norm at least this much keeps its
/// factorisation for the next iteration.
const REUSE_CONTRACTION: f64 = 1e-2;

/// Pass 1 (the model called with `c = C_BIG`): algebraic columns `dF/dy_a` as they are,
/// differential columns `(dF/dy_d + C dF/dy'_d) / C`.
struct FirstPass<'a, S: MatrixSink + ?Sized> {
    inner: &'a mut S,
    differential: &'a [bool],
}

impl<S: MatrixSink + ?Sized> MatrixSink for FirstPass<'_, S> {
    fn rows(&self) -> usize {
        self.inner.rows()
    }
    fn cols(&self) -> usize {
        self.inner.cols()
    }
    fn set(&mut self, row: usize, col: usize, value: f64) {
        let s = if self.differential[col] {
            1.0 / C_BIG
        } else {
            1.0
        };
        self.inner.set(row, col, value * s);
    }
    fn add(&mut self, row: usize, col: usize, value: f64) {
        let s = if self.differential[col] {
            1.0 / C_BIG
        } else {
            1.0
        };
        self.inner.add(row, col, value * s);
    }
    fn fill_zero(&mut self) {
        self.inner.fill_zero();
    }
}

/// Pass 2 (the model called with `c = 0`): subtract `dF/dy_d / C` from the differential
/// columns, leaving exactly `dF/dy'_d` there. Every write is an addition into a logically
/// zeroed matrix, so `set` and `add` both subtract.
struct SecondPass<'a, S: MatrixSink + ?Sized> {
    inner: &'a mut S,
    differential: &'a [bool],
}

impl<S: MatrixSink + ?Sized> MatrixSink for SecondPass<'_, S> {
    fn rows(&self) -> usize {
        self.inner.rows()
    }
    fn cols(&self) -> usize {
        self.inner.cols()
    }
    fn set(&mut self, row: usize, col: usize, value: f64) {
        if self.differential[col] {
            self.inner.add(row, col, -value / C_BIG);
        }
    }
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self.set(row, col, value);
    }
    fn fill_zero(&mut self) {}
}

/// Make `(y, yp)` consistent at `t0`: keep the differential components of `y`, compute the
/// algebraic components of `y` and the differential components of `yp` (the algebraic
/// components of `yp` are left as given). `y` and `yp` hold the initial guesses on entry.
///
/// Convergence is declared when the Newton update is below `1e-3` in the weighted RMS norm of
/// `opts` (IDA's `epiccon = 0.01 epcon`) and the residual is finite. Returns the work done.
///
/// # Errors
/// [`BdfError::DimensionMismatch`]; [`BdfError::SingularMatrix`] naming the unknown and
/// equation when the Jacobian with respect to `(y'_d, y_a)` is singular (the DAE is not of
/// index 1 in this split, or an algebraic unknown does not appear); [`BdfError::NonFiniteResidual`];
/// [`BdfError::InitialisationFailed`] when Newton does not converge in 20 iterations.
pub fn consistent_initial_values<D: ImplicitDae, L: LinearSolver>(
    dae: &D,
    ls: &mut L,
    opts: &Options,
    t0: f64,
    y: &mut [f64],
    yp: &mut [f64],
) -> Result<Stats, BdfError> {
    InitWorkspace::new(dae.dimension()).consistent_initial_values(dae, ls, opts, t0, y, yp)
}

/// The work vectors of [`consistent_initial_values`], allocated once, for a caller that makes
/// a DAE consistent again and again (a closed loop at every sample) without allocating.
#[derive(Debug, Clone)]
pub struct InitWorkspace {
    differential: Vec<bool>,
    res: Vec<f64>,
    delta: Vec<f64>,
    w: Vec<f64>,
    y_try: Vec<f64>,
    yp_try: Vec<f64>,
}

impl InitWorkspace {
    /// Work vectors for a DAE of dimension `n`.
    pub fn new(n: usize) -> Self {
        Self {
            differential: vec![false; n],
            res: vec![0.0; n],
            delta: vec![0.0; n],
            w: vec![0.0; n],
            y_try: vec![0.0; n],
            yp_try: vec![0.0; n],
        }
    }

    /// [`consistent_initial_values`] in these work vectors (which must have the DAE's
    /// dimension: [`BdfError::DimensionMismatch`] otherwise).
    ///
    /// # Errors
    /// As [`consistent_initial_values`].
    pub fn consistent_initial_values<D: ImplicitDae, L: LinearSolver>(
        &mut self,
        dae: &D,
        ls: &mut L,
        opts: &Options,
        t0: f64,
        y: &mut [f64],
        yp: &mut [f64],
    ) -> Result<Stats, BdfError> {
        let n = dae.dimension();
        if self.res.len() != n {
            return Err(BdfError::DimensionMismatch {
                what: "initialisation workspace",
                expected: n,
                found: self.res.len(),
            });
        }
        let InitWorkspace {
            differential,
            res,
            delta,
            w,
            y_try,
            yp_try,
        } = self;
        for (i, d) in differential.iter_mut().enumerate() {
            *d = dae.is_differential(i);
        }
        solve(
            dae,
            ls,
            opts,
            t0,
            y,
            yp,
            differential,
            [res, delta, w, y_try, yp_try],
        )
    }
}

#[allow(clippy::too_many_arguments)]
fn solve<D: ImplicitDae, L: LinearSolver>(
    dae: &D,
    ls: &mut L,
    opts: &Options,
    t0: f64,
    y: &mut [f64],
    yp: &mut [f64],
    differential: &[bool],
    [res, delta, w, y_try, yp_try]: [&mut Vec<f64>; 5],
) -> Result<Stats, BdfError> {
    let n = dae.dimension();
    for (what, found) in [
        ("y", y.len()),
        ("yp", yp.len()),
        ("linear solver", ls.dimension()),
    ] {
        if found != n {
            return Err(BdfError::DimensionMismatch {
                what,
                expected: n,
                found,
            });
        }
    }
    opts.validate(n)?;
    let mut stats = Stats::default();
    let eval =
        |y: &[f64], yp: &[f64], res: &mut [f64], stats: &mut Stats| -> Result<f64, BdfError> {
            dae.residual(t0, y, yp, res);
            stats.residual_evaluations += 1;
            if let Some(i) = first_non_finite(res) {
                return Err(BdfError::NonFiniteResidual {
                    t: t0,
                    equation: dae.equation_name(i),
                });
            }
            Ok(res.iter().map(|r| r * r).sum::<f64>().sqrt())
        };
    let mut fnorm = eval(y, yp, &mut *res, &mut stats)?;
    // Keep the factorisation for the next iteration (simplified Newton) after a full step
    // that contracted the residual by REUSE_CONTRACTION: the Jacobian then hardly changed
    // (exactly not at all where F is linear in y'_d and there are no algebraic unknowns, the
    // usual mechanical plant after a jump of its inputs).
    let mut reuse = false;
    for _ in 0..20 {
        // Each unknown is measured in its own tolerance units: y_a by |y_a|, y'_d by |y'_d|.
        for i in 0..n {
            y_try[i] = if differential[i] { yp[i] } else { y[i] };
        }
        error_weights(opts, y_try, &mut *w)?;
        if !reuse {
            let m = ls.matrix_mut();
            m.fill_zero();
            let mut first = FirstPass {
                inner: &mut *m,
                differential,
            };
            dae.iteration_matrix(t0, y, yp, C_BIG, &mut first);
            let mut second = SecondPass {
                inner: m,
                differential,
            };
            dae.iteration_matrix(t0, y, yp, 0.0, &mut second);
            stats.jacobian_evaluations += 2;
            stats.factorisations += 1;
        }
        match if reuse { Ok(()) } else { ls.factor() } {
            Ok(()) => {}
            Err(FactorError::Singular { column, row }) => {
                return Err(BdfError::SingularMatrix {
                    t: t0,
                    unknown: column.map(|c| {
                        if differential[c] {
                            format!("derivative of {}", dae.unknown_name(c))
                        } else {
                            dae.unknown_name(c)
                        }
                    }),
                    equation: row.map(|r| dae.equation_name(r)),
                });
            }
            Err(FactorError::OutsidePattern { row, col }) => {
                return Err(BdfError::OutsidePattern {
                    equation: dae.equation_name(row),
                    unknown: dae.unknown_name(col),
                });
            }
        }
        delta.copy_from_slice(res);
        ls.solve_in_place(&mut *delta);
        stats.newton_iterations += 1;
        let dnorm = wrms(delta, w);
        let fnorm_before = fnorm;
        let mut lambda = 1.0;
        loop {
            for i in 0..n {
                y_try[i] = y[i];
                yp_try[i] = yp[i];
                if differential[i] {
                    yp_try[i] -= lambda * delta[i];
                } else {
                    y_try[i] -= lambda * delta[i];
                }
            }
            match eval(y_try, yp_try, &mut *res, &mut stats) {
                Ok(f) if f <= (1.0 - 1e-4 * lambda) * fnorm || lambda < 1.0 / 64.0 || f == 0.0 => {
                    fnorm = f;
                    break;
                }
                Ok(_) | Err(BdfError::NonFiniteResidual { .. }) if lambda >= 1.0 / 64.0 => {
                    lambda *= 0.5;
                }
                Ok(f) => {
                    fnorm = f;
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        y.copy_from_slice(y_try);
        yp.copy_from_slice(yp_try);
        // A reused matrix's damped step says little about convergence: form a fresh one.
        let trusted = !reuse || lambda == 1.0;
        if trusted && (lambda * dnorm <= 1e-3 * opts.newton_tolerance || fnorm == 0.0) {
            return Ok(stats);
        }
        reuse = lambda == 1.0 && fnorm <= REUSE_CONTRACTION * fnorm_before;
    }
    Err(BdfError::InitialisationFailed(format!(
        "Newton did not converge in 20 iterations (residual 2-norm {fnorm:e})"
    )))
}
