//! Stabilised Hirschorn steps and relative degrees (paper, Section 2).
//!
//! A step replaces the output constraint `h_i - xi_i = 0` by `W_i(d/dt)(h_i - xi_i) = 0`
//! with a stable `W_i(s) = prod_k (s + a_k)`. The total time derivative
//! `d/dt h = sum_j dh/dx_j x_j' + dh/dt` is taken symbolically; where the model states
//! `der(x_j) = f_j` explicitly, `x_j'` is replaced by `f_j`, so that chains of explicit
//! equations are differentiated through. Each step lowers the index of the tracking DAE by one,
//! so the integrator has to resolve less.
//!
//! The relative degree of an output (the number of differentiations after which an input
//! appears) is computed exactly along explicit equations and, once implicit equations are
//! reached, structurally: the derivatives of implicitly defined states and the algebraic
//! unknowns are matched to the implicit equations (a maximum bipartite matching, as in
//! Pantelides' algorithm), and each depends on everything its block of equations contains.
//! Constraints without an implicit unknown (position or velocity constraints with their
//! multipliers, index 3 or 2) are first differentiated until they contain one, as Pantelides'
//! algorithm would, so a constrained mechanism's outputs get the relative degrees of the
//! mechanism in minimal coordinates. The structural value is the generic one; it is exact unless
//! coefficients cancel.
//!
//! The degree of each `W_i` is fixed here, at compile time: it decides which derivatives are
//! generated. Its non-leading coefficients enter the emitted rows as variables
//! ([`Symbol::TrackingCoefficient`]) read from the tracking value, so the roots can change at
//! run time; the compiled values remain the defaults and appear in the listing.

use crate::ctxt::Ctxt;
use crate::ir::{Model, Symbol};
use crate::symbolic::{ExprId, Var};
use std::collections::{BTreeSet, HashMap};

/// Why a total time derivative cannot be taken symbolically.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Obstacle {
    /// The expression depends on input `i`, whose derivative is not available.
    Input(usize),
    /// The expression depends on algebraic unknown `i`, whose derivative is not available.
    Algebraic(usize),
    /// The expression contains `x_j'` of a state without explicit equation, so its
    /// derivative would need `x_j''`.
    ImplicitDerivative(usize),
}

/// The total time derivative of `e` along the model, substituting explicit equations.
pub fn total_derivative(model: &mut Model, e: ExprId) -> Result<ExprId, Obstacle> {
    let explicit = explicit_rhs(model);
    let mut dirs: Vec<(Var, ExprId)> = Vec::new();
    let syms: Vec<(Var, Symbol)> = model
        .graph
        .vars(e)
        .into_iter()
        .map(|v| (v, model.symbols.symbol(v)))
        .collect();
    if let Some(o) = syms.iter().find_map(|(_, s)| match s {
        Symbol::Input(i) => Some(Obstacle::Input(*i)),
        _ => None,
    }) {
        return Err(o);
    }
    for (v, s) in syms {
        match s {
            Symbol::State(j) => {
                let dx = match explicit.get(&j) {
                    Some(&f) => f,
                    None => {
                        let dv = model.var(Symbol::StateDot(j));
                        model.graph.var(dv)
                    }
                };
                dirs.push((v, dx));
            }
            Symbol::Time => {
                let one = model.graph.constant(1.0);
                dirs.push((v, one));
            }
            Symbol::Param(_)
            | Symbol::IterationCoefficient
            | Symbol::TrackingInput(_)
            | Symbol::TrackingCoefficient { .. } => {}
            Symbol::StateDot(j) => return Err(Obstacle::ImplicitDerivative(j)),
            Symbol::Algebraic(i) => return Err(Obstacle::Algebraic(i)),
            Symbol::Input(i) | Symbol::InputDot(i) => return Err(Obstacle::Input(i)),
            Symbol::AlgebraicDot(i) => return Err(Obstacle::Algebraic(i)),
        }
    }
    Ok(model.graph.directional_derivative(e, &dirs))
}

