//! DAEs from the literature with exact solutions, written as a user would write them (residual,
//! exact iteration matrix and mass matrix, which unknowns are differential; no constraint
//! derivatives): shared by `tests/literature_daes.rs`. Each fixture has `exact(t) -> (y, y')`,
//! checked against its residual there before any integration is scored against it.
//!
//! * [`Kvaerno`]: Kværnø's nonlinear, fully implicit index-1 problem (A. Kværnø, "Runge-Kutta
//!   methods applied to fully implicit differential-algebraic equations of index 1", Math.
//!   Comp. 54 (1990) 583-625): `y'` enters the first equation nonlinearly (`sin^2(y1')`), the
//!   second is algebraic but not solved for any unknown.
//! * [`Jay`]: Jay's nonlinear index-2 problem in Hessenberg form (L. O. Jay, "Convergence of a
//!   class of Runge-Kutta methods for differential-algebraic systems of index 2", BIT 33 (1993),
//!   Example 7): two differential unknowns, one algebraic multiplier entering nonlinearly.
//! * [`CircularTrack`]: a particle on the unit circle driven by a constant tangential force
//!   (the test problem of Arévalo, Führer and Söderlind for index-3 Euler-Lagrange DAEs, as
//!   recalled here; every formula below is checked against its exact solution): positions
//!   constrained, multiplier algebraic, index 3, exact solution through `sin t^2`, `cos t^2`.
//! * [`KnifeEdge`]: a knife edge (skate) on an inclined plane turning at a constant rate, the
//!   classical nonholonomic example (Neimark & Fufaev, "Dynamics of nonholonomic systems";
//!   Bloch, "Nonholonomic mechanics and control"): a velocity constraint with its multiplier,
//!   index 2, with a closed-form solution.
//! * [`Bcp`]: the linear time-varying problem of Gear and Petzold (Brenan, Campbell & Petzold,
//!   "Numerical solution of initial-value problems in DAEs"; Ascher & Petzold's book) with its
//!   parameter `eta`: index 2 for every `eta != -1`, with every unknown of index 2 (its local
//!   pencil `det(c A + B) = 1 + eta` does not depend on `c`), not index 1.
//! * [`AnalyticIndex2`]: the linear time-varying index-2 problem of Ascher & Petzold's book
//!   ("Computer Methods for ODEs and DAEs", SIAM 1998, Example 10.2), the analytic example of
//!   SUNDIALS' IDA (`idaAnalytic_mels`): one differential unknown held by a constraint, one
//!   algebraic unknown that only the constraint's derivative determines.
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// Kværnø's problem (Math. Comp. 1990):
///
/// ```text
/// 0 = (sin^2(y1') + cos^2(y2)) y2'^2 - (t - 6)^2 (t - 2)^2 y1 e^-t
/// 0 = (4 - t) (y1 + y2)^3 - 64 t^2 e^-t y1 y2
/// ```
///
/// with `y1 = t^4 e^-t`, `y2 = (4 - t) t^3 e^-t` (so `y1' = y2` and the bracket is 1 on the
/// solution), on `[0.5, 1]` as in the paper. Both unknowns appear differentiated.
#[derive(Debug, Clone, Copy, Default)]
pub struct Kvaerno;

/// Interval of [`Kvaerno`] (Kværnø's).
pub const KVAERNO_T0: f64 = 0.5;
/// End of [`Kvaerno`]'s interval.
pub const KVAERNO_T_END: f64 = 1.0;

impl Kvaerno {
    /// The exact solution and its derivative.
    pub fn exact(t: f64) -> ([f64; 2], [f64; 2]) {
        let e = (-t).exp();
        let y = [t.powi(4) * e, (4.0 - t) * t.powi(3) * e];
        // d/dt (t^4 e^-t) = (4 - t) t^3 e^-t; d/dt ((4 t^3 - t^4) e^-t) = (t^2 - 8t + 12) t^2 e^-t.
        let yp = [
            (4.0 - t) * t.powi(3) * e,
            (t * t - 8.0 * t + 12.0) * t * t * e,
        ];
        (y, yp)
    }
}

