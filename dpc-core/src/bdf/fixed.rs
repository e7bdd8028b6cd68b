//! Fixed-step, fixed-order BDF ([`FixedBdf`]), the crate's one fixed-step integrator: the
//! DPC controller's inner integration runs on it (order 1, implicit Euler at the inner step).
//!
//! Constant-step BDF of order `q`: `F(t_{n+1}, y_{n+1}, (1/h) sum_j a_j y_{n+1-j}) = 0`
//! (Hairer & Wanner 1996, Section III.1, Table 1.2 of coefficients). Only past *values* of `y`
//! enter, never `y'`, so the integration may start from inconsistent values: the first step
//! (implicit Euler when no older values are given) projects onto the constraints. While fewer
//! than `q` past values are available the order ramps up (`1, 2, ..., q`), which limits the
//! global accuracy to that of the startup; supplying the history with
//! [`FixedBdf::with_history`], or starting from consistent values with
//! [`FixedBdf::with_consistent_start`], gives the full order.
//!
//! `y'` is formed from the values at every evaluation, `(a_0 y + sum_{j>=1} a_j y_{n+1-j}) / h`
//! (for implicit Euler exactly `(y - y_n) / h`), and the `k`-th step after a (re)start at `t_0`
//! reaches `t_0 + k h`. Each step's corrector is the crate's one Newton iteration
//! ([`crate::newton`]); what a caller may choose:
//!
//! * the **convergence test**: by default ([`FixedBdf::step`]) IDA's rate test on the updates
//!   plus a scaled-residual check ([`Options::residual_tolerance`]), retried once with a fresh
//!   matrix when it fails with a stale one; or the caller's [`CorrectorTest`]
//!   ([`FixedBdf::step_with`]), which sees every residual and update and decides when to stop
//!   and when to evaluate the matrix afresh;
//! * the **initial guess**: by default polynomial extrapolation through the past values; with
//!   [`FixedBdf::step_with`] whatever the caller writes (for example a previous solution
//!   shifted);
//! * the **DAE's evaluation**: any [`ImplicitDae`], or a [`FixedStepDae`] of the caller's that
//!   may keep work space and data of the step (inputs evaluated once per step) and write its
//!   matrix without the integrator zeroing it first.
//!
//! The iteration matrix `dF/dy + (a_0/h) dF/dy'` is always formed together with the residual
//! ([`FixedStepDae::eval_residual_and_matrix`]) and kept, factorised, across steps and across
//! [`FixedBdf::restart`] while the step size and order are those it was formed for;
//! [`FixedBdf::set_step`] changes the step size and [`FixedBdf::restart`] starts again from new,
//! possibly inconsistent, values without allocating.

use super::newton::{error_weights, retry_with_fresh_matrix, JacState, RateTest};
use super::{BdfError, Options, Stats, Tolerance};
use crate::error::InvalidOption;
use crate::linear_solver::LinearSolver;
use crate::newton::{
    Convergence, Corrected, Iterate, NewtonFailure, NewtonSystem, NewtonWorkspace, Verdict,
};
use crate::{ImplicitDae, MatrixSink};

/// Coefficients `a_0..a_q` of constant-step BDF of order `q` (`a_0` multiplies `y_{n+1}`).
static COEFFS: [[f64; 6]; 5] = [
    [1.0, -1.0, 0.0, 0.0, 0.0, 0.0],
    [1.5, -2.0, 0.5, 0.0, 0.0, 0.0],
    [11.0 / 6.0, -3.0, 1.5, -1.0 / 3.0, 0.0, 0.0],
    [25.0 / 12.0, -4.0, 3.0, -4.0 / 3.0, 0.25, 0.0],
    [137.0 / 60.0, -5.0, 5.0, -10.0 / 3.0, 1.25, -0.2],
];

/// The DAE `F(t, y, y') = 0` as [`FixedBdf`] evaluates it.
///
/// Every [`ImplicitDae`] is one. A type of its own serves a DAE whose evaluation needs
/// `&mut self`: work space of its own, or data the caller sets once per step through
/// [`FixedBdf::dae_mut`] (the DPC controller's tracking DAE, with its tracking inputs and
/// nominal motion evaluated once per inner step and its unknowns `[X; Z; U]`).
pub trait FixedStepDae {
    /// Number of unknowns, equal to the number of equations.
    fn size(&self) -> usize;

