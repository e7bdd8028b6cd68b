//! Step-size selection: the classical controller `h_new = fac h err^(-1/4)` and Gustafsson's
//! predictive controller (Gustafsson 1994, *Control-theoretic techniques for stepsize selection
//! in implicit Runge-Kutta methods*, ACM TOMS 20; Hairer & Wanner, Section IV.8, eq. (8.25)),
//! as in RADAU5.
//!
//! The exponent `1/4` belongs to the order-3 embedded estimate. The safety factor is lowered
//! when Newton needed many iterations (`fac = min(safety, safety (2 k_max + 1) / (k + 2 k_max))`),
//! since such steps are expensive and likely to fail again at a larger step.

use super::Options;

/// State of the controller between steps.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Controller {
    /// Step size of the last accepted step.
    h_acc: f64,
    /// Error of the last accepted step (at least `1e-2`).
    err_acc: f64,
    /// Accepted steps seen.
    accepted: usize,
}

impl Controller {
    /// `h / h_new` from the error alone (RADAU5's `QUOT`), within the option bounds.
    pub fn quotient(opts: &Options, err: f64, newton_iterations: usize) -> f64 {
        let (lo, hi) = opts.step_ratio_bounds;
        (err.powf(0.25) / Self::safety(opts, newton_iterations)).clamp(1.0 / hi, 1.0 / lo)
    }

    /// The safety factor, lowered after many Newton iterations.
    fn safety(opts: &Options, newton_iterations: usize) -> f64 {
        let nit = opts.max_newton_iterations as f64;
        opts.safety
            .min(opts.safety * (1.0 + 2.0 * nit) / (newton_iterations as f64 + 2.0 * nit))
    }

    /// `h / h_new` after the error test failed with `err` at step `h`. The exponent `1/4`
    /// assumes the estimate falls as `h^4`; after a second failure of the same step
    /// (`previous`: the step and error of the first) the observed exponent
    /// `q = ln(err_prev / err) / ln(h_prev / h)` is known, and where the estimate fell slower
    /// than `h^4` (a fast transient switched on inside the step, or a corner of the model
    /// there: the estimate then stays near a constant until `h` resolves it) the quotient
    /// `(err / fac)^(1/q)` is used, within the same bounds. The classical quotient, which
    /// shrinks such a step by about 2 per failure, ran into the failure limit on the NAND gate
    /// at `rtol = 1e-8` (the estimate 3-13 from `h = 0.07` down to `h = 8e-4`).
    pub fn rejection_quotient(
        opts: &Options,
        err: f64,
        newton_iterations: usize,
        previous: Option<(f64, f64)>,
        h: f64,
    ) -> f64 {
        let classical = Self::quotient(opts, err, newton_iterations);
        let Some((h_prev, err_prev)) = previous else {
            return classical;
        };
        let (lo, hi) = opts.step_ratio_bounds;
        let q = (err_prev / err).ln() / (h_prev / h).ln();
        if q >= 4.0 || q.is_nan() {
            // Fell as fast as assumed (or the quotient is not a number: the same step twice).
            return classical;
        }
        // An estimate that did not fall (q near or below zero) takes the largest reduction.
        let observed = if q > 0.25 {
            (err / Self::safety(opts, newton_iterations)).powf(1.0 / q)
        } else {
            f64::INFINITY
        };
        classical.max(observed.clamp(1.0 / hi, 1.0 / lo))
    }

    /// The next step size after an accepted step of size `h` with error `err`.
    pub fn accept(&mut self, opts: &Options, h: f64, err: f64, newton_iterations: usize) -> f64 {
        let mut quot = Self::quotient(opts, err, newton_iterations);
        if opts.predictive {
            if self.accepted > 0 {
                let (lo, hi) = opts.step_ratio_bounds;
                let gus = (self.h_acc / h) * (err * err / self.err_acc).powf(0.25) / opts.safety;
                quot = quot.max(gus.clamp(1.0 / hi, 1.0 / lo));
            }
            self.h_acc = h;
            self.err_acc = err.max(1e-2);
        }
        self.accepted += 1;
        h / quot
    }

