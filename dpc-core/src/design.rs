//! The design chain of a preliminary feedback, for any [`DaeModel`]: trim -> linearise ->
//! analyse -> `K_n` -> law (paper, Sections 3 and 5).
//!
//! * [`trim`] solves `F(t, x, x', z, u) = 0` for the unknown part of an equilibrium or a
//!   steady motion: the user fixes what they know (typically the inputs, or some states and
//!   rates) and the rest, algebraic unknowns included, is computed. It is a Gauss-Newton
//!   iteration on the free entries with minimum-norm steps from the singular value
//!   decomposition of their Jacobian (exact, from the generated code) and a backtracking line
//!   search on `|F|_2`; non-square problems are allowed (an over-determined one must be
//!   consistent, an under-determined one converges to the solution nearest the guess and
//!   reports its free directions).
//! * [`design`] linearises about the [`SteadyMotion`], checks the relative degrees the
//!   tracking DAE assumes there (when given), runs [`analyze`] with the given `W` and poles, measures how much the linearisation changes along the motion (one constant
//!   `K_n` fits a run only where it does not), and returns a [`Design`] from which the law
//!   [`Prefeedback`] is built. One entry point serves every plant: an ODE or index-1 plant is
//!   linearised by [`linearize`]; a constrained plant of index 2 or 3 (where `[F_x' F_z]` is
//!   singular) by [`linearize_descriptor`], whose realisation on the constraint manifold is
//!   analysed, and whose `K_n` on the reduced state is mapped back to the plant's coordinates
//!   (`K_x = K_r U^T`, zero on the constrained directions; see
//!   [`ManifoldRealisation::gain_to_plant`]).
//! * [`Design::remaining_relative_degree`] gives the controller's `nu` from the relative
//!   degrees of the linearisation at the nominal, for plants whose tracking DAE has no compiled
//!   relative degrees (the macro leaves them undefined where the structure is of higher index).
//! * [`check_relative_degrees`] compares the relative degrees a tracking DAE was compiled
//!   for with those of the linearisation at the nominal, so that a plant whose structural
//!   relative degree is not its true one is reported before a closed loop runs into a
//!   singular iteration matrix.
//!
//! # Example
//! An overhead crane (a cart and a load on a rope) whose cart position is to follow a path:
//! trimmed at rest with the cart at `0.3` (the rope angle and the force are solved for),
//! linearised there and analysed. The cart is a minimum-phase output, but plain DPC is
//! unstable about this rest (`Abar_4` has an unstable eigenvalue); the preliminary feedback
//! `K_n` the analysis builds stabilises it.
//!
//! ```
//! use dpc::core::design::{design, trim, DesignOptions, TrimOptions, TrimProblem, TrimValue};
//! use dpc::core::linear_analysis::AnalysisOptions;
//! use dpc::core::DaeModel;
//!
//! dpc::model! {
//!     /// A crane: cart position `s`, rope angle `phi` from the downward vertical.
//!     Crane {
//!         params { mc = 1.0, m = 0.5, l = 0.5, g = 9.81, b = 0.1, c = 0.2 }
//!         states { s, phi, vs, om }
//!         inputs { f }
//!         equations {
//!             der(s) = vs;
//!             der(phi) = om;
//!             (mc + m) * der(vs) + m * l * cos(phi) * der(om)
//!                 == f - b * vs + m * l * sin(phi) * om.powi(2) - c * (vs + l * cos(phi) * om);
//!             m * l * cos(phi) * der(vs) + m * l.powi(2) * der(om)
//!                 == -m * g * l * sin(phi) - c * l * (cos(phi) * vs + l * om);
//!         }
//!         outputs { cart = s }
//!         references { cart = 0.3 + 0.5 * (1.0 - cos(t)) }
//!         tracking CraneTracking { cart: [2.0] }
//!     }
//! }
//!
//! let crane = Crane::default();
//! let structure = crane.structure();
//! let mut rest = TrimProblem::equilibrium(structure);
//! rest.set(structure, "s", TrimValue::Fixed(0.3))?;
//! let trimmed = trim(&crane, &rest, &TrimOptions::default())?;
//! assert!(trimmed.motion.state[1].abs() < 1e-12 && trimmed.motion.input[0].abs() < 1e-12);
//!
//! let options = DesignOptions {
//!     analysis: AnalysisOptions { w: Some(vec![vec![2.0]]), ..AnalysisOptions::default() },
//!     horizon: 1.0,
//!     relative_degrees: vec![Some(2)], // what the tracking DAE assumes, checked here
//! };
//! let designed = design(&crane, &trimmed.motion, &options)?;
//! let verdict = &designed.analysis;
//! assert!(verdict.minimum_phase && !verdict.dpc_stable);
//! assert_eq!(verdict.dpc_stable_prefeedback, Some(true));
//! assert_eq!(verdict.k_n.as_ref().map(|k| k.shape()), Some((1, 4))); // inputs x states
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::linear_analysis::descriptor::{
    descriptor_system, linearize_descriptor, DescriptorError, DescriptorOptions,
    ManifoldRealisation,
};
use crate::linear_analysis::sampled::SampledLoop;
use crate::linear_analysis::{analyze, Analysis, AnalysisOptions, LinearError, LinearSystem};
use crate::linearize::{linearize, LinearizeError, OperatingPoint};
use crate::model::{DaeModel, Names, Structure};
use crate::numeric::max_or_nan;
use crate::prefeedback::{Nominal, NominalError, Prefeedback, SteadyMotion};
use crate::simulate::Hold;
use crate::tracking::TrackingDae;
use nalgebra::{DMatrix, DVector};
use std::fmt;
use thiserror::Error;

