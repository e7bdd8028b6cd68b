//! The generated tracking DAEs (stabilised Hirschorn steps, paper Section 2) against
//! independent computations: the paper's linear example, and trajectories of the wheel and
//! of the flexible-joint arm integrated from hand-written equations, differentiated in time
//! by high-order finite differences. Also: `W` and parameters changed at run time against
//! models compiled with the new values.

use dpc::core::model::{parameter_by_name, set_parameter_by_name, DaeModel};
use dpc::core::reference::{AtanIntegral, Components, ScalarReference, Sinusoid};
use dpc::core::tracking::TrackingError;
use dpc::core::{Reference, TrackingDae};
use dpc::nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use dpc_models::{
    FlexibleJoint, FlexibleJointTracking, Pendulum, Wheel, WheelLinear, WheelLinearTracking,
    WheelReference, WheelTracking,
};

/// Jacobian blocks of a tracking DAE at a point, as dense matrices.
fn blocks<M: DaeModel + Default>(
    x: &[f64],
    xdot: &[f64],
    z: &[f64],
) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let m = M::default();
    let st = m.structure();
    let ne = st.n_equations();
    let (nx, nz, nu) = (st.n_states(), st.n_algebraic(), st.n_inputs());
    let mut r = vec![0.0; ne];
    let (mut fxd, mut fx, mut fz, mut fu) = (
        DMatrix::zeros(ne, nx),
        DMatrix::zeros(ne, nx),
        DMatrix::zeros(ne, nz),
        DMatrix::zeros(ne, nu),
    );
    let w = vec![0.0; nu];
    m.evaluate(
        0.0, x, xdot, z, &w, &mut r, &mut fxd, &mut fx, &mut fz, &mut fu,
    );
    (fxd, fx, fz)
}

#[test]
fn linear_example_constraint_rows_are_the_papers_yhat() {
    // (4.1) with W = s + 5: yhat = [5 0 0 1 0; 0 5 0 0 1] x (paper, Section 4).
    let x = [0.3, -1.2, 0.7, 0.1, -0.4];
    let (fxd, fx, fz) = blocks::<WheelLinearTracking>(&x, &[0.0; 5], &[0.2, -0.1]);
    let rows = fx.rows(5, 2).into_owned();
    let expected =
        DMatrix::from_row_slice(2, 5, &[5.0, 0.0, 0.0, 1.0, 0.0, 0.0, 5.0, 0.0, 0.0, 1.0]);
    assert_eq!(rows, expected);
    assert!(
        fxd.rows(5, 2).iter().all(|v| *v == 0.0),
        "no X' in the rows"
    );
    assert!(fz.rows(5, 2).iter().all(|v| *v == 0.0), "no U in the rows");
    // The plant rows are the plant's own equations, with the inputs as unknowns.
    assert_eq!(fz[(2, 0)], -1.0);
    assert_eq!(fz[(4, 1)], -1.0);
    assert_eq!(
        default_w(&WheelLinearTracking::default()),
        [vec![5.0, 1.0], vec![5.0, 1.0]]
    );
}

/// The wheel of the paper's Appendix, written out by hand: x' = f(x, u).
fn wheel_rhs(x: &[f64; 5], u: [f64; 2]) -> [f64; 5] {
    let (m, r, i_r, i_n, g) = (1.0, 1.0, 0.5, 0.25, 9.81);
    let (a1, a2, a3, a4) = (
        i_n + m * r * r,
        i_r + m * r * r,
        m * r * r + i_n - i_r,
        2.0 * m * r * r + i_n,
    );
    let [th, _psi, dphi, dth, dpsi] = *x;
    let (s, c) = th.sin_cos();
    let mass = Matrix3::new(
        i_r * s * s + a1 * c * c,
        0.0,
        a1 * c,
        0.0,
        a2,
        0.0,
        a1 * c,
        0.0,
        i_n + m * r * r,
    );
    let rhs = Vector3::new(
        i_n * dth * dpsi * s + 2.0 * a3 * dphi * dth * c * s + u[0] * s,
        -a1 * dphi * dpsi * s - a3 * dphi * dphi * c * s - m * g * r * c,
        a4 * dphi * dth * s + u[1],
    );
    let acc = mass.lu().solve(&rhs).expect("mass matrix is regular");
    [dth, dpsi, acc[0], acc[1], acc[2]]
}

