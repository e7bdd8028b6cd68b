//! The crate's one Newton iteration, for every implicit system it solves: the corrector of
//! [`crate::bdf::Bdf`], the corrector of the fixed-step [`crate::bdf::FixedBdf`] (which also
//! runs the controller's inner implicit-Euler steps, [`crate::controller::Dpc`]) and the
//! consistent initialisation ([`crate::bdf::consistent_initial_values`]).
//!
//! [`NewtonWorkspace::solve`] owns the iteration: evaluate the residual (and, when the
//! factorised matrix is stale, the iteration matrix at the same point), factorise, solve for the
//! update, correct the iterate, stop. What differs between the callers is in two types the
//! caller chooses:
//!
//! * the [`NewtonSystem`]: the unknowns and how an update corrects them (the variable-step
//!   BDF's `y` with `y' = y'_pred + cj (y - y_pred)`, the fixed-step BDF's `y` with
//!   `y' = (a_0 y + sum_{j>=1} a_j y_{n+1-j}) / h` formed at every evaluation, for the
//!   controller's `[X; Z; U]` exactly `X' = (X - X_prev) / delta`, the initialisation's
//!   `(y'_d, y_a)` with backtracking);
//! * the [`Convergence`] test: IDA's rate test `s |delta| <= epcon` (the BDF, fixed-step by
//!   default), the weighted update test with a residual contraction rule for matrix reuse (the
//!   initialisation), a caller's [`crate::bdf::CorrectorTest`] of the fixed-step BDF (the
//!   controller's scaled-residual and control test with matrix reuse by the residual's fall
//!   rate).
//!
//! The workspace keeps its factorisation between solves; the caller says when it is stale.
//! Failures are typed ([`NewtonFailure`]) and mapped to each caller's error type.

use crate::linear_solver::{FactorError, LinearSolver};

/// The least rate factor `s = rho / (1 - rho)` with which a Newton solve on a DAE with unknowns
/// of index 2 or 3 judges its first update: the BDF's corrector (`RateTest::min_carried` in
/// `bdf/newton.rs`) and Radau's stage iteration (RADAU5's `FACCON`, `radau/newton.rs`). IDA and
/// RADAU5 judge it with the factor carried from the last solve, however small.
///
/// On the stabilised form of Andrews' mechanism that factor fell to `1e-8` (a solve whose first
/// update, 10^5 tolerance units in the plain weights of the accelerations and multipliers, was
/// followed by a tiny one), and the next steps accepted single updates of that size with the
/// matrix aged: their solutions missed the hidden velocity constraints by 15 tolerance units of
/// the velocities, a defect no step size removes, so the following step failed the error test
/// five times down to `h / 400` and climbed back over twenty steps, three times in the run.
/// With the floor `1e-4` (first updates up to `epcon / 1e-4 = 3 300` units still accepted at
/// once): at `rtol = 1e-4 / 1e-6 / 1e-8` 339 / 685 / 1 176 steps -> 257 / 434 / 946, 3.00 /
/// 4.35 / 6.42 digits -> 3.39 / 5.62 / 6.08, instructions -5 % / -13 % / +5 %; the index-3
/// pendulum at `1e-6 / 1e-8` 269 / 605 steps -> 161 / 310, 2.68 / 4.93 digits -> 5.03 / 6.00,
/// Andrews' index-3 form at `1e-8` 702 -> 418 steps, 3.36 -> 4.98 digits. DAEs of index 1
/// keep IDA's test (with `INDEX1_NEWTON_FACTOR`).
///
/// Radau (2026-12-05): on the Test Set's water tube at `1e-8` a step that carried a pipe's
/// flow across the laminar/turbulent switch was accepted on one update with the factor carried
/// from the smooth steps before, left the friction factor's Colebrook row with the residual
/// 0.05, and the next step's error estimate (which evaluates `F` at the step's start) failed at
/// every step size: 5 of 15 tolerance factors stopped there. With the floor all 15 run (2.72
/// digits, median; 2.77 over the ten that ran before); over the whole table at factor 1 only
/// the car axis (one step), the water tube and the spherical pendulum at `1e-8` (7.26 -> 6.39
/// digits at that factor, 6.18 -> 6.07 median over 15) move.
pub(crate) const MIN_CARRIED_RATE: f64 = 1e-4;

