//! SUNDIALS IDA's dense example `idaSlCrank_dns` written anew from its equations: a slider
//! crank with three generalized coordinates `u = (q, x, p)` (crank angle, slider position,
//! connecting rod angle), their velocities `v = (qd, xd, pd)`, two multipliers `lambda` of the
//! position constraints and two Gear-Gupta-Leimkuhler multipliers `mu`: 10 unknowns, the
//! stabilised index-2 form
//!
//! ```text
//! u' - v + G(u)^T mu = 0
//! M v' - Q(u, v) + G(u)^T lambda = 0
//! g(u) = 0                     g = (x - cos p - a cos q, -sin p - a sin q)
//! G(u) v = 0                   G = dg/du
//! ```
//!
//! with `M = diag(J1, m2, J2) = diag(1, 1, 2)`, crank half-length `a = 0.5`. The generalized
//! forces are those of a spring-damper of stiffness `k = 1`, damping `c = 1` and free length
//! `l0 = 1` and of a constant horizontal force `F = 1`: with `l(u)` the spring's length
//! (`l^2 = x^2 - x (cos p + a cos q) + (1 + a^2)/4 + (a/2) cos(p - q)`) and
//! `f = k (l - l0) + c l'` its force (`l' = grad l . v`),
//! `Q = -f grad l + F (0, 1, -sin p)`. (The example's `force` writes the same terms expanded;
//! `grad l = grad l^2 / (2 l)`.)
//!
//! The iteration matrix is exact, derived by hand: with `G2 = grad l^2` and `H2` its Hessian,
//! `grad l = G2 / 2l`, the Hessian of `l` is `Hl = H2 / 2l - G2 G2^T / 4 l^3`; `dl'/du = Hl v`,
//! `dl'/dv = grad l`; `dQ/du = -grad l (k grad l + c Hl v)^T - f Hl - F cos p e_p e_p^T`,
//! `dQ/dv = -c grad l grad l^T`; the constraint rows' second derivatives contracted with `mu`,
//! `lambda` and `v`. It is checked against differences in `tests/ida_slider_crank.rs`. The mass
//! matrix `dF/dy'` is the constant `diag(1, 1, 1, J1, m2, J2, 0, 0, 0, 0)`.
//!
//! Initial values as the example's: `q = pi/2`, `p = asin(-a)`, `x = cos p` (on both position
//! constraints), velocities 0 (on the velocity constraints), `v' = M^-1 Q` and
//! `lambda = mu = 0`. `lambda = 0` is not the consistent multiplier (the hidden acceleration
//! constraint `G v' + (dG/dt) v = 0` does not hold for `v' = M^-1 Q`), so the first steps must
//! move `lambda` and `v'`, as IDA's do from the same start (its `suppressalg` keeps
//! `lambda, mu` out of the error test; dpc declares them of index 2 and the BDF excludes them).
//!
//! [`SlCrankIndex3`] is the same mechanism in its index-3 form (no `mu`, the position
//! constraints instead of the velocity ones, 8 unknowns): the second formulation of the
//! reference ([`SLCRANK_REF`]).
#![allow(dead_code)]
// Matrix entries are written by (row, column) index, as the formulas are.
#![allow(clippy::needless_range_loop)]

use dpc_core::{ImplicitDae, MatrixSink};

/// Unknowns of the stabilised form.
pub const SLCRANK_DIM: usize = 10;
/// Unknowns of the index-3 form.
pub const SLCRANK3_DIM: usize = 8;
/// End of the interval (the example's).
pub const SLCRANK_T_END: f64 = 10.0;
/// The scored unknowns: the six differential ones (positions and velocities).
pub const SLCRANK_SCORED: [usize; 6] = [0, 1, 2, 3, 4, 5];

/// Half-length of the crank.
const A: f64 = 0.5;
/// Crank moment of inertia.
const J1: f64 = 1.0;
/// Connecting rod mass.
const M2: f64 = 1.0;
/// Connecting rod moment of inertia.
const J2: f64 = 2.0;
/// Spring stiffness.
const K: f64 = 1.0;
/// Damper constant.
const C: f64 = 1.0;
/// Spring free length.
const L0: f64 = 1.0;
/// Constant horizontal force.
const F: f64 = 1.0;
/// The mass matrix of the velocities.
const MASS: [f64; 3] = [J1, M2, J2];