/// Classical RK4 samples of an ODE on a uniform grid.
fn rk4<const N: usize>(
    f: impl Fn(f64, &[f64; N]) -> [f64; N],
    x0: [f64; N],
    h: f64,
    steps: usize,
) -> Vec<[f64; N]> {
    let mut out = vec![x0];
    let mut x = x0;
    let add = |a: &[f64; N], b: &[f64; N], s: f64| -> [f64; N] {
        let mut r = *a;
        for i in 0..N {
            r[i] += s * b[i];
        }
        r
    };
    for k in 0..steps {
        let t = k as f64 * h;
        let k1 = f(t, &x);
        let k2 = f(t + h / 2.0, &add(&x, &k1, h / 2.0));
        let k3 = f(t + h / 2.0, &add(&x, &k2, h / 2.0));
        let k4 = f(t + h, &add(&x, &k3, h));
        for i in 0..N {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        out.push(x);
    }
    out
}

/// First and second derivatives at sample `k` by 6th-order central differences.
fn derivatives(samples: &[f64], k: usize, h: f64) -> (f64, f64) {
    let s = |j: isize| samples[(k as isize + j) as usize];
    let d1 = (-s(-3) + 9.0 * s(-2) - 45.0 * s(-1) + 45.0 * s(1) - 9.0 * s(2) + s(3)) / (60.0 * h);
    let d2 = (2.0 * s(-3) - 27.0 * s(-2) + 270.0 * s(-1) - 490.0 * s(0) + 270.0 * s(1)
        - 27.0 * s(2)
        + 2.0 * s(3))
        / (180.0 * h * h);
    (d1, d2)
}

#[test]
fn wheel_constraint_rows_equal_w_of_the_outputs_along_a_trajectory() {
    let u = |t: f64| [0.3 * t.sin(), 0.2 * (0.5 * t).cos()];
    let h = 1e-3;
    let traj = rk4(
        |t, x| wheel_rhs(x, u(t)),
        [1.4, 0.0, 0.5, 0.2, -6.0],
        h,
        1000,
    );
    let theta: Vec<f64> = traj.iter().map(|x| x[0]).collect();
    let psi: Vec<f64> = traj.iter().map(|x| x[1]).collect();
    let tracking = WheelTracking::default();
    for k in [100, 400, 777, 990] {
        let t = k as f64 * h;
        let x = traj[k];
        let xdot = wheel_rhs(&x, u(t));
        let z = u(t);
        let mut g = [0.0; 7];
        tracking.residual(t, &x, &xdot, &z, &[0.0, 0.0], &mut g);
        // Plant rows vanish on a trajectory of the plant.
        for (i, gi) in g.iter().enumerate().take(5) {
            assert!(gi.abs() < 1e-10, "plant row {i} = {gi}");
        }
        let (dtheta, _) = derivatives(&theta, k, h);
        let (dpsi, _) = derivatives(&psi, k, h);
        assert!((g[5] - (5.0 * theta[k] + dtheta)).abs() < 1e-8, "theta row");
        assert!((g[6] - (5.0 * psi[k] + dpsi)).abs() < 1e-8, "psi row");
    }
}

#[test]
fn two_steps_on_the_flexible_joint_match_finite_differences() {
    let p = FlexibleJoint::default().params;
    let u = |t: f64| 2.0 * (1.3 * t).sin();
    let rhs = |t: f64, x: &[f64; 4]| {
        let [q, w, qm, wm] = *x;
        [
            w,
            (-p.m * p.g * p.l * q.sin() - p.k * (q - qm)) / p.i_link,
            wm,
            (p.k * (q - qm) + u(t)) / p.j_motor,
        ]
    };
    let h = 1e-3;
    let traj = rk4(rhs, [0.2, 0.0, -0.1, 0.5], h, 800);
    let q: Vec<f64> = traj.iter().map(|x| x[0]).collect();
    let tracking = FlexibleJointTracking::default();
    for k in [50, 333, 790] {
        let t = k as f64 * h;
        let x = traj[k];
        let mut g = [0.0; 5];
        tracking.residual(t, &x, &rhs(t, &x), &[u(t)], &[0.0], &mut g);
        let (d1, d2) = derivatives(&q, k, h);
        let w_of_q = d2 + 5.0 * d1 + 6.0 * q[k];
        assert!(
            (g[4] - w_of_q).abs() < 1e-6 * (1.0 + w_of_q.abs()),
            "row {} vs (s+2)(s+3) q = {w_of_q}",
            g[4]
        );
    }
    assert_eq!(
        default_w(&FlexibleJointTracking::default()),
        [vec![6.0, 5.0, 1.0]]
    );
}

#[test]
fn relative_degrees_are_reported() {
    // Paper, Section 4: H(s) = diag(5/(s^3 + 8.46 s), 1/s^2).
    assert_eq!(Wheel::RELATIVE_DEGREES, &[Some(3), Some(2)]);
    assert_eq!(WheelLinear::RELATIVE_DEGREES, &[Some(3), Some(2)]);
    assert_eq!(
        WheelTracking::default().relative_degrees(),
        &[Some(3), Some(2)]
    );
    assert_eq!(FlexibleJoint::RELATIVE_DEGREES, &[Some(4)]);
    // The pendulum's rod constraint is differentiated twice before the structural matching:
    // the force on the mass reaches the angle after two derivatives, as in the angle form.
    assert_eq!(Pendulum::RELATIVE_DEGREES, &[Some(2)]);
    // After one step on each wheel output the largest relative degree left is 2 (the
    // nilpotency index of N in the paper's example), after two steps on the arm also 2.
    assert_eq!(
        WheelTracking::default().remaining_relative_degree(),
        Some(2)
    );
    assert_eq!(
        FlexibleJointTracking::default().remaining_relative_degree(),
        Some(2)
    );
}

#[test]
fn tracking_dae_layout() {
    assert_eq!(WheelTracking::N_STATES, 5);
    assert_eq!(WheelTracking::N_ALGEBRAIC, 2);
    let tracking = WheelTracking::default();
    let structure = tracking.structure();
    assert_eq!(structure.algebraic, ["u1", "u2"]);
    assert_eq!(structure.inputs, ["w_theta", "w_psi"]);
    assert_eq!(WheelTracking::N_EQUATIONS, 7);
    assert_eq!(structure.n_equations(), 7);
    assert_eq!(&structure.equations[5], "dtheta + 5 * theta == w_theta");
    assert_eq!(tracking.plant_inputs(), 2);
    assert!(WheelTracking::LISTING.contains("W(s) = s + 5"));
}

#[test]
fn dsl_references_match_closed_forms() {
    // theta_ref = pi/2 + 0.1 sin t, psi_ref = -6 t - 0.5 (t atan t - ln(1 + t^2)/2).
    let theta = Sinusoid {
        offset: std::f64::consts::FRAC_PI_2,
        amplitude: 0.1,
        omega: 1.0,
        phase: 0.0,
    };
    let psi_integral = AtanIntegral { scale: -0.5 };
    let r = WheelReference::default();
    assert_eq!(r.max_order(), 2);
    let mut out = [0.0; 6];
    for &t in &[0.0, 0.7, 3.0, 12.5] {
        r.derivatives(t, 2, &mut out).unwrap();
        for k in 0..3 {
            let psi_lin = match k {
                0 => -6.0 * t,
                1 => -6.0,
                _ => 0.0,
            };
            assert!((out[2 * k] - theta.derivative(t, k)).abs() < 1e-13);
            assert!((out[2 * k + 1] - (psi_lin + psi_integral.derivative(t, k))).abs() < 1e-12);
        }
    }
    assert!(r.derivatives(0.0, 3, &mut [0.0; 8]).is_err());

    // w = W(d/dt) xi: 5 xi + xi'.
    let mut scratch = [0.0; 4];
    let mut w = [0.0; 2];
    WheelTracking::default()
        .tracking_inputs(&r, 1.0, &mut scratch, &mut w)
        .unwrap();
    let mut d = [0.0; 4];
    r.derivatives(1.0, 1, &mut d).unwrap();
    assert!((w[0] - (5.0 * d[0] + d[2])).abs() < 1e-14);
    assert!((w[1] - (5.0 * d[1] + d[3])).abs() < 1e-14);
}

#[test]
fn tracking_matrix_types_are_fixed_size() {
    let t = WheelTracking::default();
    let g: SMatrix<f64, 7, 7> = t.iteration_matrix_fixed(
        0.0,
        &[1.5, 0.0, 0.0, 0.0, -6.0].into(),
        &Default::default(),
        &Default::default(),
        &Default::default(),
        10.0,
    );
    // The iteration matrix of the tracking DAE is regular at the nominal point.
    assert!(g.determinant().abs() > 1e-8);
}

// Run-time W and parameters: the same plant compiled twice with different W.

dpc::model! {
    /// A cart on a hardening spring; W = (s + 5)(s + 1) on a nonlinear position output.
    pub CartA {
        params { m = 2.0, k = 3.0, c = 0.4 }
        states { x, v }
        inputs { f }
        equations {
            der(x) = v;
            m * der(v) == -k * x - 0.5 * k * x.powi(3) - c * v + f;
        }
        outputs { p = x + 0.1 * x.powi(2) }
        tracking CartATracking { p: [5.0, 1.0] }
    }
}

dpc::model! {
    /// The same cart with W = s (s + 3): one root 0, a plain derivative.
    pub CartB {
        params { m = 2.0, k = 3.0, c = 0.4 }
        states { x, v }
        inputs { f }
        equations {
            der(x) = v;
            m * der(v) == -k * x - 0.5 * k * x.powi(3) - c * v + f;
        }
        outputs { p = x + 0.1 * x.powi(2) }
        tracking CartBTracking { p: [3.0, 0.0] }
    }
}

/// Deterministic pseudo-random numbers in `[-1, 1)` (xorshift).
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    2.0 * ((*state >> 11) as f64 / (1u64 << 53) as f64) - 1.0
}

