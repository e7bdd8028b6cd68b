//! The slider crank of the Test Set for IVP Solvers (Mazzia, Iavernaro, Magherini, University of
//! Bari; "Slider crank", index 2, 24 unknowns; the model of B. Simeon, "Modelling a flexible
//! slider crank mechanism by a mixed system of DAEs and PDEs", Math. Modelling of Systems 2,
//! 1996): a crank driven at `omega = 150 rad/s`, a flexible connecting rod (two lateral modes
//! and a quadratic longitudinal element: four elastic coordinates `q1..q4`) and a sliding block,
//! to `t = 0.1`. The Test Set's index-2 form with linear stiffness, no damping and no gravity
//! (its default `ipar = (0, 0)`), its "close to smooth motion" initial values and its reference
//! solution at `t = 0.1`; the equations, constants, initial values and reference values are
//! transcribed from the Test Set's problem file (the residual is written here).
//!
//! Unknowns `y = (p, v, w, lambda)`, 7 + 7 + 7 + 3: positions `p = (phi1, phi2, x3, q1..q4)`
//! (crank angle, rod angle, block position, elastic coordinates), velocities `v = p'`,
//! accelerations `w = v'` and three multipliers:
//!
//! ```text
//! p' - v = 0
//! v' - w = 0
//! f(p, v) - M(p) w - G(p)^T lambda = 0      (7 rows)
//! -G(p) v + (0, 0, omega) = 0               (3 rows, the velocity constraints)
//! ```
//!
//! with the position constraints `(L1 sin phi1 + (L2 + q4) sin phi2, x3 - L1 cos phi1 - (L2 + q4)
//! cos phi2, phi1 - omega t)` differentiated once (`G = d/dp` of them). `w` and `lambda` have
//! index 2 (the Test Set's `ind = (14, 10, 0)`). The Test Set writes the last ten rows with this
//! sign (its residual negates Simeon's `M w - f + G^T lambda` and `G v - (0, 0, omega)`).
//!
//! The iteration matrix: exact in the rows `0..14` and in the columns of `w` and `lambda` (the
//! residual is linear in them: `-M^T`, `-G^T`), central differences in the columns of `p` and
//! `v` of the rows `14..24`. The residual is a polynomial of degree at most 2 in each single
//! unknown other than the two angles, so those differences are exact up to round-off for any
//! step (taken as `eps^(1/3) max(|y_j|, 1)`); the angles' columns (step `eps^(1/3)`) have a
//! truncation error of about `eps^(2/3) / 6`, `6e-12` relative. The IDA peer
//! (`bench/ida_peer.c`) computes the same matrix.
#![allow(dead_code)]
// Matrix entries are written by (row, column) index, as the formulas are.
#![allow(clippy::needless_range_loop)]

use dpc_core::{ImplicitDae, MatrixSink};

/// Unknowns.
pub const CRANK_DIM: usize = 24;
/// End of the interval (the Test Set's).
pub const CRANK_T_END: f64 = 0.1;
/// Positions and velocities (index 1); the rest (accelerations, multipliers) have index 2.
pub const CRANK_DIFFERENTIAL: usize = 14;
/// The scored unknowns: the seven positions (deTestSet, the Test Set's R port, scores its
/// slider crank on these; the elastic coordinates are the hardest of them).
pub const CRANK_SCORED: [usize; 7] = [0, 1, 2, 3, 4, 5, 6];

/// Differential index per unknown: positions and velocities 1, accelerations and multipliers 2.
pub fn crank_index() -> Vec<u8> {
    (0..CRANK_DIM)
        .map(|i| if i < CRANK_DIFFERENTIAL { 1 } else { 2 })
        .collect()
}

/// The Test Set's reference solution at `t = 0.1` (its `soln`; all 24 unknowns).
#[allow(clippy::excessive_precision)]
pub const CRANK_REF: [f64; CRANK_DIM] = [
    1.500000000000000e+01,
    -3.311734987910881e-01,
    1.697373326718410e-01,
    1.893192460247178e-04,
    2.375751865617931e-05,
    -5.323907988763734e-06,
    -8.363283141616840e-06,
    1.500000000000000e+02,
    6.025346682645789e+01,
    -8.753116989887888e+00,
    -3.005536801092212e-02,
    -5.500488291932075e-03,
    4.978243404809343e-04,
    1.104933470696396e-03,
    0.0,
    6.488722210234531e+03,
    2.167924253080623e+03,
    3.391435115267547e+01,
    1.699107480197843e-01,
    -1.415799354959001e+00,
    9.903251655235532e-01,
    -6.232893262533717e+01,
    -1.637910131687472e+02,
    2.529853213732781e+01,
];

