//! Standard DAE test problems shared by the BDF tests, benchmarks and the peer script.
#![allow(dead_code)]

use dpc_core::bdf::{Bdf, Options, Tolerance};
use dpc_core::linear_solver::NalgebraLu;
use dpc_core::{ImplicitDae, MatrixSink};
use std::time::Instant;

/// Robertson's chemical kinetics as an index-1 DAE (Hairer & Wanner 1996, Section IV.10):
/// `y1' = -0.04 y1 + 1e4 y2 y3`, `y2' = 0.04 y1 - 1e4 y2 y3 - 3e7 y2^2`,
/// `0 = y1 + y2 + y3 - 1`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Robertson;

/// Reference solution at `t = 1e11` from the Test Set for IVP Solvers (Mazzia, Magherini et
/// al., University of Bari, problem ROBER, Section "Reference solution"), computed there with
/// RADAU at tight tolerances. The DAE form has the same solution as the ODE form because
/// `y1 + y2 + y3` is conserved.
pub const ROBERTSON_T_END: f64 = 1e11;
/// See [`ROBERTSON_T_END`]. Digits as published.
#[allow(clippy::excessive_precision)]
pub const ROBERTSON_REF: [f64; 3] = [
    0.2083340149701255e-7,
    0.8333360770334713e-13,
    0.9999999791665050,
];

impl ImplicitDae for Robertson {
    fn dimension(&self) -> usize {
        3
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] + 0.04 * y[0] - 1e4 * y[1] * y[2];
        out[1] = yp[1] - 0.04 * y[0] + 1e4 * y[1] * y[2] + 3e7 * y[1] * y[1];
        out[2] = y[0] + y[1] + y[2] - 1.0;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, 0.04 + c);
        m.set(0, 1, -1e4 * y[2]);
        m.set(0, 2, -1e4 * y[1]);
        m.set(1, 0, -0.04);
        m.set(1, 1, 1e4 * y[2] + 6e7 * y[1] + c);
        m.set(1, 2, 1e4 * y[1]);
        m.set(2, 0, 1.0);
        m.set(2, 1, 1.0);
        m.set(2, 2, 1.0);
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
    fn equation_name(&self, i: usize) -> String {
        ["y1' = ...", "y2' = ...", "0 = y1 + y2 + y3 - 1"][i].to_string()
    }
    fn unknown_name(&self, i: usize) -> String {
        ["y1", "y2", "y3"][i].to_string()
    }
}

/// Absolute tolerances for Robertson at relative tolerance `rtol` (IDA's `idaRoberts_dns`
/// choice `[1e-8, 1e-14, 1e-6]` at `rtol = 1e-4`, scaled with `rtol`).
pub fn robertson_atol(rtol: f64) -> Vec<f64> {
    let s = rtol / 1e-4;
    vec![1e-8 * s, 1e-14 * s, 1e-6 * s]
}

/// Robertson's start `y = (1, 0, 0)`, `y' = (-0.04, 0.04, 0)`.
pub const ROBERTSON_START: ([f64; 3], [f64; 3]) = ([1.0, 0.0, 0.0], [-0.04, 0.04, 0.0]);

/// The BDF on `dae` (Robertson's equations) from [`ROBERTSON_START`] at `t = 0`.
pub fn robertson_bdf<D: ImplicitDae, L: dpc_core::linear_solver::LinearSolver>(
    dae: D,
    ls: L,
    opts: Options,
) -> Result<Bdf<D, L>, dpc_core::bdf::BdfError> {
    let (y0, yp0) = ROBERTSON_START;
    Bdf::new(dae, ls, opts, 0.0, &y0, &yp0)
}

/// The BDF's options for Robertson at `rtol`: IDA's `atol` ([`robertson_atol`]).
pub fn robertson_options(rtol: f64) -> Options {
    Options {
        rtol: Tolerance::Scalar(rtol),
        atol: Tolerance::Vector(robertson_atol(rtol)),
        ..Options::default()
    }
}

/// The planar pendulum in Cartesian coordinates, index 3 (Hairer & Wanner 1996, Section
/// VII.1): unknowns `(x, y, u, v, lambda)`, `x' = u`, `y' = v`, `u' = -lambda x`,
/// `v' = -lambda y - g`, `0 = x^2 + y^2 - L^2`.
#[derive(Debug, Clone, Copy)]
pub struct Pendulum {
    /// Gravity.
    pub g: f64,
    /// Length.
    pub l: f64,
}

impl Default for Pendulum {
    fn default() -> Self {
        Self { g: 9.81, l: 1.0 }
    }
}

