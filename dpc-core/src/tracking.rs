//! The tracking DAE of stabilised Hirschorn steps (paper, Section 2, (2.1)).
//!
//! `dpc::model!` with a `tracking` section generates a second type: the DAE
//! `G(X', X, Z, U, t) = 0` made of the plant equations and, per output `i`,
//! `W_i(d/dt) h_i(X, t) - w_i = 0`, with the unknowns `(X, [Z; U])` (the plant's inputs are
//! algebraic unknowns) and the inputs `w_i = W_i(d/dt) xi_i(t)`. This module holds the trait
//! it implements on top of [`DaeModel`] and the computation of `w` from a [`Reference`].
//!
//! The *degree* of each `W_i` is fixed at compile time (it decides which total derivatives
//! of `h_i` are generated); the coefficients are read from the tracking value at run time, so
//! the roots of `W_i(s) = prod_k (s + a_k)` can be changed with [`TrackingDae::set_w_roots`].
//!
//! # Example
//! A mass on a spring whose position follows `sin t`: the tracking DAE's unknowns are the
//! plant's states and, as algebraic unknowns, its inputs; its inputs are the `w` computed from
//! the reference. On the exact inverse motion (`x = sin t`, `v = cos t`,
//! `f = m x'' + k x = 3 sin t`) its residual vanishes.
//!
//! ```
//! use dpc::core::{DaeModel, TrackingDae};
//!
//! dpc::model! {
//!     /// A mass on a spring, pushed by `f`.
//!     Mass {
//!         params { m = 1.0, k = 4.0 }
//!         states { x, v }
//!         inputs { f }
//!         equations { der(x) = v; m * der(v) == f - k * x; }
//!         outputs { x }
//!         references { x = sin(t) }
//!         tracking MassTracking { x: [5.0] }
//!     }
//! }
//!
//! let tracking = MassTracking::default();
//! let s = tracking.structure();
//! assert_eq!((s.n_states(), s.n_algebraic(), s.n_inputs()), (2, 1, 1)); // X = (x, v), U = f
//! assert_eq!(tracking.relative_degrees(), &[Some(2)]);
//! assert_eq!(tracking.remaining_relative_degree(), Some(1)); // one step applied: nu = 1
//!
//! let t = 0.7_f64;
//! let mut scratch = [0.0; 4];
//! let mut w = [0.0];
//! tracking.tracking_inputs(&MassReference::default(), t, &mut scratch, &mut w)?;
//! let (x, xdot, u) = ([t.sin(), t.cos()], [t.cos(), -t.sin()], [3.0 * t.sin()]);
//! let mut g = [1.0; 3];
//! tracking.residual(t, &x, &xdot, &u, &w, &mut g);
//! assert!(g.iter().all(|r| r.abs() < 1e-12), "{g:?}");
//! # Ok::<(), dpc::core::reference::ReferenceError>(())
//! ```

use crate::model::DaeModel;
use crate::reference::{Reference, ReferenceError};
use thiserror::Error;

