//! Scenario files: one closed-loop DPC run described in TOML.
//!
//! ```toml
//! title = "The paper's wheel (Section 5)"
//! model = "wheel"                 # see `dpc models`
//! x0 = [1.5707963267948966, 0.0, 0.0, 0.0, -6.0]
//! h = 0.05                        # sampling period
//! t_end = 20.0
//! delta = 1e-3                    # inner implicit-Euler step of the controller
//! output_step = 0.01              # optional: trajectory.csv also between samples
//! extraction = "extrapolated"     # or "first-usable"
//! hold = "input"                  # or "correction": prefeedback continuous, only v held
//! prefeedback = true
//!
//! [w]                             # per output: the a_k of W(s) = prod (s + a_k)
//! theta = [5.0]
//! psi = [5.0]
//!
//! [design]                        # how K_n is built (needed when prefeedback = true)
//! poles = [-5.0, -5.0, -5.0]      # of Abar_4 + Bbar_2 K_2; a real or [re, im] each
//! nominal = { state = [1.5707963267948966, 0.0, 0.0, 0.0, -6.0], rate = [0.0, -6.0, 0.0, 0.0, 0.0], input = [0.0, 0.0] }
//!                                 # or in part, the rest trimmed: see NominalMotion
//! about = "reference"             # or "nominal" (default): where x - x0(t) is taken
//! reference_state = { theta = "theta", psi = "psi", dtheta = "theta'", dpsi = "psi'" }
//!
//! [divergence]                    # when the run counts as diverged
//! tracking_error = 1e3            # bound on |y_i - ref_i| for every output (default 1e3)
//! output = { theta = 0.5 }        # per-output bounds replacing it
//! state = { dphi = 100.0 }        # per-state |x_i| bounds; other states: only NaN/Inf
//!
//! [controller.retry]              # the retry ladder delta * growth^k, clamped to max_delta
//! growth = 4.0                    # default 4
//! max_delta = 0.05                # default: h
//! retries = 5                     # default: as many as reach max_delta
//!
//! [limits]                        # the work of one run, checked before it starts
//! samples = 100000                # t_end / h + 1 (default 100000)
//! rows = 1000000                  # rows of trajectory.csv (default 1000000)
//! nu = 20                         # largest nu (default 20)
//! retries = 100                   # retry-ladder steps per sample (default 100)
//! ```
//!
//! Every key is documented on [`Scenario`]; unknown keys are errors. The reference defaults to
//! the model's own `references` section; a `[reference]` table replaces it with a sum of
//! terms per output. `[plant]` sets the simulated plant's tolerances and parameters (a plant
//! that differs from the controller's model, for mismatch studies), `[controller]` the
//! controller model's parameters and its retry ladder, `[divergence]` the bounds that stop a
//! run, `[limits]` the sizes a run may reach ([`Limits`]).
//!
//! [`Overrides`] change any key from the command line (`--set h=0.1`,
//! `--set plant.params.m=1.2`): the same mechanism runs sweeps and the comparison runs that
//! `compare` lists.

use std::collections::BTreeMap;
use std::path::Path;

use dpc::core::controller::Extraction;
use dpc::core::reference::{AtanIntegral, Constant, Polynomial, ScalarReference, Sinusoid, Sum};
use dpc::core::simulate::{ClosedLoopOptions, Hold, PlantIntegration, MIN_OUTPUT_STEP_RATIO};
use dpc::nalgebra::Complex;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::cli::location::Source;
use crate::cli::text::{excerpt, short, Num};
use crate::cli::ScenarioError;

/// One closed-loop run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// A title for plots and summaries.
    #[serde(default)]
    pub title: Option<String>,
    /// The model's name (see `dpc models`), or the path of a plant file ending in `.dpc`,
    /// relative to the scenario file (see [`crate::cli::plant_file`]).
    pub model: String,
    /// Initial plant state.
    pub x0: Vec<f64>,
    /// Sampling period `h` of the controller.
    pub h: f64,
    /// End time of the run.
    pub t_end: f64,
    /// Inner implicit-Euler step `delta` of the controller.
    #[serde(default = "default_delta")]
    pub delta: f64,
    /// When set, `trajectory.csv` records the plant's motion between the samples too, every
    /// `output_step` time units (interpolated inside the plant integrator's steps; the samples
    /// are unchanged), with a `sample` column telling sample rows (1) from the rows between
    /// them (0). See [`ClosedLoopOptions::output_step`](dpc::core::simulate::ClosedLoopOptions::output_step).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_step: Option<f64>,
    /// How the control is extracted from the inner integration.
    #[serde(default)]
    pub extraction: Extraction,
    /// What the zero-order hold keeps.
    #[serde(default)]
    pub hold: Hold,
    /// Override of `nu` (default: from the model's relative degrees).
    #[serde(default)]
    pub nu: Option<usize>,
    /// Whether the preliminary feedback built from `[design]` is applied.
    #[serde(default)]
    pub prefeedback: bool,
    /// Per output name, the numbers `a_k` of `W(s) = prod (s + a_k)`, set at run time: as
    /// many as the model's compiled degree of `W` for that output (only the roots can change;
    /// the degree is the model's `tracking` section), each `>= 0`. Outputs not listed keep
    /// the model's `W`.
    #[serde(default)]
    pub w: BTreeMap<String, Vec<f64>>,
    /// Per output name, a sum of reference terms; absent: the model's own references.
    #[serde(default)]
    pub reference: Option<BTreeMap<String, Vec<Term>>>,
    /// The preliminary-feedback design.
    #[serde(default)]
    pub design: Option<Design>,
    /// The simulated plant.
    #[serde(default)]
    pub plant: PlantOptions,
    /// The controller's model and its retry ladder.
    #[serde(default)]
    pub controller: ControllerOptions,
    /// When the run counts as diverged: bounds on the tracking errors and on chosen states.
    #[serde(default)]
    pub divergence: DivergenceOptions,
    /// Override sets (`"key=value"`, several separated by `;`) for comparison runs drawn
    /// beside the main run in the plots, e.g. `["prefeedback=false"]`.
    #[serde(default)]
    pub compare: Vec<String>,
    /// Bounds on the work of one run, checked before it starts.
    #[serde(default)]
    pub limits: Limits,
    /// The file and text the scenario was read from (not a key): a plant file's path is
    /// relative to it, and errors about a key give its line and column in it.
    #[serde(skip)]
    pub source: Option<Source>,
}

