//! The Fekete problem of the Test Set for IVP Solvers (Mazzia, Iavernaro, Magherini, University
//! of Bari: "Problem of Fekete", index 2, 160 unknowns): 20 charged points `p_i` on the unit
//! sphere in `R^3` with velocities `q_i`, repelling each other under a damping `alpha = 1/2`,
//! from the Test Set's initial points at rest to `t = 1000`, scored as the Test Set scores it
//! (the relative digits of the 60 coordinates of the points, [`fekete_scd`]) against its
//! reference solution ([`FEKETE_REF`]).
//!
//! The equations, `alpha`, the number of points, the initial values, the interval, the scored
//! components and the reference are those of the Test Set's problem file (its `feval`, `init`,
//! `soln` and scoring), transcribed; the residual and the Jacobians are written here. (Until
//! 2026-12-04 this fixture was a "Fekete-type" problem written from memory: the same
//! equations, `alpha`, interval and first ten points, but the last ten points at other angles
//! and its own reference, scored by the largest absolute error of the coordinates.) By
//! `t = 1000` the damped points have come to rest in an equilibrium (`q` below `1e-15`); their
//! end positions still depend on the path, through the rotation of the whole configuration
//! (the problem is invariant under rotations of the sphere).
//!
//! Unknowns of the GGL (index-2) form [`Fekete`], 160: `y = (p, q, lambda, mu)`, `p_i` at
//! `y[3i..3i+3]`, `q_i` at `y[60+3i..]`, `lambda_i` at `y[120+i]`, `mu_i` at `y[140+i]`:
//!
//! ```text
//! p_i' = q_i + 2 mu_i p_i
//! q_i' = g_i(p, q) + 2 lambda_i p_i,   g_i = sum_{j != i} (p_i - p_j) / |p_i - p_j|^2 - alpha q_i
//! 0    = |p_i|^2 - 1
//! 0    = 2 p_i . q_i
//! ```
//!
//! `lambda` and `mu` are of index 2. The declared index-3 form [`FeketeIndex3`] (140 unknowns,
//! `(p, q, lambda)`) drops `mu` and the velocity constraints, as a user would write it:
//! `p' = q`, `q' = g + 2 lambda p`, `0 = |p|^2 - 1`; `Stabilised` built on it (constraint rows
//! `120..140`, kinematic rows `p_j' = q_j`) is the GGL form above up to the sign of `mu`.
//!
//! Both iteration matrices are exact (written by hand; the IDA peer `bench/ida_peer.c` has the
//! same analytic Jacobian).
#![allow(dead_code)]
#![allow(clippy::needless_range_loop)]

use std::f64::consts::PI;

use dpc_core::{ImplicitDae, MatrixSink};

/// Number of points.
pub const NPOINTS: usize = 20;
/// Damping `alpha`.
pub const ALPHA: f64 = 0.5;
/// Unknowns of the GGL form.
pub const FEKETE_DIM: usize = 160;
/// Unknowns of the declared index-3 form.
pub const FEKETE_INDEX3_DIM: usize = 140;
/// End of the interval of the work-precision table.
pub const FEKETE_T_END: f64 = 1000.0;
/// End of the interval of the tests (fast in debug builds).
pub const FEKETE_T_SHORT: f64 = 10.0;
/// Positions and velocities: index 1 (both forms).
pub const FEKETE_DIFFERENTIAL: usize = 120;

/// Differential index per unknown of the GGL form: `p`, `q` 1, `lambda`, `mu` 2.
pub fn fekete_index() -> Vec<u8> {
    (0..FEKETE_DIM)
        .map(|i| if i < FEKETE_DIFFERENTIAL { 1 } else { 2 })
        .collect()
}

/// The scored unknowns: the 60 coordinates of the points (the Test Set scores its Fekete
/// problem on these, by the largest relative error).
pub const FEKETE_SCORED: [usize; 60] = {
    let mut s = [0; 60];
    let mut i = 0;
    while i < 60 {
        s[i] = i;
        i += 1;
    }
    s
};

