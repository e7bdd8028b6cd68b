//! The tracking DAE of stabilised Hirschorn steps (paper, Section 2, (2.1)).
//!
//! `dpc::model!` with a `tracking` section generates a second type: the DAE
//! `G(X', X, Z, U, t) = 0` made of the plant equations and, per output `i`,
//! `W_i(d/dt) h_i(X, t) - w_i = 0`, with the unknowns `(X, [Z; U])` (the plant's inputs are
//! algebraic unknowns) and the inputs `w_i = W_i(d/dt) xi_i(t)`. This module holds the trait
//! it implements on top of [`DaeModel`] and the computation of `w` from a [`Reference`].

use crate::model::DaeModel;
use crate::reference::{Reference, ReferenceError};

/// A tracking DAE generated from a model's `tracking` section.
pub trait TrackingDae: DaeModel {
    /// The plant the tracking DAE was generated from.
    type Plant: DaeModel<Params = Self::Params>;

    /// Per output, the coefficients of `W_i(s)`, lowest power first (monic: the last is 1).
    /// An output without a step has `[1.0]`.
    const W_COEFFICIENTS: &'static [&'static [f64]];

    /// Per output, the relative degree of the plant output: the number of total time
    /// derivatives after which an input appears, or `None` where it is not defined (an
    /// output the inputs never reach, or a structurally higher-index plant).
    const RELATIVE_DEGREES: &'static [Option<usize>];

    /// Number of plant inputs: the trailing algebraic unknowns of the tracking DAE.
    fn plant_inputs() -> usize {
        Self::N_ALGEBRAIC - <Self::Plant as DaeModel>::N_ALGEBRAIC
    }

    /// Per output, how many derivatives of the reference `w_i` needs (`deg W_i`).
    fn reference_orders() -> impl Iterator<Item = usize> {
        Self::W_COEFFICIENTS.iter().map(|c| c.len() - 1)
    }

    /// The largest relative degree left after the steps, `max_i (r_i - deg W_i)`: the
    /// nilpotency index `nu` of the linearised pencil, which decides how many implicit-Euler
    /// controls are unusable after a restart (paper, Section 3). `None` if some relative
    /// degree is undefined.
    fn remaining_relative_degree() -> Option<usize> {
        let mut nu = 0;
        for (r, w) in Self::RELATIVE_DEGREES.iter().zip(Self::W_COEFFICIENTS) {
            nu = nu.max(r.as_ref()?.saturating_sub(w.len() - 1));
        }
        Some(nu)
    }

    /// The tracking inputs `w_i = sum_k c_ik xi_i^(k)(t)` from a reference, using `scratch`
    /// of length at least `(max_order + 1) * N_OUTPUTS` for the derivatives.
    fn tracking_inputs<R: Reference + ?Sized>(
        reference: &R,
        t: f64,
        scratch: &mut [f64],
        w: &mut [f64],
    ) -> Result<(), ReferenceError> {
        let m = Self::N_OUTPUTS;
        if reference.dimension() != m {
            return Err(ReferenceError::Dimension {
                expected: m,
                found: reference.dimension(),
            });
        }
        let order = Self::reference_orders().max().unwrap_or(0);
        if order > reference.max_order() {
            return Err(ReferenceError::OrderTooHigh {
                name: "reference".into(),
                max: reference.max_order(),
                requested: order,
            });
        }
        let len = (order + 1) * m;
        if scratch.len() < len || w.len() != m {
            return Err(ReferenceError::BufferLength {
                expected: len,
                found: scratch.len().min(w.len()),
            });
        }
        let derivs = &mut scratch[..len];
        reference.derivatives(t, order, derivs)?;
        for (i, (wi, coeffs)) in w.iter_mut().zip(Self::W_COEFFICIENTS).enumerate() {
            *wi = coeffs
                .iter()
                .enumerate()
                .map(|(k, c)| c * derivs[k * m + i])
                .sum();
        }
        Ok(())
    }
}