/// Bounds on the work and memory of one run, checked before the run starts so that a typo
/// such as `t_end = 1e12` is an error naming the key instead of a run that never ends. Each
/// can be raised deliberately (`--set limits.samples=10000000`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limits {
    /// The most samples of a run, `t_end / h + 1` (default 100000): the run keeps every
    /// sample and writes it to `trajectory.csv`, so memory, time and output grow with it.
    #[serde(default = "default_max_samples")]
    pub samples: u64,
    /// The largest `nu` (default 20): every sample integrates `nu + 2` inner steps, and the
    /// round-off of the extracted control grows like `eps * delta^-nu`.
    #[serde(default = "default_max_nu")]
    pub nu: usize,
    /// The most retries of the retry ladder per sample (default 100).
    #[serde(default = "default_max_retries")]
    pub retries: usize,
    /// The most rows of `trajectory.csv` (default 1000000): the samples and, with
    /// `output_step`, the points between them, all kept in memory until written.
    #[serde(default = "default_max_rows")]
    pub rows: u64,
}

fn default_max_samples() -> u64 {
    100_000
}
fn default_max_nu() -> usize {
    20
}
fn default_max_retries() -> usize {
    100
}
fn default_max_rows() -> u64 {
    1_000_000
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            samples: default_max_samples(),
            nu: default_max_nu(),
            retries: default_max_retries(),
            rows: default_max_rows(),
        }
    }
}

/// The largest magnitude accepted for a pole or a root of `W`: `sqrt(f64::MAX)`, beyond
/// which the product of two such numbers (a gain, a coefficient of `W`) overflows.
pub fn largest_magnitude() -> f64 {
    f64::MAX.sqrt()
}

/// A value of a scenario (or of a system file) that is out of range, by the key the user
/// wrote.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ValueError {
    /// A time, step or tolerance is not a positive finite number.
    #[error("`{key}` must be a positive finite number, found {}", Num(*value))]
    NotPositive {
        /// The key.
        key: String,
        /// Its value.
        value: f64,
    },
    /// A bound is NaN or not positive (infinity is allowed: no check).
    #[error("`{key}` must be a positive number (or inf), found {}", Num(*value))]
    NotPositiveBound {
        /// The key.
        key: String,
        /// Its value.
        value: f64,
    },
    /// The plant's relative tolerance cannot be met (below the machine epsilon) or asks for
    /// no accuracy (1 or more).
    #[error("`plant.rtol` must lie between the machine epsilon {:.1e} and 1, found {}", f64::EPSILON, Num(*value))]
    Tolerance {
        /// The tolerance given.
        value: f64,
    },
    /// The retry ladder's growth is not above 1.
    #[error("`controller.retry.growth` must be a number above 1, found {}", Num(*value))]
    Growth {
        /// The growth given.
        value: f64,
    },
    /// One value must not exceed (or reach) another.
    #[error("`{key}` ({}) must be {relation} `{other}` ({})", Num(*value), Num(*other_value))]
    Order {
        /// The key.
        key: &'static str,
        /// Its value.
        value: f64,
        /// `"at least"`, `"smaller than"`, `"at most"`.
        relation: &'static str,
        /// The other key.
        other: &'static str,
        /// Its value.
        other_value: f64,
    },
    /// An entry of a list is NaN or infinite.
    #[error("`{key}` has a non-finite entry {} at index {index}: {}", Num(*value), excerpt(values))]
    NonFinite {
        /// The key.
        key: String,
        /// The entry's index.
        index: usize,
        /// The entry.
        value: f64,
        /// The list (quoted as a short excerpt).
        values: Vec<f64>,
    },
    /// A single value is NaN or infinite.
    #[error("`{key}` is non-finite ({})", Num(*value))]
    NotFinite {
        /// The key, with the index of the entry (`design.poles[0]`).
        key: String,
        /// The value.
        value: f64,
    },
    /// A pole or a root of `W` (or a coefficient made from them) is too large to compute with.
    #[error("`{key}` = {} is beyond {limit:.1e} in magnitude, where products with it overflow; scale the problem or choose a smaller value", Num(*value))]
    TooLarge {
        /// The key, with the index of the entry (`w.theta[0]`).
        key: String,
        /// The value.
        value: f64,
        /// The largest magnitude accepted ([`largest_magnitude`]).
        limit: f64,
    },
    /// A non-zero entry of a system matrix is too small to compute with.
    #[error("`{key}` = {} is below {limit:.1e} in magnitude (and not zero), where products with it underflow to zero; scale the system", Num(*value))]
    TooSmall {
        /// The key, with the indices of the entry (`b[2][0]`).
        key: String,
        /// The value.
        value: f64,
        /// The smallest non-zero magnitude accepted, `sqrt(f64::MIN_POSITIVE)`.
        limit: f64,
    },
    /// A size that sets the work of the run exceeds its limit.
    #[error("{what} exceeds the limit `limits.{limit_key}` = {limit}; raise it deliberately (`--set limits.{limit_key}=N`) if the run is meant to be this large")]
    Limit {
        /// The key whose value sets the size (`t_end`, `nu`, `delta`).
        key: &'static str,
        /// What is too large, with its value (`` `t_end` / `h` gives 5e13 samples ``).
        what: String,
        /// The key of the limit under `[limits]`.
        limit_key: &'static str,
        /// The limit in force.
        limit: u64,
    },
    /// A reference term has a non-finite coefficient.
    #[error("`reference.{output}` has a non-finite coefficient")]
    Reference {
        /// The output.
        output: String,
    },
    /// The preliminary feedback is on but nothing says how to design it.
    #[error("`prefeedback = true` needs a `[design]` table with the nominal motion")]
    NoDesign,
    /// An entry of `compare` is malformed.
    #[error("`compare`: {0}")]
    Compare(Box<ScenarioError>),
}

