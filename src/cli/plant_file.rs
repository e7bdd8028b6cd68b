//! Plant files read at run time (see [`dpc::runtime`]): a scenario's `model = "crane.dpc"`
//! (a path ending in `.dpc`, relative to the scenario file) and `dpc model FILE.dpc`.
//!
//! A plant file becomes an [`Entry`] of its run-time plant, tracking DAE and references, so
//! a scenario runs on it through the same [`ScenarioModel`] and [`crate::cli::run::run`] as on a
//! compiled model: `simulate`, `sweep` and the comparison runs work unchanged.

use std::path::{Path, PathBuf};

use dpc::core::DaeModel;
use dpc::runtime::{PlantFileError, RelativeDegree, RuntimeModel};

use crate::cli::registry::{Entry, ScenarioModel};
use crate::cli::scenario::Scenario;
use crate::cli::ScenarioError;

/// Whether a scenario's `model` (or the argument of `dpc model`) names a plant file.
pub fn is_plant_file(model: &str) -> bool {
    Path::new(model).extension().is_some_and(|e| e == "dpc")
}

/// The plant file a scenario names, resolved against the scenario file's directory (the
/// current directory for a scenario parsed from text); `None` when its `model` is a
/// registered name.
pub fn scenario_path(scenario: &Scenario) -> Option<PathBuf> {
    if !is_plant_file(&scenario.model) {
        return None;
    }
    let dir = scenario
        .source
        .as_ref()
        .and_then(|s| s.path.parent())
        .unwrap_or(Path::new(""));
    Some(dir.join(&scenario.model))
}

/// The scenario model of a plant file: its plant, tracking DAE and (if declared) references,
/// named `name` (as the scenario wrote it).
///
/// # Errors
/// [`ScenarioError::PlantFile`] for a file that cannot be read or compiled,
/// [`ScenarioError::NoTracking`] for a file without a `tracking` section.
pub fn load(path: &Path, name: &str) -> Result<Box<dyn ScenarioModel>, ScenarioError> {
    let model = dpc::runtime::load(path).map_err(ScenarioError::PlantFile)?;
    let summary = format!("plant file {} (model {})", path.display(), model.name());
    entry(&model, name, summary).ok_or_else(|| ScenarioError::NoTracking {
        path: path.display().to_string(),
    })
}

/// The entry of a compiled plant file, if it has a tracking DAE.
fn entry(model: &RuntimeModel, name: &str, summary: String) -> Option<Box<dyn ScenarioModel>> {
    let tracking = model.tracking()?;
    let entry = Entry::new(name, summary, model.plant(), tracking).listing(model.listing());
    Some(match model.reference() {
        Some(r) => Box::new(entry.reference(r)),
        None => Box::new(entry),
    })
}

/// What `dpc model FILE.dpc` prints: the listing, dimensions, per output the relative degree
/// and how it was found, `W` and `nu` (as for a registered model), and the diagnostics.
///
/// # Errors
/// [`PlantFileError`] for a file that cannot be read or compiled: every error, one
/// `FILE:LINE:COLUMN: message` line each.
pub fn describe(path: &Path) -> Result<String, PlantFileError> {
    let model = dpc::runtime::load(path)?;
    let summary = format!("plant file (model {})", model.name());
    let mut s = match entry(&model, &path.display().to_string(), summary) {
        Some(entry) => entry.describe(),
        None => {
            let mut s = format!(
                "{}: plant file (model {})\n\n",
                path.display(),
                model.name()
            );
            s += model.listing();
            s += "\nno tracking section: scenarios cannot run this plant until it declares one\n";
            s
        }
    };
    s += "\ndiagnostics:\n";
    let outputs = model.plant().structure().outputs.to_vec();
    if outputs.is_empty() {
        s += "  no outputs: nothing to track\n";
    }
    for (name, degree) in outputs.iter().zip(model.relative_degree_analysis()) {
        s += &format!("  output {name}: {}\n", relative_degree_text(*degree));
    }
    Ok(s)
}

/// How a relative degree was found, in words.
fn relative_degree_text(degree: RelativeDegree) -> String {
    match degree {
        RelativeDegree::Symbolic(r) => {
            format!("relative degree {r}, confirmed symbolically along the equations")
        }
        RelativeDegree::Structural(r) => format!(
            "relative degree {r}, structural (the symbolic confirmation outgrew its budget; exact unless coefficients cancel)"
        ),
        RelativeDegree::Unreached => {
            "no input reaches this output: it cannot be tracked".to_string()
        }
        RelativeDegree::Undetermined => "relative degree undefined: its derivatives reach unknowns of structurally singular implicit equations (a higher-index plant); scenarios must set `nu`".to_string(),
    }
}
