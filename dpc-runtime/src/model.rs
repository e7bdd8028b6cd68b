//! The run-time model: the derived roots compiled into tapes, and the `dpc-core` traits.

use std::borrow::Cow;
use std::fmt;
use std::sync::Arc;

use dpc_codegen::derive::{Block, ConstraintDerivatives, DaeDerivatives, Derived, Layout};
use dpc_codegen::hirschorn::RelativeDegree;
use dpc_codegen::ir::{Model, Symbol};
use dpc_codegen::symbolic::ExprId;
use dpc_core::model::{Names, Structure, Units};
use dpc_core::reference::{check_buffer, Reference, ReferenceError};
use dpc_core::tracking::{check_w_coefficients, TrackingError};
use dpc_core::{DaeModel, MatrixSink, TrackingDae};

use crate::tape::{Args, Tape, Values};
use crate::PlantFileError;

/// The tapes of one type implementing `DaeModel` (the plant, or its tracking DAE).
#[derive(Debug)]
struct DaeTapes {
    structure: Structure,
    listing: String,
    residual: Tape,
    /// Residual rows, then the entries of `dF/dx'`, `dF/dx`, `dF/dz`, `dF/du`.
    evaluate: Tape,
    iteration: Tape,
    iteration_pattern: Vec<(usize, usize)>,
    /// The entries of `dF/dx'` alone (the mass matrix).
    mass: Tape,
    outputs: Tape,
    /// The entries of `dh/dx`, `dh/dz`, `dh/du`.
    output_jacobians: Tape,
    pattern_h_z: Vec<(usize, usize)>,
    pattern_h_u: Vec<(usize, usize)>,
    /// The position constraints' exact derivatives; `None` for a type without
    /// position-constraint rows (and for a tracking DAE, whose derive pass gives none).
    constraints: Option<ConstraintTapes>,
}

/// The tapes of the position-constraint rows' exact derivatives (the derive pass's
/// [`ConstraintDerivatives`], as `dpc::model!` emits them).
#[derive(Debug)]
struct ConstraintTapes {
    /// The entries of `dg/dx`.
    gradient: Tape,
    gradient_pattern: Vec<(usize, usize)>,
    /// `dg/dt` of the rows that depend on time explicitly (`time_rows`).
    time_derivative: Tape,
    time_rows: Vec<usize>,
    /// The entries of `H_jk = d^2 g/(dx_j dx_k)`, then those of `H_tk = d^2 g/(dt dx_k)`.
    curvature: Tape,
    /// The curvature's structural entries, row-major.
    curvature_entries: Vec<CurvatureSum>,
    /// The terms `H_jk v_j` of all entries, each entry's contiguous: `(root of H_jk, j)`.
    curvature_terms: Vec<(usize, usize)>,
}

/// One structural entry `(row, col)` of the curvature `sum_j H_jk v_j + H_tk`.
#[derive(Debug)]
struct CurvatureSum {
    row: usize,
    col: usize,
    /// Its terms in [`ConstraintTapes::curvature_terms`].
    terms: std::ops::Range<usize>,
    /// The root of `H_tk`, if it is not structurally zero.
    time: Option<usize>,
}

impl ConstraintTapes {
    /// The tapes of `c`, compiled by `tape`; `None` without position-constraint rows.
    fn compile<E>(
        c: &ConstraintDerivatives,
        tape: impl Fn(&[ExprId]) -> Result<Tape, E>,
    ) -> Result<Option<Self>, E> {
        if c.is_empty() {
            return Ok(None);
        }
        let time_roots: Vec<ExprId> = c.time_derivative.iter().map(|d| d.1).collect();
        let mut curvature_terms = Vec::new();
        let curvature_entries = c
            .curvature_entries()
            .into_iter()
            .map(|e| {
                let start = curvature_terms.len();
                curvature_terms.extend(e.terms.iter().copied());
                CurvatureSum {
                    row: e.row,
                    col: e.col,
                    terms: start..curvature_terms.len(),
                    time: e.time_term,
                }
            })
            .collect();
        Ok(Some(ConstraintTapes {
            gradient: tape(&c.gradient.exprs().collect::<Vec<_>>())?,
            gradient_pattern: c.gradient.pattern(),
            time_derivative: tape(&time_roots)?,
            time_rows: c.time_derivative.iter().map(|d| d.0).collect(),
            curvature: tape(&c.curvature_roots())?,
            curvature_entries,
            curvature_terms,
        }))
    }

