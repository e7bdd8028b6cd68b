//! Plants declared with `dpc::model!`.
//!
//! * [`Wheel`]: the paper's nonlinear wheel (Appendix), and [`WheelLinear`], its
//!   linearisation (4.1);
//! * [`Pendulum`]: the planar pendulum in Cartesian coordinates with a Lagrange multiplier
//!   (index 3);
//! * [`FlexibleJoint`]: a flexible-joint robot arm of relative degree 4, with two
//!   stabilised Hirschorn steps in [`FlexibleJointTracking`]; [`FlexibleJointMass`],
//!   [`FlexibleJointMass3`], [`FlexibleJointMass4`]: the same plant with implicit (mass-matrix)
//!   equations and two, three and four steps, the latter two differentiating through the
//!   implicit link equation;
//! * [`CartPendulum`]: an inverted pendulum on a cart in Cartesian coordinates with a rod
//!   constraint and its multiplier (index 3), and [`CartPendulumJoint`], the same plant in
//!   joint coordinates (an ODE);
//! * [`Arm1`], [`Arm2`], [`Arm6`]: planar arms of 1, 2 and 6 links with flexible joints
//!   (Spong's model, relative degree 4 per joint), declared once for every number of links
//!   with the DSL's indexed families, with two stabilised Hirschorn steps per joint;
//! * [`SliderCrank`]: a slider-crank with the slider position, the rod constraint and its
//!   multiplier (index 3), and [`SliderCrankJoint`], the same mechanism in the crank angle.
//!
//! [`wheel_design`] holds the paper's nominal motion, linear analysis and preliminary feedback
//! for the wheel.
//!
//! The `dpc` command line finds them by name through the registry in `dpc-cli`'s binary.
//!
//! The source files are also read by the snapshot tests of `dpc-codegen`, which store the
//! code the macro generates for each of them.
#![warn(missing_docs)]

mod arm;
mod cart_pendulum;
mod flexible_joint;
mod pendulum;
mod slider_crank;
mod wheel;
pub mod wheel_design;

pub use arm::{
    Arm1, Arm1Params, Arm1Reference, Arm1Tracking, Arm2, Arm2Params, Arm2Reference, Arm2Tracking,
    Arm6, Arm6Params, Arm6Reference, Arm6Tracking,
};
pub use cart_pendulum::{
    CartPendulum, CartPendulumJoint, CartPendulumJointParams, CartPendulumJointReference,
    CartPendulumJointTracking, CartPendulumParams, CartPendulumReference, CartPendulumTracking,
};
pub use flexible_joint::{
    FlexibleJoint, FlexibleJointMass, FlexibleJointMass3, FlexibleJointMass3Params,
    FlexibleJointMass3Reference, FlexibleJointMass3Tracking, FlexibleJointMass4,
    FlexibleJointMass4Params, FlexibleJointMass4Reference, FlexibleJointMass4Tracking,
    FlexibleJointMassParams, FlexibleJointMassReference, FlexibleJointMassTracking,
    FlexibleJointParams, FlexibleJointReference, FlexibleJointTracking,
};
pub use pendulum::{Pendulum, PendulumParams};
pub use slider_crank::{
    SliderCrank, SliderCrankJoint, SliderCrankJointParams, SliderCrankJointReference,
    SliderCrankJointTracking, SliderCrankParams, SliderCrankReference, SliderCrankTracking,
};
pub use wheel::{
    Wheel, WheelLinear, WheelLinearParams, WheelLinearTracking, WheelParams, WheelReference,
    WheelTracking,
};
