//! Closed-loop simulation of sampled DPC (paper, Section 5).
//!
//! At each sample `t_k = k h` the controller measures the plant state and computes a control
//! ([`crate::controller::Dpc::control`]); the plant, which may be a different model or have different
//! parameters than the controller's (to study mismatch), is then integrated accurately to
//! `t_(k+1)` with the control held (zero-order hold). Two hold variants: hold the whole input
//! `u`, or, with a preliminary feedback, apply `u = u0 + K_n (x - x0) + v` continuously and
//! hold only `v`.
//!
//! # The plant integrator
//! Either hold makes the plant's input jump at every sample, and with it the derivative of
//! its solution. One integrator serves the whole run and is restarted at every sample
//! ([`ClosedLoopOptions::plant_integration`]):
//! * by default ([`PlantIntegration::Auto`]) Radau IIA ([`crate::radau`]), a one-step method
//!   of order 5 that loses nothing at a restart: each interval starts at full order with the
//!   step the last one reached and, while Newton converges fast with it, the Jacobian and
//!   factorisations of the last interval. A plant without algebraic unknowns is restarted
//!   from the state and derivative the last step ended with (Radau needs no consistent
//!   derivative); one with algebraic unknowns is first made consistent for the new input;
//! * [`PlantIntegration::Bdf`], the variable-order BDF ([`crate::bdf`]), must discard its
//!   history at every sample and restart at order 1 after a consistent initialisation: on
//!   the wheel at `h = 0.01` about fifteen steps per sample where Radau takes one, and less
//!   accurate at the same tolerance (`docs/performance.md`).
//!
//! # Constrained plants
//! A plant with constraint rows (no `x'` and no algebraic unknown in the row: a mechanism's
//! position constraints with their multipliers, index 3, or velocity constraints, index 2;
//! classified by [`ConstraintStructure`]) is handled as follows:
//! * before the run, the pencil of its linearisation at the given state is checked
//!   ([`crate::linear_analysis::descriptor`]): a singular pencil or an index above 3 is a
//!   [`SimulateError::Descriptor`]; the given state is then made consistent
//!   ([`consistent_state`]: positions onto the constraints, velocities onto their hidden
//!   derivatives), and how far it moved is reported in [`ClosedLoop::constraints`];
//! * at every sample the measured state is made consistent in the same way, so the controller
//!   gets a differential state on the constraint manifold (the drift the integration left is
//!   reported); the derivatives and the multipliers are recomputed for the applied input;
//! * between samples the plant is integrated by Radau IIA ([`crate::radau`]) with the index of
//!   each unknown from the structure ([`ConstraintStructure::stabilised_index`](crate::consistent::ConstraintStructure::stabilised_index): velocities of
//!   constrained positions index 2, multipliers index 3) for the error scaling;
//! * a constraint whose residual at a sample, relative to the size of its terms, exceeds
//!   [`ClosedLoopOptions::constraint_tolerance`] stops the run with
//!   [`DivergenceCause::ConstraintViolated`], naming the equation.
//!
//! # Dense output and progress
//! With [`ClosedLoopOptions::output_step`] set, the plant's continuous motion between the
//! samples is recorded as well ([`ClosedLoop::dense`], and merged with the samples by
//! [`ClosedLoop::trajectory`]): at every `t = j * output_step` the interpolating polynomial of
//! the integrator step that covers it is evaluated (BDF's or Radau's dense output), so no
//! extra step is taken and the samples are bit for bit those of a run without it. The points
//! are stored in flat arrays reserved before the run: recording them allocates nothing per
//! point. [`simulate_with_progress`] reports the run's advance after each sample to a
//! [`Progress`] (a closure `FnMut(t, t_final)` is one); [`simulate`] reports to nobody, at no
//! cost.
//!
//! The loop reports divergence with its time and a typed [`DivergenceCause`] (a tracking
//! error beyond its bound, a bounded state leaving its domain, a non-finite state, a
//! controller failing on consecutive samples, the plant integrator failing), and stops there,
//! instead of panicking or producing NaN. Divergence is judged on what the run is for, the
//! tracking error `y - xi` per output, and on the states the user bounds: a state that grows
//! without limit while the loop tracks (a heading angle) is not a divergence.
//!
//! # Example
//! The mass on a spring starts half a unit below its reference `0.5 + sin t` and is
//! controlled at `h = 0.05`; the plant (here with a spring 1 % stiffer than the controller's
//! model, to show mismatch) is integrated between the samples with the control held.
//!
//! ```
//! use dpc::core::controller::{Dpc, DpcOptions};
//! use dpc::core::linear_solver::NalgebraLu;
//! use dpc::core::simulate::{simulate, ClosedLoopOptions};
//! use dpc::core::DaeModel;
//!
//! dpc::model! {
//!     /// A mass on a spring, pushed by `f`.
//!     Mass {
//!         params { m = 1.0, k = 4.0 }
//!         states { x, v }
//!         inputs { f }
//!         equations { der(x) = v; m * der(v) == f - k * x; }
//!         outputs { x }
//!         references { x = 0.5 + sin(t) }
//!         tracking MassTracking { x: [5.0, 5.0] } // W = (s + 5)^2: nu = 0
//!     }
//! }
//!
//! let mut dpc = Dpc::new(
//!     MassTracking::default(),
//!     MassReference::default(),
//!     NalgebraLu::<{ MassTracking::N_EQUATIONS }>::new(),
//!     DpcOptions::default(),
//! )?;
//! let plant = Mass::from_params(MassParams { k: 4.04, ..MassParams::default() });
//! let opts = ClosedLoopOptions { h: 0.05, t_end: 5.0, ..ClosedLoopOptions::default() };
//! let run = simulate(&plant, &mut dpc, &[0.0, 1.0], &opts)?;
//! assert!(run.divergence.is_none());
//! assert_eq!(run.samples.len(), 101);
//! assert!((run.samples[0].error[0] + 0.5).abs() < 1e-12); // y - reference at t = 0
//! // The initial error decays like t exp(-5 t). The spring the controller does not know,
//! // 0.04 x with |x| <= 1.5, leaves an error of about 0.04 * 1.5 / 25 = 2.4e-3.
//! let late = run.max_abs_error_since(3.0)[0];
//! assert!((1e-3..5e-3).contains(&late), "{late}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::cell::RefCell;

use crate::bdf::{Bdf, BdfError, InitWorkspace, Options};
use crate::consistent::{
    consistent_state, ConsistentError, ConsistentOptions, ConstraintStructure,
};
use crate::controller::{Dpc, DpcError};
use crate::dae::ImplicitDae;
use crate::error::InvalidOption;
use crate::linear_analysis::descriptor::{
    descriptor_system, realise, DescriptorError, DescriptorOptions,
};
use crate::linear_solver::{FaerDenseLu, LinearSolver};
use crate::linearize::OperatingPoint;
use crate::model::DaeModel;
use crate::numeric::{max_or_nan, Readable};
use crate::prefeedback::Prefeedback;
use crate::radau::{self, Radau, RadauError};
use crate::reference::Reference;
use crate::sink::MatrixSink;
use crate::stabilised::{Stabilised, StabilisedError};
use crate::tracking::TrackingDae;
use nalgebra::DMatrix;
use thiserror::Error;

/// What the zero-order hold keeps constant between samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Hold {
    /// Hold the whole plant input `u` (with a preliminary feedback, evaluated at the sample).
    #[default]
    Input,
    /// Apply the preliminary feedback continuously and hold only the DPC correction `v`.
    Correction,
}

/// Options of a closed-loop run.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedLoopOptions {
    /// Sampling period `h`.
    pub h: f64,
    /// End time.
    pub t_end: f64,
    /// Relative tolerance of the plant integration.
    pub rtol: f64,
    /// Absolute tolerance of the plant integration.
    pub atol: f64,
    /// What is held between samples.
    pub hold: Hold,
    /// Per state, in the model's order, the bound `|x_i| <= b_i` beyond which the run counts
    /// as diverged; `None` (or a state beyond the vector's end) is not bounded. Every state
    /// is checked for NaN and infinity whatever its bound.
    pub state_bounds: Vec<Option<f64>>,
    /// Per output, in the model's order, the bound `|y_i - xi_i| <= e_i` on the tracking error
    /// beyond which the run counts as diverged; `None` (or an output beyond the vector's end)
    /// is not checked.
    pub tracking_bounds: Vec<Option<f64>>,
    /// The run counts as diverged after this many consecutive samples on which the controller
    /// failed (the previous control is held meanwhile).
    pub max_consecutive_failures: usize,
    /// For a constrained plant: the run counts as diverged when a constraint `g_i(x) = 0` has,
    /// at a sample before the projection, `|g_i| > constraint_tolerance * (1 + s_i)`, `s_i =
    /// sum_j |dg_i/dx_j| |x_j|` the size of its terms. Default `1e-6`, well above the drift of an
    /// integration at the default tolerances.
    pub constraint_tolerance: f64,
    /// When set, the plant's motion between the samples is recorded every `output_step` time
    /// units, at `t = j * output_step` (a time on a sample instant is the sample), in
    /// [`ClosedLoop::dense`]: interpolated inside the plant integrator's steps, so the samples
    /// are bit for bit those of a run without it. It must be positive, finite and at least
    /// [`MIN_OUTPUT_STEP_RATIO`] times the run's length. `None` (default): the samples only.
    pub output_step: Option<f64>,
    /// The integrator of a plant without constraint rows between the samples (a constrained
    /// plant is always integrated by Radau IIA). Default [`PlantIntegration::Auto`].
    pub plant_integration: PlantIntegration,
}