/// The reference at `t = 10` (all ten unknowns of the stabilised form; `mu` is zero on the
/// exact solution, about `1e-10` here): Radau at `rtol = atol = 1e-12` on the stabilised form
/// (731 steps). On the six differential unknowns the BDF at `1e-12` on the same form agrees to
/// 8.96 digits (1552 steps), Radau at `1e-12` on `Stabilised::detect` of the index-3 form to
/// 13.6 digits and Radau at `1e-12` on the index-3 form as declared to 7.15 digits (the
/// index-3 form's own floor); `q, x, p` round to the example's printed `1.2757, 1.0236,
/// -0.49881`. The ignored test `reference_recomputed` of `tests/ida_slider_crank.rs` recomputes
/// it.
#[allow(clippy::excessive_precision)]
pub const SLCRANK_REF: [f64; SLCRANK_DIM] = [
    1.2756758486467310e0,
    1.0235785589817956e0,
    -4.9881304918191771e-1,
    -2.3991499719846465e-1,
    1.3377828321722221e-1,
    3.9731495992175736e-2,
    1.1137561580375912e0,
    -7.6250727455991818e-1,
    -3.2362284949204311e-11,
    -1.2435775217990451e-10,
];

/// Differential index per unknown of the stabilised form: `lambda` and `mu` 2 (the GGL form),
/// the rest 1.
pub fn slcrank_index() -> Vec<u8> {
    (0..SLCRANK_DIM)
        .map(|i| if i < 6 { 1 } else { 2 })
        .collect()
}

/// Differential index per unknown of the index-3 form: positions 1, velocities 2, `lambda` 3.
pub fn slcrank3_index() -> Vec<u8> {
    vec![1, 1, 1, 2, 2, 2, 3, 3]
}

/// The spring-damper at `(u, v)`: its force `f`, `grad l` and the Hessian of `l`.
struct Spring {
    f: f64,
    grad: [f64; 3],
    hess: [[f64; 3]; 3],
}

impl Spring {
    fn at(u: &[f64], v: &[f64]) -> Self {
        let (q, x, p) = (u[0], u[1], u[2]);
        let (s1, c1, s2, c2) = (q.sin(), q.cos(), p.sin(), p.cos());
        // sin(p - q), cos(p - q).
        let (s21, c21) = (s2 * c1 - c2 * s1, c2 * c1 + s2 * s1);
        let l2 = x * x - x * (c2 + A * c1) + (1.0 + A * A) / 4.0 + A * c21 / 2.0;
        let l = l2.sqrt();
        let g2 = [
            A * x * s1 + A * s21 / 2.0,
            2.0 * x - (c2 + A * c1),
            x * s2 - A * s21 / 2.0,
        ];
        let h2 = [
            [A * x * c1 - A * c21 / 2.0, A * s1, A * c21 / 2.0],
            [A * s1, 2.0, s2],
            [A * c21 / 2.0, s2, x * c2 - A * c21 / 2.0],
        ];
        let grad = g2.map(|g| g / (2.0 * l));
        let mut hess = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                hess[i][j] = h2[i][j] / (2.0 * l) - g2[i] * g2[j] / (4.0 * l * l2);
            }
        }
        let ld: f64 = (0..3).map(|i| grad[i] * v[i]).sum();
        Self {
            f: K * (l - L0) + C * ld,
            grad,
            hess,
        }
    }

    /// The generalized forces `Q = -f grad l + F (0, 1, -sin p)`.
    fn forces(&self, p: f64) -> [f64; 3] {
        [
            -self.f * self.grad[0],
            -self.f * self.grad[1] + F,
            -self.f * self.grad[2] - F * p.sin(),
        ]
    }

    /// `(dQ/du, dQ/dv)` at `(u, v)`.
    fn force_derivatives(&self, p: f64, v: &[f64]) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
        let hv: [f64; 3] = std::array::from_fn(|j| (0..3).map(|i| self.hess[j][i] * v[i]).sum());
        let mut du = [[0.0; 3]; 3];
        let mut dv = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                du[i][j] =
                    -self.grad[i] * (K * self.grad[j] + C * hv[j]) - self.f * self.hess[i][j];
                dv[i][j] = -C * self.grad[i] * self.grad[j];
            }
        }
        du[2][2] -= F * p.cos();
        (du, dv)
    }
}

