//! The water tube system of the Test Set for IVP Solvers (Univ. of Bari; problem `water`, after
//! C. Steinebach's model of a network of water pipes): an index-2 DAE of 49 unknowns on `t` in
//! `[0, 17 h] = [0, 61 200 s]`. The network has 13 nodes and 18 pipes `e = (i -> j)`; the
//! unknowns are the flows `phi_e` (`y1..y18`), the pipes' friction factors `lambda_e`
//! (`y19..y36`), the pressures of the two nodes with a buffer, `p5 = y37`, `p8 = y38`, and the
//! pressures of the eleven other nodes (`y39..y49`: `p1, p2, p3, p4, p6, p7, p9..p13`):
//!
//! ```text
//! V phi_e'            = p_i - p_j - friction_e(phi_e, lambda_e)     (18 rows)
//! 0                   = R(phi_e, lambda_e)                          (18 rows)
//! C p_n'              = netflow_n(t, phi)   n = 5, 8                (2 rows)
//! 0                   = netflow_n(t, phi)   the other 11 nodes      (11 rows)
//! ```
//!
//! with `netflow_n = e_in,n(t) - e_out,n(t) + (flows into n) - (flows out of n)`, water fed at
//! nodes 1 and 13 and drawn at node 10 (smooth functions of `t`). A pipe is turbulent where its
//! Reynolds number `Re = |phi| d / (nu a)` exceeds `Re_crit = 2300`: then
//! `friction = lambda rho L phi^2 / (a^2 d)` and `R = 1/sqrt(lambda) - 1.74 + 2 log10(2 k / d +
//! 18.7 / (Re sqrt(lambda)))` (Colebrook's law); else laminar, `friction = 32 mu L phi / (a d^2)`
//! and `R` the same with `Re_crit` for `Re` (so `lambda` stays at the constant root
//! `0.04751940452918529...`). The switch makes the residual discontinuous in `phi` (the friction
//! jumps by a factor of about 3.4 at `Re_crit`): the problem is nonsmooth, and the Test Set's
//! drivers integrate through the switches without locating them, as here.
//!
//! The pressures of the nodes without a buffer have index 2 (they are fixed by the time
//! derivative of their flow balance), the other unknowns index 1 ([`WATER_INDEX`], the Test
//! Set's `ind = (38, 11, 0)`). The mass matrix is constant and diagonal (`V` on the flows, `C`
//! on `p5, p8`, zero elsewhere).
//!
//! Equations, constants, initial values, the tolerances ([`water_atol`]) and the reference
//! solution are transcribed from the Test Set for IVP Solvers (Univ. of Bari; problem file
//! `water.f` as its MEBDFI driver holds it), written here anew; the residual is the Test Set's
//! `F = M y' - f(t, y)`. A negative friction factor (where `sqrt` has no value; the Test Set
//! returns `ierr = -1`) gives a non-finite residual, which the integrators treat as a failed
//! Newton iteration (the step is retried smaller). The Test Set's driver scores all 49
//! unknowns by their relative errors ([`WATER_SCORED`]). The iteration matrix is exact, derived
//! per pipe regime below (the branch of the point it is evaluated at); `bench/ida_peer.c` has
//! the same equations and matrix.
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// The water tube system ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct WaterTube;

/// Number of unknowns of [`WaterTube`].
pub const WATER_DIM: usize = 49;

/// Interval end of [`WaterTube`]: 17 hours, in seconds.
pub const WATER_T_END: f64 = 17.0 * 3600.0;

/// The index of each unknown: the eleven pressures of the nodes without a buffer (`y39..y49`)
/// have index 2, the rest index 1.
pub const WATER_INDEX: [u8; WATER_DIM] = {
    let mut ind = [1u8; WATER_DIM];
    let mut i = 38;
    while i < WATER_DIM {
        ind[i] = 2;
        i += 1;
    }
    ind
};

/// The unknowns the Test Set's driver scores: all 49 (relative errors; no reference value is
/// zero).
pub const WATER_SCORED: [usize; WATER_DIM] = {
    let mut s = [0usize; WATER_DIM];
    let mut i = 0;
    while i < WATER_DIM {
        s[i] = i;
        i += 1;
    }
    s
};

/// The Test Set driver's absolute tolerances at `rtol = tol`: `tol` on the flows and friction
/// factors, `1e6 tol` on the thirteen pressures (about `1.1e5` Pa).
pub fn water_atol(tol: f64) -> Vec<f64> {
    (0..WATER_DIM)
        .map(|i| if i < 36 { tol } else { 1e6 * tol })
        .collect()
}