/// Which integrator carries a plant without constraint rows from one sample to the next
/// ([`ClosedLoopOptions::plant_integration`]).
///
/// The held input jumps at every sample, and with it the solution's derivative: a multistep
/// method (BDF) must restart there at order 1 with its history discarded, while a one-step
/// method (Radau IIA) loses nothing and starts each interval at its full order 5 with the step
/// it had reached (see `docs/performance.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlantIntegration {
    /// Radau IIA, the rule for every closed loop: the input is held piecewise constant, so it
    /// jumps at every sample.
    #[default]
    Auto,
    /// Variable-order BDF ([`crate::bdf::Bdf`]), restarted at every sample.
    Bdf,
    /// Radau IIA ([`crate::radau::Radau`]), restarted at every sample with the step it had
    /// reached.
    Radau,
}

/// The smallest [`ClosedLoopOptions::output_step`] relative to the run's length `t_end`:
/// below it the times `j * output_step` are no longer resolved apart from the samples'.
pub const MIN_OUTPUT_STEP_RATIO: f64 = 1e-12;

impl ClosedLoopOptions {
    /// The number of points the dense output of a run to `t_end` records: the times
    /// `j * output_step` strictly between samples (0 without an output step, or with an
    /// invalid one).
    pub fn dense_points(&self) -> usize {
        match self.output_step {
            Some(step) if step.is_finite() && step > 0.0 && self.h > 0.0 => {
                let steps = (self.t_end / self.h).round();
                if !steps.is_finite() {
                    return 0;
                }
                let tolerance = DenseGrid::tolerance(step);
                (0..steps as u64)
                    .map(|k| {
                        let (t0, t1) = (k as f64 * self.h, (k + 1) as f64 * self.h);
                        let first = ((t0 + tolerance) / step).floor() + 1.0;
                        let last = ((t1 - tolerance) / step).ceil() - 1.0;
                        (last - first + 1.0).max(0.0) as usize
                    })
                    .fold(0, usize::saturating_add)
            }
            _ => 0,
        }
    }
}

impl Default for ClosedLoopOptions {
    fn default() -> Self {
        Self {
            h: 0.05,
            t_end: 20.0,
            rtol: 1e-8,
            atol: 1e-10,
            hold: Hold::Input,
            state_bounds: Vec::new(),
            tracking_bounds: Vec::new(),
            max_consecutive_failures: 3,
            constraint_tolerance: 1e-6,
            output_step: None,
            plant_integration: PlantIntegration::Auto,
        }
    }
}

/// Errors that prevent a run from starting (a run that starts and fails later reports a
/// [`Divergence`] instead).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimulateError {
    /// An option is out of range.
    #[error("invalid simulation option: {0}")]
    InvalidOption(#[from] InvalidOption),
    /// A state or tracking-error bound is NaN or not positive.
    #[error("the bound on {quantity} `{name}` is {}; it must be positive", Readable(*value))]
    InvalidBound {
        /// `"state"` or `"tracking error"`.
        quantity: &'static str,
        /// The state's or output's name.
        name: String,
        /// The bound given.
        value: f64,
    },
    /// More bounds than the model has states or outputs.
    #[error("{found} {quantity} bounds given, but the plant has {expected}")]
    TooManyBounds {
        /// `"state"` or `"tracking error"`.
        quantity: &'static str,
        /// The number of states or outputs.
        expected: usize,
        /// The number of bounds.
        found: usize,
    },
    /// The initial state has the wrong length.
    #[error("initial state: {found} values given, but the plant has {expected} states")]
    InitialStateLength {
        /// The number of states.
        expected: usize,
        /// The number of values given.
        found: usize,
    },
    /// A value of the initial state is NaN or infinite.
    #[error("initial state: `{state}` is {}", Readable(*value))]
    NonFiniteInitialState {
        /// The state's name as declared.
        state: String,
        /// The value given.
        value: f64,
    },
    /// [`Hold::Correction`] needs a controller with a preliminary feedback.
    #[error("hold = correction needs a preliminary feedback")]
    NoPrefeedback,
    /// The constraint structure of the plant could not be stabilised (an internal
    /// inconsistency of the structure read from the model).
    #[error("constrained plant: {0}")]
    Stabilised(#[from] StabilisedError),
    /// A constrained plant whose linearisation at the initial state has a singular pencil, an
    /// index above 3, or an input whose derivatives drive it.
    #[error("constrained plant at the initial state: {0}")]
    Descriptor(DescriptorError),
    /// A constrained plant whose initial state cannot be made consistent (the constraints
    /// cannot be met, or the multipliers are not determined), or whose structure the
    /// projection does not handle.
    #[error("constrained plant at the initial state: {0}")]
    Consistent(ConsistentError),
    /// [`ClosedLoopOptions::output_step`] is not a positive finite number, is below
    /// [`MIN_OUTPUT_STEP_RATIO`] times the run's length, or asks for more points than memory
    /// can hold.
    #[error("output step {}: {problem}", Readable(*step))]
    OutputStep {
        /// The step given.
        step: f64,
        /// What is wrong with it.
        problem: OutputStepProblem,
    },
    /// The plant and the controller disagree on the number of inputs or outputs.
    #[error("plant has {plant} {what}, controller {controller}")]
    Mismatch {
        /// What differs.
        what: &'static str,
        /// The plant's count.
        plant: usize,
        /// The controller's count.
        controller: usize,
    },
}

/// What is wrong with an [`ClosedLoopOptions::output_step`] ([`SimulateError::OutputStep`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum OutputStepProblem {
    /// Zero, negative, NaN or infinite.
    #[error("it must be a positive finite number")]
    NotPositive,
    /// Below [`MIN_OUTPUT_STEP_RATIO`] times the run's length.
    #[error("it is below {MIN_OUTPUT_STEP_RATIO:e} times the run's length, where the output times are no longer resolved")]
    TooSmall,
    /// The points it asks for do not fit in memory.
    #[error("the {points} points it asks for do not fit in memory")]
    TooManyPoints {
        /// The number of points.
        points: usize,
    },
}

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Divergence {
    /// Time at which it was detected.
    pub t: f64,
    /// What happened (serialised as its message).
    pub cause: DivergenceCause,
}

/// What made a run stop: the structured cause, rendered as text only by its `Display` (which
/// is also its serialised form).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DivergenceCause {
    /// A bounded state left its domain.
    #[error("state {state} = {} left the domain |{state}| <= {}", Readable(*value), Readable(*bound))]
    StateBound {
        /// The state's name.
        state: String,
        /// Its value.
        value: f64,
        /// The bound.
        bound: f64,
    },
    /// A state became NaN or infinite.
    #[error("state {state} is {}", Readable(*value))]
    NonFiniteState {
        /// The state's name.
        state: String,
        /// Its value.
        value: f64,
    },
    /// The tracking error of an output exceeded its bound (or is NaN).
    #[error("tracking error of {output} = {} exceeds the bound |{output} - ref| <= {}", Readable(*error), Readable(*bound))]
    TrackingError {
        /// The output's name.
        output: String,
        /// The error `y - xi`.
        error: f64,
        /// The bound.
        bound: f64,
    },
    /// The controller failed on more consecutive samples than allowed, or with an error that
    /// a retry at the next sample cannot cure.
    #[error("controller failed: {0}")]
    Controller(DpcError),
    /// The plant could not be integrated over a sampling interval.
    #[error("plant integration failed: {0}")]
    Plant(BdfError),
    /// The plant could not be integrated by Radau IIA over a sampling interval
    /// ([`PlantIntegration::Radau`]).
    #[error("plant integration (Radau IIA) failed: {0}")]
    PlantRadau(RadauError),
    /// The constrained plant could not be integrated over a sampling interval.
    #[error("integration of the constrained plant failed: {0}")]
    ConstrainedPlant(RadauError),
    /// A constraint of the plant was violated beyond
    /// [`ClosedLoopOptions::constraint_tolerance`] at a sample.
    #[error(
        "constraint {equation} violated: residual {residual:e} above the tolerance {tolerance:e}"
    )]
    ConstraintViolated {
        /// The constraint, as the model names it.
        equation: String,
        /// Its residual.
        residual: f64,
        /// The absolute tolerance it was held to (relative tolerance times the size of its
        /// terms).
        tolerance: f64,
    },
    /// The measured state of the constrained plant could not be made consistent.
    #[error("the measured state cannot be made consistent: {0}")]
    Consistent(ConsistentError),
}

