//! Linearisation of a generated model about an operating point, from its analytic Jacobians.
//!
//! For `F(t, x, x', z, u) = 0`, `y = h(t, x, z, u)` at a point where `[dF/dx' dF/dz]` is
//! regular (an ODE, or a DAE of index 1 in `z`), the variations satisfy
//! `[F_x' F_z] [dx'; dz] = -F_x dx - F_u du`, so
//! `dx' = A dx + B du`, `dz = Z_x dx + Z_u du`, `dy = (h_x + h_z Z_x) dx + (h_u + h_z Z_u) du`.
//! The solve uses a column-pivoted QR factorisation, and the rank decision is relative to the
//! norm of `[F_x' F_z]`; no Jacobian comes from finite differences.
//!
//! # Example
//! A cart pushed by a force `f` through a first-order actuator, written with an algebraic
//! unknown (the actuator's output `a`), linearised at rest:
//!
//! ```
//! use dpc::core::linearize::{linearize, OperatingPoint};
//!
//! dpc::model! {
//!     /// A cart of mass `m`, accelerated by `a`, the lagged force.
//!     Cart {
//!         params { m = 2.0, tau = 0.1 }
//!         states { p, v, f }
//!         algebraic { a }
//!         inputs { u }
//!         equations {
//!             der(p) = v;
//!             der(v) = a;
//!             tau * der(f) == u - f;
//!             m * a == f;
//!         }
//!         outputs { p }
//!     }
//! }
//!
//! let point = OperatingPoint { t: 0.0, x: &[0.0; 3], xdot: &[0.0; 3], z: &[0.0], u: &[0.0] };
//! let sys = linearize(&Cart::default(), point)?;
//! // The algebraic unknown is eliminated: dv' = f / m, df' = (u - f) / tau.
//! assert!((sys.a[(1, 2)] - 0.5).abs() < 1e-15 && (sys.a[(2, 2)] + 10.0).abs() < 1e-14);
//! assert!((sys.b[(2, 0)] - 10.0).abs() < 1e-14);
//! assert_eq!(sys.c.as_slice(), &[1.0, 0.0, 0.0]);
//! # Ok::<(), dpc::core::linearize::LinearizeError>(())
//! ```

use crate::linear_analysis::LinearSystem;
use crate::model::{DaeModel, Structure};
use nalgebra::DMatrix;
use thiserror::Error;

/// Errors of [`linearize`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LinearizeError {
    /// A point vector has the wrong length.
    #[error("{what} has length {found}, expected {expected}")]
    Dimension {
        /// Which vector.
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// `[dF/dx' dF/dz]` is singular at the point: the model is not an ODE or index-1 DAE
    /// there, so no state-space linearisation `x' = A x + B u` exists.
    #[error("[dF/dx' dF/dz] is singular at the point (rank {rank} of {n}, tolerance {tolerance:e}): the plant is not of index 1 there; a constrained plant of index 2 or 3 is linearised by `linear::descriptor::linearize_descriptor`")]
    Singular {
        /// Numerical rank found.
        rank: usize,
        /// Size of the matrix.
        n: usize,
        /// Rank tolerance used.
        tolerance: f64,
    },
    /// The model produced a non-finite Jacobian entry at the point.
    #[error("non-finite Jacobian entry at the linearisation point")]
    NonFinite,
    /// The linear system could not be formed (for example outputs and inputs differ in
    /// number).
    #[error(transparent)]
    System(#[from] crate::linear_analysis::LinearError),
}

/// A point `(t, x, x', z, u)` of a model.
#[derive(Debug, Clone, Copy)]
pub struct OperatingPoint<'a> {
    /// Time.
    pub t: f64,
    /// States.
    pub x: &'a [f64],
    /// State derivatives (along a nominal trajectory; zeros at an equilibrium).
    pub xdot: &'a [f64],
    /// Algebraic unknowns.
    pub z: &'a [f64],
    /// Inputs.
    pub u: &'a [f64],
}

/// The residual and every Jacobian block of a model at one [`OperatingPoint`]: what the
/// state-space linearisation ([`linearize`]) and the descriptor linearisation
/// ([`crate::linear_analysis::descriptor::descriptor_system`]) are built from.
#[derive(Debug, Clone, PartialEq)]
pub struct Jacobians {
    /// `F` at the point (checked by the callers that need it to vanish).
    pub residual: Vec<f64>,
    /// `dF/dx'`.
    pub f_xdot: DMatrix<f64>,
    /// `dF/dx`.
    pub f_x: DMatrix<f64>,
    /// `dF/dz`.
    pub f_z: DMatrix<f64>,
    /// `dF/du`.
    pub f_u: DMatrix<f64>,
    /// `dh/dx` of the outputs.
    pub h_x: DMatrix<f64>,
    /// `dh/dz`.
    pub h_z: DMatrix<f64>,
    /// `dh/du`.
    pub h_u: DMatrix<f64>,
}

/// Why [`Jacobians::at`] could not evaluate a model.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PointError {
    /// A point vector has the wrong length.
    #[error("{what} has length {found}, expected {expected}")]
    Dimension {
        /// Which vector (`x`, `x'`, `z` or `u`).
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A Jacobian block has a NaN or infinite entry.
    #[error("non-finite entry in {what} at the point")]
    NonFinite {
        /// The block (`dF/dx'`, `dF/dx`, `dF/dz`, `dF/du`, `dh/dx`, `dh/dz` or `dh/du`).
        what: &'static str,
    },
}