    fn gradient<S: MatrixSink + ?Sized>(&self, args: &Args<'_>, out: &mut S) {
        self.gradient
            .eval(args, |v| write(v, 0, &self.gradient_pattern, out));
    }

    fn time_derivative(&self, args: &Args<'_>, out: &mut [f64]) {
        if self.time_rows.is_empty() {
            return;
        }
        self.time_derivative.eval(args, |v| {
            for (k, &g) in self.time_rows.iter().enumerate() {
                out[g] = v.get(k);
            }
        });
    }

    /// Per structural entry, `sum_j H_jk v_j + H_tk` over its terms, summed in the order
    /// the macro's code sums them.
    fn curvature<S: MatrixSink + ?Sized>(&self, args: &Args<'_>, v: &[f64], out: &mut S) {
        if self.curvature_entries.is_empty() {
            return;
        }
        self.curvature.eval(args, |h| {
            for e in &self.curvature_entries {
                let terms = self.curvature_terms[e.terms.clone()]
                    .iter()
                    .map(|&(r, j)| h.get(r) * v[j]);
                let sum = terms
                    .chain(e.time.map(|r| h.get(r)))
                    .reduce(|a, b| a + b)
                    .unwrap_or(0.0);
                out.set(e.row, e.col, sum);
            }
        });
    }
}

impl DaeTapes {
    fn compile(
        model: &Model,
        d: &DaeDerivatives,
        w_degrees: &[usize],
        origin: &str,
    ) -> Result<Self, PlantFileError> {
        let tape = |roots: &[ExprId]| {
            Tape::compile(model, &d.layout, w_degrees, roots).map_err(|u| {
                PlantFileError::Unplaced {
                    path: origin.to_string(),
                    model: d.name.to_string(),
                    symbol: u.symbol,
                }
            })
        };
        let names =
            |list: &[Symbol]| Names::Owned(list.iter().map(|s| model.symbol_name(*s)).collect());
        let pattern = |b: &Block| Cow::Owned(b.pattern());
        Ok(DaeTapes {
            structure: Structure {
                name: Cow::Owned(d.name.to_string()),
                states: names(&d.layout.states),
                algebraic: names(&d.layout.algebraic),
                inputs: names(&d.layout.inputs),
                outputs: Names::Owned(d.outputs.iter().map(|o| o.0.clone()).collect()),
                params: Names::Owned(model.params.iter().map(|p| p.label.clone()).collect()),
                equations: Names::Owned(d.equation_texts.clone()),
                units: Units::Owned(model.units()),
                pattern_f_xdot: pattern(&d.f_xdot),
                pattern_f_x: pattern(&d.f_x),
                pattern_f_z: pattern(&d.f_z),
                pattern_f_u: pattern(&d.f_u),
                pattern_h_x: pattern(&d.h_x),
            },
            listing: d.listing.clone(),
            residual: tape(&d.residuals)?,
            evaluate: tape(&d.evaluate_roots())?,
            iteration: tape(&d.iteration.exprs().collect::<Vec<_>>())?,
            iteration_pattern: d.iteration.pattern(),
            mass: tape(&d.f_xdot.exprs().collect::<Vec<_>>())?,
            outputs: tape(&d.output_exprs())?,
            output_jacobians: tape(&d.output_jacobian_roots())?,
            pattern_h_z: d.h_z.pattern(),
            pattern_h_u: d.h_u.pattern(),
            constraints: ConstraintTapes::compile(&d.constraints, tape)?,
        })
    }