impl ImplicitDae for Kvaerno {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let e = (-t).exp();
        let bracket = yp[0].sin().powi(2) + y[1].cos().powi(2);
        out[0] = bracket * yp[1] * yp[1] - (t - 6.0).powi(2) * (t - 2.0).powi(2) * y[0] * e;
        out[1] = (4.0 - t) * (y[0] + y[1]).powi(3) - 64.0 * t * t * e * y[0] * y[1];
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let e = (-t).exp();
        let bracket = yp[0].sin().powi(2) + y[1].cos().powi(2);
        let p2 = yp[1] * yp[1];
        m.set(
            0,
            0,
            -(t - 6.0).powi(2) * (t - 2.0).powi(2) * e + c * (2.0 * yp[0]).sin() * p2,
        );
        m.set(0, 1, -(2.0 * y[1]).sin() * p2 + c * 2.0 * bracket * yp[1]);
        let s2 = 3.0 * (4.0 - t) * (y[0] + y[1]).powi(2);
        m.set(1, 0, s2 - 64.0 * t * t * e * y[1]);
        m.set(1, 1, s2 - 64.0 * t * t * e * y[0]);
    }
    /// `d/dy'` of the first row (it depends on `y'` itself: `sin(2 y1') y2'^2` and
    /// `2 (sin^2(y1') + cos^2(y2)) y2'`); the second row has no derivatives.
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        yp: &[f64],
        m: &mut S,
    ) -> bool {
        let bracket = yp[0].sin().powi(2) + y[1].cos().powi(2);
        m.set(0, 0, (2.0 * yp[0]).sin() * yp[1] * yp[1]);
        m.set(0, 1, 2.0 * bracket * yp[1]);
        true
    }
}

/// Jay's index-2 problem (BIT 1993, Example 7), unknowns `(y1, y2, z)`:
///
/// ```text
/// y1' = y1 y2^2 z^2
/// y2' = y1^2 y2^2 - 3 y2^2 z
///  0  = y1^2 y2 - 1
/// ```
///
/// with `y1 = e^t`, `y2 = e^-2t`, `z = e^2t` on `[0, 1]`. `G f_z = y1^2 y2^2 (4 y2 z - 3)`, which
/// is `y1^2 y2^2 != 0` on the solution: index 2, Hessenberg. With `linear_multiplier` the first
/// equation is `y1' = y1 y2 z` (the variant with the multiplier entering linearly; same
/// solution).
#[derive(Debug, Clone, Copy, Default)]
pub struct Jay {
    /// `y1' = y1 y2 z` instead of `y1 y2^2 z^2`.
    pub linear_multiplier: bool,
}

/// End of [`Jay`]'s interval (from 0).
pub const JAY_T_END: f64 = 1.0;

impl Jay {
    /// The exact solution and its derivative.
    pub fn exact(t: f64) -> ([f64; 3], [f64; 3]) {
        let (a, b, c) = (t.exp(), (-2.0 * t).exp(), (2.0 * t).exp());
        ([a, b, c], [a, -2.0 * b, 2.0 * c])
    }
}

impl ImplicitDae for Jay {
    fn dimension(&self) -> usize {
        3
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (y1, y2, z) = (y[0], y[1], y[2]);
        out[0] = if self.linear_multiplier {
            yp[0] - y1 * y2 * z
        } else {
            yp[0] - y1 * y2 * y2 * z * z
        };
        out[1] = yp[1] - (y1 * y1 * y2 * y2 - 3.0 * y2 * y2 * z);
        out[2] = y1 * y1 * y2 - 1.0;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (y1, y2, z) = (y[0], y[1], y[2]);
        if self.linear_multiplier {
            m.set(0, 0, c - y2 * z);
            m.set(0, 1, -y1 * z);
            m.set(0, 2, -y1 * y2);
        } else {
            m.set(0, 0, c - y2 * y2 * z * z);
            m.set(0, 1, -2.0 * y1 * y2 * z * z);
            m.set(0, 2, -2.0 * y1 * y2 * y2 * z);
        }
        m.set(1, 0, -2.0 * y1 * y2 * y2);
        m.set(1, 1, c - 2.0 * y1 * y1 * y2 + 6.0 * y2 * z);
        m.set(1, 2, 3.0 * y2 * y2);
        m.set(2, 0, 2.0 * y1 * y2);
        m.set(2, 1, y1 * y1);
    }
    /// `diag(1, 1, 0)`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        m.set(0, 0, 1.0);
        m.set(1, 1, 1.0);
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 2
    }
}

/// A particle of unit mass on the unit circle pushed along it by a tangential force of size 2,
/// unknowns `(x, y, u, v, lambda)`:
///
/// ```text
/// x' = u             u' = 2 y + x lambda
/// y' = v             v' = -2 x + y lambda
/// 0  = x^2 + y^2 - 1
/// ```
///
/// The force `2 (y, -x)` is twice the unit tangent of `(sin th, cos th)`, so `th'' = 2`: from
/// rest at `th = 0`, `x = sin t^2`, `y = cos t^2`, `u = 2t cos t^2`, `v = -2t sin t^2` and the
/// multiplier (the centripetal term) `lambda = -4 t^2`, on `[0, 2]`. Index 3.
#[derive(Debug, Clone, Copy, Default)]
pub struct CircularTrack;