/// Residual, all Jacobian blocks and the iteration matrix at a point, as dense matrices.
fn everything<M: DaeModel>(
    m: &M,
    t: f64,
    x: &[f64],
    xdot: &[f64],
    z: &[f64],
    u: &[f64],
    c: f64,
) -> Vec<DMatrix<f64>> {
    let st = m.structure();
    let ne = st.n_equations();
    let mut r = vec![0.0; ne];
    let (mut fxd, mut fx, mut fz, mut fu) = (
        DMatrix::zeros(ne, st.n_states()),
        DMatrix::zeros(ne, st.n_states()),
        DMatrix::zeros(ne, st.n_algebraic()),
        DMatrix::zeros(ne, st.n_inputs()),
    );
    m.evaluate(
        t, x, xdot, z, u, &mut r, &mut fxd, &mut fx, &mut fz, &mut fu,
    );
    let mut r2 = vec![0.0; ne];
    m.residual(t, x, xdot, z, u, &mut r2);
    let mut it = DMatrix::zeros(ne, ne);
    m.iteration_matrix(t, x, xdot, z, u, c, &mut it);
    vec![
        DMatrix::from_column_slice(ne, 1, &r),
        DMatrix::from_column_slice(ne, 1, &r2),
        fxd,
        fx,
        fz,
        fu,
        it,
    ]
}