/// `j -> f_j` for the explicit equations `der(x_j) = f_j`.
fn explicit_rhs(model: &Model) -> HashMap<usize, ExprId> {
    model.equations.iter().filter_map(|e| e.explicit).collect()
}

/// The constraints of a higher-index plant differentiated until they involve an implicitly
/// determined unknown: per implicit equation that contains none (a position constraint
/// `g(x) = 0`, a velocity constraint), its first or second total derivative along the explicit
/// equations (for `der(q) = v`, `g_q v` and then `g_q v' + ...`, which contains the implicit
/// `v'`). Keyed by the equation's index; equations that need no derivative, or whose derivative
/// reaches an input (a prescribed motion), are not listed. With them in place of the
/// constraints, the implicit equations of a mechanism with multipliers are structurally regular
/// (the index reduction of Pantelides' algorithm for constraints of index 2 and 3), so the
/// relative degrees of its outputs are defined.
fn differentiated_constraints(model: &mut Model) -> HashMap<usize, ExprId> {
    let explicit = explicit_rhs(model);
    let mut out = HashMap::new();
    for k in 0..model.equations.len() {
        if model.equations[k].explicit.is_some() {
            continue;
        }
        let residual = model.equations[k].residual;
        let mut e = residual;
        for _ in 0..2 {
            let has_unknown =
                model
                    .graph
                    .vars(e)
                    .into_iter()
                    .any(|v| match model.symbols.symbol(v) {
                        Symbol::StateDot(j) => !explicit.contains_key(&j),
                        Symbol::Algebraic(_) => true,
                        _ => false,
                    });
            if has_unknown {
                break;
            }
            match total_derivative(model, e) {
                Ok(d) => e = d,
                Err(_) => break,
            }
        }
        if e != residual {
            out.insert(k, e);
        }
    }
    out
}