/// One entry of a [`TrimProblem`]: fixed at a value, or free with a starting guess.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrimValue {
    /// Known; the trim solver keeps it.
    Fixed(f64),
    /// Unknown; the trim solver starts from this guess.
    Free(f64),
}

impl TrimValue {
    /// The value (fixed) or the guess (free).
    pub fn value(self) -> f64 {
        match self {
            Self::Fixed(v) | Self::Free(v) => v,
        }
    }

    /// Whether the solver may change it.
    pub fn is_free(self) -> bool {
        matches!(self, Self::Free(_))
    }
}

/// What [`trim`] solves: `F(t, x, rate, z, u) = 0` for the free entries, the others fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct TrimProblem {
    /// The time at which the motion's values hold (`0` for the nominals of
    /// [`SteadyMotion`]).
    pub t: f64,
    /// States `x0`.
    pub state: Vec<TrimValue>,
    /// Rates `x0'`.
    pub rate: Vec<TrimValue>,
    /// Algebraic unknowns `z0`.
    pub algebraic: Vec<TrimValue>,
    /// Inputs `u0`.
    pub input: Vec<TrimValue>,
    /// When given, a steady motion must also satisfy the equations at `t + horizon`
    /// (states moved along their rates): checked after the solve.
    pub horizon: Option<f64>,
}

impl TrimProblem {
    /// An equilibrium of a model with this structure: every rate fixed at zero, every state,
    /// algebraic unknown and input free with guess zero.
    pub fn equilibrium(structure: &Structure) -> Self {
        Self {
            t: 0.0,
            state: vec![TrimValue::Free(0.0); structure.n_states()],
            rate: vec![TrimValue::Fixed(0.0); structure.n_states()],
            algebraic: vec![TrimValue::Free(0.0); structure.n_algebraic()],
            input: vec![TrimValue::Free(0.0); structure.n_inputs()],
            horizon: None,
        }
    }

    /// Set the entry called `name` (a state, `der(state)` for its rate, an algebraic
    /// unknown or an input, as declared) to `value`.
    ///
    /// # Errors
    /// [`TrimError::UnknownName`] when the model has no such variable.
    pub fn set(
        &mut self,
        structure: &Structure,
        name: &str,
        value: TrimValue,
    ) -> Result<(), TrimError> {
        let (block, i) = locate(structure, name)?;
        self.block_mut(block)[i] = value;
        Ok(())
    }

    /// The entry called `name`, as [`set`](Self::set) names it.
    ///
    /// # Errors
    /// [`TrimError::UnknownName`] when the model has no such variable.
    pub fn value(&self, structure: &Structure, name: &str) -> Result<TrimValue, TrimError> {
        let (block, i) = locate(structure, name)?;
        Ok(match block {
            Block::Rate => self.rate[i],
            Block::State => self.state[i],
            Block::Algebraic => self.algebraic[i],
            Block::Input => self.input[i],
        })
    }

    fn block_mut(&mut self, block: Block) -> &mut [TrimValue] {
        match block {
            Block::Rate => &mut self.rate,
            Block::State => &mut self.state,
            Block::Algebraic => &mut self.algebraic,
            Block::Input => &mut self.input,
        }
    }
}

/// Which vector of a [`TrimProblem`] an entry is in.
#[derive(Clone, Copy)]
enum Block {
    Rate,
    State,
    Algebraic,
    Input,
}

/// Where the variable called `name` (a state, `der(state)`, an algebraic unknown or an
/// input) is.
fn locate(structure: &Structure, name: &str) -> Result<(Block, usize), TrimError> {
    let name = name.trim();
    let found = if let Some(inner) = name
        .strip_prefix("der(")
        .and_then(|rest| rest.strip_suffix(')'))
    {
        structure
            .states
            .position(inner.trim())
            .map(|i| (Block::Rate, i))
    } else if let Some(i) = structure.states.position(name) {
        Some((Block::State, i))
    } else if let Some(i) = structure.algebraic.position(name) {
        Some((Block::Algebraic, i))
    } else {
        structure.inputs.position(name).map(|i| (Block::Input, i))
    };
    found.ok_or_else(|| TrimError::UnknownName {
        model: structure.name.to_string(),
        name: name.to_string(),
        known: known_variables(structure),
    })
}

fn known_variables(s: &Structure) -> String {
    let mut parts = Vec::new();
    for (what, names) in [
        ("states", &s.states),
        ("algebraic unknowns", &s.algebraic),
        ("inputs", &s.inputs),
    ] {
        if !names.is_empty() {
            parts.push(format!("{what} {}", names.join(", ")));
        }
    }
    parts.push("and der(state) for a rate".to_string());
    parts.join("; ")
}

/// Options of [`trim`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrimOptions {
    /// Converged when `max |F_i| <= tolerance * (1 + |J|_inf |v|_inf)`, with `J` the Jacobian
    /// of `F` in all of `(x', x, z, u)` and `v` their values: the size of the terms the
    /// equations balance.
    pub tolerance: f64,
    /// Gauss-Newton iterations before [`TrimError::NotConverged`].
    pub max_iterations: usize,
}

