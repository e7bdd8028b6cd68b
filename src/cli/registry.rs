//! The models a command line knows by name: a [`Registry`] of [`ScenarioModel`] trait
//! objects, each usually an [`Entry`] holding one concrete plant type, its tracking DAE, an
//! optional reference and a linear-solver factory.
//!
//! The trait object is only the door: [`ScenarioModel::run`] of an [`Entry`] calls
//! [`crate::cli::run::run`], a generic function monomorphised for the entry's plant, tracking DAE
//! and solver, so the controller's update and the plant integration run without dynamic
//! dispatch, as fast as hand-written code for that model.
//!
//! ```
//! use dpc::cli::registry::{Entry, Registry};
//! use dpc_models::{Wheel, WheelReference, WheelTracking};
//!
//! let registry = Registry::new().model(
//!     Entry::new("wheel", "the paper's rolling wheel", Wheel::default(), WheelTracking::default())
//!         .reference(WheelReference::default())
//!         .listing(WheelTracking::LISTING),
//! );
//! assert_eq!(registry.get("wheel").unwrap().name(), "wheel");
//! let err = registry.get("bicycle").err().unwrap().to_string();
//! assert_eq!(err, "unknown model `bicycle`; the known models are: wheel");
//! ```

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use dpc::core::linear_solver::{FaerDenseLu, LinearSolver};
use dpc::core::model::DaeModel;
use dpc::core::reference::Reference;
use dpc::core::TrackingDae;

use crate::cli::run::RunResult;
use crate::cli::scenario::Scenario;
use crate::cli::ScenarioError;
use dpc::core::simulate::{NoProgress, Progress};

/// A model a scenario can name: what `dpc models` lists, what `dpc model NAME` prints and
/// how a scenario is run on it. Implemented by [`Entry`]; other implementations (a plant read
/// from a file at run time) plug into the same [`Registry`].
pub trait ScenarioModel: Send + Sync {
    /// The name scenarios use (`model = "NAME"`).
    fn name(&self) -> &str;

    /// One line on what the model is.
    fn summary(&self) -> &str;

    /// A readable description: the model's listing (when it has one), its dimensions and
    /// names, and per output the relative degree and the `W` of the tracking DAE.
    fn describe(&self) -> String;

    /// Run `scenario` on this model; `label` names the run in reports.
    ///
    /// # Errors
    /// [`ScenarioError`] for a scenario that does not fit the model or a controller that
    /// cannot be set up; a run that starts and then diverges is not an error.
    fn run(&self, scenario: &Scenario, label: &str) -> Result<RunResult, ScenarioError>;

    /// [`run`](Self::run), telling `progress` of each sample of the closed loop as it is
    /// recorded (for a progress bar). The default runs without telling it.
    ///
    /// # Errors
    /// As [`run`](Self::run).
    fn run_with_progress(
        &self,
        scenario: &Scenario,
        label: &str,
        progress: &mut dyn Progress,
    ) -> Result<RunResult, ScenarioError> {
        let _ = progress;
        self.run(scenario, label)
    }
}

/// A linear-solver factory: one solver per run (runs of a sweep go in parallel).
type SolverFactory<L> = Box<dyn Fn() -> L + Send + Sync>;

/// One compiled model: a plant, its tracking DAE, optionally the model's own reference, and
/// the linear solver of the controller's Newton iteration (by default a dense LU sized at run
/// time, [`FaerDenseLu`]; a fixed-size [`dpc::core::linear_solver::NalgebraLu`] through
/// [`Entry::solver`] avoids every heap allocation in the update).
pub struct Entry<P, T, L = FaerDenseLu> {
    pub(crate) name: String,
    pub(crate) summary: String,
    pub(crate) plant: P,
    pub(crate) tracking: T,
    pub(crate) reference: Option<Arc<dyn Reference + Send + Sync>>,
    pub(crate) solver: SolverFactory<L>,
    pub(crate) listing: Option<String>,
}

impl<P, T> Entry<P, T, FaerDenseLu>
where
    P: DaeModel + Clone + Send + Sync + 'static,
    T: TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
{
    /// A model named `name` (as scenarios will write it) with a one-line `summary`. The
    /// plant's and the tracking DAE's parameters, and the tracking DAE's `W`, are the values a
    /// scenario starts from. Without [`reference`](Self::reference) scenarios must give a
    /// `[reference]` table.
    pub fn new(name: impl Into<String>, summary: impl Into<String>, plant: P, tracking: T) -> Self {
        let n = tracking.structure().n_equations();
        Self {
            name: name.into(),
            summary: summary.into(),
            plant,
            tracking,
            reference: None,
            solver: Box::new(move || FaerDenseLu::new(n)),
            listing: None,
        }
    }
}

impl<P, T, L> Entry<P, T, L> {
    /// The model's own reference, used when a scenario has no `[reference]` table.
    pub fn reference(mut self, reference: impl Reference + Send + Sync + 'static) -> Self {
        self.reference = Some(Arc::new(reference));
        self
    }