/// Symbols (states, inputs, time) each implicitly determined unknown depends on, or `None`
/// if the implicit equations are structurally singular in the implicit unknowns (a plant of
/// higher index whose constraints, differentiated by [`differentiated_constraints`], still
/// leave them singular). `reduced` replaces the residuals of differentiated constraints.
fn implicit_dependencies(
    model: &Model,
    reduced: &HashMap<usize, ExprId>,
) -> Option<HashMap<Symbol, BTreeSet<Symbol>>> {
    let explicit = explicit_rhs(model);
    let is_unknown = |s: &Symbol| match s {
        Symbol::StateDot(j) => !explicit.contains_key(j),
        Symbol::Algebraic(_) => true,
        _ => false,
    };
    // Known symbols and unknowns of a set of variables, with explicit x_j' expanded.
    let split = |vars: BTreeSet<Var>| -> (BTreeSet<Symbol>, BTreeSet<Symbol>) {
        let mut known = BTreeSet::new();
        let mut unknown = BTreeSet::new();
        let mut stack: Vec<Var> = vars.into_iter().collect();
        let mut seen = BTreeSet::new();
        while let Some(v) = stack.pop() {
            if !seen.insert(v) {
                continue;
            }
            let s = model.symbols.symbol(v);
            match s {
                Symbol::State(_) | Symbol::Input(_) | Symbol::Time => {
                    known.insert(s);
                }
                Symbol::StateDot(j) if !is_unknown(&s) => {
                    stack.extend(model.graph.vars(explicit[&j]));
                }
                _ if is_unknown(&s) => {
                    unknown.insert(s);
                }
                _ => {}
            }
        }
        (known, unknown)
    };
    let mut unknowns: Vec<Symbol> = (0..model.states.len())
        .filter(|j| !explicit.contains_key(j))
        .map(Symbol::StateDot)
        .collect();
    unknowns.extend((0..model.algebraic.len()).map(Symbol::Algebraic));
    let equations: Vec<(BTreeSet<Symbol>, BTreeSet<Symbol>)> = model
        .equations
        .iter()
        .enumerate()
        .filter(|(_, e)| e.explicit.is_none())
        .map(|(k, e)| split(model.graph.vars(*reduced.get(&k).unwrap_or(&e.residual))))
        .collect();
    if equations.len() != unknowns.len() {
        return None;
    }
    // Maximum bipartite matching unknown -> equation by augmenting paths (Kuhn).
    let mut owner: Vec<Option<usize>> = vec![None; equations.len()];
    fn augment(
        u: usize,
        unknowns: &[Symbol],
        equations: &[(BTreeSet<Symbol>, BTreeSet<Symbol>)],
        owner: &mut [Option<usize>],
        visited: &mut [bool],
    ) -> bool {
        for (e, (_, unk)) in equations.iter().enumerate() {
            if visited[e] || !unk.contains(&unknowns[u]) {
                continue;
            }
            visited[e] = true;
            let free = match owner[e] {
                None => true,
                Some(o) => augment(o, unknowns, equations, owner, visited),
            };
            if free {
                owner[e] = Some(u);
                return true;
            }
        }
        false
    }
    for u in 0..unknowns.len() {
        let mut visited = vec![false; equations.len()];
        if !augment(u, &unknowns, &equations, &mut owner, &mut visited) {
            return None;
        }
    }
    let mut eq_of = vec![0; unknowns.len()];
    for (e, o) in owner.iter().enumerate() {
        eq_of[o.expect("perfect matching")] = e;
    }
    // Fixpoint: an unknown depends on the known symbols of its equation and on whatever the
    // other unknowns of that equation depend on.
    let mut deps: Vec<BTreeSet<Symbol>> = eq_of.iter().map(|&e| equations[e].0.clone()).collect();
    loop {
        let mut changed = false;
        for u in 0..unknowns.len() {
            let others: Vec<usize> = equations[eq_of[u]]
                .1
                .iter()
                .filter_map(|s| unknowns.iter().position(|x| x == s))
                .filter(|&w| w != u)
                .collect();
            for w in others {
                let add: Vec<Symbol> = deps[w].difference(&deps[u]).copied().collect();
                if !add.is_empty() {
                    changed = true;
                    deps[u].extend(add);
                }
            }
        }
        if !changed {
            break;
        }
    }
    Some(unknowns.into_iter().zip(deps).collect())
}

/// How the relative degree of one output was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RelativeDegree {
    /// An input appears after this many total derivatives, taken symbolically along the
    /// explicit equations (where cancellations are seen) and structurally through implicit
    /// ones.
    Symbolic(usize),
    /// The structural (generic) value: the shortest path from the output through the
    /// dependency graph of the equations to an input. Reported where the symbolic
    /// derivatives grew beyond [`SWELL_FACTOR`] times the model before confirming it; it is
    /// a lower bound, exact unless coefficients cancel.
    Structural(usize),
    /// No input reaches the output: no path in the dependency graph leads from it to an input
    /// (or, symbolically, its derivatives stay free of inputs), so it cannot be tracked.
    Unreached,
    /// Not defined: the output's derivatives reach unknowns of implicit equations that are
    /// structurally singular even with the constraints differentiated (an index above 3).
    Undetermined,
}

impl RelativeDegree {
    /// The degree, or `None` where it is not defined.
    pub fn value(self) -> Option<usize> {
        match self {
            RelativeDegree::Symbolic(r) | RelativeDegree::Structural(r) => Some(r),
            RelativeDegree::Unreached | RelativeDegree::Undetermined => None,
        }
    }
}

/// The symbolic confirmation of a relative degree stops when a derivative of the output has
/// more than `SWELL_FACTOR` times as many nodes as the whole model (plus [`SWELL_SLACK`]):
/// repeated derivatives of nonlinear chains grow exponentially, the structural answer does
/// not. The bound depends only on the model, so every call gives the same answer.
pub const SWELL_FACTOR: usize = 8;