/// End of [`CircularTrack`]'s interval (from 0; the angle then is 4 rad, no component near 0).
pub const TRACK_T_END: f64 = 2.0;

impl CircularTrack {
    /// The exact solution and its derivative.
    pub fn exact(t: f64) -> ([f64; 5], [f64; 5]) {
        let (s, c) = (t * t).sin_cos();
        let y = [s, c, 2.0 * t * c, -2.0 * t * s, -4.0 * t * t];
        let yp = [
            2.0 * t * c,
            -2.0 * t * s,
            2.0 * c - 4.0 * t * t * s,
            -2.0 * s - 4.0 * t * t * c,
            -8.0 * t,
        ];
        (y, yp)
    }
}

impl ImplicitDae for CircularTrack {
    fn dimension(&self) -> usize {
        5
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (x, yy, u, v, l) = (y[0], y[1], y[2], y[3], y[4]);
        out[0] = yp[0] - u;
        out[1] = yp[1] - v;
        out[2] = yp[2] - 2.0 * yy - x * l;
        out[3] = yp[3] + 2.0 * x - yy * l;
        out[4] = x * x + yy * yy - 1.0;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (x, yy, l) = (y[0], y[1], y[4]);
        for i in 0..4 {
            m.set(i, i, c);
        }
        m.set(0, 2, -1.0);
        m.set(1, 3, -1.0);
        m.set(2, 0, -l);
        m.set(2, 1, -2.0);
        m.set(2, 4, -x);
        m.set(3, 0, 2.0);
        m.set(3, 1, -l);
        m.set(3, 4, -yy);
        m.set(4, 0, 2.0 * x);
        m.set(4, 1, 2.0 * yy);
    }
    /// The identity on the positions and velocities.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..4 {
            m.set(i, i, 1.0);
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 4
    }
}

/// A knife edge of unit mass on a plane inclined so that gravity pulls along `x` with
/// `G = g sin(alpha)`, turning at the constant rate `omega`; unknowns `(x, y, phi, u, v, w,
/// lambda)`:
///
/// ```text
/// x' = u     u' = G + lambda sin(phi)        w' = 0
/// y' = v     v' = -lambda cos(phi)           0 = u sin(phi) - v cos(phi)
/// phi' = w
/// ```
///
/// The blade cannot slide sideways (the velocity constraint; `lambda` is the side force). Along
/// the blade the speed `s` obeys `s' = G cos(phi)`, so from rest at the origin with `phi = 0`:
/// `phi = omega t`, `s = a sin(omega t)` with `a = G / omega`, `u = a/2 sin(2 omega t)`,
/// `v = a/2 (1 - cos(2 omega t))`, `x = a (1 - cos(2 omega t)) / (4 omega)`,
/// `y = a/2 (t - sin(2 omega t) / (2 omega))`, `lambda = -2 G sin(omega t)`. Index 2 (the
/// constraint's gradient in `(u, v)` is the blade's normal, along which `lambda` acts).
#[derive(Debug, Clone, Copy)]
pub struct KnifeEdge {
    /// `g sin(alpha)`.
    pub gravity: f64,
    /// The turning rate.
    pub omega: f64,
}

/// The knife edge of the tests: `g = 9.81` on a slope of 30 degrees, turning at 2 rad/s.
pub const KNIFE: KnifeEdge = KnifeEdge {
    gravity: 9.81 * 0.5,
    omega: 2.0,
};

/// End of [`KnifeEdge`]'s interval (from 0; the blade has turned by 6 rad, no component near
/// zero).
pub const KNIFE_T_END: f64 = 3.0;

impl KnifeEdge {
    /// The exact solution and its derivative.
    pub fn exact(&self, t: f64) -> ([f64; 7], [f64; 7]) {
        let (g, w) = (self.gravity, self.omega);
        let a = g / w;
        let th = w * t;
        let (s2, c2) = (2.0 * th).sin_cos();
        let y = [
            a * (1.0 - c2) / (4.0 * w),
            0.5 * a * (t - s2 / (2.0 * w)),
            th,
            0.5 * a * s2,
            0.5 * a * (1.0 - c2),
            w,
            -2.0 * g * th.sin(),
        ];
        let yp = [y[3], y[4], w, g * c2, g * s2, 0.0, -2.0 * g * w * th.cos()];
        (y, yp)
    }
}