impl ValueError {
    /// The key the error is about, as the user wrote it (`design.poles[0]`), to locate it in
    /// the file; `None` when the cause is an entry of `compare` (which carries its own).
    pub fn key(&self) -> Option<String> {
        match self {
            Self::NotPositive { key, .. }
            | Self::NotPositiveBound { key, .. }
            | Self::NonFinite { key, .. }
            | Self::NotFinite { key, .. }
            | Self::TooLarge { key, .. }
            | Self::TooSmall { key, .. } => Some(key.clone()),
            Self::Order { key, .. } | Self::Limit { key, .. } => Some((*key).to_string()),
            Self::Tolerance { .. } => Some("plant.rtol".into()),
            Self::Growth { .. } => Some("controller.retry.growth".into()),
            Self::Reference { output } => Some(format!("reference.{output}")),
            Self::NoDesign => Some("prefeedback".into()),
            Self::Compare(_) => None,
        }
    }
}

/// Every entry of `values` finite.
fn check_finite(key: &str, values: &[f64]) -> Result<(), ValueError> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(index) => Err(ValueError::NonFinite {
            key: key.to_string(),
            index,
            value: values[index],
            values: values.to_vec(),
        }),
    }
}

/// A count computed in floating point: whole below `1e9`, else three digits.
fn count(n: f64) -> String {
    if n < 1e9 {
        format!("{n:.0}")
    } else {
        format!("{n:.2e}")
    }
}

/// One value finite.
fn finite_scalar(key: &str, value: f64) -> Result<(), ValueError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ValueError::NotFinite {
            key: key.to_string(),
            value,
        })
    }
}

/// One value finite and at most [`largest_magnitude`] in magnitude.
pub(crate) fn check_scalar(key: &str, value: f64) -> Result<(), ValueError> {
    finite_scalar(key, value)?;
    if value.abs() > largest_magnitude() {
        Err(ValueError::TooLarge {
            key: key.to_string(),
            value,
            limit: largest_magnitude(),
        })
    } else {
        Ok(())
    }
}

/// The roots `a_k` of `W(s) = prod (s + a_k)`, and the coefficients of `W` they make, finite
/// and at most [`largest_magnitude`] in magnitude.
pub(crate) fn check_w_roots(key: &str, roots: &[f64]) -> Result<(), ValueError> {
    for (i, root) in roots.iter().enumerate() {
        check_scalar(&format!("{key}[{i}]"), *root)?;
    }
    let coefficients = dpc::core::tracking::monic_from_negated_roots(roots);
    for (power, c) in coefficients.iter().enumerate() {
        check_scalar(&format!("{key}` as the coefficient of s^{power} of `W"), *c)?;
    }
    Ok(())
}

fn default_delta() -> f64 {
    1e-3
}

/// One term of a scalar reference.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Term {
    /// A constant.
    Constant(f64),
    /// `sum_j c_j t^j`, coefficients lowest power first.
    Polynomial(Vec<f64>),
    /// `amplitude * sin(omega t + phase)`.
    Sine {
        /// Amplitude.
        amplitude: f64,
        /// Angular frequency, in rad/s.
        omega: f64,
        /// Phase, in rad.
        #[serde(default)]
        phase: f64,
    },
    /// `scale * (t atan t - ln(1 + t^2) / 2)`, the integral of `scale * atan t`.
    AtanIntegral {
        /// The factor.
        scale: f64,
    },
}

