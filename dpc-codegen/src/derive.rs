//! Derivation: everything a checked model needs evaluated, as symbolic data.
//!
//! This pass takes the lowered model and the tracking rows of the Hirschorn steps and returns,
//! per generated type, the roots to be evaluated and where their variables come from:
//!
//! * the plant and its tracking DAE as [`DaeDerivatives`]: residual rows, the Jacobian blocks
//!   `dF/dx'`, `dF/dx`, `dF/dz`, `dF/du` and the iteration matrix `[dF/dx + c dF/dx' | dF/dz]`
//!   (each with its structural non-zeros), outputs and their Jacobians `dh/dx`, `dh/dz`,
//!   `dh/du`, the equation texts and the listing;
//! * the plant's position constraints' exact gradient, time derivative and second derivatives
//!   ([`ConstraintDerivatives`]), for the closed loop's index reduction;
//! * the relative degrees of the outputs, and per output the compiled coefficients of `W_i`;
//! * the references `xi_i(t)` with their exact time derivatives.
//!
//! It differentiates and nothing else: [`crate::emit`] turns the result into tokens and a
//! run-time model (the `dpc-runtime` crate) evaluates the same roots from the same graph, so
//! both evaluate identical expressions. Derivatives are created in a fixed order (plant,
//! relative degrees, tracking DAE, references, the plant's constraint derivatives) so that node ids, and with them the emitted
//! code, are deterministic.

use crate::hirschorn::{TrackingRow, TrackingSystem};
use crate::ir::{Model, Symbol};
use crate::symbolic::{ExprId, Var};
use proc_macro2::Ident;
use std::collections::BTreeMap;

/// A Jacobian block: the structurally non-zero entries `(row, col, expr)`.
#[derive(Clone, Debug, Default)]
pub struct Block {
    /// Non-zero entries in row-major order.
    pub entries: Vec<(usize, usize, ExprId)>,
}

impl Block {
    /// The structural non-zero positions `(row, col)`, in row-major order.
    pub fn pattern(&self) -> Vec<(usize, usize)> {
        self.entries.iter().map(|&(i, j, _)| (i, j)).collect()
    }

    /// The entries' expressions, in row-major order.
    pub fn exprs(&self) -> impl Iterator<Item = ExprId> + '_ {
        self.entries.iter().map(|e| e.2)
    }
}

/// Jacobian of `rows` with respect to the variables of `symbols`, skipping structural zeros.
pub fn jacobian(model: &mut Model, rows: &[ExprId], symbols: &[Symbol]) -> Block {
    let vars: Vec<Var> = symbols.iter().map(|s| model.var(*s)).collect();
    Block {
        entries: model.graph.jacobian(rows, &vars),
    }
}

/// Where a routine reads the value of a variable from.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// The time argument.
    Time,
    /// Entry `k` of the states.
    State(usize),
    /// Entry `k` of the state derivatives.
    StateDot(usize),
    /// Entry `k` of the algebraic unknowns.
    Algebraic(usize),
    /// Entry `k` of the inputs.
    Input(usize),
    /// Parameter `k` (in declaration order).
    Param(usize),
    /// Entry `k` of a tracking DAE's coefficients of `W` in use, all outputs concatenated
    /// (see [`crate::hirschorn::coefficient_index`]).
    WCoefficient(usize),
    /// The coefficient `c` of the iteration matrix.
    IterationCoefficient,
}

/// How the unknowns and inputs of one generated type map to the slices its routines take.
///
/// A plant and its tracking DAE share one graph and one set of symbols; they differ only in
/// which symbols are states, algebraic unknowns and inputs (in the tracking DAE the plant's
/// inputs are algebraic unknowns and the reference combinations `w_i` are the inputs).
#[derive(Clone, Debug)]
pub struct Layout {
    /// Symbols read from the states (and whose derivatives are read from the derivatives).
    pub states: Vec<Symbol>,
    /// Symbols read from the algebraic unknowns.
    pub algebraic: Vec<Symbol>,
    /// Symbols read from the inputs.
    pub inputs: Vec<Symbol>,
}

impl Layout {
    /// The layout of the plant itself.
    pub fn plant(model: &Model) -> Self {
        Layout {
            states: (0..model.states.len()).map(Symbol::State).collect(),
            algebraic: (0..model.algebraic.len()).map(Symbol::Algebraic).collect(),
            inputs: (0..model.inputs.len()).map(Symbol::Input).collect(),
        }
    }

