//! Indexed families in `model!`: a model written with `consts`, families, `for` and `sum` is
//! the model written out in scalars (same residual, Jacobians and names as the user reads
//! them), its Jacobians agree with central differences, and the arm declared with families
//! for one link is the repository's single flexible joint.

mod common;

use common::{check_model, dims};
use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::design::{design, DesignOptions};
use dpc::core::linear_analysis::AnalysisOptions;
use dpc::core::linear_solver::NalgebraLu;
use dpc::core::model::{parameter_by_name, set_parameter_by_name, DaeModel};
use dpc::core::prefeedback::SteadyMotion;
use dpc::core::simulate::{simulate, ClosedLoopOptions};
use dpc::core::TrackingDae;
use dpc_models::{Arm1, Arm1Params, Arm2, Arm2Reference, Arm2Tracking, FlexibleJoint};
use proptest::prelude::*;

dpc::model! {
    /// Three masses on springs in a row, written with families.
    pub Chain {
        consts { N = 3 }
        params { k[N] = [1.0, 2.0, 3.0], c = 0.5, w0[2][N] = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]] }
        states { x[N], v[N] }
        inputs { u[N] }
        let s[i in 0..N] = sum(0..=i, |j| x[j]);
        let p[i in 0..N] = sum(0..i, |j| p[j]) * 0.5 + x[i];
        equations {
            for i in 0..N {
                der(x[i]) = v[i];
            }
            for i in 0..N - 1 {
                der(v[i]) == -k[i] * (x[i] - x[i + 1]) - c * v[i] + u[i] + s[i] * w0[1][i] + p[i];
            }
            der(v[N - 1]) == -k[N - 1] * x[N - 1] + u[N - 1] + sum(max(0, N - 5)..N, |j| x[j] * j);
        }
        outputs { x, y[i in 0..2] = v[i] + w0[0][i] }
    }
}

dpc::model! {
    /// [`Chain`] written out in scalars.
    pub ChainScalar {
        params { k0 = 1.0, k1 = 2.0, k2 = 3.0, c = 0.5, w00 = 1.0, w01 = 2.0, w02 = 3.0, w10 = 4.0, w11 = 5.0, w12 = 6.0 }
        states { x0, x1, x2, v0, v1, v2 }
        inputs { u0, u1, u2 }
        let p0 = x0;
        let p1 = p0 * 0.5 + x1;
        let p2 = (p0 + p1) * 0.5 + x2;
        equations {
            der(x0) = v0;
            der(x1) = v1;
            der(x2) = v2;
            der(v0) == -k0 * (x0 - x1) - c * v0 + u0 + x0 * w10 + p0;
            der(v1) == -k1 * (x1 - x2) - c * v1 + u1 + (x0 + x1) * w11 + p1;
            der(v2) == -k2 * x2 + u2 + (x0 * 0.0 + x1 * 1.0 + x2 * 2.0);
        }
        outputs { x0, x1, x2, y0 = v0 + w00, y1 = v1 + w01 }
    }
}

dpc::model! {
    /// The two-link arm in the textbook form (Spong, Hutchinson & Vidyasagar, 7.3.2, with
    /// angles from the downward vertical): mass matrix, Coriolis and gravity written out.
    pub TwoLinkTextbook {
        params { m1 = 1.0, m2 = 1.0, l1 = 0.5, r1 = 0.25, r2 = 0.25, i1 = 0.02, i2 = 0.02,
                 j1 = 0.5, j2 = 0.5, k1 = 40.0, k2 = 40.0, g = 9.81 }
        states { q0, q1, w0, w1, th0, th1, wm0, wm1 }
        inputs { u0, u1 }
        let m11 = m1 * r1.powi(2) + m2 * (l1.powi(2) + r2.powi(2) + 2.0 * l1 * r2 * cos(q1)) + i1 + i2;
        let m12 = m2 * (r2.powi(2) + l1 * r2 * cos(q1)) + i2;
        let m22 = m2 * r2.powi(2) + i2;
        let h = -m2 * l1 * r2 * sin(q1);
        equations {
            der(q0) = w0;
            m11 * der(w0) + m12 * der(w1) + h * (2.0 * w0 * w1 + w1.powi(2))
                + (m1 * r1 + m2 * l1) * g * sin(q0) + m2 * r2 * g * sin(q0 + q1) + k1 * (q0 - th0) == 0.0;
            der(th0) = wm0;
            der(wm0) = (k1 * (q0 - th0) + u0) / j1;
            der(q1) = w1;
            m12 * der(w0) + m22 * der(w1) - h * w0.powi(2) + m2 * r2 * g * sin(q0 + q1)
                + k2 * (q1 - th1) == 0.0;
            der(th1) = wm1;
            der(wm1) = (k2 * (q1 - th1) + u1) / j2;
        }
    }
}