    /// Evaluate `F(t, y, y')` into `out`.
    fn eval_residual(&mut self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]);

    /// Evaluate the residual into `residual` and the iteration matrix `dF/dy + c dF/dy'` into
    /// `matrix` in one pass. The matrix is zeroed before every call unless
    /// [`overwrites_matrix`](Self::overwrites_matrix) says otherwise.
    fn eval_residual_and_matrix<S: MatrixSink + ?Sized>(
        &mut self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: &mut [f64],
        matrix: &mut S,
    );

    /// Whether every call of [`eval_residual_and_matrix`](Self::eval_residual_and_matrix)
    /// writes every entry it ever writes (as the generated models do, zeros included), so the
    /// matrix is zeroed once, when the integrator is built, instead of before every call.
    /// `false` by default, as [`ImplicitDae`] asks.
    fn overwrites_matrix(&self) -> bool {
        false
    }

    /// How many leading unknowns have their derivative read by the DAE (the differential
    /// unknowns, for example the states of `[X; Z; U]`): `y'` is formed only for these, and
    /// the later entries of the `y'` the DAE is given are left as they are. All unknowns by
    /// default.
    fn differential_unknowns(&self) -> usize {
        self.size()
    }

    /// A name for unknown `i`, for error messages.
    fn name_of_unknown(&self, i: usize) -> String {
        format!("y[{i}]")
    }

    /// A name for equation `i`, for error messages.
    fn name_of_equation(&self, i: usize) -> String {
        format!("equation {i}")
    }
}

impl<D: ImplicitDae> FixedStepDae for D {
    fn size(&self) -> usize {
        self.dimension()
    }
    #[inline]
    fn eval_residual(&mut self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.residual(t, y, yp, out);
    }
    #[inline]
    fn eval_residual_and_matrix<S: MatrixSink + ?Sized>(
        &mut self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: &mut [f64],
        matrix: &mut S,
    ) {
        self.residual_and_iteration_matrix(t, y, yp, c, residual, matrix);
    }
    fn name_of_unknown(&self, i: usize) -> String {
        self.unknown_name(i)
    }
    fn name_of_equation(&self, i: usize) -> String {
        self.equation_name(i)
    }
}

/// What a [`CorrectorTest`] decides.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CorrectorVerdict {
    /// The current iterate is the step's solution.
    Converged,
    /// Go on with the factorised matrix as it is.
    Continue,
    /// Evaluate the iteration matrix afresh, with the residual. After a residual: at once, at
    /// the iterate before the last correction when `back`, at the current one otherwise. After
    /// an update: at the next iterate.
    Refresh {
        /// Go back to the iterate before the last correction.
        back: bool,
    },
    /// Give up: the step fails with [`BdfError::NewtonFailed`].
    Fail,
}

/// A caller's convergence test for the corrector of [`FixedBdf::step_with`], in place of the
/// default rate test. It sees the step's Newton iteration after every residual evaluation and
/// every correction, decides when it has converged and when the factorised matrix is to be
/// evaluated afresh, and enforces its own iteration limit.
pub trait CorrectorTest {
    /// After the residual `residual` at the iterate `y` is known (at the start of every pass);
    /// `fresh` when the matrix in use was formed in this pass.
    fn after_residual(&mut self, y: &[f64], residual: &[f64], fresh: bool) -> CorrectorVerdict;

    /// After the refresh this test asked for from [`after_residual`](Self::after_residual)
    /// (the matrix and the residual evaluated at `y`): [`CorrectorVerdict::Fail`] stops,
    /// anything else goes on to the solve.
    fn after_refresh(&mut self, y: &[f64], residual: &[f64]) -> CorrectorVerdict {
        let _ = (y, residual);
        CorrectorVerdict::Continue
    }

    /// After the correction `y -= update`, the `solves`-th of the step.
    fn after_update(&mut self, y: &[f64], update: &[f64], solves: usize) -> CorrectorVerdict;
}

/// The last `columns` values, newest first, in a ring: a step moves an index, not the data.
#[derive(Debug, Clone)]
struct Ring {
    n: usize,
    columns: usize,
    /// The column holding the newest value.
    front: usize,
    data: Vec<f64>,
}

impl Ring {
    fn new(columns: usize, n: usize) -> Self {
        Self {
            n,
            columns,
            front: 0,
            data: vec![0.0; columns * n],
        }
    }

    /// The storage column of the `j`-th newest value (`j < columns`).
    #[inline]
    fn index(&self, j: usize) -> usize {
        let k = self.front + j;
        if k >= self.columns {
            k - self.columns
        } else {
            k
        }
    }

    /// The `j`-th newest value.
    #[inline]
    fn col(&self, j: usize) -> &[f64] {
        let k = self.index(j);
        &self.data[k * self.n..(k + 1) * self.n]
    }