    /// The tapes of a type with no equations, unknowns or outputs.
    fn empty(name: String) -> Self {
        let none = || Names::Owned(Vec::new());
        let empty = || Cow::Owned(Vec::new());
        let tape = Tape::compile_empty();
        DaeTapes {
            structure: Structure {
                name: Cow::Owned(name),
                states: none(),
                algebraic: none(),
                inputs: none(),
                outputs: none(),
                params: none(),
                equations: none(),
                units: Units::Owned(Vec::new()),
                pattern_f_xdot: empty(),
                pattern_f_x: empty(),
                pattern_f_z: empty(),
                pattern_f_u: empty(),
                pattern_h_x: empty(),
            },
            listing: String::new(),
            residual: tape.clone(),
            evaluate: tape.clone(),
            iteration: tape.clone(),
            iteration_pattern: Vec::new(),
            mass: tape.clone(),
            outputs: tape.clone(),
            output_jacobians: tape,
            pattern_h_z: Vec::new(),
            pattern_h_u: Vec::new(),
            constraints: None,
        }
    }

    /// Root `i` into `out[i]` for every root: a wrong length panics, as in generated code.
    fn residual(&self, args: &Args<'_>, out: &mut [f64]) {
        self.residual.eval(args, |v| v.copy_into(out, v.len()));
    }

    #[allow(clippy::too_many_arguments)]
    fn evaluate<A, B, C, D>(
        &self,
        args: &Args<'_>,
        residual: &mut [f64],
        f_xdot: &mut A,
        f_x: &mut B,
        f_z: &mut C,
        f_u: &mut D,
    ) where
        A: MatrixSink + ?Sized,
        B: MatrixSink + ?Sized,
        C: MatrixSink + ?Sized,
        D: MatrixSink + ?Sized,
    {
        let s = &self.structure;
        self.evaluate.eval(args, |v| {
            v.copy_into(residual, s.n_equations());
            let mut k = s.n_equations();
            k = write(v, k, &s.pattern_f_xdot, f_xdot);
            k = write(v, k, &s.pattern_f_x, f_x);
            k = write(v, k, &s.pattern_f_z, f_z);
            write(v, k, &s.pattern_f_u, f_u);
        });
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(&self, args: &Args<'_>, out: &mut S) {
        self.iteration
            .eval(args, |v| write(v, 0, &self.iteration_pattern, out));
    }

    fn mass_matrix<S: MatrixSink + ?Sized>(&self, args: &Args<'_>, out: &mut S) {
        self.mass
            .eval(args, |v| write(v, 0, &self.structure.pattern_f_xdot, out));
    }

    fn outputs(&self, args: &Args<'_>, out: &mut [f64]) {
        self.outputs.eval(args, |v| v.copy_into(out, v.len()));
    }

    fn output_jacobians<A, B, C>(&self, args: &Args<'_>, h_x: &mut A, h_z: &mut B, h_u: &mut C)
    where
        A: MatrixSink + ?Sized,
        B: MatrixSink + ?Sized,
        C: MatrixSink + ?Sized,
    {
        self.output_jacobians.eval(args, |v| {
            let k = write(v, 0, &self.structure.pattern_h_x, h_x);
            let k = write(v, k, &self.pattern_h_z, h_z);
            write(v, k, &self.pattern_h_u, h_u);
        });
    }

    /// `DaeModel::constraint_gradient`: `false` without position-constraint rows.
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, args: &Args<'_>, out: &mut S) -> bool {
        let Some(c) = &self.constraints else {
            return false;
        };
        c.gradient(args, out);
        true
    }

    /// `DaeModel::constraint_time_derivative`: `false` without position-constraint rows.
    fn constraint_time_derivative(&self, args: &Args<'_>, out: &mut [f64]) -> bool {
        let Some(c) = &self.constraints else {
            return false;
        };
        c.time_derivative(args, out);
        true
    }

    /// `DaeModel::constraint_curvature`: `false` without position-constraint rows.
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        args: &Args<'_>,
        v: &[f64],
        out: &mut S,
    ) -> bool {
        let Some(c) = &self.constraints else {
            return false;
        };
        c.curvature(args, v, out);
        true
    }
}

