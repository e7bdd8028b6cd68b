//! Reference trajectories `xi(t)` with exact derivatives.
//!
//! The tracking DAE of a stabilised Hirschorn step needs `w_i = W_i(d/dt) xi_i` (paper,
//! (2.1b)), that is the reference and its first `deg W_i` derivatives at every time. They are
//! supplied exactly, never by differencing: by closed forms for the ready-made references
//! here, and by symbolic differentiation for references written in the DSL.

use thiserror::Error;

/// Errors of reference evaluation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReferenceError {
    /// More derivatives were requested than the reference provides.
    #[error("reference `{name}` provides derivatives up to order {max}, but order {requested} was requested")]
    OrderTooHigh {
        /// Which reference.
        name: String,
        /// Highest order it provides.
        max: usize,
        /// Order requested.
        requested: usize,
    },
    /// The output buffer has the wrong length.
    #[error("reference buffer has length {found}, expected {expected} ((order + 1) x dimension)")]
    BufferLength {
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A vector reference was built from a number of components different from the outputs.
    #[error("reference has {found} components, but the model has {expected} outputs")]
    Dimension {
        /// Number of outputs.
        expected: usize,
        /// Number of components.
        found: usize,
    },
}

/// A vector reference `xi(t)` (one component per output) with exact derivatives.
pub trait Reference {
    /// Number of components.
    fn dimension(&self) -> usize;

    /// The highest derivative order available (`usize::MAX` for closed forms).
    fn max_order(&self) -> usize {
        usize::MAX
    }

    /// Write `xi^(k)(t)` for `k = 0..=order` into `out`, component-major within each order:
    /// `out[k * dimension + i] = d^k xi_i / dt^k`. `out` must have length
    /// `(order + 1) * dimension`.
    fn derivatives(&self, t: f64, order: usize, out: &mut [f64]) -> Result<(), ReferenceError>;
}

/// A shared reference is a reference: the controller and a preliminary feedback taken about
/// the reference ([`crate::prefeedback::ReferenceNominal`]) can follow the same one.
impl<R: Reference + ?Sized> Reference for std::sync::Arc<R> {
    fn dimension(&self) -> usize {
        (**self).dimension()
    }

    fn max_order(&self) -> usize {
        (**self).max_order()
    }

    fn derivatives(&self, t: f64, order: usize, out: &mut [f64]) -> Result<(), ReferenceError> {
        (**self).derivatives(t, order, out)
    }
}

/// A scalar reference with exact derivatives of every order.
pub trait ScalarReference {
    /// `d^k xi / dt^k` at `t`.
    fn derivative(&self, t: f64, k: usize) -> f64;

    /// Add `d^k xi / dt^k` at `t` to `out[k * stride]` for `k = 0..=order` (`out` must have
    /// at least `order * stride + 1` entries). The default calls
    /// [`derivative`](Self::derivative) per order; the closed forms here override it to share
    /// the work between the orders, since the controller asks for all of them at every inner
    /// step.
    fn add_derivatives(&self, t: f64, order: usize, out: &mut [f64], stride: usize) {
        for k in 0..=order {
            out[k * stride] += self.derivative(t, k);
        }
    }
}

/// `xi(t) = value`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constant(pub f64);

impl ScalarReference for Constant {
    fn derivative(&self, _t: f64, k: usize) -> f64 {
        if k == 0 {
            self.0
        } else {
            0.0
        }
    }

    fn add_derivatives(&self, _t: f64, order: usize, out: &mut [f64], stride: usize) {
        // The higher orders add a zero, as `derivative` gives (which turns a -0 into +0).
        out[0] += self.0;
        for k in 1..=order {
            out[k * stride] += 0.0;
        }
    }
}

/// `xi(t) = sum_j c_j t^j`, coefficients lowest power first.
#[derive(Debug, Clone, PartialEq)]
pub struct Polynomial(pub Vec<f64>);

impl Polynomial {
    /// Horner on the k-th derivative's coefficients `c_j * j!/(j-k)!`.
    #[inline]
    fn horner(&self, t: f64, k: usize) -> f64 {
        let mut acc = 0.0;
        for j in (k..self.0.len()).rev() {
            let falling: f64 = ((j - k + 1)..=j).map(|v| v as f64).product();
            acc = acc * t + self.0[j] * falling;
        }
        acc
    }
}

impl ScalarReference for Polynomial {
    fn derivative(&self, t: f64, k: usize) -> f64 {
        self.horner(t, k)
    }

    fn add_derivatives(&self, t: f64, order: usize, out: &mut [f64], stride: usize) {
        for k in 0..=order {
            out[k * stride] += self.horner(t, k);
        }
    }
}

/// `xi(t) = offset + amplitude * sin(omega t + phase)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    /// Constant offset.
    pub offset: f64,
    /// Amplitude.
    pub amplitude: f64,
    /// Angular frequency, in rad/s.
    pub omega: f64,
    /// Phase, in rad.
    pub phase: f64,
}