    /// The linear solver of the controller: `make` is called once per run and must return a
    /// solver of the tracking DAE's dimension (the run reports a mismatch as an error), for
    /// example `NalgebraLu::<{ CraneTracking::N_EQUATIONS }>::new`.
    pub fn solver<M: LinearSolver>(
        self,
        make: impl Fn() -> M + Send + Sync + 'static,
    ) -> Entry<P, T, M> {
        Entry {
            name: self.name,
            summary: self.summary,
            plant: self.plant,
            tracking: self.tracking,
            reference: self.reference,
            solver: Box::new(make),
            listing: self.listing,
        }
    }

    /// The listing `dpc model NAME` prints, usually the generated `LISTING` constant of the
    /// tracking type (which holds the plant's listing and the Hirschorn steps).
    pub fn listing(mut self, text: impl Into<String>) -> Self {
        self.listing = Some(text.into());
        self
    }
}

impl<P, T, L> ScenarioModel for Entry<P, T, L>
where
    P: DaeModel + Clone + Send + Sync + 'static,
    T: TrackingDae<Plant = P> + Clone + Send + Sync + 'static,
    L: LinearSolver + Send + 'static,
{
    fn name(&self) -> &str {
        &self.name
    }

    fn summary(&self) -> &str {
        &self.summary
    }

    fn describe(&self) -> String {
        describe(self)
    }

    fn run(&self, scenario: &Scenario, label: &str) -> Result<RunResult, ScenarioError> {
        crate::cli::run::run(self, scenario, label)
    }

    fn run_with_progress(
        &self,
        scenario: &Scenario,
        label: &str,
        progress: &mut dyn Progress,
    ) -> Result<RunResult, ScenarioError> {
        crate::cli::run::run_with_progress(self, scenario, label, progress)
    }
}

