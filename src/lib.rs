#![doc = include_str!(concat!(env!("OUT_DIR"), "/README.md"))]
//!
//! ---
//!
//! The facade crate re-exports [`model!`], the numerical library [`core`] (`dpc-core`), and
//! [`nalgebra`], so generated code and users name the same fixed-size types.
#![warn(missing_docs)]

// Generated code names `::dpc::...` paths; inside this crate they resolve to itself.
extern crate self as dpc;

#[cfg(feature = "cli")]
pub mod cli;
pub use dpc_core as core;
/// Declare a DAE plant: the model DSL, what it generates and its errors.
///
#[doc = include_str!(concat!(env!("OUT_DIR"), "/model.md"))]
pub use dpc_macros::model;
pub use dpc_runtime as runtime;
pub use nalgebra;

/// The guide: one page per capability, the pages of the repository's `docs/` directory
/// (every Rust snippet in them is a doctest of this crate).
pub mod guide {
    macro_rules! page {
        ($(#[$meta:meta])* $module:ident, $file:literal) => {
            $(#[$meta])*
            #[doc = include_str!(concat!(env!("OUT_DIR"), "/", $file))]
            pub mod $module {}
        };
    }
    page!(tracking, "tracking.md");
    page!(controller, "controller.md");
    page!(closed_loop, "closed_loop.md");
    page!(own_plant, "own_plant.md");
    page!(plant_files, "plant_files.md");
    page!(constrained_plants, "constrained_plants.md");
    page!(linear_analysis, "linear_analysis.md");
    page!(sampling_period, "sampling_period.md");
    page!(integrators, "integrators.md");
    page!(bdf, "bdf.md");
    page!(jacobians, "jacobians.md");
    page!(performance, "performance.md");
    page!(arms, "arms.md");
}
