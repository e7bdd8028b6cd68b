//! The wheelset of the Test Set for IVP Solvers (Univ. of Bari; problem `wheel`, after B. Simeon,
//! C. Führer and P. Rentrop, "Introduction to differential-algebraic equations in vehicle system
//! dynamics", Surv. Math. Ind. 1, 1991): a railway wheelset running at `V = 30 m/s` on a straight
//! track, conical wheels on circular rails, nonlinear creep forces (Jaschinski's smooth
//! approximation), an index-2 implicit DAE of 17 unknowns on `t` in `[0, 10]`:
//!
//! * `y1..y5`: the position `p = (x, y, z, theta, phi)` (lateral, vertical, longitudinal
//!   displacement, yaw and roll angle), `y6..y10`: the velocities `v = p'`, `y11`: `beta`, the
//!   deviation of the rotation speed from `V / r0`;
//! * `y12..y15`: the contact point coordinates `q = (psi_R, xi_R, psi_L, xi_L)` (index 1);
//! * `y16, y17`: the normal constraint forces `lambda_L, lambda_R` in units of `1e4` N (index 2).
//!
//! ```text
//! p' = v
//! M(phi) (v', beta')' = f(p, v, beta, q, lambda)     (6 rows: Newton's and Euler's laws)
//! 0 = G(p, q) v                                      (2 rows: the contact constraints, derived)
//! 0 = g2(p, q)                                       (4 rows: the contact geometry)
//! ```
//!
//! Equations, constants, initial values and the reference solution are transcribed from the
//! Test Set's problem file (`wheel.f`: `reswhs`, `creep`, `constm`, `railp`, `wheelp`, the index-2
//! formulation, straight track, no propulsion, no chassis mass), written here anew with the
//! track's curvature and inclination (zero) dropped. The Test Set's residual is `M y' - f` in
//! the unknowns' order above; its rows are kept in the order of its subroutine (`f` is evaluated
//! with `lambda` and `q` swapped into the positions the subroutine expects). A derailment (a
//! contact point off the profiles; the Test Set's `ires = -1`) or a singular contact geometry
//! gives a non-finite residual (the integrators retry a smaller step). The iteration matrix:
//! `dF/dy'` exact, `dF/dy` by central differences of the residual (step `eps^(1/3)
//! max(|y_j|, 1e-3)`).
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// The wheelset ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct Wheelset;

/// Number of unknowns of [`Wheelset`].
pub const WHEEL_DIM: usize = 17;

/// Interval end of [`Wheelset`].
pub const WHEEL_T_END: f64 = 10.0;

/// The index of each unknown: `lambda` (`y16, y17`) has index 2 (the Test Set's
/// `ind = (15, 2, 0)`).
pub const WHEEL_INDEX: [u8; WHEEL_DIM] = [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2];

/// Reference solution at `t = 10`, the Test Set's (DASSL at `rtol = atol = 1e-9` on `p, v, q`,
/// the multipliers out of the error control).
#[allow(clippy::excessive_precision)]
pub const WHEEL_REF: [f64; WHEEL_DIM] = [
    0.86355386965811e-02,
    0.13038281022727e-04,
    -0.93635784016818e-04,
    -0.13642299804033e-01,
    0.15292895005422e-02,
    -0.76985374142666e-01,
    -0.25151106429207e-03,
    0.20541188079539e-02,
    -0.23904837703692e+00,
    -0.13633468454173e-01,
    -0.24421377661131e+00,
    -0.33666751972196e-03,
    -0.15949425684022e+00,
    0.37839614386969e-03,
    0.14173214964613e+00,
    -0.10124044903201e-01,
    -0.56285630573753e-02,
];

