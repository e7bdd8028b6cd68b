//! One closed-loop run of a scenario on a registered model ([`crate::cli::registry::Entry`]): set
//! the plant's and the controller's parameters by name and the roots of `W` at run time,
//! build the reference, design the preliminary feedback on the controller's model, build the
//! controller and simulate. [`run`] is generic over the plant, the tracking DAE and the linear
//! solver, so each model gets its own monomorphised copy of the loop.
//!
//! The design of the preliminary feedback is [`dpc::core::design`]'s chain (trim ->
//! linearise -> analyse -> `K_n` -> law); the second half of this file only turns the
//! scenario's `[design]` table into its inputs (the trim problem, `W`, the poles, the nominal
//! the law is taken about) and its results into the [`DesignReport`].

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::design::{
    check_steady, design, trim, Design, DesignError, DesignOptions, Trim, TrimError, TrimOptions,
    TrimProblem, TrimValue,
};
use dpc::core::linear_analysis::sampled::CriticalPeriod;
use dpc::core::linear_analysis::AnalysisOptions;
use dpc::core::linear_solver::LinearSolver;
use dpc::core::model::{self, set_parameter_by_name, DaeModel, Structure};
use dpc::core::prefeedback::{ReferenceNominal, ReferenceState, SteadyMotion};
use dpc::core::reference::{Components, Reference, ReferenceError};
use dpc::core::simulate::{
    simulate_with_progress, ClosedLoop, ClosedLoopOptions, NoProgress, Progress, Sample,
    SimulateError,
};
use dpc::core::tracking::{negated_real_roots, TrackingError};
use dpc::core::TrackingDae;
use serde::Serialize;

use crate::cli::registry::Entry;
use crate::cli::scenario::{
    scalar_reference, About, Design as DesignTable, NominalMotion, Scenario, Values,
};
use crate::cli::ScenarioError;

/// Names of the model's variables, in order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Names {
    /// States.
    pub states: Vec<String>,
    /// Inputs.
    pub inputs: Vec<String>,
    /// Outputs.
    pub outputs: Vec<String>,
    /// The unit of each state, input and output that has one, by name (from the model).
    pub units: BTreeMap<String, String>,
}

impl Names {
    /// The unit of the variable `name`, if the model gives one.
    pub fn unit(&self, name: &str) -> Option<&str> {
        self.units.get(name).map(String::as_str)
    }
}

/// The parameters and `W` a run actually used, after the scenario's changes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelInUse {
    /// Every parameter of the simulated plant, by name.
    pub plant_params: BTreeMap<String, f64>,
    /// Every parameter of the controller's model, by name.
    pub controller_params: BTreeMap<String, f64>,
    /// Per output, the coefficients of `W_i(s)` in the controller, lowest power first.
    pub w_coefficients: BTreeMap<String, Vec<f64>>,
    /// The controller's retry ladder after the scenario's defaults were filled in.
    pub retry: RetryInUse,
}

/// The retry ladder of a run: `delta * growth^k` clamped to `max_delta`, at most `retries`
/// times per sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RetryInUse {
    /// Factor by which `delta` grows at each retry.
    pub growth: f64,
    /// The largest `delta` tried.
    pub max_delta: f64,
    /// The most retries per sample.
    pub retries: usize,
}

/// What the linear analysis of the controller's model said.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignReport {
    /// The nominal motion designed about, as the trim solver completed it.
    pub nominal: NominalReport,
    /// Eigenvalues of `Abar_4` as `[re, im]`.
    pub abar4_eigenvalues: Vec<[f64; 2]>,
    /// Whether DPC without preliminary feedback is predicted stable (Theorem 3.2).
    pub dpc_stable_without_prefeedback: bool,
    /// Whether DPC after the preliminary feedback is predicted stable.
    pub dpc_stable_with_prefeedback: Option<bool>,
    /// `K_n`, row by row (inputs x states, in the plant's own coordinates), when built.
    pub k_n: Option<Vec<Vec<f64>>>,
    /// The linear sampled-data prediction for the scenario's `h`, hold and feedback.
    pub sampled: SampledPrediction,
    /// `max |[A B](t_end) - [A B](0)| / max |[A B](0)|` along the nominal motion: zero when
    /// one linearisation (and so one constant `K_n`) serves the whole run, as for a steady
    /// motion in a cyclic coordinate.
    pub linearisation_drift: f64,
}

