//! The library behind the `dpc` command line: scenario files, closed-loop runs of the models
//! in `dpc-models`, their summaries, trajectories and plots, and parameter sweeps.
//!
//! Data flow: [`scenario::Scenario`] (TOML + overrides) -> [`run::run`] (model looked up by
//! name, controller built, closed loop simulated) -> [`report`] (summary.json,
//! trajectory.csv) and [`plot`] (SVG and PNG figures); [`sweep`] runs many scenarios in
//! parallel.

pub mod plot;
pub mod report;
pub mod run;
pub mod scenario;
pub mod sweep;

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
    /// A `--set` assignment is malformed.
    #[error("bad override: {0}")]
    Override(String),
    /// The model does not exist.
    #[error(transparent)]
    UnknownModel(#[from] dpc_models::registry::UnknownModel),
    /// The controller or the simulation could not be set up.
    #[error("{0}")]
    Setup(String),
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
