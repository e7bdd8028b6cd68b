//! Sampled-data prediction: DPC's limit law held for `h` seconds by a zero-order hold.
//!
//! The analysis of Section 3 takes `h -> 0`: at every sample DPC computes
//! `u(t_k) = K_J x(t_k) + R_xi(d/dt) xi(t_k)` (3.10), or, after a preliminary feedback,
//! `v(t_k) = K_J' x(t_k) + ...` with `u = K_n x + v`. A real controller holds that value for
//! the sampling period `h`, and the paper observes on the wheel (Section 5) that the loop
//! diverges beyond some `h`. For the linearisation `x' = A x + B u` this is a sampled-data
//! loop whose stability is decided by the spectral radius of its transition matrix over one
//! period (the reference terms are an input and do not change it):
//!
//! * [`Hold::Input`]: the whole `u_k = (K_n + K_J') x_k` is held:
//!   `x_(k+1) = (Phi + Gamma (K_n + K_J')) x_k` with `Phi = e^(A h)`,
//!   `Gamma = int_0^h e^(A s) ds B`;
//! * [`Hold::Correction`]: `u = K_n x + v` acts continuously and only `v_k = K_J' x_k` is
//!   held: the same with `A` replaced by `A + B K_n` and the held gain `K_J'`.
//!
//! Without a preliminary feedback both variants hold `u_k = K_J x_k`. `Phi` and `Gamma` come
//! from one matrix exponential of `[[A, B], [0, 0]] h` (Van Loan's block form; nalgebra's
//! scaling-and-squaring Padé approximant), and the spectral radius from the eigenvalues of the
//! transition matrix (faer's real Schur form). [`SampledLoop::critical_period`] locates the
//! first period at which the spectral radius reaches 1.

use nalgebra::DMatrix;

use crate::error::InvalidOption;
use crate::linear_analysis::{eigenvalues, Analysis, LinearError, LinearSystem};
pub use crate::simulate::Hold;

/// The linearised plant under DPC's limit law with a zero-order hold.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledLoop {
    /// The matrix of the part that acts continuously: `A`, or `A + B K_n` when only the
    /// correction is held.
    pub a_continuous: DMatrix<f64>,
    /// `B`.
    pub b: DMatrix<f64>,
    /// The gain whose value is held: `K_J`, `K_n + K_J'` or `K_J'`.
    pub k_held: DMatrix<f64>,
}

/// Where a sampled loop first loses stability as `h` grows.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CriticalPeriod {
    /// The loop is unstable already for the smallest period tried (the continuous limit law
    /// is unstable, or nearly so).
    UnstableAtAnyPeriod,
    /// The spectral radius reaches 1 at this period (within the requested tolerance); every
    /// smaller period tried was stable.
    At(f64),
    /// Stable at every period tried up to and including this one.
    StableUpTo(f64),
}

/// Spectral radius below which a transition matrix counts as stable.
const STABLE_RADIUS: f64 = 1.0 - 1e-12;

impl SampledLoop {
    /// The loop from the gains: `k_n` is the preliminary feedback if one is applied, `k_j` the
    /// DPC law of the (pre-fed-back) system.
    ///
    /// # Errors
    /// [`LinearError::DimensionMismatch`] when the shapes do not fit `A` (`n x n`),
    /// `B` (`n x m`) and gains `m x n`; [`LinearError::NonFinite`] for NaN or infinite entries.
    pub fn new(
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        k_n: Option<&DMatrix<f64>>,
        k_j: &DMatrix<f64>,
        hold: Hold,
    ) -> Result<Self, LinearError> {
        let (n, m) = (a.nrows(), b.ncols());
        let shape = |what: &str, x: &DMatrix<f64>, rows: usize, cols: usize| {
            if x.shape() == (rows, cols) {
                Ok(())
            } else {
                Err(LinearError::DimensionMismatch {
                    what: format!(
                        "{what} is {}x{}, expected {rows}x{cols} (A {}x{}, B {}x{})",
                        x.nrows(),
                        x.ncols(),
                        a.nrows(),
                        a.ncols(),
                        b.nrows(),
                        b.ncols()
                    ),
                })
            }
        };
        shape("A", a, n, n)?;
        shape("B", b, n, m)?;
        shape("K_J", k_j, m, n)?;
        if let Some(k) = k_n {
            shape("K_n", k, m, n)?;
        }
        let named = [
            ("A", Some(a)),
            ("B", Some(b)),
            ("K_J", Some(k_j)),
            ("K_n", k_n),
        ];
        for (matrix, x) in named {
            let Some(x) = x else { continue };
            for col in 0..x.ncols() {
                for row in 0..x.nrows() {
                    let value = x[(row, col)];
                    if !value.is_finite() {
                        return Err(LinearError::NonFinite {
                            matrix,
                            row,
                            col,
                            value,
                        });
                    }
                }
            }
        }
        let (a_continuous, k_held) = match (k_n, hold) {
            (None, _) => (a.clone(), k_j.clone()),
            (Some(k_n), Hold::Input) => (a.clone(), k_n + k_j),
            (Some(k_n), Hold::Correction) => (a + b * k_n, k_j.clone()),
        };
        Ok(Self {
            a_continuous,
            b: b.clone(),
            k_held,
        })
    }

