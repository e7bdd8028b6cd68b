//! Three standard problems beside the peer table's first five (issue 18's check "on standard
//! index-1, 2 and 3 problems"): the Test Set's chemical Akzo Nobel problem (index 1, 6
//! unknowns) and HIRES (an ODE of 8 unknowns, written as `F = y' - f(y)`), and Ascher and
//! Petzold's linear index-2 problem with an exact solution. Each has its exact iteration matrix.
//! Shared by the BDF and Radau tests, the work-precision example and the peer comparisons
//! (`bench/ida_peer.c` has the same equations, `bench/diffsol_peer` uses these).
#![allow(dead_code)]
// Matrix entries are written by (row, column) index, as the formulas are.
#![allow(clippy::needless_range_loop)]

use dpc_core::{ImplicitDae, MatrixSink};

/// The chemical Akzo Nobel problem (Test Set `chemakzo.f`): `M y' = f(y)`, `M = diag(1, 1, 1,
/// 1, 1, 0)`,
///
/// ```text
/// y1' = -2 r1 + r2 - r3 - r4         r1 = k1 y1^4 sqrt(y2)     r4 = k3 y1 y4^2
/// y2' = -r1/2 - r4 - r5/2 + Fin      r2 = k2 y3 y4             r5 = k4 y6^2 sqrt(y2)
/// y3' = r1 - r2 + r3                 r3 = k2/K y1 y5           Fin = klA (pCO2/H - y2)
/// y4' = -r2 + r3 - 2 r4
/// y5' = r2 - r3 + r5
///  0  = Ks y1 y4 - y6
/// ```
///
/// on `t` in `[0, 180]`; every unknown has index 1. The residual is `F = M y' - f(y)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct ChemAkzo;

/// Interval end of [`ChemAkzo`].
pub const AKZO_T_END: f64 = 180.0;

/// Reference solution at `t = 180`, the Test Set's `chemakzo.f` (`solut`), verified here: dpc's
/// Radau at `rtol = atol = 1e-12` agrees with it to 9.53 significant digits in every component
/// (`radau_testset.rs`, `akzo_hires_references_agree_with_radau`), IDA 6.4.1 at `rtol = 1e-12`,
/// `atol = 1e-15` to 11.18 (`bench/ida_peer.c --reference`).
#[allow(clippy::excessive_precision)]
pub const AKZO_REF: [f64; 6] = [
    0.1150794920661702,
    0.1203831471567715e-2,
    0.1611562887407974,
    0.3656156421249283e-3,
    0.1708010885264404e-1,
    0.4873531310307455e-2,
];

mod akzo {
    pub const K1: f64 = 18.7;
    pub const K2: f64 = 0.58;
    pub const K3: f64 = 0.09;
    pub const K4: f64 = 0.42;
    pub const KBIG: f64 = 34.4;
    pub const KLA: f64 = 3.3;
    pub const KS: f64 = 115.83;
    pub const PCO2: f64 = 0.9;
    pub const H: f64 = 737.0;
}

impl ChemAkzo {
    /// `y0` of the Test Set (`y6 = Ks y1 y4`, consistent) and the consistent `y0'`:
    /// `y0'_i = f_i(y0)` for the five differential rows and `y6' = Ks (y1' y4 + y1 y4')`.
    pub fn initial() -> ([f64; 6], [f64; 6]) {
        let y = [0.444, 0.00123, 0.0, 0.007, 0.0, akzo::KS * 0.444 * 0.007];
        let f = Self::f(&y);
        let mut yp = f;
        yp[5] = akzo::KS * (f[0] * y[3] + y[0] * f[3]);
        (y, yp)
    }

    /// `f(y)` (its last row is the constraint `Ks y1 y4 - y6`).
    pub fn f(y: &[f64]) -> [f64; 6] {
        use akzo::*;
        let s2 = y[1].sqrt();
        let r1 = K1 * y[0].powi(4) * s2;
        let r2 = K2 * y[2] * y[3];
        let r3 = K2 / KBIG * y[0] * y[4];
        let r4 = K3 * y[0] * y[3] * y[3];
        let r5 = K4 * y[5] * y[5] * s2;
        let fin = KLA * (PCO2 / H - y[1]);
        [
            -2.0 * r1 + r2 - r3 - r4,
            -0.5 * r1 - r4 - 0.5 * r5 + fin,
            r1 - r2 + r3,
            -r2 + r3 - 2.0 * r4,
            r2 - r3 + r5,
            KS * y[0] * y[3] - y[5],
        ]
    }

