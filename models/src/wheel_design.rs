//! The paper's design for the wheel (Sections 4 and 5): the nominal motion
//! `x0(t) = [pi/2, -6t, 0, 0, -6]`, `u0 = 0` (upright, rolling at a constant heading rate),
//! the linear DPC analysis with `W = s + 5` on both outputs, and the preliminary feedback with
//! the poles of `Abar_4 + Bbar_2 K_2` at -5, all through the design chain of
//! [`dpc::core::design`].
//!
//! Along this motion the linearisation does not depend on `t` (`psi` does not enter the
//! equations), so one linearisation at `t = 0` serves the whole trajectory.

use std::f64::consts::FRAC_PI_2;

use dpc::core::design::{self, Design, DesignError, DesignOptions};
use dpc::core::linear_analysis::AnalysisOptions;
use dpc::core::prefeedback::{
    NominalError, Prefeedback, ReferenceNominal, ReferenceState, SteadyMotion,
};
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
pub fn nominal() -> SteadyMotion {
    SteadyMotion {
        state: NOMINAL_STATE.to_vec(),
        rate: NOMINAL_RATE.to_vec(),
        algebraic: Vec::new(),
        input: vec![0.0, 0.0],
    }
}

/// The paper's design options: `W = s + 5` on both outputs, the three poles at -5.
pub fn options() -> DesignOptions {
    DesignOptions {
        analysis: AnalysisOptions {
            w: Some(W_ROOTS.iter().map(|a| vec![*a]).collect()),
            poles: Some(vec![Complex::new(POLE, 0.0); 3]),
            ..AnalysisOptions::default()
        },
        horizon: 0.0,
        relative_degrees: Vec::new(),
    }
}

/// The linearisation of `wheel` about the nominal motion, and its analysis.
///
/// # Errors
/// [`DesignError`] when the linearisation or the analysis fails.
pub fn design(wheel: &Wheel) -> Result<Design, DesignError> {
    design::design(wheel, &nominal(), &options())
}

/// The preliminary feedback `u = K_n (x - x0(t)) + v` of the paper's design for `wheel`,
/// about the nominal motion.
///
/// # Errors
/// [`DesignError`] when the design fails.
pub fn prefeedback(wheel: &Wheel) -> Result<Prefeedback, DesignError> {
    design(wheel)?.prefeedback()
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
/// [`NominalError`] when the reference has fewer than two components or no first
/// derivative.
pub fn about_reference<R: Reference>(
    reference: R,
) -> Result<ReferenceNominal<SteadyMotion, R>, NominalError> {
    ReferenceNominal::new(nominal(), reference, 5, reference_states())
}

#[cfg(test)]
mod tests {
    use super::*;
    use dpc::core::design::{trim, TrimOptions, TrimProblem, TrimValue};
    use dpc::core::DaeModel;

    #[test]
    fn the_design_reproduces_the_papers_verdict() {
        let d = design(&Wheel::default()).unwrap();
        assert!(!d.analysis.dpc_stable);
        assert_eq!(d.analysis.dpc_stable_prefeedback, Some(true));
        assert_eq!(d.motion.state_at(2.0), [FRAC_PI_2, -12.0, 0.0, 0.0, -6.0]);
    }

    /// Upright at a heading rate of -6 with no torque: the trim solver finds the spin rate
    /// and the heading's rate that the paper's nominal gives by hand.
    #[test]
    fn the_trim_solver_finds_the_nominal_from_a_partial_specification() {
        let wheel = Wheel::default();
        let s = wheel.structure();
        let mut p = TrimProblem::equilibrium(s);
        for (name, v) in [
            ("theta", TrimValue::Fixed(FRAC_PI_2)),
            ("psi", TrimValue::Fixed(0.0)),
            ("dtheta", TrimValue::Fixed(0.0)),
            ("dpsi", TrimValue::Fixed(-6.0)),
            ("dphi", TrimValue::Free(0.7)),
            ("der(psi)", TrimValue::Free(1.0)),
            ("u1", TrimValue::Fixed(0.0)),
            ("u2", TrimValue::Fixed(0.0)),
        ] {
            p.set(s, name, v).unwrap();
        }
        p.horizon = Some(400.0);
        let t = trim(&wheel, &p, &TrimOptions::default()).unwrap();
        let n = nominal();
        for (a, b) in t.motion.state.iter().zip(&n.state) {
            assert!((a - b).abs() < 1e-12, "{:?}", t.motion);
        }
        for (a, b) in t.motion.rate.iter().zip(&n.rate) {
            assert!((a - b).abs() < 1e-12, "{:?}", t.motion);
        }
        assert_eq!((t.unknowns, t.rank, t.free_directions()), (2, 2, 0));
    }

    /// A lean rate cannot be steady: `der(theta) = dtheta` with both fixed apart is
    /// inconsistent, and the message names the equation.
    #[test]
    fn an_inconsistent_trim_names_the_equation() {
        let wheel = Wheel::default();
        let s = wheel.structure();
        let mut p = TrimProblem::equilibrium(s);
        p.set(s, "dtheta", TrimValue::Fixed(1.0)).unwrap();
        p.set(s, "theta", TrimValue::Fixed(FRAC_PI_2)).unwrap();
        let err = trim(&wheel, &p, &TrimOptions::default()).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("der(theta) = dtheta"), "{msg}");
        assert!(msg.contains("unsatisfiable"), "{msg}");
        let err = p.set(s, "speed", TrimValue::Fixed(1.0)).unwrap_err();
        assert!(err.to_string().contains("no variable `speed`"), "{err}");
    }
}