impl ImplicitDae for Pendulum {
    fn dimension(&self) -> usize {
        5
    }
    fn residual(&self, _: f64, s: &[f64], sp: &[f64], out: &mut [f64]) {
        let (x, y, u, v, la) = (s[0], s[1], s[2], s[3], s[4]);
        out[0] = sp[0] - u;
        out[1] = sp[1] - v;
        out[2] = sp[2] + la * x;
        out[3] = sp[3] + la * y + self.g;
        out[4] = x * x + y * y - self.l * self.l;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        s: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (x, y, la) = (s[0], s[1], s[4]);
        m.set(0, 0, c);
        m.set(0, 2, -1.0);
        m.set(1, 1, c);
        m.set(1, 3, -1.0);
        m.set(2, 2, c);
        m.set(2, 0, la);
        m.set(2, 4, x);
        m.set(3, 3, c);
        m.set(3, 1, la);
        m.set(3, 4, y);
        m.set(4, 0, 2.0 * x);
        m.set(4, 1, 2.0 * y);
    }
    /// The identity on the positions and velocities.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..4 {
            m.set(i, i, 1.0);
        }
        true
    }
    /// The constraint `x^2 + y^2 - L^2`: gradient `(2x, 2y)`, no time dependence, curvature
    /// `2 (u, v)` along the velocities `(u, v)`.
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, _: f64, s: &[f64], m: &mut S) -> bool {
        m.set(4, 0, 2.0 * s[0]);
        m.set(4, 1, 2.0 * s[1]);
        true
    }
    fn constraint_time_derivative(&self, _: f64, _: &[f64], _: &mut [f64]) -> bool {
        true
    }
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        v: &[f64],
        m: &mut S,
    ) -> bool {
        m.set(4, 0, 2.0 * v[0]);
        m.set(4, 1, 2.0 * v[1]);
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 4
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        Some(vec![
            (0, 0),
            (0, 2),
            (1, 1),
            (1, 3),
            (2, 2),
            (2, 0),
            (2, 4),
            (3, 3),
            (3, 1),
            (3, 4),
            (4, 0),
            (4, 1),
        ])
    }
    fn unknown_name(&self, i: usize) -> String {
        ["x", "y", "u", "v", "lambda"][i].to_string()
    }
}

/// Differential index of the pendulum's unknowns.
pub const PENDULUM_INDEX: [u8; 5] = [1, 1, 2, 2, 3];

impl Pendulum {
    /// Consistent state at rest at angle `theta0` from the downward vertical.
    pub fn initial(&self, theta0: f64) -> ([f64; 5], [f64; 5]) {
        let s = self.state(theta0, 0.0);
        let yp = [0.0, 0.0, -s[4] * s[0], -s[4] * s[1] - self.g, 0.0];
        (s, yp)
    }

    /// Cartesian state for angle `theta` and angular velocity `omega`.
    pub fn state(&self, theta: f64, omega: f64) -> [f64; 5] {
        let l = self.l;
        let (x, y) = (l * theta.sin(), -l * theta.cos());
        let (u, v) = (l * theta.cos() * omega, l * theta.sin() * omega);
        let la = (u * u + v * v - self.g * y) / (l * l);
        [x, y, u, v, la]
    }

    /// Independent reference: the angle ODE `theta'' = -(g/L) sin theta` integrated with the
    /// classical fourth-order Runge-Kutta method and 2^17 steps per time unit (global error
    /// below 1e-13 on the intervals used in the tests), mapped to Cartesian coordinates.
    pub fn reference(&self, theta0: f64, t_end: f64) -> [f64; 5] {
        let steps = ((t_end * 131_072.0).ceil() as usize).max(1);
        let h = t_end / steps as f64;
        let k = self.g / self.l;
        let f = |th: f64, om: f64| (om, -k * th.sin());
        let (mut th, mut om) = (theta0, 0.0);
        for _ in 0..steps {
            let (a1, b1) = f(th, om);
            let (a2, b2) = f(th + 0.5 * h * a1, om + 0.5 * h * b1);
            let (a3, b3) = f(th + 0.5 * h * a2, om + 0.5 * h * b2);
            let (a4, b4) = f(th + h * a3, om + h * b3);
            th += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
            om += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
        }
        self.state(th, om)
    }
}

/// Significant correct digits `-log10(max_i |y_i - ref_i| / |ref_i|)` over the listed
/// components, as in the Test Set for IVP Solvers (mixed with an absolute floor of `1e-300`).
pub fn significant_digits(y: &[f64], reference: &[f64], components: &[usize]) -> f64 {
    components
        .iter()
        .map(|&i| (y[i] - reference[i]).abs() / reference[i].abs().max(1e-300))
        .fold(0.0f64, f64::max)
        .log10()
        .mul_add(-1.0, 0.0)
}