/// The constraint gradient `G(u)` (2 x 3).
fn gradient(u: &[f64]) -> [[f64; 3]; 2] {
    let (q, p) = (u[0], u[2]);
    let (s1, c1, s2, c2) = (q.sin(), q.cos(), p.sin(), p.cos());
    [[A * s1, 1.0, s2], [-A * c1, 0.0, -c2]]
}

/// `d/du (G(u)^T w)` (3 x 3): only the `q` and `p` diagonal entries are non-zero.
fn gradient_transpose_derivative(u: &[f64], w: &[f64]) -> [f64; 2] {
    let (q, p) = (u[0], u[2]);
    [
        A * q.cos() * w[0] + A * q.sin() * w[1],
        p.cos() * w[0] + p.sin() * w[1],
    ]
}

/// `d/du (G(u) v)` (2 x 3): entries at `q` and `p` of each row.
fn gradient_times_v_derivative(u: &[f64], v: &[f64]) -> [[f64; 2]; 2] {
    let (q, p) = (u[0], u[2]);
    [
        [A * q.cos() * v[0], p.cos() * v[2]],
        [A * q.sin() * v[0], p.sin() * v[2]],
    ]
}

/// The names of the unknowns of the stabilised form.
const UNKNOWNS: [&str; SLCRANK_DIM] = [
    "q (crank angle)",
    "x (slider)",
    "p (rod angle)",
    "qd",
    "xd",
    "pd",
    "lambda1",
    "lambda2",
    "mu1",
    "mu2",
];

/// The names of the equations of the stabilised form.
const EQUATIONS: [&str; SLCRANK_DIM] = [
    "q' = qd (GGL)",
    "x' = xd (GGL)",
    "p' = pd (GGL)",
    "crank moment balance",
    "slider force balance",
    "rod moment balance",
    "horizontal loop closure",
    "vertical loop closure",
    "horizontal loop closure velocity",
    "vertical loop closure velocity",
];

/// `idaSlCrank_dns`'s slider crank in its stabilised index-2 form ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct SlCrank;

/// The example's initial `(y, y')` of the stabilised form (the index-3 form's are its first
/// eight entries).
pub fn slcrank_initial() -> (Vec<f64>, Vec<f64>) {
    let q = std::f64::consts::FRAC_PI_2;
    let p = (-A).asin();
    let x = p.cos();
    let mut y = vec![0.0; SLCRANK_DIM];
    y[..3].copy_from_slice(&[q, x, p]);
    let spring = Spring::at(&y[..3], &y[3..6]);
    let qf = spring.forces(p);
    let mut yp = vec![0.0; SLCRANK_DIM];
    for i in 0..3 {
        yp[3 + i] = qf[i] / MASS[i];
    }
    (y, yp)
}

/// The rows of the velocities (`M v' - Q + G^T lambda`) and their matrix entries, shared by
/// both forms: residual rows `3..6` into `out[3..6]`.
fn balance_residual(y: &[f64], yp: &[f64], out: &mut [f64]) {
    let (u, v, lam) = (&y[..3], &y[3..6], &y[6..8]);
    let qf = Spring::at(u, v).forces(u[2]);
    let g = gradient(u);
    for i in 0..3 {
        out[3 + i] = MASS[i] * yp[3 + i] - qf[i] + g[0][i] * lam[0] + g[1][i] * lam[1];
    }
}

/// The entries of rows `3..6` of the iteration matrix.
fn balance_matrix<S: MatrixSink + ?Sized>(y: &[f64], c: f64, out: &mut S) {
    let (u, v, lam) = (&y[..3], &y[3..6], &y[6..8]);
    let (du, dv) = Spring::at(u, v).force_derivatives(u[2], v);
    let g = gradient(u);
    let d = gradient_transpose_derivative(u, lam);
    for i in 0..3 {
        for j in 0..3 {
            out.set(3 + i, j, -du[i][j]);
            out.set(3 + i, 3 + j, -dv[i][j]);
        }
        out.add(3 + i, 3 + i, c * MASS[i]);
        out.set(3 + i, 6, g[0][i]);
        out.set(3 + i, 7, g[1][i]);
    }
    out.add(3, 0, d[0]);
    out.add(5, 2, d[1]);
}