/// The Newton failures of the step being attempted that measured a contraction: the first and
/// the last, each as the step size, the contraction and the size of the first update (in the
/// iteration's weighted norm). For a smooth model with its exact iteration matrix the matrix
/// describes the equations of the step better as the step shrinks (the contraction falls
/// with `h`); a contraction that stays near 1 over decades of the step, with first updates
/// that do not grow as the step falls, says that it does not describe them at any step size
/// (`RadauError::StalledNewton`, `BdfError::StalledNewton`). First updates that grow as the
/// step falls say something else: the point reached misses an equation that the unknowns
/// must meet within the step (on Jay's index-2 problem a step accepted off the constraint
/// made `z` jump by the defect over `h`, and Newton then diverged from that jump).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct NewtonStall {
    first: Option<StalledAttempt>,
    last: Option<StalledAttempt>,
}

/// One failed attempt of [`NewtonStall`].
#[derive(Debug, Clone, Copy)]
struct StalledAttempt {
    h: f64,
    theta: f64,
    first_update: f64,
}

/// How far the step must have fallen between the first and the last failure of a stalled
/// iteration ([`NewtonStall::stalled`]).
const STALL_STEP_RANGE: f64 = 1e3;

/// The least contraction of the last failure of a stalled iteration ([`NewtonStall::stalled`]).
const STALL_THETA: f64 = 0.5;

/// How much the first update may grow from the first to the last failure of a stalled
/// iteration ([`NewtonStall::stalled`]): a decade, while the step falls by three or more.
const STALL_UPDATE_GROWTH: f64 = 10.0;

impl NewtonStall {
    /// Record a failed attempt at step `h` with last contraction `theta` (not recorded when 0:
    /// none was measured) and first update `first_update`.
    pub(crate) fn record(&mut self, h: f64, theta: f64, first_update: f64) {
        if theta > 0.0 && first_update.is_finite() {
            let a = StalledAttempt {
                h,
                theta,
                first_update,
            };
            self.first.get_or_insert(a);
            self.last = Some(a);
        }
    }

    /// `(h_first, h_last, theta_last)` when the step fell by at least [`STALL_STEP_RANGE`]
    /// between the first and the last failure that measured a contraction, the last
    /// contraction is still at least [`STALL_THETA`], and the first update grew by at most
    /// [`STALL_UPDATE_GROWTH`].
    fn stalled(&self) -> Option<(f64, f64, f64)> {
        let (h_first, h_last) = self.fell()?;
        let (a, b) = (self.first?, self.last?);
        (b.theta >= STALL_THETA && b.first_update <= STALL_UPDATE_GROWTH * a.first_update)
            .then_some((h_first, h_last, b.theta))
    }

    /// `(h_first, h_last)` when the step fell by at least [`STALL_STEP_RANGE`] between the
    /// first and the last failure that measured a contraction: Newton failed over decades of
    /// the step, which a point reached off a constraint the unknowns must meet within the step
    /// causes too (`BdfError::OffConstraint`, `RadauError::OffConstraint`).
    fn fell(&self) -> Option<(f64, f64)> {
        let (a, b) = (self.first?, self.last?);
        (b.h * STALL_STEP_RANGE <= a.h).then_some((a.h, b.h))
    }

