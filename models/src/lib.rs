//! Plants declared with `dpc::model!`.
//!
//! * [`Wheel`]: the paper's nonlinear wheel (Appendix), and [`WheelLinear`], its
//!   linearisation (4.1);
//! * [`Pendulum`]: the planar pendulum in Cartesian coordinates with a Lagrange multiplier
//!   (index 3);
//! * [`FlexibleJoint`]: a flexible-joint robot arm of relative degree 4, with two
//!   stabilised Hirschorn steps in [`FlexibleJointTracking`].
//!
//! [`wheel_design`] holds the paper's nominal motion, linear analysis and preliminary feedback
//! for the wheel.
//!
//! The `dpc` command line finds them by name through the registry in `dpc-cli`'s binary.
//!
//! The source files are also read by the snapshot tests of `dpc-codegen`, which store the
//! code the macro generates for each of them.

mod flexible_joint;
mod pendulum;
mod wheel;
pub mod wheel_design;

pub use flexible_joint::{
    FlexibleJoint, FlexibleJointParams, FlexibleJointReference, FlexibleJointTracking,
};
pub use pendulum::{Pendulum, PendulumParams};
pub use wheel::{
    Wheel, WheelLinear, WheelLinearParams, WheelLinearTracking, WheelParams, WheelReference,
    WheelTracking,
};
