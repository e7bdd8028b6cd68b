//! Stabilised Hirschorn steps and relative degrees (paper, Section 2).
//!
//! A step replaces the output constraint `h_i - xi_i = 0` by `W_i(d/dt)(h_i - xi_i) = 0`
//! with a stable `W_i(s) = prod_k (s + a_k)`. The total time derivative
//! `d/dt h = sum_j dh/dx_j x_j' + dh/dt` is taken symbolically; where the model states
//! `der(x_j) = f_j` explicitly, `x_j'` is replaced by `f_j`, so that chains of explicit
//! equations are differentiated through. Each step lowers the index of the tracking DAE by one,
//! so the integrator has to resolve less.
//!
//! Where a step needs the derivative of `x_j'` of a state whose equation is implicit
//! (`M(q) der(w) == ...`), the higher derivative `x_j''` becomes an unknown of the tracking DAE
//! and the implicit equations are differentiated until they determine it, as index reduction
//! does ([`tracking_rows`]): the mass matrix is never inverted.
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
use std::collections::{BTreeMap, BTreeSet, HashMap};

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
///
/// `x_j'` of a state without explicit equation is left as the unknown `der(x_j)`; an
/// expression that already contains such an unknown (or an algebraic unknown, or an input) is
/// an [`Obstacle`]. [`total_derivative_through_implicit`] goes on through implicit equations.
pub fn total_derivative(model: &mut Model, e: ExprId) -> Result<ExprId, Obstacle> {
    derivative_along(model, e, false)
}

/// The total time derivative of `e` along the model, through implicit equations too: as
/// [`total_derivative`], but the derivative of `der(x_j)` of a state whose equation is implicit
/// is the higher derivative `der2(x_j)` ([`Symbol::StateDerivative`]), that of `der2(x_j)` is
/// `der3(x_j)`, and so on, and `der(x_j)` of a state with explicit equation `der(x_j) = f_j`
/// becomes the total derivative of `f_j`. The higher derivatives are unknowns, which the total
/// derivatives of the implicit equations determine (index reduction, see [`tracking_rows`]).
/// Inputs and algebraic unknowns remain [`Obstacle`]s: their derivatives are not available.
pub fn total_derivative_through_implicit(model: &mut Model, e: ExprId) -> Result<ExprId, Obstacle> {
    derivative_along(model, e, true)
}

