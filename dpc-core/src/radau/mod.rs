//! Radau IIA integration (three stages, order 5, variable step) of implicit DAEs
//! `F(t, y, y') = 0` of index up to 3, as declared.
//!
//! The algorithm is that of Hairer & Wanner's RADAU5 (*Solving Ordinary Differential
//! Equations II*, 2nd ed., Springer 1996, Section IV.8; index-dependent error scaling from
//! Hairer, Lubich & Roche, *The Numerical Solution of Differential-Algebraic Systems by
//! Runge-Kutta Methods*, LNM 1409, 1989), written for a general implicit `F` rather than
//! `M y' = f`:
//!
//! * `tableau`: coefficients, and the transformation `T` with `T^{-1} A^{-1} T` block diagonal
//!   (one real eigenvalue `gamma`, one complex pair `alpha ± i beta`), computed from the
//!   eigen-decomposition;
//! * `newton`: the collocation conditions `F(t_n + c_i h, y_n + Z_i, Y'_i) = 0` solved by
//!   simplified Newton, one real and one complex `n x n` system per iteration;
//! * `linear`: `dF/dy` and `dF/dy'` (from two calls of `iteration_matrix`), the real system in
//!   the caller's [`LinearSolver`], the complex one in a dense complex LU (faer), in a
//!   banded complex LU (`band`) when the caller's solver is banded ([`LinearSolver::band`]),
//!   or in faer's sparse LU over `c64` in the caller's pattern when it has one
//!   ([`LinearSolver::pattern`]), `dF/dy` and `dF/dy'` then stored in that pattern too;
//! * `estimate`: the embedded error estimate filtered through the real matrix, with the extra
//!   solve on the first step and after rejections;
//! * `control`: Gustafsson's predictive step-size controller; after a step's second
//!   error-test failure the rejection uses the exponent the estimate was seen to fall with,
//!   where it fell slower than `h^4` (a fast transient or a corner inside the step);
//! * `dense`: the collocation polynomial as dense output and as Newton's starting guess;
//! * the model is evaluated for a step's start at the right limit `t_n⁺`, the piece the step
//!   integrates (a step that starts at a stop time on a corner of the inputs);
//! * a diverging Newton iteration cuts the step to where its contraction would be a half
//!   (between a tenth and RADAU5's half);
//! * optionally ([`Options::newton_growth_bound`]), after an accepted step the next one grows
//!   at most to where Newton's own slow-convergence test would still pass, the contraction
//!   predicted to grow as `h^2` and the first update as `h^4` (on Andrews' index-3 form the
//!   error estimate proposed steps 2-7 times larger that failed that test about every other
//!   step);
//! * the Jacobian is kept while Newton contracts fast (rate at most
//!   [`Options::jacobian_reuse_rate`]); the step size, and with it the factorisations, is kept
//!   when the proposed change is small ([`Options::keep_step_window`]).
//!
//! Components marked as index 2 or 3 in [`Options::index`] have their error weights multiplied
//! by `min(1, h)` and `min(1, h)^2` (RADAU5's `NIND2`/`NIND3` with the cap at `h = 1` that the
//! BDF's [`crate::bdf::HigherIndexControl::Scale`] uses too): the local error of an index-`m`
//! component is `O(h^(4-m))` larger than that of the index-1 ones and would otherwise force
//! needlessly small steps or no convergence at all.
//!
//! ```
//! use dpc_core::linear_solver::NalgebraLu;
//! use dpc_core::radau::{Options, Radau};
//! use dpc_core::{ImplicitDae, MatrixSink};
//!
//! /// y' = -y.
//! struct Decay;
//! impl ImplicitDae for Decay {
//!     fn dimension(&self) -> usize { 1 }
//!     fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
//!         out[0] = yp[0] + y[0];
//!     }
//!     fn iteration_matrix<S: MatrixSink + ?Sized>(
//!         &self, _: f64, _: &[f64], _: &[f64], c: f64, m: &mut S,
//!     ) {
//!         m.set(0, 0, 1.0 + c);
//!     }
//! }
//!
//! let opts = Options::with_tolerances(1e-8, 1e-10);
//! let mut radau = Radau::new(Decay, NalgebraLu::<1>::new(), opts, 0.0, &[1.0], &[-1.0])?;
//! let mut y = [0.0];
//! radau.solve_to(2.0, &mut y, None)?;
//! assert!((y[0] - (-2.0f64).exp()).abs() < 1e-8);
//! # Ok::<(), dpc_core::radau::RadauError>(())
//! ```

mod band;
mod control;
mod dense;
mod error;
mod estimate;
mod linear;
mod newton;
mod options;
mod stats;
mod tableau;

use crate::error::InvalidOption;
pub use error::{RadauError, StageSystem, StepFailure};
pub use options::Options;
pub use stats::Stats;

use control::Controller;
use dense::Collocation;
use estimate::EstimateWork;
use linear::{NonFiniteEntry, SetupFailure, StageMatrices};
use newton::{NewtonOutcome, StageProblem, StageWork};
use tableau::Tableau;

use crate::linear_solver::LinearSolver;
use crate::ImplicitDae;

/// Factor on RADAU5's Newton tolerance when some component has index 2 or 3 (see
/// [`Options::newton_tolerance`]). Their weights in Newton's convergence test are relaxed by
/// `h^(m-1)` like those of the error test, so an iteration stopped at RADAU5's tolerance leaves
/// errors in the multipliers and accelerations that feed back into the positions: on Andrews'
/// squeezing mechanism (index 3) the positions' significant digits at `rtol = 1e-4 / 1e-6 /
/// 1e-8` go from 2.4 / 3.7 / 5.2 to 3.9 / 4.4 / 5.7 with this factor, for 10-20% more steps.
/// Since then the velocities of an index-3 form keep their unrelaxed weight in Newton's test
/// ([`Radau::update_weights`]); without this factor the mechanisms of `tests/mechanisms.rs`
/// still lose 0.6-2.4 digits.
const HIGHER_INDEX_NEWTON_FACTOR: f64 = 0.03;

