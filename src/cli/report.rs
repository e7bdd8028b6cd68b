//! What a run leaves on disk: `summary.json` (the verdict and the numbers a user compares)
//! and `trajectory.csv` (every sample, and with `output_step` the motion between them).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use dpc::core::numeric::max_or_nan;
use dpc::core::simulate::{ConstraintReport, ControllerEvent, PlantWork};
use serde::Serialize;

use crate::cli::run::{DesignReport, ModelInUse, RunResult};
use crate::cli::scenario::Scenario;
use crate::cli::ScenarioError;

/// The contents of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// The scenario's title.
    pub title: Option<String>,
    /// The model.
    pub model: String,
    /// The overrides that made this run, or "main".
    pub label: String,
    /// Whether the run diverged (state out of bounds, repeated controller failures, plant
    /// integration failure).
    pub diverged: bool,
    /// When it diverged.
    pub t_diverged: Option<f64>,
    /// Why it diverged.
    pub divergence_cause: Option<String>,
    /// Time of the last sample.
    pub t_final: f64,
    /// Per output, the tracking error `y - reference` at the last sample.
    pub final_error: BTreeMap<String, f64>,
    /// Per output, the largest `|y - reference|` over the last quarter of the run.
    pub max_abs_error: BTreeMap<String, f64>,
    /// Number of samples.
    pub samples: usize,
    /// Newton iterations of the controller over the run.
    pub newton_iterations: usize,
    /// Extraction retries with a larger `delta` over the run.
    pub retries: usize,
    /// Samples that needed at least one retry.
    pub retried_samples: usize,
    /// Samples on which the controller failed (the previous control was held).
    pub failed_samples: usize,
    /// Every sample at which the controller retried with a larger `delta` or failed.
    pub controller_events: Vec<ControllerEvent>,
    /// The largest round-off level `eps * delta^-nu` of a control update over the run: the
    /// relative rounding error of the extracted control, which grows as `delta` shrinks
    /// while the truncation error falls; compare it with the accuracy wanted. At 1 or more
    /// the controls carry no correct digit; written as `"inf"` when it exceeds the largest
    /// double.
    pub roundoff_level: f64,
    /// Wall-clock time of the simulation, in seconds.
    pub wall_time_s: f64,
    /// The work of the plant integration between the samples (one integrator per run,
    /// restarted at each sample): intervals, steps, rejected steps, residual and matrix
    /// evaluations, factorisations, with the per-sample figures.
    pub plant_integration: PlantIntegration,
    /// The parameters of the plant and of the controller, and the controller's `W`, as run.
    pub in_use: ModelInUse,
    /// The linear analysis of the controller's model, when the scenario has a `[design]`.
    pub linear_design: Option<DesignReport>,
    /// For a constrained plant (index 2 or 3): its index, degrees of freedom, constraint
    /// equations, how far the initial state was moved onto the constraints and the largest
    /// drift and residual met during the run; absent for ODE and index-1 plants.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraints: Option<ConstraintReport>,
    /// The scenario as run.
    pub scenario: Scenario,
}

/// The plant integration's work over a run, in `summary.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlantIntegration {
    /// The totals over the run.
    #[serde(flatten)]
    pub work: PlantWork,
    /// Accepted steps per sampling interval.
    pub steps_per_sample: f64,
    /// Residual evaluations per sampling interval.
    pub residuals_per_sample: f64,
    /// Factorisations per sampling interval.
    pub factorisations_per_sample: f64,
}

impl PlantIntegration {
    /// The totals of `work` with the per-sample figures.
    pub fn of(work: &PlantWork) -> Self {
        Self {
            work: *work,
            steps_per_sample: work.steps_per_interval(),
            residuals_per_sample: work.residuals_per_interval(),
            factorisations_per_sample: work.factorisations_per_interval(),
        }
    }
}

impl Summary {
    /// The summary of a run.
    pub fn of(run: &RunResult) -> Self {
        let cl = &run.closed_loop;
        let t_final = cl.samples.last().map_or(0.0, |s| s.t);
        let mut final_error = BTreeMap::new();
        let mut max_abs_error = BTreeMap::new();
        // The last quarter of the scheduled run; a run that stopped early is judged on the
        // samples it has, which then include the divergence.
        let late = cl.max_abs_error_since(0.75 * run.scenario.t_end.min(t_final.max(0.0)));
        for (i, name) in run.names.outputs.iter().enumerate() {
            let last = cl.samples.last().map_or(f64::NAN, |s| s.error[i]);
            final_error.insert(name.clone(), last);
            max_abs_error.insert(name.clone(), late.get(i).copied().unwrap_or(f64::NAN));
        }
        Self {
            title: run.scenario.title.clone(),
            model: run.scenario.model.clone(),
            label: run.label.clone(),
            diverged: cl.divergence.is_some(),
            t_diverged: cl.divergence.as_ref().map(|d| d.t),
            divergence_cause: cl.divergence.as_ref().map(|d| d.cause.to_string()),
            t_final,
            final_error,
            max_abs_error,
            samples: cl.samples.len(),
            newton_iterations: cl.newton_iterations,
            retries: cl.retries,
            retried_samples: cl.retried_samples(),
            failed_samples: cl.failed_samples(),
            controller_events: cl.events.clone(),
            roundoff_level: cl.max_roundoff,
            wall_time_s: run.wall_time,
            plant_integration: PlantIntegration::of(&cl.plant_work),
            in_use: run.model.clone(),
            linear_design: run.design.clone(),
            constraints: cl.constraints.clone(),
            scenario: run.scenario.clone(),
        }
    }

    /// The largest late error over the outputs (NaN if any is NaN).
    pub fn worst_late_error(&self) -> f64 {
        max_or_nan(self.max_abs_error.values().copied())
    }

