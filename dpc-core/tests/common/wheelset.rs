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
//! gives a non-finite residual (the integrators retry a smaller step).
//!
//! The iteration matrix and the mass matrix are exact: the same equations are declared with
//! `dpc::model!` in [`WheelsetModel`] and the macro differentiates them symbolically, as for a
//! plant a user declares (the Test Set supplies no Jacobian). The residual stays this
//! transcription (what `bench/ida_peer.c` transcribes); `tests/wheelset.rs` checks that the
//! generated residual equals it and the generated matrix equals its central differences.
//! What the declaration does not represent: the transcription's derailment checks, which are
//! not equations. Off the rail's circle the rail profile's square root is NaN by itself (the
//! transcription stops `1e-5` earlier), and a contact point at `xi = 0` or at the track's
//! centre line divides `0 / 0` (the slopes `x / |x|`); but a contact point beyond the wheel's
//! cone (`|xi| >= 4`) and a nearly singular normal-force system (`|deter| < 1e-8`) give the
//! model finite (or infinite) values where the transcription gives NaN. The integrators
//! evaluate the transcription's residual, so they see all its checks: at such a point the
//! residual is NaN and the step is retried, whatever the matrix.
#![allow(dead_code)]

use dpc::core::DaeModel;
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
        let (x, z) = y.split_at(WheelsetModel::N_STATES);
        let xdot = &yp[..WheelsetModel::N_STATES];
        WheelsetModel::default().iteration_matrix(t, x, xdot, z, &[], c, m);
    }

    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        m: &mut S,
    ) -> bool {
        let (x, z) = y.split_at(WheelsetModel::N_STATES);
        let xdot = &yp[..WheelsetModel::N_STATES];
        WheelsetModel::default().mass_matrix(t, x, xdot, z, &[], m)
    }
}