    /// The cause of a Newton failure of `dae` whose step failed at `(t, y, y')` with the
    /// tolerances `rtol`, `atol`, when the failures this record holds span decades of the step
    /// ([`NewtonStall::fell`]): a point off a constraint (`start_near_tolerance` of the
    /// stabilised form's structure, read at the point), checked first, or a stalled iteration.
    /// For the integrators' error paths (it reads the DAE's structure there).
    pub(crate) fn diagnose<D: crate::ImplicitDae>(
        &self,
        dae: &D,
        (t, y, yp): (f64, &[f64], &[f64]),
        rtol: &crate::bdf::Tolerance,
        atol: &crate::bdf::Tolerance,
    ) -> Option<NewtonDiagnosis> {
        let (h_first, h_last) = self.fell()?;
        let point = crate::index_estimate::StartPoint::new(t, y, yp);
        if let Some(violation) = crate::stabilised::start_near_tolerance(dae, &point, rtol, atol) {
            return Some(NewtonDiagnosis::OffConstraint {
                violation,
                h_first,
                h_last,
            });
        }
        let (h_first, h_last, theta) = self.stalled()?;
        Some(NewtonDiagnosis::Stalled(h_first, h_last, theta))
    }
}

/// What [`NewtonStall::diagnose`] finds for an integrator's Newton failure.
pub(crate) enum NewtonDiagnosis {
    /// The point reached meets a constraint only to a tenth or more of what its tolerances
    /// allow it, after Newton failed from `h_first` down to `h_last`.
    OffConstraint {
        violation: crate::stabilised::ConstraintViolation,
        h_first: f64,
        h_last: f64,
    },
    /// [`NewtonStall::stalled`]: `(h_first, h_last, theta)`.
    Stalled(f64, f64, f64),
}

/// Why a Newton solve stopped without a solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum NewtonFailure {
    /// Slow or diverging iteration, or no convergence within the iteration limit.
    Convergence,
    /// Singular iteration matrix (pivot column, zero row).
    Singular(Option<usize>, Option<usize>),
    /// Non-finite residual in this equation.
    NonFinite(usize),
    /// Non-finite iteration-matrix entry (row, column).
    NonFiniteMatrix(usize, usize),
    /// Matrix entry outside the declared pattern (row, column): not recoverable.
    OutsidePattern(usize, usize),
    /// A convergence weight `1 / (rtol |v| + atol)` of this component is not positive and
    /// finite (its denominator is `value`).
    Weight {
        /// The component.
        component: usize,
        /// The denominator `rtol |v| + atol`.
        value: f64,
    },
}

impl NewtonFailure {
    /// The linear solver's report of a failed factorisation.
    fn from_factor(e: FactorError) -> Self {
        match e {
            FactorError::Singular { column, row } => Self::Singular(column, row),
            FactorError::NonFinite { row, col } => Self::NonFiniteMatrix(row, col),
            FactorError::OutsidePattern { row, col } => Self::OutsidePattern(row, col),
        }
    }
}

/// The nonlinear system `G(v) = 0` Newton solves. The iterate `v` lives in the implementor.
pub(crate) trait NewtonSystem<M: ?Sized> {
    /// Evaluate at the current iterate the residual into `res` (when `residual`; `res` then
    /// holds the residual at this iterate already, which a system that evaluates residual and
    /// matrix in one pass may overwrite with the same values) and the iteration matrix
    /// `dG/dv` into `matrix` (when given).
    fn evaluate(&mut self, res: &mut [f64], residual: bool, matrix: Option<&mut M>);

    /// Remember the current iterate (called before each correction).
    fn keep(&mut self) {}

    /// Go back to the iterate last remembered.
    fn back(&mut self) {}

    /// Correct the iterate by the Newton update `delta` (the solution of `G' delta = G`: the
    /// iterate moves by `-delta`). The system may rescale `delta` in place (the convergence
    /// test sees the rescaled update) or damp the step, in which case it evaluates the
    /// residual at the corrected iterate into `res` and says so.
    ///
    /// # Errors
    /// A failure the correction detects (a damped step's non-finite residual).
    fn correct(&mut self, delta: &mut [f64], res: &mut [f64]) -> Result<Corrected, NewtonFailure>;
}

/// What a correction did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Corrected {
    /// The fraction of the Newton update taken (1 for a full step).
    pub lambda: f64,
    /// `res` holds the residual at the corrected iterate.
    pub residual_current: bool,
}

impl Corrected {
    /// A full step after which the residual is not known.
    pub const FULL: Self = Self {
        lambda: 1.0,
        residual_current: false,
    };
}