/// Write roots `first..` into `sink` at the positions of `pattern`; the next root's index.
fn write<S: MatrixSink + ?Sized>(
    v: Values<'_>,
    first: usize,
    pattern: &[(usize, usize)],
    sink: &mut S,
) -> usize {
    for (k, &(i, j)) in pattern.iter().enumerate() {
        sink.set(i, j, v.get(first + k));
    }
    first + pattern.len()
}

/// The tracking DAE's part of a compiled model.
#[derive(Debug)]
struct TrackingPart {
    tapes: DaeTapes,
    /// Per output, the compiled monic coefficients of `W_i`, lowest power first.
    w_defaults: Vec<Vec<f64>>,
    /// Output `i` owns `w[w_offsets[i]..w_offsets[i + 1]]` of the coefficients in use.
    w_offsets: Vec<usize>,
    relative_degrees: Vec<Option<usize>>,
    plant_algebraic: usize,
}

/// The references' part of a compiled model.
#[derive(Debug)]
struct ReferencePart {
    name: String,
    tape: Tape,
    max_order: usize,
    dimension: usize,
}

/// A plant file, compiled: shared (behind an `Arc`) by every value made from it.
struct Compiled {
    origin: String,
    name: String,
    plant: DaeTapes,
    /// Present (possibly empty, see [`RuntimeTracking`]) for every model.
    tracking: TrackingPart,
    has_tracking: bool,
    references: Option<ReferencePart>,
    analysis: Vec<RelativeDegree>,
    relative_degrees: Vec<Option<usize>>,
    defaults: Vec<f64>,
}

impl fmt::Debug for Compiled {
    /// The model's name and origin (the tapes are long and say little).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Compiled")
            .field("name", &self.name)
            .field("origin", &self.origin)
            .finish_non_exhaustive()
    }
}

/// A compiled plant file: the source of its plant, tracking DAE and reference values.
///
/// Cheap to clone (one shared compilation).
#[derive(Clone, Debug)]
pub struct RuntimeModel {
    compiled: Arc<Compiled>,
}

impl RuntimeModel {
    pub(crate) fn compile(
        origin: &str,
        mut model: Model,
        derived: Derived,
    ) -> Result<Self, PlantFileError> {
        let w = &derived.w_degrees;
        let plant = DaeTapes::compile(&model, &derived.plant, w, origin)?;
        let (tracking, has_tracking) = match &derived.tracking {
            Some(t) => {
                let mut w_offsets = vec![0];
                for c in &t.w_defaults {
                    w_offsets.push(w_offsets[w_offsets.len() - 1] + c.len());
                }
                (
                    TrackingPart {
                        tapes: DaeTapes::compile(&model, &t.dae, w, origin)?,
                        w_defaults: t.w_defaults.clone(),
                        w_offsets,
                        relative_degrees: derived.relative_degrees.clone(),
                        plant_algebraic: t.plant_algebraic,
                    },
                    true,
                )
            }
            None => (
                TrackingPart {
                    tapes: DaeTapes::empty(format!("{} (no tracking section)", model.name)),
                    w_defaults: Vec::new(),
                    w_offsets: vec![0],
                    relative_degrees: Vec::new(),
                    plant_algebraic: 0,
                },
                false,
            ),
        };
        let references = match &derived.references {
            Some(r) => Some(ReferencePart {
                name: format!("{}Reference", model.name),
                tape: Tape::compile(&model, &Layout::time_only(), w, &r.roots).map_err(|u| {
                    PlantFileError::Unplaced {
                        path: origin.to_string(),
                        model: format!("{}Reference", model.name),
                        symbol: u.symbol,
                    }
                })?,
                max_order: r.max_order,
                dimension: model.outputs.len(),
            }),
            None => None,
        };
        // How each relative degree was found; the derivatives are memoised in the graph,
        // which no tape reads any more.
        let analysis = dpc_codegen::hirschorn::relative_degree_analysis(&mut model);
        Ok(RuntimeModel {
            compiled: Arc::new(Compiled {
                origin: origin.to_string(),
                name: model.name.to_string(),
                plant,
                tracking,
                has_tracking,
                references,
                analysis,
                relative_degrees: derived.relative_degrees,
                defaults: model.params.iter().map(|p| p.default).collect(),
            }),
        })
    }