dpc::model! {
    /// The wheelset of [the module](self) declared in the DSL: the same equations as
    /// [`forces`] and [`Wheelset`]'s residual, in the same rows and unknowns' order (states
    /// `y1..y11`, algebraic unknowns `y12..y17`), so that the macro differentiates them exactly.
    /// Written without branches: the profiles' slopes with `signum` (derivative 0, as the
    /// transcription's constant sign); the friction saturation (`T *= |mu N| / |T|` where `|T| > |mu N|`) as
    /// a division by `max(1, u)`, `u = |T| / |mu N| = sqrt(tanh_x^2 + tanh_y^2) <= sqrt(2)`,
    /// written `0.5 (1 + u + abs(u - 1))`: unsaturated `1` within two roundings with the
    /// derivative exactly `0` (the two `du` cancel), saturated `u` within two roundings.
    pub WheelsetModel {
        states { x, y, z, theta, phi, xd, yd, zd, thetad, phid, beta }
        algebraic { psir, xir, psil, xil, laml, lamr }
        let mr = 16.08;
        let g = 9.81;
        let v0 = 30.0;
        let rn0 = 0.1;
        let li1 = 0.0605;
        let li2 = 0.366;
        let mu = 0.12;
        let xl = 0.19;
        let cx = 6400.0;
        let cz = 6400.0;
        let ek = 1.3537956;
        let gg = 0.7115218;
        let sigma = 0.28;
        let gm = 7.92e10;
        let pi_ts = 3.1415926;
        let c11 = 4.72772197;
        let c22 = 4.27526987;
        let c23 = 1.97203505;
        let delta0 = 0.0262;
        let ar = 0.1506;
        let rs = 0.06;
        let omega = v0 / rn0;
        let sit = sin(theta);
        let cot = cos(theta);
        let sip = sin(phi);
        let cop = cos(phi);
        let sisl = sin(psil);
        let cosl = cos(psil);
        let sisr = sin(psir);
        let cosr = cos(psir);
        let e1 = laml * 1e4;
        let e2 = lamr * 1e4;
        // Wheel profiles (cones) at the contact points: value, slope (curvature 0).
        let ta = tan(delta0);
        let rxl = rn0 + ta * (ar - abs(xil));
        let drxl = -ta * signum(xil);
        let rxr = rn0 + ta * (ar - abs(xir));
        let drxr = -ta * signum(xir);
        // Rail profiles (circles): slope and curvature at the contact points.
        let sir = sin(delta0) * rs;
        let xgl = x + xil * cot * cop + rxl * (cot * sip * cosl - sit * sisl);
        let agl = abs(xgl);
        let hl = sqrt(rs * rs - (agl - ar - sir).powi(2));
        let dgxl = signum(xgl) * (-agl + ar + sir) / hl;
        let d2gxl = -rs * rs / (hl * hl * hl);
        let xgr = x + xir * cot * cop + rxr * (cot * sip * cosr - sit * sisr);
        let agr = abs(xgr);
        let hr = sqrt(rs * rs - (agr - ar - sir).powi(2));
        let dgxr = signum(xgr) * (-agr + ar + sir) / hr;
        let d2gxr = -rs * rs / (hr * hr * hr);
        // Constraint rows G (constm); entries 1 and 2 are -1 and 0.
        let ql0 = dgxl;
        let ql3 = dgxl * (rxl * (-cot * sisl - cosl * sip * sit) - cop * sit * xil);
        let ql4 = -(cosl * rxl * sip) - cop * xil + dgxl * (cop * cosl * cot * rxl - cot * sip * xil);
        let qr0 = dgxr;
        let qr3 = dgxr * (rxr * (-cot * sisr - cosr * sip * sit) - cop * sit * xir);
        let qr4 = -(cosr * rxr * sip) - cop * xir + dgxr * (cop * cosr * cot * rxr - cot * sip * xir);
        // Angles of the contact planes.
        let deltal = atan(((drxl * cop - sip * cosl) * cot + sisl * sit) / (-drxl * sip - cosl * cop));
        let deltar = atan(((drxr * cop - sip * cosr) * cot + sisr * sit) / (drxr * sip + cosr * cop));
        let sidl = sin(deltal);
        let codl = cos(deltal);
        let sidr = sin(deltar);
        let codr = cos(deltar);
        // Normal forces.
        let deter = -sidl * codr - sidr * codl;
        let wn1 = ql0 * e1 + qr0 * e2;
        let wn2 = -e1 - e2;
        let fnl = (codr * wn1 - sidr * wn2) / deter;
        let fnr = (-codl * wn1 - sidl * wn2) / deter;
        let w = omega + beta;
        // Left creep force (creep, s = 1).
        let sitl = sin(theta / codl);
        let cotl = cos(theta / codl);
        let rrl = rxl * sqrt(1.0 + drxl * drxl);
        let rhogl = -d2gxl / (1.0 + dgxl * dgxl).powf(1.5);
        let ccl = ((abs(fnl) * 3.0 * (1.0 - sigma) * ek)
            / (2.0 * pi_ts * (0.5 / rrl + 0.5 * rhogl) * gm * sqrt(gg))).powf(1.0 / 3.0);
        let vk1l = -w * rxl * (sitl * cosl + cotl * sip * sisl) + xd
            - thetad * (rxl * (sitl * sip * cosl + cotl * sisl) + xil * sitl * cop)
            - phid * cotl * (xil * sip - rxl * cop * cosl);
        let vk2l = w * rxl * cop * sisl + yd + phid * (xil * cop + rxl * sip * cosl);
        let vk3l = -w * rxl * (cotl * cosl - sitl * sip * sisl) + v0 + zd
            - thetad * (xil * cotl * cop + rxl * (cotl * sip * cosl - sitl * sisl))
            + phid * sitl * (xil * sip - rxl * cop * cosl);
        let vrl = 0.5 * sqrt((vk1l - 2.0 * xd).powi(2) + (vk2l - 2.0 * yd).powi(2)
            + (vk3l - 2.0 * zd - 2.0 * v0).powi(2));
        let nuxl = (sitl * vk1l + cotl * vk3l) / vrl;
        let nuyl = (cotl * codl * vk1l + sidl * vk2l - sitl * codl * vk3l) / vrl;
        let phisl = (-sidl * w + codl * thetad) / vrl;
        let wtl = mu * fnl;
        let tx0l = -wtl * tanh(gm * ccl * ccl * c11 * nuxl / wtl);
        let ty0l = -wtl * tanh(gm * ccl * ccl * c22 * nuyl / wtl + gm * ccl * ccl * ccl * c23 * phisl / wtl);
        let ul = sqrt(tx0l * tx0l + ty0l * ty0l) / abs(wtl);
        let satl = 0.5 * (1.0 + ul + abs(ul - 1.0));
        let txl = tx0l / satl;
        let tyl = ty0l / satl;
        let tl0 = sitl * txl + cotl * codl * tyl;
        let tl1 = sidl * tyl;
        let tl2 = cotl * txl - sitl * codl * tyl;
        // Right creep force (creep, s = -1).
        let sitr = sin(theta / codr);
        let cotr = cos(theta / codr);
        let rrr = rxr * sqrt(1.0 + drxr * drxr);
        let rhogr = -d2gxr / (1.0 + dgxr * dgxr).powf(1.5);
        let ccr = ((abs(fnr) * 3.0 * (1.0 - sigma) * ek)
            / (2.0 * pi_ts * (0.5 / rrr + 0.5 * rhogr) * gm * sqrt(gg))).powf(1.0 / 3.0);
        let vk1r = -w * rxr * (sitr * cosr + cotr * sip * sisr) + xd
            - thetad * (rxr * (sitr * sip * cosr + cotr * sisr) + xir * sitr * cop)
            - phid * cotr * (xir * sip - rxr * cop * cosr);
        let vk2r = w * rxr * cop * sisr + yd + phid * (xir * cop + rxr * sip * cosr);
        let vk3r = -w * rxr * (cotr * cosr - sitr * sip * sisr) + v0 + zd
            - thetad * (xir * cotr * cop + rxr * (cotr * sip * cosr - sitr * sisr))
            + phid * sitr * (xir * sip - rxr * cop * cosr);
        let vrr = 0.5 * sqrt((vk1r - 2.0 * xd).powi(2) + (vk2r - 2.0 * yd).powi(2)
            + (vk3r - 2.0 * zd - 2.0 * v0).powi(2));
        let nuxr = (sitr * vk1r + cotr * vk3r) / vrr;
        let nuyr = (cotr * codr * vk1r - sidr * vk2r - sitr * codr * vk3r) / vrr;
        let phisr = (sidr * w + codr * thetad) / vrr;
        let wtr = mu * fnr;
        let tx0r = -wtr * tanh(gm * ccr * ccr * c11 * nuxr / wtr);
        let ty0r = -wtr * tanh(gm * ccr * ccr * c22 * nuyr / wtr + gm * ccr * ccr * ccr * c23 * phisr / wtr);
        let ur = sqrt(tx0r * tx0r + ty0r * ty0r) / abs(wtr);
        let satr = 0.5 * (1.0 + ur + abs(ur - 1.0));
        let txr = tx0r / satr;
        let tyr = ty0r / satr;
        let tr0 = sitr * txr + cotr * codr * tyr;
        let tr1 = -sidr * tyr;
        let tr2 = cotr * txr - sitr * codr * tyr;
        // Spring forces of the (massless) chassis.
        let lm2 = -2.0 * xl * xl * cz * theta;
        equations {
            der(x) = xd;
            der(y) = yd;
            der(z) = zd;
            der(theta) = thetad;
            der(phi) = phid;
            mr * der(xd) == tl0 + tr0 + ql0 * e1 + qr0 * e2 - 2.0 * cx * x;
            mr * der(yd) == tl1 + tr1 - mr * g - e1 - e2;
            mr * der(zd) == tl2 + tr2 - 2.0 * cz * z;
            li2 * cop * der(thetad) == li2 * thetad * phid * sip - li1 * w * phid
                - (li1 - li2) * thetad * sip * phid
                - (xil * sit + rxl * sisl * cot * cop) * tl0 - rxl * sisl * sip * tl1
                + (-xil * cot + rxl * sisl * sit * cop) * tl2
                - (xir * sit + rxr * sisr * cot * cop) * tr0 - rxr * sisr * sip * tr1
                + (-xir * cot + rxr * sisr * sit * cop) * tr2
                + cop * lm2 + ql3 * e1 + qr3 * e2;
            li2 * der(phid) == li1 * w * thetad * cop + (li1 - li2) * thetad * sip * thetad * cop
                - (xil * cot * sip - rxl * cosl * cot * cop) * tl0
                + (xil * cop + rxl * cosl * sip) * tl1
                + (xil * sit * sip - rxl * cosl * sit * cop) * tl2
                - (xir * cot * sip - rxr * cosr * cot * cop) * tr0
                + (xir * cop + rxr * cosr * sip) * tr1
                + (xir * sit * sip - rxr * cosr * sit * cop) * tr2
                + ql4 * e1 + qr4 * e2;
            li1 * sip * der(thetad) + li1 * der(beta) == -li1 * thetad * phid * cop
                - rxl * (cosl * sit + sisl * cot * sip) * tl0 + rxl * sisl * cop * tl1
                - rxl * (cosl * cot - sisl * sit * sip) * tl2
                - rxr * (cosr * sit + sisr * cot * sip) * tr0 + rxr * sisr * cop * tr1
                - rxr * (cosr * cot - sisr * sit * sip) * tr2
                + sip * lm2;
            0.0 == ql0 * xd - yd + ql3 * thetad + ql4 * phid;
            0.0 == qr0 * xd - yd + qr3 * thetad + qr4 * phid;
            0.0 == dgxl * (drxl * sip + cop * cosl) + drxl * cot * cop - cot * sip * cosl + sit * sisl;
            0.0 == drxl * sit * cop - sit * sip * cosl - cot * sisl;
            0.0 == dgxr * (drxr * sip + cop * cosr) + drxr * cot * cop - cot * sip * cosr + sit * sisr;
            0.0 == drxr * sit * cop - sit * sip * cosr - cot * sisr;
        }
    }
}