const MR: f64 = 16.08;
const G: f64 = 9.81;
const V: f64 = 30.0;
const RN0: f64 = 0.1;
const LI1: f64 = 0.0605;
const LI2: f64 = 0.366;
const MU: f64 = 0.12;
const XL: f64 = 0.19;
const CX: f64 = 6400.0;
const CZ: f64 = 6400.0;
/// Creep-force constants (Kalker's coefficients and material data).
const E: f64 = 1.3537956;
const GG: f64 = 0.7115218;
const SIGMA: f64 = 0.28;
const GM: f64 = 7.92e10;
/// The Test Set's value of pi in the contact ellipses (eight digits, kept as the reference
/// was computed with it).
#[allow(clippy::approx_constant)]
const PI_TS: f64 = 3.1415926;
const C11: f64 = 4.72772197;
const C22: f64 = 4.27526987;
const C23: f64 = 1.97203505;
/// Cone angle, half the wheel distance, rail radius, profile tolerance.
const DELTA0: f64 = 0.0262;
const AR: f64 = 0.1506;
const RS: f64 = 0.06;
const EPS: f64 = 0.00001;
/// Wheel profile limits.
const B1: f64 = 0.0;
const B2: f64 = 4.0;
/// Smallest determinant of the normal-force system.
const TOL: f64 = 1e-8;

/// A profile: value and first two derivatives at `xi`, or `None` off the profile.
type Profile = Option<(f64, f64, f64)>;

/// The wheel profile (a cone) at `xi`.
fn wheel_profile(xi: f64) -> Profile {
    let a = xi.abs();
    if B1 >= a || a >= B2 {
        return None;
    }
    let ta = DELTA0.tan();
    Some((RN0 + ta * (AR - a), -ta * xi.signum(), 0.0))
}

/// The rail profile (a circle) at `x`.
fn rail_profile(x: f64) -> Profile {
    let sir = DELTA0.sin() * RS;
    let a = x.abs();
    if AR + sir + RS - EPS <= a || AR + sir - RS + EPS >= a {
        return None;
    }
    let t = (RS * RS - (a - AR - sir).powi(2)).sqrt();
    Some((
        t - RN0 - DELTA0.cos() * RS,
        x.signum() * (-a + AR + sir) / t,
        -RS * RS / (t * t * t),
    ))
}

/// The constraint row `G` of one contact (`constm`).
fn constraint_row(
    xr: f64,
    rx: f64,
    dgx: f64,
    sct: (f64, f64),
    scp: (f64, f64),
    scs: (f64, f64),
) -> [f64; 5] {
    let ((sit, cot), (sip, cop), (sis, cos)) = (sct, scp, scs);
    [
        dgx,
        -1.0,
        0.0,
        dgx * (rx * (-cot * sis - cos * sip * sit) - cop * sit * xr),
        -(cos * rx * sip) - cop * xr + dgx * (cop * cos * cot * rx - cot * sip * xr),
    ]
}

/// One contact's data for the creep forces.
struct Contact {
    xr: f64,
    rx: f64,
    drx: f64,
    d2rx: f64,
    dgx: f64,
    d2gx: f64,
    sis: f64,
    cos: f64,
    delta: f64,
    fn_: f64,
}