/// The nominal motion `x0(t) = state + t * rate`, `z0`, `u0` of a design, every entry by
/// name, and what the trim solver did to complete the scenario's partial specification.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NominalReport {
    /// `x0(0)` by state name.
    pub state: BTreeMap<String, f64>,
    /// `x0'` by state name.
    pub rate: BTreeMap<String, f64>,
    /// `z0` by name of the algebraic unknown.
    pub algebraic: BTreeMap<String, f64>,
    /// `u0` by input name.
    pub input: BTreeMap<String, f64>,
    /// The entries the scenario did not fix and the trim solver computed (`der(x)` for a
    /// rate), in the model's order.
    pub solved_for: Vec<String>,
    /// Gauss-Newton iterations of the trim solver.
    pub trim_iterations: usize,
    /// `max |F_i|` at the nominal.
    pub trim_residual: f64,
    /// Directions in which the equations leave the solved-for entries undetermined (the
    /// solver took the solution nearest the guess); `0` for a unique nominal.
    pub free_directions: usize,
    /// When the motion stops satisfying the equations before `t_end` (states that enter
    /// the equations move along their rates), the equations violated at `t_end`.
    pub not_steady: Option<String>,
}

/// DPC's limit law on the linearisation, held by the scenario's zero-order hold
/// ([`dpc::core::linear_analysis::sampled`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SampledPrediction {
    /// Spectral radius of the transition matrix over one period `h` (stable below 1).
    pub spectral_radius: f64,
    /// Where the predicted loop first loses stability as `h` grows (searched up to
    /// `min(t_end, 100 h)`).
    pub critical_period: CriticalPeriod,
}

/// The result of one run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// A label (the overrides that made this run, or "main").
    pub label: String,
    /// The scenario as run.
    pub scenario: Scenario,
    /// Variable names.
    pub names: Names,
    /// The model as run: parameters of the plant and of the controller, and `W`.
    pub model: ModelInUse,
    /// The linear analysis, when the scenario has a `[design]`.
    pub design: Option<DesignReport>,
    /// The closed loop.
    pub closed_loop: ClosedLoop,
    /// Wall-clock time of the simulation, in seconds.
    pub wall_time: f64,
}

struct Runner<'a> {
    scenario: &'a Scenario,
}

/// The scenario's reference: the model's own or one assembled from terms.
enum ScenarioReference {
    Model(Arc<dyn Reference + Send + Sync>),
    Terms(Components),
}

impl Reference for ScenarioReference {
    fn dimension(&self) -> usize {
        match self {
            Self::Model(r) => r.dimension(),
            Self::Terms(r) => r.dimension(),
        }
    }
    fn max_order(&self) -> usize {
        match self {
            Self::Model(r) => r.max_order(),
            Self::Terms(r) => r.max_order(),
        }
    }
    fn derivatives(&self, t: f64, order: usize, out: &mut [f64]) -> Result<(), ReferenceError> {
        match self {
            Self::Model(r) => r.derivatives(t, order, out),
            Self::Terms(r) => r.derivatives(t, order, out),
        }
    }
}