    #[inline]
    fn col_mut(&mut self, j: usize) -> &mut [f64] {
        let k = self.index(j);
        &mut self.data[k * self.n..(k + 1) * self.n]
    }

    /// The column behind the oldest one (the next step's iterate, which
    /// [`push_front`](Self::push_front) makes the newest value) and the newest value.
    #[inline(always)]
    fn next_and_newest(&mut self) -> (&mut [f64], &[f64]) {
        let n = self.n;
        let newest = self.front;
        let next = if newest == 0 {
            self.columns - 1
        } else {
            newest - 1
        };
        if next < newest {
            let (a, b) = self.data.split_at_mut(newest * n);
            (&mut a[next * n..(next + 1) * n], &b[..n])
        } else {
            let (a, b) = self.data.split_at_mut(next * n);
            (&mut b[..n], &a[newest * n..(newest + 1) * n])
        }
    }

    /// Make the column behind the oldest one (the next step's iterate) the newest value.
    #[inline]
    fn push_front(&mut self) {
        self.front = if self.front == 0 {
            self.columns - 1
        } else {
            self.front - 1
        };
    }
}

/// Fixed-step BDF integrator of a given order.
///
/// With [`step`](Self::step), Newton's iteration matrix is reused across steps and refreshed
/// only when Newton fails with it; a step is accepted only when Newton's update test passes
/// *and* the scaled residual passes [`Options::residual_tolerance`]. With
/// [`step_with`](Self::step_with) the caller's [`CorrectorTest`] decides both. A failed step
/// returns [`BdfError::NewtonFailed`] (or the singular-matrix / non-finite-residual error) and
/// the integrator stays at the previous point.
pub struct FixedBdf<D: FixedStepDae, L: LinearSolver> {
    dae: D,
    opts: Options,
    order: usize,
    h: f64,
    /// Time of the (re)start; the `k`-th step after it reaches `t0 + k h`.
    t0: f64,
    k: usize,
    /// The last `order + 1` values, newest first, and behind them the iterate of the step
    /// (which becomes the newest value when the step is accepted, without a copy).
    hist: Ring,
    /// Values available in `hist` (at most `order + 1`).
    navail: usize,
    ls: L,
    newton: NewtonWorkspace,
    /// `cj` of the factorised matrix and IDA's rate estimate.
    jac: JacState,
    /// The matrix is zeroed before every evaluation (the DAE does not overwrite it).
    zero_matrix: bool,
    /// The predictor of [`step`](Self::step) (the start of each attempt).
    y_pred: Vec<f64>,
    /// `sum_{j>=1} a_j y_{n+1-j}`: `y' = (a_0 y + base) / h` (above order 1; implicit Euler
    /// reads `y_n` itself).
    base: Vec<f64>,
    /// Number of leading unknowns whose `y'` is formed ([`FixedStepDae::differential_unknowns`]).
    nd: usize,
    /// The `y'` of the iterate.
    yp: Vec<f64>,
    /// The iterate before the last correction (for [`CorrectorVerdict::Refresh`] `back`).
    y_last: Vec<f64>,
    stats: Stats,
}

impl<D: FixedStepDae, L: LinearSolver> FixedBdf<D, L> {
    /// Start at `(t0, y0)`; `y0` may be inconsistent. The order ramps up from 1.
    ///
    /// # Errors
    /// [`BdfError::InvalidOption`] for an order outside `1..=5` or a non-positive step;
    /// dimension and tolerance errors as for [`super::Bdf::new`].
    pub fn new(
        dae: D,
        ls: L,
        opts: Options,
        order: usize,
        h: f64,
        t0: f64,
        y0: &[f64],
    ) -> Result<Self, BdfError> {
        Self::with_history(dae, ls, opts, order, h, t0, &[y0])
    }