    /// Largest `h_new / h` after an accepted step of size `h` whose simplified Newton iteration
    /// ended with contraction estimate `theta` and whose first update was `first_increment`
    /// Newton tolerances, with `max_iterations` iterations allowed per attempt, when the
    /// controller proposes `ratio = h_new / h`: `None` if Newton's own test for slow
    /// convergence, applied at the next step's second iteration, would pass at that ratio,
    /// else the ratio at which it would just pass, if the contraction grows as `theta r^2` and
    /// the first update as `first_increment r^4` with `r = h_new / h`.
    ///
    /// That test ([`super::newton`]) abandons the iteration when the update predicted after
    /// the remaining iterations, `theta^(k_max - 1) |ΔW_1| / (1 - theta)` at the second one,
    /// exceeds the tolerance. The exponents: the Jacobian is evaluated at the step's start
    /// whenever the contraction exceeds [`Options::jacobian_reuse_rate`], so the contraction is
    /// `h` times the change of the Jacobian across the step, itself proportional to `h`
    /// (measured between an accepted step and the next step's failure: a median exponent 2.1
    /// on Andrews' squeezing mechanism, 2.3 on the pendulum, both index 3); the first update
    /// is the error of Newton's starting guess, the last step's cubic collocation polynomial
    /// extrapolated, `O(h^4)` (measured: 3.7 to 4.7 on the pendulum). A contraction of zero
    /// (converged in one iteration) gives no bound, and one at most the reuse rate `1e-3`
    /// none below the controller's largest ratio 8 unless the first update exceeded about
    /// 3000 tolerances.
    pub fn newton_growth_limit(
        theta: f64,
        first_increment: f64,
        max_iterations: usize,
        ratio: f64,
    ) -> Option<f64> {
        // The slow-convergence test runs from the second iteration to the last but one.
        if !(theta > 0.0 && theta < 1.0 && first_increment > 0.0 && first_increment.is_finite())
            || max_iterations < 3
        {
            return None;
        }
        let m = max_iterations - 1;
        // The common case, the proposed ratio passes: a few multiplications.
        let x = theta * ratio * ratio;
        if x < 1.0 && x.powi(m as i32) * first_increment * ratio.powi(4) <= 1.0 - x {
            return None;
        }
        // The contraction x = theta r^2 at which the test is met exactly: with the first
        // update first_increment (x / theta)^2, in u = ln x,
        // g(u) = (m + 2) u + c - ln(1 - e^u) = 0 with c = ln first_increment - 2 ln theta.
        // g is increasing and convex, so Newton's method from a point right of the root
        // descends to it monotonically. Right of it: where the test failed (theta ratio^2),
        // and exp(-c / (m + 2)), where g = -ln(1 - x) > 0; below 1 - 1e-3 (a root above that
        // is taken as 1 - 1e-3: a ratio off by at most 0.05 %).
        let k = (m + 2) as f64;
        let c = first_increment.ln() - 2.0 * theta.ln();
        let g = |u: f64| k * u + c - (-u.exp()).ln_1p();
        let mut u = (-c / k).min(x.ln()).min((-1e-3f64).ln_1p());
        if g(u) > 0.0 {
            for _ in 0..30 {
                let e = u.exp();
                let step = g(u) / (k + e / (1.0 - e));
                u -= step;
                if step <= 1e-12 {
                    break;
                }
            }
        }
        let x = u.exp();
        Some((x / theta).sqrt().min(ratio))
    }