/// What a convergence test decides.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Verdict {
    /// The current iterate is the solution.
    Converged,
    /// Go on with the matrix as it is.
    Continue,
    /// Form a fresh matrix before the next solve. After a residual test: at once, at the
    /// iterate before the last correction when `back`, at the current one otherwise (the
    /// residual is evaluated again there). After an update test: at the next iterate.
    Refresh {
        /// Go back to the iterate before the last correction.
        back: bool,
    },
    /// Stop without a solution.
    Fail(NewtonFailure),
}

/// What a convergence test sees after an evaluation or a correction.
pub(crate) struct Iterate<'a, L> {
    /// The linear solver, with the factorisation in use.
    pub ls: &'a L,
    /// The residual at the current iterate (after a correction: only if the correction
    /// evaluated it).
    pub res: &'a [f64],
    /// After a correction: the update taken (before the correction's damping `lambda`).
    /// After an evaluation: scratch the test may overwrite.
    pub delta: &'a mut [f64],
    /// The weights of the update norm.
    pub w: &'a mut [f64],
    /// The matrix in use was formed in this pass (at the iterate the last evaluation saw).
    pub fresh: bool,
    /// Solves (Newton updates) so far in this solve.
    pub solves: usize,
    /// After a correction: what it did.
    pub corrected: Corrected,
}

/// A convergence test for a [`NewtonSystem`] `S` solved with the linear solver `L`: it decides
/// after every residual evaluation and every correction whether to stop, go on or refresh the
/// matrix, and it enforces its own iteration limit.
pub(crate) trait Convergence<S, L> {
    /// Screen a residual just evaluated before the matrix formed with it is factorised (for
    /// example for non-finite entries).
    ///
    /// # Errors
    /// The failure that ends the solve.
    fn screen(&mut self, _sys: &mut S, _res: &[f64]) -> Result<(), NewtonFailure> {
        Ok(())
    }

    /// After the residual at the current iterate is known (at the start of every pass).
    fn after_residual(&mut self, sys: &mut S, it: Iterate<'_, L>) -> Verdict;

    /// After the matrix was refreshed on the test's request (the residual was evaluated again
    /// with it): [`Verdict::Fail`] stops, anything else goes on to the solve.
    fn after_refresh(&mut self, _sys: &mut S, _it: Iterate<'_, L>) -> Verdict {
        Verdict::Continue
    }

    /// After a correction.
    fn after_update(&mut self, sys: &mut S, it: Iterate<'_, L>) -> Verdict;
}

/// Work counters of the Newton solves in a workspace (cumulative; the caller resets them).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct NewtonCounts {
    /// Residual evaluations by the iteration (not those a damped correction makes).
    pub residuals: usize,
    /// Iteration matrices formed (each factorised once).
    pub matrices: usize,
    /// Linear solves (Newton updates).
    pub solves: usize,
}

/// The work vectors of Newton, allocated once, and the state of the factorisation in the
/// linear solver they are used with.
#[derive(Debug, Clone)]
pub(crate) struct NewtonWorkspace {
    /// The linear solver holds a valid factorisation from this workspace's solves.
    pub valid: bool,
    /// A matrix was formed during the last solve.
    pub formed: bool,
    /// The residual.
    pub res: Vec<f64>,
    /// The Newton update (scratch for the caller between solves).
    pub delta: Vec<f64>,
    /// Weights of the update norm (set by the caller or by the test).
    pub w: Vec<f64>,
    /// Work done.
    pub counts: NewtonCounts,
}

impl NewtonWorkspace {
    /// Work vectors of dimension `n` (no factorisation yet).
    pub fn new(n: usize) -> Self {
        Self {
            valid: false,
            formed: false,
            res: vec![0.0; n],
            delta: vec![0.0; n],
            w: vec![0.0; n],
            counts: NewtonCounts::default(),
        }
    }

