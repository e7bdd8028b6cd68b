//! One closed-loop run of a scenario on a registered model ([`crate::registry::Entry`]): set
//! the plant's and the controller's parameters by name and the roots of `W` at run time,
//! build the reference, design the preliminary feedback on the controller's model, build the
//! controller and simulate. [`run`] is generic over the plant, the tracking DAE and the linear
//! solver, so each model gets its own monomorphised copy of the loop.
//!
//! The design of the preliminary feedback (`SteadyMotion`, `w_roots`, `design`,
//! `sampled_prediction`, `feedback_nominal`, `copy_params`, `negated_real_roots`) is kept
//! together in the second half of this file.

use std::collections::BTreeMap;
use std::time::Instant;

use std::sync::Arc;

use dpc::core::dpc::{Dpc, DpcOptions};
use dpc::core::linalg::LinearSolver;
use dpc::core::linear::sampled::{CriticalPeriod, SampledLoop};
use dpc::core::linear::{analyze, Analysis, AnalysisOptions, LinearError, LinearSystem};
use dpc::core::linearize::{linearize, OperatingPoint};
use dpc::core::model::{self, set_parameter_by_name, DaeModel};
use dpc::core::prefeedback::{Nominal, Prefeedback, ReferenceNominal, ReferenceState};
use dpc::core::reference::{Components, Reference, ReferenceError};
use dpc::core::simulate::{simulate, ClosedLoop, ClosedLoopOptions};
use dpc::core::tracking::TrackingError;
use dpc::core::TrackingDae;
use dpc::nalgebra::DMatrix;
use serde::Serialize;

use crate::registry::Entry;
use crate::scenario::{scalar_reference, About, NominalMotion, Scenario};
use crate::ScenarioError;

/// Names of the model's variables, in order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Names {
    /// States.
    pub states: Vec<String>,
    /// Inputs.
    pub inputs: Vec<String>,
    /// Outputs.
    pub outputs: Vec<String>,
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
    /// Eigenvalues of `Abar_4` as `[re, im]`.
    pub abar4_eigenvalues: Vec<[f64; 2]>,
    /// Whether DPC without preliminary feedback is predicted stable (Theorem 3.2).
    pub dpc_stable_without_prefeedback: bool,
    /// Whether DPC after the preliminary feedback is predicted stable.
    pub dpc_stable_with_prefeedback: Option<bool>,
    /// `K_n`, row by row (inputs x states), when built.
    pub k_n: Option<Vec<Vec<f64>>>,
    /// The linear sampled-data prediction for the scenario's `h`, hold and feedback.
    pub sampled: SampledPrediction,
    /// `max |[A B](t_end) - [A B](0)| / max |[A B](0)|` along the nominal motion: zero when
    /// one linearisation (and so one constant `K_n`) serves the whole run, as for a steady
    /// motion in a cyclic coordinate.
    pub linearisation_drift: f64,
}