impl Runner<'_> {
    /// A scenario error about `key`, located where the file writes it.
    fn invalid(&self, key: &str, message: String) -> ScenarioError {
        ScenarioError::Invalid {
            origin: self.scenario.locate(key),
            message,
        }
    }

    fn check_length(
        &self,
        what: &str,
        v: &[f64],
        names: &model::Names,
    ) -> Result<(), ScenarioError> {
        if v.len() == names.len() {
            Ok(())
        } else {
            Err(self.invalid(
                what,
                format!(
                    "`{what}` has {} entries, but model `{}` has {} ({})",
                    v.len(),
                    self.scenario.model,
                    names.len(),
                    names.join(", ")
                ),
            ))
        }
    }

    fn output_index(
        &self,
        what: &str,
        name: &str,
        outputs: &model::Names,
    ) -> Result<usize, ScenarioError> {
        outputs.position(name).ok_or_else(|| {
            self.invalid(
                &format!("{what}.{name}"),
                format!(
                    "`{what}.{name}`: model `{}` has no output `{name}`; its outputs are {}",
                    self.scenario.model,
                    outputs.join(", ")
                ),
            )
        })
    }

    fn reference(
        &self,
        own: Option<Arc<dyn Reference + Send + Sync>>,
        outputs: &model::Names,
    ) -> Result<ScenarioReference, ScenarioError> {
        let Some(terms) = &self.scenario.reference else {
            return own.map(ScenarioReference::Model).ok_or_else(|| {
                self.invalid("model", format!(
                    "model `{}` declares no reference; give a `[reference]` table with a list of terms for each of {}",
                    self.scenario.model,
                    outputs.join(", ")
                ))
            });
        };
        for name in terms.keys() {
            self.output_index("reference", name, outputs)?;
        }
        let mut components = Vec::with_capacity(outputs.len());
        for name in outputs.iter() {
            let t = terms.get(name).ok_or_else(|| {
                self.invalid(
                    "reference",
                    format!("`[reference]` has no entry for output `{name}`"),
                )
            })?;
            components.push(scalar_reference(t));
        }
        let c = Components::new(outputs.len(), components).map_err(ScenarioError::Reference)?;
        Ok(ScenarioReference::Terms(c))
    }

    /// `params` with the scenario's values for `what` (`plant.params` or
    /// `controller.params`) set by name.
    fn params<P: DaeModel>(
        &self,
        model: &P,
        what: &str,
        mut params: P::Params,
        values: &BTreeMap<String, f64>,
    ) -> Result<P::Params, ScenarioError> {
        for (name, value) in values {
            set_parameter_by_name(model, &mut params, name, *value).map_err(|e| {
                self.invalid(&format!("{what}.{name}"), format!("`{what}.{name}`: {e}"))
            })?;
        }
        Ok(params)
    }

    /// Set the roots of `W` for each output the scenario lists.
    fn set_w<T: TrackingDae>(
        &self,
        tracking: &mut T,
        outputs: &model::Names,
    ) -> Result<(), ScenarioError> {
        for (name, roots) in &self.scenario.w {
            let i = self.output_index("w", name, outputs)?;
            tracking.set_w_roots(i, roots).map_err(|e| match e {
                TrackingError::WrongDegree { expected, found, .. } => self.invalid(&format!("w.{name}"), format!(
                    "`w.{name}` has {found} root(s), but model `{}` is compiled with deg W = {expected} for `{name}` (the degree decides the symbolic derivatives); only the roots can change at run time, more or fewer Hirschorn steps need a change of the model's `tracking` section",
                    self.scenario.model
                )),
                other => self.invalid(&format!("w.{name}"), format!("`w.{name}` = {}: {other}", crate::cli::text::excerpt(roots))),
            })?;
        }
        Ok(())
    }

    /// The retry ladder: the scenario's values, `max_delta` defaulting to `h` and the number
    /// of retries to the number that reaches `max_delta`.
    fn retry(&self) -> Result<RetryInUse, ScenarioError> {
        let s = self.scenario;
        let ladder = &s.controller.retry;
        let max_delta = ladder.max_delta.unwrap_or(s.h);
        let options = DpcOptions {
            delta: s.delta,
            retry_growth: ladder.growth,
            max_delta,
            ..DpcOptions::default()
        };
        let retries = match ladder.retries {
            Some(n) => n,
            None => options.retries_to_reach_max_delta().ok_or_else(|| {
                self.invalid("controller.retry", format!(
                    "`controller.retry`: no ladder from delta = {} with growth {} reaches max_delta = {max_delta}",
                    s.delta, ladder.growth
                ))
            })?,
        };
        Ok(RetryInUse {
            growth: ladder.growth,
            max_delta,
            retries,
        })
    }

    /// Per state, the scenario's bound `divergence.state.NAME` (unlisted states: none).
    fn state_bounds(&self, states: &model::Names) -> Result<Vec<Option<f64>>, ScenarioError> {
        let given = &self.scenario.divergence.state;
        for name in given.keys() {
            if states.position(name).is_none() {
                return Err(self.invalid(&format!("divergence.state.{name}"), format!(
                    "`divergence.state.{name}`: model `{}` has no state `{name}`; its states are {}",
                    self.scenario.model,
                    states.join(", ")
                )));
            }
        }
        Ok(states.iter().map(|name| given.get(name).copied()).collect())
    }

    /// Per output, the scenario's bound `divergence.output.NAME`, else
    /// `divergence.tracking_error`.
    fn tracking_bounds(&self, outputs: &model::Names) -> Result<Vec<Option<f64>>, ScenarioError> {
        let d = &self.scenario.divergence;
        for name in d.output.keys() {
            self.output_index("divergence.output", name, outputs)?;
        }
        Ok(outputs
            .iter()
            .map(|name| Some(d.output.get(name).copied().unwrap_or(d.tracking_error)))
            .collect())
    }
}

