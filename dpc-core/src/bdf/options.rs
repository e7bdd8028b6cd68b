//! Integrator options.

use super::BdfError;
use crate::error::InvalidOption;

/// A tolerance, the same for every component or one per component.
#[derive(Debug, Clone, PartialEq)]
pub enum Tolerance {
    /// One value for all components.
    Scalar(f64),
    /// One value per component.
    Vector(Vec<f64>),
}

impl Tolerance {
    #[inline]
    pub(crate) fn get(&self, i: usize) -> f64 {
        match self {
            Self::Scalar(v) => *v,
            Self::Vector(v) => v[i],
        }
    }

    fn check(&self, name: &'static str, n: usize) -> Result<(), BdfError> {
        if let Self::Vector(v) = self {
            if v.len() != n {
                return Err(BdfError::DimensionMismatch {
                    what: if name == "rtol" { "rtol" } else { "atol" },
                    expected: n,
                    found: v.len(),
                });
            }
        }
        for i in 0..n {
            let x = self.get(i);
            if !(x.is_finite() && x >= 0.0) {
                return Err(BdfError::InvalidTolerance {
                    which: name,
                    component: i,
                    value: x,
                });
            }
        }
        Ok(())
    }
}

/// How components the user marks as index 2 or 3 enter the local error test.
///
/// BDF approximates an index-`m` component only to order `k - m + 1` in the step, so its
/// local error estimate does not shrink like `h^(k+1)` and would force needlessly small steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HigherIndexControl {
    /// Exclude them from the error test, as DASSL users and IDA's `suppressalg` do; Newton's
    /// convergence test keeps their plain weight, as in IDA. This is the default.
    ///
    /// (In the fixed-step mode, which has no error test, Newton's convergence test always
    /// weights an index-`m` component by `min(1, h)^(m - 1)`: the iteration matrix has
    /// condition `O(h^-m)`, so those updates carry round-off of that size and an unscaled test
    /// cannot pass at tight tolerances with a step that is not adapted.)
    #[default]
    Exclude,
    /// Keep them but scale their weight by `min(1, h)^(m - 1)` in the error test (Hairer,
    /// Lubich & Roche 1989; RADAU5's `nind2`, `nind3`), and in Newton's convergence test when
    /// `m` is the highest index declared (the multipliers). The others (the velocities of an
    /// index-3 mechanism, index 2 there) keep their plain weight in Newton's test, with the
    /// round-off fallback `Exclude` has: Newton's error in a velocity carries forward as a
    /// state error, which a weight relaxed by `h` admitted (as Radau's: see
    /// [`crate::radau::Options::index`]).
    Scale,
}

/// How the variable-step BDF ([`super::Bdf`]) forms a new iteration matrix
/// `dF/dy + cj dF/dy'` when `cj = alpha / h` leaves the window `[0.6, 1.67]` of the value the
/// matrix was factorised with (after a change of step or order).
///
/// Either way the model's matrix is evaluated when Newton fails with a matrix formed in an
/// earlier step, and when its `dF/dy` has served [`Options::max_matrix_age`] corrector solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MatrixUpdate {
    /// Evaluate the model's [`iteration_matrix`](crate::ImplicitDae::iteration_matrix) at the
    /// predicted point (IDA's rule). The default.
    #[default]
    Evaluate,
    /// Move the matrix to the new `cj` with the model's mass matrix: add
    /// `(cj - cj_old) dF/dy'`, taken at the point where `dF/dy` was evaluated
    /// ([`ImplicitDae::mass_matrix`](crate::ImplicitDae::mass_matrix)), and factorise again.
    /// Only the matrix a solve asks for at its start (for the new `cj`) is moved; the model's
    /// matrix is evaluated when Newton's rate test asks for a fresh one within a solve, when
    /// Newton fails with a moved or older matrix, and when its `dF/dy` has served
    /// [`Options::max_matrix_age`] solves. For models whose iteration matrix costs many
    /// residuals (difference quotients) and whose mass matrix is cheap; a model that
    /// supplies no mass matrix is integrated as with [`Evaluate`](Self::Evaluate).
    ///
    /// Newton then iterates with an older `dF/dy`: it converges more slowly, and its
    /// convergence test lets corrector errors up to its bound through where a fresh matrix
    /// would have left far smaller ones. Measured (15 tolerance factors, `max_matrix_age =
    /// 50`): the Test Set's wheelset with `dF/dy` by central differences (34 residuals; its
    /// fixture's matrix until it took the exact one from `dpc::model!`) 5 to 7 times fewer
    /// matrix evaluations and 0.49 / 0.51 / 0.68 of `Evaluate`'s time at `rtol =
    /// atol = 1e-4 / 1e-6 / 1e-8` (0.27 / 0.24 / 0.28 of IDA's), with 0.3 digits fewer at
    /// `1e-6` (0.2 more at `1e-8`); on models with cheap exact matrices it saves little time
    /// and costs digits at some tolerances (0.9 digits on the index-3 pendulum at `1e-6`, 1.5
    /// on a NAND gate), which is why it is not the default (docs/integrators.md, "`dF/dy'`
    /// from the model").
    Move,
}