/// Relative difference below which a step size counts as the one the stage matrices were
/// factorised for.
const SAME_STEP_TOLERANCE: f64 = 1e-12;

/// Weighted RMS norm `sqrt(sum (v_i w_i)^2 / n)`.
#[inline]
pub(crate) fn wrms(v: &[f64], w: &[f64]) -> f64 {
    let n = v.len().max(1) as f64;
    let s: f64 = v.iter().zip(w).map(|(a, b)| (a * b) * (a * b)).sum();
    (s / n).sqrt()
}

/// Radau IIA integrator (three stages, order 5, variable step) for `F(t, y, y') = 0`.
///
/// All work vectors and both factorisations' storage are allocated in [`Radau::new`]; steps
/// allocate nothing themselves (the linear solver decides for its own part; error paths build
/// names for the message). With [`NalgebraLu`](crate::linear_solver::NalgebraLu) or
/// [`FaerDenseLu`](crate::linear_solver::FaerDenseLu) no step, factorisation, solve or dense
/// output allocates, and with the sparse LU none once faer's factors have their largest fill
/// (a counting allocator in `tests/radau_and_sparse_alloc.rs`).
pub struct Radau<D: ImplicitDae, L: LinearSolver> {
    dae: D,
    opts: Options,
    n: usize,
    tab: Tableau,
    sm: StageMatrices<L>,
    /// Mapped tolerances (see [`Options`]).
    rtol: Vec<f64>,
    atol: Vec<f64>,
    fnewt: f64,
    /// Some component has index 2 or 3 (Newton's norm and tolerance depend on it).
    higher_index: bool,
    t: f64,
    y: Vec<f64>,
    yp: Vec<f64>,
    /// Step size of the next attempt (0 before the first step is chosen).
    h: f64,
    /// The first step after [`Radau::reinit`]: the step proposed after the last accepted one
    /// (0: none yet).
    restart_step: f64,
    /// The current integration started with [`restart_step`](Self::restart_step): a failed
    /// first step is then retried with the controller's step, not a tenth (RADAU5's rule
    /// for a guessed first step).
    carried_step: bool,
    tstop: Option<f64>,
    /// Polynomial of the last accepted step (valid when `stats.steps > steps_at_start`).
    poly: Collocation,
    steps_at_start: usize,
    /// RADAU5's `FACCON`, carried between steps.
    faccon: f64,
    /// Newton contraction of the last accepted step.
    theta: f64,
    /// The Newton failures of the step being attempted (for [`RadauError::StalledNewton`]).
    stall: crate::newton::NewtonStall,
    /// The Jacobian must be evaluated at the next step start.
    need_jacobian: bool,
    controller: Controller,
    // Work vectors.
    stages: StageWork,
    dz: [Vec<f64>; 3],
    est: EstimateWork,
    w: Vec<f64>,
    /// The weights of Newton's convergence test: those of the error test, except that only the
    /// components of the highest declared index are relaxed by `h^(m-1)` (see
    /// [`Radau::update_weights`]).
    w_newton: Vec<f64>,
    /// The highest declared index (1 when none is declared).
    top_index: u8,
    stats: Stats,
    /// Where the current integration started, for the diagnosis of a failure
    /// ([`Radau::with_index_diagnosis`]).
    start: crate::index_estimate::StartPoint,
}