/// The Test Set's significant correct digits of the positions,
/// `min_i -log10(|p_i - r_i| / |r_i|)` over the 60 coordinates.
pub fn fekete_scd(y: &[f64], reference: &[f64]) -> f64 {
    -FEKETE_SCORED
        .iter()
        .map(|&i| (y[i] - reference[i]).abs() / reference[i].abs())
        .fold(0.0f64, |m, e| {
            if e.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(e)
            }
        })
        .log10()
}

/// The points `p` (60 coordinates) at `t = 1000`: the Test Set's reference solution (`soln` of
/// its Fekete problem, RADAU5 at `rtol = atol = 1e-12`; Test Set for IVP Solvers, Univ. of
/// Bari). Its velocities are below `3e-16` there, every `lambda_i` is `-4.75` to 15 digits
/// (`-(N - 1)/4`, an equilibrium of the 20 points: `p_i . g_i = (N - 1)/2` at rest) and every
/// `mu_i` below `1e-18`. dpc Radau at `rtol = atol = 1e-12` agrees with it to `2.5e-12`
/// (10.41 digits by [`fekete_scd`]; 1317 steps), Radau at `1e-11` to `4.2e-12`, the BDF at
/// `1e-12` to `3.5e-12` (9.94 digits).
#[allow(clippy::excessive_precision)]
pub const FEKETE_REF: [f64; 60] = [
    -0.4070263380333202e+00,
    0.3463758772791802e+00,
    0.8451942450030429e+00,
    0.7752934752521549e-01,
    -0.2628662719972299e+00,
    0.9617122871829146e+00,
    0.7100577833343567e+00,
    0.1212948055586120e+00,
    0.6936177005172217e+00,
    0.2348267744557627e+00,
    0.7449277976923311e+00,
    0.6244509285956391e+00,
    -0.4341114738782885e+00,
    0.8785430442262876e+00,
    0.1992720444237660e+00,
    -0.9515059600312596e+00,
    0.2203508762787005e+00,
    0.2146669498274008e+00,
    -0.6385191643609878e+00,
    -0.4310833259390688e+00,
    0.6375425027722121e+00,
    -0.1464175087914336e+00,
    -0.9380871635228862e+00,
    0.3139337298744690e+00,
    0.5666974065069942e+00,
    -0.6739221885076542e+00,
    0.4740073135462156e+00,
    0.9843259538440293e+00,
    -0.1696995357819996e+00,
    -0.4800504290609090e-01,
    0.1464175087914331e+00,
    0.9380871635228875e+00,
    -0.3139337298744656e+00,
    -0.7092757549979014e+00,
    0.5264062637139616e+00,
    -0.4688542938854929e+00,
    -0.8665731819284478e+00,
    -0.4813878059756024e+00,
    -0.1315929352982178e+00,
    -0.2347897778700538e+00,
    -0.8594340408013130e+00,
    -0.4541441287957579e+00,
    0.5530976940074118e+00,
    -0.7674370265615124e+00,
    -0.3242273140037833e+00,
    0.7711050969896927e+00,
    0.6357041816577034e+00,
    0.3573685519777001e-01,
    0.7103951209379591e+00,
    0.2403570431280519e+00,
    -0.6614886725910596e+00,
    -0.3038208738735660e-01,
    0.4501923293640461e+00,
    -0.8924145871442046e+00,
    -0.5772996158107093e+00,
    -0.1766763414971813e+00,
    -0.7971892020969544e+00,
    0.2414481766969039e+00,
    -0.3416456818373135e+00,
    -0.9082846503446250e+00,
];