/// Additive part of the symbolic budget, so that small models are always confirmed.
pub const SWELL_SLACK: usize = 2_000;

/// What a set of symbols reaches in one differentiation.
#[derive(Default, Clone)]
struct Reach {
    states: BTreeSet<usize>,
    input: bool,
    undetermined: bool,
}

/// The dependency graph of the equations: per state `x_j`, what `x_j'` depends on.
struct Structure {
    implicit: Option<HashMap<Symbol, BTreeSet<Symbol>>>,
    explicit: HashMap<usize, ExprId>,
    successors: Vec<Reach>,
}

impl Structure {
    fn new(model: &Model, reduced: &HashMap<usize, ExprId>) -> Self {
        let mut st = Structure {
            implicit: implicit_dependencies(model, reduced),
            explicit: explicit_rhs(model),
            successors: Vec::new(),
        };
        st.successors = (0..model.states.len())
            .map(|j| match st.explicit.get(&j) {
                Some(&f) => st.expand(model, model.graph.vars(f)),
                None => st.expand_symbol(model, Symbol::StateDot(j)),
            })
            .collect();
        st
    }

    /// States, inputs and undetermined unknowns behind `vars`, with explicit `x_j'` and the
    /// implicitly determined unknowns replaced by what they depend on.
    fn expand(&self, model: &Model, vars: BTreeSet<Var>) -> Reach {
        let mut out = Reach::default();
        for v in vars {
            let r = self.expand_symbol(model, model.symbols.symbol(v));
            out.states.extend(r.states);
            out.input |= r.input;
            out.undetermined |= r.undetermined;
        }
        out
    }

    fn expand_symbol(&self, model: &Model, s: Symbol) -> Reach {
        let mut out = Reach::default();
        match s {
            Symbol::State(j) => {
                out.states.insert(j);
            }
            Symbol::Input(_) | Symbol::InputDot(_) => out.input = true,
            Symbol::StateDot(j) if self.explicit.contains_key(&j) => {
                // An explicit right-hand side is free of derivatives: one level.
                for v in model.graph.vars(self.explicit[&j]) {
                    match model.symbols.symbol(v) {
                        Symbol::StateDot(_) => out.undetermined = true,
                        other => {
                            let r = self.expand_symbol(model, other);
                            out.states.extend(r.states);
                            out.input |= r.input;
                            out.undetermined |= r.undetermined;
                        }
                    }
                }
            }
            Symbol::StateDot(_) | Symbol::Algebraic(_) | Symbol::AlgebraicDot(_) => {
                match self.implicit.as_ref().and_then(|m| m.get(&s)) {
                    Some(deps) => {
                        for d in deps {
                            match d {
                                Symbol::State(j) => {
                                    out.states.insert(*j);
                                }
                                Symbol::Input(_) => out.input = true,
                                _ => {}
                            }
                        }
                    }
                    None => out.undetermined = true,
                }
            }
            Symbol::Time
            | Symbol::Param(_)
            | Symbol::IterationCoefficient
            | Symbol::TrackingInput(_)
            | Symbol::TrackingCoefficient { .. } => {}
        }
        out
    }

    /// Breadth-first search from `start`, which is reached after `level` derivatives: the
    /// first level at which an input appears (checked before an undetermined unknown, as the
    /// symbolic derivative does). Linear in the size of the dependency graph.
    fn search(&self, start: Reach, level: usize) -> RelativeDegree {
        let mut visited: BTreeSet<usize> = start.states.clone();
        let mut frontier = start;
        let mut k = level;
        loop {
            if frontier.input {
                return RelativeDegree::Structural(k);
            }
            if frontier.undetermined {
                return RelativeDegree::Undetermined;
            }
            if frontier.states.is_empty() {
                return RelativeDegree::Unreached;
            }
            let mut next = Reach::default();
            for j in &frontier.states {
                let r = &self.successors[*j];
                next.input |= r.input;
                next.undetermined |= r.undetermined;
                for &s in &r.states {
                    if visited.insert(s) {
                        next.states.insert(s);
                    }
                }
            }
            frontier = next;
            k += 1;
        }
    }
}