fn assert_same_at_random_points<A: DaeModel, B: DaeModel>(a: &A, b: &B) {
    let st = a.structure();
    assert_eq!(st.n_equations(), b.structure().n_equations());
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    for _ in 0..50 {
        let mut draw = |n: usize| {
            (0..n)
                .map(|_| 3.0 * uniform(&mut state))
                .collect::<Vec<_>>()
        };
        let (t, c) = (draw(1)[0], 10.0 * draw(1)[0]);
        let (x, xdot) = (draw(st.n_states()), draw(st.n_states()));
        let (z, u) = (draw(st.n_algebraic()), draw(st.n_inputs()));
        let ea = everything(a, t, &x, &xdot, &z, &u, c);
        let eb = everything(b, t, &x, &xdot, &z, &u, c);
        for (k, (ma, mb)) in ea.iter().zip(&eb).enumerate() {
            let scale = 1.0 + ma.amax();
            assert!(
                (ma - mb).amax() <= 1e-13 * scale,
                "block {k} differs at x = {x:?}: {ma} vs {mb}"
            );
        }
    }
}

#[test]
fn w_roots_set_at_run_time_give_the_model_compiled_with_them() {
    assert_eq!(default_w(&CartATracking::default()), [vec![5.0, 6.0, 1.0]]);
    assert_eq!(default_w(&CartBTracking::default()), [vec![0.0, 3.0, 1.0]]);
    // The entries the coefficients multiply are structural, whatever their defaults: the
    // root 0 of CartB does not drop the column of x from its constraint row.
    let (sa, sb) = (
        CartATracking::default().structure().clone(),
        CartBTracking::default().structure().clone(),
    );
    assert_eq!(sa.pattern_f_x, sb.pattern_f_x);
    assert_eq!(sa.pattern_f_xdot, sb.pattern_f_xdot);
    assert_eq!(sa.pattern_f_z, sb.pattern_f_z);
    assert!(sb.pattern_f_x.contains(&(2, 0)));

    let mut a = CartATracking::default();
    assert_eq!(a.w_coefficients(0), &[5.0, 6.0, 1.0]);
    a.set_w_roots(0, &[3.0, 0.0]).unwrap();
    assert_eq!(a.w_coefficients(0), &[0.0, 3.0, 1.0]);
    assert_same_at_random_points(&a, &CartBTracking::default());

    let mut b = CartBTracking::default();
    b.set_w_roots(0, &[1.0, 5.0]).unwrap();
    assert_same_at_random_points(&CartATracking::default(), &b);

    // The tracking inputs w = W(d/dt) xi use the coefficients in use.
    let reference = Components::new(
        1,
        vec![Box::new(Sinusoid {
            offset: 0.2,
            amplitude: 0.5,
            omega: 1.3,
            phase: 0.1,
        })],
    )
    .unwrap();
    let (mut wa, mut wb) = ([0.0], [0.0]);
    let mut scratch = [0.0; 3];
    a.tracking_inputs(&reference, 0.7, &mut scratch, &mut wa)
        .unwrap();
    CartBTracking::default()
        .tracking_inputs(&reference, 0.7, &mut scratch, &mut wb)
        .unwrap();
    assert!((wa[0] - wb[0]).abs() < 1e-14, "{wa:?} vs {wb:?}");
    let mut d = [0.0; 3];
    reference.derivatives(0.7, 2, &mut d).unwrap();
    assert!((wa[0] - (3.0 * d[1] + d[2])).abs() < 1e-14);

    // from_params starts from the compiled W again.
    assert_eq!(
        CartATracking::from_params(a.params).w_coefficients(0),
        &[5.0, 6.0, 1.0]
    );
    assert_eq!(a.w_coefficients(1), &[] as &[f64]);
}