impl serde::Serialize for DivergenceCause {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

/// An error serialised as its message.
fn serialize_display<E: std::fmt::Display, S: serde::Serializer>(
    error: &E,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    serializer.collect_str(error)
}

/// One sample of a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Sample {
    /// Sample time.
    pub t: f64,
    /// Measured plant state.
    pub x: Vec<f64>,
    /// Plant input applied from this sample on (at the sample time).
    pub u: Vec<f64>,
    /// Plant outputs.
    pub y: Vec<f64>,
    /// References at `t`.
    pub reference: Vec<f64>,
    /// Tracking errors `y - xi`.
    pub error: Vec<f64>,
}

/// A sample at which the controller did not succeed at its first `delta`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case", tag = "event")]
pub enum ControllerEvent {
    /// The inner integration failed and succeeded after `retries` retries with `delta`.
    Retried {
        /// Sample time.
        t: f64,
        /// Retries needed.
        retries: usize,
        /// The `delta` that succeeded.
        delta: f64,
    },
    /// Every `delta` tried failed; the previous control was held.
    Failed {
        /// Sample time.
        t: f64,
        /// The controller's error (serialised as `message`, its text).
        #[serde(rename = "message", serialize_with = "serialize_display")]
        error: DpcError,
    },
}

/// The result of a closed-loop run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClosedLoop {
    /// Samples in time order.
    pub samples: Vec<Sample>,
    /// Set when the run stopped early.
    pub divergence: Option<Divergence>,
    /// Newton iterations of the controller, over all samples.
    pub newton_iterations: usize,
    /// Successful retries with a larger `delta`, over all samples.
    pub retries: usize,
    /// Every sample at which the controller retried or failed, in time order.
    pub events: Vec<ControllerEvent>,
    /// The largest round-off level `eps * delta^-nu` of an update over the run (see
    /// [`crate::controller::UpdateReport::roundoff`]).
    pub max_roundoff: f64,
    /// For a constrained plant: its constraint structure and how far states were moved onto
    /// the constraint manifold; `None` for an ODE or index-1 plant.
    pub constraints: Option<ConstraintReport>,
    /// The work of the plant integration between the samples.
    pub plant_work: PlantWork,
    /// The plant's motion between the samples at [`ClosedLoopOptions::output_step`] (empty
    /// without it); [`trajectory`](Self::trajectory) merges it with the samples.
    pub dense: DenseOutput,
}

/// The plant's motion between the samples, recorded every
/// [`ClosedLoopOptions::output_step`]: per point its time, the plant state, the input applied
/// at that time (the held one, or under [`Hold::Correction`] the continuous preliminary
/// feedback), the outputs, the references and the tracking errors. Stored flat, one array per
/// quantity, reserved before the run; read it point by point with [`point`](Self::point) or
/// [`points`](Self::points).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct DenseOutput {
    n_states: usize,
    n_inputs: usize,
    n_outputs: usize,
    t: Vec<f64>,
    x: Vec<f64>,
    u: Vec<f64>,
    y: Vec<f64>,
    reference: Vec<f64>,
    error: Vec<f64>,
}

/// One point of a run's trajectory ([`ClosedLoop::trajectory`]): a sample, or a point of the
/// dense output between samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectoryPoint<'a> {
    /// Time.
    pub t: f64,
    /// Plant state.
    pub x: &'a [f64],
    /// Plant input applied at `t` (at a sample: from the sample on).
    pub u: &'a [f64],
    /// Plant outputs.
    pub y: &'a [f64],
    /// References at `t`.
    pub reference: &'a [f64],
    /// Tracking errors `y - xi`.
    pub error: &'a [f64],
    /// Whether this is a sample instant (where the controller measured and acted) rather than
    /// a point of the dense output between samples.
    pub sample: bool,
}

impl DenseOutput {
    /// Empty, for points of these sizes, with room for `points` points.
    fn with_capacity(
        n_states: usize,
        n_inputs: usize,
        n_outputs: usize,
        points: usize,
    ) -> Result<Self, std::collections::TryReserveError> {
        let mut dense = Self {
            n_states,
            n_inputs,
            n_outputs,
            ..Self::default()
        };
        dense.t.try_reserve_exact(points)?;
        for (v, per_point) in [
            (&mut dense.x, n_states),
            (&mut dense.u, n_inputs),
            (&mut dense.y, n_outputs),
            (&mut dense.reference, n_outputs),
            (&mut dense.error, n_outputs),
        ] {
            v.try_reserve_exact(points.saturating_mul(per_point))?;
        }
        Ok(dense)
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no points (a run without an output step).
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The times of the points, increasing.
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// Point `i`, if there is one.
    pub fn point(&self, i: usize) -> Option<TrajectoryPoint<'_>> {
        let t = *self.t.get(i)?;
        let (nx, nu, ny) = (self.n_states, self.n_inputs, self.n_outputs);
        Some(TrajectoryPoint {
            t,
            x: &self.x[i * nx..(i + 1) * nx],
            u: &self.u[i * nu..(i + 1) * nu],
            y: &self.y[i * ny..(i + 1) * ny],
            reference: &self.reference[i * ny..(i + 1) * ny],
            error: &self.error[i * ny..(i + 1) * ny],
            sample: false,
        })
    }

    /// Every point in time order.
    pub fn points(&self) -> impl Iterator<Item = TrajectoryPoint<'_>> + '_ {
        (0..self.len()).filter_map(|i| self.point(i))
    }

    /// Append a point (within the reserved room: no allocation).
    fn push(&mut self, t: f64, x: &[f64], u: &[f64], y: &[f64], reference: &[f64], ref_ok: bool) {
        self.t.push(t);
        self.x.extend_from_slice(x);
        self.u.extend_from_slice(u);
        self.y.extend_from_slice(y);
        self.reference.extend_from_slice(reference);
        self.error.extend(
            y.iter()
                .zip(reference)
                .map(|(a, b)| if ref_ok { a - b } else { f64::NAN }),
        );
    }
}

impl Sample {
    /// This sample as a point of the trajectory.
    pub fn as_point(&self) -> TrajectoryPoint<'_> {
        TrajectoryPoint {
            t: self.t,
            x: &self.x,
            u: &self.u,
            y: &self.y,
            reference: &self.reference,
            error: &self.error,
            sample: true,
        }
    }
}

/// The samples and the dense output of a run merged in time order
/// ([`ClosedLoop::trajectory`]).
#[derive(Debug, Clone)]
pub struct Trajectory<'a> {
    samples: &'a [Sample],
    dense: &'a DenseOutput,
    next_sample: usize,
    next_dense: usize,
}

impl<'a> Iterator for Trajectory<'a> {
    type Item = TrajectoryPoint<'a>;