/// Every parameter of a model by name.
fn named_params<P: DaeModel>(model: &P, params: &P::Params) -> BTreeMap<String, f64> {
    model
        .structure()
        .params
        .iter()
        .enumerate()
        .filter_map(|(i, name)| Some((name.to_string(), P::parameter(params, i)?)))
        .collect()
}

/// Run `scenario` on `entry`, a model of plant type `P` with tracking DAE `T` and linear
/// solver `L` (monomorphised per model: no dynamic dispatch in the loop).
///
/// # Errors
/// [`ScenarioError`] for a scenario that does not fit the model or a controller that cannot
/// be set up. A run that starts and then diverges is not an error: see
/// [`ClosedLoop::divergence`].
pub fn run<P, T, L>(
    entry: &Entry<P, T, L>,
    scenario: &Scenario,
    label: &str,
) -> Result<RunResult, ScenarioError>
where
    P: DaeModel + Clone + Send + Sync + 'static,
    T: TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
    L: LinearSolver + Send + 'static,
{
    run_with_progress(entry, scenario, label, &mut NoProgress)
}

/// [`run`], telling `progress` of each sample of the closed loop as it is recorded.
///
/// # Errors
/// As [`run`].
pub fn run_with_progress<P, T, L>(
    entry: &Entry<P, T, L>,
    scenario: &Scenario,
    label: &str,
    progress: &mut dyn Progress,
) -> Result<RunResult, ScenarioError>
where
    P: DaeModel + Clone + Send + Sync + 'static,
    T: TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
    L: LinearSolver + Send + 'static,
{
    let runner = Runner { scenario };
    let model = entry;
    let s = runner.scenario;
    let structure = model.plant.structure();
    let outputs = &structure.outputs;
    runner.check_length("x0", &s.x0, &structure.states)?;
    // The registry's values are the starting point (a model may be registered with
    // non-default parameters); the scenario changes them by name.
    let plant_params = runner.params(
        &model.plant,
        "plant.params",
        model.plant.params().clone(),
        &s.plant.params,
    )?;
    let controller_params = runner.params(
        &model.tracking,
        "controller.params",
        model.tracking.params().clone(),
        &s.controller.params,
    )?;
    let plant = P::from_params(plant_params);
    let mut tracking = T::from_params(controller_params);
    for i in 0..outputs.len() {
        tracking
            .set_w_coefficients(i, model.tracking.w_coefficients(i))
            .map_err(ScenarioError::RegisteredW)?;
    }
    runner.set_w(&mut tracking, outputs)?;
    let in_use = ModelInUse {
        plant_params: named_params(&plant, plant.params()),
        controller_params: named_params(&tracking, tracking.params()),
        w_coefficients: outputs
            .iter()
            .enumerate()
            .map(|(i, name)| (name.to_string(), tracking.w_coefficients(i).to_vec()))
            .collect(),
        retry: runner.retry()?,
    };
    let reference = Arc::new(runner.reference(model.reference.clone(), outputs)?);

    // The design runs on the controller's model: the plant type with the controller's
    // parameters, and the W in use.
    let design = match &s.design {
        Some(table) => {
            let controller_model = P::from_params(copy_params(
                &tracking,
                tracking.params(),
                &model.plant,
                model.plant.params().clone(),
            ));
            Some(runner.design(&controller_model, &tracking, table)?)
        }
        None => None,
    };
    let mut dpc = Dpc::new(
        tracking,
        reference.clone(),
        (model.solver)(),
        DpcOptions {
            delta: s.delta,
            nu: s.nu,
            extraction: s.extraction,
            max_retries: in_use.retry.retries,
            retry_growth: in_use.retry.growth,
            max_delta: in_use.retry.max_delta,
            ..DpcOptions::default()
        },
    )
    .map_err(ScenarioError::Controller)?;
    if s.prefeedback {
        let (table, (_, designed)) = s.design.as_ref().zip(design.as_ref()).ok_or_else(|| {
            runner.invalid(
                "prefeedback",
                "`prefeedback = true` needs a `[design]` table".into(),
            )
        })?;
        let law = match table.about {
            About::Nominal => designed.prefeedback(),
            About::Reference => designed.prefeedback_about(runner.reference_nominal(
                &model.plant,
                table,
                designed.motion.clone(),
                reference,
            )?),
        }
        .map_err(ScenarioError::Design)?;
        dpc = dpc
            .with_prefeedback(law)
            .map_err(ScenarioError::Prefeedback)?;
    }
    let options = ClosedLoopOptions {
        h: s.h,
        t_end: s.t_end,
        rtol: s.plant.rtol,
        atol: s.plant.atol,
        hold: s.hold,
        state_bounds: runner.state_bounds(&structure.states)?,
        tracking_bounds: runner.tracking_bounds(outputs)?,
        max_consecutive_failures: s.plant.max_consecutive_failures,
        output_step: s.output_step,
        plant_integration: s.plant.integrator,
        ..ClosedLoopOptions::default()
    };
    let start = Instant::now();
    let mut closed_loop = simulate_with_progress(&plant, &mut dpc, &s.x0, &options, progress)
        .map_err(|e| match e {
            SimulateError::OutputStep { .. } => runner.invalid("output_step", e.to_string()),
            e => ScenarioError::Simulation(e),
        })?;
    if closed_loop.samples.is_empty() {
        closed_loop
            .samples
            .push(initial_sample(&plant, &dpc, &s.x0));
    }
    let wall_time = start.elapsed().as_secs_f64();

    Ok(RunResult {
        label: label.to_string(),
        scenario: s.clone(),
        names: Names {
            states: structure.states.to_vec(),
            inputs: structure.inputs.to_vec(),
            outputs: structure.outputs.to_vec(),
            units: structure
                .units
                .iter()
                .map(|(n, u)| (n.to_string(), u.to_string()))
                .collect(),
        },
        model: in_use,
        design: design.map(|(report, _)| report),
        closed_loop,
        wall_time,
    })
}

