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
//! * [`FixedBdf`]: constant step and order, starting from possibly inconsistent values; the
//!   caller may give each step its initial guess and its convergence test ([`CorrectorTest`]),
//!   and integrate a [`FixedStepDae`] that evaluates with work space of its own. The DPC
//!   controller's inner integration runs on it (order 1, implicit Euler at the step `delta`).
//! * [`consistent_initial_values`]: given the differential components, compute the algebraic
//!   components and `y'` (the idea of IDA's `IDACalcIC` with `IDA_YA_YDP_INIT`).
//!
//! Index-2 and index-3 components, marked in [`Options::index`], are excluded from the local
//! error test by default ([`HigherIndexControl::Exclude`], as DASSL and IDA's `suppressalg`),
//! or have their weight scaled by `h^(m-1)` ([`HigherIndexControl::Scale`]).
//!
//! The linear algebra is chosen by type through [`crate::linear_solver::LinearSolver`].
//!
//! A DAE is anything that implements [`crate::ImplicitDae`] (a plant of `dpc::model!` does,
//! through its adapter; here one written by hand): the index-1 system `y0' = -y0 + y1`,
//! `0 = y1 - y0^2`, that is `y0' = y0^2 - y0`, whose solution is
//! `y0(t) = 1 / (1 + (1 / y0(0) - 1) e^t)`:
//!
//! ```
//! use dpc_core::bdf::{Bdf, Options};
//! use dpc_core::linear_solver::NalgebraLu;
//! use dpc_core::{ImplicitDae, MatrixSink};
//!
//! struct Quadratic;
//!
//! impl ImplicitDae for Quadratic {
//!     fn dimension(&self) -> usize {
//!         2
//!     }
//!     fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
//!         out[0] = yp[0] + y[0] - y[1];
//!         out[1] = y[1] - y[0] * y[0];
//!     }
//!     fn iteration_matrix<S: MatrixSink + ?Sized>(
//!         &self,
//!         _t: f64,
//!         y: &[f64],
//!         _yp: &[f64],
//!         c: f64,
//!         out: &mut S,
//!     ) {
//!         // dF/dy + c dF/dy'
//!         out.set(0, 0, 1.0 + c);
//!         out.set(0, 1, -1.0);
//!         out.set(1, 0, -2.0 * y[0]);
//!         out.set(1, 1, 1.0);
//!     }
//!     fn is_differential(&self, i: usize) -> bool {
//!         i == 0
//!     }
//! }
//!
//! let (y0, z0) = (0.5, 0.25);
//! let mut bdf = Bdf::new(
//!     Quadratic,
//!     NalgebraLu::<2>::new(),
//!     Options::with_tolerances(1e-8, 1e-10),
//!     0.0,
//!     &[y0, z0],
//!     &[z0 - y0, 0.0],
//! )?;
//! let mut y = [0.0; 2];
//! bdf.solve_to(2.0, &mut y, None)?;
//! let exact = 1.0 / (1.0 + (1.0 / y0 - 1.0) * 2.0_f64.exp());
//! assert!((y[0] - exact).abs() < 1e-6 * exact);
//! // The algebraic equation holds to the tolerance (the output at `t = 2` is interpolated).
//! assert!((y[1] - y[0] * y[0]).abs() < 1e-8);
//! assert!(bdf.stats().steps > 10);
//! # Ok::<(), dpc_core::bdf::BdfError>(())
//! ```

mod dense;
mod error;
mod fixed;
mod history;
mod init;
mod newton;
mod options;
mod stats;
mod variable;

pub use error::BdfError;
pub use fixed::{CorrectorTest, CorrectorVerdict, FixedBdf, FixedStepDae};
pub use init::{consistent_initial_values, InitWorkspace};
pub use options::{HigherIndexControl, MatrixUpdate, Options, Tolerance, DEFAULT_MAX_MATRIX_AGE};
pub use stats::Stats;
pub use variable::Bdf;
