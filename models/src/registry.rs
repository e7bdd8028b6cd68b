//! Lookup of the tracked models by name, for programs that choose a plant at run time (the
//! `dpc simulate` command, scenario files).
//!
//! Every model here is a compile-time type, so a lookup cannot return "a model": it calls a
//! [`VisitTracked`] visitor with the concrete plant, tracking DAE and a fixed-size linear
//! solver of the right dimension. The visitor's code is then monomorphised for each model and
//! runs as fast as hand-written code for that model.
//!
//! ```
//! use dpc::core::model::DaeModel;
//! use dpc_models::registry::{visit, Tracked, VisitTracked};
//!
//! struct StateCount;
//! impl VisitTracked for StateCount {
//!     type Output = usize;
//!     fn visit<P, T, L>(self, model: Tracked<P, T, L>) -> usize
//!     where
//!         P: DaeModel + Clone + Send + Sync + 'static,
//!         T: dpc::core::TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
//!         L: dpc::core::linalg::LinearSolver + Send + 'static,
//!     {
//!         model.plant.structure().n_states()
//!     }
//! }
//! assert_eq!(visit("wheel", StateCount).unwrap(), 5);
//! assert!(visit("bicycle", StateCount).is_err());
//! ```

use dpc::core::linalg::{LinearSolver, NalgebraLu};
use dpc::core::model::DaeModel;
use dpc::core::reference::Reference;
use dpc::core::TrackingDae;

use crate::{
    FlexibleJoint, FlexibleJointReference, FlexibleJointTracking, Wheel, WheelLinear,
    WheelLinearParams, WheelLinearTracking, WheelReference, WheelTracking,
};

/// A model that can be looked up by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModelInfo {
    /// The name used in scenario files and on the command line.
    pub name: &'static str,
    /// One line on what the model is.
    pub summary: &'static str,
}

/// The models [`visit`] knows, in the order `dpc models` lists them.
pub const MODELS: &[ModelInfo] = &[
    ModelInfo {
        name: "wheel",
        summary: "the paper's nonlinear rolling wheel (Appendix); outputs theta, psi; W = s + 5 on both",
    },
    ModelInfo {
        name: "wheel-linear",
        summary: "the wheel linearised about x0(t) = [pi/2, -6t, 0, 0, -6] ((4.1) with the Appendix input gains 2, 0.8); no built-in reference",
    },
    ModelInfo {
        name: "flexible-joint",
        summary: "a flexible-joint robot arm of relative degree 4; output q_link; W = (s + 2)(s + 3)",
    },
];

/// A plant with its tracking DAE, the model's own reference (from its `references` section,
/// if it has one) and a linear solver sized for the tracking DAE.
pub struct Tracked<P, T, L> {
    /// The plant with its default parameters.
    pub plant: P,
    /// The tracking DAE with its default parameters and `W`.
    pub tracking: T,
    /// The reference declared in the model, if any.
    pub reference: Option<Box<dyn Reference + Send + Sync>>,
    /// A dense fixed-size LU of the tracking DAE's dimension.
    pub solver: L,
}

/// Code to run on a model chosen by name; see the module documentation.
pub trait VisitTracked {
    /// What the visit returns.
    type Output;

    /// Called with the concrete model.
    fn visit<P, T, L>(self, model: Tracked<P, T, L>) -> Self::Output
    where
        P: DaeModel + Clone + Send + Sync + 'static,
        T: TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
        L: LinearSolver + Send + 'static;
}

/// A model name that [`visit`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown model `{name}`; the known models are: {}", known_names())]
pub struct UnknownModel {
    /// The name asked for.
    pub name: String,
}

fn known_names() -> String {
    MODELS.iter().map(|m| m.name).collect::<Vec<_>>().join(", ")
}

/// Call `visitor` with the model called `name` (see [`MODELS`]).
///
/// # Errors
/// [`UnknownModel`] when no model has that name.
pub fn visit<V: VisitTracked>(name: &str, visitor: V) -> Result<V::Output, UnknownModel> {
    match name {
        "wheel" => Ok(visitor.visit(Tracked {
            plant: Wheel::default(),
            tracking: WheelTracking::default(),
            reference: Some(Box::new(WheelReference::default())),
            solver: NalgebraLu::<7>::new(),
        })),
        "wheel-linear" => {
            let params = WheelLinearParams {
                b1: 2.0,
                b2: 0.8,
                ..WheelLinearParams::default()
            };
            Ok(visitor.visit(Tracked {
                plant: WheelLinear::from_params(params),
                tracking: WheelLinearTracking::from_params(params),
                reference: None,
                solver: NalgebraLu::<7>::new(),
            }))
        }
        "flexible-joint" => Ok(visitor.visit(Tracked {
            plant: FlexibleJoint::default(),
            tracking: FlexibleJointTracking::default(),
            reference: Some(Box::new(FlexibleJointReference::default())),
            solver: NalgebraLu::<5>::new(),
        })),
        _ => Err(UnknownModel {
            name: name.to_string(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Dimensions;
    impl VisitTracked for Dimensions {
        type Output = (usize, usize, bool);
        fn visit<P, T, L>(self, model: Tracked<P, T, L>) -> Self::Output
        where
            P: DaeModel + Clone + Send + Sync + 'static,
            T: TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
            L: LinearSolver + Send + 'static,
        {
            (
                model.tracking.structure().n_equations(),
                model.solver.dimension(),
                model.reference.is_some(),
            )
        }
    }

    #[test]
    fn every_listed_model_is_found_with_a_solver_of_its_size() {
        for info in MODELS {
            let (n, solver, _) = visit(info.name, Dimensions).expect(info.name);
            assert_eq!(n, solver, "{}", info.name);
        }
    }

    #[test]
    fn the_error_lists_the_known_models() {
        let err = visit("bicycle", Dimensions).unwrap_err().to_string();
        assert!(err.contains("`bicycle`"), "{err}");
        for info in MODELS {
            assert!(err.contains(info.name), "{err}");
        }
    }
}