/// The points at `t = 10` ([`FEKETE_T_SHORT`], the tests' end point; the Test Set gives no
/// reference there): dpc Radau at `rtol = atol = 1e-12` (619 steps); Radau at `1e-13` agrees
/// to `9.5e-12`, the BDF at `1e-12` to `1.6e-11`.
#[allow(clippy::excessive_precision)]
pub const FEKETE_REF_SHORT: [f64; 60] = [
    -3.5116378260317149e-1,
    3.4366636734417383e-1,
    8.7096350425508184e-1,
    8.7090942481331410e-2,
    -3.1315900002746666e-1,
    9.4569900520171357e-1,
    6.7182174431144104e-1,
    1.6129268267436014e-1,
    7.2293859655301362e-1,
    2.5206851684645770e-1,
    7.8813864454350180e-1,
    5.6151486159491693e-1,
    -4.8776464238354722e-1,
    8.3949806795958193e-1,
    2.3943401498654984e-1,
    -9.5715084304477804e-1,
    2.1076919427000526e-1,
    1.9859156680343606e-1,
    -6.5443582437454884e-1,
    -3.8900798196010083e-1,
    6.4837222468774414e-1,
    -1.7016369857445163e-1,
    -9.3229786791647562e-1,
    3.1916296960308044e-1,
    5.5368532295874706e-1,
    -7.0504663552610369e-1,
    4.4310473352627289e-1,
    9.8706304779693432e-1,
    -1.5296027950699784e-1,
    4.8059260990656001e-2,
    1.1004543736540044e-1,
    9.4804972975447943e-1,
    -2.9848234726280981e-1,
    -6.8678445559730150e-1,
    5.4201339878189192e-1,
    -4.8430216506930879e-1,
    -8.4664708387329812e-1,
    -5.1408947282491124e-1,
    -1.3747992325952599e-1,
    -1.9337941025188723e-1,
    -8.7179069152679411e-1,
    -4.5009487206350907e-1,
    5.8622392658022726e-1,
    -7.2375493774345867e-1,
    -3.6403337483920717e-1,
    7.7700784676616230e-1,
    6.2886642246749447e-1,
    -2.8032637349114094e-2,
    7.4066708608372211e-1,
    1.4807869377315130e-1,
    -6.5535102658246092e-1,
    2.8953859896666521e-2,
    4.6778120380412774e-1,
    -8.8336992215302723e-1,
    -6.0684876170877489e-1,
    -1.4697382451900548e-1,
    -7.8111028371081070e-1,
    1.6118250409209464e-1,
    -3.2861738819037151e-1,
    -9.3060776514788479e-1,
];

/// The Test Set's initial points `p_i = (cos a_i cos b_i, sin a_i cos b_i, sin b_i)`
/// (`i = 1..20` as `0..20`): three at `b = 3 pi/8` (`a = 2 pi i/3 + pi/13`), seven at `pi/8`
/// (`a = 2 pi (i - 3)/7 + pi/29`), six at `-2 pi/15` (`a = 2 pi (i - 10)/6 + pi/7`), four at
/// `-3 pi/10` (`a = 2 pi (i - 17)/4 + pi/17`).
pub fn initial_points() -> [[f64; 3]; NPOINTS] {
    let mut p = [[0.0; 3]; NPOINTS];
    for (k, pk) in p.iter_mut().enumerate() {
        let i = (k + 1) as f64;
        let (a, b) = match k + 1 {
            1..=3 => (2.0 * PI * i / 3.0 + PI / 13.0, 3.0 * PI / 8.0),
            4..=10 => (2.0 * PI * (i - 3.0) / 7.0 + PI / 29.0, PI / 8.0),
            11..=16 => (2.0 * PI * (i - 10.0) / 6.0 + PI / 7.0, -2.0 * PI / 15.0),
            _ => (2.0 * PI * (i - 17.0) / 4.0 + PI / 17.0, -3.0 * PI / 10.0),
        };
        *pk = [a.cos() * b.cos(), a.sin() * b.cos(), b.sin()];
    }
    p
}

/// `g_i(p, q)` for every point into `g` (`p`, `q`, `g` of length 60).
fn forces(p: &[f64], q: &[f64], g: &mut [f64]) {
    for i in 0..3 * NPOINTS {
        g[i] = -ALPHA * q[i];
    }
    for i in 0..NPOINTS {
        for j in i + 1..NPOINTS {
            let d = [
                p[3 * i] - p[3 * j],
                p[3 * i + 1] - p[3 * j + 1],
                p[3 * i + 2] - p[3 * j + 2],
            ];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            for k in 0..3 {
                g[3 * i + k] += d[k] / r2;
                g[3 * j + k] -= d[k] / r2;
            }
        }
    }
}