#[test]
fn families_are_named_as_written() {
    let chain = Chain::default();
    let s = chain.structure();
    assert_eq!(s.states, ["x[0]", "x[1]", "x[2]", "v[0]", "v[1]", "v[2]"]);
    assert_eq!(s.inputs, ["u[0]", "u[1]", "u[2]"]);
    assert_eq!(s.outputs, ["x[0]", "x[1]", "x[2]", "y[0]", "y[1]"]);
    assert_eq!(
        s.params,
        [
            "k[0]", "k[1]", "k[2]", "c", "w0[0][0]", "w0[0][1]", "w0[0][2]", "w0[1][0]",
            "w0[1][1]", "w0[1][2]"
        ]
    );
    assert_eq!(
        &s.equations[4],
        "der(v[1]) == -k[1] * (x[1] - x[2]) - c * v[1] + u[1] + s[1] * w0[1][1] + p[1]"
    );
    assert_eq!(Chain::N_EQUATIONS, 6);
    // The generated code names elements `k_1`, `w0_1_2`; the user names them as written.
    let mut params = chain.params;
    assert_eq!(params.k_1, 2.0);
    assert_eq!(params.w0_1_2, 6.0);
    set_parameter_by_name(&chain, &mut params, "k[1]", 2.5).expect("k[1] is a parameter");
    assert_eq!(params.k_1, 2.5);
    assert_eq!(
        parameter_by_name(&chain, &params, "w0[1][2]").expect("a parameter"),
        6.0
    );
    let err = parameter_by_name(&chain, &params, "k_1").expect_err("not a user name");
    assert!(err.to_string().contains("k[1]"), "{err}");
    assert!(
        Chain::LISTING.contains("let p[i in 0..N] = sum(0..i, |j| p[j]) * 0.5 + x[i]"),
        "{}",
        Chain::LISTING
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The family model and the scalar model are the same residual and Jacobians.
    #[test]
    fn families_unroll_to_the_scalar_model(v in prop::collection::vec(-1.0..1.0f64, dims::<Chain>())) {
        check_model::<Chain>(&v);
        let (a, b) = (Chain::default(), ChainScalar::default());
        let (t, x, xdot, u) = (v[0], &v[1..7], &v[7..13], &v[13..16]);
        let (mut ra, mut rb) = ([0.0; 6], [0.0; 6]);
        a.residual(t, x, xdot, &[], u, &mut ra);
        b.residual(t, x, xdot, &[], u, &mut rb);
        for k in 0..6 {
            prop_assert!((ra[k] - rb[k]).abs() <= 1e-14 * (1.0 + ra[k].abs()), "row {}: {} vs {}", k, ra[k], rb[k]);
        }
        let (mut ya, mut yb) = ([0.0; 5], [0.0; 5]);
        a.outputs(t, x, &[], u, &mut ya);
        b.outputs(t, x, &[], u, &mut yb);
        prop_assert_eq!(ya, yb);
        let (mut ja, mut jb) = (dpc::nalgebra::DMatrix::zeros(6, 6), dpc::nalgebra::DMatrix::zeros(6, 6));
        a.iteration_matrix(t, x, xdot, &[], u, 0.7, &mut ja);
        b.iteration_matrix(t, x, xdot, &[], u, 0.7, &mut jb);
        prop_assert!((ja - jb).amax() <= 1e-13);
    }

    /// The arm's equations (d'Alembert's principle over the links, written once for every
    /// `N`) are the textbook two-link equations: residuals agree at random points, and the
    /// mass matrix `dF/d(w')` is symmetric.
    #[test]
    fn two_link_arm_is_the_textbook_arm(v in prop::collection::vec(-2.0..2.0f64, 1 + 16 + 2)) {
        let (arm, book) = (Arm2::default(), TwoLinkTextbook::default());
        let (t, x, xdot, u) = (v[0], &v[1..9], &v[9..17], &v[17..19]);
        let (mut ra, mut rb) = ([0.0; 8], [0.0; 8]);
        arm.residual(t, x, xdot, &[], u, &mut ra);
        book.residual(t, x, xdot, &[], u, &mut rb);
        for k in 0..8 {
            prop_assert!((ra[k] - rb[k]).abs() <= 1e-12 * (1.0 + rb[k].abs()), "row {}: arm {} textbook {}", k, ra[k], rb[k]);
        }
        let mut m = dpc::nalgebra::DMatrix::zeros(8, 8);
        let mut rest = [dpc::nalgebra::DMatrix::zeros(8, 8), dpc::nalgebra::DMatrix::zeros(8, 0), dpc::nalgebra::DMatrix::zeros(8, 2)];
        let [f_x, f_z, f_u] = &mut rest;
        arm.evaluate(t, x, xdot, &[], u, &mut ra, &mut m, f_x, f_z, f_u);
        // Rows 1 and 5 are the links' equations; columns 2 and 3 are w[0]', w[1]'.
        prop_assert!((m[(1, 3)] - m[(5, 2)]).abs() <= 1e-14 * (1.0 + m[(1, 3)].abs()));
    }

    #[test]
    fn arm_jacobians(v in prop::collection::vec(-1.0..1.0f64, dims::<Arm2>())) {
        check_model::<Arm2>(&v);
    }

    /// With the link inertia about the joint split into `i_link + m r^2`, the one-link arm
    /// is the flexible joint: its residual vanishes at the flexible joint's derivatives.
    #[test]
    fn one_link_arm_is_the_flexible_joint(x in prop::collection::vec(-2.0..2.0f64, 4), u in -5.0..5.0f64) {
        let joint = FlexibleJoint::default();
        let p = joint.params;
        let arm = Arm1::new(Arm1Params {
            m_0: p.m,
            r_0: p.l,
            i_link_0: p.i_link - p.m * p.l * p.l,
            j_motor_0: p.j_motor,
            ks_0: p.k,
            g: p.g,
            ..Arm1Params::default()
        });
        let mut xdot = [0.0; 4];
        // The flexible joint is explicit: F = x' - f(x, u), so f = -F at x' = 0.
        joint.residual(0.0, &x, &[0.0; 4], &[], &[u], &mut xdot);
        let xdot = xdot.map(|f| -f);
        let mut r = [0.0; 4];
        arm.residual(0.0, &x, &xdot, &[], &[u], &mut r);
        let scale = 1.0 + xdot.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, r) in r.iter().enumerate() {
            prop_assert!(r.abs() <= 1e-12 * scale, "row {}: {} (x' = {:?})", k, r, xdot);
        }
    }
}

