//! Numerical core of dpc.
//!
//! Modules follow the data flow of the method (paper, Sections 2-3):
//!
//! * [`sink`]: where generated code writes Jacobian entries (dense nalgebra, faer, sparse);
//! * [`model`]: the trait that `dpc::model!` implements for every declared plant
//!   (residual `F(t, x, x', z, u)`, its Jacobians, outputs `h(t, x)`), and the adapter
//!   that turns a model with given inputs into an [`dae::ImplicitDae`];
//! * [`dae`]: the implicit DAE `F(t, y, y') = 0` interface the integrator consumes;
//! * [`linear`]: the linear DPC analysis of Section 3 (pencil split, `K_J`, `R_xi`, `Abar_4`,
//!   verdict, preliminary feedback `K_n`).

pub mod dae;
pub mod linear;
pub mod model;
pub mod sink;

pub use dae::ImplicitDae;
pub use model::{DaeModel, ModelDae};
pub use sink::MatrixSink;
