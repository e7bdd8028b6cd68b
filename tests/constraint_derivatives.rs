//! The position constraints' exact derivatives that `dpc::model!` emits
//! (`DaeModel::constraint_gradient`, `constraint_time_derivative`, `constraint_curvature`)
//! against central differences of the generated residual and iteration matrix at random
//! points, for the constrained plants of `dpc-models` and a pendulum whose pivot moves with
//! time, and the same for those models' texts read as plant files (`dpc-runtime`; that the
//! two agree to rounding is `tests/runtime_agreement.rs`'s); models without position
//! constraints supply nothing; the crane's closed loop with the exact derivatives follows the
//! one that differences them to within the plant tolerance, and the plant file's follows the
//! macro plant's; the consistent initial state with the exact curvature agrees with the one
//! that differences it to within the difference's error estimate.

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::sync::OnceLock;

use common::model_text::invocations;
use dpc::core::consistent::{consistent_state, ConsistentOptions, ConsistentState};
use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::linear_solver::FaerDenseLu;
use dpc::core::model::Structure;
use dpc::core::simulate::{simulate, ClosedLoop, ClosedLoopOptions, Hold};
use dpc::core::{DaeModel, MatrixSink};
use dpc::nalgebra::DMatrix;
use dpc::runtime::{RuntimeModel, RuntimePlant};
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
    dims_of(M::default().structure())
}

/// Number of random values one point of a model with structure `s` takes (see [`dims`]).
fn dims_of(s: &Structure) -> usize {
    1 + 2 * s.n_states() + s.n_algebraic() + s.n_inputs()
}

/// The models of this file (`Shaken`) and of `models/src` read as plant files: the text of
/// their `model! { ... }` invocations, cut out of the sources.
fn plant_files() -> &'static HashMap<String, RuntimeModel> {
    static MODELS: OnceLock<HashMap<String, RuntimeModel>> = OnceLock::new();
    MODELS.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut models = HashMap::new();
        for file in [
            "tests/constraint_derivatives.rs",
            "models/src/cart_pendulum.rs",
            "models/src/slider_crank.rs",
            "models/src/pendulum.rs",
            "models/src/wheel.rs",
        ] {
            let source = std::fs::read_to_string(root.join(file)).expect("source file");
            for m in invocations(&source) {
                let model = dpc::runtime::parse(file, &m.body)
                    .unwrap_or_else(|e| panic!("a model of {file} as a plant file:\n{e}"));
                models.insert(model.name().to_string(), model);
            }
        }
        models
    })
}

/// The plant of the plant file of model `name` (see [`plant_files`]).
fn plant_file(name: &str) -> RuntimePlant {
    plant_files()
        .get(name)
        .unwrap_or_else(|| panic!("no model `{name}`"))
        .plant()
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
    check_model(&M::default(), p, time_dependent);
}