/// Why a `W_i` given at run time was refused; the tracking DAE is then unchanged.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TrackingError {
    /// The output index is out of range.
    #[error("tracking DAE `{model}` has {outputs} output(s); there is no output {output}")]
    UnknownOutput {
        /// The tracking DAE's name.
        model: String,
        /// The index asked for.
        output: usize,
        /// Number of outputs.
        outputs: usize,
    },
    /// The number of roots differs from the compiled degree of `W_i`.
    #[error(
        "W for output `{output}` of `{model}` has degree {expected}, fixed at compile time, but {found} root(s) were given; more or fewer Hirschorn steps need a change of the model's `tracking` section"
    )]
    WrongDegree {
        /// The tracking DAE's name.
        model: String,
        /// The output's name.
        output: String,
        /// The compiled degree.
        expected: usize,
        /// The number of roots given.
        found: usize,
    },
    /// A root or coefficient is NaN or infinite.
    #[error("W for output `{output}` of `{model}`: entry {index} is {value}, not a finite number")]
    NonFinite {
        /// The tracking DAE's name.
        model: String,
        /// The output's name.
        output: String,
        /// Position of the entry in the slice given.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A factor `s + a` with `a < 0`: a root of `W_i` in the right half plane, so the step
    /// would amplify the tracking error instead of damping it.
    #[error(
        "W for output `{output}` of `{model}`: a = {value} puts a root of W(s) = prod (s + a) at s = {} in the right half plane; W must be stable: a >= 0 (a = 0 is a plain derivative)",
        -value
    )]
    UnstableRoot {
        /// The tracking DAE's name.
        model: String,
        /// The output's name.
        output: String,
        /// The offending `a`.
        value: f64,
    },
    /// Coefficients of the wrong length (not `deg W_i + 1`).
    #[error(
        "W for output `{output}` of `{model}` needs {expected} coefficients (degree {}, fixed at compile time, plus the leading 1), but {found} were given",
        expected - 1
    )]
    WrongLength {
        /// The tracking DAE's name.
        model: String,
        /// The output's name.
        output: String,
        /// `deg W_i + 1`.
        expected: usize,
        /// The number given.
        found: usize,
    },
    /// The leading coefficient is not 1.
    #[error("W for output `{output}` of `{model}` must be monic (leading coefficient 1), found {leading}")]
    NotMonic {
        /// The tracking DAE's name.
        model: String,
        /// The output's name.
        output: String,
        /// The leading coefficient given.
        leading: f64,
    },
    /// The coefficients give a polynomial with a root in the open right half plane or a
    /// non-zero root on the imaginary axis.
    #[error(
        "W for output `{output}` of `{model}` with coefficients {coefficients:?} (lowest power first) is not stable: apart from roots at s = 0 its roots must lie in the open left half plane"
    )]
    Unstable {
        /// The tracking DAE's name.
        model: String,
        /// The output's name.
        output: String,
        /// The coefficients given.
        coefficients: Vec<f64>,
    },
}

/// A tracking DAE generated from a model's `tracking` section.
pub trait TrackingDae: DaeModel {
    /// The plant the tracking DAE was generated from.
    type Plant: DaeModel<Params = Self::Params>;

    /// Per output, the compiled default coefficients of `W_i(s)` from the model's `tracking`
    /// section, lowest power first (monic: the last is 1); empty when
    /// `output >= n_outputs`. An output without a step has `[1.0]`. Their lengths fix the
    /// degrees; the values in use are [`w_coefficients`](Self::w_coefficients).
    fn default_w_coefficients(&self, output: usize) -> &[f64];

    /// Per output, the relative degree of the plant output: the number of total time
    /// derivatives after which an input appears, or `None` where it is not defined (an
    /// output the inputs never reach, or a plant whose implicit equations stay structurally
    /// singular with its constraints differentiated).
    fn relative_degrees(&self) -> &[Option<usize>];

    /// The coefficients of `W_i(s)` in use, lowest power first, monic (the last is 1), of
    /// length `deg W_i + 1`; empty when `output >= n_outputs`.
    fn w_coefficients(&self, output: usize) -> &[f64];

    /// Replace the coefficients of `W_i(s)`, lowest power first. They must be finite, monic,
    /// of the compiled length `deg W_i + 1`, and give a stable `W_i`: roots at `s = 0` (plain
    /// derivatives) are allowed, all others must lie in the open left half plane (checked by
    /// [`check_w_coefficients`]). Prefer [`set_w_roots`](Self::set_w_roots) for the DSL's
    /// form.
    ///
    /// # Errors
    /// [`TrackingError`] saying what is wrong; the tracking DAE is then unchanged.
    fn set_w_coefficients(
        &mut self,
        output: usize,
        coefficients: &[f64],
    ) -> Result<(), TrackingError>;