/// Position constraint rows into `out[0..2]`.
fn position_constraints(u: &[f64], out: &mut [f64]) {
    let (q, x, p) = (u[0], u[1], u[2]);
    out[0] = x - p.cos() - A * q.cos();
    out[1] = -p.sin() - A * q.sin();
}

impl ImplicitDae for SlCrank {
    fn dimension(&self) -> usize {
        SLCRANK_DIM
    }

    fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (u, v, mu) = (&y[..3], &y[3..6], &y[8..10]);
        let g = gradient(u);
        for i in 0..3 {
            out[i] = yp[i] - v[i] + g[0][i] * mu[0] + g[1][i] * mu[1];
        }
        balance_residual(y, yp, out);
        position_constraints(u, &mut out[6..8]);
        for r in 0..2 {
            out[8 + r] = (0..3).map(|j| g[r][j] * v[j]).sum();
        }
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _t: f64,
        y: &[f64],
        _yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let (u, v, mu) = (&y[..3], &y[3..6], &y[8..10]);
        let g = gradient(u);
        let d = gradient_transpose_derivative(u, mu);
        for i in 0..3 {
            out.set(i, i, c);
            out.set(i, 3 + i, -1.0);
            out.set(i, 8, g[0][i]);
            out.set(i, 9, g[1][i]);
        }
        out.add(0, 0, d[0]);
        out.add(2, 2, d[1]);
        balance_matrix(y, c, out);
        let gv = gradient_times_v_derivative(u, v);
        for r in 0..2 {
            for j in 0..3 {
                out.set(6 + r, j, g[r][j]);
                out.set(8 + r, 3 + j, g[r][j]);
            }
            out.set(8 + r, 0, gv[r][0]);
            out.set(8 + r, 2, gv[r][1]);
        }
    }

    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        write_mass(m);
        true
    }

    fn is_differential(&self, i: usize) -> bool {
        i < 6
    }

    fn equation_name(&self, i: usize) -> String {
        EQUATIONS
            .get(i)
            .map_or_else(|| format!("equation {i}"), |s| s.to_string())
    }

    fn unknown_name(&self, i: usize) -> String {
        UNKNOWNS
            .get(i)
            .map_or_else(|| format!("y[{i}]"), |s| s.to_string())
    }
}

/// `dF/dy'` of both forms: the identity on the positions, the masses and moments of inertia on
/// the velocities, zero on the multipliers.
fn write_mass<S: MatrixSink + ?Sized>(m: &mut S) {
    for i in 0..3 {
        m.set(i, i, 1.0);
        m.set(3 + i, 3 + i, MASS[i]);
    }
}

/// The same slider crank in its index-3 form: `u' = v`, `M v' = Q - G^T lambda`, `g(u) = 0`;
/// unknowns `(q, x, p, qd, xd, pd, lambda1, lambda2)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct SlCrankIndex3;

impl ImplicitDae for SlCrankIndex3 {
    fn dimension(&self) -> usize {
        SLCRANK3_DIM
    }

    fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for i in 0..3 {
            out[i] = yp[i] - y[3 + i];
        }
        balance_residual(y, yp, out);
        position_constraints(&y[..3], &mut out[6..8]);
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _t: f64,
        y: &[f64],
        _yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        for i in 0..3 {
            out.set(i, i, c);
            out.set(i, 3 + i, -1.0);
        }
        balance_matrix(y, c, out);
        let g = gradient(&y[..3]);
        for r in 0..2 {
            for j in 0..3 {
                out.set(6 + r, j, g[r][j]);
            }
        }
    }

    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        write_mass(m);
        true
    }

    fn is_differential(&self, i: usize) -> bool {
        i < 6
    }

    fn equation_name(&self, i: usize) -> String {
        match i {
            0..=2 => format!("{}' = {}", ["q", "x", "p"][i], ["qd", "xd", "pd"][i]),
            _ => EQUATIONS
                .get(i)
                .map_or_else(|| format!("equation {i}"), |s| s.to_string()),
        }
    }

    fn unknown_name(&self, i: usize) -> String {
        UNKNOWNS
            .get(i)
            .map_or_else(|| format!("y[{i}]"), |s| s.to_string())
    }
}