    fn next(&mut self) -> Option<Self::Item> {
        let sample = self.samples.get(self.next_sample);
        let dense_t = self.dense.t.get(self.next_dense);
        match (sample, dense_t) {
            (Some(s), Some(&t)) if t < s.t => {
                self.next_dense += 1;
                self.dense.point(self.next_dense - 1)
            }
            (Some(s), _) => {
                self.next_sample += 1;
                Some(s.as_point())
            }
            (None, Some(_)) => {
                self.next_dense += 1;
                self.dense.point(self.next_dense - 1)
            }
            (None, None) => None,
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.samples.len() - self.next_sample + self.dense.len() - self.next_dense;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Trajectory<'_> {}

/// The work of a run's plant integration without constraints: one integrator for the whole
/// run, restarted at every sample (where the held input jumps). For BDF the counts include
/// the consistent initialisations at the samples; a Radau step's factorisation is one real
/// and one complex LU. (A constrained plant's integration is not counted here.)
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct PlantWork {
    /// The integrator used ([`PlantIntegration::Auto`] resolved; `Auto` only when no interval
    /// was integrated this way).
    pub integrator: PlantIntegration,
    /// Sampling intervals integrated.
    pub intervals: usize,
    /// Accepted integrator steps.
    pub steps: usize,
    /// Rejected step attempts (local error test or Newton failures).
    pub rejected_steps: usize,
    /// Residual evaluations, consistent initialisation at the samples included.
    pub residual_evaluations: usize,
    /// Iteration-matrix evaluations, consistent initialisation included.
    pub jacobian_evaluations: usize,
    /// LU factorisations, consistent initialisation included.
    pub factorisations: usize,
}

impl PlantWork {
    /// Accepted steps per sampling interval (0 without intervals).
    pub fn steps_per_interval(&self) -> f64 {
        self.per_interval(self.steps)
    }

    /// Residual evaluations per sampling interval (0 without intervals).
    pub fn residuals_per_interval(&self) -> f64 {
        self.per_interval(self.residual_evaluations)
    }

    /// Factorisations per sampling interval (0 without intervals).
    pub fn factorisations_per_interval(&self) -> f64 {
        self.per_interval(self.factorisations)
    }

    fn per_interval(&self, count: usize) -> f64 {
        if self.intervals == 0 {
            0.0
        } else {
            count as f64 / self.intervals as f64
        }
    }
}

/// How a constrained plant was kept on its constraint manifold during a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ConstraintReport {
    /// The index of the plant's pencil at the initial state.
    pub index: usize,
    /// Degrees of freedom (the dimension of the constraint manifold in `x`).
    pub dof: usize,
    /// The constraint equations, as the model names them.
    pub equations: Vec<String>,
    /// `x - x0` per state: how far the given initial state was moved onto the manifold.
    pub initial_move: Vec<f64>,
    /// The largest move of a state by the projection at a later sample: the drift the plant
    /// integration left.
    pub max_drift: f64,
    /// The largest relative constraint residual met at a sample before the projection (see
    /// [`ClosedLoopOptions::constraint_tolerance`]).
    pub max_residual: f64,
}

impl ClosedLoop {
    /// The samples and the points of the dense output, in time order (only the samples
    /// without [`ClosedLoopOptions::output_step`]); [`TrajectoryPoint::sample`] tells them
    /// apart.
    pub fn trajectory(&self) -> Trajectory<'_> {
        Trajectory {
            samples: &self.samples,
            dense: &self.dense,
            next_sample: 0,
            next_dense: 0,
        }
    }

    /// Per output, the largest `|y - xi|` over the samples at `t >= from` (NaN if one is
    /// NaN, 0 without samples).
    pub fn max_abs_error_since(&self, from: f64) -> Vec<f64> {
        let outputs = self.samples.first().map_or(0, |s| s.error.len());
        (0..outputs)
            .map(|i| {
                max_or_nan(
                    self.samples
                        .iter()
                        .filter(|s| s.t >= from)
                        .map(|s| s.error[i].abs()),
                )
            })
            .collect()
    }

    /// Samples on which the controller needed a larger `delta` and then succeeded.
    pub fn retried_samples(&self) -> usize {
        self.events
            .iter()
            .filter(|e| matches!(e, ControllerEvent::Retried { .. }))
            .count()
    }

    /// Samples on which the controller failed (the previous control was held).
    pub fn failed_samples(&self) -> usize {
        self.events
            .iter()
            .filter(|e| matches!(e, ControllerEvent::Failed { .. }))
            .count()
    }
}

/// The plant with its inputs given by the hold: constant `u`, or the preliminary feedback
/// `u0(t) + K_n (x - x0(t)) + v` with constant `v`. One for the whole run: the held values
/// change at every sample ([`hold`](Self::hold)), the plant and the law do not.
struct HeldPlant<'p, M: DaeModel> {
    model: &'p M,
    feedback: Option<std::sync::Arc<Prefeedback>>,
    scratch: RefCell<HeldScratch>,
}

struct HeldScratch {
    /// The held `u` (or `v` under the continuous feedback).
    held: Vec<f64>,
    u: Vec<f64>,
    x0: Vec<f64>,
    f_xdot: DMatrix<f64>,
    f_x: DMatrix<f64>,
    f_z: DMatrix<f64>,
    f_u: DMatrix<f64>,
    res: Vec<f64>,
}

impl<'p, M: DaeModel> HeldPlant<'p, M> {
    fn new(model: &'p M, feedback: Option<std::sync::Arc<Prefeedback>>) -> Self {
        let structure = model.structure();
        let (ne, nx, nz, nu) = (
            structure.n_equations(),
            structure.n_states(),
            structure.n_algebraic(),
            structure.n_inputs(),
        );
        Self {
            model,
            feedback,
            scratch: RefCell::new(HeldScratch {
                held: vec![0.0; nu],
                u: vec![0.0; nu],
                x0: vec![0.0; nx],
                f_xdot: DMatrix::zeros(ne, nx),
                f_x: DMatrix::zeros(ne, nx),
                f_z: DMatrix::zeros(ne, nz),
                f_u: DMatrix::zeros(ne, nu),
                res: vec![0.0; ne],
            }),
        }
    }

    /// Hold `values` from now on.
    fn hold(&self, values: &[f64]) {
        self.scratch.borrow_mut().held.copy_from_slice(values);
    }

    /// The plant input at `(t, x)` under the hold, as the integrator sees it.
    fn input_at(&self, t: f64, x: &[f64], u: &mut [f64]) {
        let s = &mut *self.scratch.borrow_mut();
        self.inputs(t, x, s);
        u.copy_from_slice(&s.u);
    }

    fn inputs(&self, t: f64, x: &[f64], s: &mut HeldScratch) {
        match &self.feedback {
            Some(pf) => pf.input(t, x, &s.held, &mut s.x0, &mut s.u),
            None => s.u.copy_from_slice(&s.held),
        }
    }
}

impl<M: DaeModel> ImplicitDae for HeldPlant<'_, M> {
    fn dimension(&self) -> usize {
        self.model.structure().n_equations()
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (x, z) = y.split_at(self.model.structure().n_states());
        let s = &mut *self.scratch.borrow_mut();
        self.inputs(t, x, s);
        self.model
            .residual(t, x, &yp[..self.model.structure().n_states()], z, &s.u, out);
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let nx = self.model.structure().n_states();
        let (x, z) = y.split_at(nx);
        let xdot = &yp[..nx];
        let s = &mut *self.scratch.borrow_mut();
        self.inputs(t, x, s);
        let Some(pf) = &self.feedback else {
            self.model.iteration_matrix(t, x, xdot, z, &s.u, c, out);
            return;
        };
        for m in [&mut s.f_xdot, &mut s.f_x, &mut s.f_z, &mut s.f_u] {
            m.fill(0.0);
        }
        self.model.evaluate(
            t,
            x,
            xdot,
            z,
            &s.u,
            &mut s.res,
            &mut s.f_xdot,
            &mut s.f_x,
            &mut s.f_z,
            &mut s.f_u,
        );
        // u depends on x through K_n: dF/dx gains dF/du K_n (summed in place: a Jacobian
        // evaluation inside the integrator allocates nothing).
        pf.iteration_matrix(
            c,
            &s.f_x,
            &s.f_xdot,
            s.f_u.columns(0, s.f_u.ncols()),
            s.f_z.columns(0, s.f_z.ncols()),
            out,
        );
    }

    fn residual_and_iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: &mut [f64],
        out: &mut S,
    ) {
        if self.feedback.is_some() {
            self.residual(t, y, yp, residual);
            self.iteration_matrix(t, y, yp, c, out);
            return;
        }
        let nx = self.model.structure().n_states();
        let (x, z) = y.split_at(nx);
        let s = &mut *self.scratch.borrow_mut();
        self.inputs(t, x, s);
        self.model
            .residual_and_iteration_matrix(t, x, &yp[..nx], z, &s.u, c, residual, out);
    }

    // `dF/dx'` does not depend on the input's law (the input is a function of `t` and `x`,
    // never of `x'`), so the model's own serves with or without preliminary feedback.
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        out: &mut S,
    ) -> bool {
        let nx = self.model.structure().n_states();
        let (x, z) = y.split_at(nx);
        let s = &mut *self.scratch.borrow_mut();
        self.inputs(t, x, s);
        self.model.mass_matrix(t, x, &yp[..nx], z, &s.u, out)
    }

    // The position constraints' exact derivatives, when the model supplies them (generated
    // models do). The constraint rows do not contain the input, so it is handed over as last
    // evaluated, not evaluated again at (t, x).
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, t: f64, y: &[f64], out: &mut S) -> bool {
        let (x, z) = y.split_at(self.model.structure().n_states());
        let s = self.scratch.borrow();
        self.model.constraint_gradient(t, x, z, &s.u, out)
    }

    fn constraint_time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) -> bool {
        let (x, z) = y.split_at(self.model.structure().n_states());
        let s = self.scratch.borrow();
        self.model.constraint_time_derivative(t, x, z, &s.u, out)
    }

    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        v: &[f64],
        out: &mut S,
    ) -> bool {
        let nx = self.model.structure().n_states();
        let (x, z) = y.split_at(nx);
        let s = self.scratch.borrow();
        self.model
            .constraint_curvature(t, x, z, &s.u, &v[..nx], out)
    }

    fn is_differential(&self, i: usize) -> bool {
        i < self.model.structure().n_states()
    }

    fn equation_name(&self, i: usize) -> String {
        self.model.structure().equation_name(i)
    }

    fn unknown_name(&self, i: usize) -> String {
        self.model.structure().unknown_name(i)
    }
}