impl Jacobians {
    /// Evaluate `model` at `point` (the generated code's exact derivatives), after checking the
    /// lengths of the point's vectors against the model.
    ///
    /// # Errors
    /// [`PointError::Dimension`] for a vector of the wrong length,
    /// [`PointError::NonFinite`] naming the first Jacobian block with a NaN or infinite entry.
    pub fn at<M: DaeModel>(model: &M, point: OperatingPoint<'_>) -> Result<Self, PointError> {
        let structure = model.structure();
        let (nx, nz, nu, ny, ne) = (
            structure.n_states(),
            structure.n_algebraic(),
            structure.n_inputs(),
            structure.n_outputs(),
            structure.n_equations(),
        );
        for (what, v, n) in [
            ("x", point.x, nx),
            ("x'", point.xdot, nx),
            ("z", point.z, nz),
            ("u", point.u, nu),
        ] {
            if v.len() != n {
                return Err(PointError::Dimension {
                    what,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        let mut j = Self {
            residual: vec![0.0; ne],
            f_xdot: DMatrix::zeros(ne, nx),
            f_x: DMatrix::zeros(ne, nx),
            f_z: DMatrix::zeros(ne, nz),
            f_u: DMatrix::zeros(ne, nu),
            h_x: DMatrix::zeros(ny, nx),
            h_z: DMatrix::zeros(ny, nz),
            h_u: DMatrix::zeros(ny, nu),
        };
        model.evaluate(
            point.t,
            point.x,
            point.xdot,
            point.z,
            point.u,
            &mut j.residual,
            &mut j.f_xdot,
            &mut j.f_x,
            &mut j.f_z,
            &mut j.f_u,
        );
        model.output_jacobians(
            point.t, point.x, point.z, point.u, &mut j.h_x, &mut j.h_z, &mut j.h_u,
        );
        for (what, m) in [
            ("dF/dx'", &j.f_xdot),
            ("dF/dx", &j.f_x),
            ("dF/dz", &j.f_z),
            ("dF/du", &j.f_u),
            ("dh/dx", &j.h_x),
            ("dh/dz", &j.h_z),
            ("dh/du", &j.h_u),
        ] {
            if m.iter().any(|v| !v.is_finite()) {
                return Err(PointError::NonFinite { what });
            }
        }
        Ok(j)
    }
}

impl From<PointError> for LinearizeError {
    fn from(e: PointError) -> Self {
        match e {
            PointError::Dimension {
                what,
                expected,
                found,
            } => Self::Dimension {
                what,
                expected,
                found,
            },
            PointError::NonFinite { .. } => Self::NonFinite,
        }
    }
}

/// The state-space linearisation `(A, B, C, D)` of `model` about `point`.
///
/// # Errors
/// [`LinearizeError`] for wrong lengths, a singular `[dF/dx' dF/dz]`, non-finite Jacobians,
/// and a non-square result (as many outputs as inputs are required for DPC).
pub fn linearize<M: DaeModel>(
    model: &M,
    point: OperatingPoint<'_>,
) -> Result<LinearSystem, LinearizeError> {
    let jacobians = Jacobians::at(model, point)?;
    linearize_jacobians(model.structure(), jacobians)
}

/// [`linearize`] from the Jacobians of a model with the structure `structure`: compiled once
/// in this crate, not once per model in every crate that linearises one.
fn linearize_jacobians(
    structure: &Structure,
    jacobians: Jacobians,
) -> Result<LinearSystem, LinearizeError> {
    let (nx, nz, nu, ne) = (
        structure.n_states(),
        structure.n_algebraic(),
        structure.n_inputs(),
        structure.n_equations(),
    );
    let Jacobians {
        f_xdot,
        f_x,
        f_z,
        f_u,
        h_x,
        h_z,
        h_u,
        ..
    } = jacobians;
    // [F_x' F_z] [dx'; dz] = -[F_x F_u] [dx; du].
    let mut lhs = DMatrix::zeros(ne, nx + nz);
    lhs.columns_mut(0, nx).copy_from(&f_xdot);
    lhs.columns_mut(nx, nz).copy_from(&f_z);
    let mut rhs = DMatrix::zeros(ne, nx + nu);
    rhs.columns_mut(0, nx).copy_from(&(-&f_x));
    rhs.columns_mut(nx, nu).copy_from(&(-&f_u));
    let qr = lhs.clone().col_piv_qr();
    let rdiag = qr.r().diagonal();
    let tolerance = (ne.max(1) as f64) * f64::EPSILON * 100.0 * lhs.amax().max(f64::MIN_POSITIVE);
    let rank = rdiag.iter().filter(|v| v.abs() > tolerance).count();
    if rank < ne {
        return Err(LinearizeError::Singular {
            rank,
            n: ne,
            tolerance,
        });
    }
    let sol = qr.solve(&rhs).ok_or(LinearizeError::Singular {
        rank,
        n: ne,
        tolerance,
    })?;
    let a = sol.view((0, 0), (nx, nx)).into_owned();
    let b = sol.view((0, nx), (nx, nu)).into_owned();
    let z_x = sol.view((nx, 0), (nz, nx)).into_owned();
    let z_u = sol.view((nx, nx), (nz, nu)).into_owned();
    let c = &h_x + &h_z * z_x;
    let d = &h_u + &h_z * z_u;
    Ok(LinearSystem::new(a, b, c, d)?)
}