/// [`check`] for the model `m`.
fn check_model<M: DaeModel>(m: &M, p: &[f64], time_dependent: bool) {
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
        let (rp, rm) = (residual(m, t, &xp, z, u), residual(m, t, &xm, z, u));
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
    let (rp, rm) = (residual(m, t + dt, x, z, u), residual(m, t - dt, x, z, u));
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
        let (jp, jm) = (f_x(m, t, &xp, z, u), f_x(m, t, &xm, z, u));
        // d^2 F/(dt dx_k) as a central difference of dF/dx_k in t.
        let (tp, tm) = (f_x(m, t + dt, x, z, u), f_x(m, t - dt, x, z, u));
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

    #[test]
    fn plant_files_constraint_derivatives_match_central_differences(p in prop::collection::vec(-2.0..2.0f64, 64)) {
        for (name, time_dependent) in [
            ("CartPendulum", false),
            ("SliderCrank", false),
            ("Pendulum", false),
            ("Shaken", true),
        ] {
            let m = plant_file(name);
            let n = dims_of(m.structure());
            check_model(&m, &p[..n], time_dependent);
        }
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
        none_of(&M::default());
    }
    fn none_of<M: DaeModel>(m: &M) {
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
    // The same models' texts as plant files.
    none_of(&plant_file("Wheel"));
    none_of(&plant_file("SliderCrankJoint"));
    none_of(
        &plant_files()["CartPendulum"]
            .tracking()
            .expect("tracking section"),
    );
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

/// Largest difference of the states of two runs of the same length, neither diverged.
fn max_state_difference(a: &ClosedLoop, b: &ClosedLoop) -> f64 {
    assert!(a.divergence.is_none(), "{:?}", a.divergence);
    assert!(b.divergence.is_none(), "{:?}", b.divergence);
    assert_eq!(a.samples.len(), b.samples.len());
    let mut d = 0.0_f64;
    for (p, q) in a.samples.iter().zip(&b.samples) {
        for (v, w) in p.x.iter().zip(&q.x) {
            d = d.max((v - w).abs());
        }
    }
    d
}

#[test]
fn crane_closed_loop_from_the_plant_file_follows_the_macro_plants() {
    let file = plant_file("CartPendulum");
    // The file's plant supplies the exact derivatives (the loop would difference them
    // otherwise, as `Differenced` makes it).
    let s = file.structure();
    let mut g = DMatrix::zeros(s.n_equations(), s.n_equations());
    let x0 = [0.0, 0.1, -0.4, 0.2, 0.3, -0.1];
    assert!(file.constraint_gradient(0.0, &x0, &[1.0], &[0.0], &mut g));
    let compiled = crane_loop(&CartPendulum::default());
    let exact = crane_loop(&file);
    let differenced = crane_loop(&Differenced(file.clone()));
    let d = max_state_difference(&compiled, &exact);
    let d_differenced = max_state_difference(&compiled, &differenced);
    println!(
        "crane from the plant file: max |dx| = {d:e} from the macro plant's loop ({d_differenced:e} with the constraint derivatives differenced)"
    );
    // The tapes evaluate what the generated code evaluates, to rounding (runtime_agreement):
    // the loops agree far inside the plant tolerance, and closer than with differences.
    assert!(d < 1e-9, "{d:e}");
    assert!(d <= d_differenced, "{d:e} > {d_differenced:e}");
}

/// The consistent states of `m` from `x` with its exact curvature and with the curvature
/// differenced (`Differenced` hides it); `None` where the projection fails for `m`.
fn consistent_pair<M: DaeModel + Clone>(
    m: &M,
    x: &[f64],
    u: &[f64],
) -> Option<(ConsistentState, ConsistentState)> {
    let opts = ConsistentOptions::default();
    let exact = consistent_state(m, 0.3, x, u, &opts).ok()?;
    let differenced = consistent_state(&Differenced(m.clone()), 0.3, x, u, &opts)
        .expect("the differenced projection succeeds where the exact one does");
    Some((exact, differenced))
}

/// The exact and differenced consistent states of `m` from `x` agree: the curvature terms
/// to within the difference's error estimate (and rounding), the derivatives and multipliers
/// accordingly.
fn consistent_agrees<M: DaeModel + Clone>(m: &M, x: &[f64], u: &[f64]) {
    let Some((exact, differenced)) = consistent_pair(m, x, u) else {
        return;
    };
    let name = &m.structure().name;
    assert!(exact.curvature_exact, "{name}: {exact:?}");
    assert_eq!(exact.curvature_error, 0.0);
    assert!(!differenced.curvature_exact);
    assert_eq!(
        exact.x, differenced.x,
        "{name}: the positions do not use kappa"
    );
    let err = differenced.curvature_error;
    for (a, b) in exact.curvature.iter().zip(&differenced.curvature) {
        // The estimate is of the truncation error; for these constraints (quadratic in the
        // positions, or nearly) that is at the level of rounding, which in the difference
        // quotient is of the order eps^(2/3) ~ 4e-11 of the terms (measured: up to 3e-11,
        // up to 10 times the estimate).
        let rounding = 3e-10 * (1.0 + a.abs());
        assert!(
            (a - b).abs() <= err + rounding,
            "{name}: kappa exact {a:e}, differenced {b:e}, estimate {err:e}"
        );
    }
    let scale = exact
        .xdot
        .iter()
        .chain(&exact.z)
        .fold(1.0_f64, |m, v| m.max(v.abs()));
    // kappa's difference reaches x'' and the multipliers through one least-squares solve
    // (measured: up to 8e-11).
    let tol = 1e-8 * scale;
    for (a, b) in exact
        .xdot
        .iter()
        .chain(&exact.z)
        .zip(differenced.xdot.iter().chain(&differenced.z))
    {
        assert!(
            (a - b).abs() <= tol,
            "{name}: x', z exact {a:e}, differenced {b:e}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn consistent_state_with_the_exact_curvature_agrees_with_the_differenced_one(
        p in prop::collection::vec(-1.0..1.0f64, 8),
    ) {
        // Near each plant's usual states: positions off the constraint, velocities off its
        // hidden constraint, so that every stage works.
        let crane = [p[0], 0.5 * p[1], -0.4 + 0.1 * p[2], p[3], p[4], p[5]];
        consistent_agrees(&CartPendulum::default(), &crane, &[p[6]]);
        consistent_agrees(&plant_file("CartPendulum"), &crane, &[p[6]]);
        let crank = [p[0] * 3.0, 1.4 + 0.2 * p[1], 3.0 * p[2], p[3]];
        consistent_agrees(&SliderCrank::default(), &crank, &[p[4]]);
        consistent_agrees(&plant_file("SliderCrank"), &crank, &[p[4]]);
        let pendulum = Pendulum::default();
        let n = pendulum.structure().n_states();
        let x: Vec<f64> = (0..n).map(|k| 0.3 + 0.5 * p[k % p.len()]).collect();
        let nu = pendulum.structure().n_inputs();
        consistent_agrees(&pendulum, &x, &vec![p[7]; nu]);
        // A moving constraint: its d^2 g/(dt dx) is not part of kappa (neither way).
        let shaken = [0.3 + 0.2 * p[0], -0.9 + 0.1 * p[1], p[2], p[3]];
        consistent_agrees(&Shaken::default(), &shaken, &[p[4]]);
        consistent_agrees(&plant_file("Shaken"), &shaken, &[p[4]]);
    }
}

/// One crane loop (see [`crane_loop`]) on the plant `DPC_CRANE_PLANT` names, for callgrind
/// (release build; `--toggle-collect='dpc_core::simulate::simulate*'`): `macro` (the
/// default), `file` (the plant file), `macro-differenced` or `file-differenced` (the
/// constraint derivatives hidden, so that the loop and the projection difference them).
#[test]
#[ignore = "a measurement: run it under callgrind"]
fn crane_loop_for_profiling() {
    let which = std::env::var("DPC_CRANE_PLANT").unwrap_or_else(|_| "macro".to_string());
    let run = match which.as_str() {
        "macro" => crane_loop(&CartPendulum::default()),
        "file" => crane_loop(&plant_file("CartPendulum")),
        "macro-differenced" => crane_loop(&Differenced(CartPendulum::default())),
        "file-differenced" => crane_loop(&Differenced(plant_file("CartPendulum"))),
        other => {
            panic!("DPC_CRANE_PLANT={other}: macro, file, macro-differenced or file-differenced")
        }
    };
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    println!("{which}: {} samples", run.samples.len());
}