/// The sample at `t = 0` of a run that stopped before its first control (a state already
/// outside its bound): the outputs with no input applied yet (and the algebraic unknowns at
/// zero, as the closed loop starts them), the reference and the errors, so that the summary
/// reports the errors the run stopped with.
fn initial_sample<P, T, R, L>(plant: &P, dpc: &Dpc<T, R, L>, x0: &[f64]) -> Sample
where
    P: DaeModel,
    T: TrackingDae,
    R: Reference,
    L: LinearSolver,
{
    let structure = plant.structure();
    let u = vec![0.0; structure.n_inputs()];
    let mut y = vec![0.0; structure.n_outputs()];
    plant.outputs(0.0, x0, &vec![0.0; structure.n_algebraic()], &u, &mut y);
    let mut reference = vec![0.0; y.len()];
    let error = match dpc.reference().derivatives(0.0, 0, &mut reference) {
        Ok(()) => y.iter().zip(&reference).map(|(a, b)| a - b).collect(),
        Err(_) => vec![f64::NAN; y.len()],
    };
    Sample {
        t: 0.0,
        x: x0.to_vec(),
        u,
        y,
        reference,
        error,
    }
}

// ---------------------------------------------------------------------------------------
// The design of the preliminary feedback: the scenario's `[design]` table as the inputs of
// dpc::core::design's chain, and its results as a report.
// ---------------------------------------------------------------------------------------

