//! Options of the Radau IIA integrator, in the style of [`crate::bdf::Options`].

use super::error::RadauError;
use crate::bdf::Tolerance;
use crate::error::InvalidOption;

/// Options of [`super::Radau`]. Field names shared with [`crate::bdf::Options`] mean the same.
///
/// The tolerances are the user's: internally they are mapped as in RADAU5 (Hairer & Wanner's
/// code), `rtol' = 0.1 rtol^(2/3)` and `atol' = rtol' atol / rtol`, because the embedded error
/// estimate is of order 3 while the method is of order 5; with this map the global error tracks
/// `rtol` over a wide range of tolerances.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Relative tolerance (default `1e-6`).
    pub rtol: Tolerance,
    /// Absolute tolerance (default `1e-8`).
    pub atol: Tolerance,
    /// Step limit for one call of [`super::Radau::solve_to`] (default 100 000).
    pub max_steps: usize,
    /// First step size; `None` lets the integrator choose (`0.001 |tout - t0|`, reduced so that
    /// `h |y'|` of the index-0/1 components is at most half a tolerance unit, as the BDF does).
    pub initial_step: Option<f64>,
    /// Largest step size (default infinity).
    pub max_step: f64,
    /// Smallest step size before the integrator gives up (default 0, meaning only the round-off
    /// bound `4 eps |t|`).
    pub min_step: f64,
    /// Simplified-Newton iterations per attempt (default 7, RADAU5's `NIT`).
    pub max_newton_iterations: usize,
    /// Newton stops when `theta / (1 - theta) |ΔW| <= newton_tolerance` in the weighted RMS norm
    /// of the transformed stage increments (RADAU5's test). `None` (default) uses RADAU5's rule
    /// `max(10 eps / rtol', min(0.03, sqrt(rtol')))` with the mapped `rtol'`, times `0.03` when
    /// [`index`](Self::index) marks a component of index 2 or 3 (their relaxed weights would
    /// otherwise let Newton's error in the multipliers reach the positions). An iteration that
    /// would fail while its increment is no larger than the one the round-off of the stage
    /// residuals causes (the bound `10 eps (|dF/dy| |y| + |dF/dy'| |y'|)` solved as Newton's
    /// residuals are) counts as converged: further iterations cannot reduce it.
    pub newton_tolerance: Option<f64>,
    /// Keep the Jacobian for the next step when the last Newton contraction rate was at most
    /// this (default `0.001`, RADAU5's `THET`). A negative value re-evaluates it every step.
    pub jacobian_reuse_rate: f64,
    /// Keep the step size (and so the factorisations) when the proposed ratio `h_new / h` lies
    /// in this window and the Jacobian is kept (default `(1.0, 1.2)`, RADAU5's `QUOT1`, `QUOT2`).
    pub keep_step_window: (f64, f64),
    /// Bounds on `h_new / h` after one step (default `(0.2, 8.0)`).
    pub step_ratio_bounds: (f64, f64),
    /// Safety factor of the step-size formula (default `0.9`).
    pub safety: f64,
    /// Gustafsson's predictive step-size controller (default `true`); `false` uses the classical
    /// controller `h_new = fac h err^(-1/4)` only.
    pub predictive: bool,
    /// Bound the growth of the next step by Newton's predicted convergence (default `false`):
    /// after an accepted step the next one grows at most to where Newton's slow-convergence
    /// test would still pass, with the contraction predicted to grow as `h^2` and the first
    /// update as `h^4` (see `docs/integrators.md`, "Newton failures on the index-3 forms and
    /// the growth bound"). On Andrews' squeezing mechanism in index-3 form it removes 28-47 %
    /// of the Newton failures and 5-18 % of the instructions, on Ascher and Petzold's index-2
    /// problem 7-24 %; not the default because at `rtol = 1e-4` several problems' digits moved
    /// down within their tolerance jitter (the index-3 pendulum 5.54 -> 5.21, median over ten
    /// factors) and the index-3 double pendulum at `1e-6` lost 0.4 / 0.85 digits in positions /
    /// velocities at the nominal tolerance.
    pub newton_growth_bound: bool,
    /// Consecutive failed attempts (Newton, singular matrix or non-finite residual) allowed in
    /// one step before giving up (default 20). A failure halves the step (a diverging
    /// iteration cuts it by up to ten), so twenty span the step range of IDA's ten failures,
    /// each of which quarters it (`MXNCF`; RADAU5 itself has no count, only the smallest
    /// step). With ten, Radau stopped on the Test Set's NAND gate at `rtol = 1e-10` at the
    /// input's corner `t = 25` (eleven halvings from the carried step needed) and runs to ten
    /// digits with twenty.
    pub max_newton_failures: usize,
    /// Consecutive error-test failures allowed in one step before giving up (default 10).
    pub max_error_test_failures: usize,
    /// Differential index per component (0 or 1 for ordinary components, 2 or 3 for
    /// higher-index ones). Empty means every component has index at most 1. The error weight of
    /// an index-`m` component is multiplied by `min(1, h)^(m - 1)` in the error test (Hairer,
    /// Lubich & Roche 1989; RADAU5's `NIND2`, `NIND3`), and in Newton's convergence test when
    /// `m` is the highest index declared (the multipliers); the others, such as the velocities
    /// of an index-3 mechanism, keep their unrelaxed weight there, because Newton's error in
    /// them carries forward as a state error.
    pub index: Vec<u8>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: Tolerance::Scalar(1e-6),
            atol: Tolerance::Scalar(1e-8),
            max_steps: 100_000,
            initial_step: None,
            max_step: f64::INFINITY,
            min_step: 0.0,
            max_newton_iterations: 7,
            newton_tolerance: None,
            jacobian_reuse_rate: 0.001,
            keep_step_window: (1.0, 1.2),
            step_ratio_bounds: (0.2, 8.0),
            safety: 0.9,
            predictive: true,
            newton_growth_bound: false,
            max_newton_failures: 20,
            max_error_test_failures: 10,
            index: Vec::new(),
        }
    }
}

