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
}