    /// Set `W_i(s) = prod_k (s + a_k)` from the `a_k` (`roots`, as in the DSL: the negated
    /// roots), e.g. `[3.0]` for `s + 3`. The number of `a_k` must be the compiled degree of
    /// `W_i`; each must be finite and `>= 0` (`0` is a plain derivative).
    ///
    /// Allocates a vector of `deg W_i + 1` coefficients: call it when setting up, not per
    /// step.
    ///
    /// # Errors
    /// [`TrackingError::UnknownOutput`], [`TrackingError::WrongDegree`],
    /// [`TrackingError::NonFinite`] or [`TrackingError::UnstableRoot`]; the tracking DAE is
    /// then unchanged.
    fn set_w_roots(&mut self, output: usize, roots: &[f64]) -> Result<(), TrackingError> {
        let name = output_name(self, output)?;
        let degree = self.default_w_coefficients(output).len() - 1;
        if roots.len() != degree {
            return Err(TrackingError::WrongDegree {
                model: self.structure().name.to_string(),
                output: name,
                expected: degree,
                found: roots.len(),
            });
        }
        for (index, &value) in roots.iter().enumerate() {
            if !value.is_finite() {
                return Err(TrackingError::NonFinite {
                    model: self.structure().name.to_string(),
                    output: name,
                    index,
                    value,
                });
            }
            if value < 0.0 {
                return Err(TrackingError::UnstableRoot {
                    model: self.structure().name.to_string(),
                    output: name,
                    value,
                });
            }
        }
        self.set_w_coefficients(output, &monic_from_negated_roots(roots))
    }

    /// Number of plant inputs: the trailing algebraic unknowns of the tracking DAE.
    fn plant_inputs(&self) -> usize {
        self.structure().n_algebraic() - self.plant_algebraic()
    }

    /// Number of algebraic unknowns before the plant's inputs: the plant's own, then the
    /// higher derivatives of states that steps through implicit equations add (the plant's
    /// inputs follow them).
    fn plant_algebraic(&self) -> usize;

    /// Per output, how many derivatives of the reference `w_i` needs (`deg W_i`, fixed at
    /// compile time).
    fn reference_orders(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.structure().n_outputs()).map(|i| self.default_w_coefficients(i).len() - 1)
    }

    /// The largest relative degree left after the steps, `max_i (r_i - deg W_i)`: the
    /// nilpotency index `nu` of the linearised pencil, which decides how many implicit-Euler
    /// controls are unusable after a restart (paper, Section 3). `None` if some relative
    /// degree is undefined.
    fn remaining_relative_degree(&self) -> Option<usize> {
        let mut nu = 0;
        for (r, w) in self.relative_degrees().iter().zip(self.reference_orders()) {
            nu = nu.max(r.as_ref()?.saturating_sub(w));
        }
        Some(nu)
    }

    /// The tracking inputs `w_i = sum_k c_ik xi_i^(k)(t)` from a reference, with the
    /// coefficients `c_ik` in use ([`w_coefficients`](Self::w_coefficients)), using `scratch`
    /// of length at least `(max_order + 1) * n_outputs` for the derivatives.
    fn tracking_inputs<R: Reference + ?Sized>(
        &self,
        reference: &R,
        t: f64,
        scratch: &mut [f64],
        w: &mut [f64],
    ) -> Result<(), ReferenceError> {
        let m = self.structure().n_outputs();
        if reference.dimension() != m {
            return Err(ReferenceError::Dimension {
                expected: m,
                found: reference.dimension(),
            });
        }
        let order = self.reference_orders().max().unwrap_or(0);
        if order > reference.max_order() {
            return Err(ReferenceError::OrderTooHigh {
                name: "reference".into(),
                max: reference.max_order(),
                requested: order,
            });
        }
        let len = (order + 1) * m;
        if scratch.len() < len || w.len() != m {
            return Err(ReferenceError::BufferLength {
                expected: len,
                found: scratch.len().min(w.len()),
            });
        }
        let derivs = &mut scratch[..len];
        reference.derivatives(t, order, derivs)?;
        for (i, wi) in w.iter_mut().enumerate() {
            *wi = self
                .w_coefficients(i)
                .iter()
                .enumerate()
                .map(|(k, c)| c * derivs[k * m + i])
                .sum();
        }
        Ok(())
    }
}

fn output_name<T: TrackingDae + ?Sized>(
    tracking: &T,
    output: usize,
) -> Result<String, TrackingError> {
    let structure = tracking.structure();
    match structure.outputs.get(output) {
        Some(name) => Ok(name.to_string()),
        None => Err(TrackingError::UnknownOutput {
            model: structure.name.to_string(),
            output,
            outputs: structure.n_outputs(),
        }),
    }
}