impl Term {
    fn scalar(&self) -> Box<dyn ScalarReference + Send + Sync> {
        match self {
            Term::Constant(c) => Box::new(Constant(*c)),
            Term::Polynomial(c) => Box::new(Polynomial(c.clone())),
            Term::Sine {
                amplitude,
                omega,
                phase,
            } => Box::new(Sinusoid {
                offset: 0.0,
                amplitude: *amplitude,
                omega: *omega,
                phase: *phase,
            }),
            Term::AtanIntegral { scale } => Box::new(AtanIntegral { scale: *scale }),
        }
    }

    fn is_finite(&self) -> bool {
        match self {
            Term::Constant(c) => c.is_finite(),
            Term::Polynomial(c) => c.iter().all(|v| v.is_finite()),
            Term::Sine {
                amplitude,
                omega,
                phase,
            } => amplitude.is_finite() && omega.is_finite() && phase.is_finite(),
            Term::AtanIntegral { scale } => scale.is_finite(),
        }
    }
}

/// The sum of `terms` as one scalar reference.
pub fn scalar_reference(terms: &[Term]) -> Box<dyn ScalarReference + Send + Sync> {
    Box::new(Sum(terms.iter().map(Term::scalar).collect()))
}

/// A real pole or an `[re, im]` pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "a real number or an [re, im] pair")]
pub enum Pole {
    /// A real pole.
    Real(f64),
    /// A complex pole (its conjugate must be listed too).
    Complex([f64; 2]),
}

impl Pole {
    /// As a complex number.
    pub fn complex(self) -> Complex<f64> {
        match self {
            Pole::Real(r) => Complex::new(r, 0.0),
            Pole::Complex([re, im]) => Complex::new(re, im),
        }
    }
}

/// How the preliminary feedback is designed: the linearisation of the controller's model
/// along a steady motion, and the poles of `Abar_4 + Bbar_2 K_2`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Design {
    /// Poles of `Abar_4 + Bbar_2 K_2`; absent: the analysis' default.
    #[serde(default)]
    pub poles: Option<Vec<Pole>>,
    /// The nominal motion `x0(t) = state + t * rate`, `z0`, `u0`, in full or in part (the
    /// rest trimmed); absent: the equilibrium nearest `x0`.
    #[serde(default)]
    pub nominal: NominalMotion,
    /// Where the deviation coordinates `x - x0(t)` of the feedback are taken.
    #[serde(default)]
    pub about: About,
    /// Used with `about = "reference"` (ignored otherwise): per state name, the output whose reference it follows,
    /// with one `'` per derivative (`dtheta = "theta'"`). Absent: every output that is also
    /// a state follows its own reference.
    #[serde(default)]
    pub reference_state: Option<BTreeMap<String, String>>,
}

/// Where the preliminary feedback `u = u0 + K_n (x - x0(t)) + v` takes its deviation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum About {
    /// `x0(t)` is the nominal motion the feedback was designed on (the paper's choice).
    #[default]
    Nominal,
    /// The states listed in `reference_state` follow the reference and its derivatives.
    Reference,
}

/// A steady nominal motion `x0(t) = state + t * rate` with constant algebraic unknowns `z0`
/// and input `u0`, given in full or in part: what is not given is solved for by the trim
/// solver ([`dpc::core::design::trim`]) so that the model's equations hold at `t = 0`.
///
/// Each of `state`, `rate`, `algebraic` and `input` is either an array (every entry fixed)
/// or a table by name (the named entries fixed, the others solved for). Absent `state`,
/// `algebraic` or `input`: solved for; absent `rate`: all zero (an equilibrium). `guess`
/// gives starting values for entries that are solved for, by name (`der(psi)` for a rate);
/// states without a guess start from `x0`, everything else from zero.
///
/// ```toml
/// [design.nominal]                  # the wheel upright, heading rate -6, no torque
/// state = { theta = 1.5707963267948966, psi = 0.0, dtheta = 0.0, dpsi = -6.0 }
/// rate = { theta = 0.0, dtheta = 0.0, dphi = 0.0, dpsi = 0.0 }
/// input = [0.0, 0.0]
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NominalMotion {
    /// `x0(0)`.
    #[serde(default)]
    pub state: Option<Values>,
    /// `x0'`, constant.
    #[serde(default)]
    pub rate: Option<Values>,
    /// `z0`, constant.
    #[serde(default)]
    pub algebraic: Option<Values>,
    /// `u0`, constant.
    #[serde(default)]
    pub input: Option<Values>,
    /// Starting values of entries that are solved for, by name.
    #[serde(default)]
    pub guess: BTreeMap<String, f64>,
}

/// Values of a vector of the model: all of them in order, or some of them by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "an array of numbers (every entry, in the model's order) or a table of NAME = number (some entries by name)"
)]
pub enum Values {
    /// Every entry, in the model's order.
    All(Vec<f64>),
    /// Some entries, by name.
    Named(BTreeMap<String, f64>),
}

