//! BDF integration of implicit DAEs `F(t, y, y') = 0` of index up to 3.
//!
//! * [`Bdf`]: variable-step, variable-order (1-5) BDF in the fixed-leading-coefficient,
//!   modified-divided-difference form of DASSL and IDA (Brenan, Campbell & Petzold,
//!   *Numerical Solution of Initial-Value Problems in Differential-Algebraic Equations*,
//!   1989, ch. 5; Hindmarsh et al., *SUNDIALS: Suite of nonlinear and differential/algebraic
//!   equation solvers*, ACM TOMS 31, 2005): predictor from the divided-difference history,
//!   modified Newton on `dF/dy + (alpha/h) dF/dy'` with reuse of the factorisation across
//!   steps, convergence-rate test, local error test in a weighted RMS norm with relative and
//!   absolute tolerances, rejection and retry, IDA's order selection, dense output.
//! * [`FixedBdf`]: constant step and order, starting from possibly inconsistent values, for the
//!   DPC inner integration.
//! * [`consistent_initial_values`]: given the differential components, compute the algebraic
//!   components and `y'` (the idea of IDA's `IDACalcIC` with `IDA_YA_YDP_INIT`).
//!
//! Index-2 and index-3 components, marked in [`Options::index`], are excluded from the local
//! error test by default ([`HigherIndexControl::Exclude`], as DASSL and IDA's `suppressalg`),
//! or have their weight scaled by `h^(m-1)` ([`HigherIndexControl::Scale`]).
//!
//! The linear algebra is chosen by type through [`crate::linalg::LinearSolver`].

mod dense;
mod error;
mod fixed;
mod init;
mod newton;
mod options;
mod stats;
mod variable;

pub use error::BdfError;
pub use fixed::FixedBdf;
pub use init::{consistent_initial_values, InitWorkspace};
pub use options::{HigherIndexControl, Options, Tolerance};
pub use stats::Stats;
pub use variable::Bdf;
