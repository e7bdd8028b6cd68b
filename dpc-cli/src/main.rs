//! The `dpc` command line for the models of this repository (`dpc-models`): the registry of
//! their entries, handed to the library's entry point [`dpc::cli::main`]. A crate with its own
//! plants writes the same few lines with its own entries.

use std::process::ExitCode;

use dpc::cli::registry::{Entry, Registry};
use dpc::core::linear_solver::NalgebraLu;
use dpc_models::{
    Arm2, Arm2Reference, Arm2Tracking, Arm6, Arm6Reference, Arm6Tracking, CartPendulum,
    CartPendulumJoint, CartPendulumJointReference, CartPendulumJointTracking,
    CartPendulumReference, CartPendulumTracking, FlexibleJoint, FlexibleJointReference,
    FlexibleJointTracking, SliderCrank, SliderCrankJoint, SliderCrankJointReference,
    SliderCrankJointTracking, SliderCrankReference, SliderCrankTracking, Wheel, WheelLinear,
    WheelLinearParams, WheelLinearTracking, WheelReference, WheelTracking,
};

/// The repository's tracked models, in the order `dpc models` lists them.
fn registry() -> Registry {
    // The linearised wheel with the Appendix input gains.
    let linear = WheelLinearParams {
        b1: 2.0,
        b2: 0.8,
        ..WheelLinearParams::default()
    };
    Registry::new()
        .model(
            Entry::new(
                "wheel",
                "the paper's nonlinear rolling wheel (Appendix); outputs theta, psi; W = s + 5 on both",
                Wheel::default(),
                WheelTracking::default(),
            )
            .reference(WheelReference::default())
            .listing(WheelTracking::LISTING)
            .solver(NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "wheel-linear",
                "the wheel linearised about x0(t) = [pi/2, -6t, 0, 0, -6] ((4.1) with the Appendix input gains 2, 0.8); no built-in reference",
                WheelLinear::new(linear),
                WheelLinearTracking::new(linear),
            )
            .listing(WheelLinearTracking::LISTING)
            .solver(NalgebraLu::<{ WheelLinearTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "flexible-joint",
                "a flexible-joint robot arm of relative degree 4; output q_link; W = (s + 2)(s + 3)",
                FlexibleJoint::default(),
                FlexibleJointTracking::default(),
            )
            .reference(FlexibleJointReference::default())
            .listing(FlexibleJointTracking::LISTING)
            .solver(NalgebraLu::<{ FlexibleJointTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "arm2",
                "a planar two-link arm with flexible joints (relative degree 4 per joint); outputs q[0], q[1]; W = (s + 4)^2 on both",
                Arm2::default(),
                Arm2Tracking::default(),
            )
            .reference(Arm2Reference::default())
            .listing(Arm2Tracking::LISTING)
            .solver(NalgebraLu::<{ Arm2Tracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "arm6",
                "a planar six-link arm with flexible joints (relative degree 4 per joint); outputs q[0] .. q[5]; W = (s + 4)^2 on each",
                Arm6::default(),
                Arm6Tracking::default(),
            )
            .reference(Arm6Reference::default())
            .listing(Arm6Tracking::LISTING)
            .solver(NalgebraLu::<{ Arm6Tracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "crane",
                "a load on a rigid rope under a cart, in Cartesian coordinates with the rope multiplier (index 3); output cart; W = s + 2",
                CartPendulum::default(),
                CartPendulumTracking::default(),
            )
            .reference(CartPendulumReference::default())
            .listing(CartPendulumTracking::LISTING)
            .solver(NalgebraLu::<{ CartPendulumTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "crane-joint",
                "the crane in the cart position and the rope angle (an ODE); output cart; W = s + 2",
                CartPendulumJoint::default(),
                CartPendulumJointTracking::default(),
            )
            .reference(CartPendulumJointReference::default())
            .listing(CartPendulumJointTracking::LISTING)
            .solver(NalgebraLu::<{ CartPendulumJointTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "slider-crank",
                "a slider-crank with the slider position and the rod multiplier (index 3); output angle; W = s + 4",
                SliderCrank::default(),
                SliderCrankTracking::default(),
            )
            .reference(SliderCrankReference::default())
            .listing(SliderCrankTracking::LISTING)
            .solver(NalgebraLu::<{ SliderCrankTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "slider-crank-joint",
                "the slider-crank in the crank angle alone (an ODE); output angle; W = s + 4",
                SliderCrankJoint::default(),
                SliderCrankJointTracking::default(),
            )
            .reference(SliderCrankJointReference::default())
            .listing(SliderCrankJointTracking::LISTING)
            .solver(NalgebraLu::<{ SliderCrankJointTracking::N_EQUATIONS }>::new),
        )
}

fn main() -> ExitCode {
    dpc::cli::main(registry())
}