impl Runner<'_> {
    /// Trim the scenario's nominal, linearise the controller's model about it, check the
    /// tracking DAE's relative degrees there, analyse, and predict the sampled loop.
    fn design<P: DaeModel, T: TrackingDae>(
        &self,
        model: &P,
        tracking: &T,
        table: &DesignTable,
    ) -> Result<(DesignReport, Design), ScenarioError> {
        let structure = model.structure();
        let problem = self.trim_problem(structure, &table.nominal)?;
        let trim_options = TrimOptions::default();
        let trimmed = trim(model, &problem, &trim_options)
            .map_err(|e| ScenarioError::Design(DesignError::Trim(e)))?;
        let t_end = self.scenario.t_end;
        let not_steady = match check_steady(model, &trimmed.motion, 0.0, t_end, &trim_options) {
            Ok(()) => None,
            Err(TrimError::NotSteady { t, equations, .. }) => {
                Some(format!("at t = {t} along the rates: {equations}"))
            }
            Err(e) => return Err(ScenarioError::Design(DesignError::Trim(e))),
        };
        let poles = table
            .poles
            .as_ref()
            .map(|p| p.iter().map(|p| p.complex()).collect());
        let designed = design(
            model,
            &trimmed.motion,
            &DesignOptions {
                analysis: AnalysisOptions {
                    w: Some(self.w_roots(tracking, &structure.outputs)?),
                    poles,
                    ..AnalysisOptions::default()
                },
                horizon: t_end,
                relative_degrees: tracking.relative_degrees().to_vec(),
            },
        )
        .map_err(ScenarioError::Design)?;
        let nominal = NominalReport::new(structure, &problem, &trimmed, not_steady);
        let analysis = &designed.analysis;
        let report = DesignReport {
            nominal,
            abar4_eigenvalues: analysis
                .abar4_eigenvalues
                .iter()
                .map(|c| [c.re, c.im])
                .collect(),
            dpc_stable_without_prefeedback: analysis.dpc_stable,
            dpc_stable_with_prefeedback: analysis.dpc_stable_prefeedback,
            // In the plant's own coordinates (for a constrained plant, the realisation's gain
            // mapped back), as the law applies it.
            k_n: designed
                .plant_gain()
                .ok()
                .map(|k| k.row_iter().map(|r| r.iter().copied().collect()).collect()),
            sampled: self.sampled_prediction(&designed)?,
            linearisation_drift: designed.linearisation_drift,
        };
        Ok((report, designed))
    }

    /// The trim problem of the scenario's nominal: arrays fix every entry, tables the named
    /// ones; see [`NominalMotion`] for the defaults and the guesses.
    fn trim_problem(
        &self,
        structure: &Structure,
        nominal: &NominalMotion,
    ) -> Result<TrimProblem, ScenarioError> {
        let s = self.scenario;
        let mut problem = TrimProblem::equilibrium(structure);
        // Free states start from the run's initial state, when it fits the model.
        if s.x0.len() == structure.n_states() {
            problem.state = s.x0.iter().map(|x| TrimValue::Free(*x)).collect();
        }
        let blocks: [(&str, &Option<Values>, &model::Names, &mut Vec<TrimValue>); 4] = [
            (
                "state",
                &nominal.state,
                &structure.states,
                &mut problem.state,
            ),
            ("rate", &nominal.rate, &structure.states, &mut problem.rate),
            (
                "algebraic",
                &nominal.algebraic,
                &structure.algebraic,
                &mut problem.algebraic,
            ),
            (
                "input",
                &nominal.input,
                &structure.inputs,
                &mut problem.input,
            ),
        ];
        for (what, given, names, slots) in blocks {
            let key = format!("design.nominal.{what}");
            match given {
                None => {}
                Some(Values::All(values)) => {
                    self.check_length(&key, values, names)?;
                    for (slot, v) in slots.iter_mut().zip(values) {
                        *slot = TrimValue::Fixed(*v);
                    }
                }
                Some(Values::Named(values)) => {
                    // Entries not named are solved for, starting from their defaults.
                    for slot in slots.iter_mut() {
                        *slot = TrimValue::Free(slot.value());
                    }
                    for (name, v) in values {
                        let i = names.position(name).ok_or_else(|| {
                            self.invalid(
                                &format!("{key}.{name}"),
                                format!(
                                    "`{key}.{name}`: model `{}` has no {} `{name}`; {}",
                                    self.scenario.model,
                                    kind_name(what),
                                    listed(what, names)
                                ),
                            )
                        })?;
                        slots[i] = TrimValue::Fixed(*v);
                    }
                }
            }
        }
        for (name, v) in &nominal.guess {
            let current = match problem.value(structure, name) {
                Ok(current) => current,
                Err(e) => {
                    return Err(self.invalid(
                        &format!("design.nominal.guess.{name}"),
                        format!("`design.nominal.guess.{name}`: {e}"),
                    ))
                }
            };
            if !current.is_free() {
                return Err(self.invalid(&format!("design.nominal.guess.{name}"), format!(
                    "`design.nominal.guess.{name}`: `{name}` is fixed by the nominal, a guess is for an entry the trim solver computes"
                )));
            }
            problem
                .set(structure, name, TrimValue::Free(*v))
                .map_err(|e| {
                    self.invalid(
                        &format!("design.nominal.guess.{name}"),
                        format!("`design.nominal.guess.{name}`: {e}"),
                    )
                })?;
        }
        Ok(problem)
    }

    /// The per-output roots of the `W` in use, for the analysis: the scenario's where given,
    /// else those of the controller's coefficients.
    fn w_roots<T: TrackingDae>(
        &self,
        tracking: &T,
        outputs: &model::Names,
    ) -> Result<Vec<Vec<f64>>, ScenarioError> {
        let mut roots = Vec::with_capacity(outputs.len());
        for (i, name) in outputs.iter().enumerate() {
            match self.scenario.w.get(name) {
                Some(r) => roots.push(r.clone()),
                None => roots.push(
                    negated_real_roots(tracking.w_coefficients(i)).ok_or_else(|| {
                        self.invalid("w", format!(
                            "the model's W for `{name}` has complex roots, which the linear design cannot take; give `w.{name}`"
                        ))
                    })?,
                ),
            }
        }
        Ok(roots)
    }

    /// The sampled-data prediction of the linearised loop for this scenario: with the
    /// preliminary feedback only when the scenario applies it.
    fn sampled_prediction(&self, designed: &Design) -> Result<SampledPrediction, ScenarioError> {
        let s = self.scenario;
        let failed = ScenarioError::SampledPrediction;
        let sampled = designed
            .sampled_loop(s.hold, s.prefeedback)
            .map_err(failed)?;
        Ok(SampledPrediction {
            spectral_radius: sampled.spectral_radius(s.h).map_err(failed)?,
            critical_period: sampled
                .critical_period(s.t_end.min(100.0 * s.h), 500, 1e-4)
                .map_err(failed)?,
        })
    }

    /// The designed motion with the states of `design.reference_state` following the
    /// reference (`about = "reference"`).
    fn reference_nominal<P: DaeModel>(
        &self,
        plant: &P,
        table: &DesignTable,
        motion: SteadyMotion,
        reference: Arc<ScenarioReference>,
    ) -> Result<ReferenceNominal<SteadyMotion, Arc<ScenarioReference>>, ScenarioError> {
        let structure = plant.structure();
        let (states, outputs) = (&structure.states, &structure.outputs);
        let map = match &table.reference_state {
            Some(entries) => entries
                .iter()
                .map(|(state, target)| {
                    let state_index = states.position(state).ok_or_else(|| {
                        self.invalid(&format!("design.reference_state.{state}"), format!(
                            "`design.reference_state.{state}`: model `{}` has no state `{state}`; its states are {}",
                            self.scenario.model,
                            states.join(", ")
                        ))
                    })?;
                    let name = target.trim_end_matches('\'');
                    let order = target.len() - name.len();
                    let output = self.output_index("design.reference_state", name, outputs)?;
                    Ok(ReferenceState {
                        state: state_index,
                        output,
                        order,
                    })
                })
                .collect::<Result<Vec<_>, ScenarioError>>()?,
            None => outputs
                .iter()
                .enumerate()
                .filter_map(|(output, name)| {
                    states.position(name).map(|state| ReferenceState {
                        state,
                        output,
                        order: 0,
                    })
                })
                .collect(),
        };
        if map.is_empty() {
            return Err(self.invalid("design.about", format!(
                "`design.about = \"reference\"` needs `design.reference_state`: no output of model `{}` is a state",
                self.scenario.model
            )));
        }
        ReferenceNominal::new(motion, reference, structure.n_states(), map).map_err(|e| {
            self.invalid(
                "design.reference_state",
                format!("`design.reference_state`: {e}"),
            )
        })
    }
}