/// The creep force of one contact in the nominal frame (`creep`, one side; `right` flips the
/// signs of the lateral terms as the Test Set's right contact has them).
fn creep_force(y: &[f64], c: &Contact, right: bool) -> [f64; 3] {
    let (teta, phi) = (y[3], y[4]);
    let (xxp, yyp, zzp, tetap, phip, betap) = (y[5], y[6], y[7], y[8], y[9], y[10]);
    let omega = V / RN0;
    let (sip, cop) = phi.sin_cos();
    let (sid, cod) = c.delta.sin_cos();
    let (sit, cot) = (teta / cod).sin_cos();
    let (rx, xr, sis, cos) = (c.rx, c.xr, c.sis, c.cos);
    // Contact ellipse.
    let rr = rx * (1.0 + c.drx * c.drx).sqrt();
    let rhog = -c.d2gx / (1.0 + c.dgx * c.dgx).powf(1.5);
    let rhor = c.d2rx / (1.0 + c.drx * c.drx).powf(1.5);
    let (a, b) = (0.5 / rr, 0.5 * (rhog + rhor));
    let wabs = c.fn_.abs() * 3.0;
    let cc =
        ((wabs * (1.0 - SIGMA) * E) / (2.0 * PI_TS * (a + b) * GM * GG.sqrt())).powf(1.0 / 3.0);
    // Relative velocity (straight track: the curvature terms vanish).
    let w = omega + betap;
    let vk1 = -w * rx * (sit * cos + cot * sip * sis) + xxp
        - tetap * (rx * (sit * sip * cos + cot * sis) + xr * sit * cop)
        - phip * cot * (xr * sip - rx * cop * cos);
    let vk2 = w * rx * cop * sis + yyp + phip * (xr * cop + rx * sip * cos);
    let vk3 = -w * rx * (cot * cos - sit * sip * sis) + V + zzp
        - tetap * (xr * cot * cop + rx * (cot * sip * cos - sit * sis))
        + phip * sit * (xr * sip - rx * cop * cos);
    // Rolling velocity.
    let vk4 = vk1 - 2.0 * xxp;
    let vk5 = vk2 - 2.0 * yyp;
    let vk6 = vk3 - 2.0 * zzp - 2.0 * V;
    let vr = 0.5 * (vk4 * vk4 + vk5 * vk5 + vk6 * vk6).sqrt();
    // Creepages.
    let s = if right { -1.0 } else { 1.0 };
    let nux = (sit * vk1 + cot * vk3) / vr;
    let nuy = (cot * cod * vk1 + s * sid * vk2 - sit * cod * vk3) / vr;
    let phis = (-s * sid * w + cod * tetap) / vr;
    // Creep forces, saturated at the friction limit.
    let wt = MU * c.fn_;
    let mut tx = -wt * (GM * cc * cc * C11 * nux / wt).tanh();
    let mut ty = -wt * (GM * cc * cc * C22 * nuy / wt + GM * cc * cc * cc * C23 * phis / wt).tanh();
    let sqt = (tx * tx + ty * ty).sqrt();
    if sqt * sqt > wt * wt {
        tx *= wt.abs() / sqt;
        ty *= wt.abs() / sqt;
    }
    [
        sit * tx + cot * cod * ty,
        s * sid * ty,
        cot * tx - sit * cod * ty,
    ]
}