impl Default for TrimOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-12,
            max_iterations: 50,
        }
    }
}

/// An equation's residual, for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct EquationResidual {
    /// The equation as [`Structure::equation_name`] names it.
    pub equation: String,
    /// Its residual.
    pub residual: f64,
}

/// The equations with the largest residuals, as one phrase.
#[derive(Debug, Clone, PartialEq)]
pub struct Residuals(pub Vec<EquationResidual>);

impl fmt::Display for Residuals {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, e) in self.0.iter().enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{} (residual {:.3e})", e.equation, e.residual)?;
        }
        Ok(())
    }
}

/// Why [`trim`] found no solution.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TrimError {
    /// A vector of the problem has the wrong length.
    #[error("trim of `{model}`: `{what}` has {found} entries, expected {expected}")]
    Dimension {
        /// The model.
        model: String,
        /// Which vector.
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A name that is not a variable of the model.
    #[error("model `{model}` has no variable `{name}`; it has {known}")]
    UnknownName {
        /// The model.
        model: String,
        /// The name given.
        name: String,
        /// What the model has.
        known: String,
    },
    /// A fixed value or a guess is NaN or infinite, or the model evaluated to one.
    #[error("trim of `{model}`: {what} is not finite")]
    NonFinite {
        /// The model.
        model: String,
        /// What was not finite (a variable by name, or an equation's residual or Jacobian).
        what: String,
    },
    /// The fixed values admit no solution: the iteration reached a least-squares minimum
    /// with a non-zero residual.
    #[error("trim of `{model}`: the fixed values leave these equations unsatisfiable: {equations}; fix fewer values or change them")]
    Inconsistent {
        /// The model.
        model: String,
        /// The equations left with a residual, largest first.
        equations: Residuals,
    },
    /// The iteration did not converge.
    #[error("trim of `{model}` did not converge in {iterations} iterations; left: {equations}; give better guesses or fix more values")]
    NotConverged {
        /// The model.
        model: String,
        /// Iterations done.
        iterations: usize,
        /// The equations left with a residual, largest first.
        equations: Residuals,
    },
    /// A solution at `t` that is not a steady motion: moved along its rates, it no longer
    /// satisfies the equations.
    #[error("trim of `{model}`: not a steady motion: at t = {t} along the rates {equations}; the equations depend on a state that moves (only cyclic coordinates may have a rate)")]
    NotSteady {
        /// The model.
        model: String,
        /// Where the check failed.
        t: f64,
        /// The violated equations, largest first.
        equations: Residuals,
    },
}

/// The result of [`trim`].
#[derive(Debug, Clone, PartialEq)]
pub struct Trim {
    /// The motion found (with its values at `t = problem.t`).
    pub motion: SteadyMotion,
    /// Gauss-Newton iterations used.
    pub iterations: usize,
    /// `max |F_i|` at the solution.
    pub residual: f64,
    /// Number of free entries.
    pub unknowns: usize,
    /// Numerical rank of the free entries' Jacobian at the solution: below `unknowns`, the
    /// solution is not unique (`unknowns - rank` free directions; the solver returned the
    /// one nearest the guess).
    pub rank: usize,
}

impl Trim {
    /// Directions along which the solution is not determined by the equations.
    pub fn free_directions(&self) -> usize {
        self.unknowns - self.rank
    }
}

/// The free entries of a problem and where they go.
struct Layout {
    /// Per free entry: (block, index) with block 0 rate, 1 state, 2 algebraic, 3 input.
    free: Vec<(usize, usize)>,
}

/// Values of `(rate, state, algebraic, input)`.
struct Point {
    v: [Vec<f64>; 4],
}

/// Residual and Jacobian of a model, evaluated by blocks.
struct Evaluation {
    residual: DVector<f64>,
    /// Jacobian blocks in the order rate, state, algebraic, input.
    blocks: [DMatrix<f64>; 4],
}

/// Residual and Jacobian blocks at `p` (its states are `p.v[1]`).
fn evaluate<P: DaeModel>(model: &P, t: f64, p: &Point) -> Evaluation {
    let s = model.structure();
    let ne = s.n_equations();
    let mut r = vec![0.0; ne];
    let mut blocks = [
        DMatrix::zeros(ne, s.n_states()),
        DMatrix::zeros(ne, s.n_states()),
        DMatrix::zeros(ne, s.n_algebraic()),
        DMatrix::zeros(ne, s.n_inputs()),
    ];
    let [f_xdot, f_x, f_z, f_u] = &mut blocks;
    model.evaluate(
        t, &p.v[1], &p.v[0], &p.v[2], &p.v[3], &mut r, f_xdot, f_x, f_z, f_u,
    );
    Evaluation {
        residual: DVector::from_vec(r),
        blocks,
    }
}

fn largest_residuals(structure: &Structure, r: &DVector<f64>, floor: f64) -> Residuals {
    let mut rows: Vec<(usize, f64)> = r
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_nan() || v.abs() > floor)
        .map(|(i, v)| (i, *v))
        .collect();
    rows.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    rows.truncate(5);
    Residuals(
        rows.into_iter()
            .map(|(i, v)| EquationResidual {
                equation: structure.equation_name(i),
                residual: v,
            })
            .collect(),
    )
}