#[test]
fn bad_w_gives_typed_errors_and_leaves_w_unchanged() {
    let mut a = CartATracking::default();
    let name = |e: &TrackingError| e.to_string();
    let e = a.set_w_roots(1, &[1.0, 2.0]).unwrap_err();
    assert!(
        matches!(
            e,
            TrackingError::UnknownOutput {
                output: 1,
                outputs: 1,
                ..
            }
        ),
        "{e:?}"
    );
    let e = a.set_w_roots(0, &[1.0]).unwrap_err();
    assert_eq!(
        e,
        TrackingError::WrongDegree {
            model: "CartATracking".into(),
            output: "p".into(),
            expected: 2,
            found: 1
        }
    );
    assert!(name(&e).contains("tracking"), "{e}");
    let e = a.set_w_roots(0, &[1.0, 2.0, 3.0]).unwrap_err();
    assert!(
        matches!(e, TrackingError::WrongDegree { found: 3, .. }),
        "{e:?}"
    );
    let e = a.set_w_roots(0, &[1.0, f64::NAN]).unwrap_err();
    assert!(
        matches!(e, TrackingError::NonFinite { index: 1, .. }),
        "{e:?}"
    );
    let e = a.set_w_roots(0, &[f64::INFINITY, 1.0]).unwrap_err();
    assert!(
        matches!(e, TrackingError::NonFinite { index: 0, .. }),
        "{e:?}"
    );
    let e = a.set_w_roots(0, &[2.0, -0.5]).unwrap_err();
    assert!(
        matches!(e, TrackingError::UnstableRoot { value, .. } if value == -0.5),
        "{e:?}"
    );
    assert!(name(&e).contains("right half plane"), "{e}");

    let e = a.set_w_coefficients(0, &[1.0, 1.0]).unwrap_err();
    assert!(
        matches!(
            e,
            TrackingError::WrongLength {
                expected: 3,
                found: 2,
                ..
            }
        ),
        "{e:?}"
    );
    let e = a.set_w_coefficients(0, &[1.0, 2.0, 2.0]).unwrap_err();
    assert!(
        matches!(e, TrackingError::NotMonic { leading, .. } if leading == 2.0),
        "{e:?}"
    );
    // s^2 - 1 and s^2 + 1.
    for c in [[-1.0, 0.0, 1.0], [1.0, 0.0, 1.0]] {
        let e = a.set_w_coefficients(0, &c).unwrap_err();
        assert!(matches!(e, TrackingError::Unstable { .. }), "{c:?}: {e:?}");
    }
    assert_eq!(
        a.w_coefficients(0),
        &[5.0, 6.0, 1.0],
        "unchanged after errors"
    );

    // Complex stable roots are fine as coefficients: s^2 + 0.4 s + 4.
    a.set_w_coefficients(0, &[4.0, 0.4, 1.0]).unwrap();
    assert_eq!(a.w_coefficients(0), &[4.0, 0.4, 1.0]);
    // Two plain derivatives: W = s^2.
    a.set_w_roots(0, &[0.0, 0.0]).unwrap();
    assert_eq!(a.w_coefficients(0), &[0.0, 0.0, 1.0]);
}