    /// The loop DPC gives on `sys` according to `analysis` (of the same system): with the
    /// preliminary feedback `K_n` and `K_J'` when the analysis built them, else plain `K_J`.
    ///
    /// # Errors
    /// As [`SampledLoop::new`].
    pub fn from_analysis(
        sys: &LinearSystem,
        analysis: &Analysis,
        hold: Hold,
    ) -> Result<Self, LinearError> {
        match (&analysis.k_n, &analysis.k_j_prefeedback) {
            (Some(k_n), Some(k_j)) => Self::new(&sys.a, &sys.b, Some(k_n), k_j, hold),
            _ => Self::new(&sys.a, &sys.b, None, &analysis.k_j, hold),
        }
    }

    /// Eigenvalues of the continuous closed loop `A_c + B K_held`, the limit `h -> 0`.
    ///
    /// # Errors
    /// [`LinearError::NoConvergence`] if the eigenvalue iteration fails.
    pub fn continuous_eigenvalues(&self) -> Result<Vec<nalgebra::Complex<f64>>, LinearError> {
        eigenvalues(&(&self.a_continuous + &self.b * &self.k_held))
    }

    /// `Phi = e^(A_c h)` and `Gamma = int_0^h e^(A_c s) ds B` from one exponential of the
    /// block matrix `[[A_c, B], [0, 0]] h`.
    ///
    /// # Errors
    /// [`LinearError::NonFinite`] when the exponential overflows (for a huge `h ||A||`).
    pub fn discretize(&self, h: f64) -> Result<(DMatrix<f64>, DMatrix<f64>), LinearError> {
        let (n, m) = (self.b.nrows(), self.b.ncols());
        let mut block = DMatrix::zeros(n + m, n + m);
        block
            .view_mut((0, 0), (n, n))
            .copy_from(&(&self.a_continuous * h));
        block.view_mut((0, n), (n, m)).copy_from(&(&self.b * h));
        let e = block.exp();
        if let Some((k, &value)) = e.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(LinearError::NonFinite {
                matrix: "exp([[A, B], [0, 0]] h)",
                row: k % (n + m),
                col: k / (n + m),
                value,
            });
        }
        Ok((
            e.view((0, 0), (n, n)).into_owned(),
            e.view((0, n), (n, m)).into_owned(),
        ))
    }

    /// The transition matrix over one period, `Phi + Gamma K_held`.
    ///
    /// # Errors
    /// As [`SampledLoop::discretize`]; [`LinearError::InvalidOption`] for `h <= 0` or NaN.
    pub fn transition(&self, h: f64) -> Result<DMatrix<f64>, LinearError> {
        InvalidOption::positive("h", h)?;
        let (phi, gamma) = self.discretize(h)?;
        Ok(phi + gamma * &self.k_held)
    }

    /// The spectral radius of [`transition`](Self::transition): the loop is stable at `h`
    /// iff it is below 1.
    ///
    /// # Errors
    /// As [`SampledLoop::transition`], and [`LinearError::NoConvergence`].
    pub fn spectral_radius(&self, h: f64) -> Result<f64, LinearError> {
        let ev = eigenvalues(&self.transition(h)?)?;
        Ok(ev.iter().map(|z| z.norm()).fold(0.0, f64::max))
    }

    /// The first period at which the loop loses stability: periods `h_max k / samples`,
    /// `k = 1..=samples`, are tried in increasing order and the first unstable one is refined
    /// by bisection against its stable predecessor until the bracket is below
    /// `rel_tol` times the period.
    ///
    /// # Errors
    /// [`LinearError::InvalidOption`] for a non-positive `h_max` or `rel_tol`, or
    /// `samples == 0`; the errors of [`SampledLoop::spectral_radius`].
    pub fn critical_period(
        &self,
        h_max: f64,
        samples: usize,
        rel_tol: f64,
    ) -> Result<CriticalPeriod, LinearError> {
        InvalidOption::positive("h_max", h_max)?;
        InvalidOption::positive("rel_tol", rel_tol)?;
        if samples == 0 {
            return Err(InvalidOption::new("samples", 0.0, "at least 1").into());
        }
        let stable = |h: f64| self.spectral_radius(h).map(|r| r < STABLE_RADIUS);
        let mut previous = None;
        for k in 1..=samples {
            let h = h_max * k as f64 / samples as f64;
            if stable(h)? {
                previous = Some(h);
                continue;
            }
            let Some(mut lo) = previous else {
                return Ok(CriticalPeriod::UnstableAtAnyPeriod);
            };
            let mut hi = h;
            while hi - lo > rel_tol * hi {
                let mid = 0.5 * (lo + hi);
                if stable(mid)? {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Ok(CriticalPeriod::At(0.5 * (lo + hi)));
        }
        Ok(CriticalPeriod::StableUpTo(h_max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `x' = u`, `u_k = -k x_k`: `x_(k+1) = (1 - k h) x_k`, stable iff `h < 2 / k`.
    #[test]
    fn scalar_integrator_loses_stability_at_two_over_k() {
        let a = DMatrix::from_element(1, 1, 0.0);
        let b = DMatrix::from_element(1, 1, 1.0);
        let k = DMatrix::from_element(1, 1, -4.0);
        let l = SampledLoop::new(&a, &b, None, &k, Hold::Input).unwrap();
        assert!((l.spectral_radius(0.1).unwrap() - 0.6).abs() < 1e-14);
        match l.critical_period(2.0, 40, 1e-10).unwrap() {
            CriticalPeriod::At(h) => assert!((h - 0.5).abs() < 1e-9, "{h}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(
            l.critical_period(0.4, 8, 1e-6).unwrap(),
            CriticalPeriod::StableUpTo(0.4)
        );
    }

    /// `x' = a x + u` with `u_k = -k x_k`: `Phi = e^(a h)`, `Gamma = (e^(a h) - 1) / a`.
    #[test]
    fn scalar_exact_discretisation() {
        let (a0, k0, h) = (0.7, -3.0, 0.3);
        let a = DMatrix::from_element(1, 1, a0);
        let b = DMatrix::from_element(1, 1, 1.0);
        let k = DMatrix::from_element(1, 1, k0);
        let l = SampledLoop::new(&a, &b, None, &k, Hold::Input).unwrap();
        let (phi, gamma) = l.discretize(h).unwrap();
        let e = (a0 * h).exp();
        assert!((phi[(0, 0)] - e).abs() < 1e-14);
        assert!((gamma[(0, 0)] - (e - 1.0) / a0).abs() < 1e-14);
        let expected = (e + (e - 1.0) / a0 * k0).abs();
        assert!((l.spectral_radius(h).unwrap() - expected).abs() < 1e-13);
    }

    /// The two holds differ: with the feedback continuous, `x' = (a + k_n) x + v`.
    #[test]
    fn correction_hold_discretises_the_pre_fed_back_plant() {
        let a = DMatrix::from_element(1, 1, 2.0);
        let b = DMatrix::from_element(1, 1, 1.0);
        let k_n = DMatrix::from_element(1, 1, -5.0);
        let k_j = DMatrix::from_element(1, 1, -1.0);
        let h = 0.2_f64;
        let input = SampledLoop::new(&a, &b, Some(&k_n), &k_j, Hold::Input).unwrap();
        let (e, ek) = ((2.0 * h).exp(), (-3.0 * h).exp());
        let want_input = e + (e - 1.0) / 2.0 * (-6.0);
        assert!((input.transition(h).unwrap()[(0, 0)] - want_input).abs() < 1e-13);
        let corr = SampledLoop::new(&a, &b, Some(&k_n), &k_j, Hold::Correction).unwrap();
        // Phi = e^(-3h), Gamma = (1 - e^(-3h)) / 3, held gain -1.
        let want_corr = ek - (1.0 - ek) / 3.0;
        assert!((corr.transition(h).unwrap()[(0, 0)] - want_corr).abs() < 1e-13);
        // Both have the same continuous limit A + B (K_n + K_J) = -4.
        for l in [input, corr] {
            let ev = l.continuous_eigenvalues().unwrap();
            assert!((ev[0].re + 4.0).abs() < 1e-12);
        }
    }

    #[test]
    fn an_unstable_limit_law_is_unstable_at_every_period() {
        let a = DMatrix::from_element(1, 1, 1.0);
        let b = DMatrix::from_element(1, 1, 1.0);
        let k = DMatrix::from_element(1, 1, 0.0);
        let l = SampledLoop::new(&a, &b, None, &k, Hold::Input).unwrap();
        assert_eq!(
            l.critical_period(1.0, 10, 1e-6).unwrap(),
            CriticalPeriod::UnstableAtAnyPeriod
        );
    }

    #[test]
    fn bad_shapes_and_values_are_typed_errors() {
        let a = DMatrix::from_element(2, 2, 0.0);
        let b = DMatrix::from_element(2, 1, 1.0);
        let k = DMatrix::from_element(2, 2, 0.0);
        assert!(matches!(
            SampledLoop::new(&a, &b, None, &k, Hold::Input),
            Err(LinearError::DimensionMismatch { .. })
        ));
        let mut k = DMatrix::from_element(1, 2, 0.0);
        k[(0, 1)] = f64::NAN;
        assert!(matches!(
            SampledLoop::new(&a, &b, None, &k, Hold::Input),
            Err(LinearError::NonFinite {
                matrix: "K_J",
                row: 0,
                col: 1,
                ..
            })
        ));
        let k = DMatrix::from_element(1, 2, 0.0);
        let l = SampledLoop::new(&a, &b, None, &k, Hold::Input).unwrap();
        assert!(matches!(
            l.transition(0.0),
            Err(LinearError::InvalidOption(InvalidOption { name: "h", .. }))
        ));
    }
}