/// DPC's limit law on the linearisation, held by the scenario's zero-order hold
/// ([`dpc::core::linear::sampled`]).
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
    fn invalid(&self, message: String) -> ScenarioError {
        ScenarioError::Invalid {
            origin: format!("scenario for model `{}`", self.scenario.model),
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
            Err(self.invalid(format!(
                "`{what}` has {} entries, but model `{}` has {} ({})",
                v.len(),
                self.scenario.model,
                names.len(),
                names.join(", ")
            )))
        }
    }

    fn output_index(
        &self,
        what: &str,
        name: &str,
        outputs: &model::Names,
    ) -> Result<usize, ScenarioError> {
        outputs.position(name).ok_or_else(|| {
            self.invalid(format!(
                "`{what}.{name}`: model `{}` has no output `{name}`; its outputs are {}",
                self.scenario.model,
                outputs.join(", ")
            ))
        })
    }

    fn reference(
        &self,
        own: Option<Arc<dyn Reference + Send + Sync>>,
        outputs: &model::Names,
    ) -> Result<ScenarioReference, ScenarioError> {
        let Some(terms) = &self.scenario.reference else {
            return own.map(ScenarioReference::Model).ok_or_else(|| {
                self.invalid(format!(
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
                self.invalid(format!("`[reference]` has no entry for output `{name}`"))
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
            set_parameter_by_name(model, &mut params, name, *value)
                .map_err(|e| self.invalid(format!("`{what}.{name}`: {e}")))?;
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
                TrackingError::WrongDegree { expected, found, .. } => self.invalid(format!(
                    "`w.{name}` has {found} root(s), but model `{}` is compiled with deg W = {expected} for `{name}` (the degree decides the symbolic derivatives); only the roots can change at run time, more or fewer Hirschorn steps need a change of the model's `tracking` section",
                    self.scenario.model
                )),
                other => self.invalid(format!("`w.{name}` = {roots:?}: {other}")),
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
                self.invalid(format!(
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
                return Err(self.invalid(format!(
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

    let mut design_report = None;
    let mut k_n = None;
    if let Some(design) = &s.design {
        // The controller's model: the plant type with the controller's parameters, and
        // the W in use.
        let controller_model = P::from_params(copy_params(
            &tracking,
            tracking.params(),
            &model.plant,
            model.plant.params().clone(),
        ));
        let w = runner.w_roots(&tracking, outputs)?;
        let (report, k) = runner.design(&controller_model, &design.nominal, w)?;
        design_report = Some(report);
        k_n = k;
    }
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
        let design = s.design.as_ref().ok_or_else(|| {
            runner.invalid("`prefeedback = true` needs a `[design]` table".into())
        })?;
        let k_n = k_n.ok_or(ScenarioError::NoFeedbackGain)?;
        let nominal = &design.nominal;
        let motion = SteadyMotion {
            state: nominal.state.clone(),
            rate: nominal
                .rate
                .clone()
                .unwrap_or_else(|| vec![0.0; structure.n_states()]),
            input: nominal
                .input
                .clone()
                .unwrap_or_else(|| vec![0.0; structure.n_inputs()]),
        };
        dpc = dpc
            .with_prefeedback(Prefeedback {
                k_n,
                nominal: runner.feedback_nominal(&model.plant, motion, reference)?,
            })
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
        ..ClosedLoopOptions::default()
    };
    let start = Instant::now();
    let closed_loop =
        simulate(&plant, &mut dpc, &s.x0, &options).map_err(ScenarioError::Simulation)?;
    let wall_time = start.elapsed().as_secs_f64();

    Ok(RunResult {
        label: label.to_string(),
        scenario: s.clone(),
        names: Names {
            states: structure.states.to_vec(),
            inputs: structure.inputs.to_vec(),
            outputs: structure.outputs.to_vec(),
        },
        model: in_use,
        design: design_report,
        closed_loop,
        wall_time,
    })
}

// ---------------------------------------------------------------------------------------
// The design of the preliminary feedback: linearise the controller's model about the
// scenario's steady motion, analyse, build K_n and its nominal.
// ---------------------------------------------------------------------------------------

/// `x0(t) = state + t * rate`, `u0 = input`.
struct SteadyMotion {
    state: Vec<f64>,
    rate: Vec<f64>,
    input: Vec<f64>,
}

impl Nominal for SteadyMotion {
    fn state(&self, t: f64, x0: &mut [f64]) {
        for ((x, s), r) in x0.iter_mut().zip(&self.state).zip(&self.rate) {
            *x = s + t * r;
        }
    }
    fn input(&self, _t: f64, u0: &mut [f64]) {
        u0.copy_from_slice(&self.input);
    }
}

impl Runner<'_> {
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
                        self.invalid(format!(
                            "the model's W for `{name}` has complex roots, which the linear design cannot take; give `w.{name}`"
                        ))
                    })?,
                ),
            }
        }
        Ok(roots)
    }

    fn design<P: DaeModel>(
        &self,
        model: &P,
        nominal: &NominalMotion,
        w: Vec<Vec<f64>>,
    ) -> Result<(DesignReport, Option<DMatrix<f64>>), ScenarioError> {
        let structure = model.structure();
        let nx = structure.n_states();
        self.check_length("design.nominal.state", &nominal.state, &structure.states)?;
        let rate = nominal.rate.clone().unwrap_or_else(|| vec![0.0; nx]);
        self.check_length("design.nominal.rate", &rate, &structure.states)?;
        let input = nominal
            .input
            .clone()
            .unwrap_or_else(|| vec![0.0; structure.n_inputs()]);
        self.check_length("design.nominal.input", &input, &structure.inputs)?;
        if structure.n_algebraic() > 0 {
            return Err(self.invalid(format!(
                "a preliminary-feedback design for model `{}` needs its algebraic unknowns at the nominal point, which scenarios cannot give yet",
                self.scenario.model
            )));
        }
        let sys = linearize(
            model,
            OperatingPoint {
                t: 0.0,
                x: &nominal.state,
                xdot: &rate,
                z: &[],
                u: &input,
            },
        )
        .map_err(|e| ScenarioError::Setup(format!("linearisation about the nominal: {e}")))?;
        // K_n is designed at t = 0; how much the linearisation changes along the motion up
        // to t_end tells whether one constant K_n fits the whole run.
        let t_end = self.scenario.t_end;
        let x_end: Vec<f64> = nominal
            .state
            .iter()
            .zip(&rate)
            .map(|(x, r)| x + t_end * r)
            .collect();
        let sys_end = linearize(
            model,
            OperatingPoint {
                t: t_end,
                x: &x_end,
                xdot: &rate,
                z: &[],
                u: &input,
            },
        )
        .map_err(|e| {
            ScenarioError::Setup(format!(
                "linearisation along the nominal at t = {t_end}: {e}"
            ))
        })?;
        let scale = sys.a.amax().max(sys.b.amax()).max(f64::MIN_POSITIVE);
        let linearisation_drift = (&sys_end.a - &sys.a)
            .amax()
            .max((&sys_end.b - &sys.b).amax())
            / scale;
        let poles = self
            .scenario
            .design
            .as_ref()
            .and_then(|d| d.poles.as_ref())
            .map(|p| p.iter().map(|p| p.complex()).collect());
        let analysis = analyze(
            &sys,
            &AnalysisOptions {
                w: Some(w),
                poles,
                ..AnalysisOptions::default()
            },
        )
        .map_err(|e| ScenarioError::Setup(format!("linear analysis: {e}")))?;
        let k_n = analysis.k_n.clone();
        let report = DesignReport {
            abar4_eigenvalues: analysis
                .abar4_eigenvalues
                .iter()
                .map(|c| [c.re, c.im])
                .collect(),
            dpc_stable_without_prefeedback: analysis.dpc_stable,
            dpc_stable_with_prefeedback: analysis.dpc_stable_prefeedback,
            k_n: k_n
                .as_ref()
                .map(|k| k.row_iter().map(|r| r.iter().copied().collect()).collect()),
            sampled: self.sampled_prediction(&sys, &analysis)?,
            linearisation_drift,
        };
        Ok((report, k_n))
    }

    /// The sampled-data prediction of the linearised loop for this scenario: with the
    /// preliminary feedback only when the scenario applies it.
    fn sampled_prediction(
        &self,
        sys: &LinearSystem,
        analysis: &Analysis,
    ) -> Result<SampledPrediction, ScenarioError> {
        let s = self.scenario;
        let failed = |e: LinearError| ScenarioError::Setup(format!("sampled-data prediction: {e}"));
        let sampled = if s.prefeedback {
            SampledLoop::from_analysis(sys, analysis, s.hold)
        } else {
            SampledLoop::new(&sys.a, &sys.b, None, &analysis.k_j, s.hold)
        }
        .map_err(failed)?;
        Ok(SampledPrediction {
            spectral_radius: sampled.spectral_radius(s.h).map_err(failed)?,
            critical_period: sampled
                .critical_period(s.t_end.min(100.0 * s.h), 500, 1e-4)
                .map_err(failed)?,
        })
    }

    /// The nominal of the preliminary feedback: the designed motion, or, about the
    /// reference, that motion with the mapped states following the reference.
    fn feedback_nominal<P: DaeModel>(
        &self,
        plant: &P,
        motion: SteadyMotion,
        reference: Arc<ScenarioReference>,
    ) -> Result<Box<dyn Nominal + Send + Sync>, ScenarioError> {
        let Some(design) = &self.scenario.design else {
            return Ok(Box::new(motion));
        };
        if design.about == About::Nominal {
            return Ok(Box::new(motion));
        }
        let structure = plant.structure();
        let (states, outputs) = (&structure.states, &structure.outputs);
        let map = match &design.reference_state {
            Some(entries) => entries
                .iter()
                .map(|(state, target)| {
                    let state_index = states.position(state).ok_or_else(|| {
                        self.invalid(format!(
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
            return Err(self.invalid(format!(
                "`design.about = \"reference\"` needs `design.reference_state`: no output of model `{}` is a state",
                self.scenario.model
            )));
        }
        let nominal = ReferenceNominal::new(motion, reference, structure.n_states(), map)
            .map_err(|e| self.invalid(format!("`design.reference_state`: {e}")))?;
        Ok(Box::new(nominal))
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

/// The `a_k` of a monic `prod (s + a_k)` given lowest power first, if all roots are real.
fn negated_real_roots(coefficients: &[f64]) -> Option<Vec<f64>> {
    let n = coefficients.len().checked_sub(1)?;
    if n == 0 {
        return Some(Vec::new());
    }
    let lead = coefficients[n];
    // Companion matrix of the monic polynomial; its eigenvalues (Schur) are the roots.
    let companion = DMatrix::from_fn(n, n, |i, j| {
        if j == n - 1 {
            -coefficients[i] / lead
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let scale = coefficients.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
    let mut roots = Vec::with_capacity(n);
    for z in companion.complex_eigenvalues().iter() {
        if z.im.abs() > 1e-9 * (1.0 + scale) {
            return None;
        }
        roots.push(-z.re);
    }
    roots.sort_by(f64::total_cmp);
    Some(roots)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dpc::core::tracking::monic_from_negated_roots;

    #[test]
    fn roots_round_trip_through_coefficients() {
        let c = monic_from_negated_roots(&[2.0, 3.0]);
        assert_eq!(c, vec![6.0, 5.0, 1.0]);
        let r = negated_real_roots(&c).unwrap();
        assert!(
            (r[0] - 2.0).abs() < 1e-12 && (r[1] - 3.0).abs() < 1e-12,
            "{r:?}"
        );
        assert_eq!(negated_real_roots(&[5.0, 1.0]).unwrap(), vec![5.0]);
        // s^2 + 1 has imaginary roots.
        assert!(negated_real_roots(&[1.0, 0.0, 1.0]).is_none());
    }
}