/// Per output, its relative degree, or `None` where it is not defined.
pub fn relative_degrees(model: &mut Model) -> Vec<Option<usize>> {
    relative_degree_analysis(model)
        .into_iter()
        .map(RelativeDegree::value)
        .collect()
}

/// Per output, its relative degree and how it was found.
///
/// Structural first: a breadth-first search on the dependency graph of the equations
/// (through the implicit ones by the matching of `implicit_dependencies`), linear in the
/// model. Then symbolically, by repeated total derivatives along the explicit equations,
/// which sees cancellations, but only while the derivative stays within the budget of
/// [`SWELL_FACTOR`]; beyond it the structural value is reported. The derivatives are
/// memoised in the graph, so the Hirschorn steps of [`tracking_rows`] reuse them.
pub fn relative_degree_analysis(model: &mut Model) -> Vec<RelativeDegree> {
    let reduced = differentiated_constraints(model);
    let st = Structure::new(model, &reduced);
    let roots: Vec<ExprId> = model
        .equations
        .iter()
        .map(|e| e.residual)
        .chain(model.outputs.iter().map(|o| o.expr))
        .collect();
    let budget = SWELL_FACTOR * model.graph.size(&roots) + SWELL_SLACK;
    let outputs: Vec<ExprId> = model.outputs.iter().map(|o| o.expr).collect();
    outputs
        .into_iter()
        .map(|h| {
            let structural = st.search(st.expand(model, model.graph.vars(h)), 0);
            if structural == RelativeDegree::Unreached {
                // No path to an input: exact, whatever the symbolic form.
                return structural;
            }
            symbolic_relative_degree(model, &st, h, budget).unwrap_or(structural)
        })
        .collect()
}

/// The relative degree by total derivatives along the explicit equations, continued
/// structurally from the first derivative that needs an implicit equation; `None` if a
/// derivative grows beyond `budget` nodes first.
fn symbolic_relative_degree(
    model: &mut Model,
    st: &Structure,
    h: ExprId,
    budget: usize,
) -> Option<RelativeDegree> {
    let limit = model.states.len() + model.algebraic.len() + 1;
    let mut e = h;
    for r in 0..=limit {
        match total_derivative(model, e) {
            Ok(next) => {
                e = next;
                if model.graph.size(&[e]) > budget {
                    return None;
                }
            }
            Err(Obstacle::Input(_)) => return Some(RelativeDegree::Symbolic(r)),
            Err(_) => {
                return Some(match st.search(st.expand(model, model.graph.vars(e)), r) {
                    RelativeDegree::Structural(k) => RelativeDegree::Symbolic(k),
                    other => other,
                });
            }
        }
    }
    Some(RelativeDegree::Unreached)
}

/// `W(s)` as text, e.g. `(s + 2)(s + 3)`, `s`, or `1` for no step.
pub fn polynomial_text(roots: &[f64]) -> String {
    if roots.is_empty() {
        return "1".into();
    }
    let factor = |a: f64| {
        if a == 0.0 {
            "s".to_string()
        } else {
            format!("(s + {a:?})")
        }
    };
    if roots.len() == 1 {
        return factor(roots[0])
            .trim_start_matches('(')
            .trim_end_matches(')')
            .to_string();
    }
    roots.iter().map(|&a| factor(a)).collect()
}

/// Coefficients of `prod_k (s + a_k)`, lowest power first.
pub fn polynomial_from_negated_roots(roots: &[f64]) -> Vec<f64> {
    let mut c = vec![1.0];
    for &a in roots {
        let mut next = vec![0.0; c.len() + 1];
        for (k, ck) in c.iter().enumerate() {
            next[k] += a * ck;
            next[k + 1] += ck;
        }
        c = next;
    }
    c
}