/// The corrector solves an evaluation of the iteration matrix serves at most on a DAE whose
/// unknowns all have index at most 1, unless [`Options::max_matrix_age`] says otherwise: the
/// steps CVODE allows between two set-ups of its matrix (IDA has no such bound).
pub const DEFAULT_MAX_MATRIX_AGE: usize = 20;

/// Options of the variable-step integrator ([`super::Bdf`]) and, where they apply, of the
/// fixed-step mode ([`super::FixedBdf`]) and consistent initialisation.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Relative tolerance (default `1e-6`).
    pub rtol: Tolerance,
    /// Absolute tolerance (default `1e-8`).
    pub atol: Tolerance,
    /// Highest BDF order, 1 to 5 (default 5).
    pub max_order: usize,
    /// Step limit for one call of [`super::Bdf::solve_to`] (default 100 000).
    pub max_steps: usize,
    /// First step size; `None` lets the integrator choose (IDA's rule: `0.001 |tout - t0|`,
    /// reduced so that `h |y'|` is at most half a tolerance unit).
    pub initial_step: Option<f64>,
    /// Largest step size (default infinity).
    pub max_step: f64,
    /// Smallest step size before the integrator gives up (default 0, meaning only the round-off
    /// bound `4 eps |t|`).
    pub min_step: f64,
    /// Newton iterations per attempt (default 4, IDA's `maxcor`).
    pub max_newton_iterations: usize,
    /// Newton convergence constant (default 0.33, IDA's `epcon`): the iteration stops when the
    /// estimated remaining error is below this fraction of the local error tolerance. On a DAE
    /// whose unknowns all have index at most 1 (no 2 or 3 in [`index`](Self::index)) the
    /// variable-step integrator asks for a tenth of it and gives an iteration up as soon as its
    /// convergence rate shows that [`max_newton_iterations`](Self::max_newton_iterations)
    /// cannot reach that: the local error estimate contains the corrector's error, and where
    /// algebraic unknowns amplify the differential ones' (the transistor amplifier) IDA's
    /// constant lets it fail the error test.
    pub newton_tolerance: f64,
    /// Newton failures allowed within one step before giving up (default 10).
    pub max_newton_failures: usize,
    /// Error test failures allowed within one step before giving up (default 10).
    pub max_error_test_failures: usize,
    /// Differential index per component (0 or 1 for ordinary components, 2 or 3 for
    /// higher-index ones). Empty means every component has index at most 1.
    pub index: Vec<u8>,
    /// How components with index 2 or 3 enter the error test.
    pub higher_index: HigherIndexControl,
    /// Fixed-step mode only: after Newton's update test passes, the scaled residual must also
    /// satisfy `max_i |F_i| / max_j (|G_ij| / w_j) <= residual_tolerance`, with `G` the
    /// iteration matrix and `w_j` the error weights: every equation must be satisfied to
    /// within what a change of the unknowns by this many tolerance units would cause (default
    /// `1.0`); `f64::INFINITY` disables the check.
    pub residual_tolerance: f64,
    /// Variable-step integrator only: how a new iteration matrix is formed when the step or
    /// the order changes `cj` (default [`MatrixUpdate::Evaluate`], IDA's rule).
    pub matrix_update: MatrixUpdate,
    /// Variable-step integrator only: the corrector solves one evaluation of the model's
    /// `dF/dy` serves at most; the next solve evaluates the iteration matrix anew even when
    /// `cj` stays in its window. `None` (the default): [`DEFAULT_MAX_MATRIX_AGE`] solves on a
    /// DAE whose unknowns all have index at most 1 (an implicit ODE or an index-1 DAE), no
    /// bound on a DAE with unknowns of index 2 or 3 (IDA's rule: there the bound cost digits
    /// on the car axis for few steps saved). `Some(n)`: `n` solves on every DAE, `Some(0)` no
    /// bound. A matrix kept through many steps of a solution that moves (a reaction front)
    /// slows Newton's convergence, and the corrector's error it leaves in the local error
    /// estimate keeps the step from growing and lowers the order (docs/integrators.md, "The
    /// age of the iteration matrix").
    pub max_matrix_age: Option<usize>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: Tolerance::Scalar(1e-6),
            atol: Tolerance::Scalar(1e-8),
            max_order: 5,
            max_steps: 100_000,
            initial_step: None,
            max_step: f64::INFINITY,
            min_step: 0.0,
            max_newton_iterations: 4,
            newton_tolerance: 0.33,
            max_newton_failures: 10,
            max_error_test_failures: 10,
            index: Vec::new(),
            higher_index: HigherIndexControl::Exclude,
            residual_tolerance: 1.0,
            matrix_update: MatrixUpdate::Evaluate,
            max_matrix_age: None,
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
    /// [`BdfError::InvalidTolerance`], [`BdfError::DimensionMismatch`] or
    /// [`BdfError::InvalidOption`].
    pub fn validate(&self, n: usize) -> Result<(), BdfError> {
        self.rtol.check("rtol", n)?;
        self.atol.check("atol", n)?;
        for i in 0..n {
            if self.rtol.get(i) == 0.0 && self.atol.get(i) == 0.0 {
                return Err(BdfError::InvalidTolerance {
                    which: "rtol and atol",
                    component: i,
                    value: 0.0,
                });
            }
        }
        if !(1..=5).contains(&self.max_order) {
            return Err(
                InvalidOption::new("max_order", self.max_order as f64, "between 1 and 5").into(),
            );
        }
        if !self.index.is_empty() && self.index.len() != n {
            return Err(BdfError::DimensionMismatch {
                what: "index",
                expected: n,
                found: self.index.len(),
            });
        }
        if let Some(&m) = self.index.iter().find(|&&m| m > 3) {
            return Err(InvalidOption::new("index", f64::from(m), "at most 3").into());
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if let Some(h) = self.initial_step {
            if !positive(h) {
                return Err(InvalidOption::new("initial_step", h, "positive and finite").into());
            }
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return Err(InvalidOption::new("max_step", self.max_step, "positive").into());
        }
        if !self.min_step.is_finite() || self.min_step < 0.0 || self.min_step > self.max_step {
            return Err(InvalidOption::new(
                "min_step",
                self.min_step,
                "finite, not negative and at most max_step",
            )
            .into());
        }
        if self.max_newton_iterations == 0 {
            return Err(InvalidOption::new("max_newton_iterations", 0.0, "at least 1").into());
        }
        if !positive(self.newton_tolerance) {
            return Err(InvalidOption::new(
                "newton_tolerance",
                self.newton_tolerance,
                "positive and finite",
            )
            .into());
        }
        if self.residual_tolerance.is_nan() || self.residual_tolerance <= 0.0 {
            return Err(InvalidOption::new(
                "residual_tolerance",
                self.residual_tolerance,
                "positive",
            )
            .into());
        }
        Ok(())
    }

    /// Check that some unknown is in the variable-step error test: [`Options::index`] giving
    /// every unknown index 2 or 3 under [`HigherIndexControl::Exclude`] leaves none, and
    /// nothing would bound the step (the fixed-step mode has no error test and does not ask).
    ///
    /// # Errors
    /// [`BdfError::NothingInErrorTest`].
    pub fn check_error_test(&self) -> Result<(), BdfError> {
        if self.higher_index == HigherIndexControl::Exclude
            && !self.index.is_empty()
            && self.index.iter().all(|&m| m >= 2)
        {
            return Err(BdfError::NothingInErrorTest);
        }
        Ok(())
    }

    /// Index of component `i` (at least 1).
    #[inline]
    pub(crate) fn index_of(&self, i: usize) -> u8 {
        self.index.get(i).copied().unwrap_or(1).max(1)
    }
}