/// `f` of the Test Set (`reswhs`, index-2 formulation) at `y` in the unknowns' order of this
/// fixture, in its rows' order; `None` at a derailment or a singular contact geometry.
fn forces(y: &[f64]) -> Option<[f64; WHEEL_DIM]> {
    let (xx, zz, teta, phi) = (y[0], y[2], y[3], y[4]);
    let (tetap, phip, betap) = (y[8], y[9], y[10]);
    let (psir, xrr, psil, xrl) = (y[11], y[12], y[13], y[14]);
    let (e1, e2) = (y[15] * 1e4, y[16] * 1e4);
    let omega = V / RN0;
    let (sit, cot) = teta.sin_cos();
    let (sip, cop) = phi.sin_cos();
    let (sisl, cosl) = psil.sin_cos();
    let (sisr, cosr) = psir.sin_cos();
    // Profiles at the contact points.
    let (rxl, drxl, d2rxl) = wheel_profile(xrl)?;
    let xgl = xx + xrl * cot * cop + rxl * (cot * sip * cosl - sit * sisl);
    // The rail heights enter only the index-3 form's constraints.
    let (_, dgxl, d2gxl) = rail_profile(xgl)?;
    let (rxr, drxr, d2rxr) = wheel_profile(xrr)?;
    let xgr = xx + xrr * cot * cop + rxr * (cot * sip * cosr - sit * sisr);
    let (_, dgxr, d2gxr) = rail_profile(xgr)?;
    let ql = constraint_row(xrl, rxl, dgxl, (sit, cot), (sip, cop), (sisl, cosl));
    let qr = constraint_row(xrr, rxr, dgxr, (sit, cot), (sip, cop), (sisr, cosr));
    // Angles of the contact planes.
    let w1 = (drxl * cop - sip * cosl) * cot + sisl * sit;
    let w2 = -drxl * sip - cosl * cop;
    let deltal = (w1 / w2).atan();
    let w1 = (drxr * cop - sip * cosr) * cot + sisr * sit;
    let w2 = drxr * sip + cosr * cop;
    let deltar = (w1 / w2).atan();
    let (sidl, codl) = deltal.sin_cos();
    let (sidr, codr) = deltar.sin_cos();
    // Normal forces.
    let deter = -sidl * codr - sidr * codl;
    if deter.abs() < TOL {
        return None;
    }
    let w1 = ql[0] * e1 + qr[0] * e2;
    let w2 = ql[1] * e1 + qr[1] * e2;
    let fnl = (codr * w1 - sidr * w2) / deter;
    let fnr = (-codl * w1 - sidl * w2) / deter;
    let left = Contact {
        xr: xrl,
        rx: rxl,
        drx: drxl,
        d2rx: d2rxl,
        dgx: dgxl,
        d2gx: d2gxl,
        sis: sisl,
        cos: cosl,
        delta: deltal,
        fn_: fnl,
    };
    let right = Contact {
        xr: xrr,
        rx: rxr,
        drx: drxr,
        d2rx: d2rxr,
        dgx: dgxr,
        d2gx: d2gxr,
        sis: sisr,
        cos: cosr,
        delta: deltar,
        fn_: fnr,
    };
    let tl = creep_force(y, &left, false);
    let tr = creep_force(y, &right, true);
    // Chassis forces (no chassis mass): only the springs.
    let fq2 = 0.0;
    let fq3 = -2.0 * CZ * zz;
    let lm2 = -2.0 * XL * XL * CZ * teta;
    let mut f = [0.0; WHEEL_DIM];
    f[..5].copy_from_slice(&y[5..10]);
    f[5] = tl[0] + tr[0] + ql[0] * e1 + qr[0] * e2 - 2.0 * CX * xx;
    f[6] = tl[1] + tr[1] + fq2 - MR * G + ql[1] * e1 + qr[1] * e2;
    f[7] = tl[2] + tr[2] + fq3 + ql[2] * e1 + qr[2] * e2;
    let w1 = -(xrl * sit + rxl * sisl * cot * cop) * tl[0] - rxl * sisl * sip * tl[1]
        + (-xrl * cot + rxl * sisl * sit * cop) * tl[2];
    let w2 = -(xrr * sit + rxr * sisr * cot * cop) * tr[0] - rxr * sisr * sip * tr[1]
        + (-xrr * cot + rxr * sisr * sit * cop) * tr[2];
    f[8] =
        LI2 * tetap * phip * sip - LI1 * (omega + betap) * phip - (LI1 - LI2) * tetap * sip * phip
            + w1
            + w2
            + cop * lm2
            + ql[3] * e1
            + qr[3] * e2;
    let w1 = -(xrl * cot * sip - rxl * cosl * cot * cop) * tl[0]
        + (xrl * cop + rxl * cosl * sip) * tl[1]
        + (xrl * sit * sip - rxl * cosl * sit * cop) * tl[2];
    let w2 = -(xrr * cot * sip - rxr * cosr * cot * cop) * tr[0]
        + (xrr * cop + rxr * cosr * sip) * tr[1]
        + (xrr * sit * sip - rxr * cosr * sit * cop) * tr[2];
    f[9] = LI1 * (omega + betap) * tetap * cop
        + (LI1 - LI2) * tetap * sip * tetap * cop
        + w1
        + w2
        + ql[4] * e1
        + qr[4] * e2;
    let w1 = -rxl * (cosl * sit + sisl * cot * sip) * tl[0] + rxl * sisl * cop * tl[1]
        - rxl * (cosl * cot - sisl * sit * sip) * tl[2];
    let w2 = -rxr * (cosr * sit + sisr * cot * sip) * tr[0] + rxr * sisr * cop * tr[1]
        - rxr * (cosr * cot - sisr * sit * sip) * tr[2];
    f[10] = -LI1 * tetap * phip * cop + w1 + w2 + sip * lm2;
    // Contact constraints, index-2 form: G v.
    f[11] = (0..5).map(|i| ql[i] * y[5 + i]).sum();
    f[12] = (0..5).map(|i| qr[i] * y[5 + i]).sum();
    // Contact geometry (normals parallel, no intersection).
    f[13] = dgxl * (drxl * sip + cop * cosl) + drxl * cot * cop - cot * sip * cosl + sit * sisl;
    f[14] = drxl * sit * cop - sit * sip * cosl - cot * sisl;
    f[15] = dgxr * (drxr * sip + cop * cosr) + drxr * cot * cop - cot * sip * cosr + sit * sisr;
    f[16] = drxr * sit * cop - sit * sip * cosr - cot * sisr;
    Some(f)
}