/// The constraint row of one output in the tracking DAE.
pub struct TrackingRow {
    /// Index of the output.
    pub output: usize,
    /// Compiled default coefficients of `W_i`, lowest power first (monic).
    pub coefficients: Vec<f64>,
    /// `h_i, h_i', ..., h_i^(deg W_i)`.
    pub derivatives: Vec<ExprId>,
    /// `W_i(d/dt) h_i` with the compiled coefficients folded in, for the listing and the
    /// equation text.
    pub combination: ExprId,
    /// `W_i(d/dt) h_i - w_i` with the coefficients of `s^0 .. s^(deg W_i - 1)` as
    /// [`Symbol::TrackingCoefficient`] variables (the leading 1 stays a constant): the row
    /// that is emitted, so that `W` can change at run time and every entry a coefficient
    /// multiplies is in the sparsity pattern, even where its default is 0.
    pub row: ExprId,
}

/// Per output, the compiled degree of `W_i` (0 for an output without an entry).
pub fn w_degrees(model: &Model) -> Vec<usize> {
    (0..model.outputs.len())
        .map(|i| {
            model
                .tracking
                .as_ref()
                .and_then(|t| t.entries.iter().find(|e| e.output == i))
                .map_or(0, |e| e.roots.len())
        })
        .collect()
}

/// Where coefficient `power` of `W_output` sits in the tracking value's coefficient array:
/// all outputs' monic coefficient lists concatenated, lowest power first, so output `i`
/// starts at `sum_{j < i} (deg W_j + 1)`.
pub fn coefficient_index(degrees: &[usize], output: usize, power: usize) -> usize {
    degrees[..output].iter().map(|d| d + 1).sum::<usize>() + power
}