impl<D: ImplicitDae, L: LinearSolver> Radau<D, L> {
    /// Set up the integrator at `(t0, y0, yp0)`, which should be consistent
    /// (`F(t0, y0, yp0) = 0`; see [`crate::bdf::consistent_initial_values`]). `yp0` enters only
    /// the first Jacobian and the first Newton guess, so an inexact derivative of the algebraic
    /// components (for example zero) costs iterations, not accuracy.
    ///
    /// # Errors
    /// [`RadauError::DimensionMismatch`] if `y0`, `yp0` or the solver do not match
    /// `dae.dimension()`; option errors from [`Options::validate`];
    /// [`RadauError::NonFiniteResidual`] if `F(t0, y0, yp0)` is not finite;
    /// [`RadauError::InconsistentConstraint`] if [`Options::index`] declares an unknown of
    /// index 2 or 3 and the initial values miss a constraint, or a position constraint's
    /// hidden velocity constraint, by more than the tolerances allow (the first step would
    /// jump onto it without an error).
    pub fn new(
        dae: D,
        ls: L,
        opts: Options,
        t0: f64,
        y0: &[f64],
        yp0: &[f64],
    ) -> Result<Self, RadauError> {
        let n = dae.dimension();
        for (what, found) in [
            ("y0", y0.len()),
            ("yp0", yp0.len()),
            ("linear solver", ls.dimension()),
        ] {
            if found != n {
                return Err(RadauError::DimensionMismatch {
                    what,
                    expected: n,
                    found,
                });
            }
        }
        opts.validate(n)?;
        if !t0.is_finite() {
            return Err(InvalidOption::new("t0", t0, "finite").into());
        }
        let mut res = vec![0.0; n];
        dae.residual(t0, y0, yp0, &mut res);
        if let Some(i) = res.iter().position(|v| !v.is_finite()) {
            return Err(RadauError::NonFiniteResidual {
                t: t0,
                equation: dae.equation_name(i),
            });
        }
        let (mut rtol, mut atol) = (vec![0.0; n], vec![0.0; n]);
        for i in 0..n {
            let (r, a) = (opts.rtol.get(i), opts.atol.get(i));
            let r2 = 0.1 * r.powf(2.0 / 3.0);
            rtol[i] = r2;
            // RADAU5 keeps atol/rtol fixed; a pure absolute tolerance maps like a relative one.
            atol[i] = if r > 0.0 {
                r2 * a / r
            } else {
                0.1 * a.powf(2.0 / 3.0)
            };
        }
        let tolst = rtol
            .iter()
            .copied()
            .filter(|r| *r > 0.0)
            .fold(f64::INFINITY, f64::min);
        let tolst = if tolst.is_finite() {
            tolst
        } else {
            atol.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let higher_index = (0..n).any(|i| opts.index_of(i) >= 2);
        if higher_index {
            let tolerance = |j: usize| opts.rtol.get(j) * y0[j].abs() + opts.atol.get(j);
            if let Some(v) = crate::stabilised::start_violation(&dae, t0, y0, yp0, tolerance) {
                return Err(RadauError::InconsistentConstraint {
                    t: t0,
                    equation: v.equation,
                    residual: v.residual,
                    bound: v.bound,
                });
            }
        }
        let fnewt = opts.newton_tolerance.unwrap_or_else(|| {
            let f = (10.0 * f64::EPSILON / tolst).max(0.03f64.min(tolst.sqrt()));
            if higher_index {
                HIGHER_INDEX_NEWTON_FACTOR * f
            } else {
                f
            }
        });
        let sm = StageMatrices::new(ls, n);
        let stats = Stats {
            residual_evaluations: 1,
            ..Stats::default()
        };
        let mut poly = Collocation::new(n);
        poly.t0 = t0;
        poly.y0.copy_from_slice(y0);
        let v = || [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        Ok(Self {
            dae,
            n,
            tab: Tableau::radau_iia_3(),
            sm,
            rtol,
            atol,
            fnewt,
            higher_index,
            t: t0,
            y: y0.to_vec(),
            yp: yp0.to_vec(),
            h: 0.0,
            restart_step: 0.0,
            carried_step: false,
            tstop: None,
            poly,
            steps_at_start: 0,
            faccon: 1.0,
            theta: 0.0,
            stall: crate::newton::NewtonStall::default(),
            need_jacobian: true,
            controller: Controller::default(),
            stages: StageWork::new(n),
            dz: v(),
            est: EstimateWork::new(n),
            w: vec![0.0; n],
            w_newton: vec![0.0; n],
            top_index: (0..n).map(|i| opts.index_of(i)).max().unwrap_or(1),
            stats,
            opts,
            start: crate::index_estimate::StartPoint::new(t0, y0, yp0),
        })
    }

    /// Restart from a new point `(t0, y0, yp0)` without allocating (for example after a jump of
    /// the model's inputs). Statistics keep accumulating; the stop time is cleared.
    ///
    /// The Jacobian and its factorisations are kept when the last step would have kept them
    /// for its successor (its Newton iteration contracted by at most
    /// [`Options::jacobian_reuse_rate`]): at the first step Newton's rate decides as at any
    /// other, and if Newton fails there with the kept Jacobian, the step is retried at the same
    /// size with a fresh one before it is reduced.
    ///
    /// Radau IIA is a one-step method: nothing of the old integration enters the new steps
    /// except the size of the first one (and the Jacobian, below). Unless
    /// [`Options::initial_step`] is set, that is the step the controller proposed after the
    /// last accepted step, cut to the stop time as any step is: a solution whose derivative
    /// jumps at `t0` but is as smooth as before on either side needs the steps it needed
    /// before. Should that step fail the error test, it is reduced by the controller's ratio
    /// (not to a tenth, RADAU5's rule for a guessed first step). Before any step the rule of
    /// [`Radau::new`] applies.
    ///
    /// `F(t0, y0, yp0)` is screened for non-finite values as in [`Radau::new`], except when
    /// `(t0, y0, yp0)` is the integrator's own last point ([`t`](Self::t), [`y`](Self::y),
    /// [`yp`](Self::yp) bit for bit), whose values come from an accepted step: there a
    /// non-finite residual (of inputs that changed) fails the first step instead.
    ///
    /// # Errors
    /// [`RadauError::DimensionMismatch`], [`RadauError::NonFiniteResidual`] or
    /// [`RadauError::InvalidOption`] as for [`Radau::new`]. The constraints are not checked
    /// here (the allocation-free restart of closed loops, which project their states
    /// themselves): a start given to `reinit` must satisfy them.
    pub fn reinit(&mut self, t0: f64, y0: &[f64], yp0: &[f64]) -> Result<(), RadauError> {
        for (what, found) in [("y0", y0.len()), ("yp0", yp0.len())] {
            if found != self.n {
                return Err(RadauError::DimensionMismatch {
                    what,
                    expected: self.n,
                    found,
                });
            }
        }
        if !t0.is_finite() {
            return Err(InvalidOption::new("t0", t0, "finite").into());
        }
        // The residual at the new point is screened unless the point is the integrator's own
        // last one (the same `t`, `y` and `y'` bit for bit, as a closed loop that integrates
        // on from where it stopped with new held inputs passes): its values come from an
        // accepted step, whose residuals were finite. A non-finite residual there (from inputs
        // that changed) fails the first step instead, with the same error after the step's
        // halvings.
        let own = t0 == self.t && y0 == self.y.as_slice() && yp0 == self.yp.as_slice();
        if !own {
            let f = &mut self.est.err;
            self.dae.residual(t0, y0, yp0, f);
            self.stats.residual_evaluations += 1;
            if let Some(i) = f.iter().position(|v| !v.is_finite()) {
                return Err(RadauError::NonFiniteResidual {
                    t: t0,
                    equation: self.dae.equation_name(i),
                });
            }
        }
        self.t = t0;
        self.y.copy_from_slice(y0);
        self.yp.copy_from_slice(yp0);
        self.poly.t0 = t0;
        self.poly.h = 0.0;
        self.poly.y0.copy_from_slice(y0);
        self.h = match self.opts.initial_step {
            Some(_) => 0.0,
            None => self.restart_step,
        };
        self.carried_step = self.h > 0.0;
        self.tstop = None;
        self.steps_at_start = self.stats.steps;
        self.start.set(t0, y0, yp0);
        self.faccon = 1.0;
        self.theta = 0.0;
        // The Jacobian (and with an unchanged step the factorisations) is kept when the last
        // step would have kept it: a restart on the same trajectory moves it little, and a
        // kept Jacobian that makes Newton fail is replaced at once (`step_internal`).
        self.sm.current = false;
        self.controller.reset();
        Ok(())
    }

    /// The DAE being integrated.
    pub fn dae(&self) -> &D {
        &self.dae
    }

    /// Work counters so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Time reached by the last accepted step.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Solution at [`t`](Self::t).
    pub fn y(&self) -> &[f64] {
        &self.y
    }

    /// Derivative at [`t`](Self::t) (the last stage derivative `Y'_3`, which satisfies
    /// `F(t, y, y') = 0`).
    pub fn yp(&self) -> &[f64] {
        &self.yp
    }

    /// Step size of the last accepted step (0 before the first).
    pub fn last_step(&self) -> f64 {
        if self.nst() == 0 {
            0.0
        } else {
            self.poly.h
        }
    }

    /// Step size the next step will try (0 before it is chosen).
    pub fn next_step(&self) -> f64 {
        self.h
    }

    /// Never step past `tstop` (for example a discontinuity of the model's inputs); the step
    /// that reaches it ends on it exactly.
    ///
    /// # Errors
    /// [`RadauError::TimeOutOfRange`] if `tstop` is not ahead of the current time.
    pub fn set_stop_time(&mut self, tstop: f64) -> Result<(), RadauError> {
        if !(tstop > self.t && tstop.is_finite()) {
            return Err(RadauError::TimeOutOfRange {
                t: tstop,
                from: self.t,
                to: f64::INFINITY,
            });
        }
        self.tstop = Some(tstop);
        Ok(())
    }

    /// Integrate to `tout` and write `y(tout)` (and `y'(tout)` if asked) from the collocation
    /// polynomial of the step that covers it. Returns the time the output refers to: `tout`, or
    /// the stop time when [`set_stop_time`](Self::set_stop_time) set one before `tout` (it is
    /// then cleared).
    ///
    /// # Errors
    /// Any step failure; [`RadauError::TooManySteps`] after [`Options::max_steps`] steps in this
    /// call; [`RadauError::TimeOutOfRange`] if `tout` lies before the last step.
    pub fn solve_to(
        &mut self,
        tout: f64,
        y_out: &mut [f64],
        yp_out: Option<&mut [f64]>,
    ) -> Result<f64, RadauError> {
        if y_out.len() != self.n {
            return Err(RadauError::DimensionMismatch {
                what: "y_out",
                expected: self.n,
                found: y_out.len(),
            });
        }
        let t_first = self.t - self.last_step();
        if !(tout.is_finite() && tout >= t_first) {
            return Err(RadauError::TimeOutOfRange {
                t: tout,
                from: t_first,
                to: f64::INFINITY,
            });
        }
        if self.h == 0.0 && tout > self.t {
            self.h = self.initial_step(tout);
        }
        let mut steps = 0;
        while self.t < tout {
            if let Some(ts) = self.tstop {
                if self.t >= ts {
                    self.tstop = None;
                    self.interpolate(ts, y_out, yp_out)?;
                    return Ok(ts);
                }
            }
            if steps >= self.opts.max_steps {
                return Err(self.with_index_diagnosis(RadauError::TooManySteps {
                    max_steps: self.opts.max_steps,
                    tout,
                    t: self.t,
                }));
            }
            self.step_internal()
                .map_err(|e| self.with_index_diagnosis(e))?;
            steps += 1;
        }
        if self.tstop.is_some_and(|ts| ts <= tout && ts <= self.t) {
            self.tstop = None;
        }
        self.interpolate(tout, y_out, yp_out)?;
        Ok(tout)
    }

    /// Take one step; returns the new time.
    ///
    /// # Errors
    /// [`RadauError::StepTooSmall`], [`RadauError::RepeatedFailures`],
    /// [`RadauError::SingularMatrix`], [`RadauError::NonFiniteResidual`] when a step cannot be
    /// completed; [`RadauError::NonFiniteMatrix`] at once when `dF/dy` or `dF/dy'` at the
    /// step's start has a non-finite entry; [`RadauError::InvalidTolerance`] when an error weight is not positive.
    pub fn step(&mut self) -> Result<f64, RadauError> {
        if self.h == 0.0 {
            let t = self.tstop.unwrap_or(self.t + 1.0);
            self.h = self.initial_step(t);
        }
        self.step_internal()
            .map_err(|e| self.with_index_diagnosis(e))?;
        Ok(self.t)
    }

    /// `e`, or, when it is a failure to step before the first step of an integration from
    /// initial values that do not satisfy an equation, `e` wrapped in
    /// [`RadauError::InconsistentStart`] ([`crate::index_estimate::inconsistent_start`]), or that
    /// meet a constraint only to a large share of what the tolerances allow, in
    /// [`RadauError::StartNearTolerance`];
    /// otherwise, when it is a failure to step of a DAE declared with every unknown of index
    /// at most 1 whose iteration matrix at the last point reached shows unknowns of index 2
    /// or 3, `e` wrapped in [`RadauError::UndeclaredIndex`] (the start of the integration
    /// reads them so too) or [`RadauError::SingularPoint`] (it read every unknown as of index
    /// 1): [`crate::index_estimate::diagnose_failure`]. Runs only on that error path.
    fn with_index_diagnosis(&self, e: RadauError) -> RadauError {
        use crate::index_estimate::{diagnose_failure, FailureDiagnosis};
        let stepping = matches!(
            e,
            RadauError::StepTooSmall { .. }
                | RadauError::RepeatedFailures { .. }
                | RadauError::TooManySteps { .. }
        );
        if !stepping {
            return e;
        }
        if self.nst() == 0 {
            if let Some(w) = crate::index_estimate::inconsistent_start(&self.dae, &self.start) {
                return RadauError::InconsistentStart {
                    t: self.start.t(),
                    equation: self.dae.equation_name(w.equation),
                    residual: w.residual,
                    bound: w.bound,
                    source: Box::new(e),
                };
            }
            let (rtol, atol) = (&self.opts.rtol, &self.opts.atol);
            if let Some(v) =
                crate::stabilised::start_near_tolerance(&self.dae, &self.start, rtol, atol)
            {
                return RadauError::StartNearTolerance {
                    t: self.start.t(),
                    equation: v.equation,
                    residual: v.residual,
                    bound: v.bound,
                    source: Box::new(e),
                };
            }
        }
        if self.higher_index {
            return self.with_newton_diagnosis(e);
        }
        let t = self.t;
        match diagnose_failure(&self.dae, &self.start, (t, self.y(), self.yp())) {
            FailureDiagnosis::None => self.with_newton_diagnosis(e),
            FailureDiagnosis::Undeclared(unknowns) => RadauError::UndeclaredIndex {
                t,
                unknowns,
                source: Box::new(e),
            },
            FailureDiagnosis::OnlyHere { t_start, unknowns } => RadauError::SingularPoint {
                t,
                t_start,
                unknowns,
                source: Box::new(e),
            },
        }
    }

    /// `e`, or, when it is a failure of Newton's iteration ([`RadauError::StepTooSmall`] or
    /// [`RadauError::RepeatedFailures`] with [`StepFailure::Newton`]) over decades of the step
    /// (`NewtonStall::fell` in `crate::newton`): at a point that meets a constraint only to a
    /// tenth or more of its tolerances, `e` wrapped in [`RadauError::OffConstraint`]; else,
    /// when its contraction did not fall as the step was cut (`NewtonStall::stalled`), in
    /// [`RadauError::StalledNewton`].
    fn with_newton_diagnosis(&self, e: RadauError) -> RadauError {
        let newton = matches!(
            e,
            RadauError::StepTooSmall {
                cause: StepFailure::Newton,
                ..
            } | RadauError::RepeatedFailures {
                cause: StepFailure::Newton,
                ..
            }
        );
        if !newton {
            return e;
        }
        use crate::newton::NewtonDiagnosis;
        let t = self.t;
        let (rtol, atol) = (&self.opts.rtol, &self.opts.atol);
        match self
            .stall
            .diagnose(&self.dae, (t, &self.y, &self.yp), rtol, atol)
        {
            Some(NewtonDiagnosis::OffConstraint {
                violation: v,
                h_first,
                h_last,
            }) => RadauError::OffConstraint {
                t,
                equation: v.equation,
                residual: v.residual,
                bound: v.bound,
                h_first,
                h_last,
                source: Box::new(e),
            },
            Some(NewtonDiagnosis::Stalled(h_first, h_last, theta)) => RadauError::StalledNewton {
                t,
                h_first,
                h_last,
                theta,
                source: Box::new(e),
            },
            None => e,
        }
    }

    /// Evaluate the collocation polynomial of the last step at `t` in `[t - h_last, t]` (the
    /// initial values before the first step; at the step's end, its values [`y`](Self::y) and
    /// [`yp`](Self::yp)).
    ///
    /// # Errors
    /// [`RadauError::TimeOutOfRange`] if `t` is outside the last step (with a round-off
    /// margin); [`RadauError::DimensionMismatch`] for wrong output lengths.
    pub fn interpolate(
        &self,
        t: f64,
        y_out: &mut [f64],
        yp_out: Option<&mut [f64]>,
    ) -> Result<(), RadauError> {
        for (what, len) in [
            ("y_out", Some(y_out.len())),
            ("yp_out", yp_out.as_ref().map(|v| v.len())),
        ] {
            if let Some(found) = len.filter(|&l| l != self.n) {
                return Err(RadauError::DimensionMismatch {
                    what,
                    expected: self.n,
                    found,
                });
            }
        }
        let hl = self.last_step();
        let margin = 100.0 * f64::EPSILON * (self.t.abs() + hl);
        if !(t.is_finite() && t <= self.t + margin && t >= self.t - hl - margin) {
            return Err(RadauError::TimeOutOfRange {
                t,
                from: self.t - hl,
                to: self.t,
            });
        }
        // At the end of the last step (an output on a stop time, as at every sample of a
        // closed loop) its values serve: the polynomial's `y` there is `y_n + Z_3` (bit for
        // bit when the step was cut to `t`), its `y'` the last stage derivative, each up to
        // round-off.
        if self.nst() == 0 || t == self.t {
            y_out.copy_from_slice(&self.y);
            if let Some(yp) = yp_out {
                yp.copy_from_slice(&self.yp);
            }
            return Ok(());
        }
        self.poly.eval(&self.tab.c, t, y_out, yp_out);
        Ok(())
    }

    /// Steps since the start of the current integration.
    fn nst(&self) -> usize {
        self.stats.steps - self.steps_at_start
    }

    fn hmin(&self) -> f64 {
        self.opts.min_step.max(4.0 * f64::EPSILON * self.t.abs())
    }

    /// `0.001 |tout - t|`, reduced so that `h |y'|` of the index-0/1 components is at most half
    /// a tolerance unit; the user's choice if given.
    fn initial_step(&self, tout: f64) -> f64 {
        let h = match self.opts.initial_step {
            Some(h) => h,
            None => {
                let d = (tout - self.t).abs();
                let mut h = if d > 0.0 {
                    1e-3 * d
                } else {
                    1e-6 * self.t.abs().max(1.0)
                };
                let mut s = 0.0;
                for i in 0..self.n {
                    if self.opts.index_of(i) <= 1 {
                        let v = self.yp[i]
                            / (self.opts.rtol.get(i) * self.y[i].abs() + self.opts.atol.get(i));
                        s += v * v;
                    }
                }
                let ypnorm = (s / self.n.max(1) as f64).sqrt();
                if ypnorm.is_finite() && ypnorm * h > 0.5 {
                    h = 0.5 / ypnorm;
                }
                h
            }
        };
        h.min(self.opts.max_step)
    }

    /// Error weights `min(1, h)^(m-1) / (rtol' |y_i| + atol'_i)` at the step start, and
    /// Newton's weights: the same for the components of the highest declared index, unrelaxed
    /// `1 / (rtol' |y_i| + atol'_i)` for the others.
    ///
    /// In a mechanism's index-3 form (`q' = v`, `M v' = f - G^T lambda`, `0 = g(q)`) the
    /// components of index 2 are the velocities: differential unknowns, whose error is a state
    /// error that the index-3 form never corrects (a velocity off along the constraint manifold
    /// stays off and moves the positions in proportion to time). Newton's error in them is the
    /// stage positions' error divided by `h`; relaxed by `h`, the test admitted velocity errors
    /// of `fnewt tol' / h`, largest in the first, smallest steps: on the rigid slider crank
    /// (`tests/mechanisms.rs`) the crank speed was off by 8e-6 after five steps at `rtol =
    /// 1e-8` (`h = 2e-5`) and the positions kept 3.2 / 3.4 / 4.0 digits at `1e-4 / 1e-6 /
    /// 1e-8`. Only the multipliers (the highest index), which the positions and velocities
    /// determine and which carry no error forward, keep the relaxed weight. The error test keeps
    /// the relaxation of every higher-index component (RADAU5's scaling of its embedded
    /// estimate; tightening it there is not what the measurements asked for).
    fn update_weights(&mut self, h: f64) -> Result<(), RadauError> {
        let hs = h.abs().min(1.0);
        for i in 0..self.n {
            let d = self.rtol[i] * self.y[i].abs() + self.atol[i];
            if !(d > 0.0 && d.is_finite()) {
                return Err(RadauError::InvalidTolerance {
                    which: "error weight",
                    component: i,
                    value: d,
                });
            }
            let m = self.opts.index_of(i);
            self.w[i] = hs.powi(i32::from(m) - 1) / d;
            self.w_newton[i] = if m == self.top_index {
                self.w[i]
            } else {
                1.0 / d
            };
        }
        Ok(())
    }

    /// Newton's starting guess: the last step's polynomial extrapolated to the new nodes, or
    /// `Z_i = c_i h y'_n` when there is none.
    fn predict(&mut self, h: f64) {
        let first = self.nst() == 0;
        let z = &mut self.stages.z;
        if first {
            for (i, zi) in z.iter_mut().enumerate() {
                let ci = self.tab.c[i] * h;
                for (a, b) in zi.iter_mut().zip(&self.yp) {
                    *a = ci * b;
                }
            }
            return;
        }
        for (i, zi) in z.iter_mut().enumerate() {
            let ti = self.t + self.tab.c[i] * h;
            self.poly.eval(&self.tab.c, ti, zi, None);
            for (a, b) in zi.iter_mut().zip(&self.y) {
                *a -= b;
            }
        }
    }

    fn setup_error(&self, f: SetupFailure, h: f64) -> RadauError {
        match f {
            SetupFailure::Singular(system, col, row) => RadauError::SingularMatrix {
                t: self.t,
                h,
                system,
                unknown: col.map(|c| self.dae.unknown_name(c)),
                equation: row.map(|r| self.dae.equation_name(r)),
            },
            SetupFailure::NonFinite(r, c) => RadauError::NonFiniteMatrix {
                t: self.t,
                equation: self.dae.equation_name(r),
                unknown: self.dae.unknown_name(c),
            },
            SetupFailure::OutsidePattern(r, c) => RadauError::OutsidePattern {
                equation: self.dae.equation_name(r),
                unknown: self.dae.unknown_name(c),
            },
        }
    }

    /// The time at which the model is evaluated for the step's start `t_n`: the right limit
    /// `t_n⁺` (the next float), as the step covers `(t_n, t_n + h]`. A model that is smooth in
    /// `t` cannot tell the two apart; one with a corner or jump at `t_n` (a pulse input, a
    /// stop time set at a discontinuity) is evaluated on the piece the step integrates, not
    /// on the one that ended there. The left piece there made the error estimate carry the
    /// jump (a term proportional to `h` that each rejection shrinks by at most the
    /// controller's ratio) and fail the step.
    fn start_limit(&self) -> f64 {
        self.t.next_up()
    }

    fn step_internal(&mut self) -> Result<(), RadauError> {
        let mut h = self.h;
        if let Some(ts) = self.tstop {
            // Stretch by up to 10% rather than leave a sliver before the stop time.
            if self.t + 1.1 * h >= ts {
                h = ts - self.t;
            }
        }
        let mut newton_failures = 0;
        let mut error_failures = 0;
        self.stall = crate::newton::NewtonStall::default();
        // The step size and error of the last error-test failure of this step.
        let mut last_failure: Option<(f64, f64)> = None;
        let mut rejected = false;
        loop {
            h = h.min(self.opts.max_step);
            if h < self.hmin() || h <= 0.0 {
                return Err(RadauError::StepTooSmall {
                    t: self.t,
                    h,
                    cause: if newton_failures > 0 && error_failures == 0 {
                        StepFailure::Newton
                    } else {
                        StepFailure::ErrorTest
                    },
                });
            }
            if self.need_jacobian && !self.sm.current {
                let formed = self
                    .sm
                    .evaluate(&self.dae, self.start_limit(), &self.y, &self.yp);
                self.stats.jacobian_evaluations += 1;
                // `J` and `M` at the step's start: a smaller step would factorise the same
                // non-finite entries again.
                if let Err(NonFiniteEntry { row, col }) = formed {
                    return Err(RadauError::NonFiniteMatrix {
                        t: self.t,
                        equation: self.dae.equation_name(row),
                        unknown: self.dae.unknown_name(col),
                    });
                }
            }
            self.update_weights(h)?;
            // A factorisation for a step within round-off of this one serves it (a step cut
            // to a stop time differs from the same step a sample earlier by a few ulps).
            let refactor = (self.sm.h_factored - h).abs() > SAME_STEP_TOLERANCE * h;
            if !self.sm.factored || refactor {
                self.stats.factorisations += 1;
                if let Err(f) = self
                    .sm
                    .factor(h, self.tab.gamma, self.tab.alpha, self.tab.beta)
                {
                    if let SetupFailure::OutsidePattern(..) = f {
                        return Err(self.setup_error(f, h));
                    }
                    self.stats.newton_failures += 1;
                    newton_failures += 1;
                    if newton_failures >= self.opts.max_newton_failures {
                        return Err(self.setup_error(f, h));
                    }
                    h *= 0.5;
                    rejected = true;
                    self.need_jacobian = true;
                    continue;
                }
            }
            self.predict(h);
            let problem = StageProblem {
                t: self.t,
                h,
                y: &self.y,
                w: &self.w_newton,
                max_iterations: self.opts.max_newton_iterations,
                fnewt: self.fnewt,
                transformed_norm: self.higher_index,
                min_carried: if self.higher_index {
                    crate::newton::MIN_CARRIED_RATE
                } else {
                    0.0
                },
            };
            let outcome = newton::solve(
                &self.dae,
                &mut self.sm,
                &self.tab,
                &mut self.stats,
                &problem,
                &mut self.stages,
                &mut self.dz,
                &mut self.faccon,
            );
            let (iterations, theta, first_increment) = match outcome {
                NewtonOutcome::Converged {
                    iterations,
                    theta,
                    first_increment,
                } => (iterations, theta, first_increment),
                NewtonOutcome::Failed {
                    factor,
                    theta,
                    first_increment,
                } => {
                    self.stats.newton_failures += 1;
                    newton_failures += 1;
                    self.stall.record(h, theta, first_increment);
                    if self.nst() == 0 && !self.sm.current && !rejected {
                        // The Jacobian kept across a restart does not fit the new point:
                        // the same step with a fresh one.
                        self.need_jacobian = true;
                        rejected = true;
                        continue;
                    }
                    if newton_failures >= self.opts.max_newton_failures {
                        return Err(RadauError::RepeatedFailures {
                            t: self.t,
                            h,
                            failures: newton_failures,
                            cause: StepFailure::Newton,
                        });
                    }
                    h *= factor;
                    rejected = true;
                    self.need_jacobian = true;
                    continue;
                }
                NewtonOutcome::NonFinite { equation, t } => {
                    self.stats.newton_failures += 1;
                    newton_failures += 1;
                    if newton_failures >= self.opts.max_newton_failures || h * 0.5 < self.hmin() {
                        return Err(RadauError::NonFiniteResidual {
                            t,
                            equation: self.dae.equation_name(equation),
                        });
                    }
                    h *= 0.5;
                    rejected = true;
                    self.need_jacobian = true;
                    continue;
                }
            };
            let refine = self.nst() == 0 || rejected;
            let t_start = self.start_limit();
            let err = match estimate::estimate(
                &self.dae,
                &mut self.sm,
                &self.tab,
                &mut self.stats,
                t_start,
                h,
                &self.y,
                &self.stages,
                &self.w,
                refine,
                &mut self.est,
            ) {
                Ok(e) => e,
                Err(estimate::NonFinite(equation)) => {
                    self.stats.newton_failures += 1;
                    newton_failures += 1;
                    if newton_failures >= self.opts.max_newton_failures || h * 0.5 < self.hmin() {
                        return Err(RadauError::NonFiniteResidual {
                            t: self.t,
                            equation: self.dae.equation_name(equation),
                        });
                    }
                    h *= 0.5;
                    rejected = true;
                    self.need_jacobian = true;
                    continue;
                }
            };
            if err < 1.0 {
                self.accept(h, err, (iterations, theta, first_increment), rejected);
                return Ok(());
            }
            self.stats.error_test_failures += 1;
            error_failures += 1;
            let h_failed = h;
            if error_failures >= self.opts.max_error_test_failures {
                return Err(RadauError::RepeatedFailures {
                    t: self.t,
                    h,
                    failures: error_failures,
                    cause: StepFailure::ErrorTest,
                });
            }
            h = if self.nst() == 0 && !self.carried_step {
                0.1 * h
            } else {
                h / Controller::rejection_quotient(&self.opts, err, iterations, last_failure, h)
            };
            last_failure = Some((h_failed, err));
            rejected = true;
            self.need_jacobian = true;
        }
    }

    /// Take the step of size `h` with error `err` whose Newton iteration ended with
    /// `(iterations, theta, first_increment)`, and choose the next step size.
    fn accept(
        &mut self,
        h: f64,
        err: f64,
        (iterations, theta, first_increment): (usize, f64, f64),
        rejected: bool,
    ) {
        self.stats.steps += 1;
        let t_new = match self.tstop {
            Some(ts) if (self.t + h - ts).abs() <= 4.0 * f64::EPSILON * ts.abs().max(h) => ts,
            _ => self.t + h,
        };
        self.poly.t0 = self.t;
        self.poly.h = h;
        self.poly.y0.copy_from_slice(&self.y);
        for (p, z) in self.poly.z.iter_mut().zip(&self.stages.z) {
            p.copy_from_slice(z);
        }
        for k in 0..self.n {
            self.y[k] += self.stages.z[2][k];
        }
        self.yp.copy_from_slice(&self.stages.yp[2]);
        self.t = t_new;
        self.theta = theta;

        let mut h_new = self.controller.accept(&self.opts, h, err, iterations);
        if rejected {
            h_new = h_new.min(h);
        }
        // Newton's contraction bounds the growth where it, not the error, limits the step.
        if self.opts.newton_growth_bound {
            if let Some(r) = Controller::newton_growth_limit(
                theta,
                first_increment,
                self.opts.max_newton_iterations,
                h_new / h,
            ) {
                h_new = h * r;
            }
        }
        h_new = h_new.min(self.opts.max_step);
        self.restart_step = h_new;
        let keep_jacobian = theta <= self.opts.jacobian_reuse_rate;
        let (q1, q2) = self.opts.keep_step_window;
        let ratio = h_new / h;
        if keep_jacobian && (q1..=q2).contains(&ratio) {
            h_new = h;
        }
        self.h = h_new;
        self.need_jacobian = !keep_jacobian;
        // The stored Jacobian belongs to the old step start from here on.
        self.sm.current = false;
    }
}

impl<D: ImplicitDae> Radau<crate::stabilised::Stabilised<D>, crate::linear_solver::FaerLu> {
    /// Radau IIA on the stabilised index-2 form of `dae` that
    /// [`Stabilised::detect`](crate::stabilised::Stabilised::detect) finds at the start: the
    /// documented default for a DAE of index 3 (docs/integrators.md measures both forms), in
    /// one call, with the linear solver [`FaerLu::for_dae`](crate::linear_solver::FaerLu::for_dae)
    /// picks for the stabilised form. [`Radau::new`] with the index declared in
    /// [`Options::index`] is the alternative that integrates the DAE as declared.
    ///
    /// `(y0, yp0)` are `dae`'s (consistent, with the velocities on their hidden constraints);
    /// `opts.index` is replaced by the stabilised form's
    /// ([`Stabilised::index`](crate::stabilised::Stabilised::index)), the other options are
    /// kept. The unknowns are `dae`'s followed by one stabilising multiplier `mu` per position
    /// constraint (zero on exact solutions): [`y`](Self::y), [`yp`](Self::yp) and the output of
    /// [`solve_to`](Self::solve_to) have that length, and their first `dae.dimension()`
    /// entries are `dae`'s unknowns.
    ///
    /// ```
    /// use dpc_core::radau::{Options, Radau};
    /// use dpc_core::{ImplicitDae, MatrixSink};
    ///
    /// /// The pendulum of length 1, index 3: x' = u, y' = v, u' = -x l, v' = -y l - 1,
    /// /// 0 = x^2 + y^2 - 1.
    /// struct Pendulum;
    /// impl ImplicitDae for Pendulum {
    ///     fn dimension(&self) -> usize { 5 }
    ///     fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
    ///         out[0] = yp[0] - y[2];
    ///         out[1] = yp[1] - y[3];
    ///         out[2] = yp[2] + y[0] * y[4];
    ///         out[3] = yp[3] + y[1] * y[4] + 1.0;
    ///         out[4] = y[0] * y[0] + y[1] * y[1] - 1.0;
    ///     }
    ///     fn iteration_matrix<S: MatrixSink + ?Sized>(
    ///         &self, _t: f64, y: &[f64], _yp: &[f64], c: f64, out: &mut S,
    ///     ) {
    ///         for i in 0..4 { out.set(i, i, c); }
    ///         out.set(0, 2, -1.0);
    ///         out.set(1, 3, -1.0);
    ///         out.set(2, 0, y[4]);
    ///         out.set(2, 4, y[0]);
    ///         out.set(3, 1, y[4]);
    ///         out.set(3, 4, y[1]);
    ///         out.set(4, 0, 2.0 * y[0]);
    ///         out.set(4, 1, 2.0 * y[1]);
    ///     }
    /// }
    ///
    /// // Horizontal at rest: x = 1, y = 0, l = 0, and u' = 0, v' = -1.
    /// let (y0, yp0) = ([1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, -1.0, 0.0]);
    /// let mut r = Radau::stabilised(Pendulum, Options::with_tolerances(1e-6, 1e-6), 0.0, &y0, &yp0)
    ///     .unwrap();
    /// let mut y = vec![0.0; r.y().len()]; // 5 unknowns and one mu
    /// r.solve_to(1.0, &mut y, None).unwrap();
    /// // Still on the circle.
    /// assert!((y[0] * y[0] + y[1] * y[1] - 1.0).abs() < 1e-6);
    /// ```
    ///
    /// # Errors
    /// [`RadauError::Structure`] when the structure cannot be read at the start (lengths that
    /// differ from the DAE's dimension, a non-finite iteration matrix there); then as
    /// [`Radau::new`].
    pub fn stabilised(
        dae: D,
        opts: Options,
        t0: f64,
        y0: &[f64],
        yp0: &[f64],
    ) -> Result<Self, RadauError> {
        let s = crate::stabilised::Stabilised::start(dae, t0, y0, yp0)?;
        let opts = Options {
            index: s.index,
            ..opts
        };
        Radau::new(s.form, s.ls, opts, t0, &s.y, &s.yp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear_solver::NalgebraLu;
    use crate::MatrixSink;

    /// `y' = lambda y` (one component).
    struct Scalar(f64);
    impl ImplicitDae for Scalar {
        fn dimension(&self) -> usize {
            1
        }
        fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = yp[0] - self.0 * y[0];
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            _: &[f64],
            _: &[f64],
            c: f64,
            m: &mut S,
        ) {
            m.set(0, 0, c - self.0);
        }
    }

    #[test]
    fn one_step_is_the_stability_function() {
        // For y' = λ y, one Radau IIA step multiplies by the (2,3)-Padé approximant
        // R(z) = (1 + 2z/5 + z^2/20) / (1 - 3z/5 + 3z^2/20 - z^3/60), z = hλ.
        let lam = -3.0;
        let h = 0.2;
        let opts = Options {
            initial_step: Some(h),
            newton_tolerance: Some(1e-12),
            ..Options::with_tolerances(1.0, 1.0)
        };
        let mut r = Radau::new(
            Scalar(lam),
            NalgebraLu::<1>::new(),
            opts,
            0.0,
            &[1.0],
            &[lam],
        )
        .unwrap();
        r.step().unwrap();
        let z: f64 = h * lam;
        let rz = (1.0 + 0.4 * z + z * z / 20.0) / (1.0 - 0.6 * z + 0.15 * z * z - z * z * z / 60.0);
        assert!((r.t() - h).abs() < 1e-15);
        assert!((r.y()[0] - rz).abs() < 1e-13, "{} vs {rz}", r.y()[0]);
        // The stage derivative at the end satisfies the equation.
        assert!((r.yp()[0] - lam * r.y()[0]).abs() < 1e-12);
    }
}