/// The heat equation `u_t = u_xx` on `[0, 1]` by central differences on `m` intervals, with the
/// boundary conditions `u_0 = 0`, `u_m = 1` kept as algebraic equations: an index-1 DAE of
/// dimension `m + 1` with a tridiagonal iteration matrix (the large/sparse test case).
///
/// `u_i(t) = exp(-lambda t) sin(pi x_i) + x_i` with `lambda = (4/dx^2) sin^2(pi dx / 2)` solves
/// the semi-discrete system exactly (`sin(pi x_i)` is an eigenvector of the discrete Laplacian,
/// `x_i` is in its kernel).
#[derive(Debug, Clone, Copy)]
pub struct Heat {
    /// Number of intervals.
    pub m: usize,
}

impl Heat {
    fn dx(&self) -> f64 {
        1.0 / self.m as f64
    }
    /// Exact solution of the semi-discrete system.
    pub fn exact(&self, t: f64, u: &mut [f64], up: &mut [f64]) {
        let dx = self.dx();
        let lam = 4.0 / (dx * dx) * (std::f64::consts::PI * dx / 2.0).sin().powi(2);
        for i in 0..=self.m {
            let x = i as f64 * dx;
            let s = (std::f64::consts::PI * x).sin();
            u[i] = (-lam * t).exp() * s + x;
            up[i] = -lam * (-lam * t).exp() * s;
        }
        up[0] = 0.0;
        up[self.m] = 0.0;
    }
}

impl ImplicitDae for Heat {
    fn dimension(&self) -> usize {
        self.m + 1
    }
    fn residual(&self, _: f64, u: &[f64], up: &[f64], out: &mut [f64]) {
        let m = self.m;
        let k = 1.0 / (self.dx() * self.dx());
        out[0] = u[0];
        out[m] = u[m] - 1.0;
        for i in 1..m {
            out[i] = up[i] - k * (u[i - 1] - 2.0 * u[i] + u[i + 1]);
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        mat: &mut S,
    ) {
        let m = self.m;
        let k = 1.0 / (self.dx() * self.dx());
        mat.set(0, 0, 1.0);
        mat.set(m, m, 1.0);
        for i in 1..m {
            mat.set(i, i - 1, -k);
            mat.set(i, i, c + 2.0 * k);
            mat.set(i, i + 1, -k);
        }
    }
    /// The identity on the interior nodes (the boundary rows are algebraic).
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        mat: &mut S,
    ) -> bool {
        for i in 1..self.m {
            mat.set(i, i, 1.0);
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i > 0 && i < self.m
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let m = self.m;
        let mut p = vec![(0, 0), (m, m)];
        for i in 1..m {
            p.extend([(i, i - 1), (i, i), (i, i + 1)]);
        }
        Some(p)
    }
}

/// Robertson to `t = 1e11`: returns (significant digits, steps, seconds).
pub fn robertson(rtol: f64) -> (f64, usize, f64) {
    let start = Instant::now();
    let opts = robertson_options(rtol);
    let y0 = [1.0, 0.0, 0.0];
    let yp0 = [-0.04, 0.04, 0.0];
    let mut bdf = Bdf::new(Robertson, NalgebraLu::<3>::new(), opts, 0.0, &y0, &yp0).unwrap();
    bdf.set_stop_time(ROBERTSON_T_END).unwrap();
    let mut y = [0.0; 3];
    bdf.solve_to(ROBERTSON_T_END, &mut y, None).unwrap();
    let scd = significant_digits(&y, &ROBERTSON_REF, &[0, 1, 2]);
    (scd, bdf.stats().steps, start.elapsed().as_secs_f64())
}

/// Initial angle of the pendulum runs, in rad from the downward vertical.
pub const THETA0: f64 = 1.0;
/// End time of the pendulum runs.
pub const PENDULUM_T: f64 = 3.0;

/// Pendulum to `t = 3`: returns (digits in positions, digits in all components, steps, s).
pub fn pendulum(rtol: f64, reference: &[f64; 5]) -> (f64, f64, usize, f64) {
    let p = Pendulum::default();
    let start = Instant::now();
    let opts = Options {
        index: PENDULUM_INDEX.to_vec(),
        ..Options::with_tolerances(rtol, rtol)
    };
    let (y0, yp0) = p.initial(THETA0);
    let mut bdf = Bdf::new(p, NalgebraLu::<5>::new(), opts, 0.0, &y0, &yp0).unwrap();
    let mut y = [0.0; 5];
    bdf.set_stop_time(PENDULUM_T).unwrap();
    bdf.solve_to(PENDULUM_T, &mut y, None).unwrap();

    let elapsed = start.elapsed().as_secs_f64();
    (
        significant_digits(&y, reference, &[0, 1]),
        significant_digits(&y, reference, &[0, 1, 2, 3, 4]),
        bdf.stats().steps,
        elapsed,
    )
}