/// Told how far a closed-loop run has come ([`simulate_with_progress`]).
pub trait Progress {
    /// The run has recorded its sample at `t`; it ends at `t_final` (the last sample's time,
    /// unless it stops early).
    fn sample(&mut self, t: f64, t_final: f64);
}

/// A [`Progress`] that ignores the reports ([`simulate`]'s).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    #[inline]
    fn sample(&mut self, _t: f64, _t_final: f64) {}
}

impl<F: FnMut(f64, f64)> Progress for F {
    fn sample(&mut self, t: f64, t_final: f64) {
        self(t, t_final)
    }
}

/// Run the closed loop of `dpc` on `plant` from the state `x0` (algebraic unknowns of the
/// plant are initialised consistently at every sample).
///
/// # Errors
/// [`SimulateError`] when the run cannot start; failures during the run are reported in
/// [`ClosedLoop::divergence`].
pub fn simulate<P, T, R, L>(
    plant: &P,
    dpc: &mut Dpc<T, R, L>,
    x0: &[f64],
    opts: &ClosedLoopOptions,
) -> Result<ClosedLoop, SimulateError>
where
    P: DaeModel,
    T: TrackingDae,
    R: Reference,
    L: LinearSolver,
{
    simulate_with_progress(plant, dpc, x0, opts, &mut NoProgress)
}

/// [`simulate`], telling `progress` of each sample as it is recorded (for a progress bar; a
/// closure `|t, t_final| ...` will do). The guide's closed-loop page has an example.
///
/// # Errors
/// As [`simulate`].
pub fn simulate_with_progress<P, T, R, L, G>(
    plant: &P,
    dpc: &mut Dpc<T, R, L>,
    x0: &[f64],
    opts: &ClosedLoopOptions,
    progress: &mut G,
) -> Result<ClosedLoop, SimulateError>
where
    P: DaeModel,
    T: TrackingDae,
    R: Reference,
    L: LinearSolver,
    G: Progress + ?Sized,
{
    let (nx, nz, nu, ny) = (
        plant.structure().n_states(),
        plant.structure().n_algebraic(),
        plant.structure().n_inputs(),
        plant.structure().n_outputs(),
    );
    InvalidOption::positive("h", opts.h)?;
    InvalidOption::positive("t_end", opts.t_end)?;
    check_bounds("state", &opts.state_bounds, &plant.structure().states)?;
    check_bounds(
        "tracking error",
        &opts.tracking_bounds,
        &plant.structure().outputs,
    )?;
    if x0.len() != nx {
        return Err(SimulateError::InitialStateLength {
            expected: nx,
            found: x0.len(),
        });
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(SimulateError::NonFiniteInitialState {
            state: plant.structure().states[i].to_string(),
            value: x0[i],
        });
    }
    if dpc.model().structure().n_states() != nx {
        return Err(SimulateError::Mismatch {
            what: "states",
            plant: nx,
            controller: dpc.model().structure().n_states(),
        });
    }
    let controller_inputs = dpc.model().plant_inputs();
    if controller_inputs != nu {
        return Err(SimulateError::Mismatch {
            what: "inputs",
            plant: nu,
            controller: controller_inputs,
        });
    }
    if dpc.model().structure().n_outputs() != ny {
        return Err(SimulateError::Mismatch {
            what: "outputs",
            plant: ny,
            controller: dpc.model().structure().n_outputs(),
        });
    }
    if opts.hold == Hold::Correction && dpc.prefeedback().is_none() {
        return Err(SimulateError::NoPrefeedback);
    }
    InvalidOption::positive("constraint_tolerance", opts.constraint_tolerance)?;
    let steps = (opts.t_end / opts.h).round() as usize;
    let t_final = steps as f64 * opts.h;
    let mut grid = match opts.output_step {
        Some(step) => Some(DenseGrid::new(step, t_final, nx + nz)?),
        None => None,
    };
    let dense = match &grid {
        Some(g) => {
            let points = opts.dense_points();
            DenseOutput::with_capacity(nx, nu, ny, points).map_err(|_| {
                SimulateError::OutputStep {
                    step: g.step,
                    problem: OutputStepProblem::TooManyPoints { points },
                }
            })?
        }
        None => DenseOutput::default(),
    };
    let bdf_opts = Options::with_tolerances(opts.rtol, opts.atol);
    let mut result = ClosedLoop {
        samples: Vec::new(),
        divergence: None,
        newton_iterations: 0,
        retries: 0,
        events: Vec::new(),
        max_roundoff: 0.0,
        constraints: None,
        plant_work: PlantWork::default(),
        dense,
    };
    // The dense output's work vectors (empty, unallocated, without it).
    let dense_size = |n: usize| if grid.is_some() { n } else { 0 };
    let mut dense_u = vec![0.0; dense_size(nu)];
    let mut dense_y = vec![0.0; dense_size(ny)];
    let mut dense_reference = vec![0.0; dense_size(ny)];
    let mut y = vec![0.0; nx + nz];
    y[..nx].copy_from_slice(x0);
    let mut yp = vec![0.0; nx + nz];
    let mut control = vec![0.0; nu];
    let mut applied = vec![0.0; nu];
    let mut x0_scratch = vec![0.0; nx];
    let mut consecutive_failures = 0;
    let mut reference = vec![0.0; ny];
    let mut outputs = vec![0.0; ny];
    let constrained = Constrained::new(plant, x0, opts)?;
    if let Some(c) = &constrained {
        let first = c.project(plant, 0.0, x0, &applied);
        let first = first.map_err(SimulateError::Consistent)?;
        y[..nx].copy_from_slice(&first.x);
        result.constraints = Some(ConstraintReport {
            index: c.index,
            dof: c.dof,
            equations: c
                .rows
                .iter()
                .map(|&i| plant.structure().equation_name(i))
                .collect(),
            initial_move: first.moved,
            max_drift: 0.0,
            max_residual: 0.0,
        });
    }
    // One plant with its hold and one integrator for the whole run.
    let held_plant = HeldPlant::new(
        plant,
        match opts.hold {
            Hold::Input => None,
            Hold::Correction => dpc.shared_prefeedback(),
        },
    );
    let mut integrator = PlantIntegrator::new(&held_plant, bdf_opts, opts.plant_integration);
    let stabilised = match &constrained {
        Some(c) => Some(c.stabilise(&held_plant)?),
        None => None,
    };
    result.samples.reserve(steps + 1);
    for k in 0..=steps {
        let t = k as f64 * opts.h;
        if let Some(cause) = state_divergence(plant, &y[..nx], &opts.state_bounds) {
            result.divergence = Some(Divergence { t, cause });
            break;
        }
        if let (Some(c), Some(report)) = (&constrained, result.constraints.as_mut()) {
            // The measured state onto the constraint manifold, after checking the drift.
            let checked = c
                .check(plant, t, &y[..nx], &applied, report)
                .and_then(|()| {
                    c.project(plant, t, &y[..nx], &applied)
                        .map_err(DivergenceCause::Consistent)
                });
            match checked {
                Ok(state) => {
                    if k > 0 {
                        report.max_drift = report.max_drift.max(state.max_move);
                    }
                    y[..nx].copy_from_slice(&state.x);
                }
                Err(cause) => {
                    result.divergence = Some(Divergence { t, cause });
                    break;
                }
            }
        }
        let x = &y[..nx];
        match dpc.control(t, x, &mut control) {
            Ok(report) => {
                consecutive_failures = 0;
                result.newton_iterations += report.newton_iterations;
                result.max_roundoff = result.max_roundoff.max(report.roundoff);
                if report.retries > 0 {
                    result.retries += report.retries;
                    result.events.push(ControllerEvent::Retried {
                        t,
                        retries: report.retries,
                        delta: report.delta,
                    });
                }
            }
            Err(err) => {
                consecutive_failures += 1;
                let fatal = consecutive_failures > opts.max_consecutive_failures
                    || !matches!(err, DpcError::NoSolution { .. } | DpcError::Singular { .. });
                result.events.push(ControllerEvent::Failed {
                    t,
                    error: err.clone(),
                });
                if fatal {
                    result.divergence = Some(Divergence {
                        t,
                        cause: DivergenceCause::Controller(err),
                    });
                    break;
                }
                // Hold the previous control and try again at the next sample.
            }
        }
        // The plant input at the sample (for the record, and for Hold::Input).
        match dpc.prefeedback() {
            Some(pf) => pf.input(t, x, &control, &mut x0_scratch, &mut applied),
            None => applied.copy_from_slice(&control),
        }
        if let Some(c) = &constrained {
            // Derivatives and multipliers for the applied input (the state is already on the
            // manifold, so only they change).
            match c.project(plant, t, &y[..nx], &applied) {
                Ok(state) => {
                    y[nx..].copy_from_slice(&state.z);
                    yp[..nx].copy_from_slice(&state.xdot);
                    yp[nx..].fill(0.0);
                }
                Err(err) => {
                    result.divergence = Some(Divergence {
                        t,
                        cause: DivergenceCause::Consistent(err),
                    });
                    break;
                }
            }
        }
        let (xs, zs) = y.split_at(nx);
        plant.outputs(t, xs, zs, &applied, &mut outputs);
        let ref_ok = record_reference(dpc, t, &mut reference);
        result.samples.push(Sample {
            t,
            x: xs.to_vec(),
            u: applied.clone(),
            y: outputs.clone(),
            reference: reference.clone(),
            error: outputs
                .iter()
                .zip(&reference)
                .map(|(a, b)| if ref_ok { a - b } else { f64::NAN })
                .collect(),
        });
        if let Some(cause) = result
            .samples
            .last()
            .and_then(|s| tracking_divergence(plant, &s.error, &opts.tracking_bounds))
        {
            result.divergence = Some(Divergence { t, cause });
            break;
        }
        progress.sample(t, t_final);
        if k == steps {
            break;
        }
        // Integrate the plant over [t, t + h] with the hold.
        held_plant.hold(match opts.hold {
            Hold::Input => &applied,
            Hold::Correction => &control,
        });
        // The dense output between t and t + h: the state the integrator interpolates, with
        // the input, outputs and references there.
        let dense = &mut result.dense;
        let held = &held_plant;
        let mut record = |td: f64, yd: &[f64]| {
            let (xd, zd) = yd.split_at(nx);
            held.input_at(td, xd, &mut dense_u);
            plant.outputs(td, xd, zd, &dense_u, &mut dense_y);
            let ok = record_reference(dpc, td, &mut dense_reference);
            dense.push(td, xd, &dense_u, &dense_y, &dense_reference, ok);
        };
        let dense_interval = grid.as_mut().map(|g| {
            g.start(t);
            (g, &mut record as &mut dyn FnMut(f64, &[f64]))
        });
        let integrated = match (&constrained, &stabilised) {
            (Some(c), Some(dae)) => c
                .integrate(dae, t, t + opts.h, &mut y, &mut yp, dense_interval)
                .map_err(DivergenceCause::ConstrainedPlant),
            _ => integrator.interval(t, t + opts.h, &mut y, &mut yp, dense_interval),
        };
        if let Err(cause) = integrated {
            result.divergence = Some(Divergence { t, cause });
            break;
        }
    }
    result.plant_work = integrator.work();
    Ok(result)
}

