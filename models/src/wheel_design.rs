//! The paper's design for the wheel (Sections 4 and 5): the nominal motion
//! `x0(t) = [pi/2, -6t, 0, 0, -6]`, `u0 = 0` (upright, rolling at a constant heading rate),
//! the linearisation of [`Wheel`] about it from the generated Jacobians, the linear DPC
//! analysis with `W = s + 5` on both outputs, and the preliminary feedback with the poles of
//! `Abar_4 + Bbar_2 K_2` at -5.
//!
//! Along this motion the linearisation does not depend on `t` (`psi` does not enter the
//! equations), so one linearisation at `t = 0` serves the whole trajectory.

use std::f64::consts::FRAC_PI_2;

use dpc::core::dpc::{Nominal, Prefeedback, ReferenceNominal, ReferenceState};
use dpc::core::linear::{analyze, Analysis, AnalysisOptions, LinearError, LinearSystem};
use dpc::core::linearize::{linearize, LinearizeError, OperatingPoint};
use dpc::core::reference::Reference;
use dpc::nalgebra::Complex;

use crate::Wheel;

/// `x0(0)` of the nominal motion.
pub const NOMINAL_STATE: [f64; 5] = [FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];
/// `x0'` of the nominal motion (constant).
pub const NOMINAL_RATE: [f64; 5] = [0.0, -6.0, 0.0, 0.0, 0.0];
/// The roots `a` of `W(s) = s + a` on `theta` and `psi`.
pub const W_ROOTS: [f64; 2] = [5.0, 5.0];
/// The poles of `Abar_4 + Bbar_2 K_2`.
pub const POLE: f64 = -5.0;

/// The nominal motion `x0(t) = [pi/2, -6t, 0, 0, -6]`, `u0 = 0`.
#[derive(Debug, Clone, Copy, Default)]
pub struct UprightRolling;

impl Nominal for UprightRolling {
    fn state(&self, t: f64, x0: &mut [f64]) {
        for ((x, s), r) in x0.iter_mut().zip(&NOMINAL_STATE).zip(&NOMINAL_RATE) {
            *x = s + t * r;
        }
    }

    fn input(&self, _t: f64, u0: &mut [f64]) {
        u0.fill(0.0);
    }
}

/// Why the design could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DesignError {
    /// The linearisation failed.
    #[error("linearisation of the wheel: {0}")]
    Linearize(#[from] LinearizeError),
    /// The linear analysis failed.
    #[error("linear analysis of the wheel: {0}")]
    Analysis(#[from] LinearError),
    /// The reference does not fit the map of [`reference_states`].
    #[error("reference of the preliminary feedback: {0}")]
    Reference(String),
    /// The analysis built no `K_n`.
    #[error("the linear analysis built no preliminary feedback: {0}")]
    NoPrefeedback(String),
}

/// The linearisation of `wheel` about the nominal motion, and its analysis.
///
/// # Errors
/// [`DesignError`] when the linearisation or the analysis fails.
pub fn design(wheel: &Wheel) -> Result<(LinearSystem, Analysis), DesignError> {
    let sys = linearize(
        wheel,
        OperatingPoint {
            t: 0.0,
            x: &NOMINAL_STATE,
            xdot: &NOMINAL_RATE,
            z: &[],
            u: &[0.0, 0.0],
        },
    )?;
    let analysis = analyze(
        &sys,
        &AnalysisOptions {
            w: Some(W_ROOTS.iter().map(|a| vec![*a]).collect()),
            poles: Some(vec![Complex::new(POLE, 0.0); 3]),
            ..AnalysisOptions::default()
        },
    )?;
    Ok((sys, analysis))
}

/// The preliminary feedback `u = K_n (x - x0(t)) + v` of the paper's design for `wheel`,
/// about the nominal motion.
///
/// # Errors
/// [`DesignError`] when the design fails.
pub fn prefeedback(wheel: &Wheel) -> Result<Prefeedback, DesignError> {
    let (_, analysis) = design(wheel)?;
    let k_n = analysis.k_n.ok_or_else(|| {
        DesignError::NoPrefeedback(analysis.prefeedback_error.unwrap_or_default())
    })?;
    Ok(Prefeedback {
        k_n,
        nominal: Box::new(UprightRolling),
    })
}

/// The states that follow the reference when the feedback is taken about it:
/// `theta, psi <- theta_ref, psi_ref` and `dtheta, dpsi <- theta_ref', psi_ref'`.
pub fn reference_states() -> Vec<ReferenceState> {
    let follow = |state, output, order| ReferenceState {
        state,
        output,
        order,
    };
    vec![
        follow(0, 0, 0),
        follow(1, 1, 0),
        follow(3, 0, 1),
        follow(4, 1, 1),
    ]
}

/// The nominal motion with [`reference_states`] following `reference` (the wheel's
/// `theta` and `psi` references, e.g. [`crate::WheelReference`]).
///
/// # Errors
/// [`DesignError::Reference`] when the reference has fewer than two components or no first
/// derivative.
pub fn about_reference<R: Reference>(
    reference: R,
) -> Result<ReferenceNominal<UprightRolling, R>, DesignError> {
    ReferenceNominal::new(UprightRolling, reference, 5, reference_states())
        .map_err(|e| DesignError::Reference(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_design_reproduces_the_papers_verdict() {
        let (_, a) = design(&Wheel::default()).unwrap();
        assert!(!a.dpc_stable);
        assert_eq!(a.dpc_stable_prefeedback, Some(true));
        let mut x0 = [0.0; 5];
        UprightRolling.state(2.0, &mut x0);
        assert_eq!(x0, [FRAC_PI_2, -12.0, 0.0, 0.0, -6.0]);
    }
}
