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

use super::newton::error_weights;
use super::{BdfError, Options, Stats};
use crate::linear_solver::LinearSolver;
use crate::newton::{
    first_non_finite, wrms, Convergence, Corrected, Iterate, NewtonFailure, NewtonSystem,
    NewtonWorkspace, Verdict,
};
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
/// [`BdfError::InitialisationFailed`] when Newton diverges or does not converge in 20
/// iterations.
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
    newton: NewtonWorkspace,
    y_try: Vec<f64>,
    yp_try: Vec<f64>,
}

impl InitWorkspace {
    /// Work vectors for a DAE of dimension `n`.
    pub fn new(n: usize) -> Self {
        Self {
            differential: vec![false; n],
            newton: NewtonWorkspace::new(n),
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
        BdfError::check_lengths(
            n,
            &[
                ("initialisation workspace", self.y_try.len()),
                ("y", y.len()),
                ("yp", yp.len()),
                ("linear solver", ls.dimension()),
            ],
        )?;
        opts.validate(n)?;
        for (i, d) in self.differential.iter_mut().enumerate() {
            *d = dae.is_differential(i);
        }
        let mut system = InitSystem {
            dae,
            t0,
            differential: &self.differential,
            y,
            yp,
            y_try: &mut self.y_try,
            yp_try: &mut self.yp_try,
            fnorm: 0.0,
            trial_residuals: 0,
        };
        let mut test = InitTest {
            opts,
            fnorm_before: 0.0,
        };
        let before = self.newton.counts;
        let outcome = self.newton.solve(ls, &mut system, &mut test, true);
        let counts = self.newton.counts;
        let matrices = counts.matrices - before.matrices;
        let stats = Stats {
            residual_evaluations: counts.residuals - before.residuals + system.trial_residuals,
            jacobian_evaluations: 2 * matrices,
            factorisations: matrices,
            newton_iterations: counts.solves - before.solves,
            ..Stats::default()
        };
        let fnorm = system.fnorm;
        match outcome {
            Ok(_) => Ok(stats),
            Err(NewtonFailure::Convergence) => Err(BdfError::InitialisationFailed {
                iterations: stats.newton_iterations,
                residual_norm: fnorm,
            }),
            Err(NewtonFailure::Singular(column, row)) => Err(BdfError::SingularMatrix {
                t: t0,
                unknown: column.map(|c| {
                    if self.differential[c] {
                        format!("derivative of {}", dae.unknown_name(c))
                    } else {
                        dae.unknown_name(c)
                    }
                }),
                equation: row.map(|r| dae.equation_name(r)),
            }),
            Err(other) => Err(other.into_error(dae, t0, 0.0)),
        }
    }
}

/// Newton iterations before the initialisation gives up.
const MAX_ITERATIONS: usize = 20;

/// The unknowns `(y'_d, y_a)` at `t0`, corrected with backtracking on the residual's 2-norm.
struct InitSystem<'a, D> {
    dae: &'a D,
    t0: f64,
    differential: &'a [bool],
    y: &'a mut [f64],
    yp: &'a mut [f64],
    y_try: &'a mut [f64],
    yp_try: &'a mut [f64],
    /// The residual's 2-norm at the current iterate.
    fnorm: f64,
    /// Residual evaluations of the backtracking.
    trial_residuals: usize,
}

impl<D: ImplicitDae> InitSystem<'_, D> {
    /// The weights of the unknowns: each in its own tolerance units, `y_a` by `|y_a|`,
    /// `y'_d` by `|y'_d|`.
    fn weights(&mut self, opts: &Options, w: &mut [f64]) -> Result<(), NewtonFailure> {
        for i in 0..self.y.len() {
            self.y_try[i] = if self.differential[i] {
                self.yp[i]
            } else {
                self.y[i]
            };
        }
        error_weights(opts, self.y_try, w).map_err(|e| match e {
            BdfError::InvalidTolerance {
                component, value, ..
            } => NewtonFailure::Weight { component, value },
            _ => NewtonFailure::Convergence,
        })
    }
}