/// Coefficients of `prod_k (s + a_k)` from the `a_k`, lowest power first (monic).
pub fn monic_from_negated_roots(roots: &[f64]) -> Vec<f64> {
    let mut c = vec![0.0; roots.len() + 1];
    c[0] = 1.0;
    for (n, &a) in roots.iter().enumerate() {
        // Multiply the degree-n polynomial in c[..=n] by (s + a), from the top down.
        for k in (0..=n + 1).rev() {
            let shifted = if k > 0 { c[k - 1] } else { 0.0 };
            let kept = if k <= n { c[k] } else { 0.0 };
            c[k] = shifted + a * kept;
        }
    }
    c
}

/// The `a_k` of a monic `prod_k (s + a_k)` given by its coefficients lowest power first (the
/// inverse of [`monic_from_negated_roots`]), sorted ascending; `None` when a root is complex
/// (the linear analysis takes real roots only) or there are no coefficients. The roots are
/// the eigenvalues of the companion matrix, computed by a Schur decomposition.
pub fn negated_real_roots(coefficients: &[f64]) -> Option<Vec<f64>> {
    let n = coefficients.len().checked_sub(1)?;
    if n == 0 {
        return Some(Vec::new());
    }
    let lead = coefficients[n];
    let companion = nalgebra::DMatrix::from_fn(n, n, |i, j| {
        if j == n - 1 {
            -coefficients[i] / lead
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let scale = coefficients.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
    let mut roots = Vec::with_capacity(n);
    for z in companion.complex_eigenvalues().iter() {
        if !(z.re.is_finite() && z.im.is_finite()) || z.im.abs() > 1e-9 * (1.0 + scale) {
            return None;
        }
        roots.push(-z.re);
    }
    roots.sort_by(f64::total_cmp);
    Some(roots)
}

/// Check coefficients for output `output` of `T` before they are stored: the output exists,
/// the length is the compiled `deg W_i + 1`, all are finite, the leading one is exactly 1,
/// and the polynomial is stable in the sense of the Hirschorn step: after dividing out the
/// roots at `s = 0` (trailing zero coefficients, plain derivatives) the rest is Hurwitz,
/// decided by the Routh array. Generated `set_w_coefficients` calls this.
///
/// # Errors
/// The [`TrackingError`] for the first check that fails.
pub fn check_w_coefficients<T: TrackingDae + ?Sized>(
    tracking: &T,
    output: usize,
    coefficients: &[f64],
) -> Result<(), TrackingError> {
    let name = output_name(tracking, output)?;
    let model = tracking.structure().name.to_string();
    let expected = tracking.default_w_coefficients(output).len();
    if coefficients.len() != expected {
        return Err(TrackingError::WrongLength {
            model,
            output: name,
            expected,
            found: coefficients.len(),
        });
    }
    if let Some((index, &value)) = coefficients
        .iter()
        .enumerate()
        .find(|(_, c)| !c.is_finite())
    {
        return Err(TrackingError::NonFinite {
            model,
            output: name,
            index,
            value,
        });
    }
    let leading = coefficients[expected - 1];
    if leading != 1.0 {
        return Err(TrackingError::NotMonic {
            model,
            output: name,
            leading,
        });
    }
    let zeros = coefficients.iter().take_while(|c| **c == 0.0).count();
    if !is_hurwitz(&coefficients[zeros..]) {
        return Err(TrackingError::Unstable {
            model,
            output: name,
            coefficients: coefficients.to_vec(),
        });
    }
    Ok(())
}

/// Whether the real polynomial with `c` (lowest power first, `c.last() > 0`) has all roots in
/// the open left half plane: all coefficients positive and the first column of the Routh
/// array positive (Routh-Hurwitz criterion).
fn is_hurwitz(c: &[f64]) -> bool {
    if c.iter().any(|v| *v <= 0.0) {
        return false;
    }
    let n = c.len() - 1;
    if n <= 2 {
        // Positive coefficients are necessary and sufficient up to degree 2.
        return true;
    }
    // Rows of the Routh array, highest power first: c_n, c_{n-2}, ... and c_{n-1}, c_{n-3}, ...
    let mut upper: Vec<f64> = (0..=n).rev().step_by(2).map(|k| c[k]).collect();
    let mut lower: Vec<f64> = (0..n).rev().step_by(2).map(|k| c[k]).collect();
    for _ in 0..n - 1 {
        let pivot = lower[0];
        if pivot <= 0.0 {
            return false;
        }
        let next: Vec<f64> = (0..upper.len() - 1)
            .map(|j| {
                let a = upper.get(j + 1).copied().unwrap_or(0.0);
                let b = lower.get(j + 1).copied().unwrap_or(0.0);
                a - upper[0] / pivot * b
            })
            .collect();
        upper = std::mem::replace(&mut lower, next);
    }
    // The last row, of the power s^0.
    lower[0] > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_round_trip_through_coefficients() {
        let c = monic_from_negated_roots(&[2.0, 3.0]);
        assert_eq!(c, vec![6.0, 5.0, 1.0]);
        let r = negated_real_roots(&c).unwrap();
        assert!(
            (r[0] - 2.0).abs() < 1e-12 && (r[1] - 3.0).abs() < 1e-12,
            "{r:?}"
        );
        assert_eq!(negated_real_roots(&[5.0, 1.0]).unwrap(), vec![5.0]);
        // s^2 + 1 has imaginary roots.
        assert!(negated_real_roots(&[1.0, 0.0, 1.0]).is_none());
        assert!(negated_real_roots(&[]).is_none());
    }

    #[test]
    fn coefficients_from_negated_roots() {
        assert_eq!(monic_from_negated_roots(&[]), vec![1.0]);
        assert_eq!(monic_from_negated_roots(&[5.0]), vec![5.0, 1.0]);
        assert_eq!(monic_from_negated_roots(&[2.0, 3.0]), vec![6.0, 5.0, 1.0]);
        assert_eq!(monic_from_negated_roots(&[0.0, 0.0]), vec![0.0, 0.0, 1.0]);
        assert_eq!(
            monic_from_negated_roots(&[1.0, 1.0, 1.0]),
            vec![1.0, 3.0, 3.0, 1.0]
        );
    }

    #[test]
    fn routh_hurwitz_on_known_polynomials() {
        // Products of stable factors.
        for roots in [
            &[1.0][..],
            &[2.0, 3.0],
            &[1.0, 1.0, 1.0],
            &[0.5, 4.0, 9.0, 20.0],
        ] {
            assert!(is_hurwitz(&monic_from_negated_roots(roots)), "{roots:?}");
        }
        // (s^2 + 0.2 s + 4)(s + 3): complex stable roots.
        assert!(is_hurwitz(&[12.0, 4.6, 3.2, 1.0]));
        // s^3 + s^2 + s + 10: positive coefficients, but 1 * 1 < 10 (two roots in the RHP).
        assert!(!is_hurwitz(&[10.0, 1.0, 1.0, 1.0]));
        // s^2 + 1: roots on the imaginary axis.
        assert!(!is_hurwitz(&[1.0, 0.0, 1.0]));
        // (s - 1)(s + 2).
        assert!(!is_hurwitz(&[-2.0, 1.0, 1.0]));
        // (s^2 + 1)(s + 1) = s^3 + s^2 + s + 1: a zero in the Routh column.
        assert!(!is_hurwitz(&[1.0, 1.0, 1.0, 1.0]));
        // Degree 0 and 1.
        assert!(is_hurwitz(&[1.0]));
        assert!(is_hurwitz(&[0.5, 1.0]));
    }

    #[test]
    fn products_of_stable_real_factors_pass_the_routh_test() {
        // Deterministic pseudo-random roots over four decades, degrees 1 to 6.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let degree = 1 + (next() * 6.0) as usize;
            let roots: Vec<f64> = (0..degree)
                .map(|_| 10f64.powf(4.0 * next() - 2.0))
                .collect();
            assert!(is_hurwitz(&monic_from_negated_roots(&roots)), "{roots:?}");
        }
    }
}