#[test]
fn arm_tracking_has_two_steps_per_joint() {
    assert_eq!(Arm2::RELATIVE_DEGREES, &[Some(4), Some(4)]);
    let tracking = Arm2Tracking::default();
    assert_eq!(tracking.remaining_relative_degree(), Some(2));
    assert_eq!(tracking.w_coefficients(1), &[16.0, 8.0, 1.0]);
    assert_eq!(tracking.structure().inputs, ["w_q[0]", "w_q[1]"]);
}

/// DPC with two stabilised Hirschorn steps per joint tracks the two-link arm's joint-space
/// reference from rest (as `scenarios/arm2.toml`): the two steps leave relative degree 2 per
/// joint, the linear analysis predicts plain DPC unstable, and the preliminary feedback
/// designed about the hanging rest (poles at -40) makes it track; the error left after the
/// transient of `W = (s + 4)^2` is small against the reference's amplitude 0.3, and no
/// sample fails.
#[test]
fn two_steps_per_joint_track_the_two_link_arm() {
    let rest = SteadyMotion {
        state: vec![0.0; 8],
        rate: vec![0.0; 8],
        algebraic: vec![],
        input: vec![0.0; 2],
    };
    let designed = design(
        &Arm2::default(),
        &rest,
        &DesignOptions {
            analysis: AnalysisOptions {
                w: Some(vec![vec![4.0, 4.0]; 2]),
                poles: Some(vec![dpc::nalgebra::Complex::new(-40.0, 0.0); 4]),
                ..AnalysisOptions::default()
            },
            horizon: 6.0,
            relative_degrees: Arm2::RELATIVE_DEGREES.to_vec(),
        },
    )
    .expect("design about the hanging rest");
    assert!(
        !designed.analysis.dpc_stable,
        "plain DPC is predicted unstable"
    );
    let mut dpc = Dpc::new(
        Arm2Tracking::default(),
        Arm2Reference::default(),
        NalgebraLu::<{ Arm2Tracking::N_EQUATIONS }>::new(),
        DpcOptions {
            delta: 1e-3,
            ..DpcOptions::default()
        },
    )
    .expect("controller")
    .with_prefeedback(designed.prefeedback().expect("K_n"))
    .expect("prefeedback");
    let run = simulate(
        &Arm2::default(),
        &mut dpc,
        &[0.0; 8],
        &ClosedLoopOptions {
            h: 0.01,
            t_end: 6.0,
            ..ClosedLoopOptions::default()
        },
    )
    .expect("run starts");
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    assert_eq!(run.failed_samples(), 0);
    let early = run.max_abs_error_since(0.0);
    let late = run.max_abs_error_since(4.0);
    for (e0, e) in early.iter().zip(&late) {
        assert!(
            *e < 0.01,
            "late tracking errors {late:?} (from t = 0: {early:?})"
        );
        assert!(e < e0, "the error decays: {late:?} against {early:?}");
    }
}