impl<D: ImplicitDae, M: MatrixSink + ?Sized> NewtonSystem<M> for InitSystem<'_, D> {
    fn evaluate(&mut self, res: &mut [f64], residual: bool, matrix: Option<&mut M>) {
        if residual {
            self.dae.residual(self.t0, self.y, self.yp, res);
            self.fnorm = norm2(res);
        }
        if let Some(m) = matrix {
            m.fill_zero();
            let mut first = FirstPass {
                inner: &mut *m,
                differential: self.differential,
            };
            self.dae
                .iteration_matrix(self.t0, self.y, self.yp, C_BIG, &mut first);
            let mut second = SecondPass {
                inner: m,
                differential: self.differential,
            };
            self.dae
                .iteration_matrix(self.t0, self.y, self.yp, 0.0, &mut second);
        }
    }

    /// Backtracking: halve the step until the residual's 2-norm falls by the fraction
    /// `1e-4 lambda` (or `lambda` drops below `1/64`); a non-finite residual halves the step
    /// as well, and fails at the smallest one.
    fn correct(&mut self, delta: &mut [f64], res: &mut [f64]) -> Result<Corrected, NewtonFailure> {
        let fnorm = self.fnorm;
        let mut lambda = 1.0;
        loop {
            self.y_try.copy_from_slice(self.y);
            self.yp_try.copy_from_slice(self.yp);
            for (i, d) in delta.iter().enumerate() {
                if self.differential[i] {
                    self.yp_try[i] -= lambda * d;
                } else {
                    self.y_try[i] -= lambda * d;
                }
            }
            self.dae.residual(self.t0, self.y_try, self.yp_try, res);
            self.trial_residuals += 1;
            let small = lambda < 1.0 / 64.0;
            match first_non_finite(res) {
                None => {
                    let f = norm2(res);
                    if f <= (1.0 - 1e-4 * lambda) * fnorm || small || f == 0.0 {
                        self.fnorm = f;
                        break;
                    }
                }
                Some(i) if small => return Err(NewtonFailure::NonFinite(i)),
                Some(_) => {}
            }
            lambda *= 0.5;
        }
        self.y.copy_from_slice(self.y_try);
        self.yp.copy_from_slice(self.yp_try);
        Ok(Corrected {
            lambda,
            residual_current: true,
        })
    }
}

/// The residual's 2-norm.
fn norm2(res: &[f64]) -> f64 {
    res.iter().map(|r| r * r).sum::<f64>().sqrt()
}

/// The initialisation's convergence test: the weighted update (times the damping) below
/// `1e-3` times [`Options::newton_tolerance`] (IDA's `epiccon = 0.01 epcon`), from a matrix
/// formed in this pass or after a full step; the matrix is kept for the next pass after a
/// full step that shrank the residual by [`REUSE_CONTRACTION`].
struct InitTest<'a> {
    opts: &'a Options,
    /// The residual's 2-norm before the correction.
    fnorm_before: f64,
}

impl<D: ImplicitDae, L> Convergence<InitSystem<'_, D>, L> for InitTest<'_> {
    fn screen(&mut self, _sys: &mut InitSystem<'_, D>, res: &[f64]) -> Result<(), NewtonFailure> {
        match first_non_finite(res) {
            Some(i) => Err(NewtonFailure::NonFinite(i)),
            None => Ok(()),
        }
    }

    fn after_residual(&mut self, sys: &mut InitSystem<'_, D>, it: Iterate<'_, L>) -> Verdict {
        if let Err(f) = sys.weights(self.opts, it.w) {
            return Verdict::Fail(f);
        }
        self.fnorm_before = sys.fnorm;
        Verdict::Continue
    }

    fn after_update(&mut self, sys: &mut InitSystem<'_, D>, it: Iterate<'_, L>) -> Verdict {
        let lambda = it.corrected.lambda;
        let dnorm = wrms(it.delta, it.w);
        // A reused matrix's damped step says little about convergence: form a fresh one.
        let trusted = it.fresh || lambda == 1.0;
        if trusted && (lambda * dnorm <= 1e-3 * self.opts.newton_tolerance || sys.fnorm == 0.0) {
            return Verdict::Converged;
        }
        if it.solves >= MAX_ITERATIONS {
            return Verdict::Fail(NewtonFailure::Convergence);
        }
        // Keep the factorisation for the next iteration (simplified Newton) after a full
        // step that contracted the residual by REUSE_CONTRACTION: the Jacobian then hardly
        // changed (exactly not at all where F is linear in y'_d and there are no algebraic
        // unknowns, the usual mechanical plant after a jump of its inputs).
        if lambda == 1.0 && sys.fnorm <= REUSE_CONTRACTION * self.fnorm_before {
            Verdict::Continue
        } else {
            Verdict::Refresh { back: false }
        }
    }
}