    /// `df/dy` (dense; `y2 > 0` on the solution).
    pub fn f_jacobian(y: &[f64]) -> [[f64; 6]; 6] {
        use akzo::*;
        let s2 = y[1].sqrt();
        // dr_k / dy_j of the five reaction rates.
        let mut dr = [[0.0; 6]; 5];
        dr[0][0] = 4.0 * K1 * y[0].powi(3) * s2;
        dr[0][1] = 0.5 * K1 * y[0].powi(4) / s2;
        dr[1][2] = K2 * y[3];
        dr[1][3] = K2 * y[2];
        dr[2][0] = K2 / KBIG * y[4];
        dr[2][4] = K2 / KBIG * y[0];
        dr[3][0] = K3 * y[3] * y[3];
        dr[3][3] = 2.0 * K3 * y[0] * y[3];
        dr[4][1] = 0.5 * K4 * y[5] * y[5] / s2;
        dr[4][5] = 2.0 * K4 * y[5] * s2;
        // Stoichiometry of f1..f5 in r1..r5.
        const S: [[f64; 5]; 5] = [
            [-2.0, 1.0, -1.0, -1.0, 0.0],
            [-0.5, 0.0, 0.0, -1.0, -0.5],
            [1.0, -1.0, 1.0, 0.0, 0.0],
            [0.0, -1.0, 1.0, -2.0, 0.0],
            [0.0, 1.0, -1.0, 0.0, 1.0],
        ];
        let mut j = [[0.0; 6]; 6];
        for i in 0..5 {
            for c in 0..6 {
                j[i][c] = (0..5).map(|k| S[i][k] * dr[k][c]).sum();
            }
        }
        j[1][1] -= KLA;
        j[5][0] = KS * y[3];
        j[5][3] = KS * y[0];
        j[5][5] = -1.0;
        j
    }
}

impl ImplicitDae for ChemAkzo {
    fn dimension(&self) -> usize {
        6
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let f = Self::f(y);
        for i in 0..6 {
            out[i] = if i < 5 { yp[i] } else { 0.0 } - f[i];
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
        let j = Self::f_jacobian(y);
        for r in 0..6 {
            for k in 0..6 {
                let v = if r == k && r < 5 { c } else { 0.0 } - j[r][k];
                if v != 0.0 {
                    m.set(r, k, v);
                }
            }
        }
    }
    /// `M = diag(1, 1, 1, 1, 1, 0)`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for r in 0..5 {
            m.set(r, r, 1.0);
        }
        true
    }
}

/// HIRES (Test Set `hires.f`; Schaefer 1975, Hairer & Wanner): the "high irradiance responses"
/// of photomorphogenesis, an ODE of 8 unknowns on `t` in `[0, 321.8122]`, written as the DAE
/// `F = y' - f(y)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Hires;

/// Interval end of [`Hires`].
pub const HIRES_T_END: f64 = 321.8122;

/// Reference solution at `t = 321.8122`, the Test Set's `hires.f` (`solut`), verified here as
/// [`AKZO_REF`] is: Radau at `rtol = 1e-12`, `atol = 1e-15` agrees with it to 10.39 significant
/// digits, IDA to 10.24.
#[allow(clippy::excessive_precision)]
pub const HIRES_REF: [f64; 8] = [
    0.7371312573325668e-3,
    0.1442485726316185e-3,
    0.5888729740967575e-4,
    0.1175651343283149e-2,
    0.2386356198831331e-2,
    0.6238968252742796e-2,
    0.2849998395185769e-2,
    0.2850001604814231e-2,
];

