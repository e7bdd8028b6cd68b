//! Linear DPC analysis (paper, Section 3): for a square system `x' = Ax + Bu, y = Cx + Du`,
//! optionally partially stabilised by `W_i(d/dt)`, compute the limit `h -> 0` of DPC,
//! `u = K_J x + R_xi(d/dt) xi` (3.10), decide whether it is stable (Theorem 3.2), and build the
//! preliminary feedback `K_n = [0 K_2] Q^-1` when it is not (Section 3.1).
//!
//! One concept per file:
//! * [`system`]: [`LinearSystem`] and the partial stabilisation by `W_i(s)`;
//! * [`compress`]: row compression `V` of `[B; D]` and the pencil data `E, F, H, J`;
//! * [`pencil`]: regularity and Weierstrass split (`M`, `Q`, `A_1`, `N`, `nu`) by Wong sequences;
//! * [`vstar`]: the largest output-nulling controlled-invariant subspace;
//! * [`zeros`]: transmission zeros;
//! * [`place`]: multi-input pole placement (Luenberger controller form);
//! * [`transfer`]: `H(s)`, `R_xi(s)`, the check of Theorem 3.3;
//! * [`sampled`]: the limit law held by a zero-order hold: stability against the period `h`;
//! * [`analysis`]: the report and the whole pipeline;
//! * [`descriptor`]: linearised descriptor plants (index up to 3) realised on their constraint
//!   manifold, the input of [`analyze`] for constrained plants.
//!
//! ```
//! use dpc_core::linear_analysis::{analyze, AnalysisOptions, LinearSystem};
//! use nalgebra::DMatrix;
//! // x1' = x2, x2' = u, y = x1, stabilised by W = s + 2.
//! let sys = LinearSystem::without_feedthrough(
//!     DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]),
//!     DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
//!     DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
//! )
//! .unwrap();
//! let opts = AnalysisOptions { w: Some(vec![vec![2.0]]), ..Default::default() };
//! let report = analyze(&sys, &opts).unwrap();
//! assert_eq!(report.nu, 1);
//! assert!((report.transmission_zeros[0].re + 2.0).abs() < 1e-9); // the root of W
//! // Plain DPC has eig(Abar_4) = {2}: unstable; the preliminary feedback fixes it.
//! assert!(!report.dpc_stable);
//! assert_eq!(report.dpc_stable_prefeedback, Some(true));
//! ```

pub mod analysis;
pub mod compress;
pub mod descriptor;
mod error;
pub mod pencil;
pub mod place;
pub mod sampled;
pub mod serial;
pub mod subspace;
pub mod system;
pub mod transfer;
pub mod vstar;
pub mod zeros;

pub use analysis::{
    analyze, dpc_law, Analysis, AnalysisOptions, DpcLaw, PrefeedbackPolicy, Tolerances,
};
pub use error::LinearError;
pub use subspace::eigenvalues;
pub use system::LinearSystem;
