//! The analytic Jacobians generated for the plants in `dpc-models` agree with central
//! differences of the generated residual at random points (relative error < 1e-6), and the
//! generated routines agree with each other (iteration matrix, fixed-size conveniences).

mod common;

use common::{check_model, dims};
use dpc_models::{
    FlexibleJoint, FlexibleJointMass4Tracking, FlexibleJointTracking, Pendulum, Wheel, WheelLinear,
    WheelTracking,
};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn wheel_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<Wheel>())) {
        check_model::<Wheel>(&v);
    }

    #[test]
    fn wheel_linear_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<WheelLinear>())) {
        check_model::<WheelLinear>(&v);
    }

    #[test]
    fn flexible_joint_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<FlexibleJoint>())) {
        check_model::<FlexibleJoint>(&v);
    }

    #[test]
    fn tracking_dae_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<WheelTracking>())) {
        check_model::<WheelTracking>(&v);
    }

    #[test]
    fn two_step_tracking_dae_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<FlexibleJointTracking>())) {
        check_model::<FlexibleJointTracking>(&v);
    }

    #[test]
    fn steps_through_implicit_equations_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<FlexibleJointMass4Tracking>())) {
        check_model::<FlexibleJointMass4Tracking>(&v);
    }

    #[test]
    fn pendulum_jacobians_match_central_differences(v in prop::collection::vec(0.2..3.0f64, dims::<Pendulum>())) {
        check_model::<Pendulum>(&v);
    }
}

#[test]
fn wheel_linearisation_reproduces_the_paper() {
    // About x0 = [pi/2, -6t, 0, 0, -6] with u = 0: A of (4.1), B with the Appendix gains.
    let wheel = Wheel::default();
    let x = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];
    let j = wheel.jacobians_fixed(
        0.0,
        &x.into(),
        &Default::default(),
        &Default::default(),
        &Default::default(),
    );
    // x' = -(dF/dx')^-1 dF/dx x - (dF/dx')^-1 dF/du u.
    let m = j.f_xdot.lu();
    let a = m.solve(&(-j.f_x)).unwrap();
    let b = m.solve(&(-j.f_u)).unwrap();
    let a_paper = dpc::nalgebra::SMatrix::<f64, 5, 5>::from_row_slice(&[
        0.0, 0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, 1.0, //
        0.0, 0.0, 0.0, -3.0, 0.0, //
        6.54, 0.0, 5.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    assert!((a - a_paper).amax() < 1e-12, "A = {a}");
    let b_appendix = dpc::nalgebra::SMatrix::<f64, 5, 2>::from_row_slice(&[
        0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.8,
    ]);
    assert!((b - b_appendix).amax() < 1e-12, "B = {b}");
}