    /// The model's name as declared.
    pub fn name(&self) -> &str {
        &self.compiled.name
    }

    /// The file (or origin) it was read from.
    pub fn origin(&self) -> &str {
        &self.compiled.origin
    }

    /// The listing: declarations, equations and outputs, and with a `tracking` section the
    /// Hirschorn steps of the tracking DAE (the text of a generated tracking type's
    /// `LISTING`, or the plant's without one).
    pub fn listing(&self) -> &str {
        if self.compiled.has_tracking {
            &self.compiled.tracking.tapes.listing
        } else {
            &self.compiled.plant.listing
        }
    }

    /// Per output, the relative degree (`None` where it is not defined), as the macro's
    /// `RELATIVE_DEGREES`.
    pub fn relative_degrees(&self) -> &[Option<usize>] {
        &self.compiled.relative_degrees
    }

    /// Per output, the relative degree and how it was found (symbolically, structurally,
    /// unreached or undetermined).
    pub fn relative_degree_analysis(&self) -> &[RelativeDegree] {
        &self.compiled.analysis
    }

    /// The declared parameter values.
    pub fn params(&self) -> RuntimeParams {
        RuntimeParams {
            model: Arc::clone(&self.compiled),
            values: self.compiled.defaults.clone(),
        }
    }

    /// The plant with the declared parameters.
    pub fn plant(&self) -> RuntimePlant {
        RuntimePlant::from_params(self.params())
    }

    /// The tracking DAE with the declared parameters and the compiled `W`, if the file has a
    /// `tracking` section.
    pub fn tracking(&self) -> Option<RuntimeTracking> {
        self.compiled
            .has_tracking
            .then(|| RuntimeTracking::from_params(self.params()))
    }

    /// The references with the declared parameters, if the file has a `references` section.
    pub fn reference(&self) -> Option<RuntimeReference> {
        self.compiled.references.as_ref().map(|_| RuntimeReference {
            params: self.params(),
        })
    }

    /// Number of arithmetic instructions per call of the plant's `residual`, `evaluate`,
    /// `iteration_matrix`, `outputs` and `output_jacobians` (a measure of their cost).
    pub fn plant_instructions(&self) -> [usize; 5] {
        let p = &self.compiled.plant;
        [
            p.residual.len(),
            p.evaluate.len(),
            p.iteration.len(),
            p.outputs.len(),
            p.output_jacobians.len(),
        ]
    }
}

/// Parameter values of a run-time model, by index in declaration order (names in
/// [`Structure::params`]); shared by its plant, tracking DAE and references.
#[derive(Clone)]
pub struct RuntimeParams {
    model: Arc<Compiled>,
    values: Vec<f64>,
}

impl RuntimeParams {
    /// The values, in declaration order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The parameter names, in declaration order.
    pub fn names(&self) -> &Names {
        &self.model.plant.structure.params
    }
}

impl fmt::Debug for RuntimeParams {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}Params ", self.model.name)?;
        f.debug_map()
            .entries(self.names().iter().zip(&self.values))
            .finish()
    }
}

impl PartialEq for RuntimeParams {
    /// Equal values of the same compiled model.
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.model, &other.model) && self.values == other.values
    }
}

/// The plant of a plant file: implements [`DaeModel`].
#[derive(Clone, Debug, PartialEq)]
pub struct RuntimePlant {
    params: RuntimeParams,
}