    /// Start at `t0` with `history[j] = y(t0 - j h)` for `j = 0, 1, ...` (at least one entry,
    /// at most `order`); steps use order `min(order, available values)`.
    ///
    /// # Errors
    /// As for [`FixedBdf::new`], and [`BdfError::InvalidOption`] for an empty or too long
    /// history.
    pub fn with_history(
        dae: D,
        ls: L,
        opts: Options,
        order: usize,
        h: f64,
        t0: f64,
        history: &[&[f64]],
    ) -> Result<Self, BdfError> {
        let n = dae.size();
        if !(1..=5).contains(&order) {
            return Err(InvalidOption::new("order", order as f64, "between 1 and 5").into());
        }
        InvalidOption::positive("h", h)?;
        if !t0.is_finite() {
            return Err(InvalidOption::new("t0", t0, "finite").into());
        }
        if history.is_empty() || history.len() > order {
            return Err(InvalidOption::new(
                "history length",
                history.len() as f64,
                "between 1 and the order",
            )
            .into());
        }
        if ls.dimension() != n {
            return Err(BdfError::DimensionMismatch {
                what: "linear solver",
                expected: n,
                found: ls.dimension(),
            });
        }
        for v in history {
            if v.len() != n {
                return Err(BdfError::DimensionMismatch {
                    what: "y0",
                    expected: n,
                    found: v.len(),
                });
            }
        }
        opts.validate(n)?;
        let nd = dae.differential_unknowns().min(n);
        let mut hist = Ring::new(order + 2, n);
        for (j, src) in history.iter().enumerate() {
            hist.col_mut(j).copy_from_slice(src);
        }
        let mut ls = ls;
        let zero_matrix = !dae.overwrites_matrix();
        if !zero_matrix {
            ls.matrix_mut().fill_zero();
        }
        Ok(Self {
            dae,
            opts,
            order,
            h,
            t0,
            k: 0,
            navail: history.len(),
            hist,
            ls,
            newton: NewtonWorkspace::new(n),
            jac: JacState::default(),
            zero_matrix,
            y_pred: vec![0.0; n],
            base: vec![0.0; n],
            nd,
            yp: vec![0.0; n],
            y_last: vec![0.0; n],
            stats: Stats::default(),
        })
    }

    /// Restart at `(t0, y0)` (possibly inconsistent) without allocating: the order ramps up
    /// again and the iteration matrix is re-formed at the first step.
    ///
    /// # Errors
    /// [`BdfError::DimensionMismatch`] if `y0` has the wrong length.
    pub fn reset(&mut self, t0: f64, y0: &[f64]) -> Result<(), BdfError> {
        self.restart(t0, y0)?;
        self.yp.fill(0.0);
        self.refresh_matrix();
        Ok(())
    }

    /// Restart at `(t0, y0)` (possibly inconsistent) without allocating, as
    /// [`reset`](Self::reset) does, but keep the factorised iteration matrix: the first step
    /// uses it if it was formed for the same step size and order (the convergence test decides
    /// when it is evaluated afresh).
    ///
    /// # Errors
    /// [`BdfError::DimensionMismatch`] if `y0` has the wrong length.
    pub fn restart(&mut self, t0: f64, y0: &[f64]) -> Result<(), BdfError> {
        if y0.len() != self.hist.n {
            return Err(BdfError::DimensionMismatch {
                what: "y0",
                expected: self.hist.n,
                found: y0.len(),
            });
        }
        self.restart_with(t0, |y| y.copy_from_slice(y0));
        Ok(())
    }

    /// [`restart`](Self::restart) at `t0` from the value `init` writes (into storage that
    /// holds an older value), without an intermediate copy.
    #[inline]
    pub fn restart_with(&mut self, t0: f64, init: impl FnOnce(&mut [f64])) {
        self.t0 = t0;
        self.k = 0;
        init(self.hist.col_mut(0));
        self.navail = 1;
    }

    /// Take the following steps with size `h` from the current point: the values at the old
    /// spacing are dropped (the order ramps up again, as after a restart here), and a matrix
    /// formed for another step size is evaluated afresh at the next step.
    ///
    /// # Errors
    /// [`BdfError::InvalidOption`] for a step that is not positive and finite.
    pub fn set_step(&mut self, h: f64) -> Result<(), BdfError> {
        InvalidOption::positive("h", h)?;
        if h != self.h {
            self.t0 = self.t();
            self.k = 0;
            self.navail = 1;
            self.h = h;
        }
        Ok(())
    }

    /// Evaluate the iteration matrix afresh at the next step (after the DAE changed through
    /// [`dae_mut`](Self::dae_mut) in a way that invalidates it).
    pub fn refresh_matrix(&mut self) {
        self.jac = JacState::default();
        self.newton.valid = false;
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t0 + self.k as f64 * self.h
    }

    /// The time the next step reaches.
    pub fn next_t(&self) -> f64 {
        self.t0 + (self.k + 1) as f64 * self.h
    }

    /// The step size.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Solution at [`t`](Self::t).
    pub fn y(&self) -> &[f64] {
        self.hist.col(0)
    }

    /// The BDF derivative approximation at [`t`](Self::t) (zero before the first step; after
    /// a [`restart`](Self::restart), the last step's until the next); formed only for the
    /// [`FixedStepDae::differential_unknowns`], the later entries stay zero.
    pub fn yp(&self) -> &[f64] {
        &self.yp
    }