/// Solve `problem` for its free entries; see the module documentation for the method.
///
/// # Errors
/// [`TrimError`]: wrong lengths, non-finite values, an inconsistent problem or one that did
/// not converge (naming the equations left unsatisfied), or a solution that is not a steady
/// motion over `problem.horizon`.
pub fn trim<P: DaeModel>(
    model: &P,
    problem: &TrimProblem,
    options: &TrimOptions,
) -> Result<Trim, TrimError> {
    let s = model.structure();
    let name = s.name.to_string();
    let blocks: [(&'static str, &[TrimValue], usize, &Names); 4] = [
        ("rate", &problem.rate, s.n_states(), &s.states),
        ("state", &problem.state, s.n_states(), &s.states),
        (
            "algebraic",
            &problem.algebraic,
            s.n_algebraic(),
            &s.algebraic,
        ),
        ("input", &problem.input, s.n_inputs(), &s.inputs),
    ];
    let mut layout = Layout { free: Vec::new() };
    let mut point = Point {
        v: Default::default(),
    };
    for (b, (what, values, n, names)) in blocks.iter().enumerate() {
        if values.len() != *n {
            return Err(TrimError::Dimension {
                model: name,
                what,
                expected: *n,
                found: values.len(),
            });
        }
        for (i, v) in values.iter().enumerate() {
            if !v.value().is_finite() {
                let var = names.get(i).unwrap_or("?");
                let var = if b == 0 {
                    format!("der({var})")
                } else {
                    var.to_string()
                };
                return Err(TrimError::NonFinite {
                    model: name,
                    what: format!("the value of `{var}` ({})", v.value()),
                });
            }
            if v.is_free() {
                layout.free.push((b, i));
            }
        }
        point.v[b] = values.iter().map(|v| v.value()).collect();
    }
    let nf = layout.free.len();
    let ne = s.n_equations();
    let non_finite = |e: &Evaluation| -> Option<String> {
        if let Some(i) = e.residual.iter().position(|v| !v.is_finite()) {
            return Some(format!("the residual of {}", s.equation_name(i)));
        }
        for blk in &e.blocks {
            for (k, v) in blk.iter().enumerate() {
                if !v.is_finite() {
                    return Some(format!("the Jacobian of {}", s.equation_name(k % ne)));
                }
            }
        }
        None
    };
    let mut e = evaluate(model, problem.t, &point);
    let mut iterations = 0;
    let rank;
    loop {
        if let Some(what) = non_finite(&e) {
            return Err(TrimError::NonFinite { model: name, what });
        }
        let tol = options.tolerance * jacobian_scale(&e, &point);
        let jf = DMatrix::from_fn(ne, nf, |i, k| {
            let (b, c) = layout.free[k];
            e.blocks[b][(i, c)]
        });
        let r_max = e.residual.amax();
        if nf == 0 || ne == 0 {
            // Nothing to solve for (or nothing to satisfy): the point is checked as given.
            if r_max <= tol {
                rank = 0;
                break;
            }
            return Err(TrimError::Inconsistent {
                model: name,
                equations: largest_residuals(s, &e.residual, tol),
            });
        }
        let svd = jf.clone().svd(true, true);
        let smax = svd.singular_values.iter().fold(0.0_f64, |m, v| m.max(*v));
        let rank_tol = (ne.max(nf).max(1) as f64) * f64::EPSILON * 100.0 * smax;
        if r_max <= tol {
            rank = svd
                .singular_values
                .iter()
                .filter(|v| **v > rank_tol)
                .count();
            break;
        }
        // Minimum-norm Gauss-Newton step.
        let step = svd
            .solve(&(-&e.residual), rank_tol)
            .map_err(|_| TrimError::NotConverged {
                model: name.clone(),
                iterations,
                equations: largest_residuals(s, &e.residual, tol),
            })?;
        let f0 = e.residual.norm_squared();
        // The decrease of |F|^2 the linear model predicts: (almost) none means the residual
        // is orthogonal to everything the free entries can change, a least-squares minimum
        // of an inconsistent problem.
        let predicted = 1.0 - (&e.residual + &jf * &step).norm_squared() / f0;
        if predicted < STATIONARY {
            return Err(TrimError::Inconsistent {
                model: name,
                equations: largest_residuals(s, &e.residual, tol),
            });
        }
        if iterations >= options.max_iterations {
            return Err(TrimError::NotConverged {
                model: name,
                iterations,
                equations: largest_residuals(s, &e.residual, tol),
            });
        }
        iterations += 1;
        let mut lambda = 1.0;
        let mut accepted = None;
        for _ in 0..40 {
            let mut trial = Point { v: point.v.clone() };
            for (k, &(b, c)) in layout.free.iter().enumerate() {
                trial.v[b][c] += lambda * step[k];
            }
            let et = evaluate(model, problem.t, &trial);
            let ft = et.residual.norm_squared();
            if ft.is_finite() && ft <= (1.0 - 1e-4 * lambda) * f0 {
                accepted = Some((trial, et));
                break;
            }
            lambda *= 0.5;
        }
        match accepted {
            Some((p, et)) => {
                point = p;
                e = et;
            }
            None => {
                // No decrease along a step that predicts one: the iteration is stuck.
                let equations = largest_residuals(s, &e.residual, tol);
                let err = if predicted < 1e-3 {
                    TrimError::Inconsistent {
                        model: name,
                        equations,
                    }
                } else {
                    TrimError::NotConverged {
                        model: name,
                        iterations,
                        equations,
                    }
                };
                return Err(err);
            }
        }
    }
    let residual = e.residual.amax();
    let [rate, state, algebraic, input] = point.v;
    let motion = SteadyMotion {
        state,
        rate,
        algebraic,
        input,
    };
    if let Some(horizon) = problem.horizon {
        check_steady(model, &motion, problem.t, horizon, options)?;
    }
    Ok(Trim {
        motion,
        iterations,
        residual,
        unknowns: nf,
        rank,
    })
}

/// Check that `motion`, whose values hold at time `t`, still satisfies the model's equations
/// at `t + horizon` with its states moved `horizon * rate`, to the tolerance of [`trim`]. A
/// motion without rates is an equilibrium and always passes.
///
/// # Errors
/// [`TrimError::Dimension`] when the motion does not fit the model, [`TrimError::NotSteady`]
/// naming the violated equations (a NaN residual counts as violated).
pub fn check_steady<P: DaeModel>(
    model: &P,
    motion: &SteadyMotion,
    t: f64,
    horizon: f64,
    options: &TrimOptions,
) -> Result<(), TrimError> {
    let s = model.structure();
    for (what, v, n) in [
        ("state", &motion.state, s.n_states()),
        ("rate", &motion.rate, s.n_states()),
        ("algebraic", &motion.algebraic, s.n_algebraic()),
        ("input", &motion.input, s.n_inputs()),
    ] {
        if v.len() != n {
            return Err(TrimError::Dimension {
                model: s.name.to_string(),
                what,
                expected: n,
                found: v.len(),
            });
        }
    }
    if motion.rate.iter().all(|r| *r == 0.0) {
        return Ok(());
    }
    let moved = Point {
        v: [
            motion.rate.clone(),
            motion.state_at(horizon),
            motion.algebraic.clone(),
            motion.input.clone(),
        ],
    };
    let t = t + horizon;
    let later = evaluate(model, t, &moved);
    let tol = options.tolerance * jacobian_scale(&later, &moved);
    let worst = max_or_nan(later.residual.iter().map(|v| v.abs()));
    if worst.is_nan() || worst > tol {
        return Err(TrimError::NotSteady {
            model: s.name.to_string(),
            t,
            equations: largest_residuals(s, &later.residual, tol),
        });
    }
    Ok(())
}

/// `1 + |J|_inf |v|_inf`: the size of the terms the equations balance at a point, the scale
/// of [`TrimOptions::tolerance`].
fn jacobian_scale(e: &Evaluation, p: &Point) -> f64 {
    let j = e.blocks.iter().map(row_sum_max).fold(0.0, f64::max);
    let v = p.v.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    1.0 + j * v
}

/// Relative decrease of `|F|^2` predicted by a Gauss-Newton step below which the problem
/// counts as inconsistent (a least-squares minimum with a non-zero residual).
const STATIONARY: f64 = 1e-8;

fn row_sum_max(m: &DMatrix<f64>) -> f64 {
    m.row_iter()
        .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Options of [`design`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DesignOptions {
    /// The analysis: `W` (the roots in use by the controller), poles, policy, tolerances.
    pub analysis: AnalysisOptions,
    /// The linearisation is also taken at `t = horizon` along the motion (typically the
    /// run's `t_end`) to measure [`Design::linearisation_drift`].
    pub horizon: f64,
    /// The relative degrees the controller's tracking DAE assumes, per output
    /// ([`crate::TrackingDae::relative_degrees`]): when given
    /// (non-empty), they are checked against the linearisation at the nominal with
    /// [`check_relative_degrees`] before the analysis, so that a tracking DAE that is
    /// singular at the nominal is reported as such. Empty: not checked.
    pub relative_degrees: Vec<Option<usize>>,
}

/// Why a design could not be made.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DesignError {
    /// The motion does not fit the model.
    #[error(transparent)]
    Nominal(#[from] NominalError),
    /// The trim solver failed.
    #[error(transparent)]
    Trim(#[from] TrimError),
    /// The linearisation failed.
    #[error("linearisation about the nominal at t = {t}: {source}")]
    Linearize {
        /// Where along the motion.
        t: f64,
        /// Why.
        source: LinearizeError,
    },
    /// The descriptor linearisation of a constrained plant failed (an inconsistent nominal, a
    /// singular pencil, an index above 3, an improper input).
    #[error("descriptor linearisation about the nominal at t = {t}: {source}")]
    Descriptor {
        /// Where along the motion.
        t: f64,
        /// Why.
        source: DescriptorError,
    },
    /// The linear analysis failed.
    #[error("linear analysis: {0}")]
    Analysis(#[from] LinearError),
    /// No input reaches an output in the linearisation at the nominal, so the controller's
    /// `nu` is not defined.
    #[error("output `{output}`: no input reaches it in the linearisation at the nominal, so its relative degree (and the controller's nu) is undefined")]
    Unreached {
        /// The output's name.
        output: String,
    },
    /// The analysis built no `K_n`.
    #[error("the linear analysis built no preliminary feedback{}", reason.as_ref().map(|r| format!(": {r}")).unwrap_or_default())]
    NoPrefeedback {
        /// The analysis's reason, if it gave one.
        reason: Option<String>,
    },
    /// Relative degrees at the nominal differ from those the tracking DAE assumes.
    #[error("{0}")]
    RelativeDegree(RelativeDegreeMismatch),
}

/// The linearisation about a steady motion and its analysis.
#[derive(Debug, Clone)]
pub struct Design {
    /// The motion designed about.
    pub motion: SteadyMotion,
    /// The linearisation at `t = 0`: in the plant's states for an ODE or index-1 plant; for a
    /// constrained plant, the realisation on the constraint manifold, whose state is the
    /// reduced `xi = U^T dx` of [`realisation`](Self::realisation).
    pub system: LinearSystem,
    /// The Section 3 analysis of [`system`](Self::system). Its `k_n` acts on the state of
    /// `system`; [`plant_gain`](Self::plant_gain) is the gain on the plant's states.
    pub analysis: Analysis,
    /// `max |[A B](horizon) - [A B](0)| / max |[A B](0)|` along the motion (for a constrained
    /// plant, of the descriptor matrices `[E A B]`, which do not depend on a choice of basis):
    /// zero when one linearisation (and so one constant `K_n`) serves the whole run, as for a
    /// steady motion in a cyclic coordinate.
    pub linearisation_drift: f64,
    /// For a constrained plant (not of index 1 at the nominal): the realisation on the
    /// constraint manifold, with the tangent basis `U`, the constrained states and the index;
    /// `None` for an ODE or index-1 plant.
    pub realisation: Option<ManifoldRealisation>,
}

impl Design {
    /// The law `u = u0 + K_n (x - x0(t)) + v` about the designed motion.
    ///
    /// # Errors
    /// [`DesignError::NoPrefeedback`] when the analysis built no `K_n`.
    pub fn prefeedback(&self) -> Result<Prefeedback, DesignError> {
        self.prefeedback_about(self.motion.clone())
    }

    /// DPC's limit law on this linearisation held by `hold` (see
    /// [`crate::linear_analysis::sampled`]): with the preliminary feedback `K_n` when `prefeedback` is
    /// set (and the analysis built one), else plain DPC.
    ///
    /// # Errors
    /// [`LinearError`] from building the sampled loop.
    pub fn sampled_loop(&self, hold: Hold, prefeedback: bool) -> Result<SampledLoop, LinearError> {
        if prefeedback {
            SampledLoop::from_analysis(&self.system, &self.analysis, hold)
        } else {
            SampledLoop::new(
                &self.system.a,
                &self.system.b,
                None,
                &self.analysis.k_j,
                hold,
            )
        }
    }

    /// The law with this design's `K_n` about another nominal (for example a
    /// [`ReferenceNominal`](crate::prefeedback::ReferenceNominal) built on the motion).
    ///
    /// # Errors
    /// [`DesignError::NoPrefeedback`] when the analysis built no `K_n`.
    pub fn prefeedback_about<N: Nominal + Send + Sync + 'static>(
        &self,
        nominal: N,
    ) -> Result<Prefeedback, DesignError> {
        Ok(Prefeedback {
            k_n: self.plant_gain()?,
            nominal: Box::new(nominal),
        })
    }

    /// `K_n` on the plant's states (`inputs x states`): the analysis's `K_n` itself for an ODE
    /// or index-1 plant; for a constrained plant the reduced gain mapped back,
    /// `K_x = K_r U^T` ([`ManifoldRealisation::gain_to_plant`]), which acts on every consistent
    /// variation as `K_r` acts on the reduced state and is zero on the constrained directions.
    ///
    /// # Errors
    /// [`DesignError::NoPrefeedback`] when the analysis built no `K_n`.
    pub fn plant_gain(&self) -> Result<DMatrix<f64>, DesignError> {
        let k_n = self
            .analysis
            .k_n
            .as_ref()
            .ok_or_else(|| DesignError::NoPrefeedback {
                reason: self.analysis.prefeedback_error.clone(),
            })?;
        match &self.realisation {
            None => Ok(k_n.clone()),
            Some(r) => r
                .gain_to_plant(k_n)
                .map_err(|source| DesignError::Descriptor { t: 0.0, source }),
        }
    }

    /// Per output, the relative degree of the linearisation at the nominal (for a constrained
    /// plant, of its realisation on the constraint manifold: the constraints are differentiated
    /// through, as the plant in minimal coordinates would be); `None` where no input reaches
    /// the output. See [`linear_relative_degrees`].
    pub fn relative_degrees(&self) -> Vec<Option<usize>> {
        linear_relative_degrees(&self.system)
    }

    /// The controller's `nu` for `tracking` at this nominal: `max_i (r_i - deg W_i)` with the
    /// relative degrees `r_i` of [`relative_degrees`](Self::relative_degrees) and the compiled
    /// degrees of the `W_i`. This is the `nu` of a constrained plant, whose tracking DAE has no
    /// compiled relative degrees: the closed loop gives the controller a state on the constraint
    /// manifold (positions and velocities consistent), so the constraint chain starts consistent
    /// and adds no unusable inner steps; only the output chains do, as for the plant in minimal
    /// coordinates. Pass it as [`DpcOptions::nu`](crate::controller::DpcOptions::nu).
    ///
    /// # Errors
    /// [`DesignError::Unreached`] for an output no input reaches at the nominal.
    pub fn remaining_relative_degree<T: TrackingDae>(
        &self,
        tracking: &T,
    ) -> Result<usize, DesignError> {
        let mut nu = 0;
        for (i, (r, w)) in self
            .relative_degrees()
            .into_iter()
            .zip(tracking.reference_orders())
            .enumerate()
        {
            let r = r.ok_or_else(|| DesignError::Unreached {
                output: tracking
                    .structure()
                    .outputs
                    .get(i)
                    .unwrap_or_default()
                    .to_string(),
            })?;
            nu = nu.max(r.saturating_sub(w));
        }
        Ok(nu)
    }
}

/// Linearise `model` about `motion` and analyse it; see the module documentation.
///
/// # Errors
/// [`DesignError`] when the motion does not fit the model, the linearisation or the analysis
/// fails.
pub fn design<P: DaeModel>(
    model: &P,
    motion: &SteadyMotion,
    options: &DesignOptions,
) -> Result<Design, DesignError> {
    let s = model.structure();
    let motion = SteadyMotion::new(
        (s.n_states(), s.n_algebraic(), s.n_inputs()),
        motion.state.clone(),
        motion.rate.clone(),
        motion.algebraic.clone(),
        motion.input.clone(),
    )?;
    let point = |t: f64| {
        let x = motion.state_at(t);
        (t, x)
    };
    fn at<'a>(motion: &'a SteadyMotion, t: f64, x: &'a [f64]) -> OperatingPoint<'a> {
        OperatingPoint {
            t,
            x,
            xdot: &motion.rate,
            z: &motion.algebraic,
            u: &motion.input,
        }
    }
    let (t0, x0) = point(0.0);
    let (t1, x1) = point(options.horizon);
    let (system, realisation, linearisation_drift) = match linearize(model, at(&motion, t0, &x0)) {
        Ok(system) => {
            let end = linearize(model, at(&motion, t1, &x1))
                .map_err(|source| DesignError::Linearize { t: t1, source })?;
            let drift = relative_change(&[&system.a, &system.b], &[&end.a, &end.b]);
            (system, None, drift)
        }
        // Not of index 1 at the nominal: a constrained plant, realised on its constraint
        // manifold.
        Err(LinearizeError::Singular { .. }) => {
            let opts = DescriptorOptions::default();
            let (desc, real) = linearize_descriptor(model, at(&motion, t0, &x0), &opts)
                .map_err(|source| DesignError::Descriptor { t: t0, source })?;
            let end = descriptor_system(model, at(&motion, t1, &x1), &opts)
                .map_err(|source| DesignError::Descriptor { t: t1, source })?;
            let drift = relative_change(&[&desc.e, &desc.a, &desc.b], &[&end.e, &end.a, &end.b]);
            (real.system.clone(), Some(real), drift)
        }
        Err(source) => return Err(DesignError::Linearize { t: t0, source }),
    };
    if !options.relative_degrees.is_empty() {
        check_relative_degrees(&system, &s.outputs, &options.relative_degrees)?;
    }
    let analysis = analyze(&system, &options.analysis)?;
    Ok(Design {
        motion,
        system,
        analysis,
        linearisation_drift,
        realisation,
    })
}

/// `max_k |after_k - before_k| / max_k |before_k|` over matrices of equal shapes.
fn relative_change(before: &[&DMatrix<f64>], after: &[&DMatrix<f64>]) -> f64 {
    let scale = before
        .iter()
        .map(|m| m.amax())
        .fold(f64::MIN_POSITIVE, f64::max);
    let change = before
        .iter()
        .zip(after)
        .map(|(b, a)| (*a - *b).amax())
        .fold(0.0, f64::max);
    change / scale
}

/// One output whose relative degree at the nominal is not the one assumed.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputDegree {
    /// The output's name.
    pub output: String,
    /// Its relative degree in the linearisation at the nominal; `None` when no input reaches
    /// it there.
    pub at_nominal: Option<usize>,
    /// The relative degree the tracking DAE was compiled for.
    pub assumed: usize,
}

/// Relative degrees at the nominal that differ from the compiled ones, or a decoupling
/// matrix that is singular there.
#[derive(Debug, Clone, PartialEq)]
pub struct RelativeDegreeMismatch {
    /// The outputs whose degrees differ.
    pub outputs: Vec<OutputDegree>,
    /// When the degrees agree but the rows `C_i A^(r_i - 1) B` are dependent: the rank found
    /// and the number of outputs.
    pub decoupling_rank: Option<(usize, usize)>,
}

impl fmt::Display for RelativeDegreeMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, o) in self.outputs.iter().enumerate() {
            if k > 0 {
                f.write_str("; ")?;
            }
            match o.at_nominal {
                Some(r) => write!(
                    f,
                    "output `{}`: relative degree {r} at the nominal, {} assumed by the tracking DAE",
                    o.output, o.assumed
                )?,
                None => write!(
                    f,
                    "output `{}`: no input reaches it at the nominal, relative degree {} assumed by the tracking DAE",
                    o.output, o.assumed
                )?,
            }
        }
        if let Some((rank, m)) = self.decoupling_rank {
            write!(
                f,
                "the decoupling matrix of the outputs has rank {rank} of {m} at the nominal: the tracking DAE is singular there"
            )?;
        }
        f.write_str(
            " (the compiled relative degrees are structural; the plant's true ones at this point are higher: track other outputs, or declare the model so that the inputs enter where the structure says)",
        )
    }
}

