//! Numerical core of dpc.
//!
//! Modules follow the data flow of the method (paper, Sections 2-3):
//!
//! * [`sink`]: where generated code writes Jacobian entries (dense nalgebra, faer, sparse);
//! * [`model`]: the trait that `dpc::model!` implements for every declared plant
//!   (residual `F(t, x, x', z, u)`, its Jacobians, outputs `h(t, x)`, and its
//!   [`Structure`]: names, dimensions, sparsity);
//! * [`consistent`]: consistent initial values of index-2/3 plants from given states;
//! * [`dae`]: the implicit DAE `F(t, y, y') = 0` interface the integrator consumes;
//! * [`difference`]: its iteration matrix by difference quotients of the residual, for a
//!   hand-written DAE without a Jacobian (grouped by the DAE's pattern);
//! * [`design`]: the design chain of a preliminary feedback (trim, linearise, analyse, `K_n`)
//!   and the check of the relative degrees at the nominal;
//! * [`error`]: errors shared by the layers (an option out of range);
//! * [`controller`]: one sampled update of the Descriptor Predictive Controller;
//! * [`bdf`]: the variable-step variable-order BDF integrator and its fixed-step mode;
//! * [`radau`]: the Radau IIA integrator (order 5) for DAEs of index up to 3 as declared;
//! * [`linear_solver`]: the linear solvers behind the integrator's Newton iteration;
//! * [`linear_analysis`]: the linear DPC analysis of Section 3 (pencil split, `K_J`, `R_xi`, `Abar_4`,
//!   verdict, preliminary feedback `K_n`);
//! * [`linearize`]: state-space linearisation of a generated model from its Jacobians;
//! * [`numeric`]: floating-point helpers (a maximum that keeps NaN);
//! * [`prefeedback`]: the preliminary feedback law and the nominal motions it acts about;
//! * [`reference`](mod@reference): reference trajectories with exact derivatives;
//! * [`tracking`]: the tracking DAE of stabilised Hirschorn steps generated from a model;
//! * [`stabilised`]: the index-2 (GGL) stabilised form of an index-3 mechanical DAE;
//! * [`simulate`]: the sampled closed loop, with the plant integrated accurately between samples.
#![warn(missing_docs)]

pub mod bdf;
pub mod consistent;
pub mod controller;
pub mod dae;
pub mod design;
pub mod difference;
pub mod error;
pub mod index_estimate;
pub mod linear_analysis;
pub mod linear_solver;
pub mod linearize;
pub mod model;
mod newton;
pub mod numeric;
pub mod prefeedback;
pub mod radau;
pub mod reference;
pub mod simulate;
pub mod sink;
pub mod stabilised;
pub mod tracking;

pub use dae::ImplicitDae;
pub use difference::DifferenceQuotients;
pub use error::InvalidOption;
pub use model::{DaeModel, Structure};
pub use reference::Reference;
pub use sink::MatrixSink;
pub use tracking::TrackingDae;