/// The simulated plant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlantOptions {
    /// Relative tolerance of the integration between samples.
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Absolute tolerance of the integration between samples.
    #[serde(default = "default_atol")]
    pub atol: f64,
    /// The run counts as diverged after this many consecutive failed controller updates.
    #[serde(default = "default_failures")]
    pub max_consecutive_failures: usize,
    /// Parameters of the simulated plant that differ from the model's, by name (the
    /// controller keeps its own); an unknown name is an error listing the model's parameters.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// The integrator between samples of a plant without constraints: `auto` (Radau IIA),
    /// `bdf` or `radau` (a constrained plant always uses Radau IIA).
    #[serde(default)]
    pub integrator: PlantIntegration,
}

fn default_rtol() -> f64 {
    1e-8
}
fn default_atol() -> f64 {
    1e-10
}
fn default_failures() -> usize {
    3
}

impl Default for PlantOptions {
    fn default() -> Self {
        Self {
            rtol: default_rtol(),
            atol: default_atol(),
            max_consecutive_failures: default_failures(),
            params: BTreeMap::new(),
            integrator: PlantIntegration::Auto,
        }
    }
}

/// The controller's model and its retry ladder.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerOptions {
    /// Parameters of the controller's model (its tracking DAE and the linear design) that
    /// differ from the model's, by name.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// What the controller does when the first implicit-Euler step from the measured state
    /// has no solution at `delta`.
    #[serde(default)]
    pub retry: RetryLadder,
}

/// The retry ladder `delta * growth^k`, clamped to `max_delta`: a large inconsistency of the
/// measured state can leave the first inner step without a solution below some `delta`
/// (about 0.03 for the wheel with `theta(0) = pi/2 + 0.3`), which only a larger step reaches.
/// Every retry is reported in `controller_events`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RetryLadder {
    /// Factor by which `delta` grows at each retry (default 4, must exceed 1).
    #[serde(default = "default_growth")]
    pub growth: f64,
    /// The largest `delta` tried; absent: the sampling period `h`.
    #[serde(default)]
    pub max_delta: Option<f64>,
    /// The most retries per sample; absent: as many as the ladder needs to reach
    /// `max_delta`.
    #[serde(default)]
    pub retries: Option<usize>,
}

fn default_growth() -> f64 {
    4.0
}

impl Default for RetryLadder {
    fn default() -> Self {
        Self {
            growth: default_growth(),
            max_delta: None,
            retries: None,
        }
    }
}

/// When a run counts as diverged (besides a non-finite state, repeated controller failures
/// and a failing plant integration, which always stop it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DivergenceOptions {
    /// The bound on `|y_i - xi_i|` for every output not listed in `output` (default `1e3`;
    /// `inf` disables the check).
    #[serde(default = "default_tracking_error")]
    pub tracking_error: f64,
    /// Per output name, its own bound on the tracking error.
    #[serde(default)]
    pub output: BTreeMap<String, f64>,
    /// Per state name, a bound on `|x_i|`; states not listed are only checked for NaN and
    /// infinity (a heading angle that grows without limit while the loop tracks is fine).
    #[serde(default)]
    pub state: BTreeMap<String, f64>,
}

fn default_tracking_error() -> f64 {
    1e3
}

impl Default for DivergenceOptions {
    fn default() -> Self {
        Self {
            tracking_error: default_tracking_error(),
            output: BTreeMap::new(),
            state: BTreeMap::new(),
        }
    }
}

/// `key=value` assignments to apply to a scenario before it is read: the key is a dotted path
/// of TOML keys, the value a TOML value (a bare word that is not one is taken as a string).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides(pub Vec<(String, toml::Value)>);

impl Overrides {
    /// Parse `"key=value"` assignments.
    ///
    /// # Errors
    /// [`ScenarioError::Override`] for a missing `=` or an empty key.
    pub fn parse<'a>(items: impl IntoIterator<Item = &'a str>) -> Result<Self, ScenarioError> {
        let mut out = Vec::new();
        for item in items {
            let (key, value) = split_assignment(item)?;
            out.push((key.to_string(), parse_value(value)));
        }
        Ok(Self(out))
    }

    /// A short label such as `h=0.1,prefeedback=false`.
    pub fn label(&self) -> String {
        self.0
            .iter()
            .map(|(k, v)| format!("{k}={}", value_text(v)))
            .collect::<Vec<_>>()
            .join(",")
    }
}

/// Why a `--set` assignment (or an entry of `compare`) is malformed; the assignment is quoted
/// as a short excerpt.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum OverrideError {
    /// No `=`.
    #[error("`{}` is not of the form key=value", short(item))]
    NotAssignment {
        /// The assignment.
        item: String,
    },
    /// An empty key or an empty part of a dotted key.
    #[error(
        "`{}` has an empty key; expected a dotted path such as plant.params.m",
        short(item)
    )]
    EmptyKey {
        /// The assignment.
        item: String,
    },
    /// A swept key with an empty value among its values.
    #[error("`{}` has an empty value; expected key=v1,v2,...", short(item))]
    EmptyValue {
        /// The assignment.
        item: String,
    },
    /// A dotted key goes through a value that is not a table.
    #[error("cannot set `{}`: `{part}` is not a table", short(key))]
    NotATable {
        /// The dotted key.
        key: String,
        /// Its part that names a value, not a table.
        part: String,
    },
}