/// The Test Set's data set (its `RESMBS`): masses, lengths, inertias, the rod's material and
/// cross-section, the crank's angular velocity. Its `pi` is the rounded `3.1415927`.
mod data {
    pub const M1: f64 = 0.36;
    pub const M2: f64 = 0.151104;
    pub const M3: f64 = 0.075552;
    pub const L1: f64 = 0.15;
    pub const L2: f64 = 0.30;
    pub const J1: f64 = 0.002727;
    pub const J2: f64 = 0.0045339259;
    /// The Test Set's rounded `pi` (part of its data: the rod's matrices use it).
    #[allow(clippy::approx_constant)]
    pub const PI: f64 = 3.1415927;
    pub const EE: f64 = 0.20e12;
    pub const BB: f64 = 0.0080;
    pub const HH: f64 = 0.0080;
    pub const RHO: f64 = 7870.0;
    pub const OMEGA: f64 = 150.0;
}
use data::*;

/// The rod's finite-element data (the Test Set's grid: two lateral modes, one quadratic
/// longitudinal element): mass `mq`, stiffness `kq`, the antisymmetric coupling `bq` and the
/// vectors `c1, c2, c12, c21`.
struct Rod {
    mq: [[f64; 4]; 4],
    kq: [[f64; 4]; 4],
    bq: [[f64; 4]; 4],
    c1: [f64; 4],
    c2: [f64; 4],
    c12: [f64; 4],
    c21: [f64; 4],
}

fn rod() -> Rod {
    let facm = RHO * BB * HH * L2;
    let fack = EE * BB * HH / L2;
    let facb = BB * HH * L2;
    let hl2 = (HH / L2) * (HH / L2);
    let pi3 = PI * PI * PI;
    let pi4 = pi3 * PI;
    let mut r = Rod {
        mq: [[0.0; 4]; 4],
        kq: [[0.0; 4]; 4],
        bq: [[0.0; 4]; 4],
        c1: [0.0; 4],
        c2: [0.0; 4],
        c12: [0.0; 4],
        c21: [0.0; 4],
    };
    r.mq[0][0] = facm * 0.5;
    r.mq[1][1] = facm * 0.5;
    r.mq[2][2] = facm * 8.0;
    r.mq[2][3] = facm;
    r.mq[3][2] = facm;
    r.mq[3][3] = facm * 2.0;
    r.kq[0][0] = fack * pi4 / 24.0 * hl2;
    r.kq[1][1] = fack * pi4 * 2.0 / 3.0 * hl2;
    r.kq[2][2] = fack * 16.0 / 3.0;
    r.kq[2][3] = -fack * 8.0 / 3.0;
    r.kq[3][2] = -fack * 8.0 / 3.0;
    r.kq[3][3] = fack * 7.0 / 3.0;
    r.bq[0][2] = -facb * 16.0 / pi3;
    r.bq[0][3] = facb * (8.0 / pi3 - 1.0 / PI);
    r.bq[1][3] = facb * 0.5 / PI;
    r.bq[2][0] = facb * 16.0 / pi3;
    r.bq[3][0] = -facb * (8.0 / pi3 - 1.0 / PI);
    r.bq[3][1] = -facb * 0.5 / PI;
    r.c1[2] = facb * 2.0 / 3.0;
    r.c1[3] = facb / 6.0;
    r.c2[0] = facb * 2.0 / PI;
    r.c12[2] = L2 * facb / 3.0;
    r.c12[3] = L2 * facb / 6.0;
    r.c21[0] = L2 * facb / PI;
    r.c21[1] = -L2 * facb * 0.5 / PI;
    r
}

fn dot(a: &[f64; 4], b: &[f64]) -> f64 {
    (0..4).map(|i| a[i] * b[i]).sum()
}