/// The plant's integrator for a whole run: created at the first sampling interval, restarted
/// ([`Bdf::reinit`], [`Radau::reinit`]) at each later one after the state is made consistent
/// for the new held input, so that a sample allocates nothing.
struct PlantIntegrator<'h, 'p, M: DaeModel> {
    held: &'h HeldPlant<'p, M>,
    opts: Options,
    radau_opts: radau::Options,
    /// [`PlantIntegration::Auto`] resolved.
    method: PlantIntegration,
    /// The plant has algebraic unknowns (to be made consistent at every sample).
    algebraic: bool,
    /// The solver and work vectors of the consistent initialisation.
    init_solver: FaerDenseLu,
    init: InitWorkspace,
    bdf: Option<Bdf<&'h HeldPlant<'p, M>, FaerDenseLu>>,
    radau: Option<Radau<&'h HeldPlant<'p, M>, FaerDenseLu>>,
    /// Work of the initialisations (the integrator counts its own).
    init_work: crate::bdf::Stats,
    intervals: usize,
}

impl<'h, 'p, M: DaeModel> PlantIntegrator<'h, 'p, M> {
    fn new(held: &'h HeldPlant<'p, M>, opts: Options, method: PlantIntegration) -> Self {
        let n = held.dimension();
        let radau_opts = radau::Options {
            rtol: opts.rtol.clone(),
            atol: opts.atol.clone(),
            ..radau::Options::default()
        };
        Self {
            held,
            opts,
            radau_opts,
            method: match method {
                PlantIntegration::Auto => PlantIntegration::Radau,
                m => m,
            },
            algebraic: held.model.structure().n_algebraic() > 0,
            init_solver: FaerDenseLu::new(n),
            init: InitWorkspace::new(n),
            bdf: None,
            radau: None,
            init_work: crate::bdf::Stats::default(),
            intervals: 0,
        }
    }

    /// Make the plant consistent at `t0` (the input may have jumped) and integrate to `t1`;
    /// with `dense`, record each of its times in `(t0, t1)` from inside the steps.
    fn interval(
        &mut self,
        t0: f64,
        t1: f64,
        y: &mut [f64],
        yp: &mut [f64],
        dense: Option<DenseInterval<'_, '_>>,
    ) -> Result<(), DivergenceCause> {
        self.intervals += 1;
        if self.method == PlantIntegration::Radau && self.radau.is_some() && !self.algebraic {
            // Radau needs no consistent derivative (it enters only Newton's first guess and
            // a Jacobian, if one is due), and a plant without algebraic unknowns has nothing
            // else to make consistent: the derivative of the last step serves.
            return self.radau_interval(t0, t1, y, yp, dense);
        }
        let init = self
            .init
            .consistent_initial_values(self.held, &mut self.init_solver, &self.opts, t0, y, yp)
            .map_err(DivergenceCause::Plant)?;
        let w = &mut self.init_work;
        w.residual_evaluations += init.residual_evaluations;
        w.jacobian_evaluations += init.jacobian_evaluations;
        w.factorisations += init.factorisations;
        let n = self.held.dimension();
        if self.method == PlantIntegration::Bdf {
            let bdf = match &mut self.bdf {
                Some(bdf) => {
                    bdf.reinit(t0, y, yp).map_err(DivergenceCause::Plant)?;
                    bdf
                }
                None => self.bdf.insert(
                    Bdf::new(self.held, FaerDenseLu::new(n), self.opts.clone(), t0, y, yp)
                        .map_err(DivergenceCause::Plant)?,
                ),
            };
            bdf.set_stop_time(t1).map_err(DivergenceCause::Plant)?;
            return match dense {
                None => bdf.solve_to(t1, y, Some(yp)).map(|_| ()),
                Some((grid, record)) => {
                    step_with_dense_output(bdf, t1, self.opts.max_steps, grid, record, y, yp)
                        .map_err(|e| {
                            e.into_error(|max_steps, t| BdfError::TooManySteps {
                                max_steps,
                                tout: t1,
                                t,
                            })
                        })
                }
            }
            .map_err(DivergenceCause::Plant);
        }
        self.radau_interval(t0, t1, y, yp, dense)
    }