impl Sinusoid {
    /// `d^k xi / dt^k` for `k = 0..=order`, in order, from one `sin`/`cos` pair:
    /// `d^k/dt^k sin(w t + p)` cycles through `w^k (sin, cos, -sin, -cos)(w t + p)`.
    fn each_derivative(&self, t: f64, order: usize, mut f: impl FnMut(usize, f64)) {
        let (sin, cos) = (self.omega * t + self.phase).sin_cos();
        let mut scale = self.amplitude;
        for k in 0..=order {
            let v = scale * [sin, cos, -sin, -cos][k % 4];
            f(k, if k == 0 { self.offset + v } else { v });
            scale *= self.omega;
        }
    }
}

/// `xi(t) = scale * (t atan t - ln(1 + t^2) / 2)`, the integral of `scale * atan t` from 0,
/// used for the heading reference of the paper's wheel example (Section 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtanIntegral {
    /// Factor in front of the integral.
    pub scale: f64,
}

impl AtanIntegral {
    /// `d^k xi / dt^k` for `k = 0..=order`, in order. From the second derivative on,
    /// `atan^(n)(t) = (-1)^(n-1) (n-1)! Im(z^n)` with `z = 1 / (t - i) = (t + i) / (1 + t^2)`
    /// (the closed form `sin(n (pi/2 - atan t)) / (1 + t^2)^(n/2)` of the same, by
    /// `t + i = sqrt(1 + t^2) e^(i (pi/2 - atan t))`), so every order costs a complex
    /// multiplication instead of a `sin`, an `atan` and a `powf`.
    fn each_derivative(&self, t: f64, order: usize, mut f: impl FnMut(usize, f64)) {
        let atan = t.atan();
        f(0, self.scale * (t * atan - 0.5 * (t * t).ln_1p()));
        if order == 0 {
            return;
        }
        f(1, self.scale * atan);
        let d = 1.0 + t * t;
        let (zr, zi) = (t / d, 1.0 / d);
        // z^n and (-1)^(n-1) (n-1)! for n = k - 1.
        let (mut pr, mut pi) = (zr, zi);
        let mut factor = 1.0;
        for k in 2..=order {
            let n = k - 1;
            f(k, self.scale * factor * pi);
            (pr, pi) = (pr * zr - pi * zi, pr * zi + pi * zr);
            factor *= -(n as f64);
        }
    }
}

/// `ScalarReference` for a type whose `each_derivative(t, order, f)` hands every derivative of
/// orders `0..=order` to `f` in one pass.
macro_rules! scalar_reference_by_each_derivative {
    ($($ty:ty),*) => {$(
        impl ScalarReference for $ty {
            fn derivative(&self, t: f64, k: usize) -> f64 {
                let mut value = 0.0;
                self.each_derivative(t, k, |j, v| {
                    if j == k {
                        value = v;
                    }
                });
                value
            }

            fn add_derivatives(&self, t: f64, order: usize, out: &mut [f64], stride: usize) {
                self.each_derivative(t, order, |k, v| out[k * stride] += v);
            }
        }
    )*};
}

scalar_reference_by_each_derivative!(Sinusoid, AtanIntegral);

/// The sum of scalar references.
pub struct Sum(pub Vec<Box<dyn ScalarReference + Send + Sync>>);

impl ScalarReference for Sum {
    fn derivative(&self, t: f64, k: usize) -> f64 {
        self.0.iter().map(|r| r.derivative(t, k)).sum()
    }

    fn add_derivatives(&self, t: f64, order: usize, out: &mut [f64], stride: usize) {
        for r in &self.0 {
            r.add_derivatives(t, order, out, stride);
        }
    }
}

/// A vector reference made of one scalar reference per output.
pub struct Components(pub Vec<Box<dyn ScalarReference + Send + Sync>>);

impl Components {
    /// One scalar reference per output of a model with `outputs` outputs.
    pub fn new(
        outputs: usize,
        components: Vec<Box<dyn ScalarReference + Send + Sync>>,
    ) -> Result<Self, ReferenceError> {
        if components.len() != outputs {
            return Err(ReferenceError::Dimension {
                expected: outputs,
                found: components.len(),
            });
        }
        Ok(Self(components))
    }
}

impl Reference for Components {
    fn dimension(&self) -> usize {
        self.0.len()
    }

    fn derivatives(&self, t: f64, order: usize, out: &mut [f64]) -> Result<(), ReferenceError> {
        let m = self.0.len();
        check_buffer(m, order, out)?;
        out.fill(0.0);
        for (i, r) in self.0.iter().enumerate() {
            r.add_derivatives(t, order, &mut out[i..], m);
        }
        Ok(())
    }
}