/// The mass matrix `M(p)` (7 x 7, symmetric), the constraint matrix `G(p)` (3 x 7) and the
/// forces `f(p, v)` (7) at positions `p` and velocities `v`.
fn mechanics(rod: &Rod, p: &[f64], v: &[f64]) -> ([[f64; 7]; 7], [[f64; 7]; 3], [f64; 7]) {
    let (q, qd) = (&p[3..7], &v[3..7]);
    let (c1, s1) = (p[0].cos(), p[0].sin());
    let (c2, s2) = (p[1].cos(), p[1].sin());
    let (c12, s12) = ((p[0] - p[1]).cos(), (p[0] - p[1]).sin());
    let (v1, v2) = (v[0], v[1]);
    let c1q = dot(&rod.c1, q);
    let c1qd = dot(&rod.c1, qd);
    let c2q = dot(&rod.c2, q);
    let c2qd = dot(&rod.c2, qd);
    let c12q = dot(&rod.c12, q);
    let c12qd = dot(&rod.c12, qd);
    let mut mqq = [0.0; 4];
    let mut kqq = [0.0; 4];
    let mut qtbq = [0.0; 4];
    let mut bqqd = [0.0; 4];
    for i in 0..4 {
        for j in 0..4 {
            mqq[i] += rod.mq[j][i] * q[j];
            kqq[i] += rod.kq[j][i] * q[j];
            qtbq[i] += q[j] * rod.bq[j][i];
            bqqd[i] += rod.bq[i][j] * qd[j];
        }
    }
    let qtmqq: f64 = (0..4).map(|i| q[i] * mqq[i]).sum();
    let qdtmqq: f64 = (0..4).map(|i| qd[i] * mqq[i]).sum();
    let qdtbqqd: f64 = (0..4).map(|i| qd[i] * bqqd[i]).sum();

    let mut m = [[0.0; 7]; 7];
    m[0][0] = J1 + M2 * L1 * L1;
    m[0][1] = 0.5 * L1 * L2 * M2 * c12 + RHO * L1 * (s12 * c2q + c12 * c1q);
    m[1][1] = J2 + qtmqq + 2.0 * RHO * c12q;
    m[2][2] = M3;
    for i in 0..4 {
        m[0][3 + i] = RHO * L1 * (-s12 * rod.c1[i] + c12 * rod.c2[i]);
        m[1][3 + i] = RHO * rod.c21[i] + RHO * qtbq[i];
        for j in 0..4 {
            m[3 + j][3 + i] = rod.mq[j][i];
        }
    }
    for i in 0..7 {
        for j in i + 1..7 {
            m[j][i] = m[i][j];
        }
    }

    // KU = 4 (the longitudinal coordinate q4 enters the constraints), KV = 0.
    let q4 = q[3];
    let mut g = [[0.0; 7]; 3];
    g[0][0] = L1 * c1;
    g[0][1] = (L2 + q4) * c2;
    g[1][0] = L1 * s1;
    g[1][1] = (L2 + q4) * s2;
    g[1][2] = 1.0;
    g[2][0] = 1.0;
    g[0][6] = s2;
    g[1][6] = -c2;

    // No gravity (the Test Set's GRAV = 0) and no damping.
    let mut f = [0.0; 7];
    f[0] = -0.5 * L1 * L2 * M2 * v2 * v2 * s12 + RHO * L1 * v2 * v2 * (-s12 * c1q + c12 * c2q)
        - 2.0 * RHO * L1 * v2 * (c12 * c1qd + s12 * c2qd);
    f[1] = 0.5 * L1 * L2 * M2 * v1 * v1 * s12 + RHO * L1 * v1 * v1 * (s12 * c1q - c12 * c2q)
        - 2.0 * RHO * v2 * c12qd
        - 2.0 * v2 * qdtmqq
        - RHO * qdtbqqd;
    for i in 0..4 {
        f[3 + i] = v2 * v2 * mqq[i]
            + RHO
                * (v2 * v2 * rod.c12[i]
                    + L1 * v1 * v1 * (c12 * rod.c1[i] + s12 * rod.c2[i])
                    + 2.0 * v2 * bqqd[i])
            - kqq[i];
    }
    (m, g, f)
}