    /// Solve `sys` from its current iterate under `test` with the linear solver `ls` (always
    /// the same one for a workspace), with a fresh matrix at the start when `fresh` (or when
    /// `ls` holds no valid factorisation). Returns the number of solves (Newton updates).
    ///
    /// # Errors
    /// The failure the test or the factorisation reports; the iterate is then wherever the
    /// iteration stopped.
    pub fn solve<L, S, C>(
        &mut self,
        ls: &mut L,
        sys: &mut S,
        test: &mut C,
        fresh: bool,
    ) -> Result<usize, NewtonFailure>
    where
        L: LinearSolver,
        S: NewtonSystem<L::Matrix>,
        C: Convergence<S, L>,
    {
        self.formed = false;
        let mut need_matrix = fresh || !self.valid;
        let mut residual_current = false;
        let mut solves = 0;

        sys.keep();
        loop {
            if need_matrix || !residual_current {
                self.evaluate(ls, sys, test, !residual_current, need_matrix)?;
            }
            let fresh_now = need_matrix;
            need_matrix = false;
            let verdict =
                test.after_residual(sys, self.view(ls, fresh_now, solves, Corrected::FULL));
            let mut fresh_now = fresh_now;
            match verdict {
                Verdict::Converged => return Ok(solves),
                Verdict::Continue => {}
                Verdict::Fail(f) => return Err(f),
                Verdict::Refresh { back } => {
                    if back {
                        sys.back();
                    }
                    self.evaluate(ls, sys, test, true, true)?;
                    fresh_now = true;
                    let verdict =
                        test.after_refresh(sys, self.view(ls, true, solves, Corrected::FULL));
                    if let Verdict::Fail(f) = verdict {
                        return Err(f);
                    }
                }
            }
            sys.keep();
            self.delta.copy_from_slice(&self.res);
            ls.solve_in_place(&mut self.delta);
            solves += 1;
            self.counts.solves += 1;
            let corrected = sys.correct(&mut self.delta, &mut self.res)?;
            residual_current = corrected.residual_current;
            let verdict = test.after_update(sys, self.view(ls, fresh_now, solves, corrected));
            match verdict {
                Verdict::Converged => return Ok(solves),
                Verdict::Continue => {}
                Verdict::Refresh { .. } => need_matrix = true,
                Verdict::Fail(f) => return Err(f),
            }
        }
    }

    /// What a convergence test sees of this workspace and the solver `ls`.
    fn view<'a, L>(
        &'a mut self,
        ls: &'a L,
        fresh: bool,
        solves: usize,
        corrected: Corrected,
    ) -> Iterate<'a, L> {
        Iterate {
            ls,
            res: &self.res,
            delta: &mut self.delta,
            w: &mut self.w,
            fresh,
            solves,
            corrected,
        }
    }

    /// Evaluate the residual (when `residual`) and the matrix (when `matrix`), screen the
    /// residual, factorise the matrix.
    fn evaluate<L, S, C>(
        &mut self,
        ls: &mut L,
        sys: &mut S,
        test: &mut C,
        residual: bool,
        matrix: bool,
    ) -> Result<(), NewtonFailure>
    where
        L: LinearSolver,
        S: NewtonSystem<L::Matrix>,
        C: Convergence<S, L>,
    {
        if matrix {
            sys.evaluate(&mut self.res, residual, Some(ls.matrix_mut()));
            self.counts.matrices += 1;
            self.formed = true;
            self.valid = false;
        } else {
            sys.evaluate(&mut self.res, residual, None);
        }
        if residual {
            self.counts.residuals += 1;
            test.screen(sys, &self.res)?;
        }
        if matrix {
            ls.factor().map_err(NewtonFailure::from_factor)?;
            self.valid = true;
        }
        Ok(())
    }
}

/// Weighted RMS norm `sqrt(sum (v_i w_i)^2 / n)`.
#[inline]
pub(crate) fn wrms(v: &[f64], w: &[f64]) -> f64 {
    let n = v.len().max(1) as f64;
    let s: f64 = v.iter().zip(w).map(|(a, b)| (a * b) * (a * b)).sum();
    (s / n).sqrt()
}

/// First index of a non-finite entry.
#[inline]
pub(crate) fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}