    /// The layout of a routine of time and parameters only (the references).
    pub fn time_only() -> Self {
        Layout {
            states: vec![],
            algebraic: vec![],
            inputs: vec![],
        }
    }

    /// The derivative symbols of the states.
    pub fn state_dots(&self) -> Vec<Symbol> {
        self.states
            .iter()
            .map(|s| match s {
                Symbol::State(i) => Symbol::StateDot(*i),
                other => unreachable!("layout state {other:?} is not a state"),
            })
            .collect()
    }

    /// Where the value of `symbol` comes from in a routine of this layout (`w_degrees` from
    /// [`crate::hirschorn::w_degrees`] places the coefficients of `W`), or `None` for a
    /// symbol that has no place in it (the checks exclude such uses).
    pub fn source(&self, symbol: Symbol, w_degrees: &[usize]) -> Option<Source> {
        let find = |list: &[Symbol], s: Symbol| list.iter().position(|x| *x == s);
        match symbol {
            Symbol::Time => return Some(Source::Time),
            Symbol::Param(k) => return Some(Source::Param(k)),
            Symbol::IterationCoefficient => return Some(Source::IterationCoefficient),
            Symbol::TrackingCoefficient { output, power } => {
                return Some(Source::WCoefficient(crate::hirschorn::coefficient_index(
                    w_degrees, output, power,
                )))
            }
            Symbol::StateDot(i) => {
                if let Some(k) = find(&self.states, Symbol::State(i)) {
                    return Some(Source::StateDot(k));
                }
            }
            _ => {}
        }
        if let Some(k) = find(&self.states, symbol) {
            return Some(Source::State(k));
        }
        if let Some(k) = find(&self.algebraic, symbol) {
            return Some(Source::Algebraic(k));
        }
        find(&self.inputs, symbol).map(Source::Input)
    }
}

/// One type implementing `DaeModel` (the plant, or its tracking DAE) with every root its
/// routines evaluate.
#[derive(Clone, Debug)]
pub struct DaeDerivatives {
    /// Name of the type (the model's name, or the tracking type's).
    pub name: Ident,
    /// Which symbols are states, algebraic unknowns and inputs.
    pub layout: Layout,
    /// Residual rows.
    pub residuals: Vec<ExprId>,
    /// Text of each residual row.
    pub equation_texts: Vec<String>,
    /// Output names and expressions.
    pub outputs: Vec<(String, ExprId)>,
    /// Readable listing of the type's equations.
    pub listing: String,
    /// `dF/dx'`.
    pub f_xdot: Block,
    /// `dF/dx`.
    pub f_x: Block,
    /// `dF/dz`.
    pub f_z: Block,
    /// `dF/du`.
    pub f_u: Block,
    /// `dh/dx`.
    pub h_x: Block,
    /// `dh/dz`.
    pub h_z: Block,
    /// `dh/du`.
    pub h_u: Block,
    /// The iteration matrix `[dF/dx + c dF/dx' | dF/dz]`, assembled symbolically so the sum
    /// of the two blocks is one expression per entry; in row-major order.
    pub iteration: Block,
    /// The exact derivatives of the position-constraint rows (the plant's; empty for a
    /// tracking DAE, which is not index-reduced by `Stabilised`).
    pub constraints: ConstraintDerivatives,
}

impl DaeDerivatives {
    /// The output expressions, in order.
    pub fn output_exprs(&self) -> Vec<ExprId> {
        self.outputs.iter().map(|o| o.1).collect()
    }

    /// The roots of one `evaluate` call: residual rows, then the entries of `dF/dx'`,
    /// `dF/dx`, `dF/dz`, `dF/du` (scheduled together, so they share subexpressions).
    pub fn evaluate_roots(&self) -> Vec<ExprId> {
        let mut roots = self.residuals.clone();
        for b in [&self.f_xdot, &self.f_x, &self.f_z, &self.f_u] {
            roots.extend(b.exprs());
        }
        roots
    }

    /// The roots of one `residual_and_iteration_matrix` call: residual rows, then the entries
    /// of the iteration matrix (scheduled together, so the residual's subexpressions serve
    /// the matrix).
    pub fn residual_and_iteration_roots(&self) -> Vec<ExprId> {
        let mut roots = self.residuals.clone();
        roots.extend(self.iteration.exprs());
        roots
    }