/// The last ten rows of the residual (`f - M w - G^T lambda`, `-G v + (0, 0, omega)`) into
/// `out[0..10]`.
fn dynamic_rows(rod: &Rod, y: &[f64], out: &mut [f64]) {
    let (p, v, w, lambda) = (&y[0..7], &y[7..14], &y[14..21], &y[21..24]);
    let (m, g, f) = mechanics(rod, p, v);
    for i in 0..7 {
        let mut r = f[i];
        for j in 0..7 {
            r -= m[j][i] * w[j];
        }
        for k in 0..3 {
            r -= g[k][i] * lambda[k];
        }
        out[i] = r;
    }
    for k in 0..3 {
        out[7 + k] = -(0..7).map(|j| g[k][j] * v[j]).sum::<f64>();
    }
    out[9] += OMEGA;
}

/// The slider crank in the Test Set's index-2 form (module documentation).
#[derive(Debug, Clone, Copy, Default)]
pub struct SliderCrank;

impl SliderCrank {
    /// The Test Set's initial values ("close to smooth motion"; accelerations and multipliers
    /// consistent for the linear stiffness and no damping) and `y0' = (v, w, 0)`. They are
    /// consistent to the nine digits the positions and velocities are given with.
    pub fn initial() -> (Vec<f64>, Vec<f64>) {
        #[allow(clippy::excessive_precision)]
        let y = vec![
            0.0,
            0.0,
            0.450016933,
            0.0,
            0.0,
            0.103339863e-4,
            0.169327969e-4,
            0.150000000e3,
            -0.749957670e2,
            -0.268938672e-5,
            0.444896105,
            0.463434311e-2,
            -0.178591076e-5,
            -0.268938672e-5,
            0.0,
            -1.344541576008661e-3,
            -5.062194923138079e3,
            -6.833142732779555e-5,
            1.449382650173157e-8,
            -4.268463211410861,
            2.098334687947376e-1,
            -6.397251492537153e-8,
            3.824589508329281e2,
            -4.376060460948886e-9,
        ];
        let mut yp = vec![0.0; CRANK_DIM];
        yp[..14].copy_from_slice(&y[7..21]);
        (y, yp)
    }
}

impl ImplicitDae for SliderCrank {
    fn dimension(&self) -> usize {
        CRANK_DIM
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for i in 0..14 {
            out[i] = yp[i] - y[7 + i];
        }
        dynamic_rows(&rod(), y, &mut out[14..24]);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let rod = rod();
        for i in 0..14 {
            m.set(i, i, c);
            m.set(i, 7 + i, -1.0);
        }
        // Columns of w and lambda: exact.
        let (mass, g, _) = mechanics(&rod, &y[0..7], &y[7..14]);
        for i in 0..7 {
            for j in 0..7 {
                m.set(14 + i, 14 + j, -mass[j][i]);
            }
            for k in 0..3 {
                m.set(14 + i, 21 + k, -g[k][i]);
            }
        }
        // Columns of p and v: central differences of the last ten rows.
        let third = f64::EPSILON.cbrt();
        let mut yy = [0.0; CRANK_DIM];
        yy.copy_from_slice(y);
        let (mut plus, mut minus) = ([0.0; 10], [0.0; 10]);
        for j in 0..14 {
            let h = if j < 2 {
                third
            } else {
                third * y[j].abs().max(1.0)
            };
            yy[j] = y[j] + h;
            dynamic_rows(&rod, &yy, &mut plus);
            yy[j] = y[j] - h;
            dynamic_rows(&rod, &yy, &mut minus);
            yy[j] = y[j];
            let step = (y[j] + h) - (y[j] - h);
            for i in 0..10 {
                let d = (plus[i] - minus[i]) / step;
                if d != 0.0 {
                    m.set(14 + i, j, d);
                }
            }
        }
    }
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..14 {
            m.set(i, i, 1.0);
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < CRANK_DIFFERENTIAL
    }
    fn unknown_name(&self, i: usize) -> String {
        const NAMES: [&str; 7] = ["phi1", "phi2", "x3", "q1", "q2", "q3", "q4"];
        match i {
            0..7 => NAMES[i].to_string(),
            7..14 => format!("v_{}", NAMES[i - 7]),
            14..21 => format!("w_{}", NAMES[i - 14]),
            _ => format!("lambda{}", i - 20),
        }
    }
}
