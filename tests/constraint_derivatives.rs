//! The position constraints' exact derivatives that `dpc::model!` emits
//! (`DaeModel::constraint_gradient`, `constraint_time_derivative`, `constraint_curvature`)
//! against central differences of the generated residual and iteration matrix at random
//! points, for the constrained plants of `dpc-models` and a pendulum whose pivot moves with
//! time; models without position constraints supply nothing; and the crane's closed loop with
//! the exact derivatives follows the one that differences them to within the plant tolerance.

use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::linear_solver::FaerDenseLu;
use dpc::core::model::Structure;
use dpc::core::simulate::{simulate, ClosedLoop, ClosedLoopOptions, Hold};
use dpc::core::{DaeModel, MatrixSink};
use dpc::nalgebra::DMatrix;
use dpc_models::{
    CartPendulum, CartPendulumReference, CartPendulumTracking, Pendulum, SliderCrank,
    SliderCrankJoint, Wheel,
};
use proptest::prelude::*;

dpc::model! {
    /// A pendulum whose pivot is shaken horizontally, `a sin(w t)`: a position constraint
    /// that depends on time (and a term in `t x` so that `d^2 g/(dt dx)` has two sources).
    pub Shaken {
        params { m = 1.0, l = 1.0, g = 9.81, a = 0.2, w = 3.0, b = 0.1 }
        states { x, y, vx, vy }
        algebraic { lambda }
        inputs { f }
        equations {
            der(x) = vx;
            der(y) = vy;
            m * der(vx) == -lambda * (x - a * sin(w * t)) + f;
            m * der(vy) == -lambda * y - m * g;
            0.0 == 0.5 * ((x - a * sin(w * t)).powi(2) + y.powi(2) - l.powi(2)) + b * t * x * y;
        }
        outputs { x }
    }
}

/// The rows of states, time and parameters only (no `x'`, no algebraic unknown, no input),
/// read from the structural patterns.
fn constraint_rows(s: &Structure) -> Vec<usize> {
    let in_row = |p: &[(usize, usize)], i: usize| p.iter().any(|&(r, _)| r == i);
    (0..s.n_equations())
        .filter(|&i| {
            !(in_row(&s.pattern_f_xdot, i)
                || in_row(&s.pattern_f_z, i)
                || in_row(&s.pattern_f_u, i))
        })
        .collect()
}

/// Number of random values one point of `M` takes: `t`, `x`, `z`, `u`, `v`.
fn dims<M: DaeModel + Default>() -> usize {
    let s = M::default().structure().clone();
    1 + 2 * s.n_states() + s.n_algebraic() + s.n_inputs()
}

/// The residual of `m` at `(t, x, x' = 0, z, u)`.
fn residual<M: DaeModel>(m: &M, t: f64, x: &[f64], z: &[f64], u: &[f64]) -> Vec<f64> {
    let s = m.structure();
    let mut r = vec![0.0; s.n_equations()];
    m.residual(t, x, &vec![0.0; s.n_states()], z, u, &mut r);
    r
}

/// `dF/dx` (the iteration matrix at `c = 0`, first `nx` columns) of `m`.
fn f_x<M: DaeModel>(m: &M, t: f64, x: &[f64], z: &[f64], u: &[f64]) -> DMatrix<f64> {
    let s = m.structure();
    let n = s.n_equations();
    let mut j = DMatrix::zeros(n, n);
    m.iteration_matrix(t, x, &vec![0.0; s.n_states()], z, u, 0.0, &mut j);
    j
}

fn close(what: &str, exact: f64, differenced: f64, scale: f64) {
    assert!(
        (exact - differenced).abs() <= 1e-6 * (1.0 + scale),
        "{what}: exact {exact:e}, differenced {differenced:e}"
    );
}