/// `key=value` split at the first `=`, both parts trimmed.
pub(crate) fn split_assignment(item: &str) -> Result<(&str, &str), ScenarioError> {
    let Some((key, value)) = item.split_once('=') else {
        return Err(ScenarioError::Override(OverrideError::NotAssignment {
            item: item.to_string(),
        }));
    };
    let key = key.trim();
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(ScenarioError::Override(OverrideError::EmptyKey {
            item: item.to_string(),
        }));
    }
    Ok((key, value.trim()))
}

/// A TOML value from text, or the text itself as a string.
pub(crate) fn parse_value(text: &str) -> toml::Value {
    #[derive(Deserialize)]
    struct Holder {
        v: toml::Value,
    }
    toml::from_str::<Holder>(&format!("v = {text}"))
        .map(|h| h.v)
        .unwrap_or_else(|_| toml::Value::String(text.to_string()))
}

/// A value as it would be written on the command line.
pub(crate) fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => element_text(other),
    }
}

/// A value inside a list: strings quoted, numbers readable ([`Num`]).
fn element_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => Num(*f).to_string(),
        toml::Value::Array(items) => format!(
            "[{}]",
            items
                .iter()
                .map(element_text)
                .collect::<Vec<_>>()
                .join(", ")
        ),
        other => other.to_string(),
    }
}

impl Scenario {
    /// Read a scenario file and apply `overrides`.
    ///
    /// # Errors
    /// [`ScenarioError`] naming the file, and the line where TOML gives one.
    pub fn load(path: &Path, overrides: &Overrides) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError::Read {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::parse(&path.display().to_string(), &text, overrides)
    }

    /// Parse scenario text (`origin` names it in errors) and apply `overrides`.
    ///
    /// # Errors
    /// [`ScenarioError`] for malformed TOML, unknown keys, wrong types or invalid values.
    pub fn parse(origin: &str, text: &str, overrides: &Overrides) -> Result<Self, ScenarioError> {
        let mut table: toml::Table =
            toml::from_str(text).map_err(|e| crate::cli::toml_error(origin, text, &e))?;
        for (key, value) in &overrides.0 {
            set_path(&mut table, key, value.clone())?;
        }
        let scenario: Scenario = if overrides.0.is_empty() {
            toml::from_str(text).map_err(|e| crate::cli::toml_error(origin, text, &e))?
        } else {
            // Re-serialise so that errors point at lines of the modified document.
            let modified = toml::to_string(&table).map_err(|e| ScenarioError::Invalid {
                origin: origin.to_string(),
                message: e.to_string(),
            })?;
            toml::from_str(&modified).map_err(|e| {
                let mut err = crate::cli::toml_error(origin, &modified, &e);
                if let ScenarioError::Invalid { message, .. } = &mut err {
                    message.push_str(&format!(" (after --set {})", short(&overrides.label())));
                }
                err
            })?
        };
        let mut scenario = scenario;
        scenario.source = Some(Source {
            path: origin.into(),
            text: text.into(),
            overridden: overrides.0.iter().map(|(k, _)| k.clone()).collect(),
        });
        scenario
            .validate()
            .map_err(|cause| scenario.value_error(cause))?;
        Ok(scenario)
    }

    /// Where `key` is written: `FILE:LINE:COLUMN` (see [`Source::locate`]), or `scenario` for
    /// a scenario built in code.
    pub fn locate(&self, key: &str) -> String {
        match &self.source {
            Some(source) => source.locate(key),
            None => "scenario".into(),
        }
    }

    /// A [`ScenarioError::Value`] located at the key it is about.
    pub fn value_error(&self, cause: ValueError) -> ScenarioError {
        let origin = match cause.key() {
            Some(key) => self.locate(&key),
            None => self.locate(""),
        };
        ScenarioError::Value { origin, cause }
    }