impl ImplicitDae for KnifeEdge {
    fn dimension(&self) -> usize {
        7
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (phi, u, v, w, l) = (y[2], y[3], y[4], y[5], y[6]);
        let (s, c) = phi.sin_cos();
        out[0] = yp[0] - u;
        out[1] = yp[1] - v;
        out[2] = yp[2] - w;
        out[3] = yp[3] - self.gravity - l * s;
        out[4] = yp[4] + l * c;
        out[5] = yp[5];
        out[6] = u * s - v * c;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (phi, u, v, l) = (y[2], y[3], y[4], y[6]);
        let (sn, cs) = phi.sin_cos();
        for i in 0..6 {
            m.set(i, i, c);
        }
        m.set(0, 3, -1.0);
        m.set(1, 4, -1.0);
        m.set(2, 5, -1.0);
        m.set(3, 2, -l * cs);
        m.set(3, 6, -sn);
        m.set(4, 2, -l * sn);
        m.set(4, 6, cs);
        m.set(6, 2, u * cs + v * sn);
        m.set(6, 3, sn);
        m.set(6, 4, -cs);
    }
    /// The identity on the six differential unknowns.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..6 {
            m.set(i, i, 1.0);
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 6
    }
}

/// Gear and Petzold's linear time-varying DAE, unknowns `(y1, y2)`:
///
/// ```text
/// 0 = y1 + eta t y2 - e^-t
/// 0 = y1' + eta t y2' + (1 + eta) y2
/// ```
///
/// with `y1 = (1 - eta t) e^-t`, `y2 = e^-t` for every `eta` (differentiating the first row
/// and subtracting it from the second gives `y2 = e^-t`). Index 2; BDF methods are known to be
/// unstable on it for `eta < -0.5`.
#[derive(Debug, Clone, Copy)]
pub struct Bcp {
    /// The coupling parameter.
    pub eta: f64,
}

impl Bcp {
    /// The exact solution and its derivative.
    pub fn exact(&self, t: f64) -> ([f64; 2], [f64; 2]) {
        let e = (-t).exp();
        let eta = self.eta;
        ([(1.0 - eta * t) * e, e], [(eta * t - eta - 1.0) * e, -e])
    }
}

impl ImplicitDae for Bcp {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = y[0] + self.eta * t * y[1] - (-t).exp();
        out[1] = yp[0] + self.eta * t * yp[1] + (1.0 + self.eta) * y[1];
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, 1.0);
        m.set(0, 1, self.eta * t);
        m.set(1, 0, c);
        m.set(1, 1, c * self.eta * t + 1.0 + self.eta);
    }
    /// The second row's `(1, eta t)`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, t: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        m.set(1, 0, 1.0);
        m.set(1, 1, self.eta * t);
        true
    }
}

/// Ascher & Petzold's Example 10.2 (SIAM 1998, p. 267), as SUNDIALS' `idaAnalytic_mels` states
/// it, unknowns `(x1, x2)`, with its stiffness parameter `alpha` (10 there):
///
/// ```text
/// x1' = (1 - alpha) / (t - 2) x1 - x1 + (alpha - 1) x2 + 2 e^t
///  0  = (t + 2) x1 - (t + 2) e^t
/// ```
///
/// with `x1 = e^t`, `x2 = e^t / (t - 2)` on `[0, 1]`. The constraint holds `x1`, a
/// differential unknown, so `x1' = e^t` is fixed and the first equation determines `x2`
/// (through `alpha - 1 != 0`): index 2, `x2` the unknown of index 2. The residual is written
/// in the example's sign, `f - x1'` (the mass matrix `dF/dx' = diag(-1, 0)`).
#[derive(Debug, Clone, Copy)]
pub struct AnalyticIndex2 {
    /// The stiffness parameter (SUNDIALS' example: 10).
    pub alpha: f64,
}

/// End of [`AnalyticIndex2`]'s interval (from 0).
pub const ANALYTIC_T_END: f64 = 1.0;

impl AnalyticIndex2 {
    /// The exact solution and its derivative (`x2' = e^t (t - 3) / (t - 2)^2`).
    pub fn exact(t: f64) -> ([f64; 2], [f64; 2]) {
        let e = t.exp();
        let d = t - 2.0;
        ([e, e / d], [e, e * (d - 1.0) / (d * d)])
    }
}

impl ImplicitDae for AnalyticIndex2 {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let a = self.alpha;
        out[0] = (1.0 - a) / (t - 2.0) * y[0] - y[0] + (a - 1.0) * y[1] + 2.0 * t.exp() - yp[0];
        out[1] = (t + 2.0) * y[0] - (t + 2.0) * t.exp();
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let a = self.alpha;
        m.set(0, 0, (1.0 - a) / (t - 2.0) - 1.0 - c);
        m.set(0, 1, a - 1.0);
        m.set(1, 0, t + 2.0);
    }
    /// `diag(-1, 0)`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        m.set(0, 0, -1.0);
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i == 0
    }
    fn equation_name(&self, i: usize) -> String {
        ["x1'", "constraint"][i].to_string()
    }
    fn unknown_name(&self, i: usize) -> String {
        ["x1", "x2"][i].to_string()
    }
}