/// Check the length of a derivative buffer for `order` and `dimension`.
pub fn check_buffer(dimension: usize, order: usize, out: &[f64]) -> Result<(), ReferenceError> {
    let expected = (order + 1) * dimension;
    if out.len() != expected {
        return Err(ReferenceError::BufferLength {
            expected,
            found: out.len(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Derivative k of `r` by a high-order central difference of derivative k-1.
    fn fd(r: &dyn ScalarReference, t: f64, k: usize) -> f64 {
        let h = 1e-3;
        let f = |s: f64| r.derivative(s, k - 1);
        (-f(t + 2.0 * h) + 8.0 * f(t + h) - 8.0 * f(t - h) + f(t - 2.0 * h)) / (12.0 * h)
    }

    fn check(r: &dyn ScalarReference) {
        for &t in &[-1.3, 0.0, 0.4, 2.5] {
            for k in 1..6 {
                let (exact, approx) = (r.derivative(t, k), fd(r, t, k));
                assert!(
                    (exact - approx).abs() < 1e-7 * (1.0 + exact.abs()),
                    "k = {k}, t = {t}: exact {exact}, differences {approx}"
                );
            }
        }
    }

    #[test]
    fn closed_forms_match_differences() {
        check(&Polynomial(vec![1.0, -2.0, 0.5, 0.25, -0.1]));
        check(&Sinusoid {
            offset: 1.5,
            amplitude: 0.1,
            omega: 1.3,
            phase: 0.2,
        });
        check(&AtanIntegral { scale: -0.5 });
        check(&Sum(vec![
            Box::new(Constant(2.0)),
            Box::new(AtanIntegral { scale: 1.0 }),
        ]));
    }

    #[test]
    fn all_orders_at_once_agree_with_each_order() {
        let sum = Sum(vec![
            Box::new(Constant(2.0)),
            Box::new(Polynomial(vec![1.0, -2.0, 0.5])),
            Box::new(Sinusoid {
                offset: 0.3,
                amplitude: 0.1,
                omega: 1.3,
                phase: 0.2,
            }),
            Box::new(AtanIntegral { scale: -0.5 }),
        ]);
        for &t in &[-3.1, -0.2, 0.0, 0.7, 12.0] {
            let order = 7;
            let stride = 3;
            let mut out = vec![0.0; order * stride + 1];
            sum.add_derivatives(t, order, &mut out, stride);
            for k in 0..=order {
                let one = sum.derivative(t, k);
                assert!(
                    (out[k * stride] - one).abs() <= 1e-15 * (1.0 + one.abs()),
                    "t = {t}, k = {k}: {} against {one}",
                    out[k * stride]
                );
            }
        }
    }

    #[test]
    fn atan_derivatives_match_the_trigonometric_closed_form() {
        // atan^(n)(t) = (-1)^(n-1) (n-1)! sin(n (pi/2 - atan t)) / (1 + t^2)^(n/2).
        let r = AtanIntegral { scale: 1.0 };
        for &t in &[-5.0_f64, -0.4, 0.0, 0.3, 2.0, 40.0] {
            for k in 2..9_usize {
                let n = k - 1;
                let fact: f64 = (1..n).map(|v| v as f64).product();
                let sign = if (n - 1).is_multiple_of(2) { 1.0 } else { -1.0 };
                // The size of the terms (the sine aside): the scale of the round-off.
                let size = fact / (1.0 + t * t).powf(n as f64 / 2.0);
                let want =
                    sign * size * (n as f64 * (std::f64::consts::FRAC_PI_2 - f64::atan(t))).sin();
                let got = r.derivative(t, k);
                assert!(
                    (got - want).abs() <= 1e-13 * size,
                    "t = {t}, k = {k}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn atan_integral_values() {
        let r = AtanIntegral { scale: 1.0 };
        assert_eq!(r.derivative(0.0, 0), 0.0);
        let t: f64 = 2.0;
        assert!((r.derivative(t, 0) - (t * t.atan() - 0.5 * (1.0 + t * t).ln())).abs() < 1e-15);
        assert!((r.derivative(t, 2) - 1.0 / (1.0 + t * t)).abs() < 1e-15);
        assert!((r.derivative(t, 3) + 2.0 * t / (1.0 + t * t).powi(2)).abs() < 1e-15);
    }

    #[test]
    fn vector_reference_layout_and_errors() {
        let r = Components::new(
            2,
            vec![
                Box::new(Constant(1.0)),
                Box::new(Polynomial(vec![0.0, 3.0])),
            ],
        )
        .unwrap();
        let mut out = [0.0; 4];
        r.derivatives(2.0, 1, &mut out).unwrap();
        assert_eq!(out, [1.0, 6.0, 0.0, 3.0]);
        assert!(matches!(
            r.derivatives(2.0, 2, &mut out),
            Err(ReferenceError::BufferLength {
                expected: 6,
                found: 4
            })
        ));
        assert!(Components::new(3, vec![Box::new(Constant(1.0))]).is_err());
    }
}