    /// Checks that need no model: finite positive times, finite vectors, poles and roots of
    /// `W` that can be computed with, a design when the preliminary feedback is on, and the
    /// work of the run within [`Limits`].
    ///
    /// # Errors
    /// The first [`ValueError`] found.
    pub fn validate(&self) -> Result<(), ValueError> {
        let positive = |key: &str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ValueError::NotPositive {
                    key: key.to_string(),
                    value,
                })
            }
        };
        // A bound may be infinite (no check), never NaN or non-positive.
        let bound = |key: &str, value: f64| {
            if value > 0.0 {
                Ok(())
            } else {
                Err(ValueError::NotPositiveBound {
                    key: key.to_string(),
                    value,
                })
            }
        };
        positive("h", self.h)?;
        positive("t_end", self.t_end)?;
        positive("delta", self.delta)?;
        if let Some(step) = self.output_step {
            positive("output_step", step)?;
            let least = MIN_OUTPUT_STEP_RATIO * self.t_end;
            if step < least {
                return Err(ValueError::Order {
                    key: "output_step",
                    value: step,
                    relation: "at least 1e-12 times",
                    other: "t_end",
                    other_value: self.t_end,
                });
            }
        }
        positive("plant.rtol", self.plant.rtol)?;
        if !(f64::EPSILON..1.0).contains(&self.plant.rtol) {
            return Err(ValueError::Tolerance {
                value: self.plant.rtol,
            });
        }
        positive("plant.atol", self.plant.atol)?;
        bound("divergence.tracking_error", self.divergence.tracking_error)?;
        for (name, value) in &self.divergence.output {
            bound(&format!("divergence.output.{name}"), *value)?;
        }
        for (name, value) in &self.divergence.state {
            bound(&format!("divergence.state.{name}"), *value)?;
        }
        let retry = &self.controller.retry;
        if !(retry.growth.is_finite() && retry.growth > 1.0) {
            return Err(ValueError::Growth {
                value: retry.growth,
            });
        }
        if let Some(max_delta) = retry.max_delta {
            positive("controller.retry.max_delta", max_delta)?;
            if max_delta < self.delta {
                return Err(ValueError::Order {
                    key: "controller.retry.max_delta",
                    value: max_delta,
                    relation: "at least",
                    other: "delta",
                    other_value: self.delta,
                });
            }
        }
        if self.delta >= self.h {
            return Err(ValueError::Order {
                key: "delta",
                value: self.delta,
                relation: "smaller than the sampling period",
                other: "h",
                other_value: self.h,
            });
        }
        if self.h > self.t_end {
            return Err(ValueError::Order {
                key: "h",
                value: self.h,
                relation: "at most",
                other: "t_end",
                other_value: self.t_end,
            });
        }
        self.check_limits()?;
        check_finite("x0", &self.x0)?;
        for (name, roots) in &self.w {
            check_w_roots(&format!("w.{name}"), roots)?;
        }
        for (name, value) in &self.plant.params {
            finite_scalar(&format!("plant.params.{name}"), *value)?;
        }
        for (name, value) in &self.controller.params {
            finite_scalar(&format!("controller.params.{name}"), *value)?;
        }
        if let Some(reference) = &self.reference {
            for (name, terms) in reference {
                if terms.iter().any(|t| !t.is_finite()) {
                    return Err(ValueError::Reference {
                        output: name.clone(),
                    });
                }
            }
        }
        if self.prefeedback && self.design.is_none() {
            return Err(ValueError::NoDesign);
        }
        if let Some(design) = &self.design {
            let n = &design.nominal;
            for (what, values) in [
                ("state", &n.state),
                ("rate", &n.rate),
                ("algebraic", &n.algebraic),
                ("input", &n.input),
            ] {
                match values {
                    None => {}
                    Some(Values::All(v)) => check_finite(&format!("design.nominal.{what}"), v)?,
                    Some(Values::Named(m)) => {
                        for (name, v) in m {
                            finite_scalar(&format!("design.nominal.{what}.{name}"), *v)?;
                        }
                    }
                }
            }
            for (name, value) in &n.guess {
                finite_scalar(&format!("design.nominal.guess.{name}"), *value)?;
            }
            for (i, pole) in design.poles.iter().flatten().enumerate() {
                let c = pole.complex();
                check_scalar(&format!("design.poles[{i}]"), c.re)?;
                check_scalar(&format!("design.poles[{i}]"), c.im)?;
            }
        }
        for set in &self.compare {
            for item in set.split(';') {
                split_assignment(item).map_err(|e| ValueError::Compare(Box::new(e)))?;
            }
        }
        Ok(())
    }

    /// The number of samples, `nu` and the retry ladder within [`Limits`].
    fn check_limits(&self) -> Result<(), ValueError> {
        let limits = &self.limits;
        // As the closed loop counts them: round(t_end / h) + 1.
        let samples = (self.t_end / self.h).round() + 1.0;
        if samples > limits.samples as f64 {
            return Err(ValueError::Limit {
                key: "t_end",
                what: format!(
                    "`t_end` / `h` = {} / {} gives {} samples, which",
                    Num(self.t_end),
                    Num(self.h),
                    count(samples)
                ),
                limit_key: "samples",
                limit: limits.samples,
            });
        }
        let options = ClosedLoopOptions {
            h: self.h,
            t_end: self.t_end,
            output_step: self.output_step,
            ..ClosedLoopOptions::default()
        };
        let rows = samples + options.dense_points() as f64;
        if rows > limits.rows as f64 {
            let what = match self.output_step {
                Some(step) => format!(
                    "`output_step` = {} over `t_end` = {} gives {} rows of trajectory.csv ({} samples and the points between them), which",
                    Num(step),
                    Num(self.t_end),
                    count(rows),
                    count(samples)
                ),
                None => format!(
                    "`t_end` / `h` = {} / {} gives {} rows of trajectory.csv, which",
                    Num(self.t_end),
                    Num(self.h),
                    count(rows)
                ),
            };
            return Err(ValueError::Limit {
                key: if self.output_step.is_some() {
                    "output_step"
                } else {
                    "t_end"
                },
                what,
                limit_key: "rows",
                limit: limits.rows,
            });
        }
        if let Some(nu) = self.nu {
            if nu > limits.nu {
                return Err(ValueError::Limit {
                    key: "nu",
                    what: format!("`nu` = {nu}"),
                    limit_key: "nu",
                    limit: limits.nu as u64,
                });
            }
        }
        let retry = &self.controller.retry;
        let max_delta = retry.max_delta.unwrap_or(self.h);
        // The ladder delta * growth^k reaches max_delta after this many retries.
        let to_reach = ((max_delta / self.delta).ln() / retry.growth.ln())
            .ceil()
            .max(0.0);
        let retries = retry.retries.map_or(to_reach, |r| (r as f64).min(to_reach));
        if retries > limits.retries as f64 {
            return Err(ValueError::Limit {
                key: "delta",
                what: format!(
                    "the retry ladder from `delta` = {} with `controller.retry.growth` = {} to `max_delta` = {} takes {} retries, which",
                    Num(self.delta),
                    Num(retry.growth),
                    Num(max_delta),
                    count(retries)
                ),
                limit_key: "retries",
                limit: limits.retries as u64,
            });
        }
        Ok(())
    }

    /// The comparison runs listed in `compare`, each with its overrides.
    ///
    /// # Errors
    /// [`ScenarioError::Override`] for a malformed entry.
    pub fn comparisons(&self) -> Result<Vec<Overrides>, ScenarioError> {
        self.compare
            .iter()
            .map(|set| Overrides::parse(set.split(';')))
            .collect()
    }
}

