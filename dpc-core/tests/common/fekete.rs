//! A Fekete-type problem with 20 points: 20 charged points `p_i` on the unit sphere in `R^3`
//! with velocities `q_i`, repelling each other under a damping `alpha = 1/2`, the large
//! constrained mechanical problem of the Test Set for IVP Solvers (Mazzia, Iavernaro, Magherini,
//! University of Bari: "Problem of Fekete", index 2, 160 unknowns).
//!
//! The equations, the interval `[0, 1000]`, `alpha` and the initial points follow the Test
//! Set's description as recalled (the project has no copy of `fekete.f` to check them
//! against): hence "Fekete-type". The problem is self-consistent either way, and its
//! reference solution is computed here: dpc Radau at `rtol = atol = 1e-12`, checked against
//! dpc's BDF at `1e-12` and SUNDIALS IDA as tightly as it runs (see [`FEKETE_REF`]). By
//! `t = 1000` the damped points have come to rest in an equilibrium (`q` below `1e-16`); their
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

/// Digits of the positions: `-log10 max_i |p_i - r_i|` over the 60 coordinates. Every point
/// has length 1, so the absolute error is the error relative to the points' scale (a relative
/// error per coordinate would judge coordinates near 0 by their own size).
pub fn fekete_digits(y: &[f64], reference: &[f64]) -> f64 {
    -(0..3 * NPOINTS)
        .map(|i| (y[i] - reference[i]).abs())
        .fold(0.0f64, |m, e| {
            if e.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(e)
            }
        })
        .log10()
}

/// The points `p` (60 coordinates) at `t = 1000`: dpc Radau at `rtol = atol = 1e-12` (1863
/// steps). dpc's BDF at `1e-12` agrees to `5.5e-12`, Radau at `1e-11` to `4.6e-12`, IDA at
/// `1e-10` from a first step of `1e-2` (`bench/ida_peer.c --reference`; IDA's Newton iteration
/// fails at `t = 0` from tighter tolerances) to `3.8e-10`. Every `lambda_i` is `-4.75` there to
/// 15 digits (`-(N - 1)/4`, an equilibrium of the 20 points: `p_i . g_i = (N - 1)/2` at rest).
#[allow(clippy::excessive_precision)]
pub const FEKETE_REF: [f64; 60] = [
    -2.7706815285150327e-1,
    4.0809509883468847e-1,
    8.6988023829867633e-1,
    -1.5586934085678317e-1,
    -3.6822760105407643e-1,
    9.1657688297427176e-1,
    4.8844238381895866e-1,
    1.6326663782831799e-1,
    8.5718611903220299e-1,
    4.6908178380900911e-1,
    7.8901840009277180e-1,
    3.9675211960820161e-1,
    -2.8269713777153188e-1,
    9.2489766244669869e-1,
    2.5425703981682812e-1,
    -8.7061865293055996e-1,
    3.3770853068152701e-1,
    3.5773748681722078e-1,
    -7.8100622844226320e-1,
    -4.3955328119779130e-1,
    4.4364646298899651e-1,
    -1.6642413363072267e-1,
    -9.3825073015980687e-1,
    3.0329618378715656e-1,
    5.6371914287723790e-1,
    -6.1332269443891063e-1,
    5.5322328262641540e-1,
    9.7066505921274748e-1,
    -1.6888478644690702e-2,
    2.3984186897324949e-1,
    -9.3756365522121343e-1,
    -1.7661970554142400e-1,
    -2.9963289542821947e-1,
    -4.6908178380900856e-1,
    -7.8901840009277224e-1,
    -3.9675211960820123e-1,
    4.6672698362198495e-1,
    -8.6453685867717311e-1,
    -1.8639190633643152e-1,
    8.3076285235941671e-1,
    -2.4178970803182867e-1,
    -5.0136894621578743e-1,
    7.7655453012709608e-1,
    5.6411175170716732e-1,
    -2.8060825598145961e-1,
    -6.7489351150262999e-1,
    6.1001730908590512e-1,
    -4.1520793675848833e-1,
    1.2168801267741329e-1,
    -5.3740561628095362e-1,
    -8.3449819122650604e-1,
    3.0689951005331995e-1,
    2.7561416375738734e-1,
    -9.1096076944363980e-1,
    6.2310207024898812e-2,
    8.8026594985872519e-1,
    -4.7037144430740113e-1,
    -4.4162786856586622e-1,
    3.2617569826238785e-2,
    -8.9660521961708461e-1,
];