#[test]
fn parameters_set_by_name_change_the_residual_as_the_parameter_would() {
    let cart = CartA::default();
    assert_eq!(cart.structure().params, ["m", "k", "c"]);
    let mut params = CartAParams::default();
    set_parameter_by_name(&cart, &mut params, "k", 7.5).unwrap();
    assert_eq!(
        params,
        CartAParams {
            k: 7.5,
            ..CartAParams::default()
        }
    );
    assert_eq!(parameter_by_name(&cart, &params, "k"), Ok(7.5));
    assert_eq!(CartA::parameter(&params, 0), Some(2.0));
    assert_eq!(CartA::parameter(&params, 3), None);
    assert!(!CartA::set_parameter(&mut params, 3, 1.0));

    let (x, xdot, u) = ([0.7, -0.3], [0.1, 0.4], [0.25]);
    let mut r = [0.0; 2];
    CartA::from_params(params).residual(0.0, &x, &xdot, &[], &u, &mut r);
    // m v' + k x + k x^3 / 2 + c v - f with k = 7.5.
    let k = 7.5;
    let expected = 2.0 * 0.4 - (-k * 0.7 - 0.5 * k * 0.7_f64.powi(3) - 0.4 * -0.3 + 0.25);
    assert!((r[1] - expected).abs() < 1e-14, "{r:?} vs {expected}");
    let mut r0 = [0.0; 2];
    CartA::default().residual(0.0, &x, &xdot, &[], &u, &mut r0);
    assert!((r[1] - r0[1]).abs() > 1.0);

    // The tracking DAE shares the parameters: the controller's model changes the same way.
    let mut cp = CartATracking::default().params;
    set_parameter_by_name(&CartATracking::default(), &mut cp, "m", 3.0).unwrap();
    let controller = CartATracking::from_params(cp);
    let mut g = [0.0; 3];
    controller.residual(0.0, &x, &xdot, &u, &[0.0], &mut g);
    let mut plant = [0.0; 2];
    CartA::from_params(CartAParams {
        m: 3.0,
        ..CartAParams::default()
    })
    .residual(0.0, &x, &xdot, &[], &u, &mut plant);
    assert_eq!(&g[..2], &plant);

    let e = set_parameter_by_name(&cart, &mut params, "nope", 1.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "model `CartA` has no parameter `nope`; its parameters are m, k, c"
    );
    assert_eq!(params.k, 7.5, "unchanged after an error");
    let wheel = Wheel::default();
    let e = parameter_by_name(&wheel, &wheel.params, "mass").unwrap_err();
    assert!(e.to_string().contains("m, r, i_r, i_n, g"), "{e}");
}

/// The compiled default `W_i` of every output of a tracking DAE.
fn default_w<T: TrackingDae>(tracking: &T) -> Vec<Vec<f64>> {
    (0..tracking.structure().n_outputs())
        .map(|i| tracking.default_w_coefficients(i).to_vec())
        .collect()
}