/// Set `key` (a dotted path) in `table`, creating tables on the way.
fn set_path(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), ScenarioError> {
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().unwrap_or(key);
    let mut current = table;
    for part in parts {
        let entry = current
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        current = match entry {
            toml::Value::Table(t) => t,
            _ => {
                return Err(ScenarioError::Override(OverrideError::NotATable {
                    key: key.to_string(),
                    part: part.to_string(),
                }))
            }
        };
    }
    current.insert(last.to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
model = "wheel"
x0 = [1.5, 0.0, 0.0, 0.0, -6.0]
h = 0.05
t_end = 1.0
"#;

    #[test]
    fn defaults_fill_the_optional_keys() {
        let s = Scenario::parse("s.toml", MINIMAL, &Overrides::default()).unwrap();
        assert_eq!(s.delta, 1e-3);
        assert_eq!(s.extraction, Extraction::Extrapolated);
        assert_eq!(s.hold, Hold::Input);
        assert!(!s.prefeedback);
        assert!(s.reference.is_none());
        assert_eq!(s.plant, PlantOptions::default());
    }

    #[test]
    fn overrides_reach_nested_keys_and_parse_values() {
        let o = Overrides::parse([
            "h=0.1",
            "hold=correction",
            "plant.params.m=1.25",
            "extraction = first-usable",
        ])
        .unwrap();
        let s = Scenario::parse("s.toml", MINIMAL, &o).unwrap();
        assert_eq!(s.h, 0.1);
        assert_eq!(s.hold, Hold::Correction);
        assert_eq!(s.extraction, Extraction::FirstUsable);
        assert_eq!(s.plant.params["m"], 1.25);
        assert_eq!(
            o.label(),
            "h=0.1,hold=correction,plant.params.m=1.25,extraction=first-usable"
        );
    }

    #[test]
    fn errors_are_one_line_and_name_the_file_and_line() {
        let text = format!("{MINIMAL}hh = 2\n");
        let e = Scenario::parse("s.toml", &text, &Overrides::default())
            .unwrap_err()
            .to_string();
        assert!(!e.contains('\n'), "{e}");
        assert!(e.starts_with("s.toml:6:"), "{e}");
        assert!(e.contains("unknown field `hh`"), "{e}");

        let e = Scenario::parse("s.toml", MINIMAL, &Overrides::parse(["h=-1"]).unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`h` must be a positive finite number, found -1"),
            "{e}"
        );

        let e = Overrides::parse(["h"]).unwrap_err().to_string();
        assert!(e.contains("key=value"), "{e}");

        let e = Scenario::parse(
            "s.toml",
            MINIMAL,
            &Overrides::parse(["prefeedback=true"]).unwrap(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("[design]"), "{e}");

        let e = Scenario::parse("s.toml", MINIMAL, &Overrides::parse(["x0.a=1"]).unwrap())
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a table"), "{e}");
    }

    #[test]
    fn reference_terms_sum() {
        let text = format!(
            "{MINIMAL}[reference]\ntheta = [{{ constant = 1.0 }}, {{ sine = {{ amplitude = 0.5, omega = 2.0 }} }}]\npsi = [{{ polynomial = [0.0, -6.0] }}, {{ atan-integral = {{ scale = -0.5 }} }}]\n"
        );
        let s = Scenario::parse("s.toml", &text, &Overrides::default()).unwrap();
        let r = s.reference.unwrap();
        let theta = scalar_reference(&r["theta"]);
        let t = 0.3_f64;
        assert!((theta.derivative(t, 0) - (1.0 + 0.5 * (2.0 * t).sin())).abs() < 1e-15);
        assert!((theta.derivative(t, 1) - (2.0 * t).cos()).abs() < 1e-15);
        let psi = scalar_reference(&r["psi"]);
        assert!((psi.derivative(t, 1) - (-6.0 - 0.5 * t.atan())).abs() < 1e-15);
    }
}