    /// Forget the history (after a restart).
    pub fn reset(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classical_and_predictive_steps() {
        let opts = Options::default();
        let mut c = Controller::default();
        // err = 1/16: classical ratio 2 / fac with fac = 0.9 (one Newton iteration).
        let h1 = c.accept(&opts, 1.0, 1.0 / 16.0, 1);
        assert!((h1 - 0.9 * 2.0).abs() < 1e-12, "{h1}");
        // Error jumping from 1/16 to 1/2 at the same step: the predictive controller reads the
        // growth rate and shrinks the step, quotient (0.25/0.0625)^(1/4)/0.9 = 1.571, where the
        // classical one (0.5^(1/4)/0.9 = 0.934) would still grow it.
        let classical = 1.0 / Controller::quotient(&opts, 0.5, 1);
        let h2 = c.accept(&opts, 1.0, 0.5, 1);
        assert!(classical > 1.0);
        assert!((h2 - 0.9 / 2f64.sqrt()).abs() < 1e-12, "{h2}");
        // Bounds: a tiny error at most multiplies by 8, a huge one divides by 5.
        assert!((1.0 / Controller::quotient(&opts, 1e-30, 1) - 8.0).abs() < 1e-12);
        assert!((Controller::quotient(&opts, 1e30, 1) - 5.0).abs() < 1e-12);
    }

    #[test]
    fn a_rejection_reads_how_the_estimate_fell() {
        let opts = Options::default();
        // One Newton iteration: the safety factor 0.9.
        let classical = Controller::quotient(&opts, 4.0, 1);
        // The first failure of a step, or an estimate that fell as h^4 or faster: the
        // classical quotient.
        assert_eq!(
            Controller::rejection_quotient(&opts, 4.0, 1, None, 0.1),
            classical
        );
        let faster = Some((0.2, 4.0 * 32.0));
        assert_eq!(
            Controller::rejection_quotient(&opts, 4.0, 1, faster, 0.1),
            classical
        );
        // Fell as h: (4 / fac)^1 = 4.44, where the classical quotient is 1.57.
        let as_h = Some((0.2, 8.0));
        let q = Controller::rejection_quotient(&opts, 4.0, 1, as_h, 0.1);
        assert!((q - 4.0 / 0.9).abs() < 1e-12, "{q}");
        // Did not fall, or grew: the largest reduction.
        for previous in [(0.2, 4.0), (0.2, 1.5)] {
            let q = Controller::rejection_quotient(&opts, 4.0, 1, Some(previous), 0.1);
            assert!((q - 5.0).abs() < 1e-12, "{q}");
        }
    }

    #[test]
    fn growth_is_bounded_by_newtons_predicted_convergence() {
        let nit = Options::default().max_newton_iterations;
        let lim = |theta, d| Controller::newton_growth_limit(theta, d, nit, 8.0);
        // The bound is the ratio r at which Newton's slow-convergence test at the second
        // iteration, with theta r^2 and first_increment r^4, predicts exactly the tolerance.
        let predicted = |theta: f64, d: f64, r: f64| {
            let x = theta * r * r;
            x.powi(nit as i32 - 1) * d * r.powi(4) / (1.0 - x)
        };
        for (theta, d) in [
            (0.12, 3e3),
            (0.1, 5e2),
            (0.25, 1e4),
            (0.01, 1e2),
            (0.5, 1e-3),
        ] {
            let r = lim(theta, d).unwrap();
            let p = predicted(theta, d, r);
            assert!(
                (p - 1.0).abs() < 1e-3,
                "theta {theta}, d {d}: r {r}, predicted {p}"
            );
            // A proposed ratio below the bound passes unchanged.
            assert_eq!(
                Controller::newton_growth_limit(theta, d, nit, 0.99 * r),
                None
            );
        }
        // Andrews' squeezing mechanism at rtol = 1e-4 (traced before this bound, at
        // t = 0.0106): a step accepted after 4 iterations with theta 0.1245 and a first update
        // of 146 tolerances was followed by a step 2.98 times larger whose Newton iteration
        // failed (theta 0.63, first update 5192), then one 1.64 times larger that failed again
        // (theta 0.33, 661); the bound allows 1.56.
        let r = Controller::newton_growth_limit(0.1245, 146.0, nit, 2.98).unwrap();
        assert!((r - 1.56).abs() < 0.01, "{r}");
        // A converged step that would not have passed the test at its own size (Newton
        // converged on a later, smaller contraction estimate) shrinks the next one.
        assert!(lim(0.3, 1e4).unwrap() < 1.0);
        // Larger contraction or first update, smaller bound.
        assert!(lim(0.2, 1e3).unwrap() < lim(0.1, 1e3).unwrap());
        assert!(lim(0.1, 1e4).unwrap() < lim(0.1, 1e3).unwrap());
        // No bound from one iteration (theta not measured), a Jacobian the next step reuses
        // (theta at most 1e-3) with an ordinary first update, or too few iterations to test.
        assert_eq!(lim(0.0, 1e3), None);
        assert_eq!(lim(1e-3, 1e3), None);
        assert_eq!(Controller::newton_growth_limit(0.1, 1e3, 2, 8.0), None);
    }
}