    /// The roots of one `output_jacobians` call: the entries of `dh/dx`, `dh/dz`, `dh/du`.
    pub fn output_jacobian_roots(&self) -> Vec<ExprId> {
        [&self.h_x, &self.h_z, &self.h_u]
            .iter()
            .flat_map(|b| b.exprs())
            .collect()
    }
}

/// The exact derivatives of a plant's *position-constraint rows*: the equations `0 = g(t, x)`
/// of states, time and parameters only (no `x'`, no algebraic unknown, no input: no entry in
/// `dF/dx'`, `dF/dz` or `dF/du`, the classification dpc-core's consistent initialisation makes
/// at run time from the same patterns). The closed loop's index reduction (`Stabilised`)
/// needs their gradients `G = dg/dx`, `dg/dt` and the curvature
/// `d/dx_k (G v + dg/dt) = sum_j H_jk v_j + H_tk` along the velocities `v`; the second
/// derivatives `H_jk = d^2 g/(dx_j dx_k)` and `H_tk = d^2 g/(dt dx_k)` are derived here, the
/// sum over `j` is formed at run time (only over the structural non-zeros).
#[derive(Clone, Debug, Default)]
pub struct ConstraintDerivatives {
    /// The position-constraint rows, ascending.
    pub rows: Vec<usize>,
    /// `dg/dx`: the rows' entries of `dF/dx`, in row-major order.
    pub gradient: Block,
    /// `dg/dt` of the rows that depend on time explicitly, `(row, expr)`, ascending.
    pub time_derivative: Vec<(usize, ExprId)>,
    /// `H_jk = d^2 g/(dx_j dx_k)` as `(row, j, k, expr)`, structural non-zeros, ordered by
    /// row, then `j`, then `k`.
    pub hessian: Vec<(usize, usize, usize, ExprId)>,
    /// `H_tk = d^2 g/(dt dx_k)`: `(row, k, expr)`, structural non-zeros, row-major.
    pub time_hessian: Block,
}

/// One structural entry `(row, col)` of the curvature `sum_j H_jk v_j + H_tk`, with where its
/// terms' values are in [`ConstraintDerivatives::curvature_roots`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CurvatureEntry {
    /// The constraint row `g`.
    pub row: usize,
    /// The state `k` (the column).
    pub col: usize,
    /// Per term `H_jk v_j`: the index of `H_jk` among the roots, and `j`.
    pub terms: Vec<(usize, usize)>,
    /// The index of `H_tk` among the roots, if it is not structurally zero.
    pub time_term: Option<usize>,
}

impl ConstraintDerivatives {
    /// Whether the type has no position-constraint rows (nothing to emit).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The roots of the curvature routine: the entries of `H_jk`, then those of `H_tk`.
    pub fn curvature_roots(&self) -> Vec<ExprId> {
        let mut roots: Vec<ExprId> = self.hessian.iter().map(|h| h.3).collect();
        roots.extend(self.time_hessian.exprs());
        roots
    }

    /// The curvature's structural entries in row-major order, each with its terms.
    pub fn curvature_entries(&self) -> Vec<CurvatureEntry> {
        let mut entries: BTreeMap<(usize, usize), CurvatureEntry> = BTreeMap::new();
        let empty = |row: usize, col: usize| CurvatureEntry {
            row,
            col,
            terms: Vec::new(),
            time_term: None,
        };
        for (r, &(row, j, k, _)) in self.hessian.iter().enumerate() {
            let e = entries.entry((row, k)).or_insert_with(|| empty(row, k));
            e.terms.push((r, j));
        }
        let offset = self.hessian.len();
        for (r, &(row, k, _)) in self.time_hessian.entries.iter().enumerate() {
            let e = entries.entry((row, k)).or_insert_with(|| empty(row, k));
            e.time_term = Some(offset + r);
        }
        entries.into_values().collect()
    }
}

/// The tracking DAE: the plant equations plus one constraint row per output.
#[derive(Clone, Debug)]
pub struct TrackingDerivatives {
    /// Its residual, Jacobians and outputs.
    pub dae: DaeDerivatives,
    /// Per output, the compiled monic coefficients of `W_i`, lowest power first.
    pub w_defaults: Vec<Vec<f64>>,
    /// Number of algebraic unknowns before the plant's inputs: the plant's own, then the
    /// higher derivatives of states that steps through implicit equations add.
    pub plant_algebraic: usize,
}

