//! Numerical core of dpc.
//!
//! Modules follow the data flow of the method (paper, Sections 2-3):
//!
//! * [`sink`]: where generated code writes Jacobian entries (dense nalgebra, faer, sparse);
//! * [`model`]: the trait that `dpc::model!` implements for every declared plant
//!   (residual `F(t, x, x', z, u)`, its Jacobians, outputs `h(t, x)`, and its
//!   [`Structure`]: names, dimensions, sparsity);
//! * [`dae`]: the implicit DAE `F(t, y, y') = 0` interface the integrator consumes;
//! * [`dpc`]: one sampled update of the Descriptor Predictive Controller;
//! * [`bdf`]: the variable-step variable-order BDF integrator and its fixed-step mode;
//! * [`radau`]: the Radau IIA integrator (order 5) for DAEs of index up to 3 as declared;
//! * [`linalg`]: the linear solvers behind the integrator's Newton iteration;
//! * [`linear`]: the linear DPC analysis of Section 3 (pencil split, `K_J`, `R_xi`, `Abar_4`,
//!   verdict, preliminary feedback `K_n`);
//! * [`linearize`]: state-space linearisation of a generated model from its Jacobians;
//! * [`numeric`]: floating-point helpers (a maximum that keeps NaN);
//! * [`reference`](mod@reference): reference trajectories with exact derivatives;
//! * [`tracking`]: the tracking DAE of stabilised Hirschorn steps generated from a model;
//! * [`simulate`]: the sampled closed loop, with the plant integrated accurately between samples.

pub mod bdf;
pub mod dae;
pub mod dpc;
pub mod linalg;
pub mod linear;
pub mod linearize;
pub mod model;
pub mod numeric;
pub mod radau;
pub mod reference;
pub mod simulate;
pub mod sink;
pub mod tracking;

pub use dae::ImplicitDae;
pub use model::{DaeModel, Structure};
pub use reference::Reference;
pub use sink::MatrixSink;
pub use tracking::TrackingDae;