/// The text of `dpc model NAME` for an entry.
fn describe<P, T, L>(entry: &Entry<P, T, L>) -> String
where
    P: DaeModel,
    T: TrackingDae<Plant = P>,
    L: LinearSolver,
{
    let plant = entry.plant.structure();
    let tracking = entry.tracking.structure();
    let mut s = format!("{}: {}\n\n", entry.name, entry.summary);
    match &entry.listing {
        Some(listing) => {
            s += listing;
            if !listing.ends_with('\n') {
                s.push('\n');
            }
        }
        None => {
            s += &format!("model {}\n  equations\n", plant.name);
            for (i, e) in plant.equations.iter().enumerate() {
                s += &format!("    [{i}] {e}\n");
            }
            s += &format!("tracking {}\n  equations\n", tracking.name);
            for (i, e) in tracking.equations.iter().enumerate() {
                s += &format!("    [{i}] {e}\n");
            }
        }
    }
    let list = |names: &dpc::core::model::Names| {
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    };
    s += "\n";
    s += &format!("states ({}): {}\n", plant.n_states(), list(&plant.states));
    s += &format!(
        "algebraic unknowns ({}): {}\n",
        plant.n_algebraic(),
        list(&plant.algebraic)
    );
    s += &format!("inputs ({}): {}\n", plant.n_inputs(), list(&plant.inputs));
    let params: Vec<String> = plant
        .params
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            Some(format!(
                "{name} = {}",
                P::parameter(entry.plant.params(), i)?
            ))
        })
        .collect();
    s += &format!(
        "parameters: {}\n",
        if params.is_empty() {
            "none".into()
        } else {
            params.join(", ")
        }
    );
    s += &format!(
        "tracking DAE {}: {} equations in X and [Z; U]\n",
        tracking.name,
        tracking.n_equations()
    );
    for (i, output) in plant.outputs.iter().enumerate() {
        let degree = match entry.tracking.relative_degrees().get(i).copied().flatten() {
            Some(r) => r.to_string(),
            None => "undefined".to_string(),
        };
        let w = entry.tracking.w_coefficients(i);
        s += &format!(
            "  output {output}: relative degree {degree}, deg W = {}, W coefficients (lowest power first) [{}]\n",
            w.len().saturating_sub(1),
            w.iter()
                .map(|c| crate::cli::text::Num(*c).to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s += &match entry.tracking.remaining_relative_degree() {
        Some(nu) => format!("nu = {nu} unusable inner steps after a restart\n"),
        None => "nu is undefined: scenarios must set `nu`\n".to_string(),
    };
    s += &match &entry.reference {
        Some(r) => format!(
            "reference: the model's own ({} components, derivatives up to order {})\n",
            r.dimension(),
            r.max_order()
        ),
        None => "reference: none; scenarios must give a `[reference]` table\n".to_string(),
    };
    let solver = (entry.solver)();
    s += &format!(
        "linear solver: {} ({} x {})\n",
        std::any::type_name::<L>(),
        solver.dimension(),
        solver.dimension()
    );
    s
}

/// A model name that the registry does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown model `{name}`; the known models are: {}", known.join(", "))]
pub struct UnknownModel {
    /// The name asked for.
    pub name: String,
    /// The names the registry knows, in order.
    pub known: Vec<String>,
}

/// The models of a command line, in the order `dpc models` lists them; plant files that
/// scenarios name are read once and kept.
#[derive(Default)]
pub struct Registry {
    models: Vec<Box<dyn ScenarioModel>>,
    files: Mutex<Vec<(PathBuf, Arc<dyn ScenarioModel>)>>,
}

impl Registry {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// The registry with `model` added after the others (a later model of the same name is
    /// never found: the first one wins).
    pub fn model(mut self, model: impl ScenarioModel + 'static) -> Self {
        self.models.push(Box::new(model));
        self
    }

    /// The registry with an already boxed model added.
    pub fn boxed(mut self, model: Box<dyn ScenarioModel>) -> Self {
        self.models.push(model);
        self
    }

    /// The models, in order.
    pub fn models(&self) -> impl Iterator<Item = &dyn ScenarioModel> + '_ {
        self.models.iter().map(|m| m.as_ref())
    }

    /// The model called `name`.
    ///
    /// # Errors
    /// [`UnknownModel`] listing the known names.
    pub fn get(&self, name: &str) -> Result<&dyn ScenarioModel, UnknownModel> {
        self.models()
            .find(|m| m.name() == name)
            .ok_or_else(|| UnknownModel {
                name: name.to_string(),
                known: self.models().map(|m| m.name().to_string()).collect(),
            })
    }

    /// Run `scenario` on the model it names: a registered model, or a plant file (a `model`
    /// ending in `.dpc`, see [`crate::cli::plant_file`]).
    ///
    /// The whole loop as library calls: a scenario from text (with a nominal given in part,
    /// completed by the trim solver), the run, and what it found.
    ///
    /// ```
    /// use dpc::cli::registry::{Entry, Registry};
    /// use dpc::cli::scenario::{Overrides, Scenario};
    /// use dpc_models::{Wheel, WheelReference, WheelTracking};
    ///
    /// let registry = Registry::new().model(
    ///     Entry::new("wheel", "the paper's wheel", Wheel::default(), WheelTracking::default())
    ///         .reference(WheelReference::default()),
    /// );
    /// let text = r#"
    ///     model = "wheel"
    ///     x0 = [1.5707963267948966, 0.0, 0.0, 0.0, -6.0]
    ///     h = 0.05
    ///     t_end = 2.0
    ///     prefeedback = true
    ///     [design]
    ///     poles = [-5.0, -5.0, -5.0]
    ///     [design.nominal]   # upright, heading rate -6, no torque
    ///     state = { theta = 1.5707963267948966, psi = 0.0, dtheta = 0.0, dpsi = -6.0 }
    ///     rate = { theta = 0.0, dtheta = 0.0, dphi = 0.0, dpsi = 0.0 }
    ///     input = [0.0, 0.0]
    /// "#;
    /// let scenario = Scenario::parse("wheel.toml", text, &Overrides::default())?;
    /// let run = registry.run(&scenario, "main")?;
    /// let design = run.design.as_ref().expect("the scenario has a [design]");
    /// assert_eq!(design.nominal.solved_for, ["dphi", "der(psi)"]);
    /// assert!(!design.dpc_stable_without_prefeedback);
    /// assert!(run.closed_loop.divergence.is_none());
    /// # Ok::<(), dpc::cli::ScenarioError>(())
    /// ```
    ///
    /// # Errors
    /// [`ScenarioError::UnknownModel`], the errors of [`crate::cli::plant_file::load`] and those
    /// of [`ScenarioModel::run`].
    pub fn run(&self, scenario: &Scenario, label: &str) -> Result<RunResult, ScenarioError> {
        self.run_with_progress(scenario, label, &mut NoProgress)
    }

    /// [`run`](Self::run), telling `progress` of each sample of the closed loop (`dpc
    /// simulate` draws its bar from it, [`crate::cli::progress::RunProgress`]).
    ///
    /// # Errors
    /// As [`run`](Self::run).
    pub fn run_with_progress(
        &self,
        scenario: &Scenario,
        label: &str,
        progress: &mut dyn Progress,
    ) -> Result<RunResult, ScenarioError> {
        match crate::cli::plant_file::scenario_path(scenario) {
            Some(path) => self
                .plant_file(&path, &scenario.model)?
                .run_with_progress(scenario, label, progress),
            None => self
                .get(&scenario.model)
                .map_err(|cause| ScenarioError::UnknownModel {
                    origin: scenario.locate("model"),
                    cause,
                })?
                .run_with_progress(scenario, label, progress),
        }
    }

    /// The model of the plant file at `path`, read on first use (the runs of a sweep share
    /// it).
    fn plant_file(&self, path: &Path, name: &str) -> Result<Arc<dyn ScenarioModel>, ScenarioError> {
        // A panic elsewhere while the lock was held leaves the list intact: keep using it.
        let mut files = self.files.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, model)) = files.iter().find(|(p, _)| p == path) {
            return Ok(Arc::clone(model));
        }
        let model: Arc<dyn ScenarioModel> = crate::cli::plant_file::load(path, name)?.into();
        files.push((path.to_path_buf(), Arc::clone(&model)));
        Ok(model)
    }
}