fn derivative_along(
    model: &mut Model,
    e: ExprId,
    through_implicit: bool,
) -> Result<ExprId, Obstacle> {
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
            Symbol::StateDot(j) if through_implicit => {
                let d = match explicit.get(&j) {
                    // Explicit right-hand sides are free of derivatives: one level.
                    Some(&f) => derivative_along(model, f, false)?,
                    None => {
                        let dv = model.var(Symbol::StateDerivative { state: j, order: 2 });
                        model.graph.var(dv)
                    }
                };
                dirs.push((v, d));
            }
            Symbol::StateDerivative { state, order } if through_implicit => {
                let dv = model.var(Symbol::StateDerivative {
                    state,
                    order: order + 1,
                });
                let d = model.graph.var(dv);
                dirs.push((v, d));
            }
            Symbol::StateDot(j) | Symbol::StateDerivative { state: j, .. } => {
                return Err(Obstacle::ImplicitDerivative(j))
            }
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

/// The position constraints of an index-3 plant, each replaced in the tracking DAE by its
/// first total derivative along the explicit equations (the velocity constraint `g_q v = 0`
/// for `g(q) = 0` with `der(q) = v`): per implicit equation that contains no implicitly
/// determined unknown and whose first derivative contains none either (so the multiplier
/// would need two differentiations), that derivative. Keyed by the equation's index.
///
/// Why: DPC integrates the tracking DAE by implicit Euler with a small inner step `delta`.
/// On the index-3 form the multiplier's round-off grows like `eps / delta^2`, which swamps the
/// controls below `delta` of about `1e-5`; on the index-2 form it grows like `eps / delta`.
/// The measured state the controller starts from satisfies the constraint (the closed loop
/// projects it), and the position constraint's drift over the few inner steps is `O(delta^2)`
/// per step, so the controls are the same up to the integration's own error.
fn velocity_constraints(model: &mut Model) -> Vec<(usize, ExprId)> {
    let explicit = explicit_rhs(model);
    let has_implicit_unknown = |model: &Model, e: ExprId| {
        model
            .graph
            .vars(e)
            .into_iter()
            .any(|v| match model.symbols.symbol(v) {
                Symbol::StateDot(j) => !explicit.contains_key(&j),
                Symbol::Algebraic(_) => true,
                _ => false,
            })
    };
    let mut out = Vec::new();
    for k in 0..model.equations.len() {
        if model.equations[k].explicit.is_some() {
            continue;
        }
        let residual = model.equations[k].residual;
        if has_implicit_unknown(model, residual) {
            continue;
        }
        let Ok(first) = total_derivative(model, residual) else {
            continue;
        };
        if has_implicit_unknown(model, first) {
            continue;
        }
        out.push((k, first));
    }
    out
}

/// The implicit equations matched to the unknowns they determine.
struct ImplicitMatching {
    /// The implicitly determined unknowns: `der(x_j)` of the states without explicit
    /// equation, then the algebraic unknowns.
    unknowns: Vec<Symbol>,
    /// Per implicit equation: its index among the model's equations, the known symbols
    /// (states, inputs, time) and the unknowns it contains (with explicit `x_j'` expanded).
    equations: Vec<(usize, BTreeSet<Symbol>, BTreeSet<Symbol>)>,
    /// Per unknown, the implicit equation (index into `equations`) matched to it.
    equation_of: Vec<usize>,
}

/// A perfect matching of the implicitly determined unknowns to the implicit equations (a
/// maximum bipartite matching, as in Pantelides' algorithm), or `None` if the implicit
/// equations are structurally singular in them. `reduced` replaces the residuals of
/// differentiated constraints (see [`differentiated_constraints`]).
fn implicit_matching(model: &Model, reduced: &HashMap<usize, ExprId>) -> Option<ImplicitMatching> {
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
    let equations: Vec<(usize, BTreeSet<Symbol>, BTreeSet<Symbol>)> = model
        .equations
        .iter()
        .enumerate()
        .filter(|(_, e)| e.explicit.is_none())
        .map(|(k, e)| {
            let (known, unknown) = split(model.graph.vars(*reduced.get(&k).unwrap_or(&e.residual)));
            (k, known, unknown)
        })
        .collect();
    if equations.len() != unknowns.len() {
        return None;
    }
    // Maximum bipartite matching unknown -> equation by augmenting paths (Kuhn).
    let mut owner: Vec<Option<usize>> = vec![None; equations.len()];
    fn augment(
        u: usize,
        unknowns: &[Symbol],
        equations: &[(usize, BTreeSet<Symbol>, BTreeSet<Symbol>)],
        owner: &mut [Option<usize>],
        visited: &mut [bool],
    ) -> bool {
        for (e, (_, _, unk)) in equations.iter().enumerate() {
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
    let mut equation_of = vec![0; unknowns.len()];
    for (e, o) in owner.iter().enumerate() {
        equation_of[(*o)?] = e;
    }
    Some(ImplicitMatching {
        unknowns,
        equations,
        equation_of,
    })
}

/// Symbols (states, inputs, time) each implicitly determined unknown depends on, or `None`
/// if the implicit equations are structurally singular in the implicit unknowns (a plant of
/// higher index whose constraints, differentiated by [`differentiated_constraints`], still
/// leave them singular). `reduced` replaces the residuals of differentiated constraints.
fn implicit_dependencies(
    model: &Model,
    reduced: &HashMap<usize, ExprId>,
) -> Option<HashMap<Symbol, BTreeSet<Symbol>>> {
    let ImplicitMatching {
        unknowns,
        equations,
        equation_of,
    } = implicit_matching(model, reduced)?;
    // Fixpoint: an unknown depends on the known symbols of its equation and on whatever the
    // other unknowns of that equation depend on.
    let mut deps: Vec<BTreeSet<Symbol>> = equation_of
        .iter()
        .map(|&e| equations[e].1.clone())
        .collect();
    loop {
        let mut changed = false;
        for u in 0..unknowns.len() {
            let others: Vec<usize> = equations[equation_of[u]]
                .2
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
            Symbol::StateDot(_)
            | Symbol::StateDerivative { .. }
            | Symbol::Algebraic(_)
            | Symbol::AlgebraicDot(_) => {
                // A higher derivative of an implicitly determined state reaches what its first
                // derivative does.
                let key = match s {
                    Symbol::StateDerivative { state, .. } => Symbol::StateDot(state),
                    other => other,
                };
                match self.implicit.as_ref().and_then(|m| m.get(&key)) {
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

/// A total time derivative of an implicit equation of the plant, a row of a tracking DAE
/// whose steps differentiate through implicit equations.
#[derive(Clone, Debug)]
pub struct DifferentiatedEquation {
    /// Index of the plant equation.
    pub equation: usize,
    /// How many times it is differentiated (at least 1).
    pub order: usize,
    /// `d^order/dt^order` of its residual, along the model
    /// ([`total_derivative_through_implicit`]).
    pub residual: ExprId,
}

/// The rows a tracking DAE adds to the plant equations, and its additional unknowns.
pub struct TrackingSystem {
    /// One constraint row per output.
    pub rows: Vec<TrackingRow>,
    /// The total derivatives of implicit equations that the rows need, by order, then by
    /// equation (empty unless a step differentiates through an implicit equation).
    pub differentiated: Vec<DifferentiatedEquation>,
    /// The higher derivatives of states ([`Symbol::StateDerivative`]) they determine: the
    /// tracking DAE's additional algebraic unknowns, by order, then by state.
    pub higher_derivatives: Vec<Symbol>,
    /// The position constraints of an index-3 plant and the first total derivatives that
    /// replace them in the tracking DAE (see `velocity_constraints`), by equation.
    pub velocity_constraints: Vec<(usize, ExprId)>,
}

/// Why the implicit equations cannot be differentiated as far as the steps need.
enum ReductionObstacle {
    /// The implicit equations are structurally singular in their unknowns.
    Singular,
    /// The unknown would be determined by the derivatives of a constraint (an equation
    /// without implicit unknown, differentiated for the matching already): not supported.
    Constraint(usize),
    /// The derivative of this order of this equation cannot be taken.
    Derivative {
        equation: usize,
        order: usize,
        obstacle: Obstacle,
    },
}

/// Per state, the highest order `>= 2` of its derivative among the variables of `exprs`.
fn higher_derivative_orders(model: &Model, exprs: &[ExprId]) -> BTreeMap<usize, usize> {
    let mut out = BTreeMap::new();
    for &e in exprs {
        for v in model.graph.vars(e) {
            if let Symbol::StateDerivative { state, order } = model.symbols.symbol(v) {
                let o = out.entry(state).or_insert(order);
                *o = (*o).max(order);
            }
        }
    }
    out
}

/// The index reduction the steps need: per state `x_j` whose derivatives up to `x_j^(m_j)`
/// occur (`orders`, `m_j >= 2`), the implicit equations are differentiated, in the manner of
/// Pantelides' algorithm, until they determine them. The unknown `der(x_j)` is matched to an
/// implicit equation ([`implicit_matching`]); to determine its derivatives up to order
/// `m_j - 1`, that equation is differentiated `m_j - 1` times, and its derivatives contain the
/// derivatives of the same order of every other unknown in it, which need their equations
/// differentiated as often: the least fixpoint. As many derivative rows as new unknowns
/// result, one per equation and order.
fn differentiate_implicit_equations(
    model: &mut Model,
    orders: &BTreeMap<usize, usize>,
) -> Result<(Vec<DifferentiatedEquation>, Vec<Symbol>), ReductionObstacle> {
    if orders.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let reduced = differentiated_constraints(model);
    let matching = implicit_matching(model, &reduced).ok_or(ReductionObstacle::Singular)?;
    // How many times each unknown is differentiated.
    let mut need = vec![0usize; matching.unknowns.len()];
    for (&state, &order) in orders {
        let u = matching
            .unknowns
            .iter()
            .position(|s| *s == Symbol::StateDot(state))
            .ok_or(ReductionObstacle::Singular)?;
        need[u] = need[u].max(order - 1);
    }
    loop {
        let mut changed = false;
        for u in 0..need.len() {
            if need[u] == 0 {
                continue;
            }
            let (_, _, unknowns) = &matching.equations[matching.equation_of[u]];
            for other in unknowns {
                if let Some(w) = matching.unknowns.iter().position(|x| x == other) {
                    if need[w] < need[u] {
                        need[w] = need[u];
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    // Per model equation, how many times it is differentiated.
    let mut equation_orders: BTreeMap<usize, usize> = BTreeMap::new();
    for (u, &n) in need.iter().enumerate() {
        if n > 0 {
            let k = matching.equations[matching.equation_of[u]].0;
            if reduced.contains_key(&k) {
                return Err(ReductionObstacle::Constraint(k));
            }
            equation_orders.insert(k, n);
        }
    }
    let highest = equation_orders.values().copied().max().unwrap_or(0);
    let mut last: BTreeMap<usize, ExprId> = equation_orders
        .keys()
        .map(|&k| (k, model.equations[k].residual))
        .collect();
    let mut differentiated = Vec::new();
    let mut higher = Vec::new();
    for order in 1..=highest {
        for (&equation, &n) in &equation_orders {
            if n < order {
                continue;
            }
            let residual =
                total_derivative_through_implicit(model, last[&equation]).map_err(|obstacle| {
                    ReductionObstacle::Derivative {
                        equation,
                        order,
                        obstacle,
                    }
                })?;
            last.insert(equation, residual);
            differentiated.push(DifferentiatedEquation {
                equation,
                order,
                residual,
            });
        }
        for (u, &n) in need.iter().enumerate() {
            match matching.unknowns[u] {
                Symbol::StateDot(state) if n >= order => higher.push(Symbol::StateDerivative {
                    state,
                    order: order + 1,
                }),
                // An algebraic unknown with a derivative: its equation's derivative stopped
                // at it above already.
                _ => {}
            }
        }
    }
    Ok((differentiated, higher))
}

/// The constraint rows of the tracking DAE, one per output (outputs without an entry get
/// `W_i = 1`), with the derivatives of implicit equations the steps need, or `None` after
/// recording errors for steps that cannot be taken.
///
/// The derivatives of the outputs are taken through implicit equations
/// ([`total_derivative_through_implicit`]): where a step needs the derivative of `der(x_j)` of
/// a state whose equation is implicit (`M(q) der(w) == ...`), the higher derivative
/// `der2(x_j)` is a new unknown, and the implicit equations are differentiated as often as
/// needed to determine it ([`TrackingSystem::differentiated`]), instead of the mass matrix
/// being inverted symbolically. Steps are refused where the derivatives would need an input's
/// derivative (more steps than the relative degree), an algebraic unknown's derivative, or the
/// derivatives of a constraint.
pub fn tracking_rows(model: &mut Model, cx: &mut Ctxt) -> Option<TrackingSystem> {
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
            match total_derivative_through_implicit(model, last) {
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
    // The derivatives of the implicit equations, first per output (so that an error names the
    // output whose steps need them), then for all rows together.
    let mut orders: BTreeMap<usize, usize> = BTreeMap::new();
    for row in &rows {
        let needed = higher_derivative_orders(model, &row.derivatives);
        if let Err(obstacle) = differentiate_implicit_equations(model, &needed) {
            report_reduction_obstacle(model, cx, &tracking, row, obstacle);
            ok = false;
        }
        for (state, order) in needed {
            let o = orders.entry(state).or_insert(order);
            *o = (*o).max(order);
        }
    }
    let (differentiated, higher_derivatives) = if ok {
        match differentiate_implicit_equations(model, &orders) {
            Ok(reduction) => reduction,
            Err(_) => {
                cx.error_at(
                    tracking.span,
                    "internal error: the implicit equations could be differentiated for each output's steps, but not for all together",
                );
                return None;
            }
        }
    } else {
        (Vec::new(), Vec::new())
    };
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
    let velocity_constraints = if ok {
        velocity_constraints(model)
    } else {
        Vec::new()
    };
    ok.then_some(TrackingSystem {
        rows,
        differentiated,
        higher_derivatives,
        velocity_constraints,
    })
}

/// The error for a row whose steps need derivatives of implicit equations that cannot be
/// taken, at the row's `tracking` entry.
fn report_reduction_obstacle(
    model: &mut Model,
    cx: &mut Ctxt,
    tracking: &crate::ir::Tracking,
    row: &TrackingRow,
    obstacle: ReductionObstacle,
) {
    let i = row.output;
    let entry = tracking.entries.iter().find(|e| e.output == i);
    let span = entry.map(|e| e.span).unwrap_or(tracking.span);
    let out = model.outputs[i].label.clone();
    let n = row.derivatives.len() - 1;
    let steps = format!("{n} step{}", if n == 1 { "" } else { "s" });
    let higher_in = |m: &Model, d: ExprId| -> Vec<Symbol> {
        m.graph
            .vars(d)
            .into_iter()
            .map(|v| m.symbols.symbol(v))
            .filter(|s| matches!(s, Symbol::StateDerivative { .. }))
            .collect()
    };
    // The first derivative of the output that contains a higher derivative of a state: the
    // steps before it need no derivative of an implicit equation.
    let first = (0..=n)
        .find(|&k| !higher_in(model, row.derivatives[k]).is_empty())
        .unwrap_or(n);
    // The highest derivative in the last one, which the steps need.
    let symbol = higher_in(model, row.derivatives[n])
        .into_iter()
        .max_by_key(|s| match s {
            Symbol::StateDerivative { order, .. } => *order,
            _ => 0,
        })
        .map_or_else(
            || "a higher derivative".to_string(),
            |s| model.symbol_name(s),
        );
    let roots = |k: usize| {
        format!(
            "use at most {k} root{} for `{out}`",
            if k == 1 { "" } else { "s" }
        )
    };
    let before = roots(first.saturating_sub(1));
    let head = format!(
        "cannot apply {steps} to output `{out}`: its derivative of order {n} contains `{symbol}`"
    );
    let msg = match obstacle {
        ReductionObstacle::Singular => format!(
            "{head}, but the implicit equations are structurally singular in their unknowns, so their derivatives cannot determine it; {before}"
        ),
        ReductionObstacle::Constraint(k) => format!(
            "{head}, which only derivatives of the constraint `{}` would determine; steps through the derivatives of constraints are not supported; {before}",
            model.equations[k].text
        ),
        ReductionObstacle::Derivative {
            equation,
            order,
            obstacle,
        } => {
            let text = model.equations[equation].text.clone();
            let derivative = match order {
                1 => format!("the derivative of equation `{text}`"),
                _ => format!("the derivative of order {order} of equation `{text}`"),
            };
            match obstacle {
                Obstacle::Input(u) => {
                    let degree = relative_degrees(model)[i].filter(|&r| r < n);
                    let limit = match degree {
                        Some(r) => format!(" (relative degree {r}); {}", roots(r)),
                        None => format!("; {before}"),
                    };
                    format!(
                        "{head}, and determining it needs {derivative}, which would need the derivative of input `{}`{limit}",
                        model.inputs[u].label
                    )
                }
                Obstacle::Algebraic(z) => format!(
                    "{head}, and determining it needs {derivative}, which would need the derivative of the algebraic unknown `{}` (steps through implicit equations do not differentiate algebraic unknowns); {before}",
                    model.algebraic[z].label
                ),
                Obstacle::ImplicitDerivative(j) => format!(
                    "{head}, and determining it needs {derivative}, which would need a derivative of `der({})` that is not available; {before}",
                    model.states[j].label
                ),
            }
        }
    };
    cx.error_at(span, msg);
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
        let rows = tracking_rows(&mut m, &mut cx)
            .expect("steps can be taken")
            .rows;
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

    /// Values of the symbols named in `values` (by [`Model::symbol_name`]); 0 for others.
    fn eval_at(m: &Model, e: ExprId, values: &[(&str, f64)]) -> f64 {
        m.graph.eval(e, &|v| {
            let name = m.symbol_name(m.symbols.symbol(v));
            values
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(0.0, |(_, x)| *x)
        })
    }

    #[test]
    fn steps_through_an_implicit_equation_differentiate_it() {
        // x'' = v' is given implicitly with a state-dependent mass; the third step needs
        // der2(v), which d/dt of the implicit equation determines:
        // 2 x x' v' + (2 + x^2) v'' - w' = 2 x v v' + (2 + x^2) der2(v) - u.
        let source = |roots: proc_macro2::TokenStream| {
            quote! {
                Plant {
                    states { x, v, w }
                    inputs { u }
                    equations {
                        der(x) = v;
                        (2.0 + x.powi(2)) * der(v) == w;
                        der(w) = u;
                    }
                    outputs { x }
                    tracking PlantTracking { x: #roots }
                }
            }
        };
        let mut m = model(source(quote!([1.0, 2.0, 3.0])));
        assert_eq!(relative_degrees(&mut m), vec![Some(3)]);
        let mut cx = Ctxt::new();
        let system = tracking_rows(&mut m, &mut cx).expect("three steps are taken");
        cx.check().expect("no errors");
        let der2_v = Symbol::StateDerivative { state: 1, order: 2 };
        assert_eq!(system.higher_derivatives, vec![der2_v]);
        assert_eq!(system.differentiated.len(), 1);
        let d = &system.differentiated[0];
        assert_eq!((d.equation, d.order), (1, 1));
        assert_eq!(m.display(system.rows[0].derivatives[3]), "der2(v)");
        let point = [
            ("x", 0.7),
            ("v", -1.3),
            ("w", 0.4),
            ("der(v)", 2.1),
            ("der2(v)", -0.6),
            ("u", 1.9),
        ];
        let (x, v, dv, d2v, u) = (0.7, -1.3, 2.1, -0.6, 1.9);
        let want = 2.0 * x * v * dv + (2.0_f64 + x * x) * d2v - u;
        let got = eval_at(&m, d.residual, &point);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");

        // A fourth step is beyond the relative degree: d^2/dt^2 of the equation needs u'.
        let mut m = model(source(quote!([1.0, 2.0, 3.0, 4.0])));
        let mut cx = Ctxt::new();
        assert!(tracking_rows(&mut m, &mut cx).is_none());
        let message = cx.check().expect_err("refused").to_string();
        assert!(
            message.contains("its derivative of order 4 contains `der3(v)`")
                && message.contains("derivative of input `u` (relative degree 3)")
                && message.contains("use at most 3 roots"),
            "{message}"
        );
    }

    #[test]
    fn coupled_implicit_equations_are_differentiated_together() {
        // Two masses coupled through a mass matrix [[2, 1], [1, 2 + x^2]] (Pantelides): der2 of
        // y needs the derivative of the first equation, which contains der(b) too, so the
        // second equation is differentiated as well and der2(b) joins: two rows, two unknowns.
        let mut m = model(quote! {
            Coupled {
                states { y, a, x, b }
                inputs { u, f }
                equations {
                    der(y) = a;
                    2.0 * der(a) + der(b) == -y + x;
                    der(x) = b;
                    der(a) + (2.0 + x.powi(2)) * der(b) == -x;
                }
                outputs { y }
                tracking CoupledTracking { y: [1.0, 2.0, 3.0] }
            }
        });
        // Not square (two inputs, one output): use the reduction directly.
        let mut cx = Ctxt::new();
        assert!(tracking_rows(&mut m, &mut cx).is_none());
        assert!(cx.check().is_err(), "refused with a diagnostic");
        let orders = BTreeMap::from([(1, 2)]);
        let Ok((differentiated, higher)) = differentiate_implicit_equations(&mut m, &orders) else {
            panic!("the coupled equations are differentiated");
        };
        assert_eq!(
            differentiated
                .iter()
                .map(|d| (d.equation, d.order))
                .collect::<Vec<_>>(),
            vec![(1, 1), (3, 1)]
        );
        assert_eq!(
            higher,
            vec![
                Symbol::StateDerivative { state: 1, order: 2 },
                Symbol::StateDerivative { state: 3, order: 2 },
            ]
        );
        // d/dt of the second: der2(a) + 2 x b der(b) + (2 + x^2) der2(b) + b.
        let point = [
            ("x", 0.5),
            ("b", -0.8),
            ("der(b)", 0.3),
            ("der2(a)", 1.1),
            ("der2(b)", -2.0),
        ];
        let want = 1.1 + 2.0 * 0.5 * -0.8 * 0.3 + (2.0 + 0.25) * -2.0 + -0.8;
        let got = eval_at(&m, differentiated[1].residual, &point);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