    /// Work counters so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The DAE being integrated.
    pub fn dae(&self) -> &D {
        &self.dae
    }

    /// The DAE being integrated, to set what it evaluates at the next step (for example
    /// inputs evaluated once per step at [`next_t`](Self::next_t)).
    pub fn dae_mut(&mut self) -> &mut D {
        &mut self.dae
    }

    /// The order of the next step and its coefficients; above order 1, `base` set from the
    /// past values (for the unknowns whose `y'` is formed).
    fn prepare(&mut self) -> (usize, &'static [f64; 6]) {
        let q = self.order.min(self.navail);
        let a = &COEFFS[q - 1];
        if q > 1 {
            let a1 = a[1];
            let base = &mut self.base[..self.nd];
            for (b, v) in base.iter_mut().zip(self.hist.col(0)) {
                *b = a1 * v;
            }
            for (j, aj) in a.iter().enumerate().take(q + 1).skip(2) {
                let base = &mut self.base[..self.nd];
                for (b, v) in base.iter_mut().zip(self.hist.col(j - 1)) {
                    *b += aj * v;
                }
            }
        }
        (q, a)
    }

    /// Take one step of size `h` from the extrapolated past values with the default
    /// convergence test; returns the new time. On error the state is unchanged.
    ///
    /// # Errors
    /// [`BdfError::NewtonFailed`], [`BdfError::SingularMatrix`],
    /// [`BdfError::NonFiniteResidual`], [`BdfError::InvalidTolerance`].
    pub fn step(&mut self) -> Result<f64, BdfError> {
        let (q, a) = self.prepare();
        let h = self.h;
        let t_new = self.next_t();
        let cj = a[0] / h;
        // Predictor: polynomial extrapolation through the available past values.
        let m = self.navail.min(q + 1);
        let mut binom = 1.0;
        for j in 0..m {
            // coefficient (-1)^j C(m, j+1)
            binom = binom * (m - j) as f64 / (j + 1) as f64;
            let c = if j % 2 == 0 { binom } else { -binom };
            let col = self.hist.col(j);
            if j == 0 {
                for (p, v) in self.y_pred.iter_mut().zip(col) {
                    *p = c * v;
                }
            } else {
                for (p, v) in self.y_pred.iter_mut().zip(col) {
                    *p += c * v;
                }
            }
        }
        error_weights(&self.opts, self.hist.col(0), &mut self.newton.w)?;
        let hs = h.min(1.0);
        for (i, w) in self.newton.w.iter_mut().enumerate() {
            let m = self.opts.index_of(i);
            if m > 1 {
                *w *= hs.powi(i32::from(m) - 1);
            }
        }
        self.jac.start_solve(cj);
        let mut fresh = cj != self.jac.cj_factored;
        let before = self.newton.counts;
        let outcome = loop {
            self.hist.next_and_newest().0.copy_from_slice(&self.y_pred);
            let mut test = RateTest::new(
                self.jac.ss,
                self.opts.newton_tolerance,
                self.opts.max_newton_iterations.max(4),
                self.opts.residual_tolerance,
            );
            let outcome = self.solve(t_new, q, a[0], fresh, false, &mut test);
            self.jac.ss = test.ss;
            if !retry_with_fresh_matrix(&outcome, fresh, self.newton.formed) {
                break outcome;
            }
            fresh = true;
        };
        self.finish(outcome, before, t_new)
    }

    /// Take one step of size `h` from the caller's initial guess under the caller's
    /// convergence test; returns the new time. `guess(y_n, y)` writes the guess into `y` from
    /// the current solution `y_n`. On error the state is unchanged.
    ///
    /// # Errors
    /// [`BdfError::NewtonFailed`] when `test` gives up, [`BdfError::SingularMatrix`] and
    /// [`BdfError::OutsidePattern`] when the matrix cannot be factorised.
    pub fn step_with<T: CorrectorTest>(
        &mut self,
        guess: impl FnOnce(&[f64], &mut [f64]),
        test: &mut T,
    ) -> Result<f64, BdfError> {
        let (q, a) = self.prepare();
        let t_new = self.next_t();
        let (y, y_n) = self.hist.next_and_newest();
        guess(y_n, y);
        let fresh = a[0] / self.h != self.jac.cj_factored;
        let before = self.newton.counts;
        let outcome = self.solve(t_new, q, a[0], fresh, true, &mut CallerTest(test));
        self.finish(outcome, before, t_new)
    }