    /// [`interval`](Self::interval) by Radau IIA from `(y, yp)` as they are.
    fn radau_interval(
        &mut self,
        t0: f64,
        t1: f64,
        y: &mut [f64],
        yp: &mut [f64],
        dense: Option<DenseInterval<'_, '_>>,
    ) -> Result<(), DivergenceCause> {
        let n = self.held.dimension();
        let radau = match &mut self.radau {
            Some(radau) => {
                radau
                    .reinit(t0, y, yp)
                    .map_err(DivergenceCause::PlantRadau)?;
                radau
            }
            None => self.radau.insert(
                Radau::new(
                    self.held,
                    FaerDenseLu::new(n),
                    self.radau_opts.clone(),
                    t0,
                    y,
                    yp,
                )
                .map_err(DivergenceCause::PlantRadau)?,
            ),
        };
        radau
            .set_stop_time(t1)
            .map_err(DivergenceCause::PlantRadau)?;
        match dense {
            None => radau.solve_to(t1, y, Some(yp)).map(|_| ()),
            Some((grid, record)) => {
                step_with_dense_output(radau, t1, self.radau_opts.max_steps, grid, record, y, yp)
                    .map_err(|e| {
                        e.into_error(|max_steps, t| RadauError::TooManySteps {
                            max_steps,
                            tout: t1,
                            t,
                        })
                    })
            }
        }
        .map_err(DivergenceCause::PlantRadau)
    }

    fn work(&self) -> PlantWork {
        // The BDF's and Radau's `Stats` are two types with the same counters.
        macro_rules! counts {
            ($s:expr) => {{
                let s = $s;
                (
                    s.steps,
                    s.error_test_failures + s.newton_failures,
                    s.residual_evaluations,
                    s.jacobian_evaluations,
                    s.factorisations,
                )
            }};
        }
        let (steps, rejected, residuals, jacobians, factorisations) = match (&self.bdf, &self.radau)
        {
            (Some(b), _) => counts!(b.stats()),
            (None, Some(r)) => counts!(r.stats()),
            (None, None) => (0, 0, 0, 0, 0),
        };
        PlantWork {
            integrator: if self.intervals > 0 {
                self.method
            } else {
                PlantIntegration::Auto
            },
            intervals: self.intervals,
            steps,
            rejected_steps: rejected,
            residual_evaluations: residuals + self.init_work.residual_evaluations,
            jacobian_evaluations: jacobians + self.init_work.jacobian_evaluations,
            factorisations: factorisations + self.init_work.factorisations,
        }
    }
}

/// An integrator taken one step at a time, with the interpolating polynomial of its last
/// step: what the dense output between two samples needs of BDF and of Radau.
trait DenseStepper {
    /// The integrator's own error.
    type Error;
    /// The number of unknowns it integrates.
    fn dimension(&self) -> usize;
    /// The time reached.
    fn t(&self) -> f64;
    /// One step (never past the stop time).
    fn step(&mut self) -> Result<(), Self::Error>;
    /// The solution (and its derivative) at `t` within the last step.
    fn interpolate(&self, t: f64, y: &mut [f64], yp: Option<&mut [f64]>)
        -> Result<(), Self::Error>;
}

impl<D: ImplicitDae, L: LinearSolver> DenseStepper for Bdf<D, L> {
    type Error = BdfError;
    fn dimension(&self) -> usize {
        self.dae().dimension()
    }
    fn t(&self) -> f64 {
        Bdf::t(self)
    }
    fn step(&mut self) -> Result<(), BdfError> {
        Bdf::step(self).map(|_| ())
    }
    fn interpolate(&self, t: f64, y: &mut [f64], yp: Option<&mut [f64]>) -> Result<(), BdfError> {
        Bdf::interpolate(self, t, y, yp)
    }
}

impl<D: ImplicitDae, L: LinearSolver> DenseStepper for Radau<D, L> {
    type Error = RadauError;
    fn dimension(&self) -> usize {
        self.dae().dimension()
    }
    fn t(&self) -> f64 {
        Radau::t(self)
    }
    fn step(&mut self) -> Result<(), RadauError> {
        Radau::step(self).map(|_| ())
    }
    fn interpolate(&self, t: f64, y: &mut [f64], yp: Option<&mut [f64]>) -> Result<(), RadauError> {
        Radau::interpolate(self, t, y, yp)
    }
}

/// Why [`step_with_dense_output`] stopped.
enum DenseStepError<E> {
    /// `max_steps` steps did not reach the end; the time reached.
    TooManySteps { max_steps: usize, t: f64 },
    /// The integrator's own failure.
    Integrator(E),
}

impl<E> From<E> for DenseStepError<E> {
    fn from(e: E) -> Self {
        Self::Integrator(e)
    }
}

impl<E> DenseStepError<E> {
    /// The integrator's error, with `too_many(max_steps, t)` its own for the step limit.
    fn into_error(self, too_many: impl FnOnce(usize, f64) -> E) -> E {
        match self {
            Self::TooManySteps { max_steps, t } => too_many(max_steps, t),
            Self::Integrator(e) => e,
        }
    }
}

/// The steps `solve_to(t1)` would take (the integrator's stop time is `t1`, so the first step
/// is sized for it and none passes it), one at a time, each of the grid's times due after a
/// step interpolated and recorded (the first `grid`-dimension unknowns of the integrator's);
/// then `(y, yp)` at `t1` (their lengths: the integrator's dimension).
fn step_with_dense_output<S: DenseStepper>(
    stepper: &mut S,
    t1: f64,
    max_steps: usize,
    grid: &mut DenseGrid,
    record: &mut dyn FnMut(f64, &[f64]),
    y: &mut [f64],
    yp: &mut [f64],
) -> Result<(), DenseStepError<S::Error>> {
    let (recorded, dimension) = (grid.dimension, stepper.dimension());
    if grid.y.len() < dimension {
        // Once per run at most (a constrained plant's stabilised form has more unknowns).
        grid.y.resize(dimension, 0.0);
    }
    let mut steps = 0;
    while stepper.t() < t1 {
        if steps >= max_steps {
            return Err(DenseStepError::TooManySteps {
                max_steps,
                t: stepper.t(),
            });
        }
        stepper.step()?;
        steps += 1;
        while let Some(td) = grid.due(stepper.t(), t1) {
            stepper.interpolate(td, &mut grid.y[..dimension], None)?;
            record(td, &grid.y[..recorded]);
            grid.advance();
        }
    }
    Ok(stepper.interpolate(t1, y, Some(yp))?)
}

/// The times of the dense output, `j * step`, and the work vector they are interpolated into.
struct DenseGrid {
    step: f64,
    /// The index `j` of the next time.
    next: u64,
    /// Times within this of a sample instant are that sample.
    tolerance: f64,
    /// The plant's unknowns `(x, z)`: the first this many of [`y`](Self::y) are recorded.
    dimension: usize,
    /// The integrator's unknowns at a time of the grid (the plant's `(x, z)` first).
    y: Vec<f64>,
}

/// The grid and where its points go, for one sampling interval.
type DenseInterval<'g, 'r> = (&'g mut DenseGrid, &'r mut dyn FnMut(f64, &[f64]));

impl DenseGrid {
    fn new(step: f64, t_final: f64, dimension: usize) -> Result<Self, SimulateError> {
        let problem = if !(step.is_finite() && step > 0.0) {
            Some(OutputStepProblem::NotPositive)
        } else if step < MIN_OUTPUT_STEP_RATIO * t_final {
            Some(OutputStepProblem::TooSmall)
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(SimulateError::OutputStep { step, problem });
        }
        Ok(Self {
            step,
            next: 1,
            tolerance: Self::tolerance(step),
            dimension,
            y: vec![0.0; dimension],
        })
    }

    /// Times within this of a sample instant are that sample.
    fn tolerance(step: f64) -> f64 {
        1e-6 * step
    }

    fn time(&self) -> f64 {
        self.next as f64 * self.step
    }

    /// Skip the times at or next to the sample `t0`.
    fn start(&mut self, t0: f64) {
        while self.time() <= t0 + self.tolerance {
            self.next += 1;
        }
    }

    /// The next time, if it lies before the sample `t1` and at or before `reached`.
    fn due(&self, reached: f64, t1: f64) -> Option<f64> {
        let t = self.time();
        (t <= reached && t < t1 - self.tolerance).then_some(t)
    }

    fn advance(&mut self) {
        self.next += 1;
    }
}

/// What the closed loop needs to run a constrained plant.
struct Constrained {
    /// The constraint rows.
    rows: Vec<usize>,
    /// The position-constraint rows, stabilised by their hidden velocity constraints.
    position_rows: Vec<usize>,
    /// Per state, its kinematic row.
    kinematic: Vec<Option<usize>>,
    /// Radau's options with the index of every unknown.
    radau: radau::Options,
    consistent: ConsistentOptions,
    tolerance: f64,
    index: usize,
    dof: usize,
}

