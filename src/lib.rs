#![doc = include_str!("../README.md")]
//!
//! ---
//!
//! The facade crate re-exports [`model!`], the numerical library [`core`] (`dpc-core`), and
//! [`nalgebra`], so generated code and users name the same fixed-size types.

// Generated code names `::dpc::...` paths; inside this crate they resolve to itself.
extern crate self as dpc;

#[cfg(feature = "cli")]
pub mod cli;
pub use dpc_core as core;
pub use dpc_macros::model;
pub use dpc_runtime as runtime;
pub use nalgebra;