/// The constraint rows of the tracking DAE, one per output (outputs without an entry get
/// `W_i = 1`), or `None` after recording errors for steps that cannot be taken.
pub fn tracking_rows(model: &mut Model, cx: &mut Ctxt) -> Option<Vec<TrackingRow>> {
    let tracking = model.tracking.clone()?;
    let (ny, nu) = (model.outputs.len(), model.inputs.len());
    if ny != nu {
        cx.error_at(
            tracking.span,
            format!(
                "a tracking DAE needs as many outputs as inputs, but the model has {ny} output{} and {nu} input{}",
                if ny == 1 { "" } else { "s" },
                if nu == 1 { "" } else { "s" }
            ),
        );
        return None;
    }
    let mut ok = true;
    let mut rows = Vec::new();
    for i in 0..ny {
        let entry = tracking.entries.iter().find(|e| e.output == i);
        let roots = entry.map(|e| e.roots.clone()).unwrap_or_default();
        let coefficients = polynomial_from_negated_roots(&roots);
        let mut derivatives = vec![model.outputs[i].expr];
        for k in 0..roots.len() {
            let last = derivatives[k];
            match total_derivative(model, last) {
                Ok(d) => derivatives.push(d),
                Err(obstacle) => {
                    let span = entry.map(|e| e.span).unwrap_or(tracking.span);
                    let out = model.outputs[i].label.clone();
                    let n = roots.len();
                    let steps = format!("{n} step{}", if n == 1 { "" } else { "s" });
                    let limit = format!(
                        "use at most {k} root{} for `{out}`",
                        if k == 1 { "" } else { "s" }
                    );
                    let msg = match obstacle {
                        Obstacle::Input(u) if k == 0 => format!(
                            "cannot apply a Hirschorn step to output `{out}`: it depends on input `{}` directly (relative degree 0), so `W` must be empty; write `{out}: []` or remove the entry",
                            model.inputs[u].label
                        ),
                        Obstacle::Input(u) => format!(
                            "cannot apply {steps} to output `{out}`: its derivative of order {k} already depends on input `{}` (relative degree {k}), and a further step would need the input's derivative; {limit}",
                            model.inputs[u].label
                        ),
                        Obstacle::Algebraic(z) => format!(
                            "cannot apply {steps} to output `{out}`: its derivative of order {k} depends on the algebraic unknown `{}`, whose derivative is not available; {limit}",
                            model.algebraic[z].label
                        ),
                        Obstacle::ImplicitDerivative(j) => {
                            let x = &model.states[j].label;
                            format!(
                                "cannot apply {steps} to output `{out}`: its derivative of order {k} contains `der({x})`, so a further step would need the second derivative of `{x}`, which has no explicit equation `der({x}) = ...`; {limit}, or state `der({x})` explicitly"
                            )
                        }
                    };
                    cx.error_at(span, msg);
                    ok = false;
                    break;
                }
            }
        }
        if !ok {
            continue;
        }
        let mut sum = model.graph.constant(0.0);
        for (c, &d) in coefficients.iter().zip(&derivatives) {
            let cc = model.graph.constant(*c);
            let term = model.graph.mul(cc, d);
            sum = model.graph.add(sum, term);
        }
        let degree = roots.len();
        let mut runtime = model.graph.constant(0.0);
        for (power, &d) in derivatives.iter().enumerate() {
            let term = if power == degree {
                d
            } else {
                let cv = model.var(Symbol::TrackingCoefficient { output: i, power });
                let c = model.graph.var(cv);
                model.graph.mul(c, d)
            };
            runtime = model.graph.add(runtime, term);
        }
        let wv = model.var(Symbol::TrackingInput(i));
        let w = model.graph.var(wv);
        let row = model.graph.sub(runtime, w);
        rows.push(TrackingRow {
            output: i,
            coefficients,
            derivatives,
            combination: sum,
            row,
        });
    }
    // After the rows, so that the derivatives the steps need are built first and the
    // expansion of a model with reachable outputs is the same as without this check.
    for (i, degree) in relative_degree_analysis(model).into_iter().enumerate() {
        if degree != RelativeDegree::Unreached {
            continue;
        }
        let out = &model.outputs[i];
        let entry = tracking.entries.iter().find(|e| e.output == i);
        let span = entry.map(|e| e.span).unwrap_or(tracking.span);
        cx.error_at(
            span,
            format!(
                "cannot track output `{}` = `{}`: no input reaches it (none of its time derivatives depends on an input, so its relative degree is undefined and the tracking DAE cannot determine the inputs); track an output that an input influences",
                out.label, out.text
            ),
        );
        ok = false;
    }
    ok.then_some(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use quote::quote;

    fn model(tokens: proc_macro2::TokenStream) -> Model {
        crate::lower_model(tokens).expect("model lowers")
    }

    #[test]
    fn polynomial_coefficients() {
        assert_eq!(polynomial_from_negated_roots(&[]), vec![1.0]);
        assert_eq!(polynomial_from_negated_roots(&[5.0]), vec![5.0, 1.0]);
        assert_eq!(
            polynomial_from_negated_roots(&[2.0, 3.0]),
            vec![6.0, 5.0, 1.0]
        );
        assert_eq!(
            polynomial_from_negated_roots(&[0.0, 0.0]),
            vec![0.0, 0.0, 1.0]
        );
    }

    #[test]
    fn tracking_rows_read_the_non_leading_coefficients_as_variables() {
        let mut m = model(quote! {
            Cart {
                states { x, v, y }
                inputs { f, g }
                equations {
                    der(x) = v;
                    der(v) = f;
                    der(y) = g;
                }
                outputs { x, y }
                tracking CartTracking { x: [2.0, 0.0] }
            }
        });
        let mut cx = Ctxt::new();
        let rows = tracking_rows(&mut m, &mut cx).expect("steps can be taken");
        cx.check().expect("no errors");
        assert_eq!(w_degrees(&m), vec![2, 0]);
        let coefficient_vars = |m: &Model, e: ExprId| -> Vec<Symbol> {
            m.graph
                .vars(e)
                .into_iter()
                .map(|v| m.symbols.symbol(v))
                .filter(|s| matches!(s, Symbol::TrackingCoefficient { .. }))
                .collect()
        };
        // W = s^2 + 2 s + 0: both non-leading coefficients are variables, even the zero one.
        assert_eq!(
            coefficient_vars(&m, rows[0].row),
            vec![
                Symbol::TrackingCoefficient {
                    output: 0,
                    power: 0
                },
                Symbol::TrackingCoefficient {
                    output: 0,
                    power: 1
                },
            ]
        );
        assert_eq!(rows[0].coefficients, vec![0.0, 2.0, 1.0]);
        // The listing form folds the compiled values in.
        assert!(coefficient_vars(&m, rows[0].combination).is_empty());
        assert_eq!(m.display(rows[0].combination), "f + 2 * v");
        // W = 1 on y: no coefficient at all.
        assert!(coefficient_vars(&m, rows[1].row).is_empty());
        // The coefficient array: [x: c0, c1, 1 | y: 1].
        assert_eq!(coefficient_index(&[2, 0], 0, 1), 1);
        assert_eq!(coefficient_index(&[2, 0], 1, 0), 3);
        assert_eq!(coefficient_index(&[1, 2, 1], 2, 0), 5);
    }

    #[test]
    fn chain_of_integrators_has_its_length_as_relative_degree() {
        let mut m = model(quote! {
            Chain {
                states { x1, x2, x3, x4 }
                inputs { u, v }
                equations {
                    der(x1) = x2;
                    der(x2) = x3;
                    der(x3) = x4;
                    der(x4) = u;
                }
                outputs { y = x1, z = x3 + x1, w = 2.0 * x4 + t, k = x2.sin() }
            }
        });
        assert_eq!(
            relative_degrees(&mut m),
            vec![Some(4), Some(2), Some(1), Some(3)]
        );
    }

    #[test]
    fn implicit_equations_are_handled_structurally() {
        // x2' is given implicitly together with an algebraic unknown; the input enters
        // through the algebraic equation only.
        let mut m = model(quote! {
            Implicit {
                states { x1, x2 }
                algebraic { z }
                inputs { u }
                equations {
                    der(x1) = x2;
                    (1.0 + x1.powi(2)) * der(x2) == -x1 + z;
                    0.0 == z - x2 * u;
                }
                outputs { y = x1 }
            }
        });
        assert_eq!(relative_degrees(&mut m), vec![Some(2)]);
    }

    #[test]
    fn constraints_are_differentiated_through() {
        // A pendulum on a cart in Cartesian coordinates (index 3): the rod constraint contains
        // no implicit unknown; its second derivative does, and then the multiplier is
        // determined. The cart position has relative degree 2, the bob's horizontal position
        // too (the force reaches it through the multiplier).
        let mut m = model(quote! {
            CartPendulum {
                params { mc = 1.0, m = 0.5, l = 0.5, g = 9.81 }
                states { s, xb, yb, vs, vx, vy }
                algebraic { lambda }
                inputs { f }
                equations {
                    der(s) = vs;
                    der(xb) = vx;
                    der(yb) = vy;
                    mc * der(vs) == f + lambda * (xb - s);
                    m * der(vx) == -lambda * (xb - s);
                    m * der(vy) == -lambda * yb - m * g;
                    0.0 == 0.5 * ((xb - s).powi(2) + yb.powi(2) - l.powi(2));
                }
                outputs { cart = s, bob = xb }
            }
        });
        assert_eq!(relative_degrees(&mut m), vec![Some(2), Some(2)]);
    }

    #[test]
    fn outputs_unreached_by_inputs_have_no_relative_degree() {
        let mut m = model(quote! {
            Unreached {
                states { x, v }
                inputs { u }
                equations {
                    der(x) = -x;
                    der(v) = u;
                }
                outputs { y = x }
            }
        });
        assert_eq!(relative_degrees(&mut m), vec![None]);
    }
}