    /// Newton on the step of order `q` from the iterate (the column behind the history).
    #[allow(clippy::too_many_arguments)]
    fn solve<C>(
        &mut self,
        t: f64,
        q: usize,
        a0: f64,
        fresh: bool,
        keep_last: bool,
        test: &mut C,
    ) -> Result<usize, NewtonFailure>
    where
        C: for<'a> Convergence<StepSystem<'a, D>, L>,
    {
        let nd = self.nd;
        let (y, y_n) = self.hist.next_and_newest();
        let mut system = StepSystem {
            dae: &mut self.dae,
            t,
            h: self.h,
            a0,
            euler: q == 1,
            base: if q == 1 { &y_n[..nd] } else { &self.base[..nd] },
            y,
            yp: &mut self.yp,
            y_last: &mut self.y_last,
            keep_last,
            has_last: false,
            zero_matrix: self.zero_matrix,
            cj_factored: &mut self.jac.cj_factored,
            yp_current: false,
        };
        let outcome = self.newton.solve(&mut self.ls, &mut system, test, fresh);
        if outcome.is_ok() && !system.yp_current {
            system.update_yp();
        }
        outcome
    }

    /// Count the work of the step's solves (from `before`) and accept the step or report why
    /// it failed.
    fn finish(
        &mut self,
        outcome: Result<usize, NewtonFailure>,
        before: crate::newton::NewtonCounts,
        t_new: f64,
    ) -> Result<f64, BdfError> {
        self.stats.add_newton(before, self.newton.counts);
        if let Err(f) = outcome {
            self.stats.newton_failures += 1;
            let dae = &self.dae;
            return Err(f.into_error_named(
                t_new,
                self.h,
                |i| dae.name_of_unknown(i),
                |i| dae.name_of_equation(i),
            ));
        }
        self.hist.push_front();
        self.navail = (self.navail + 1).min(self.order + 1);
        self.k += 1;
        self.stats.steps += 1;
        Ok(t_new)
    }
}

impl<D: ImplicitDae, L: LinearSolver> FixedBdf<D, L> {
    /// Start from *consistent* values `(t0, y0, yp0)` at the full order: the first
    /// `order - 1` points `t0 + j h` are computed by the variable-step [`super::Bdf`] with the
    /// tolerances of `opts` divided by 1000 (at least `1e-14`), so that the startup does not
    /// lower the convergence order. The integrator is then at `t0 + (order - 1) h`.
    ///
    /// # Errors
    /// As for [`FixedBdf::new`] and [`super::Bdf::new`], and any failure of the startup
    /// integration.
    #[allow(clippy::too_many_arguments)]
    pub fn with_consistent_start(
        dae: D,
        ls: L,
        opts: Options,
        order: usize,
        h: f64,
        t0: f64,
        y0: &[f64],
        yp0: &[f64],
    ) -> Result<Self, BdfError> {
        let mut f = Self::with_history(dae, ls, opts, order, h, t0, &[y0])?;
        if order == 1 {
            return Ok(f);
        }
        let n = y0.len();
        let tighten = |t: &Tolerance| match t {
            Tolerance::Scalar(v) => Tolerance::Scalar((v * 1e-3).max(1e-14)),
            Tolerance::Vector(v) => {
                Tolerance::Vector(v.iter().map(|x| (x * 1e-3).max(1e-14)).collect())
            }
        };
        let startup_opts = Options {
            rtol: tighten(&f.opts.rtol),
            atol: tighten(&f.opts.atol),
            ..f.opts.clone()
        };
        let mut bdf = super::Bdf::new(&f.dae, &mut f.ls, startup_opts, t0, y0, yp0)?;
        let mut points = vec![vec![0.0; n]; order];
        points[0].copy_from_slice(y0);
        for (j, p) in points.iter_mut().enumerate().skip(1) {
            bdf.set_stop_time(t0 + j as f64 * h)?;
            bdf.solve_to(t0 + j as f64 * h, p, None)?;
        }
        let startup = bdf.stats();
        drop(bdf);
        for (j, p) in points.iter().rev().enumerate() {
            f.hist.col_mut(j).copy_from_slice(p);
        }
        f.navail = order;
        f.k = order - 1;
        f.stats = startup;
        f.refresh_matrix();
        Ok(f)
    }
}