/// What a vector's entries are called, for messages.
fn kind_name(what: &str) -> &'static str {
    match what {
        "algebraic" => "algebraic unknown",
        "input" => "input",
        _ => "state",
    }
}

/// `its states are a, b` (or `it has none`), for messages.
fn listed(what: &str, names: &model::Names) -> String {
    let plural = match what {
        "algebraic" => "algebraic unknowns",
        "input" => "inputs",
        _ => "states",
    };
    if names.is_empty() {
        format!("it has no {plural}")
    } else {
        format!("its {plural} are {}", names.join(", "))
    }
}

impl NominalReport {
    fn new(
        structure: &Structure,
        problem: &TrimProblem,
        trimmed: &Trim,
        not_steady: Option<String>,
    ) -> Self {
        let by_name = |names: &model::Names, values: &[f64]| -> BTreeMap<String, f64> {
            names
                .iter()
                .zip(values)
                .map(|(n, v)| (n.to_string(), *v))
                .collect()
        };
        let m = &trimmed.motion;
        let mut solved_for = Vec::new();
        for (names, entries, rate) in [
            (&structure.states, &problem.state, false),
            (&structure.states, &problem.rate, true),
            (&structure.algebraic, &problem.algebraic, false),
            (&structure.inputs, &problem.input, false),
        ] {
            for (name, entry) in names.iter().zip(entries) {
                if entry.is_free() {
                    solved_for.push(if rate {
                        format!("der({name})")
                    } else {
                        name.to_string()
                    });
                }
            }
        }
        Self {
            state: by_name(&structure.states, &m.state),
            rate: by_name(&structure.states, &m.rate),
            algebraic: by_name(&structure.algebraic, &m.algebraic),
            input: by_name(&structure.inputs, &m.input),
            solved_for,
            trim_iterations: trimmed.iterations,
            trim_residual: trimmed.residual,
            free_directions: trimmed.free_directions(),
            not_steady,
        }
    }
}

/// `into` with every parameter of `from` copied by name. A tracking DAE shares its plant's
/// parameter type, but generic code cannot name that equality, so values go by name.
fn copy_params<A: DaeModel, B: DaeModel>(
    a: &A,
    from: &A::Params,
    b: &B,
    mut into: B::Params,
) -> B::Params {
    let target = b.structure();
    for (i, name) in a.structure().params.iter().enumerate() {
        if let (Some(value), Some(j)) = (A::parameter(from, i), target.parameter_index(name)) {
            B::set_parameter(&mut into, j, value);
        }
    }
    into
}