/// Reference solution at `t = 61 200 s`, the Test Set's.
#[allow(clippy::excessive_precision)]
pub const WATER_REF: [f64; WATER_DIM] = [
    0.2298488296477430e-002,
    0.1188984650746585e-002,
    0.1109503645730845e-002,
    0.1589620100314825e-003,
    0.1030022640715102e-002,
    0.8710606306836165e-003,
    0.3243571480903489e-002,
    0.1109503645730845e-002,
    0.7120986206521341e-003,
    0.6414613963833099e-003,
    0.9416978549524347e-003,
    0.3403428519096511e-002,
    0.2397639310739395e-002,
    0.2397639310739395e-002,
    0.3348581430454180e-002,
    0.1353560017035444e-002,
    0.1995021413418736e-002,
    0.5746220741193575e-002,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4311196778792902e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.4249217433601160e-001,
    0.4732336439609648e-001,
    0.4732336439609648e-001,
    0.4270002118868241e-001,
    0.4751940452918529e-001,
    0.4751940452918529e-001,
    0.3651427026675656e-001,
    0.1111268591478108e+006,
    0.1111270045592387e+006,
    0.1111271078730254e+006,
    0.1111269851929858e+006,
    0.1111269255355337e+006,
    0.1111269322658045e+006,
    0.1111269221703983e+006,
    0.1111270121140691e+006,
    0.1111274419515807e+006,
    0.1111255158881087e+006,
    0.1111278793439227e+006,
    0.1111270995171642e+006,
    0.1111298338971779e+006,
];

/// The pipes `(i, j)` (nodes numbered from 1, as the Test Set numbers them): flow `phi_e = y_e`
/// from node `i` to node `j`, friction factor `y_{18 + e}`.
pub const PIPES: [(usize, usize); 18] = [
    (1, 2),
    (2, 3),
    (2, 6),
    (3, 4),
    (3, 5),
    (4, 5),
    (5, 10),
    (6, 5),
    (7, 4),
    (7, 8),
    (8, 5),
    (8, 10),
    (9, 8),
    (11, 9),
    (11, 12),
    (12, 7),
    (12, 8),
    (13, 11),
];

/// The unknown (zero-based) holding the pressure of node `n` (1..=13); it is also the row of
/// node `n`'s flow balance.
pub const fn pressure(n: usize) -> usize {
    match n {
        5 => 36,
        8 => 37,
        1..=4 => 37 + n,
        6 | 7 => 36 + n,
        _ => 35 + n,
    }
}

/// Kinematic viscosity of water [m^2/s].
const NU: f64 = 1.31e-6;
/// Gravity [m/s^2].
const G: f64 = 9.8;
/// Density of water [kg/m^3].
const RHO: f64 = 1.0e3;
/// Critical Reynolds number: laminar below, turbulent above.
const RCRIT: f64 = 2.3e3;
/// Length of every pipe [m].
const LENGTH: f64 = 1.0e3;
/// Roughness of the pipes' walls [m].
const K: f64 = 2.0e-4;
/// Diameter of every pipe [m].
const D: f64 = 1.0;
/// Cross-section of the buffers [m^2].
const B: f64 = 2.0e2;
/// Cross-section of a pipe.
const A: f64 = std::f64::consts::PI * D * D / 4.0;
/// Dynamic viscosity.
const MU: f64 = NU * RHO;
/// The buffers' capacitance `b / (rho g)` (the mass-matrix entry of `p5`, `p8`).
const C: f64 = B / (RHO * G);
/// The pipes' inertance `rho L / a` (the mass-matrix entry of the flows).
const V: f64 = RHO * LENGTH / A;
/// The Test Set's initial friction factor: the root of the laminar `R(lambda) = 0`.
#[allow(clippy::excessive_precision)]
const LAMBDA0: f64 = 0.47519404529185289807e-1;

/// The water fed at nodes 1 and 13 and drawn at node 10 at time `t` [s] (in m^3/s):
/// `(e_in1, e_in13, e_out10)`.
pub fn inflows(t: f64) -> (f64, f64, f64) {
    let th = t / 3600.0;
    let s = 1.0 - ((-th).exp() - 1.0).cos();
    (
        s / 200.0,
        s / 80.0,
        th * th * (3.0 * th * th - 92.0 * th + 720.0) / 1e6,
    )
}