/// The references of a `references` section with their exact time derivatives.
#[derive(Clone, Debug)]
pub struct ReferenceDerivatives {
    /// The highest derivative order provided (one more than the tracking DAE needs).
    pub max_order: usize,
    /// `roots[k * m + i] = d^k xi_i / dt^k` for `k = 0..=max_order`, `m` outputs.
    pub roots: Vec<ExprId>,
    /// Per output, `name = expression` as written.
    pub texts: Vec<String>,
}

/// Everything to be emitted or evaluated for one model.
#[derive(Clone, Debug)]
pub struct Derived {
    /// The plant.
    pub plant: DaeDerivatives,
    /// Per output, the relative degree (`None` where it is not defined).
    pub relative_degrees: Vec<Option<usize>>,
    /// Per output, the compiled degree of `W_i` (0 without a `tracking` entry).
    pub w_degrees: Vec<usize>,
    /// With a `tracking` section, the tracking DAE.
    pub tracking: Option<TrackingDerivatives>,
    /// With a `references` section, the references.
    pub references: Option<ReferenceDerivatives>,
}

/// Human-readable listing of a model: declarations, intermediates, equations, outputs.
pub fn listing(model: &Model) -> String {
    let mut s = format!("model {}\n", model.name);
    if !model.params.is_empty() {
        let ps: Vec<String> = model
            .params
            .iter()
            .map(|p| format!("{}{} = {:?}", p.label, unit_suffix(&p.unit), p.default))
            .collect();
        s += &format!("  params     {}\n", ps.join(", "));
    }
    let names = |d: &[crate::ir::Decl]| {
        d.iter()
            .map(|x| format!("{}{}", x.label, unit_suffix(&x.unit)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    s += &format!("  states     {}\n", names(&model.states));
    if !model.algebraic.is_empty() {
        s += &format!("  algebraic  {}\n", names(&model.algebraic));
    }
    if !model.inputs.is_empty() {
        s += &format!("  inputs     {}\n", names(&model.inputs));
    }
    for l in &model.intermediates {
        s += &format!("  let {} = {}\n", l.label, l.text);
    }
    s += "  equations\n";
    for (i, e) in model.equations.iter().enumerate() {
        s += &format!("    [{i}] {}\n", e.text);
    }
    if !model.outputs.is_empty() {
        s += "  outputs\n";
        for o in &model.outputs {
            s += &format!("    {}{} = {}\n", o.label, unit_suffix(&o.unit), o.text);
        }
    }
    s
}

/// ` [unit]` after a name in the listing, or nothing.
fn unit_suffix(unit: &Option<String>) -> String {
    unit.as_ref().map(|u| format!(" [{u}]")).unwrap_or_default()
}

/// Derive everything for a lowered, checked model; `system` holds the tracking rows from
/// [`crate::hirschorn::tracking_rows`] (`None` without a `tracking` section).
pub fn derive(model: &mut Model, system: Option<&TrackingSystem>) -> Derived {
    let plant_outputs: Vec<(String, ExprId)> = model
        .outputs
        .iter()
        .map(|o| (o.label.clone(), o.expr))
        .collect();
    let plant = derive_dae(
        model,
        model.name.clone(),
        Layout::plant(model),
        model.equations.iter().map(|e| e.residual).collect(),
        model.equations.iter().map(|e| e.text.clone()).collect(),
        plant_outputs.clone(),
        listing(model),
    );
    let relative_degrees = crate::hirschorn::relative_degrees(model);
    let tracking = system.and_then(|system| derive_tracking(model, system, plant_outputs));
    let references = derive_references(model, system.map(|s| &s.rows[..]));
    // Last, so the nodes of everything above (and the code emitted from them) do not move.
    let mut plant = plant;
    plant.constraints = derive_constraints(model, &plant);
    Derived {
        plant,
        relative_degrees,
        w_degrees: crate::hirschorn::w_degrees(model),
        tracking,
        references,
    }
}

/// Residual, Jacobians and the iteration matrix of one type.
fn derive_dae(
    model: &mut Model,
    name: Ident,
    layout: Layout,
    residuals: Vec<ExprId>,
    equation_texts: Vec<String>,
    outputs: Vec<(String, ExprId)>,
    listing: String,
) -> DaeDerivatives {
    let nx = layout.states.len();
    let f_xdot = jacobian(model, &residuals, &layout.state_dots());
    let f_x = jacobian(model, &residuals, &layout.states);
    let f_z = jacobian(model, &residuals, &layout.algebraic);
    let f_u = jacobian(model, &residuals, &layout.inputs);
    let output_exprs: Vec<ExprId> = outputs.iter().map(|o| o.1).collect();
    let h_x = jacobian(model, &output_exprs, &layout.states);
    let h_z = jacobian(model, &output_exprs, &layout.algebraic);
    let h_u = jacobian(model, &output_exprs, &layout.inputs);

    let c_var = model.var(Symbol::IterationCoefficient);
    let c = model.graph.var(c_var);
    let mut iteration: BTreeMap<(usize, usize), ExprId> = BTreeMap::new();
    for &(i, j, e) in &f_x.entries {
        iteration.insert((i, j), e);
    }
    for &(i, j, e) in &f_xdot.entries {
        let scaled = model.graph.mul(c, e);
        let entry = match iteration.get(&(i, j)) {
            Some(&prev) => model.graph.add(prev, scaled),
            None => scaled,
        };
        iteration.insert((i, j), entry);
    }
    for &(i, j, e) in &f_z.entries {
        iteration.insert((i, nx + j), e);
    }
    DaeDerivatives {
        name,
        layout,
        residuals,
        equation_texts,
        outputs,
        listing,
        f_xdot,
        f_x,
        f_z,
        f_u,
        h_x,
        h_z,
        h_u,
        iteration: Block {
            entries: iteration.into_iter().map(|((i, j), e)| (i, j, e)).collect(),
        },
        constraints: ConstraintDerivatives::default(),
    }
}

/// The exact derivatives of the position-constraint rows of `ty` (see
/// [`ConstraintDerivatives`]).
fn derive_constraints(model: &mut Model, ty: &DaeDerivatives) -> ConstraintDerivatives {
    let in_row = |b: &Block, i: usize| b.entries.iter().any(|e| e.0 == i);
    let rows: Vec<usize> = (0..ty.residuals.len())
        .filter(|&i| !(in_row(&ty.f_xdot, i) || in_row(&ty.f_z, i) || in_row(&ty.f_u, i)))
        .collect();
    if rows.is_empty() {
        return ConstraintDerivatives::default();
    }
    let states: Vec<Var> = ty.layout.states.iter().map(|s| model.var(*s)).collect();
    let gradient = Block {
        entries: ty
            .f_x
            .entries
            .iter()
            .filter(|e| rows.contains(&e.0))
            .copied()
            .collect(),
    };
    let mut hessian = Vec::new();
    for &(g, j, e) in &gradient.entries {
        for (k, &v) in states.iter().enumerate() {
            let h = model.graph.diff(e, v);
            if !model.graph.is_zero(h) {
                hessian.push((g, j, k, h));
            }
        }
    }
    let time = model.var(Symbol::Time);
    let mut time_derivative = Vec::new();
    let mut time_hessian = Vec::new();
    for &g in &rows {
        let d = model.graph.diff(ty.residuals[g], time);
        if model.graph.is_zero(d) {
            continue;
        }
        time_derivative.push((g, d));
        for (k, &v) in states.iter().enumerate() {
            let h = model.graph.diff(d, v);
            if !model.graph.is_zero(h) {
                time_hessian.push((g, k, h));
            }
        }
    }
    ConstraintDerivatives {
        rows,
        gradient,
        time_derivative,
        hessian,
        time_hessian: Block {
            entries: time_hessian,
        },
    }
}

/// The tracking DAE: the plant equations, the derivatives of implicit equations the steps
/// need, and one constraint row per output, in the unknowns `(X, [Z; D; U])` (`D` the higher
/// derivatives of states those derivatives determine) with the inputs `w`.
fn derive_tracking(
    model: &mut Model,
    system: &TrackingSystem,
    outputs: Vec<(String, ExprId)>,
) -> Option<TrackingDerivatives> {
    let tracking = model.tracking.clone()?;
    let rows: &[TrackingRow] = &system.rows;
    let mut layout = Layout::plant(model);
    let inputs = std::mem::take(&mut layout.inputs);
    layout
        .algebraic
        .extend(system.higher_derivatives.iter().copied());
    layout.algebraic.extend(inputs);
    layout.inputs = (0..model.outputs.len())
        .map(Symbol::TrackingInput)
        .collect();

    let mut residuals: Vec<ExprId> = model.equations.iter().map(|e| e.residual).collect();
    let mut texts: Vec<String> = model.equations.iter().map(|e| e.text.clone()).collect();
    let mut listing_text = listing(model);
    let input_names: Vec<String> = model.inputs.iter().map(|d| d.label.clone()).collect();
    let w_names: Vec<String> = model
        .outputs
        .iter()
        .map(|o| format!("w_{}", o.label))
        .collect();
    listing_text += &format!(
        "tracking {}: the equations above, with {} as algebraic unknowns and inputs {}, plus\n",
        tracking.type_name,
        input_names.join(", "),
        w_names.join(", ")
    );
    if !system.velocity_constraints.is_empty() {
        listing_text +=
            "  position constraints replaced by their first derivatives (velocity constraints)\n";
        for &(k, d) in &system.velocity_constraints {
            let text = format!("{} ({})", derivative_operator(1), model.equations[k].text);
            listing_text += &format!("    [{k}] {text}\n");
            residuals[k] = d;
            texts[k] = text;
        }
    }
    if !system.differentiated.is_empty() {
        let unknowns: Vec<String> = system
            .higher_derivatives
            .iter()
            .map(|s| model.symbol_name(*s))
            .collect();
        listing_text += &format!(
            "  derivatives of implicit equations, with {} as algebraic unknowns\n",
            unknowns.join(", ")
        );
        for d in &system.differentiated {
            let text = format!(
                "{} ({})",
                derivative_operator(d.order),
                model.equations[d.equation].text
            );
            listing_text += &format!("    [{}] {text}\n", d.equation);
            residuals.push(d.residual);
            texts.push(text);
        }
    }
    for row in rows {
        let out = model.outputs[row.output].label.clone();
        let roots: Vec<f64> = tracking
            .entries
            .iter()
            .find(|e| e.output == row.output)
            .map(|e| e.roots.clone())
            .unwrap_or_default();
        listing_text += &format!(
            "  output {out}: W(s) = {}\n",
            crate::hirschorn::polynomial_text(&roots)
        );
        for (k, d) in row.derivatives.iter().enumerate().skip(1) {
            listing_text += &format!(
                "    {} {out} = {}\n",
                derivative_operator(k),
                model.display(*d)
            );
        }
        let text = format!("{} == w_{out}", model.display(row.combination));
        listing_text += &format!("    {text}\n");
        residuals.push(row.row);
        texts.push(text);
    }
    let plant_algebraic = model.algebraic.len() + system.higher_derivatives.len();
    let dae = derive_dae(
        model,
        tracking.type_name.clone(),
        layout,
        residuals,
        texts,
        outputs,
        listing_text,
    );
    Some(TrackingDerivatives {
        dae,
        w_defaults: rows.iter().map(|r| r.coefficients.clone()).collect(),
        plant_algebraic,
    })
}

/// `d/dt`, `d^2/dt^2`, ...
fn derivative_operator(order: usize) -> String {
    match order {
        1 => "d/dt".to_string(),
        _ => format!("d^{order}/dt^{order}"),
    }
}

/// The references with exact derivatives up to one more than the tracking DAE needs.
fn derive_references(
    model: &mut Model,
    rows: Option<&[TrackingRow]>,
) -> Option<ReferenceDerivatives> {
    if model.references.is_empty() {
        return None;
    }
    let m = model.outputs.len();
    let needed = rows
        .map(|r| {
            r.iter()
                .map(|r| r.coefficients.len() - 1)
                .max()
                .unwrap_or(0)
        })
        .unwrap_or(0);
    let max_order = needed + 1;
    let time = model.var(Symbol::Time);
    let mut per_output: Vec<Vec<ExprId>> = Vec::new();
    let mut texts = Vec::new();
    for i in 0..m {
        // Lowering checks that every output has exactly one reference.
        let r = model.references.iter().find(|r| r.output == i)?.clone();
        texts.push(format!("{} = {}", model.outputs[i].label, r.text));
        let mut ds = vec![r.expr];
        for k in 0..max_order {
            let d = model.graph.diff(ds[k], time);
            ds.push(d);
        }
        per_output.push(ds);
    }
    let roots: Vec<ExprId> = (0..=max_order)
        .flat_map(|k| per_output.iter().map(move |ds| ds[k]))
        .collect();
    Some(ReferenceDerivatives {
        max_order,
        roots,
        texts,
    })
}