impl Hires {
    /// `y0 = (1, 0, 0, 0, 0, 0, 0, 0.0057)` and `y0' = f(y0)`.
    pub fn initial() -> ([f64; 8], [f64; 8]) {
        let y = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0057];
        (y, Self::f(&y))
    }

    /// `f(y)`.
    pub fn f(y: &[f64]) -> [f64; 8] {
        let r = 280.0 * y[5] * y[7];
        [
            -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007,
            1.71 * y[0] - 8.75 * y[1],
            -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4],
            8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3],
            -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6],
            -r + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6],
            r - 1.81 * y[6],
            -r + 1.81 * y[6],
        ]
    }

    /// The non-zero entries `(row, column, value)` of `df/dy`.
    pub fn f_jacobian(y: &[f64]) -> [(usize, usize, f64); 25] {
        let (a, b) = (280.0 * y[7], 280.0 * y[5]);
        [
            (0, 0, -1.71),
            (0, 1, 0.43),
            (0, 2, 8.32),
            (1, 0, 1.71),
            (1, 1, -8.75),
            (2, 2, -10.03),
            (2, 3, 0.43),
            (2, 4, 0.035),
            (3, 1, 8.32),
            (3, 2, 1.71),
            (3, 3, -1.12),
            (4, 4, -1.745),
            (4, 5, 0.43),
            (4, 6, 0.43),
            (5, 3, 0.69),
            (5, 4, 1.71),
            (5, 5, -a - 0.43),
            (5, 6, 0.69),
            (5, 7, -b),
            (6, 5, a),
            (6, 6, -1.81),
            (6, 7, b),
            (7, 5, -a),
            (7, 6, 1.81),
            (7, 7, -b),
        ]
    }
}

impl ImplicitDae for Hires {
    fn dimension(&self) -> usize {
        8
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let f = Self::f(y);
        for i in 0..8 {
            out[i] = yp[i] - f[i];
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
        for i in 0..8 {
            m.set(i, i, c);
        }
        for (r, k, v) in Self::f_jacobian(y) {
            m.add(r, k, -v);
        }
    }
    /// The identity (an ODE).
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..8 {
            m.set(i, i, 1.0);
        }
        true
    }
}

/// Ascher and Petzold's linear index-2 problem (after their book, Computer Methods for ODEs and
/// DAEs, SIAM 1998) with `a = 50` on `t` in `[0, 1]`:
///
/// ```text
/// u1' - a (2 - t) w = (a - 1/(2 - t)) u1 + (3 - t)/(2 - t) e^t
/// u2' - (a - 1) w   = (a - 1) u1/(2 - t) - u2 + 2 e^t
///                 0 = (2 + t) u1 + (t^2 - 4) u2 - (t^2 + t - 2) e^t
/// ```
///
/// with the exact solution `u1 = u2 = e^t`, `w = -e^t/(2 - t)` (substituted: the three rows
/// vanish identically; a test checks it). Differentiating the constraint once gives
/// `(4 - t^2) w` plus terms in `u`: `w` has index 2, `u` index 1.
#[derive(Debug, Clone, Copy)]
pub struct AscherPetzold {
    /// The stiffness parameter `a`.
    pub a: f64,
}

impl Default for AscherPetzold {
    fn default() -> Self {
        Self { a: 50.0 }
    }
}

/// Interval end of [`AscherPetzold`].
pub const AP_T_END: f64 = 1.0;

/// The index of `(u1, u2, w)` ([`dpc_core::bdf::Options::index`]).
pub const AP_INDEX: [u8; 3] = [1, 1, 2];

impl AscherPetzold {
    /// The exact solution `(y, y')` at `t`.
    pub fn exact(t: f64) -> ([f64; 3], [f64; 3]) {
        let e = t.exp();
        let d = 2.0 - t;
        ([e, e, -e / d], [e, e, -e * (3.0 - t) / (d * d)])
    }
}

impl ImplicitDae for AscherPetzold {
    fn dimension(&self) -> usize {
        3
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (a, d, e) = (self.a, 2.0 - t, t.exp());
        out[0] = yp[0] - a * d * y[2] - (a - 1.0 / d) * y[0] - (3.0 - t) / d * e;
        out[1] = yp[1] - (a - 1.0) * y[2] - (a - 1.0) * y[0] / d + y[1] - 2.0 * e;
        out[2] = (2.0 + t) * y[0] + (t * t - 4.0) * y[1] - (t * t + t - 2.0) * e;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (a, d) = (self.a, 2.0 - t);
        m.set(0, 0, c - (a - 1.0 / d));
        m.set(0, 2, -a * d);
        m.set(1, 0, -(a - 1.0) / d);
        m.set(1, 1, c + 1.0);
        m.set(1, 2, -(a - 1.0));
        m.set(2, 0, 2.0 + t);
        m.set(2, 1, t * t - 4.0);
    }
    /// `diag(1, 1, 0)`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        m.set(0, 0, 1.0);
        m.set(1, 1, 1.0);
        true
    }
}