/// One pipe's friction term of the momentum row, its Colebrook residual `R`, and their
/// derivatives `(d friction / d phi, d friction / d lambda, dR / d phi, dR / d lambda)`, at
/// flow `phi` and friction factor `lambda > 0`, in the regime of `phi`.
fn pipe(phi: f64, lambda: f64) -> (f64, f64, [f64; 4]) {
    let s = lambda.sqrt();
    let re = (phi * D / (NU * A)).abs();
    let turbulent = re > RCRIT;
    // R = 1/s - 1.74 + 2 log10(u), u = 2k/d + 18.7 / (re' s), re' = re or RCRIT.
    let rr = if turbulent { re } else { RCRIT };
    let u = 2.0 * K / D + 18.7 / (rr * s);
    let r = 1.0 / s - 1.74 + 2.0 * u.log10();
    let dlog = 2.0 / (std::f64::consts::LN_10 * u);
    // d(1/s)/d lambda = -1 / (2 lambda s); du/d lambda = 18.7 / rr d(1/s)/d lambda.
    let d_inv_s = -1.0 / (2.0 * lambda * s);
    let dr_dlambda = d_inv_s * (1.0 + dlog * 18.7 / rr);
    if turbulent {
        let q = RHO * LENGTH / (A * A * D);
        let dre_dphi = phi.signum() * D / (NU * A);
        let dr_dphi = dlog * (-18.7 / (re * re * s)) * dre_dphi;
        (
            lambda * q * phi * phi,
            r,
            [2.0 * lambda * q * phi, q * phi * phi, dr_dphi, dr_dlambda],
        )
    } else {
        let q = 32.0 * MU * LENGTH / (A * D * D);
        (q * phi, r, [q, 0.0, 0.0, dr_dlambda])
    }
}

impl WaterTube {
    /// The Test Set's consistent start: no flow, every pressure `109 800` Pa, the laminar
    /// friction factor, `y' = 0` (the inflows and their first derivatives vanish at `t = 0`,
    /// so the hidden constraints hold too).
    pub fn initial() -> ([f64; WATER_DIM], [f64; WATER_DIM]) {
        let mut y = [0.0; WATER_DIM];
        y[18..36].fill(LAMBDA0);
        y[36..].fill(109_800.0);
        (y, [0.0; WATER_DIM])
    }
}

impl ImplicitDae for WaterTube {
    fn dimension(&self) -> usize {
        WATER_DIM
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        if y[18..36].iter().any(|&l| l < 0.0) {
            out.fill(f64::NAN);
            return;
        }
        let (ein1, ein13, eout10) = inflows(t);
        for n in 1..=13 {
            out[pressure(n)] = 0.0;
        }
        out[pressure(1)] = -ein1;
        out[pressure(13)] = -ein13;
        out[pressure(10)] = eout10;
        for (e, &(i, j)) in PIPES.iter().enumerate() {
            let (friction, r, _) = pipe(y[e], y[18 + e]);
            out[e] = V * yp[e] - (y[pressure(i)] - y[pressure(j)] - friction);
            out[18 + e] = -r;
            // -netflow: the flow leaves i and enters j.
            out[pressure(i)] += y[e];
            out[pressure(j)] -= y[e];
        }
        out[pressure(5)] += C * yp[pressure(5)];
        out[pressure(8)] += C * yp[pressure(8)];
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        for (e, &(i, j)) in PIPES.iter().enumerate() {
            let l = 18 + e;
            let (_, _, [df_dphi, df_dlambda, dr_dphi, dr_dlambda]) = pipe(y[e], y[l]);
            m.set(e, e, c * V + df_dphi);
            if df_dlambda != 0.0 {
                m.set(e, l, df_dlambda);
            }
            m.set(e, pressure(i), -1.0);
            m.set(e, pressure(j), 1.0);
            if dr_dphi != 0.0 {
                m.set(l, e, -dr_dphi);
            }
            m.set(l, l, -dr_dlambda);
            m.set(pressure(i), e, 1.0);
            m.set(pressure(j), e, -1.0);
        }
        m.set(pressure(5), pressure(5), c * C);
        m.set(pressure(8), pressure(8), c * C);
    }

    /// The constant diagonal `M`: `V` on the flows, `C` on `p5`, `p8`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for e in 0..PIPES.len() {
            m.set(e, e, V);
        }
        m.set(pressure(5), pressure(5), C);
        m.set(pressure(8), pressure(8), C);
        true
    }
}
