//! Fixed-step, fixed-order BDF ([`FixedBdf`]).
//!
//! Constant-step BDF of order `q`: `F(t_{n+1}, y_{n+1}, (1/h) sum_j a_j y_{n+1-j}) = 0`
//! (Hairer & Wanner 1996, Section III.1, Table 1.2 of coefficients). Only past *values* of `y`
//! enter, never `y'`, so the integration may start from inconsistent values: the first step
//! (implicit Euler when no older values are given) projects onto the constraints. While fewer
//! than `q` past values are available the order ramps up (`1, 2, ..., q`), which limits the
//! global accuracy to that of the startup; supplying the history with
//! [`FixedBdf::with_history`], or starting from consistent values with
//! [`FixedBdf::with_consistent_start`], gives the full order.

use super::history::History;
use super::newton::{error_weights, Corrector, NewtonProblem};
use super::{BdfError, Options, Stats, Tolerance};
use crate::error::InvalidOption;
use crate::linear_solver::LinearSolver;
use crate::ImplicitDae;

/// Coefficients `a_0..a_q` of constant-step BDF of order `q` (`a_0` multiplies `y_{n+1}`).
const COEFFS: [[f64; 6]; 5] = [
    [1.0, -1.0, 0.0, 0.0, 0.0, 0.0],
    [1.5, -2.0, 0.5, 0.0, 0.0, 0.0],
    [11.0 / 6.0, -3.0, 1.5, -1.0 / 3.0, 0.0, 0.0],
    [25.0 / 12.0, -4.0, 3.0, -4.0 / 3.0, 0.25, 0.0],
    [137.0 / 60.0, -5.0, 5.0, -10.0 / 3.0, 1.25, -0.2],
];

/// Fixed-step BDF integrator of a given order.
///
/// Newton's iteration matrix `dF/dy + (a_0/h) dF/dy'` is reused across steps and refreshed only
/// when Newton fails with it. A step is accepted only when Newton's update test passes *and*
/// the scaled residual passes [`Options::residual_tolerance`]; otherwise the step
/// returns [`BdfError::NewtonFailed`] (or the singular-matrix / non-finite-residual error) and
/// the integrator stays at the previous point.
pub struct FixedBdf<D: ImplicitDae, L: LinearSolver> {
    dae: D,
    opts: Options,
    order: usize,
    h: f64,
    t: f64,
    /// `hist[0]` is `y_n`, `hist[j]` is `y_{n-j}`.
    hist: History,
    navail: usize,
    /// The order the factorised iteration matrix was formed for (0: none yet).
    jac_order: usize,
    /// The corrector's linear solver, iteration matrix and work vectors.
    corrector: Corrector<L>,
    stats: Stats,
}

impl<D: ImplicitDae, L: LinearSolver> FixedBdf<D, L> {
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
        let n = dae.dimension();
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
        let mut hist = History::new(6, n);
        for (j, src) in history.iter().enumerate() {
            hist.col_mut(j).copy_from_slice(src);
        }
        let mut corrector = Corrector::new(ls, n);
        corrector.y.copy_from_slice(history[0]);
        Ok(Self {
            dae,
            opts,
            order,
            h,
            t: t0,
            navail: history.len(),
            hist,
            jac_order: 0,
            corrector,
            stats: Stats::default(),
        })
    }

    /// Restart at `(t0, y0)` (possibly inconsistent) without allocating: the order ramps up
    /// again and the iteration matrix is re-formed at the first step.
    ///
    /// # Errors
    /// [`BdfError::DimensionMismatch`] if `y0` has the wrong length.
    pub fn reset(&mut self, t0: f64, y0: &[f64]) -> Result<(), BdfError> {
        if y0.len() != self.corrector.y.len() {
            return Err(BdfError::DimensionMismatch {
                what: "y0",
                expected: self.corrector.y.len(),
                found: y0.len(),
            });
        }
        self.t = t0;
        self.hist.col_mut(0).copy_from_slice(y0);
        self.corrector.y.copy_from_slice(y0);
        self.corrector.yp.fill(0.0);
        self.navail = 1;
        self.corrector.reset();
        self.jac_order = 0;
        Ok(())
    }

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
        let mut bdf = super::Bdf::new(&f.dae, &mut f.corrector.ls, startup_opts, t0, y0, yp0)?;
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
        f.corrector.y.copy_from_slice(&points[order - 1]);
        f.navail = order;
        f.t = t0 + (order - 1) as f64 * h;
        f.stats = startup;
        f.corrector.reset();
        Ok(f)
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Solution at [`t`](Self::t).
    pub fn y(&self) -> &[f64] {
        self.hist.col(0)
    }

    /// The BDF derivative approximation at [`t`](Self::t) (zero before the first step).
    pub fn yp(&self) -> &[f64] {
        &self.corrector.yp
    }

    /// Work counters so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The DAE being integrated.
    pub fn dae(&self) -> &D {
        &self.dae
    }

    /// Take one step of size `h`; returns the new time. On error the state is unchanged.
    ///
    /// # Errors
    /// [`BdfError::NewtonFailed`], [`BdfError::SingularMatrix`],
    /// [`BdfError::NonFiniteResidual`], [`BdfError::InvalidTolerance`].
    pub fn step(&mut self) -> Result<f64, BdfError> {
        let q = self.order.min(self.navail);
        let a = &COEFFS[q - 1];
        let h = self.h;
        let t_new = self.t + h;
        let cj = a[0] / h;
        // Predictor: polynomial extrapolation through the available past values.
        let m = self.navail.min(q + 1);
        self.corrector.y_pred.fill(0.0);
        let mut binom = 1.0;
        for j in 0..m {
            // coefficient (-1)^j C(m, j+1)
            binom = binom * (m - j) as f64 / (j + 1) as f64;
            let c = if j % 2 == 0 { binom } else { -binom };
            for (p, v) in self.corrector.y_pred.iter_mut().zip(self.hist.col(j)) {
                *p += c * v;
            }
        }
        for i in 0..self.corrector.y_pred.len() {
            let mut s = a[0] * self.corrector.y_pred[i];
            for (j, aj) in a.iter().enumerate().take(q + 1).skip(1) {
                s += aj * self.hist.col(j - 1)[i];
            }
            self.corrector.yp_pred[i] = s / h;
        }
        error_weights(&self.opts, self.hist.col(0), &mut self.corrector.newton.w)?;
        let hs = h.min(1.0);
        for (i, w) in self.corrector.newton.w.iter_mut().enumerate() {
            let m = self.opts.index_of(i);
            if m > 1 {
                *w *= hs.powi(i32::from(m) - 1);
            }
        }
        let problem = NewtonProblem {
            t: t_new,
            cj,
            max_iterations: self.opts.max_newton_iterations.max(4),
            epcon: self.opts.newton_tolerance,
            residual_tolerance: self.opts.residual_tolerance,
            force_setup: self.jac_order != q,
        };
        let out = self.corrector.solve(&self.dae, &mut self.stats, &problem);
        if let Err(f) = out {
            self.stats.newton_failures += 1;
            return Err(f.into_error(&self.dae, t_new, h));
        }
        self.jac_order = q;
        self.hist.push_front().copy_from_slice(&self.corrector.y);
        self.navail = (self.navail + 1).min(6);
        self.t = t_new;
        self.stats.steps += 1;
        Ok(t_new)
    }
}