/// `-dg/dp - 2 lambda_i I` (rows `row0 + 3i + k`, columns `3j + l`) and `c + alpha` on the
/// diagonal of the velocity rows (columns `60 + 3i + k`) into `m`: the velocity rows of both
/// forms' iteration matrices, without the multipliers' columns.
fn velocity_rows<S: MatrixSink + ?Sized>(p: &[f64], lambda: &[f64], c: f64, m: &mut S) {
    let row0 = 3 * NPOINTS;
    let mut diag = [[[0.0; 3]; 3]; NPOINTS];
    for i in 0..NPOINTS {
        for j in 0..NPOINTS {
            if i == j {
                continue;
            }
            let d = [
                p[3 * i] - p[3 * j],
                p[3 * i + 1] - p[3 * j + 1],
                p[3 * i + 2] - p[3 * j + 2],
            ];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            // d/dp_i of d / |d|^2 = I / r2 - 2 d d^T / r2^2; d/dp_j is its negative.
            for k in 0..3 {
                for l in 0..3 {
                    let b = if k == l { 1.0 / r2 } else { 0.0 } - 2.0 * d[k] * d[l] / (r2 * r2);
                    diag[i][k][l] += b;
                    m.set(row0 + 3 * i + k, 3 * j + l, b);
                }
            }
        }
    }
    for i in 0..NPOINTS {
        for k in 0..3 {
            for l in 0..3 {
                let v = -diag[i][k][l] - if k == l { 2.0 * lambda[i] } else { 0.0 };
                m.set(row0 + 3 * i + k, 3 * i + l, v);
            }
            m.set(row0 + 3 * i + k, row0 + 3 * i + k, c + ALPHA);
            m.set(row0 + 3 * i + k, 120 + i, -2.0 * p[3 * i + k]);
        }
    }
}

/// The GGL index-2 form (160 unknowns; module documentation).
#[derive(Debug, Clone, Copy, Default)]
pub struct Fekete;

impl Fekete {
    /// Consistent initial values `(y0, y0')`: the points of [`initial_points`] at rest,
    /// `mu = 0`, `lambda_i = -p_i . g_i / 2` (the hidden constraint `p_i . q_i' = 0`), so that
    /// `q_i' = g_i - (p_i . g_i) p_i`; `p' = 0` and `lambda' = mu' = 0`.
    pub fn initial() -> (Vec<f64>, Vec<f64>) {
        let pts = initial_points();
        let mut y = vec![0.0; FEKETE_DIM];
        for (i, pt) in pts.iter().enumerate() {
            y[3 * i..3 * i + 3].copy_from_slice(pt);
        }
        let mut g = [0.0; 60];
        forces(&y[0..60], &y[60..120], &mut g);
        let mut yp = vec![0.0; FEKETE_DIM];
        for i in 0..NPOINTS {
            let pg: f64 = (0..3).map(|k| y[3 * i + k] * g[3 * i + k]).sum();
            y[120 + i] = -pg / 2.0;
            for k in 0..3 {
                yp[60 + 3 * i + k] = g[3 * i + k] - pg * y[3 * i + k];
            }
        }
        (y, yp)
    }
}