/// The `DaeModel` methods of a type, delegated to its tapes (`self.tapes()`) with its `W`
/// coefficients (`self.w()`).
macro_rules! dae_model_methods {
    () => {
        fn from_params(params: Self::Params) -> Self {
            Self::new(params)
        }

        fn params(&self) -> &Self::Params {
            &self.params
        }

        fn parameter(params: &Self::Params, index: usize) -> Option<f64> {
            params.values.get(index).copied()
        }

        fn set_parameter(params: &mut Self::Params, index: usize, value: f64) -> bool {
            match params.values.get_mut(index) {
                Some(v) => {
                    *v = value;
                    true
                }
                None => false,
            }
        }

        fn residual(&self, t: f64, x: &[f64], xdot: &[f64], z: &[f64], u: &[f64], out: &mut [f64]) {
            let a = Args {
                t,
                x,
                xdot,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().residual(&a, out);
        }

        fn evaluate<A, B, C, D>(
            &self,
            t: f64,
            x: &[f64],
            xdot: &[f64],
            z: &[f64],
            u: &[f64],
            residual: &mut [f64],
            f_xdot: &mut A,
            f_x: &mut B,
            f_z: &mut C,
            f_u: &mut D,
        ) where
            A: MatrixSink + ?Sized,
            B: MatrixSink + ?Sized,
            C: MatrixSink + ?Sized,
            D: MatrixSink + ?Sized,
        {
            let a = Args {
                t,
                x,
                xdot,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().evaluate(&a, residual, f_xdot, f_x, f_z, f_u);
        }

        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            x: &[f64],
            xdot: &[f64],
            z: &[f64],
            u: &[f64],
            c: f64,
            out: &mut S,
        ) {
            let a = Args {
                t,
                x,
                xdot,
                z,
                u,
                c,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().iteration_matrix(&a, out);
        }

        fn mass_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            x: &[f64],
            xdot: &[f64],
            z: &[f64],
            u: &[f64],
            out: &mut S,
        ) -> bool {
            let a = Args {
                t,
                x,
                xdot,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().mass_matrix(&a, out);
            true
        }

        fn outputs(&self, t: f64, x: &[f64], z: &[f64], u: &[f64], out: &mut [f64]) {
            let a = Args {
                t,
                x,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().outputs(&a, out);
        }

        fn output_jacobians<A, B, C>(
            &self,
            t: f64,
            x: &[f64],
            z: &[f64],
            u: &[f64],
            h_x: &mut A,
            h_z: &mut B,
            h_u: &mut C,
        ) where
            A: MatrixSink + ?Sized,
            B: MatrixSink + ?Sized,
            C: MatrixSink + ?Sized,
        {
            let a = Args {
                t,
                x,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().output_jacobians(&a, h_x, h_z, h_u);
        }

        fn constraint_gradient<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            x: &[f64],
            z: &[f64],
            u: &[f64],
            out: &mut S,
        ) -> bool {
            let a = Args {
                t,
                x,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().constraint_gradient(&a, out)
        }

        fn constraint_time_derivative(
            &self,
            t: f64,
            x: &[f64],
            z: &[f64],
            u: &[f64],
            out: &mut [f64],
        ) -> bool {
            let a = Args {
                t,
                x,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().constraint_time_derivative(&a, out)
        }

        fn constraint_curvature<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            x: &[f64],
            z: &[f64],
            u: &[f64],
            v: &[f64],
            out: &mut S,
        ) -> bool {
            let a = Args {
                t,
                x,
                z,
                u,
                ..Args::model(&self.params.values, self.w())
            };
            self.tapes().constraint_curvature(&a, v, out)
        }
    };
}

impl RuntimePlant {
    /// The plant with the given parameters.
    pub fn new(params: RuntimeParams) -> Self {
        RuntimePlant { params }
    }

    /// The model's listing (see [`RuntimeModel::listing`]).
    pub fn listing(&self) -> &str {
        &self.params.model.plant.listing
    }

    fn tapes(&self) -> &DaeTapes {
        &self.params.model.plant
    }

    fn w(&self) -> &[f64] {
        &[]
    }
}

impl DaeModel for RuntimePlant {
    type Params = RuntimeParams;

    fn structure(&self) -> &Structure {
        &self.params.model.plant.structure
    }

    dae_model_methods!();
}

/// The tracking DAE of a plant file's `tracking` section: implements [`TrackingDae`], with
/// the coefficients of `W` in use held in the value (as generated tracking types do).
///
/// Made from the parameters of a file without a `tracking` section
/// ([`DaeModel::from_params`]), it is a DAE with no equations, unknowns or outputs, named
/// `NAME (no tracking section)`; [`RuntimeModel::tracking`] returns `None` for such a file.
#[derive(Clone, Debug, PartialEq)]
pub struct RuntimeTracking {
    params: RuntimeParams,
    w: Vec<f64>,
}

impl RuntimeTracking {
    /// The tracking DAE with the given parameters and the compiled `W`.
    pub fn new(params: RuntimeParams) -> Self {
        let w = params
            .model
            .tracking
            .w_defaults
            .iter()
            .flatten()
            .copied()
            .collect();
        RuntimeTracking { params, w }
    }

    /// The listing of the plant and its Hirschorn steps (a generated tracking type's
    /// `LISTING`).
    pub fn listing(&self) -> &str {
        &self.params.model.tracking.tapes.listing
    }

    fn tapes(&self) -> &DaeTapes {
        &self.params.model.tracking.tapes
    }

    fn w(&self) -> &[f64] {
        &self.w
    }

    fn range(&self, output: usize) -> std::ops::Range<usize> {
        let o = &self.params.model.tracking.w_offsets;
        match (o.get(output), o.get(output + 1)) {
            (Some(&a), Some(&b)) => a..b,
            _ => 0..0,
        }
    }
}

impl DaeModel for RuntimeTracking {
    type Params = RuntimeParams;

    fn structure(&self) -> &Structure {
        &self.params.model.tracking.tapes.structure
    }

    dae_model_methods!();
}

impl TrackingDae for RuntimeTracking {
    type Plant = RuntimePlant;

    fn default_w_coefficients(&self, output: usize) -> &[f64] {
        self.params
            .model
            .tracking
            .w_defaults
            .get(output)
            .map_or(&[], Vec::as_slice)
    }

    fn relative_degrees(&self) -> &[Option<usize>] {
        &self.params.model.tracking.relative_degrees
    }

    fn w_coefficients(&self, output: usize) -> &[f64] {
        &self.w[self.range(output)]
    }

    fn set_w_coefficients(
        &mut self,
        output: usize,
        coefficients: &[f64],
    ) -> Result<(), TrackingError> {
        check_w_coefficients(self, output, coefficients)?;
        let range = self.range(output);
        self.w[range].copy_from_slice(coefficients);
        Ok(())
    }

    fn plant_algebraic(&self) -> usize {
        self.params.model.tracking.plant_algebraic
    }
}

/// The references of a plant file's `references` section, with exact derivatives up to one
/// more than the tracking DAE needs: implements [`Reference`].
#[derive(Clone, Debug, PartialEq)]
pub struct RuntimeReference {
    params: RuntimeParams,
}

impl RuntimeReference {
    /// The references with the given parameters, if the model has a `references` section.
    pub fn new(params: RuntimeParams) -> Option<Self> {
        params
            .model
            .references
            .is_some()
            .then_some(RuntimeReference { params })
    }
}

impl Reference for RuntimeReference {
    fn dimension(&self) -> usize {
        self.params
            .model
            .references
            .as_ref()
            .map_or(0, |r| r.dimension)
    }

    fn max_order(&self) -> usize {
        self.params
            .model
            .references
            .as_ref()
            .map_or(0, |r| r.max_order)
    }

    fn derivatives(&self, t: f64, order: usize, out: &mut [f64]) -> Result<(), ReferenceError> {
        // `new` and `RuntimeModel::reference` only make values of models with references.
        let Some(r) = self.params.model.references.as_ref() else {
            return check_buffer(0, order, out);
        };
        if order > r.max_order {
            return Err(ReferenceError::OrderTooHigh {
                name: r.name.clone(),
                max: r.max_order,
                requested: order,
            });
        }
        check_buffer(r.dimension, order, out)?;
        r.tape.eval(&Args::time(t, &self.params.values), |v| {
            for (k, o) in out.iter_mut().enumerate() {
                *o = v.get(k);
            }
        });
        Ok(())
    }
}