impl Wheelset {
    /// The Test Set's consistent initial values `(y0, y0')`.
    #[allow(clippy::excessive_precision)]
    pub fn initial() -> ([f64; WHEEL_DIM], [f64; WHEEL_DIM]) {
        let y = [
            0.14941e-02,
            0.40089e-06,
            0.11241e-05,
            -0.28573e-03,
            0.26459e-03,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            -7.4122380357667139e-06,
            -0.1521364296121248,
            7.5634406395172940e-06,
            0.1490635714733819,
            -8.3593e-3,
            -7.4144e-3,
        ];
        let mut yp = [0.0; WHEEL_DIM];
        yp[5..11].copy_from_slice(&[
            -1.975258894011285,
            -1.0898297102811276e-03,
            7.8855083626142589e-02,
            -5.533362821731549,
            -0.3487021489546511,
            -2.132968724380927,
        ]);
        (y, yp)
    }
}

impl ImplicitDae for Wheelset {
    fn dimension(&self) -> usize {
        WHEEL_DIM
    }

    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let Some(f) = forces(y) else {
            out.fill(f64::NAN);
            return;
        };
        let (sip, cop) = y[4].sin_cos();
        for i in 0..5 {
            out[i] = yp[i] - f[i];
        }
        for i in 5..8 {
            out[i] = MR * yp[i] - f[i];
        }
        out[8] = LI2 * cop * yp[8] - f[8];
        out[9] = LI2 * yp[9] - f[9];
        out[10] = LI1 * sip * yp[8] + LI1 * yp[10] - f[10];
        for i in 11..WHEEL_DIM {
            out[i] = -f[i];
        }
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (sip, cop) = y[4].sin_cos();
        for i in 0..5 {
            m.add(i, i, c);
        }
        for i in 5..8 {
            m.add(i, i, c * MR);
        }
        m.add(8, 8, c * LI2 * cop);
        m.add(9, 9, c * LI2);
        m.add(10, 8, c * LI1 * sip);
        m.add(10, 10, c * LI1);
        let h0 = f64::EPSILON.cbrt();
        let (mut up, mut down) = ([0.0; WHEEL_DIM], [0.0; WHEEL_DIM]);
        let mut z = [0.0; WHEEL_DIM];
        z.copy_from_slice(y);
        for j in 0..WHEEL_DIM {
            let h = h0 * y[j].abs().max(1e-3);
            z[j] = y[j] + h;
            self.residual(t, &z, yp, &mut up);
            z[j] = y[j] - h;
            self.residual(t, &z, yp, &mut down);
            z[j] = y[j];
            for i in 0..WHEEL_DIM {
                let d = (up[i] - down[i]) / (2.0 * h);
                if d != 0.0 {
                    m.add(i, j, d);
                }
            }
        }
    }
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, y: &[f64], _: &[f64], m: &mut S) -> bool {
        let (sip, cop) = y[4].sin_cos();
        for i in 0..5 {
            m.add(i, i, 1.0);
        }
        for i in 5..8 {
            m.add(i, i, MR);
        }
        m.add(8, 8, LI2 * cop);
        m.add(9, 9, LI2);
        m.add(10, 8, LI1 * sip);
        m.add(10, 10, LI1);
        true
    }
}