impl Options {
    /// Options with scalar relative and absolute tolerances, other fields default.
    pub fn with_tolerances(rtol: f64, atol: f64) -> Self {
        Self {
            rtol: Tolerance::Scalar(rtol),
            atol: Tolerance::Scalar(atol),
            ..Self::default()
        }
    }

    /// Check every field against the dimension `n` of the DAE.
    ///
    /// # Errors
    /// [`RadauError::InvalidTolerance`], [`RadauError::DimensionMismatch`] or
    /// [`RadauError::InvalidOption`].
    pub fn validate(&self, n: usize) -> Result<(), RadauError> {
        for (what, tol) in [("rtol", &self.rtol), ("atol", &self.atol)] {
            if let Tolerance::Vector(v) = tol {
                if v.len() != n {
                    return Err(RadauError::DimensionMismatch {
                        what,
                        expected: n,
                        found: v.len(),
                    });
                }
            }
            for i in 0..n {
                let x = tol.get(i);
                if !(x.is_finite() && x >= 0.0) {
                    return Err(RadauError::InvalidTolerance {
                        which: what,
                        component: i,
                        value: x,
                    });
                }
            }
        }
        for i in 0..n {
            if self.rtol.get(i) == 0.0 && self.atol.get(i) == 0.0 {
                return Err(RadauError::InvalidTolerance {
                    which: "rtol and atol",
                    component: i,
                    value: 0.0,
                });
            }
        }
        if !self.index.is_empty() && self.index.len() != n {
            return Err(RadauError::DimensionMismatch {
                what: "index",
                expected: n,
                found: self.index.len(),
            });
        }
        if let Some(&m) = self.index.iter().find(|&&m| m > 3) {
            return Err(InvalidOption::new("index", f64::from(m), "at most 3").into());
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        let check = |ok: bool, name: &'static str, value: f64, requirement: &'static str| {
            if ok {
                Ok(())
            } else {
                Err(RadauError::from(InvalidOption::new(
                    name,
                    value,
                    requirement,
                )))
            }
        };
        if let Some(h) = self.initial_step {
            check(positive(h), "initial_step", h, "positive and finite")?;
        }
        check(
            !self.max_step.is_nan() && self.max_step > 0.0,
            "max_step",
            self.max_step,
            "positive",
        )?;
        check(
            self.min_step.is_finite() && self.min_step >= 0.0 && self.min_step <= self.max_step,
            "min_step",
            self.min_step,
            "finite, non-negative and at most max_step",
        )?;
        check(
            self.max_newton_iterations > 0,
            "max_newton_iterations",
            self.max_newton_iterations as f64,
            "at least 1",
        )?;
        if let Some(f) = self.newton_tolerance {
            check(positive(f), "newton_tolerance", f, "positive and finite")?;
        }
        check(
            !self.jacobian_reuse_rate.is_nan() && self.jacobian_reuse_rate < 1.0,
            "jacobian_reuse_rate",
            self.jacobian_reuse_rate,
            "below 1",
        )?;
        let (q1, q2) = self.keep_step_window;
        check(
            q1.is_finite() && q2.is_finite() && 0.0 < q1 && q1 <= 1.0 && q2 >= 1.0,
            "keep_step_window",
            if q1 > 1.0 { q1 } else { q2 },
            "lower end in (0, 1], upper end at least 1",
        )?;
        let (r1, r2) = self.step_ratio_bounds;
        check(
            positive(r1) && r1 < 1.0,
            "step_ratio_bounds.0",
            r1,
            "in (0, 1)",
        )?;
        check(
            r2.is_finite() && r2 > 1.0,
            "step_ratio_bounds.1",
            r2,
            "finite and above 1",
        )?;
        check(
            positive(self.safety) && self.safety <= 1.0,
            "safety",
            self.safety,
            "in (0, 1]",
        )?;
        check(
            self.max_newton_failures > 0 && self.max_error_test_failures > 0,
            "max_newton_failures / max_error_test_failures",
            self.max_newton_failures.min(self.max_error_test_failures) as f64,
            "at least 1",
        )?;
        Ok(())
    }

    /// Index of component `i` (at least 1).
    #[inline]
    pub(crate) fn index_of(&self, i: usize) -> u8 {
        self.index.get(i).copied().unwrap_or(1).max(1)
    }
}
