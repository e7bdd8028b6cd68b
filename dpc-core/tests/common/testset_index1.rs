//! Index-1 problem of the Test Set for IVP Solvers (Mazzia, Iavernaro, Magherini, University of
//! Bari, release 2.4; Lioen & de Swart, CWI) with a singular, non-diagonal mass matrix: the
//! transistor amplifier (8 unknowns). Shared by the BDF and Radau tests, the work-precision
//! example and the peer comparisons.
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// The transistor amplifier (Test Set `transamp.F` rev 1.3; Hairer, Lubich & Roche 1989):
/// node voltages `U_1 .. U_8` of a two-transistor amplifier with input `U_e(t) = 0.1
/// sin(200 pi t)`, written as `M y' = phi(t, y)` with the Test Set's singular mass matrix
///
/// ```text
///     -c1  c1                               phi_1 = (y1 - U_e)/r0
///      c1 -c1                               phi_2 = y2/r1 + (y2 - ub)/r2 + (1 - alpha) g(y2 - y3)
///              -c2                          phi_3 = y3/r3 - g(y2 - y3)
///                  -c3  c3                  phi_4 = (y4 - ub)/r4 + alpha g(y2 - y3)
///                   c3 -c3                  phi_5 = y5/r5 + (y5 - ub)/r6 + (1 - alpha) g(y5 - y6)
///                           -c4             phi_6 = y6/r7 - g(y5 - y6)
///                               -c5  c5     phi_7 = (y7 - ub)/r8 + alpha g(y5 - y6)
///                                c5 -c5     phi_8 = y8/r9
/// ```
///
/// with `g(u) = beta (exp(u / uf) - 1)`; the residual is `F = M y' - phi(t, y)`, as in the
/// Test Set's `transres`. Every unknown has index 1 (the Test Set's `ind = (8, 0, 0)`).
#[derive(Debug, Clone, Copy, Default)]
pub struct TransistorAmplifier;

/// Interval end of [`TransistorAmplifier`].
pub const TRANSAMP_T_END: f64 = 0.2;

/// Reference solution at `t = 0.2`: the Test Set's `transsoln` (PSIDE at `rtol = atol = 1e-14`
/// on a Cray C90, 16 061 steps), as published in the Test Set's `transamp.F` and in deTestSet's
/// `reference("transistor")`.
#[allow(clippy::excessive_precision)]
pub const TRANSAMP_REF: [f64; 8] = [
    -0.5562145012262709e-2,
    0.3006522471903042e+1,
    0.2849958788608128e+1,
    0.2926422536206241e+1,
    0.2704617865010554e+1,
    0.2761837778393145e+1,
    0.4770927631616772e+1,
    0.1236995868091548e+1,
];

mod transamp_constants {
    pub const UB: f64 = 6.0;
    pub const UF: f64 = 0.026;
    pub const ALPHA: f64 = 0.99;
    pub const BETA: f64 = 1e-6;
    pub const R0: f64 = 1000.0;
    /// `r1 .. r9` are all 9000.
    pub const R: f64 = 9000.0;
    /// `r1` and `r2`, named for the initial values' voltage divider `ub / (r2 / r1 + 1)`.
    pub const R1: f64 = R;
    pub const R2: f64 = R;
    pub const C: [f64; 5] = [1e-6, 2e-6, 3e-6, 4e-6, 5e-6];
}

impl TransistorAmplifier {
    /// The Test Set's initial values `(y0, y0')` (the derivatives of the coupled nodes are the
    /// Test Set's numerically determined values, to the digits it publishes).
    #[allow(clippy::excessive_precision)]
    pub fn initial() -> ([f64; 8], [f64; 8]) {
        use transamp_constants::*;
        let half = UB / (R2 / R1 + 1.0);
        let y = [0.0, half, half, UB, half, half, UB, 0.0];
        let yp = [
            51.338775,
            51.338775,
            -half / (C[1] * R),
            -24.9757667,
            -24.9757667,
            -half / (C[3] * R),
            -10.00564453,
            -10.00564453,
        ];
        (y, yp)
    }

    /// `phi(t, y)`.
    pub fn phi(t: f64, y: &[f64]) -> [f64; 8] {
        use transamp_constants::*;
        let ue = 0.1 * (200.0 * std::f64::consts::PI * t).sin();
        let g1 = BETA * (((y[1] - y[2]) / UF).exp() - 1.0);
        let g2 = BETA * (((y[4] - y[5]) / UF).exp() - 1.0);
        [
            (y[0] - ue) / R0,
            y[1] / R + (y[1] - UB) / R + (1.0 - ALPHA) * g1,
            y[2] / R - g1,
            (y[3] - UB) / R + ALPHA * g1,
            y[4] / R + (y[4] - UB) / R + (1.0 - ALPHA) * g2,
            y[5] / R - g2,
            (y[6] - UB) / R + ALPHA * g2,
            y[7] / R,
        ]
    }

    /// The mass matrix's non-zero entries `(row, column, value)`.
    pub fn mass_entries() -> [(usize, usize, f64); 14] {
        use transamp_constants::C;
        [
            (0, 0, -C[0]),
            (0, 1, C[0]),
            (1, 0, C[0]),
            (1, 1, -C[0]),
            (2, 2, -C[1]),
            (3, 3, -C[2]),
            (3, 4, C[2]),
            (4, 3, C[2]),
            (4, 4, -C[2]),
            (5, 5, -C[3]),
            (6, 6, -C[4]),
            (6, 7, C[4]),
            (7, 6, C[4]),
            (7, 7, -C[4]),
        ]
    }

    /// `d phi / d y` as `(row, column, value)` entries (structurally non-zero ones).
    pub fn phi_jacobian(y: &[f64]) -> [(usize, usize, f64); 16] {
        use transamp_constants::*;
        let d1 = BETA * ((y[1] - y[2]) / UF).exp() / UF;
        let d2 = BETA * ((y[4] - y[5]) / UF).exp() / UF;
        [
            (0, 0, 1.0 / R0),
            (1, 1, 2.0 / R + (1.0 - ALPHA) * d1),
            (1, 2, -(1.0 - ALPHA) * d1),
            (2, 1, -d1),
            (2, 2, 1.0 / R + d1),
            (3, 1, ALPHA * d1),
            (3, 2, -ALPHA * d1),
            (3, 3, 1.0 / R),
            (4, 4, 2.0 / R + (1.0 - ALPHA) * d2),
            (4, 5, -(1.0 - ALPHA) * d2),
            (5, 4, -d2),
            (5, 5, 1.0 / R + d2),
            (6, 4, ALPHA * d2),
            (6, 5, -ALPHA * d2),
            (6, 6, 1.0 / R),
            (7, 7, 1.0 / R),
        ]
    }
}

impl ImplicitDae for TransistorAmplifier {
    fn dimension(&self) -> usize {
        8
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let phi = Self::phi(t, y);
        out.copy_from_slice(&phi);
        for o in out.iter_mut() {
            *o = -*o;
        }
        for (r, c, v) in Self::mass_entries() {
            out[r] += v * yp[c];
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        for (r, col, v) in Self::mass_entries() {
            m.add(r, col, c * v);
        }
        for (r, col, v) in Self::phi_jacobian(y) {
            m.add(r, col, -v);
        }
    }
    /// The constant capacitance matrix ([`Self::mass_entries`]).
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for (r, col, v) in Self::mass_entries() {
            m.add(r, col, v);
        }
        true
    }
    fn unknown_name(&self, i: usize) -> String {
        format!("U{}", i + 1)
    }
}