    /// The numbers a sweep keeps of this run.
    pub fn digest(&self) -> Digest {
        Digest {
            label: self.label.clone(),
            diverged: self.diverged,
            t_diverged: self.t_diverged,
            divergence_cause: self.divergence_cause.clone(),
            final_error: self.final_error.clone(),
            max_abs_error: self.max_abs_error.clone(),
            samples: self.samples,
            newton_iterations: self.newton_iterations,
            retries: self.retries,
            failed_samples: self.failed_samples,
            roundoff_level: self.roundoff_level,
            wall_time_s: self.wall_time_s,
        }
    }
}

/// What a sweep keeps of each run for its table, its plot and its report lines: the verdict
/// and a few numbers per output, not the samples, events or scenario (those are in the run's
/// own `summary.json`), so that a sweep's memory does not grow with the length of its runs.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Digest {
    /// The overrides that made this run.
    pub label: String,
    /// Whether the run diverged.
    pub diverged: bool,
    /// When it diverged.
    pub t_diverged: Option<f64>,
    /// Why it diverged.
    pub divergence_cause: Option<String>,
    /// Per output, the tracking error at the last sample.
    pub final_error: BTreeMap<String, f64>,
    /// Per output, the largest `|y - reference|` over the last quarter of the run.
    pub max_abs_error: BTreeMap<String, f64>,
    /// Number of samples.
    pub samples: usize,
    /// Newton iterations of the controller over the run.
    pub newton_iterations: usize,
    /// Extraction retries with a larger `delta` over the run.
    pub retries: usize,
    /// Samples on which the controller failed.
    pub failed_samples: usize,
    /// The largest round-off level `eps * delta^-nu` of a control update (infinite when the
    /// controls carry no digit; written as `"inf"`).
    #[serde(deserialize_with = "crate::cli::json::number_or_inf")]
    pub roundoff_level: f64,
    /// Wall-clock time of the simulation, in seconds.
    pub wall_time_s: f64,
}

impl Digest {
    /// The largest late error over the outputs (NaN if any is NaN).
    pub fn worst_late_error(&self) -> f64 {
        max_or_nan(self.max_abs_error.values().copied())
    }
}

fn write_error(path: &Path, e: impl std::fmt::Display) -> ScenarioError {
    ScenarioError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Write `summary.json` and `trajectory.csv` of `run` into `dir` (created if needed; the
/// callers write into a [`crate::cli::output::Staging`] directory that is moved into place when
/// everything is written). Infinite numbers in `summary.json` are written as `"inf"` or
/// `"-inf"` ([`crate::cli::json`]).
///
/// # Errors
/// [`ScenarioError::Write`] when a file cannot be written, [`ScenarioError::NotFinite`] when
/// a number of the summary is NaN.
pub fn write_run(dir: &Path, run: &RunResult) -> Result<Summary, ScenarioError> {
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    let summary = Summary::of(run);
    let path = dir.join("summary.json");
    let json =
        crate::cli::json::to_string_pretty(&summary).map_err(|cause| ScenarioError::NotFinite {
            path: path.display().to_string(),
            cause,
        })?;
    std::fs::write(&path, json + "\n").map_err(|e| write_error(&path, e))?;
    write_trajectory(&dir.join("trajectory.csv"), run)?;
    Ok(summary)
}

/// A CSV column header: the name, and its unit in brackets when the model gives one
/// (`theta [rad]`).
fn column(name: String, unit: Option<&str>) -> String {
    match unit {
        Some(u) if !u.is_empty() => format!("{name} [{u}]"),
        _ => name,
    }
}

/// Write the samples as CSV: `t [s]`, states, inputs, `ref_<output>`, `err_<output>`, each
/// with its unit where the model gives one. With the scenario's `output_step`, the rows of
/// the dense output between the samples are interleaved in time order and a last column
/// `sample` is 1 on the samples and 0 between them. Numbers are written plainly, in the
/// shortest decimal form that reads back to the same `f64` (no exponent: `0.05`, `0`,
/// `0.000001`).
///
/// # Errors
/// [`ScenarioError::Write`] when the file cannot be written.
pub fn write_trajectory(path: &Path, run: &RunResult) -> Result<(), ScenarioError> {
    let file = std::fs::File::create(path).map_err(|e| write_error(path, e))?;
    let mut out = std::io::BufWriter::new(file);
    let names = &run.names;
    let mut header = vec!["t [s]".to_string()];
    for n in names.states.iter().chain(&names.inputs) {
        header.push(column(n.clone(), names.unit(n)));
    }
    header.extend(
        names
            .outputs
            .iter()
            .map(|o| column(format!("ref_{o}"), names.unit(o))),
    );
    header.extend(
        names
            .outputs
            .iter()
            .map(|o| column(format!("err_{o}"), names.unit(o))),
    );
    let dense = run.scenario.output_step.is_some();
    if dense {
        header.push("sample".into());
    }
    writeln!(out, "{}", header.join(",")).map_err(|e| write_error(path, e))?;
    for p in run.closed_loop.trajectory() {
        let numbers = std::iter::once(p.t)
            .chain(p.x.iter().copied())
            .chain(p.u.iter().copied())
            .chain(p.reference.iter().copied())
            .chain(p.error.iter().copied());
        let mut first = true;
        for v in numbers {
            let separator = if first { "" } else { "," };
            first = false;
            write!(out, "{separator}{v}").map_err(|e| write_error(path, e))?;
        }
        if dense {
            write!(out, ",{}", u8::from(p.sample)).map_err(|e| write_error(path, e))?;
        }
        writeln!(out).map_err(|e| write_error(path, e))?;
    }
    out.flush().map_err(|e| write_error(path, e))
}