/// One step as the system Newton solves: the iterate `y` with
/// `y' = (a_0 y + base) / h` formed at every evaluation.
struct StepSystem<'a, D> {
    dae: &'a mut D,
    t: f64,
    h: f64,
    a0: f64,
    /// Implicit Euler: `base` is `y_n` and `y' = (y - y_n) / h`.
    euler: bool,
    /// `y_n` (implicit Euler) or `sum_{j>=1} a_j y_{n+1-j}`, for the unknowns whose `y'` is
    /// formed.
    base: &'a [f64],
    y: &'a mut [f64],
    yp: &'a mut [f64],
    y_last: &'a mut [f64],
    /// Remember the iterate before each correction (in the pass of the correction).
    keep_last: bool,
    /// `y_last` holds the iterate before the last correction (none yet: `y` is the first
    /// iterate, where going back stays).
    has_last: bool,
    zero_matrix: bool,
    /// `cj` of the factorised matrix (set when the system forms one).
    cj_factored: &'a mut f64,
    /// `yp` belongs to the current `y`.
    yp_current: bool,
}

impl<D> StepSystem<'_, D> {
    #[inline]
    fn update_yp(&mut self) {
        let (a0, h) = (self.a0, self.h);
        let values = self.yp.iter_mut().zip(self.y.iter()).zip(self.base);
        if self.euler {
            // Implicit Euler: `(y - y_n) / h`.
            for ((d, y), b) in values {
                *d = (y - b) / h;
            }
        } else {
            for ((d, y), b) in values {
                *d = (a0 * y + b) / h;
            }
        }
        self.yp_current = true;
    }
}

/// The fixed-step integrator evaluates every matrix it forms.
impl<D> super::newton::MatrixOrigin for StepSystem<'_, D> {
    fn last_matrix_moved(&self) -> bool {
        false
    }
}

impl<D: FixedStepDae, M: MatrixSink + ?Sized> NewtonSystem<M> for StepSystem<'_, D> {
    fn evaluate(&mut self, res: &mut [f64], _residual: bool, matrix: Option<&mut M>) {
        self.update_yp();
        match matrix {
            None => self.dae.eval_residual(self.t, self.y, self.yp, res),
            Some(m) => {
                if self.zero_matrix {
                    m.fill_zero();
                }
                let cj = self.a0 / self.h;
                self.dae
                    .eval_residual_and_matrix(self.t, self.y, self.yp, cj, res, m);
                *self.cj_factored = cj;
            }
        }
    }

    fn keep(&mut self) {
        // The iterate is remembered by `correct`, in the pass that changes it.
    }

    fn back(&mut self) {
        if self.has_last {
            self.y.copy_from_slice(self.y_last);
            self.yp_current = false;
        }
    }

    fn correct(&mut self, delta: &mut [f64], _res: &mut [f64]) -> Result<Corrected, NewtonFailure> {
        if self.keep_last {
            let values = self.y.iter_mut().zip(self.y_last.iter_mut());
            for ((y, last), d) in values.zip(delta.iter()) {
                *last = *y;
                *y -= d;
            }
            self.has_last = true;
        } else {
            for (y, d) in self.y.iter_mut().zip(delta.iter()) {
                *y -= d;
            }
        }
        self.yp_current = false;
        Ok(Corrected::FULL)
    }
}

/// A caller's [`CorrectorTest`] as the Newton iteration's convergence test.
struct CallerTest<'t, T>(&'t mut T);

impl CorrectorVerdict {
    fn verdict(self) -> Verdict {
        match self {
            Self::Converged => Verdict::Converged,
            Self::Continue => Verdict::Continue,
            Self::Refresh { back } => Verdict::Refresh { back },
            Self::Fail => Verdict::Fail(NewtonFailure::Convergence),
        }
    }
}

impl<D, L, T: CorrectorTest> Convergence<StepSystem<'_, D>, L> for CallerTest<'_, T> {
    #[inline]
    fn after_residual(&mut self, sys: &mut StepSystem<'_, D>, it: Iterate<'_, L>) -> Verdict {
        self.0.after_residual(sys.y, it.res, it.fresh).verdict()
    }

    #[inline]
    fn after_refresh(&mut self, sys: &mut StepSystem<'_, D>, it: Iterate<'_, L>) -> Verdict {
        self.0.after_refresh(sys.y, it.res).verdict()
    }

    #[inline]
    fn after_update(&mut self, sys: &mut StepSystem<'_, D>, it: Iterate<'_, L>) -> Verdict {
        self.0.after_update(sys.y, it.delta, it.solves).verdict()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear_solver::NalgebraLu;

    /// `y0' = -y0 + y1`, `0 = y1 - y0^2` (index 1).
    struct Quadratic;

    impl ImplicitDae for Quadratic {
        fn dimension(&self) -> usize {
            2
        }
        fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = yp[0] + y[0] - y[1];
            out[1] = y[1] - y[0] * y[0];
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _t: f64,
            y: &[f64],
            _yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            out.set(0, 0, 1.0 + c);
            out.set(0, 1, -1.0);
            out.set(1, 0, -2.0 * y[0]);
            out.set(1, 1, 1.0);
        }
    }