/// The relative degree of each output of `sys` (the first `k` with `C_i A^(k-1) B != 0`, `0`
/// when `D_i != 0`); `None` where no input reaches the output.
///
/// A Markov row `m = C_i A^(k-1) B` counts as non-zero when it exceeds both its own rounding
/// noise and a relative threshold: `|m| > 1e-10 |v| |B| + 64 eps | |C_i| |A|^(k-1) |B| |`, with
/// `v = C_i A^(k-1)` the row as computed (so a row is measured against its own size, not
/// against `|C_i| |A|^(k-1)`, which for a stiff or many-link plant is dominated by other parts
/// of `A` and would hide a true degree) and the entrywise product of absolute values bounding
/// the error of the computed product.
pub fn linear_relative_degrees(sys: &LinearSystem) -> Vec<Option<usize>> {
    let n = sys.a.nrows();
    let nb = sys.b.norm();
    let (abs_a, abs_b) = (sys.a.abs(), sys.b.abs());
    let tol = 1e-10;
    let noise = 64.0 * f64::EPSILON;
    (0..sys.c.nrows())
        .map(|i| {
            let d = sys.d.row(i);
            if d.norm() > tol * (sys.c.row(i).norm() * nb + d.norm()).max(f64::MIN_POSITIVE) {
                return Some(0);
            }
            let mut v = sys.c.row(i).into_owned();
            let mut abs_v = v.abs();
            for k in 1..=n {
                if v.iter().all(|&e| e == 0.0) {
                    return None;
                }
                let markov = &v * &sys.b;
                let rounding = (&abs_v * &abs_b).norm();
                if markov.norm() > tol * v.norm() * nb + noise * rounding {
                    return Some(k);
                }
                v = &v * &sys.a;
                abs_v = &abs_v * &abs_a;
            }
            None
        })
        .collect()
}