/// The exact gradient, time derivative and curvature of `M`'s constraint rows at the point
/// `p` (see [`dims`]) against central differences; `time_dependent` says whether some row
/// depends on `t`. Returns nothing; panics on a mismatch.
fn check<M: DaeModel + Default>(p: &[f64], time_dependent: bool) {
    let m = M::default();
    let s = m.structure().clone();
    let (ne, nx, nz, nu) = (s.n_equations(), s.n_states(), s.n_algebraic(), s.n_inputs());
    let t = p[0];
    let x = &p[1..1 + nx];
    let z = &p[1 + nx..1 + nx + nz];
    let u = &p[1 + nx + nz..1 + nx + nz + nu];
    let v = &p[1 + nx + nz + nu..];
    let rows = constraint_rows(&s);
    assert!(!rows.is_empty(), "{}: a constrained plant", s.name);

    // Gradient against central differences of the residual.
    let mut grad = DMatrix::zeros(ne, ne);
    assert!(m.constraint_gradient(t, x, z, u, &mut grad));
    let step = |xj: f64| 1e-6 * (1.0 + xj.abs());
    let moved = |j: usize, d: f64| {
        let mut y = x.to_vec();
        y[j] += d;
        y
    };
    for j in 0..nx {
        let e = step(x[j]);
        let (xp, xm) = (moved(j, e), moved(j, -e));
        let (rp, rm) = (residual(&m, t, &xp, z, u), residual(&m, t, &xm, z, u));
        for i in 0..ne {
            let d = (rp[i] - rm[i]) / (xp[j] - xm[j]);
            let expected = if rows.contains(&i) { d } else { 0.0 };
            close(
                &format!("{} dF_{i}/dx_{j}", s.name),
                grad[(i, j)],
                expected,
                d.abs(),
            );
        }
    }
    for i in 0..ne {
        for j in nx..ne {
            assert_eq!(grad[(i, j)], 0.0, "{}: no algebraic column", s.name);
        }
    }

    // dF/dt against a central difference in t.
    let mut dgdt = vec![0.0; ne];
    assert!(m.constraint_time_derivative(t, x, z, u, &mut dgdt));
    let dt = 1e-6 * (1.0 + t.abs());
    let (rp, rm) = (residual(&m, t + dt, x, z, u), residual(&m, t - dt, x, z, u));
    let mut any_time = false;
    for i in 0..ne {
        let d = (rp[i] - rm[i]) / ((t + dt) - (t - dt));
        let expected = if rows.contains(&i) { d } else { 0.0 };
        close(&format!("{} dF_{i}/dt", s.name), dgdt[i], expected, d.abs());
        any_time |= dgdt[i] != 0.0;
    }
    // (A moving constraint may have dg/dt = 0 at a point; the hand-written test below
    // checks one where it has not.)
    assert!(time_dependent || !any_time, "{}: dg/dt written", s.name);

    // Curvature: d/dx_k (sum_j dF/dx_j v_j + dF/dt), by central differences of the generated
    // iteration matrix (dF/dx) and of the residual's difference in t.
    let mut curv = DMatrix::zeros(ne, ne);
    assert!(m.constraint_curvature(t, x, z, u, v, &mut curv));
    for k in 0..nx {
        let e = step(x[k]);
        let (xp, xm) = (moved(k, e), moved(k, -e));
        let h = xp[k] - xm[k];
        let (jp, jm) = (f_x(&m, t, &xp, z, u), f_x(&m, t, &xm, z, u));
        // d^2 F/(dt dx_k) as a central difference of dF/dx_k in t.
        let (tp, tm) = (f_x(&m, t + dt, x, z, u), f_x(&m, t - dt, x, z, u));
        for &i in &rows {
            let mut d = 0.0;
            for j in 0..nx {
                d += (jp[(i, j)] - jm[(i, j)]) / h * v[j];
            }
            d += (tp[(i, k)] - tm[(i, k)]) / ((t + dt) - (t - dt));
            close(
                &format!("{} curvature ({i}, {k})", s.name),
                curv[(i, k)],
                d,
                d.abs() + v.iter().map(|w| w.abs()).sum::<f64>(),
            );
        }
    }
    for i in (0..ne).filter(|i| !rows.contains(i)) {
        for k in 0..ne {
            assert_eq!(curv[(i, k)], 0.0, "{}: row {i} is no constraint", s.name);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn crane_constraint_derivatives_match_central_differences(p in prop::collection::vec(-2.0..2.0f64, dims::<CartPendulum>())) {
        check::<CartPendulum>(&p, false);
    }

    #[test]
    fn slider_crank_constraint_derivatives_match_central_differences(p in prop::collection::vec(-2.0..2.0f64, dims::<SliderCrank>())) {
        check::<SliderCrank>(&p, false);
    }

    #[test]
    fn pendulum_constraint_derivatives_match_central_differences(p in prop::collection::vec(-2.0..2.0f64, dims::<Pendulum>())) {
        check::<Pendulum>(&p, false);
    }

    #[test]
    fn a_moving_constraint_has_its_time_derivatives(p in prop::collection::vec(-2.0..2.0f64, dims::<Shaken>())) {
        check::<Shaken>(&p, true);
    }
}

#[test]
fn the_moving_constraint_by_hand() {
    // g = ((x - a sin(w t))^2 + y^2 - l^2) / 2 + b t x y at a point, written out; the row
    // `0 == g` has the residual F = 0 - g.
    let m = Shaken::default();
    let (a, w, b) = (0.2_f64, 3.0_f64, 0.1_f64);
    let (t, x, y) = (0.7, 0.4, -0.9);
    let (vx, vy) = (1.5, -0.5);
    let st = (w * t).sin();
    let ct = (w * t).cos();
    let q = x - a * st;
    let mut grad = DMatrix::zeros(5, 5);
    assert!(m.constraint_gradient(t, &[x, y, vx, vy], &[3.0], &[0.5], &mut grad));
    assert!((grad[(4, 0)] + (q + b * t * y)).abs() < 1e-14, "{grad}");
    assert!((grad[(4, 1)] + (y + b * t * x)).abs() < 1e-14);
    let mut dgdt = [0.0; 5];
    assert!(m.constraint_time_derivative(t, &[x, y, vx, vy], &[3.0], &[0.5], &mut dgdt));
    assert!((dgdt[4] + (-q * a * w * ct + b * x * y)).abs() < 1e-14);
    let mut curv = DMatrix::zeros(5, 5);
    let v = [vx, vy, 0.0, 0.0];
    assert!(m.constraint_curvature(t, &[x, y, vx, vy], &[3.0], &[0.5], &v, &mut curv));
    // d/dx: vx + b t vy - a w cos(w t) + b y; d/dy: b t vx + vy + b x.
    let cx = vx + b * t * vy - a * w * ct + b * y;
    let cy = b * t * vx + vy + b * x;
    assert!((curv[(4, 0)] + cx).abs() < 1e-14, "{}", curv[(4, 0)]);
    assert!((curv[(4, 1)] + cy).abs() < 1e-14, "{}", curv[(4, 1)]);
    assert_eq!(curv.iter().filter(|c| **c != 0.0).count(), 2);
}

#[test]
fn models_without_position_constraints_supply_nothing() {
    fn none<M: DaeModel + Default>() {
        let m = M::default();
        let s = m.structure();
        let (ne, nx, nz, nu) = (s.n_equations(), s.n_states(), s.n_algebraic(), s.n_inputs());
        let (x, z, u) = (vec![0.1; nx], vec![0.0; nz], vec![0.0; nu]);
        let mut g = DMatrix::zeros(ne, ne);
        assert!(!m.constraint_gradient(0.0, &x, &z, &u, &mut g));
        assert!(!m.constraint_time_derivative(0.0, &x, &z, &u, &mut vec![0.0; ne]));
        assert!(!m.constraint_curvature(0.0, &x, &z, &u, &x, &mut g));
        assert!(g.iter().all(|v| *v == 0.0));
    }
    none::<Wheel>();
    none::<SliderCrankJoint>();
    none::<CartPendulumTracking>();
}

/// A plant that hides its constraint derivatives, so the closed loop differences them.
#[derive(Debug, Clone, Default)]
struct Differenced<M>(M);

impl<M: DaeModel> DaeModel for Differenced<M> {
    type Params = M::Params;
    fn structure(&self) -> &Structure {
        self.0.structure()
    }
    fn from_params(params: Self::Params) -> Self {
        Self(M::from_params(params))
    }
    fn params(&self) -> &Self::Params {
        self.0.params()
    }
    fn parameter(params: &Self::Params, index: usize) -> Option<f64> {
        M::parameter(params, index)
    }
    fn set_parameter(params: &mut Self::Params, index: usize, value: f64) -> bool {
        M::set_parameter(params, index, value)
    }
    fn residual(&self, t: f64, x: &[f64], xdot: &[f64], z: &[f64], u: &[f64], out: &mut [f64]) {
        self.0.residual(t, x, xdot, z, u, out);
    }
    fn evaluate<A, B, C, D>(
        &self,
        t: f64,
        x: &[f64],
        xdot: &[f64],
        z: &[f64],
        u: &[f64],
        residual: &mut [f64],
        f_xdot: &mut A,
        f_x: &mut B,
        f_z: &mut C,
        f_u: &mut D,
    ) where
        A: MatrixSink + ?Sized,
        B: MatrixSink + ?Sized,
        C: MatrixSink + ?Sized,
        D: MatrixSink + ?Sized,
    {
        self.0
            .evaluate(t, x, xdot, z, u, residual, f_xdot, f_x, f_z, f_u);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        x: &[f64],
        xdot: &[f64],
        z: &[f64],
        u: &[f64],
        c: f64,
        out: &mut S,
    ) {
        self.0.iteration_matrix(t, x, xdot, z, u, c, out);
    }
    fn residual_and_iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        x: &[f64],
        xdot: &[f64],
        z: &[f64],
        u: &[f64],
        c: f64,
        residual: &mut [f64],
        out: &mut S,
    ) {
        self.0
            .residual_and_iteration_matrix(t, x, xdot, z, u, c, residual, out);
    }
    fn outputs(&self, t: f64, x: &[f64], z: &[f64], u: &[f64], out: &mut [f64]) {
        self.0.outputs(t, x, z, u, out);
    }
    fn output_jacobians<A, B, C>(
        &self,
        t: f64,
        x: &[f64],
        z: &[f64],
        u: &[f64],
        h_x: &mut A,
        h_z: &mut B,
        h_u: &mut C,
    ) where
        A: MatrixSink + ?Sized,
        B: MatrixSink + ?Sized,
        C: MatrixSink + ?Sized,
    {
        self.0.output_jacobians(t, x, z, u, h_x, h_z, h_u);
    }
}

/// The crane's closed loop (plain DPC, `W = s + 2`, from the load swung out by 0.3 rad) on
/// `plant`.
fn crane_loop<P: DaeModel>(plant: &P) -> ClosedLoop {
    let tracking = CartPendulumTracking::default();
    let n = tracking.structure().n_equations();
    let mut dpc = Dpc::new(
        tracking,
        CartPendulumReference::default(),
        FaerDenseLu::new(n),
        DpcOptions {
            delta: 1e-3,
            ..DpcOptions::default()
        },
    )
    .expect("controller");
    let (l, phi) = (0.5_f64, 0.3_f64);
    let x0 = [0.0, l * phi.sin(), -l * phi.cos(), 0.0, 0.0, 0.0];
    let options = ClosedLoopOptions {
        h: 0.01,
        t_end: 1.0,
        hold: Hold::Input,
        tracking_bounds: vec![Some(1.0)],
        ..ClosedLoopOptions::default()
    };
    simulate(plant, &mut dpc, &x0, &options).expect("run starts")
}

#[test]
fn crane_closed_loop_with_exact_derivatives_follows_the_differenced_one() {
    let exact = crane_loop(&CartPendulum::default());
    let differenced = crane_loop(&Differenced(CartPendulum::default()));
    assert!(exact.divergence.is_none(), "{:?}", exact.divergence);
    assert!(
        differenced.divergence.is_none(),
        "{:?}",
        differenced.divergence
    );
    assert_eq!(exact.samples.len(), differenced.samples.len());
    let mut d = 0.0_f64;
    for (a, b) in exact.samples.iter().zip(&differenced.samples) {
        for (p, q) in a.x.iter().zip(&b.x) {
            d = d.max((p - q).abs());
        }
    }
    println!("crane: exact against differenced constraint derivatives, max |dx| = {d:e}");
    // The plant is integrated at rtol 1e-8 (atol 1e-10) on states of order 1, in a loop whose
    // error grows like e^(1.9 t) without the preliminary feedback.
    assert!(d < 1e-6, "{d:e}");
}
