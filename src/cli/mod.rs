//! The library behind the `dpc` command line, for any registry of models: scenario files,
//! closed-loop runs, their summaries, trajectories and plots, parameter sweeps, and the
//! command line itself ([`main`]).
//!
//! Data flow: [`scenario::Scenario`] (TOML + overrides) -> [`registry::Registry::run`] (model
//! looked up by name) -> [`run::run`] (monomorphised for the model: controller built, closed
//! loop simulated) -> [`report`] (summary.json, trajectory.csv) and [`plot`] (SVG and PNG
//! figures); [`sweep`] runs many scenarios in parallel.
//!
//! A crate that declares its own plants with `dpc::model!` gets the whole command line
//! (`simulate`, `sweep`, `analyze`, `models`, `model NAME`) for them in a few lines:
//!
//! ```no_run
//! use dpc::cli::registry::{Entry, Registry};
//! use dpc_models::{FlexibleJoint, FlexibleJointReference, FlexibleJointTracking};
//!
//! fn main() -> std::process::ExitCode {
//!     dpc::cli::main(Registry::new().model(
//!         Entry::new(
//!             "arm",
//!             "a flexible-joint arm",
//!             FlexibleJoint::default(),
//!             FlexibleJointTracking::default(),
//!         )
//!         .reference(FlexibleJointReference::default()),
//!     ))
//! }
//! ```

pub mod command;
pub mod json;
pub mod location;
pub mod output;
pub mod plant_file;
pub mod plot;
pub mod progress;
pub mod registry;
pub mod report;
pub mod run;
pub mod scenario;
pub mod sweep;
pub mod text;

pub use command::main;

use dpc::core::controller::DpcError;
use dpc::core::design::DesignError;
use dpc::core::linear_analysis::LinearError;
use dpc::core::reference::ReferenceError;
use dpc::core::simulate::SimulateError;
use dpc::core::tracking::TrackingError;
use thiserror::Error;

/// Everything that can go wrong between a scenario file and its outputs. Each message is one
/// line that names what was wrong and, where it helps, what was expected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ScenarioError {
    /// A file could not be read.
    #[error("cannot read {path}: {message}")]
    Read {
        /// The file.
        path: String,
        /// The system's reason.
        message: String,
    },
    /// The scenario is malformed or inconsistent with its model.
    #[error("{origin}: {message}")]
    Invalid {
        /// File (and line) the problem is in.
        origin: String,
        /// What is wrong.
        message: String,
    },
    /// A value of the scenario is out of range (or sets more work than its limit).
    #[error("{origin}: {cause}")]
    Value {
        /// The file the scenario came from.
        origin: String,
        /// What is wrong, by the key the user wrote.
        cause: scenario::ValueError,
    },
    /// A `--set` assignment is malformed.
    #[error("bad override: {0}")]
    Override(scenario::OverrideError),
    /// The model does not exist.
    #[error("{origin}: {cause}")]
    UnknownModel {
        /// Where the name was written (`FILE:LINE:COLUMN` of a scenario's `model`).
        origin: String,
        /// The name and the names that exist.
        cause: registry::UnknownModel,
    },
    /// The plant file a scenario names cannot be read or compiled: every error, one
    /// `FILE:LINE:COLUMN: message` line each.
    #[error(transparent)]
    PlantFile(dpc::runtime::PlantFileError),
    /// The plant file a scenario names has no `tracking` section, so there is no tracking DAE
    /// to control it with.
    #[error("{path}: the plant file has no `tracking` section; a scenario needs its tracking DAE")]
    NoTracking {
        /// The plant file.
        path: String,
    },
    /// The design of the preliminary feedback could not be made: the nominal could not be
    /// trimmed, the linearisation or the analysis failed, or the tracking DAE's relative
    /// degrees are not the plant's at the nominal.
    #[error("design: {0}")]
    Design(DesignError),
    /// The linear sampled-data prediction of the designed loop failed.
    #[error("sampled-data prediction: {0}")]
    SampledPrediction(LinearError),
    /// The reference assembled from the scenario's terms does not fit the model.
    #[error(transparent)]
    Reference(ReferenceError),
    /// The `W` the model was registered with is not accepted by a fresh tracking DAE.
    #[error("the registered model's W: {0}")]
    RegisteredW(TrackingError),
    /// The controller could not be built.
    #[error("controller: {0}")]
    Controller(DpcError),
    /// The preliminary feedback does not fit the controller.
    #[error("preliminary feedback: {0}")]
    Prefeedback(DpcError),
    /// The linear analysis gave no `K_n` although the preliminary feedback is on.
    #[error("the linear analysis built no K_n")]
    NoFeedbackGain,
    /// The closed loop could not start.
    #[error("simulation: {0}")]
    Simulation(SimulateError),
    /// The results could not be put in place.
    #[error(transparent)]
    Output(#[from] output::OutputError),
    /// A run or the writing of its results failed after the output directory was checked;
    /// nothing of it reached the output directory.
    #[error("{cause}; {}", if *previous { format!("the previous results in {target} are unchanged") } else { format!("nothing was written to {target}") })]
    NotWritten {
        /// The output directory.
        target: String,
        /// Whether it holds earlier results (left as they were).
        previous: bool,
        /// What failed.
        cause: Box<ScenarioError>,
    },
    /// Every run of a sweep failed.
    #[error("all {runs} runs of the sweep failed, the first with: {first}; {}", if *previous { format!("the previous results in {target} are unchanged") } else { format!("nothing was written to {target}") })]
    SweepFailed {
        /// The number of runs.
        runs: usize,
        /// The error of the first run.
        first: Box<ScenarioError>,
        /// The output directory.
        target: String,
        /// Whether it holds earlier results (left as they were).
        previous: bool,
    },
    /// `--shard` is not `K/N` with `1 <= K <= N`.
    #[error("--shard {text}: expected K/N, part K of N parts with 1 <= K <= N (e.g. --shard 2/8)")]
    Shard {
        /// The text given (a short excerpt).
        text: String,
    },
    /// The parts of a sweep cannot be merged.
    #[error("sweep merge: {0}")]
    Merge(sweep::MergeError),
    /// A run of a sweep's part failed; its error as the part recorded it.
    #[error("{message}")]
    InPart {
        /// The error's message.
        message: String,
    },
    /// A sweep has more combinations than its limit.
    #[error("the sweep has {} combinations ({}), more than --max-runs = {limit}; raise it deliberately (--max-runs N) if the sweep is meant to be this large", sizes.iter().try_fold(1_usize, |n, k| n.checked_mul(*k)).map_or("more than 2^64".to_string(), |n| n.to_string()), text::short(&sizes.iter().map(ToString::to_string).collect::<Vec<_>>().join(" x ")))]
    TooManyRuns {
        /// The number of values of each swept key.
        sizes: Vec<usize>,
        /// The limit in force.
        limit: usize,
    },
    /// A number to be written is NaN: a quantity that could not be computed.
    #[error("{path}: {cause}")]
    NotFinite {
        /// The file it was to be written to.
        path: String,
        /// The key of the number.
        cause: json::JsonError,
    },
    /// Writing results failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: String,
        /// The reason.
        message: String,
    },
}

/// A TOML error as one line `origin:line:column: message`.
pub fn toml_error(origin: &str, text: &str, err: &toml::de::Error) -> ScenarioError {
    let message = err
        .message()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let origin = match err.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("{origin}:{line}:{column}")
        }
        None => origin.to_string(),
    };
    ScenarioError::Invalid { origin, message }
}
