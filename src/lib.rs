//! # dpc — Descriptor Predictive Control
//!
//! The facade crate users depend on. It re-exports
//!
//! * [`model!`], the procedural macro that compiles a plant declared in the DSL into
//!   residuals, analytic Jacobians and (with a `tracking` block) the stabilised Hirschorn
//!   tracking DAE;
//! * [`core`], the numerical library: traits implemented by generated code, the BDF
//!   integrator, the linear DPC analysis and the controller;
//! * [`nalgebra`], so generated code and users name the same fixed-size types.
//!
//! See the repository README for the DSL reference and a complete example.

pub use dpc_core as core;
pub use dpc_macros::model;
pub use nalgebra;