impl ImplicitDae for Fekete {
    fn dimension(&self) -> usize {
        FEKETE_DIM
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (p, q, lambda, mu) = (&y[0..60], &y[60..120], &y[120..140], &y[140..160]);
        let mut g = [0.0; 60];
        forces(p, q, &mut g);
        for i in 0..NPOINTS {
            let mut pp = 0.0;
            let mut pq = 0.0;
            for k in 0..3 {
                let r = 3 * i + k;
                out[r] = yp[r] - q[r] - 2.0 * mu[i] * p[r];
                out[60 + r] = yp[60 + r] - g[r] - 2.0 * lambda[i] * p[r];
                pp += p[r] * p[r];
                pq += p[r] * q[r];
            }
            out[120 + i] = pp - 1.0;
            out[140 + i] = 2.0 * pq;
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
        let (p, q, lambda, mu) = (&y[0..60], &y[60..120], &y[120..140], &y[140..160]);
        velocity_rows(p, lambda, c, m);
        for i in 0..NPOINTS {
            for k in 0..3 {
                let r = 3 * i + k;
                m.set(r, r, c - 2.0 * mu[i]);
                m.set(r, 60 + r, -1.0);
                m.set(r, 140 + i, -2.0 * p[r]);
                m.set(120 + i, r, 2.0 * p[r]);
                m.set(140 + i, r, 2.0 * q[r]);
                m.set(140 + i, 60 + r, 2.0 * p[r]);
            }
        }
    }
    /// The identity on `p` and `q` (the constraint rows have no derivatives).
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for r in 0..FEKETE_DIFFERENTIAL {
            m.set(r, r, 1.0);
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < FEKETE_DIFFERENTIAL
    }
    fn unknown_name(&self, i: usize) -> String {
        unknown_name(i)
    }
}

/// `p3_2` (point 3, second coordinate), `q..`, `lambda3`, `mu3` (points counted from 1).
fn unknown_name(i: usize) -> String {
    match i {
        0..60 => format!("p{}_{}", i / 3 + 1, i % 3 + 1),
        60..120 => format!("q{}_{}", (i - 60) / 3 + 1, i % 3 + 1),
        120..140 => format!("lambda{}", i - 119),
        _ => format!("mu{}", i - 139),
    }
}

/// The index-3 form as declared (140 unknowns `(p, q, lambda)`; module documentation), with
/// its constraints' exact gradients and curvature for `Stabilised`.
#[derive(Debug, Clone, Copy, Default)]
pub struct FeketeIndex3;

impl FeketeIndex3 {
    /// The first 140 values of [`Fekete::initial`].
    pub fn initial() -> (Vec<f64>, Vec<f64>) {
        let (mut y, mut yp) = Fekete::initial();
        y.truncate(FEKETE_INDEX3_DIM);
        yp.truncate(FEKETE_INDEX3_DIM);
        (y, yp)
    }
}

impl ImplicitDae for FeketeIndex3 {
    fn dimension(&self) -> usize {
        FEKETE_INDEX3_DIM
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (p, q, lambda) = (&y[0..60], &y[60..120], &y[120..140]);
        let mut g = [0.0; 60];
        forces(p, q, &mut g);
        for i in 0..NPOINTS {
            let mut pp = 0.0;
            for k in 0..3 {
                let r = 3 * i + k;
                out[r] = yp[r] - q[r];
                out[60 + r] = yp[60 + r] - g[r] - 2.0 * lambda[i] * p[r];
                pp += p[r] * p[r];
            }
            out[120 + i] = pp - 1.0;
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
        let (p, lambda) = (&y[0..60], &y[120..140]);
        velocity_rows(p, lambda, c, m);
        for i in 0..NPOINTS {
            for k in 0..3 {
                let r = 3 * i + k;
                m.set(r, r, c);
                m.set(r, 60 + r, -1.0);
                m.set(120 + i, r, 2.0 * p[r]);
            }
        }
    }
    /// The identity on `p` and `q`, as [`Fekete`]'s.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for r in 0..FEKETE_DIFFERENTIAL {
            m.set(r, r, 1.0);
        }
        true
    }
    /// `d(|p_i|^2 - 1)/dp_i = 2 p_i`.
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, _: f64, y: &[f64], m: &mut S) -> bool {
        for r in 0..3 * NPOINTS {
            m.set(120 + r / 3, r, 2.0 * y[r]);
        }
        true
    }
    /// The constraints do not depend on `t`.
    fn constraint_time_derivative(&self, _: f64, _: &[f64], _: &mut [f64]) -> bool {
        true
    }
    /// `d/dp_i (2 p_i . v_i) = 2 v_i`.
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        v: &[f64],
        m: &mut S,
    ) -> bool {
        for r in 0..3 * NPOINTS {
            m.set(120 + r / 3, r, 2.0 * v[r]);
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < FEKETE_DIFFERENTIAL
    }
    fn unknown_name(&self, i: usize) -> String {
        unknown_name(i)
    }
}