    /// Converged when the largest residual is below `tol`; counts what it saw.
    struct Small {
        tol: f64,
        residuals: usize,
        fresh: usize,
    }

    impl CorrectorTest for Small {
        fn after_residual(&mut self, _y: &[f64], res: &[f64], fresh: bool) -> CorrectorVerdict {
            self.residuals += 1;
            self.fresh += usize::from(fresh);
            if res.iter().all(|r| r.abs() <= self.tol) {
                CorrectorVerdict::Converged
            } else {
                CorrectorVerdict::Continue
            }
        }
        fn after_update(&mut self, _y: &[f64], _d: &[f64], solves: usize) -> CorrectorVerdict {
            if solves >= 10 {
                CorrectorVerdict::Fail
            } else {
                CorrectorVerdict::Continue
            }
        }
    }

    fn small() -> Small {
        Small {
            tol: 1e-13,
            residuals: 0,
            fresh: 0,
        }
    }

    fn integrator(h: f64) -> FixedBdf<Quadratic, NalgebraLu<2>> {
        FixedBdf::new(
            Quadratic,
            NalgebraLu::<2>::new(),
            Options::default(),
            1,
            h,
            0.5,
            &[0.5, 0.0],
        )
        .expect("valid")
    }

    #[test]
    fn implicit_euler_from_the_callers_guess_under_the_callers_test() {
        let h = 1e-2;
        let mut f = integrator(h);
        let mut test = small();
        let t = f
            .step_with(|y_n, y| y.copy_from_slice(y_n), &mut test)
            .expect("converges");
        assert_eq!(t, 0.5 + h);
        // The step's equations hold with y' = (y - y_n) / h exactly as written.
        let y = f.y();
        let yp0 = (y[0] - 0.5) / h;
        assert!((yp0 + y[0] - y[1]).abs() <= 1e-13, "{y:?}");
        assert!((y[1] - y[0] * y[0]).abs() <= 1e-13, "{y:?}");
        assert_eq!(f.yp()[0], yp0);
        assert_eq!(test.fresh, 1);
        assert_eq!(f.stats().steps, 1);
        assert_eq!(f.stats().jacobian_evaluations, 1);
    }

    #[test]
    fn the_matrix_is_kept_across_restarts_for_the_same_step() {
        let h = 1e-2;
        let mut f = integrator(h);
        let take = |f: &mut FixedBdf<Quadratic, NalgebraLu<2>>| {
            let mut test = small();
            f.step_with(|y_n, y| y.copy_from_slice(y_n), &mut test)
                .expect("converges");
            test.fresh
        };
        assert_eq!(take(&mut f), 1);
        assert_eq!(take(&mut f), 0);
        // A restart from a new (inconsistent) value keeps the matrix; the next time is
        // counted from the restart.
        f.restart(1.0, &[0.4, 7.0]).expect("length");
        assert_eq!(f.next_t(), 1.0 + h);
        assert_eq!(take(&mut f), 0);
        // A new step size forms it afresh, and so does a reset.
        f.set_step(2.0 * h).expect("positive");
        assert_eq!(take(&mut f), 1);
        f.reset(0.0, &[0.5, 0.0]).expect("length");
        assert_eq!(take(&mut f), 1);
        assert_eq!(f.stats().jacobian_evaluations, 3);
        assert_eq!(f.stats().steps, 5);
    }

    #[test]
    fn a_test_that_gives_up_leaves_the_state_unchanged() {
        let mut f = integrator(1e-2);
        let mut never = Small {
            tol: -1.0,
            residuals: 0,
            fresh: 0,
        };
        let err = f
            .step_with(|y_n, y| y.copy_from_slice(y_n), &mut never)
            .expect_err("never converges");
        assert!(matches!(err, BdfError::NewtonFailed { .. }), "{err}");
        assert_eq!(f.y(), &[0.5, 0.0]);
        assert_eq!(f.t(), 0.5);
        assert_eq!(f.stats().newton_failures, 1);
        assert_eq!(never.residuals, 10);
    }

    #[test]
    fn the_times_are_counted_from_the_start() {
        let mut f = integrator(0.1);
        for _ in 0..10 {
            f.step().expect("steps");
        }
        assert_eq!(f.t(), 0.5 + 10.0 * 0.1);
    }
}