/// The points at `t = 10` ([`FEKETE_T_SHORT`], the tests' end point): dpc Radau at
/// `rtol = atol = 1e-12`; Radau at `1e-13` agrees to `1.0e-11`, the BDF at `1e-12` to `5.3e-11`.
#[allow(clippy::excessive_precision)]
pub const FEKETE_REF_SHORT: [f64; 60] = [
    -2.7606751577289168e-1,
    4.2939018423002184e-1,
    8.5988999088365503e-1,
    -1.1016771998856224e-1,
    -3.5077688924934353e-1,
    9.2995626103654760e-1,
    5.0251157752935183e-1,
    9.4115883738873918e-2,
    8.5943255400119267e-1,
    4.3688844911487035e-1,
    7.8361793240695510e-1,
    4.4166890205249038e-1,
    -2.4887796149975286e-1,
    9.4621165880902847e-1,
    2.0674442438332971e-1,
    -8.6157977451527934e-1,
    3.5895558692353152e-1,
    3.5893060438277391e-1,
    -7.7287556211696673e-1,
    -4.1027558976373402e-1,
    4.8408398643871992e-1,
    -1.9842844824191128e-1,
    -9.3274495504697152e-1,
    3.0101993250070730e-1,
    5.8556591802317703e-1,
    -6.5081362151562194e-1,
    4.8327444138852899e-1,
    9.6818416545703367e-1,
    4.7045254929062932e-2,
    2.4577665826299835e-1,
    -9.2715549852173718e-1,
    -2.0767431101284628e-1,
    -3.1185583545325662e-1,
    -4.8794714065426070e-1,
    -7.6638166722685075e-1,
    -4.1781183332443278e-1,
    4.1502413702474050e-1,
    -8.7340173547253674e-1,
    -2.5480261804076931e-1,
    8.6017036709069128e-1,
    -2.8188883448687252e-1,
    -4.2502426350821215e-1,
    7.3618865059192107e-1,
    6.1746717340114543e-1,
    -2.7705696257565204e-1,
    -7.1962776064428846e-1,
    5.7245851394926417e-1,
    -3.9297218211609691e-1,
    1.1830655010795021e-1,
    -4.8690423477013878e-1,
    -8.6540616265685366e-1,
    4.0539020908368661e-1,
    2.5089357623503622e-1,
    -8.7903992615982973e-1,
    6.0207430563080019e-3,
    8.1669733203791750e-1,
    -5.7703485032985435e-1,
    -4.3092496953709231e-1,
    4.9204919414383992e-2,
    -9.0104525221260678e-1,
];

/// The initial points `p_i = (cos a_i cos b_i, sin a_i cos b_i, sin b_i)` (`i = 1..20` as
/// `0..20`): three at `b = 3 pi/8`, seven at `pi/8`, six at `-pi/7`, four at `-9 pi/20`.
pub fn initial_points() -> [[f64; 3]; NPOINTS] {
    let mut p = [[0.0; 3]; NPOINTS];
    for (k, pk) in p.iter_mut().enumerate() {
        let i = (k + 1) as f64;
        let (a, b) = match k + 1 {
            1..=3 => (2.0 * PI * i / 3.0 + PI / 13.0, 3.0 * PI / 8.0),
            4..=10 => (2.0 * PI * (i - 3.0) / 7.0 + PI / 29.0, PI / 8.0),
            11..=16 => (2.0 * PI * (i - 10.0) / 6.0 + 7.0 * PI / 11.0, -PI / 7.0),
            _ => (
                2.0 * PI * (i - 17.0) / 4.0 + 17.0 * PI / 11.0,
                -9.0 * PI / 20.0,
            ),
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