impl Constrained {
    /// `None` for a plant without constraint rows; else the structure, checked by the pencil
    /// at `x0` (a singular pencil or an index above 3 is refused before any projection).
    fn new<P: DaeModel>(
        plant: &P,
        x0: &[f64],
        opts: &ClosedLoopOptions,
    ) -> Result<Option<Self>, SimulateError> {
        let structure = ConstraintStructure::of(plant);
        if !structure.is_constrained() && structure.prescribed.is_empty() {
            return Ok(None);
        }
        structure
            .check_supported(plant)
            .map_err(SimulateError::Consistent)?;
        let s = plant.structure();
        let (nz, nu) = (s.n_algebraic(), s.n_inputs());
        let zeros_x = vec![0.0; x0.len()];
        let zeros_z = vec![0.0; nz];
        let zeros_u = vec![0.0; nu];
        // The pencil's structure (regularity, index) at the given state; its consistency is
        // not asked for here, the projection below makes it so.
        let pencil_opts = DescriptorOptions {
            consistency_tol: f64::INFINITY,
            ..DescriptorOptions::default()
        };
        let desc = descriptor_system(
            plant,
            OperatingPoint {
                t: 0.0,
                x: x0,
                xdot: &zeros_x,
                z: &zeros_z,
                u: &zeros_u,
            },
            &pencil_opts,
        )
        .map_err(SimulateError::Descriptor)?;
        let real = realise(&desc, &pencil_opts, |i| s.unknown_name(i))
            .map_err(SimulateError::Descriptor)?;
        let mut radau = radau::Options::with_tolerances(opts.rtol, opts.atol);
        radau.index = structure.stabilised_index();
        Ok(Some(Self {
            rows: structure.constraint_rows(),
            position_rows: structure.position_constraints.clone(),
            kinematic: structure.kinematic.clone(),
            radau,
            consistent: ConsistentOptions::default(),
            tolerance: opts.constraint_tolerance,
            index: real.index,
            dof: real.dof,
        }))
    }

    fn project<P: DaeModel>(
        &self,
        plant: &P,
        t: f64,
        x: &[f64],
        u: &[f64],
    ) -> Result<crate::consistent::ConsistentState, ConsistentError> {
        consistent_state(plant, t, x, u, &self.consistent)
    }

    /// The constraint residuals at `x`, relative to the size of their terms: the largest goes
    /// into the report, and one beyond the tolerance is a divergence.
    fn check<P: DaeModel>(
        &self,
        plant: &P,
        t: f64,
        x: &[f64],
        u: &[f64],
        report: &mut ConstraintReport,
    ) -> Result<(), DivergenceCause> {
        let s = plant.structure();
        let (ne, nx, nz) = (s.n_equations(), s.n_states(), s.n_algebraic());
        let mut r = vec![0.0; ne];
        let mut f_x = DMatrix::zeros(ne, nx);
        model_jacobian_x(plant, t, x, &vec![0.0; nz], u, &mut r, &mut f_x);
        for &i in &self.rows {
            let scale: f64 = (0..nx).map(|j| f_x[(i, j)].abs() * x[j].abs()).sum();
            let tolerance = self.tolerance * (1.0 + scale);
            let relative = r[i].abs() / (1.0 + scale);
            report.max_residual = max_or_nan([report.max_residual, relative]);
            if r[i].is_nan() || r[i].abs() > tolerance {
                return Err(DivergenceCause::ConstraintViolated {
                    equation: s.equation_name(i),
                    residual: r[i],
                    tolerance,
                });
            }
        }
        Ok(())
    }

    /// The held plant in its stabilised form: its position constraints with the kinematic
    /// rows of the states.
    fn stabilise<'h, M: DaeModel>(
        &self,
        held: &'h HeldPlant<'_, M>,
    ) -> Result<Stabilised<&'h HeldPlant<'h, M>>, StabilisedError> {
        let kinematic = self
            .kinematic
            .iter()
            .enumerate()
            .filter_map(|(j, row)| row.map(|i| (j, i)))
            .collect();
        Stabilised::new(held, self.position_rows.clone(), kinematic)
    }

    /// Integrate the plant over `[t0, t1]` in its stabilised form
    /// ([`Stabilised`](crate::stabilised::Stabilised)) from the
    /// consistent `(y, yp)`, with `mu = 0`; with `dense`, record each of its times in
    /// `(t0, t1)` from inside the steps.
    fn integrate<M: DaeModel>(
        &self,
        dae: &Stabilised<&HeldPlant<'_, M>>,
        t0: f64,
        t1: f64,
        y: &mut [f64],
        yp: &mut [f64],
        dense: Option<DenseInterval<'_, '_>>,
    ) -> Result<(), RadauError> {
        let n = y.len();
        let (mut ys, mut yps) = dae.extend(y, yp);
        let ls = FaerDenseLu::new(dae.dimension());
        let mut radau = Radau::new(dae, ls, self.radau.clone(), t0, &ys, &yps)?;
        radau.set_stop_time(t1)?;
        match dense {
            None => radau.solve_to(t1, &mut ys, Some(&mut yps)).map(|_| ()),
            Some((grid, record)) => step_with_dense_output(
                &mut radau,
                t1,
                self.radau.max_steps,
                grid,
                record,
                &mut ys,
                &mut yps,
            )
            .map_err(|e| {
                e.into_error(|max_steps, t| RadauError::TooManySteps {
                    max_steps,
                    tout: t1,
                    t,
                })
            }),
        }?;
        y.copy_from_slice(&ys[..n]);
        yp.copy_from_slice(&yps[..n]);
        Ok(())
    }
}

/// The residual and `dF/dx` of `plant` at `(t, x, x' = 0, z, u)` (constraint rows do not
/// depend on `x'` or `z`).
fn model_jacobian_x<P: DaeModel>(
    plant: &P,
    t: f64,
    x: &[f64],
    z: &[f64],
    u: &[f64],
    r: &mut [f64],
    f_x: &mut DMatrix<f64>,
) {
    let s = plant.structure();
    let (ne, nx, nz, nu) = (s.n_equations(), s.n_states(), s.n_algebraic(), s.n_inputs());
    let mut f_xdot = DMatrix::zeros(ne, nx);
    let mut f_z = DMatrix::zeros(ne, nz);
    let mut f_u = DMatrix::zeros(ne, nu);
    plant.evaluate(
        t,
        x,
        &vec![0.0; nx],
        z,
        u,
        r,
        &mut f_xdot,
        f_x,
        &mut f_z,
        &mut f_u,
    );
}

/// Bounds must be positive (infinity: unbounded) and no more than there are names.
fn check_bounds(
    quantity: &'static str,
    bounds: &[Option<f64>],
    names: &crate::model::Names,
) -> Result<(), SimulateError> {
    if bounds.len() > names.len() {
        return Err(SimulateError::TooManyBounds {
            quantity,
            expected: names.len(),
            found: bounds.len(),
        });
    }
    for (i, bound) in bounds.iter().enumerate() {
        if let Some(value) = *bound {
            if value.is_nan() || value <= 0.0 {
                return Err(SimulateError::InvalidBound {
                    quantity,
                    name: names.get(i).unwrap_or_default().to_string(),
                    value,
                });
            }
        }
    }
    Ok(())
}

/// The first non-finite state, else the first bounded state beyond its bound.
fn state_divergence<P: DaeModel>(
    plant: &P,
    x: &[f64],
    bounds: &[Option<f64>],
) -> Option<DivergenceCause> {
    let name = |i: usize| {
        plant
            .structure()
            .states
            .get(i)
            .unwrap_or_default()
            .to_string()
    };
    if let Some((i, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Some(DivergenceCause::NonFiniteState {
            state: name(i),
            value,
        });
    }
    x.iter()
        .zip(bounds)
        .enumerate()
        .find_map(|(i, (&value, bound))| match *bound {
            Some(bound) if value.abs() > bound => Some(DivergenceCause::StateBound {
                state: name(i),
                value,
                bound,
            }),
            _ => None,
        })
}

/// The first output whose tracking error is beyond its bound or NaN.
fn tracking_divergence<P: DaeModel>(
    plant: &P,
    error: &[f64],
    bounds: &[Option<f64>],
) -> Option<DivergenceCause> {
    error
        .iter()
        .zip(bounds)
        .enumerate()
        .find_map(|(i, (&e, bound))| match *bound {
            // A NaN error fails the test too.
            Some(bound) if e.is_nan() || e.abs() > bound => Some(DivergenceCause::TrackingError {
                output: plant
                    .structure()
                    .outputs
                    .get(i)
                    .unwrap_or_default()
                    .to_string(),
                error: e,
                bound,
            }),
            _ => None,
        })
}

fn record_reference<T: TrackingDae, R: Reference, L: LinearSolver>(
    dpc: &Dpc<T, R, L>,
    t: f64,
    out: &mut [f64],
) -> bool {
    dpc.reference().derivatives(t, 0, out).is_ok()
}