/// Compare the relative degrees a tracking DAE assumes (`assumed`, per output; `None` where
/// the model does not define one, which is not checked) with those of the linearisation
/// `sys` at the nominal, and check that the decoupling matrix is regular.
///
/// # Errors
/// [`DesignError::RelativeDegree`] naming every output that differs, or the rank of a
/// singular decoupling matrix.
pub fn check_relative_degrees(
    sys: &LinearSystem,
    outputs: &Names,
    assumed: &[Option<usize>],
) -> Result<(), DesignError> {
    let found = linear_relative_degrees(sys);
    let mut mismatches = Vec::new();
    for (i, (f, a)) in found.iter().zip(assumed).enumerate() {
        if let Some(a) = a {
            if *f != Some(*a) {
                mismatches.push(OutputDegree {
                    output: outputs.get(i).unwrap_or("?").to_string(),
                    at_nominal: *f,
                    assumed: *a,
                });
            }
        }
    }
    if !mismatches.is_empty() {
        return Err(DesignError::RelativeDegree(RelativeDegreeMismatch {
            outputs: mismatches,
            decoupling_rank: None,
        }));
    }
    if assumed.len() != found.len() || assumed.iter().any(Option::is_none) {
        return Ok(());
    }
    let m = found.len();
    let mut decoupling = DMatrix::zeros(m, sys.b.ncols());
    for (i, r) in found.iter().enumerate() {
        let row = match r {
            Some(0) | None => sys.d.row(i).into_owned(),
            Some(r) => {
                let mut v = sys.c.row(i).into_owned();
                for _ in 1..*r {
                    v = &v * &sys.a;
                }
                &v * &sys.b
            }
        };
        // Each row is scaled to unit length: the rank question is about directions.
        let norm = row.norm().max(f64::MIN_POSITIVE);
        decoupling.row_mut(i).copy_from(&(row / norm));
    }
    let sv = decoupling.singular_values();
    let tol = (m.max(1) as f64) * 1e-10;
    let rank = sv.iter().filter(|v| **v > tol).count();
    if rank < m {
        return Err(DesignError::RelativeDegree(RelativeDegreeMismatch {
            outputs: Vec::new(),
            decoupling_rank: Some((rank, m)),
        }));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_degrees_of_a_chain_of_integrators() {
        // x1' = x2, x2' = u: y = x1 has degree 2, y = x2 degree 1.
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
        for (c, want) in [([1.0, 0.0], Some(2)), ([0.0, 1.0], Some(1))] {
            let sys = LinearSystem::new(
                a.clone(),
                b.clone(),
                DMatrix::from_row_slice(1, 2, &c),
                DMatrix::zeros(1, 1),
            )
            .unwrap();
            assert_eq!(linear_relative_degrees(&sys), vec![want]);
        }
        // y = x1 with x1 decoupled from u: unreachable.
        let a = DMatrix::zeros(2, 2);
        let sys = LinearSystem::new(
            a,
            b,
            DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
            DMatrix::zeros(1, 1),
        )
        .unwrap();
        assert_eq!(linear_relative_degrees(&sys), vec![None]);
        let names = Names::Owned(vec!["y".into()]);
        let err = check_relative_degrees(&sys, &names, &[Some(1)]).unwrap_err();
        assert!(
            err.to_string().contains("output `y`: no input reaches it"),
            "{err}"
        );
    }
}
