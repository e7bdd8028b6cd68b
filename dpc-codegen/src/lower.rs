//! Lowering: from the parsed syntax to the checked model IR.
//!
//! Resolves every name, lowers expressions into the symbolic graph, and runs the structural
//! checks of a well-formed plant (section order, duplicates, counts, `der()` usage, states
//! that are never differentiated). All errors are collected in the [`Ctxt`] and reported
//! together, each spanning the offending tokens and saying what was expected.

use crate::ctxt::Ctxt;
use crate::expr::{BinaryOp, ClosureParam, Expr, ExprKind, ExprRef, UnaryOp};
use crate::ir::{
    Decl, Equation, Intermediate, Model, Output, Param, Reference, Symbol, Symbols, Tracking,
    TrackingEntry,
};
use crate::parse::{EquationItem, Item, ModelDef, SectionBody, Subscript, SECTION_ORDER};
use crate::symbolic::{ExprId, Func, Graph};
use crate::text::expr_text;
use proc_macro2::Span;
use quote::ToTokens;
use std::collections::{HashMap, HashSet};
use syn::ext::IdentExt;
use syn::{Attribute, Ident, Lit};

/// Named constants usable in expressions, with their values.
pub const CONSTANTS: &[(&str, f64)] = &[
    ("PI", std::f64::consts::PI),
    ("TAU", std::f64::consts::TAU),
    ("E", std::f64::consts::E),
    ("SQRT_2", std::f64::consts::SQRT_2),
    ("LN_2", std::f64::consts::LN_2),
    ("LN_10", std::f64::consts::LN_10),
    ("FRAC_PI_2", std::f64::consts::FRAC_PI_2),
    ("FRAC_PI_3", std::f64::consts::FRAC_PI_3),
    ("FRAC_PI_4", std::f64::consts::FRAC_PI_4),
    ("FRAC_PI_6", std::f64::consts::FRAC_PI_6),
    ("FRAC_1_SQRT_2", std::f64::consts::FRAC_1_SQRT_2),
];

/// Functions of two arguments (free form `f(a, b)`, method form `a.f(b)`).
const BINARY_FUNCTIONS: &[&str] = &["atan2", "hypot", "min", "max", "powi", "powf"];

/// Functions of one argument.
const UNARY_FUNCTIONS: &[&str] = &[
    "sqrt", "exp", "ln", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh",
    "abs", "signum",
];

fn supported_functions() -> String {
    UNARY_FUNCTIONS
        .iter()
        .chain(BINARY_FUNCTIONS)
        .copied()
        .collect::<Vec<_>>()
        .join(", ")
}

/// What a name stands for while lowering.
#[derive(Clone, Copy)]
enum Binding {
    Param(usize),
    State(usize),
    Algebraic(usize),
    Input(usize),
    Let {
        expr: ExprId,
        uses_der: bool,
    },
    /// An integer constant of the `consts` section.
    Const(i64),
    /// An indexed family: index into `Lowerer::families`.
    Family(usize),
}

impl Binding {
    fn describe(self) -> &'static str {
        match self {
            Binding::Param(_) => "a parameter",
            Binding::State(_) => "a state",
            Binding::Algebraic(_) => "an algebraic unknown",
            Binding::Input(_) => "an input",
            Binding::Let { .. } => "a `let` intermediate",
            Binding::Const(_) => "a constant",
            Binding::Family(_) => "an indexed family",
        }
    }

    /// The plural of [`Binding::describe`], for families.
    fn plural(self) -> &'static str {
        match self {
            Binding::Param(_) => "parameters",
            Binding::State(_) => "states",
            Binding::Algebraic(_) => "algebraic unknowns",
            Binding::Input(_) => "inputs",
            Binding::Let { .. } => "`let` intermediates",
            Binding::Const(_) => "constants",
            Binding::Family(_) => "indexed families",
        }
    }
}

/// An indexed family (`states { q[N] }`, `let c[i in 0..N] = ...`): its lengths and the
/// scalar binding of every element, row-major. Lowering unrolls families into scalars, so
/// everything after it sees only elements (`q[2]`, named `q_2` in generated code).
struct Family {
    /// What its elements are, plural (`states`).
    plural: &'static str,
    /// Its lengths, one per index.
    dims: Vec<usize>,
    /// The element bindings; `None` for an element a `let` family does not (yet) define.
    elements: Vec<Option<Binding>>,
    /// For a `let` family, its subscripts as written (`[i in 1..N]`), for messages.
    defined: Option<String>,
    /// A family whose lengths could not be evaluated (reported there): uses of it are
    /// not reported again.
    poisoned: bool,
    /// Offsets of `let` elements whose expressions had errors (reported there): uses of
    /// them are not reported again.
    failed: HashSet<usize>,
}

/// The row-major list of all multi-indices of a family with lengths `dims`.
fn multi_indices(dims: &[usize]) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new()];
    for &d in dims {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                (0..d).map(move |k| {
                    let mut ix = prefix.clone();
                    ix.push(k);
                    ix
                })
            })
            .collect();
    }
    out
}

/// `q[1][2]` and the generated-code name `q_1_2` of an element.
fn element_names(name: &Ident, ix: &[usize]) -> (String, Ident) {
    let base = name.unraw().to_string();
    let label = format!(
        "{base}{}",
        ix.iter().map(|k| format!("[{k}]")).collect::<String>()
    );
    let code = format!(
        "{base}{}",
        ix.iter().map(|k| format!("_{k}")).collect::<String>()
    );
    (label, Ident::new(&code, name.span()))
}

/// Where an expression appears, which decides what it may use.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Place {
    Equation,
    Let,
    Output,
    Reference,
}

impl Place {
    fn describe(self) -> &'static str {
        match self {
            Place::Equation => "an equation",
            Place::Let => "a `let` intermediate",
            Place::Output => "an output",
            Place::Reference => "a reference",
        }
    }
}

struct Lowerer<'a> {
    cx: &'a mut Ctxt,
    graph: Graph,
    symbols: Symbols,
    env: HashMap<String, (Binding, Span)>,
    /// Names of `let`s not yet defined, for a better message on forward use.
    pending_lets: HashSet<String>,
    /// Indexed families, referred to by [`Binding::Family`].
    families: Vec<Family>,
    /// Index variables in scope (`for`, `sum`, the subscripts of a family definition) with
    /// their current values, innermost last.
    indices: Vec<(String, i64)>,
    /// Names the generated code binds (parameters, states, algebraic unknowns, inputs), with
    /// the name as the user wrote it: an element `q[2]` is bound as `q_2` and must not meet
    /// a declared `q_2`.
    code_names: HashMap<String, String>,
}

/// What lowering collects from the model's items, section by section.
#[derive(Default)]
struct Sections {
    params: Vec<Param>,
    states: Vec<Decl>,
    algebraic: Vec<Decl>,
    inputs: Vec<Decl>,
    intermediates: Vec<Intermediate>,
    equations: Vec<Equation>,
    outputs: Vec<Output>,
    references: Vec<Reference>,
    tracking: Option<Tracking>,
    /// The `equations` keyword, where the count of equations is reported.
    equations_keyword: Option<Ident>,
}

/// Lower a parsed model, recording every problem in `cx`. Returns `None` if there were
/// errors that make the IR meaningless.
///
/// The items are lowered in the order written (a `let` or an output may use only what is
/// declared before it), one section at a time; then the checks that need the whole model
/// run, each a small pass of its own.
pub fn lower(def: ModelDef, cx: &mut Ctxt) -> Option<Model> {
    let mut lw = Lowerer {
        cx,
        graph: Graph::new(),
        symbols: Symbols::default(),
        env: HashMap::new(),
        pending_lets: HashSet::new(),
        families: Vec::new(),
        indices: Vec::new(),
        code_names: HashMap::new(),
    };
    let attrs = lw.doc_attrs(&def.attrs, "the model");
    check_section_order(&def, lw.cx);

    for item in &def.items {
        if let Item::Let(l) = item {
            lw.pending_lets.insert(l.name.to_string());
        }
    }
    let mut sx = Sections::default();
    for item in &def.items {
        match item {
            Item::Let(l) => lw.lower_let(l, &mut sx.intermediates),
            Item::Section(section) => lw.lower_section(section, &mut sx),
        }
    }

    check_generated_names(&def, &sx.tracking, !sx.references.is_empty(), lw.cx);
    let equations_keyword = check_required_sections(&def, &sx, lw.cx)?;
    check_equation_count(&sx, &equations_keyword, lw.cx);
    if !lw.cx.has_errors() {
        check_unknowns_used(&sx, &lw.graph, &lw.symbols, lw.cx);
    }

    if lw.cx.has_errors() {
        return None;
    }
    Some(Model {
        attrs,
        vis: def.vis,
        name: def.name,
        params: sx.params,
        states: sx.states,
        algebraic: sx.algebraic,
        inputs: sx.inputs,
        intermediates: sx.intermediates,
        equations: sx.equations,
        outputs: sx.outputs,
        references: sx.references,
        tracking: sx.tracking,
        graph: lw.graph,
        symbols: lw.symbols,
    })
}

/// A section with no entry is refused: it is a leftover or a mistake.
fn check_not_empty(section: &crate::parse::Section, cx: &mut Ctxt) {
    let empty = match &section.body {
        SectionBody::Consts(v) => v.is_empty(),
        SectionBody::Params(v) => v.is_empty(),
        SectionBody::States(v) | SectionBody::Algebraic(v) | SectionBody::Inputs(v) => v.is_empty(),
        SectionBody::Equations(v) => v.is_empty(),
        SectionBody::Outputs(v) => v.is_empty(),
        SectionBody::References(v) => v.is_empty(),
        SectionBody::Tracking(t) => t.entries.is_empty(),
    };
    if empty {
        cx.error_at(
            section.brace_span,
            format!(
                "empty section `{}`: declare at least one entry or remove the section",
                section.keyword
            ),
        );
    }
}

/// A model needs `states` and `equations`; returns the `equations` keyword (`None`, with the
/// error recorded, when there is no such section).
fn check_required_sections(def: &ModelDef, sx: &Sections, cx: &mut Ctxt) -> Option<Ident> {
    if sx.states.is_empty() && !def.items.iter().any(|i| is_section(i, "states")) {
        cx.error_spanned_by(
            &def.name,
            format!("model `{}` has no `states` section; declare its differential unknowns, e.g. `states {{ x, v }}`", def.name),
        );
    }
    if sx.equations_keyword.is_none() {
        cx.error_spanned_by(
            &def.name,
            format!(
                "model `{}` has no `equations` section; add `equations {{ der(x) = ...; }}`",
                def.name
            ),
        );
    }
    sx.equations_keyword.clone()
}

/// As many equations as unknowns (checked only on an otherwise correct model, where the
/// count is meaningful).
fn check_equation_count(sx: &Sections, keyword: &Ident, cx: &mut Ctxt) {
    let (states, algebraic) = (sx.states.len(), sx.algebraic.len());
    let (equations, unknowns) = (sx.equations.len(), states + algebraic);
    if equations != 0 && !cx.has_errors() && equations != unknowns {
        cx.error_spanned_by(
            keyword,
            format!(
                "found {} equation{} for {} unknown{} ({} state{} + {} algebraic); the number of equations must equal the number of unknowns",
                equations,
                plural(equations),
                unknowns,
                plural(unknowns),
                states,
                plural(states),
                algebraic
            ),
        );
    }
}

/// Every state differentiated somewhere, every algebraic unknown used somewhere.
fn check_unknowns_used(sx: &Sections, graph: &Graph, symbols: &Symbols, cx: &mut Ctxt) {
    let mut used = HashSet::new();
    for eq in &sx.equations {
        for v in graph.vars(eq.residual) {
            used.insert(symbols.symbol(v));
        }
    }
    for (i, s) in sx.states.iter().enumerate() {
        if !used.contains(&Symbol::StateDot(i)) {
            cx.error_spanned_by(
                &s.name,
                format!(
                    "state `{}` is never differentiated: no equation contains `der({0})`; add its equation or declare it in `algebraic`",
                    s.name
                ),
            );
        }
    }
    for (i, a) in sx.algebraic.iter().enumerate() {
        if !used.contains(&Symbol::Algebraic(i)) {
            cx.error_spanned_by(
                &a.name,
                format!("algebraic unknown `{}` appears in no equation, so the system cannot determine it", a.name),
            );
        }
    }
}

/// Lowering, one item or section at a time.
impl Lowerer<'_> {
    fn lower_let(&mut self, l: &crate::parse::LetDef, out: &mut Vec<Intermediate>) {
        self.pending_lets.remove(&l.name.to_string());
        let text = expr_text(l.expr.root());
        let label = if l.subscripts.is_empty() {
            if let Some(expr) = self.lower_expr(l.expr.root(), Place::Let) {
                let uses_der = self.uses_derivatives(expr);
                self.declare(&l.name, Binding::Let { expr, uses_der });
            }
            l.name.to_string()
        } else {
            self.lower_let_family(l)
        };
        out.push(Intermediate {
            name: l.name.clone(),
            label,
            text,
        });
    }

    fn lower_section(&mut self, section: &crate::parse::Section, sx: &mut Sections) {
        check_not_empty(section, self.cx);
        match &section.body {
            SectionBody::Consts(list) => {
                for c in list {
                    if let Some(v) = self.eval_int(c.value.root()) {
                        self.declare(&c.name, Binding::Const(v));
                    }
                }
            }
            SectionBody::Params(list) => self.lower_params(list, &mut sx.params),
            SectionBody::States(list) => self.declare_decls(list, &mut sx.states, Binding::State),
            SectionBody::Algebraic(list) => {
                self.declare_decls(list, &mut sx.algebraic, Binding::Algebraic)
            }
            SectionBody::Inputs(list) => self.declare_decls(list, &mut sx.inputs, Binding::Input),
            SectionBody::Equations(list) => {
                sx.equations_keyword = Some(section.keyword.clone());
                let mut explicit_seen: HashMap<usize, Span> = HashMap::new();
                self.lower_equation_items(list, &sx.states, &mut explicit_seen, &mut sx.equations);
            }
            SectionBody::Outputs(list) => self.lower_outputs(list, sx),
            SectionBody::References(list) => {
                sx.references = self.lower_references(&section.keyword, list, &sx.outputs)
            }
            SectionBody::Tracking(t) => {
                sx.tracking = Some(self.lower_tracking(&section.keyword, t, &sx.outputs))
            }
        }
    }

    fn lower_params(&mut self, list: &[crate::parse::ParamDef], params: &mut Vec<Param>) {
        for p in list {
            let docs = self.doc_attrs(&p.attrs, "a parameter");
            if p.dims.is_empty() {
                let default = self.param_default(p.default.root(), &p.name.to_string());
                self.declare(&p.name, Binding::Param(params.len()));
                self.claim_code_name(&p.name, &p.name.unraw().to_string(), None);
                params.push(Param {
                    name: p.name.clone(),
                    label: p.name.unraw().to_string(),
                    unit: unit_text(p.unit.as_ref()),
                    default,
                    docs,
                });
                continue;
            }
            let Some(dims) = self.eval_dims(&p.dims) else {
                self.declare_family(&p.name, Binding::Param(0), Vec::new(), Vec::new());
                continue;
            };
            let defaults = self.param_defaults(p.default.root(), &p.name, &dims);
            let elements = multi_indices(&dims)
                .into_iter()
                .zip(defaults)
                .map(|(ix, default)| {
                    let (label, name) = element_names(&p.name, &ix);
                    self.claim_code_name(&name, &label, Some(&p.name));
                    params.push(Param {
                        name,
                        label,
                        unit: unit_text(p.unit.as_ref()),
                        default,
                        docs: docs.clone(),
                    });
                    Some(Binding::Param(params.len() - 1))
                })
                .collect();
            self.declare_family(&p.name, Binding::Param(0), dims, elements);
        }
    }

    fn lower_outputs(&mut self, list: &[crate::parse::OutputDef], sx: &mut Sections) {
        for o in list {
            if let Some(msg) = crate::names::check(&o.name, "an output") {
                self.cx.error_spanned_by(&o.name, msg);
                continue;
            }
            let docs = self.doc_attrs(&o.attrs, "an output");
            for (label, name, expr, text) in self.lower_output(o) {
                if sx
                    .outputs
                    .iter()
                    .any(|p| p.label == label || p.name == name)
                {
                    self.cx
                        .error_spanned_by(&o.name, format!("duplicate output `{label}`"));
                    continue;
                }
                let unit = match &o.expr {
                    Some(_) => unit_text(o.unit.as_ref()),
                    None => self.bare_output_unit(
                        o,
                        &text,
                        [&sx.states, &sx.algebraic, &sx.inputs],
                        &sx.params,
                    ),
                };
                sx.outputs.push(Output {
                    name,
                    label,
                    unit,
                    expr,
                    text,
                    docs: docs.clone(),
                });
            }
        }
    }

    /// The references, one per output (every output needs one when the section is given).
    fn lower_references(
        &mut self,
        keyword: &Ident,
        list: &[crate::parse::ReferenceDef],
        outputs: &[Output],
    ) -> Vec<Reference> {
        let mut references = Vec::new();
        let mut seen = HashSet::new();
        for r in list {
            let Some(targets) = self.target_outputs(
                &r.output,
                &r.subscripts,
                outputs,
                "references are given per output",
            ) else {
                continue;
            };
            for (index, bound) in targets {
                if !seen.insert(index) {
                    self.cx.error_spanned_by(
                        &r.output,
                        format!("duplicate reference for output `{}`", outputs[index].label),
                    );
                    continue;
                }
                let depth = self.indices.len();
                self.indices.extend(bound);
                let text = self.indexed_text(r.expr.root());
                let expr = self.lower_expr(r.expr.root(), Place::Reference);
                self.indices.truncate(depth);
                if let Some(expr) = expr {
                    references.push(Reference {
                        output: index,
                        expr,
                        text,
                    });
                }
            }
        }
        let missing: Vec<String> = outputs
            .iter()
            .enumerate()
            .filter(|(i, _)| !seen.contains(i))
            .map(|(_, o)| format!("`{}`", o.label))
            .collect();
        if !missing.is_empty() && !list.is_empty() {
            self.cx.error_spanned_by(
                keyword,
                format!(
                    "`references` must give every output a reference; missing: {}",
                    missing.join(", ")
                ),
            );
        }
        references
    }

    /// The tracking section: per output, the negated roots of `W(s)`.
    fn lower_tracking(
        &mut self,
        keyword: &Ident,
        t: &crate::parse::TrackingDef,
        outputs: &[Output],
    ) -> Tracking {
        let mut entries: Vec<TrackingEntry> = Vec::new();
        for entry in &t.entries {
            let Some(targets) = self.target_outputs(
                &entry.output,
                &entry.subscripts,
                outputs,
                "`tracking` names outputs declared in `outputs`",
            ) else {
                continue;
            };
            let roots = self.negated_roots(entry);
            let span = entry
                .output
                .span()
                .join(entry.bracket_span)
                .unwrap_or_else(|| entry.output.span());
            for (index, _) in targets {
                if entries.iter().any(|e| e.output == index) {
                    self.cx.error_spanned_by(
                        &entry.output,
                        format!(
                            "duplicate tracking entry for output `{}`",
                            outputs[index].label
                        ),
                    );
                    continue;
                }
                entries.push(TrackingEntry {
                    output: index,
                    roots: roots.clone(),
                    span,
                });
            }
        }
        entries.sort_by_key(|e| e.output);
        Tracking {
            type_name: t.type_name.clone(),
            entries,
            span: keyword.span(),
        }
    }

    /// The negated roots of one tracking entry's `W(s)`: finite numbers `>= 0` whose
    /// polynomial's coefficients fit `f64`.
    fn negated_roots(&mut self, entry: &crate::parse::TrackingEntry) -> Vec<f64> {
        let mut roots = Vec::new();
        for r in &entry.roots {
            match numeric_literal(r.root()) {
                Some(a) if !a.is_finite() => self.cx.error_spanned_by(
                    r,
                    format!(
                        "`{}` is out of range for `f64` (it overflows to infinity); a negated root of W(s) must be a finite number",
                        expr_text(r.root())
                    ),
                ),
                Some(a) if a >= 0.0 => roots.push(a),
                Some(a) => self.cx.error_spanned_by(
                    r,
                    format!(
                        "`{a}` would put a root of W(s) at s = {}, which is unstable; entries are the negated roots and must be >= 0 (e.g. `5.0` for `s + 5`, `0.0` for plain differentiation)",
                        -a
                    ),
                ),
                None => self.cx.error_spanned_by(
                    r,
                    format!(
                        "expected a number (a negated root of W(s), e.g. `5.0` for `s + 5`), found `{}`",
                        expr_text(r.root())
                    ),
                ),
            }
        }
        let coefficients = crate::hirschorn::polynomial_from_negated_roots(&roots);
        if coefficients.iter().any(|c| !c.is_finite()) {
            self.cx.error_at(
                entry.bracket_span,
                format!(
                    "the coefficients of W(s) = {} overflow `f64`; use smaller roots",
                    crate::hirschorn::polynomial_text(&roots)
                ),
            );
        }
        roots
    }
}

/// The model's name, the tracking type's name and the items the expansion declares from
/// them (`<Model>`, `<Model>Params`, the tracking type, `<Model>Reference`) must be usable
/// type names and pairwise distinct.
fn check_generated_names(
    def: &ModelDef,
    tracking: &Option<Tracking>,
    has_references: bool,
    cx: &mut Ctxt,
) {
    let model = &def.name;
    if let Some(msg) = crate::names::check(model, "a model") {
        cx.error_spanned_by(model, msg);
    }
    let Some(tracking) = tracking else {
        return;
    };
    let ty = &tracking.type_name;
    if let Some(msg) = crate::names::check(ty, "a tracking type") {
        cx.error_spanned_by(ty, msg);
        return;
    }
    let base = model.unraw().to_string();
    let taken = [
        (base.clone(), "the model type itself", true),
        (
            format!("{base}Params"),
            "the model's parameter struct",
            true,
        ),
        (
            format!("{base}Reference"),
            "the reference type generated for the `references` section",
            has_references,
        ),
    ];
    let name = ty.unraw().to_string();
    if let Some((_, what, _)) = taken.iter().find(|(n, _, on)| *on && *n == name) {
        cx.error_spanned_by(
            ty,
            format!(
                "the tracking type cannot be named `{name}`: the expansion already declares `{name}` as {what}; choose another name, e.g. `{base}Tracking`"
            ),
        );
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn is_section(item: &Item, name: &str) -> bool {
    matches!(item, Item::Section(s) if s.keyword == name)
}

/// Sections must appear at most once each, in [`SECTION_ORDER`], with `let`s after the
/// declarations and before `equations`.
fn check_section_order(def: &ModelDef, cx: &mut Ctxt) {
    let rank = |name: &str| SECTION_ORDER.iter().position(|s| *s == name).unwrap_or(0);
    let equations_rank = rank("equations");
    let mut seen: HashMap<String, Span> = HashMap::new();
    let mut last: Option<(usize, String)> = None;
    let mut first_let: Option<Span> = None;
    for item in &def.items {
        match item {
            Item::Let(l) => {
                first_let.get_or_insert(l.let_token.span);
                if let Some((r, name)) = &last {
                    if *r >= equations_rank {
                        cx.error_spanned_by(
                            l.let_token,
                            format!(
                                "misplaced `let`: intermediates must come before `equations` (found after `{name}`)"
                            ),
                        );
                    }
                }
            }
            Item::Section(s) => {
                let name = s.keyword.to_string();
                let r = rank(&name);
                if let Some(prev) = seen.get(&name) {
                    let mut err = syn::Error::new(
                        s.keyword.span(),
                        format!("duplicate section `{name}`; merge its entries into the first one"),
                    );
                    err.combine(syn::Error::new(
                        *prev,
                        format!("first `{name}` section here"),
                    ));
                    cx.push(err);
                    continue;
                }
                seen.insert(name.clone(), s.keyword.span());
                if let Some((prev_rank, prev_name)) = &last {
                    if r < *prev_rank {
                        cx.error_spanned_by(
                            &s.keyword,
                            format!(
                                "misplaced section `{name}`: it must come before `{prev_name}`; sections go in the order {}",
                                SECTION_ORDER.join(", ")
                            ),
                        );
                    }
                }
                if r < equations_rank && first_let.is_some() {
                    cx.error_spanned_by(
                        &s.keyword,
                        format!("misplaced section `{name}`: declarations must come before the `let` intermediates"),
                    );
                }
                if last.as_ref().is_none_or(|(p, _)| r > *p) {
                    last = Some((r, name));
                }
            }
        }
    }
}

/// The expression under any unary minus signs and parentheses, and whether an odd number of
/// minus signs negates it (`-(-(2))` is `2`, not negated).
fn strip_signs(e: ExprRef<'_>) -> (ExprRef<'_>, bool) {
    let mut e = e;
    let mut negated = false;
    loop {
        match e.kind() {
            ExprKind::Unary {
                op: UnaryOp::Neg,
                operand,
                ..
            } => {
                negated = !negated;
                e = e.at(*operand);
            }
            ExprKind::Paren(inner) => e = e.at(*inner),
            _ => return (e, negated),
        }
    }
}

/// The value of a numeric literal, optionally negated (`1.0`, `2`, `-9.81`).
pub fn numeric_literal(e: ExprRef<'_>) -> Option<f64> {
    let (e, negated) = strip_signs(e);
    let value = match e.kind() {
        ExprKind::Lit(Lit::Float(f)) if matches!(f.suffix(), "" | "f64") => f.base10_parse::<f64>(),
        ExprKind::Lit(Lit::Int(i)) if matches!(i.suffix(), "" | "f64") => i.base10_parse::<f64>(),
        _ => return None,
    };
    value.ok().map(|v| if negated { -v } else { v })
}

/// The value of an integer literal, optionally negated, if it fits `i32`.
fn integer_literal(e: ExprRef<'_>) -> Option<i32> {
    let (e, negated) = strip_signs(e);
    match e.kind() {
        ExprKind::Lit(Lit::Int(i)) if matches!(i.suffix(), "" | "i32") => i
            .base10_parse::<i32>()
            .ok()
            .map(|v| if negated { -v } else { v }),
        _ => None,
    }
}

impl Lowerer<'_> {
    fn doc_attrs(&mut self, attrs: &[Attribute], what: &str) -> Vec<Attribute> {
        let mut docs = Vec::new();
        for a in attrs {
            if a.path().is_ident("doc") {
                docs.push(a.clone());
            } else {
                self.cx.error_spanned_by(
                    a,
                    format!("unsupported attribute on {what}; only doc comments (`/// ...`) are allowed"),
                );
            }
        }
        docs
    }

    fn declare(&mut self, name: &Ident, binding: Binding) {
        self.declare_as(name, binding, binding.describe());
    }

    /// Declares `name`; `what` names what it is in refusals of reserved names (`a state`,
    /// also for a family of states).
    fn declare_as(&mut self, name: &Ident, binding: Binding, what: &str) {
        let s = name.unraw().to_string();
        if s == "t" {
            self.cx
                .error_spanned_by(name, "`t` is reserved for time; choose another name");
            return;
        }
        if s.contains("__") {
            self.cx.error_spanned_by(
                name,
                format!("`{s}` contains `__`, which is reserved for generated code; choose another name"),
            );
            return;
        }
        if let Some(msg) = crate::names::check(name, what) {
            self.cx.error_spanned_by(name, msg);
            return;
        }
        if CONSTANTS.iter().any(|(c, _)| *c == s) {
            self.cx.error_spanned_by(
                name,
                format!("`{s}` is a named constant; choose another name"),
            );
            return;
        }
        if let Some((prev, prev_span)) = self.env.get(&s) {
            let mut err = syn::Error::new(
                name.span(),
                format!(
                    "duplicate name `{s}`: it is already declared as {}",
                    prev.describe()
                ),
            );
            err.combine(syn::Error::new(
                *prev_span,
                format!("`{s}` first declared here"),
            ));
            self.cx.push(err);
            return;
        }
        self.env.insert(s, (binding, name.span()));
    }

    fn uses_derivatives(&self, e: ExprId) -> bool {
        self.graph.vars(e).into_iter().any(|v| {
            matches!(
                self.symbols.symbol(v),
                Symbol::StateDot(_)
                    | Symbol::StateDerivative { .. }
                    | Symbol::AlgebraicDot(_)
                    | Symbol::InputDot(_)
            )
        })
    }

    fn symbol(&mut self, s: Symbol) -> ExprId {
        let v = self.symbols.var(s);
        self.graph.var(v)
    }

    fn lower_equation(&mut self, e: ExprRef<'_>) -> Option<Equation> {
        let text = self.indexed_text(e);
        let span = e.spans().joined();
        match e.kind() {
            ExprKind::Assign { left, right } => {
                let left = e.at(*left);
                let state = match left.kind() {
                    ExprKind::Call { .. } if left.call_name().as_deref() == Some("der") => {
                        let d = self.lower_expr(left, Place::Equation)?;
                        match self.graph.node(d) {
                            crate::symbolic::Node::Var(v) => match self.symbols.symbol(*v) {
                                Symbol::StateDot(j) => Some((j, d)),
                                _ => None,
                            },
                            _ => None,
                        }
                    }
                    _ => {
                        self.cx.error_spanned_by(
                            left,
                            format!(
                                "the left side of `=` must be `der(state)`, found `{}`; write implicit equations as `lhs == rhs`",
                                expr_text(left)
                            ),
                        );
                        None
                    }
                };
                let rhs = self.lower_expr(e.at(*right), Place::Equation);
                let (j, lhs) = state?;
                let rhs = rhs?;
                let residual = self.graph.sub(lhs, rhs);
                let explicit = (!self.uses_derivatives(rhs)).then_some((j, rhs));
                Some(Equation {
                    residual,
                    text,
                    explicit,
                    span,
                })
            }
            ExprKind::Binary {
                op: BinaryOp::Eq,
                left,
                right,
                ..
            } => {
                let lhs = self.lower_expr(e.at(*left), Place::Equation);
                let rhs = self.lower_expr(e.at(*right), Place::Equation);
                let (lhs, rhs) = (lhs?, rhs?);
                let residual = self.graph.sub(lhs, rhs);
                Some(Equation {
                    residual,
                    text,
                    explicit: None,
                    span,
                })
            }
            _ => {
                self.cx.error_spanned_by(
                    e,
                    format!(
                        "expected an equation, either explicit `der(x) = expr` or implicit `lhs == rhs`, found `{}`",
                        expr_text(e)
                    ),
                );
                None
            }
        }
    }

    /// Lowers `e` into the graph, or records its errors and returns `None`.
    ///
    /// A loop over an explicit stack of [`Task`]s and a stack of lowered values, so that the
    /// depth of the expression costs heap, not call stack. A node pushes the lowering of its
    /// operands (left first) and then combines their values; errors are found in the same
    /// order as by a recursive descent, and graph nodes are created in the same order.
    fn lower_expr(&mut self, e: ExprRef<'_>, place: Place) -> Option<ExprId> {
        let mut tasks = vec![Task::Lower(e)];
        let mut values: Vec<Option<ExprId>> = Vec::new();
        while let Some(task) = tasks.pop() {
            match task {
                Task::Lower(e) => self.lower_node(e, place, &mut tasks, &mut values),
                Task::Combine(e) => {
                    let v = self.combine_node(e, &mut values);
                    values.push(v);
                }
                Task::Bind(name, k) => self.indices.push((name, k)),
                Task::Unbind => {
                    self.indices.pop();
                }
                Task::AddTerm => {
                    let term = values.pop().flatten();
                    let total = values.pop().flatten();
                    values.push(match (total, term) {
                        (Some(total), Some(term)) => Some(self.graph.add(total, term)),
                        _ => None,
                    });
                }
            }
        }
        values.pop().flatten()
    }

    /// One node of [`Lowerer::lower_expr`]: its value, or the tasks that compute it.
    fn lower_node<'a>(
        &mut self,
        e: ExprRef<'a>,
        place: Place,
        tasks: &mut Vec<Task<'a>>,
        values: &mut Vec<Option<ExprId>>,
    ) {
        let value = match e.kind() {
            ExprKind::Paren(inner) => {
                tasks.push(Task::Lower(e.at(*inner)));
                return;
            }
            ExprKind::Lit(l) => match numeric_literal(e) {
                Some(v) if !v.is_finite() => {
                    self.cx.error_spanned_by(
                        e,
                        format!(
                            "the literal `{}` is out of range for `f64`: it overflows to infinity (the largest finite value is about 1.8e308)",
                            l.to_token_stream()
                        ),
                    );
                    None
                }
                Some(v) => Some(self.graph.constant(v)),
                None => {
                    self.cx.error_spanned_by(
                        e,
                        format!("expected a number, found `{}`", l.to_token_stream()),
                    );
                    None
                }
            },
            ExprKind::Path {
                leading_colon,
                segments,
            } => match (leading_colon, segments.as_slice()) {
                (false, [ident]) => self.lower_name(ident, place),
                _ => match std_constant(segments) {
                    Some(v) => Some(self.graph.constant(v)),
                    None => {
                        self.cx.error_spanned_by(
                            e,
                            format!(
                                "expected a declared name or a constant such as `PI`, found the path `{}`",
                                expr_text(e)
                            ),
                        );
                        None
                    }
                },
            },
            ExprKind::Index { .. } => self
                .resolve_element(e)
                .and_then(|(binding, label)| self.lower_binding(binding, &e, &label, place)),
            ExprKind::Unary {
                op: UnaryOp::Neg,
                operand,
                ..
            } => {
                tasks.push(Task::Combine(e));
                tasks.push(Task::Lower(e.at(*operand)));
                return;
            }
            ExprKind::Unary { op_span, .. } => {
                self.cx.error_spanned_by(
                    crate::expr::Spans::single(*op_span),
                    "unsupported operator; expected `-` (negation) or one of `+ - * /`",
                );
                None
            }
            ExprKind::Binary {
                op,
                op_spans,
                left,
                right,
            } => {
                match op {
                    BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div => {
                        tasks.push(Task::Combine(e));
                        tasks.push(Task::Lower(e.at(*right)));
                        tasks.push(Task::Lower(e.at(*left)));
                        return;
                    }
                    BinaryOp::Eq => {
                        self.cx.error_spanned_by(
                        op_spans,
                        format!("`==` may appear only once, at the top of an equation, not inside {}", place.describe()),
                    );
                        None
                    }
                    _ => {
                        self.cx.error_spanned_by(
                        op_spans,
                        format!(
                            "unsupported operator `{}`; expected `+`, `-`, `*` or `/` (use `powi`/`powf` for powers)",
                            op.as_str()
                        ),
                    );
                        None
                    }
                }
            }
            ExprKind::Call { func, .. } => {
                let Some(name) = e.call_name() else {
                    self.cx.error_spanned_by(
                        e.at(*func),
                        format!(
                            "expected a function name ({}), found `{}`",
                            supported_functions(),
                            expr_text(e.at(*func))
                        ),
                    );
                    values.push(None);
                    return;
                };
                if name == "der" {
                    self.lower_der(e, place)
                } else if name == "sum" {
                    self.lower_sum(e, tasks, values);
                    return;
                } else {
                    let (_, args) = call_parts(e);
                    self.lower_call(e, &name, &e.at(*func), &args, false, tasks, values);
                    return;
                }
            }
            ExprKind::MethodCall {
                method, turbofish, ..
            } => {
                if let Some(tf) = turbofish {
                    self.cx.error_spanned_by(
                        tf,
                        "type arguments are not supported in model expressions",
                    );
                    values.push(None);
                    return;
                }
                let name = method.to_string();
                if name == "der" {
                    self.cx
                        .error_spanned_by(method, "write derivatives as `der(x)`, not `x.der()`");
                    values.push(None);
                    return;
                }
                let (_, args) = call_parts(e);
                self.lower_call(e, &name, method, &args, true, tasks, values);
                return;
            }
            ExprKind::Assign { .. } => {
                self.cx.error_spanned_by(
                    e,
                    format!("`=` may appear only at the top of an explicit equation `der(x) = expr`, not inside {}", place.describe()),
                );
                None
            }
            _ => {
                self.cx.error_spanned_by(
                    e,
                    "unsupported expression; expected numbers, declared names, `+ - * /`, unary `-`, parentheses and function calls",
                );
                None
            }
        };
        values.push(value);
    }

    /// The value of a node from the values of its operands, lowered before it (on top of
    /// `values`, last operand last).
    fn combine_node(&mut self, e: ExprRef<'_>, values: &mut Vec<Option<ExprId>>) -> Option<ExprId> {
        match e.kind() {
            ExprKind::Unary { .. } => {
                let a = values.pop().flatten()?;
                Some(self.graph.neg(a))
            }
            ExprKind::Binary { op, .. } => {
                let r = values.pop().flatten();
                let l = values.pop().flatten();
                let (l, r) = (l?, r?);
                Some(match op {
                    BinaryOp::Add => self.graph.add(l, r),
                    BinaryOp::Sub => self.graph.sub(l, r),
                    BinaryOp::Mul => self.graph.mul(l, r),
                    _ => self.graph.div(l, r),
                })
            }
            ExprKind::Call { .. } | ExprKind::MethodCall { .. } => {
                let (name, args) = call_parts(e);
                let name = name?;
                if name == "powi" {
                    let base = values.pop().flatten();
                    let exponent = *args.get(1)?;
                    let Some(n) = integer_literal(exponent) else {
                        self.cx.error_spanned_by(
                            exponent,
                            format!(
                                "`powi` needs an integer literal exponent such as `2` or `-1`, found `{}`; use `powf` for real or variable exponents",
                                expr_text(exponent)
                            ),
                        );
                        return None;
                    };
                    return Some(self.graph.powi(base?, n));
                }
                let lowered = values.split_off(values.len().saturating_sub(args.len()));
                let lowered: Vec<ExprId> = lowered.into_iter().collect::<Option<_>>()?;
                Some(match name.as_str() {
                    "atan2" => self.graph.atan2(lowered[0], lowered[1]),
                    "hypot" => self.graph.hypot(lowered[0], lowered[1]),
                    "min" => self.graph.min(lowered[0], lowered[1]),
                    "max" => self.graph.max(lowered[0], lowered[1]),
                    "powf" => self.graph.powf(lowered[0], lowered[1]),
                    _ => {
                        let f = Func::from_name(&name)?;
                        self.graph.func(f, lowered[0])
                    }
                })
            }
            _ => None,
        }
    }

    fn lower_name(&mut self, ident: &Ident, place: Place) -> Option<ExprId> {
        let s = ident.unraw().to_string();
        if s == "t" {
            return Some(self.symbol(Symbol::Time));
        }
        if let Some((_, v)) = self.indices.iter().rev().find(|(n, _)| *n == s) {
            let v = *v as f64;
            return Some(self.graph.constant(v));
        }
        let Some((binding, _)) = self.env.get(&s).copied() else {
            if let Some((_, v)) = CONSTANTS.iter().find(|(c, _)| *c == s) {
                return Some(self.graph.constant(*v));
            }
            let msg = self.unknown_name_message(&s);
            self.cx.error_spanned_by(ident, msg);
            return None;
        };
        self.lower_binding(binding, ident, &s, place)
    }

    /// The message for a name that is not declared.
    fn unknown_name_message(&self, s: &str) -> String {
        if self.pending_lets.contains(s) {
            format!("`{s}` is used before its `let` definition; move the definition up")
        } else {
            let mut known: Vec<&String> = self.env.keys().collect();
            known.sort();
            format!(
                "unknown identifier `{s}`; expected a declared parameter, state, algebraic unknown, input or `let`, `t`, or a constant such as `PI`{}",
                if known.is_empty() {
                    String::new()
                } else {
                    format!(" (declared: {})", known.iter().map(|k| k.as_str()).collect::<Vec<_>>().join(", "))
                }
            )
        }
    }

    /// The expression of a scalar binding (a declared name or a family's element, written
    /// `s` by the user at `tokens`) in `place`.
    fn lower_binding(
        &mut self,
        binding: Binding,
        tokens: &dyn ToTokens,
        s: &str,
        place: Place,
    ) -> Option<ExprId> {
        if place == Place::Reference && !matches!(binding, Binding::Param(_) | Binding::Const(_)) {
            self.cx.error_spanned_by(
                tokens,
                format!(
                    "a reference may depend only on `t` and parameters, but `{s}` is {}",
                    binding.describe()
                ),
            );
            return None;
        }
        Some(match binding {
            Binding::Param(i) => self.symbol(Symbol::Param(i)),
            Binding::State(i) => self.symbol(Symbol::State(i)),
            Binding::Algebraic(i) => self.symbol(Symbol::Algebraic(i)),
            Binding::Input(i) => self.symbol(Symbol::Input(i)),
            Binding::Const(v) => self.graph.constant(v as f64),
            Binding::Family(f) => {
                let fam = &self.families[f];
                if fam.poisoned {
                    return None;
                }
                let example = fam.dims.iter().map(|_| "[i]").collect::<String>();
                let msg = format!(
                    "`{s}` is a family of {} {}; use one element, e.g. `{s}{example}` inside `for i in ...` or `sum(.., |i| ..)`",
                    fam.elements.len(),
                    fam.plural,
                );
                self.cx.error_spanned_by(tokens, msg);
                return None;
            }
            Binding::Let { expr, uses_der } => {
                if uses_der && place == Place::Output {
                    self.cx.error_spanned_by(
                        tokens,
                        format!("`{s}` uses `der()`, which an output may not depend on"),
                    );
                    return None;
                }
                expr
            }
        })
    }

    fn lower_der(&mut self, c: ExprRef<'_>, place: Place) -> Option<ExprId> {
        let ExprKind::Call { args, .. } = c.kind() else {
            return None;
        };
        if matches!(place, Place::Output | Place::Reference) {
            self.cx.error_spanned_by(
                c,
                format!(
                    "`der()` cannot appear in {}; only equations and `let`s may use it",
                    place.describe()
                ),
            );
            return None;
        }
        if args.len() != 1 {
            self.cx.error_spanned_by(
                c,
                format!(
                    "`der` takes exactly one state name, found {} arguments",
                    args.len()
                ),
            );
            return None;
        }
        let arg = c.at(args[0]);
        if arg.call_name().as_deref() == Some("der") {
            self.cx.error_spanned_by(
                c,
                "nested `der(der(..))` is not supported; introduce a state for the first derivative (e.g. `der(x) = v; der(v) = ...`)",
            );
            return None;
        }
        if matches!(arg.strip_parentheses().kind(), ExprKind::Index { .. }) {
            let (binding, label) = self.resolve_element(arg)?;
            return match binding {
                Binding::State(i) => Some(self.symbol(Symbol::StateDot(i))),
                b => {
                    self.cx.error_spanned_by(
                        arg,
                        format!(
                            "`der()` applies to states only, but `{label}` is {}",
                            b.describe()
                        ),
                    );
                    None
                }
            };
        }
        let Some(ident) = arg.path_ident() else {
            self.cx.error_spanned_by(
                arg,
                format!(
                    "`der()` takes the name of a state, found the expression `{}`",
                    expr_text(arg)
                ),
            );
            return None;
        };
        match self.env.get(&ident.to_string()).copied() {
            Some((Binding::State(i), _)) => Some(self.symbol(Symbol::StateDot(i))),
            Some((Binding::Family(f), _)) if self.families[f].poisoned => None,
            Some((Binding::Family(f), _)) => {
                let msg = format!(
                    "`der()` applies to one state, but `{ident}` is a family of {} {}; write `der({ident}[i])` inside `for i in ...`",
                    self.families[f].elements.len(),
                    self.families[f].plural
                );
                self.cx.error_spanned_by(arg, msg);
                None
            }
            Some((b, _)) => {
                let hint = match b {
                    Binding::Algebraic(_) => {
                        "; declare it in `states` if it is a differential unknown"
                    }
                    _ => "",
                };
                self.cx.error_spanned_by(
                    arg,
                    format!(
                        "`der()` applies to states only, but `{ident}` is {}{hint}",
                        b.describe()
                    ),
                );
                None
            }
            None if ident == "t" => {
                self.cx
                    .error_spanned_by(arg, "`der(t)` is always 1; write `1.0`");
                None
            }
            None => {
                self.cx.error_spanned_by(
                    arg,
                    format!("unknown identifier `{ident}` in `der()`; expected a declared state"),
                );
                None
            }
        }
    }

    /// A call of a supported function (`name` at `name_tokens`, arguments including a
    /// method's receiver): checks the arity and pushes the lowering of the arguments and
    /// their combination at `e`.
    #[allow(clippy::too_many_arguments)]
    fn lower_call<'a>(
        &mut self,
        e: ExprRef<'a>,
        name: &str,
        name_tokens: &dyn ToTokens,
        args: &[ExprRef<'a>],
        method: bool,
        tasks: &mut Vec<Task<'a>>,
        values: &mut Vec<Option<ExprId>>,
    ) {
        let arity = if UNARY_FUNCTIONS.contains(&name) {
            1
        } else if BINARY_FUNCTIONS.contains(&name) {
            2
        } else {
            self.cx.error_spanned_by(
                name_tokens,
                format!(
                    "unknown function `{name}`; supported functions are {}",
                    supported_functions()
                ),
            );
            values.push(None);
            return;
        };
        if args.len() != arity {
            let (found, expected) = if method {
                (args.len() - 1, arity - 1)
            } else {
                (args.len(), arity)
            };
            let form = if arity == 1 {
                format!("`{name}(x)` or `x.{name}()`")
            } else {
                format!("`{name}(a, b)` or `a.{name}(b)`")
            };
            let what = if method {
                format!(
                    "`.{name}()` takes {expected} argument{} besides its receiver",
                    plural(expected)
                )
            } else {
                format!("`{name}` takes {expected} argument{}", plural(expected))
            };
            self.cx
                .error_spanned_by(name_tokens, format!("{what}, found {found}; write {form}"));
            values.push(None);
            return;
        }
        tasks.push(Task::Combine(e));
        if name == "powi" {
            // The exponent is checked, not lowered.
            tasks.push(Task::Lower(args[0]));
            return;
        }
        tasks.extend(args.iter().rev().map(|a| Task::Lower(*a)));
    }
}

/// Work of [`Lowerer::lower_expr`].
enum Task<'a> {
    /// Lower a node: its value goes on the value stack, directly or through more tasks.
    Lower(ExprRef<'a>),
    /// Combine the values of a node's operands, lowered just before, into its own.
    Combine(ExprRef<'a>),
    /// Bind the index variable of a `sum` for the next term.
    Bind(String, i64),
    /// Unbind it after the term.
    Unbind,
    /// Add the last value (a term of a `sum`) to the one below it (the total so far).
    AddTerm,
}

/// The function name and the arguments of a call, or the method name and the receiver
/// followed by the arguments of a method call.
fn call_parts(e: ExprRef<'_>) -> (Option<String>, Vec<ExprRef<'_>>) {
    match e.kind() {
        ExprKind::Call { args, .. } => (e.call_name(), args.iter().map(|a| e.at(*a)).collect()),
        ExprKind::MethodCall {
            receiver,
            method,
            args,
            ..
        } => (
            Some(method.to_string()),
            std::iter::once(*receiver)
                .chain(args.iter().copied())
                .map(|a| e.at(a))
                .collect(),
        ),
        _ => (None, Vec::new()),
    }
}

/// The text of a unit as declared (checked by the parser), without surrounding blanks.
fn unit_text(unit: Option<&syn::LitStr>) -> Option<String> {
    unit.map(|u| u.value().trim().to_string())
}

/// `std::f64::consts::PI`, `core::f64::consts::PI` and `f64::consts::PI`.
fn std_constant(segments: &[Ident]) -> Option<f64> {
    let segs: Vec<String> = segments.iter().map(|s| s.to_string()).collect();
    let tail = match segs.as_slice() {
        [a, b, c, d] if (a == "std" || a == "core") && b == "f64" && c == "consts" => d,
        [b, c, d] if b == "f64" && c == "consts" => d,
        _ => return None,
    };
    CONSTANTS.iter().find(|(n, _)| n == tail).map(|(_, v)| *v)
}

/// Every combination of values of `ranges` (half-open), row-major.
fn range_product(ranges: &[(i64, i64)]) -> Vec<Vec<i64>> {
    let mut out = vec![Vec::new()];
    for &(a, b) in ranges {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                (a..b).map(move |k| {
                    let mut ix = prefix.clone();
                    ix.push(k);
                    ix
                })
            })
            .collect();
    }
    out
}

/// The subscripts of a definition as written: `[i in 0..N][2]`.
fn subscripts_text(subscripts: &[Subscript]) -> String {
    subscripts
        .iter()
        .map(|s| match s {
            Subscript::Binder { var, range } => format!("[{var} in {}]", expr_text(range.root())),
            Subscript::Index(e) => format!("[{}]", expr_text(e.root())),
        })
        .collect()
}

/// What the integer expressions of lengths, ranges and indices may contain.
const INDEX_EXPRESSIONS: &str = "integer literals, constants of the `consts` section and index variables (of `for`, `sum` or a family definition), combined with `+ - *`, `min` and `max`";

/// Indexed families: declaration, element access, index arithmetic and unrolling.
impl Lowerer<'_> {
    /// The value of an integer expression (a length, range bound or index), or `None` with
    /// the error recorded on the offending tokens.
    ///
    /// Evaluated with an explicit stack (operands first, then the node on a second visit),
    /// reporting errors in the order of a left-to-right descent.
    fn eval_int(&mut self, e: ExprRef<'_>) -> Option<i64> {
        let mut todo = vec![(e, false)];
        let mut stack: Vec<Option<i64>> = Vec::new();
        while let Some((e, ready)) = todo.pop() {
            let e = e.strip_parentheses();
            if ready {
                let value = match e.kind() {
                    ExprKind::Unary { .. } => match stack.pop().flatten() {
                        Some(v) => self.checked(v.checked_neg(), e),
                        None => None,
                    },
                    ExprKind::Binary { op, .. } => {
                        let r = stack.pop().flatten();
                        let l = stack.pop().flatten();
                        match (l, r) {
                            (Some(l), Some(r)) => {
                                let v = match op {
                                    BinaryOp::Add => l.checked_add(r),
                                    BinaryOp::Sub => l.checked_sub(r),
                                    _ => l.checked_mul(r),
                                };
                                self.checked(v, e)
                            }
                            _ => None,
                        }
                    }
                    _ => {
                        let b = stack.pop().flatten();
                        let a = stack.pop().flatten();
                        match (a, b) {
                            (Some(a), Some(b)) if e.call_name().as_deref() == Some("min") => {
                                Some(a.min(b))
                            }
                            (Some(a), Some(b)) => Some(a.max(b)),
                            _ => None,
                        }
                    }
                };
                stack.push(value);
                continue;
            }
            let value = match e.kind() {
                ExprKind::Lit(lit) => match lit {
                    Lit::Int(i) if matches!(i.suffix(), "" | "usize" | "i64" | "i32") => {
                        match i.base10_parse::<i64>() {
                            Ok(v) => Some(v),
                            Err(_) => {
                                self.cx.error_spanned_by(
                                    e,
                                    format!(
                                        "the integer `{}` is too large for an index or length",
                                        lit.to_token_stream()
                                    ),
                                );
                                None
                            }
                        }
                    }
                    _ => {
                        self.cx.error_spanned_by(
                            e,
                            format!(
                                "lengths, ranges and indices are integers, found `{}`; write e.g. `3` or `N`",
                                lit.to_token_stream()
                            ),
                        );
                        None
                    }
                },
                ExprKind::Path { .. } => self.eval_int_name(e),
                ExprKind::Unary {
                    op: UnaryOp::Neg,
                    operand,
                    ..
                } => {
                    todo.push((e, true));
                    todo.push((e.at(*operand), false));
                    continue;
                }
                ExprKind::Binary {
                    op: BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul,
                    left,
                    right,
                    ..
                } => {
                    todo.push((e, true));
                    todo.push((e.at(*right), false));
                    todo.push((e.at(*left), false));
                    continue;
                }
                ExprKind::Call { args, .. }
                    if args.len() == 2
                        && matches!(e.call_name().as_deref(), Some("min") | Some("max")) =>
                {
                    todo.push((e, true));
                    todo.push((e.at(args[1]), false));
                    todo.push((e.at(args[0]), false));
                    continue;
                }
                _ => {
                    self.cx.error_spanned_by(
                        e,
                        format!(
                            "unsupported index expression `{}`; lengths, ranges and indices may use {INDEX_EXPRESSIONS}",
                            expr_text(e)
                        ),
                    );
                    None
                }
            };
            stack.push(value);
        }
        stack.pop().flatten()
    }

    /// The value of a name in an integer expression: an index variable or a constant.
    fn eval_int_name(&mut self, e: ExprRef<'_>) -> Option<i64> {
        let Some(ident) = e.path_ident() else {
            self.cx.error_spanned_by(
                e,
                format!(
                    "expected an integer constant or index variable, found the path `{}`",
                    expr_text(e)
                ),
            );
            return None;
        };
        let s = ident.unraw().to_string();
        if let Some((_, v)) = self.indices.iter().rev().find(|(n, _)| *n == s) {
            return Some(*v);
        }
        match self.env.get(&s).copied() {
            Some((Binding::Const(v), _)) => Some(v),
            Some((b, _)) => {
                self.cx.error_spanned_by(
                    ident,
                    format!(
                        "`{s}` is {}, not a constant: lengths, ranges and indices must be known when the model is compiled, so they may use only {INDEX_EXPRESSIONS}",
                        b.describe()
                    ),
                );
                None
            }
            None => {
                let mut scope: Vec<&str> = self.indices.iter().map(|(n, _)| n.as_str()).collect();
                scope.dedup();
                let in_scope = if scope.is_empty() {
                    "no index variable is in scope here".to_string()
                } else {
                    format!("in scope: {}", scope.join(", "))
                };
                self.cx.error_spanned_by(
                    ident,
                    format!(
                        "unknown index variable `{s}` ({in_scope}); an index may use {INDEX_EXPRESSIONS}"
                    ),
                );
                None
            }
        }
    }

    fn checked(&mut self, v: Option<i64>, e: ExprRef<'_>) -> Option<i64> {
        if v.is_none() {
            self.cx.error_spanned_by(
                e,
                format!("the index expression `{}` overflows", expr_text(e)),
            );
        }
        v
    }

    /// A range `a..b` or `a..=b` as half-open bounds.
    fn eval_range(&mut self, e: ExprRef<'_>) -> Option<(i64, i64)> {
        let r = e.strip_parentheses();
        let ExprKind::Range { start, end, closed } = r.kind() else {
            self.cx.error_spanned_by(
                e,
                format!(
                    "expected an index range such as `0..N` or `1..=3`, found `{}`",
                    expr_text(e)
                ),
            );
            return None;
        };
        let (Some(start), Some(end)) = (start, end) else {
            self.cx.error_spanned_by(
                r,
                format!(
                    "an index range needs both bounds, e.g. `0..N`, found `{}`",
                    expr_text(e)
                ),
            );
            return None;
        };
        let a = self.eval_int(r.at(*start));
        let b = self.eval_int(r.at(*end));
        let (a, b) = (a?, b?);
        if *closed {
            Some((a, self.checked(b.checked_add(1), e)?))
        } else {
            Some((a, b))
        }
    }

    /// The lengths of a declared family, each at least 1.
    fn eval_dims(&mut self, dims: &[Expr]) -> Option<Vec<usize>> {
        let mut out = Vec::new();
        let mut ok = true;
        for d in dims {
            match self.eval_int(d.root()) {
                Some(v) if v >= 1 => out.push(v as usize),
                Some(v) => {
                    self.cx.error_spanned_by(
                        d,
                        format!(
                            "the length of an indexed family must be at least 1, found `{}` = {v}",
                            expr_text(d.root())
                        ),
                    );
                    ok = false;
                }
                None => ok = false,
            }
        }
        let total = out.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d));
        if ok && total.is_none_or(|n| n > MAX_FAMILY_ELEMENTS) {
            self.cx.error_spanned_by(
                &dims[0],
                format!(
                    "an indexed family may have at most {MAX_FAMILY_ELEMENTS} elements, found lengths {}",
                    out.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(" x ")
                ),
            );
            ok = false;
        }
        ok.then_some(out)
    }

    /// The default of a scalar parameter (or one element), or 0 with the error recorded.
    fn param_default(&mut self, e: ExprRef<'_>, label: &str) -> f64 {
        match numeric_literal(e) {
            Some(v) if !v.is_finite() => {
                self.cx.error_spanned_by(
                    e,
                    format!(
                        "the default of parameter `{label}` is out of range for `f64`: `{}` overflows to infinity (the largest finite value is about 1.8e308)",
                        expr_text(e)
                    ),
                );
                0.0
            }
            Some(v) => v,
            None => {
                self.cx.error_spanned_by(
                    e,
                    format!(
                        "the default of parameter `{label}` must be a number such as `1.0` or `-9.81`, found `{}`",
                        expr_text(e)
                    ),
                );
                0.0
            }
        }
    }

    /// The defaults of a parameter family, row-major: one number for every element, or an
    /// array literal (nested per index) of exactly the family's lengths.
    fn param_defaults(&mut self, e: ExprRef<'_>, name: &Ident, dims: &[usize]) -> Vec<f64> {
        let total: usize = dims.iter().product();
        if numeric_literal(e).is_some() {
            let v = self.param_default(e, &name.unraw().to_string());
            return vec![v; total];
        }
        let mut out = Vec::with_capacity(total);
        self.collect_defaults(e, name, dims, &mut Vec::new(), &mut out);
        out.resize(total, 0.0);
        out
    }

    fn collect_defaults(
        &mut self,
        e: ExprRef<'_>,
        name: &Ident,
        dims: &[usize],
        prefix: &mut Vec<usize>,
        out: &mut Vec<f64>,
    ) {
        let Some((&len, rest)) = dims.split_first() else {
            let (label, _) = element_names(name, prefix);
            let v = self.param_default(e, &label);
            out.push(v);
            return;
        };
        let (label, _) = element_names(name, prefix);
        let array = e.strip_parentheses();
        let ExprKind::Array(items) = array.kind() else {
            self.cx.error_spanned_by(
                e,
                format!(
                    "the default of `{label}` must be an array of {len} value{} such as `[{}]`, or one number for every element, found `{}`",
                    plural(len),
                    vec!["1.0"; len.min(3)].join(", ") + if len > 3 { ", ..." } else { "" },
                    expr_text(e)
                ),
            );
            out.extend(std::iter::repeat_n(
                0.0,
                rest.iter().product::<usize>() * len,
            ));
            return;
        };
        if items.len() != len {
            self.cx.error_spanned_by(
                array,
                format!(
                    "length mismatch: `{label}` has length {len} as declared, but its default lists {} value{}",
                    items.len(),
                    plural(items.len())
                ),
            );
            out.extend(std::iter::repeat_n(
                0.0,
                rest.iter().product::<usize>() * len,
            ));
            return;
        }
        for (k, x) in items.iter().enumerate() {
            prefix.push(k);
            self.collect_defaults(array.at(*x), name, rest, prefix, out);
            prefix.pop();
        }
    }

    /// Records that the generated code binds `code` for the name `label`; a clash between
    /// a family's element (`q_2` for `q[2]`) and another declared name is an error on the
    /// later one.
    fn claim_code_name(&mut self, code: &Ident, label: &str, family: Option<&Ident>) {
        let key = code.unraw().to_string();
        match self.code_names.get(&key) {
            Some(prev) if prev != label => {
                let (at, msg): (&dyn ToTokens, String) = match family {
                    Some(f) => (
                        f,
                        format!(
                            "element `{label}` of the family `{f}` is named `{key}` in the generated code, which is already the name of `{prev}`; rename one of them"
                        ),
                    ),
                    None => (
                        code,
                        format!(
                            "`{key}` is the name the generated code gives to element `{prev}`; choose another name"
                        ),
                    ),
                };
                self.cx.error_spanned_by(at, msg);
            }
            _ => {
                self.code_names.insert(key, label.to_string());
            }
        }
    }

    /// Declares `name` as a family of `kind`s (the variant only says which).
    fn declare_family(
        &mut self,
        name: &Ident,
        kind: Binding,
        dims: Vec<usize>,
        elements: Vec<Option<Binding>>,
    ) -> usize {
        let f = self.families.len();
        self.families.push(Family {
            plural: kind.plural(),
            dims,
            poisoned: elements.is_empty(),
            elements,
            defined: None,
            failed: HashSet::new(),
        });
        if name.unraw().to_string().ends_with('_') {
            self.cx.error_spanned_by(
                name,
                format!("the name of an indexed family may not end in `_`: its elements are named `{name}_0`, ... in the generated code, and `__` is reserved for it"),
            );
        }
        self.declare_as(name, Binding::Family(f), kind.describe());
        f
    }

    /// States, algebraic unknowns or inputs, scalars and families.
    fn declare_decls(
        &mut self,
        list: &[crate::parse::NameDef],
        out: &mut Vec<Decl>,
        binding: fn(usize) -> Binding,
    ) {
        for n in list {
            let what = binding(0).describe();
            let docs = self.doc_attrs(&n.attrs, what);
            if n.dims.is_empty() {
                self.declare(&n.name, binding(out.len()));
                self.claim_code_name(&n.name, &n.name.unraw().to_string(), None);
                out.push(Decl {
                    name: n.name.clone(),
                    label: n.name.unraw().to_string(),
                    unit: unit_text(n.unit.as_ref()),
                    docs,
                });
                continue;
            }
            let Some(dims) = self.eval_dims(&n.dims) else {
                self.declare_family(&n.name, binding(0), Vec::new(), Vec::new());
                continue;
            };
            let elements = multi_indices(&dims)
                .into_iter()
                .map(|ix| {
                    let (label, name) = element_names(&n.name, &ix);
                    self.claim_code_name(&name, &label, Some(&n.name));
                    out.push(Decl {
                        name,
                        label,
                        unit: unit_text(n.unit.as_ref()),
                        docs: docs.clone(),
                    });
                    Some(binding(out.len() - 1))
                })
                .collect();
            self.declare_family(&n.name, binding(0), dims, elements);
        }
    }

    /// Binds an index variable for the duration of a loop; `false` (with the error
    /// recorded) if its name is taken.
    fn check_index_var(&mut self, var: &Ident) -> bool {
        let s = var.unraw().to_string();
        let taken = if s == "t" {
            Some("`t` is time".to_string())
        } else if let Some((b, _)) = self.env.get(&s) {
            Some(format!("`{s}` is already declared as {}", b.describe()))
        } else if CONSTANTS.iter().any(|(c, _)| *c == s) {
            Some(format!("`{s}` is a named constant"))
        } else if self.indices.iter().any(|(n, _)| *n == s) {
            Some(format!(
                "`{s}` is already the index variable of an enclosing loop, sum or family"
            ))
        } else {
            None
        };
        match taken {
            Some(why) => {
                self.cx.error_spanned_by(
                    var,
                    format!("{why}; choose another name for the index variable"),
                );
                false
            }
            None => true,
        }
    }

    /// The text of `e` with the index variables in scope written as their values.
    fn indexed_text(&self, e: ExprRef<'_>) -> String {
        let scope = &self.indices;
        let env = &self.env;
        crate::text::expr_text_with(
            e,
            &|s| scope.iter().rev().find(|(n, _)| n == s).map(|(_, v)| *v),
            &|s| match env.get(s) {
                Some((Binding::Const(v), _)) => Some(*v),
                _ => None,
            },
        )
    }

    /// `let name[i in a..b]... = expr;`: one intermediate per index, in row-major order; an
    /// element may use the family's earlier elements. Returns the label for the listing.
    fn lower_let_family(&mut self, l: &crate::parse::LetDef) -> String {
        let label = format!("{}{}", l.name, subscripts_text(&l.subscripts));
        let mut vars = Vec::new();
        let mut ranges = Vec::new();
        let mut ok = true;
        for sub in &l.subscripts {
            match sub {
                Subscript::Binder { var, range } => match self.eval_range(range.root()) {
                    Some((a, _)) if a < 0 => {
                        self.cx.error_spanned_by(
                            range,
                            format!(
                                "the indices of `{}` start at 0; the range `{}` starts at {a}",
                                l.name,
                                expr_text(range.root())
                            ),
                        );
                        ok = false;
                    }
                    Some(r) => {
                        vars.push(var);
                        ranges.push(r);
                    }
                    None => ok = false,
                },
                Subscript::Index(e) => {
                    self.cx.error_spanned_by(
                        e,
                        format!(
                            "a `let` family names each index with its range, e.g. `let {}[i in 0..N] = ...`, found `[{}]`",
                            l.name,
                            expr_text(e.root())
                        ),
                    );
                    ok = false;
                }
            }
        }
        for var in &vars {
            ok &= self.check_index_var(var);
        }
        if vars.len() > 1 {
            for (k, v) in vars.iter().enumerate() {
                if vars[..k].iter().any(|w| w.unraw() == v.unraw()) {
                    self.cx
                        .error_spanned_by(v, format!("index variable `{v}` appears twice"));
                    ok = false;
                }
            }
        }
        let zero = self.graph.constant(0.0);
        let kind = Binding::Let {
            expr: zero,
            uses_der: false,
        };
        if !ok {
            self.declare_family(&l.name, kind, Vec::new(), Vec::new());
            return label;
        }
        if ranges.iter().any(|&(a, b)| b <= a) {
            self.cx.error_spanned_by(
                &l.name,
                format!("the `let` family `{label}` defines no element: a range is empty"),
            );
            self.declare_family(&l.name, kind, Vec::new(), Vec::new());
            return label;
        }
        let dims: Vec<usize> = ranges.iter().map(|&(_, b)| b as usize).collect();
        let total = dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d));
        if total.is_none_or(|n| n > MAX_FAMILY_ELEMENTS) {
            self.cx.error_spanned_by(
                &l.name,
                format!("an indexed family may have at most {MAX_FAMILY_ELEMENTS} elements"),
            );
            self.declare_family(&l.name, kind, Vec::new(), Vec::new());
            return label;
        }
        let f = self.declare_family(&l.name, kind, dims.clone(), vec![None; total.unwrap_or(0)]);
        self.families[f].defined = Some(subscripts_text(&l.subscripts));
        for values in range_product(&ranges) {
            let depth = self.indices.len();
            self.indices.extend(
                vars.iter()
                    .zip(&values)
                    .map(|(v, k)| (v.unraw().to_string(), *k)),
            );
            let expr = self.lower_expr(l.expr.root(), Place::Let);
            self.indices.truncate(depth);
            let offset = values
                .iter()
                .zip(&dims)
                .fold(0usize, |acc, (&k, &d)| acc * d + k as usize);
            match expr {
                Some(expr) => {
                    let uses_der = self.uses_derivatives(expr);
                    self.families[f].elements[offset] = Some(Binding::Let { expr, uses_der });
                }
                None => {
                    self.families[f].failed.insert(offset);
                }
            }
        }
        label
    }

    /// The equations of `items`, `for` loops unrolled, in order.
    fn lower_equation_items(
        &mut self,
        items: &[EquationItem],
        states: &[Decl],
        explicit_seen: &mut HashMap<usize, Span>,
        out: &mut Vec<Equation>,
    ) {
        for item in items {
            match item {
                EquationItem::Equation(e) => {
                    let Some(eq) = self.lower_equation(e.root()) else {
                        continue;
                    };
                    if let Some((j, _)) = eq.explicit {
                        if let Some(prev) = explicit_seen.insert(j, eq.span) {
                            let mut err = syn::Error::new(
                                eq.span,
                                format!(
                                    "state `{}` has a second explicit equation `der({0}) = ...`; write at most one per state (make the other implicit with `==`)",
                                    states[j].label
                                ),
                            );
                            err.combine(syn::Error::new(prev, "first explicit equation here"));
                            self.cx.push(err);
                        }
                    }
                    out.push(eq);
                }
                EquationItem::For(f) => {
                    let range = self.eval_range(f.range.root());
                    if !self.check_index_var(&f.var) {
                        continue;
                    }
                    let Some((a, b)) = range else {
                        continue;
                    };
                    for k in a..b {
                        self.indices.push((f.var.unraw().to_string(), k));
                        self.lower_equation_items(&f.body, states, explicit_seen, out);
                        self.indices.pop();
                    }
                }
            }
        }
    }

    /// Every combination of a target's subscripts: per combination, the bound index
    /// variables and the indices.
    fn subscript_combinations(
        &mut self,
        subscripts: &[Subscript],
    ) -> Option<Vec<(Bound, Vec<i64>)>> {
        let mut ranges = Vec::new();
        let mut vars: Vec<Option<String>> = Vec::new();
        let mut ok = true;
        for sub in subscripts {
            match sub {
                Subscript::Binder { var, range } => {
                    let r = self.eval_range(range.root());
                    ok &= self.check_index_var(var);
                    match r {
                        Some(r) => ranges.push(r),
                        None => ok = false,
                    }
                    vars.push(Some(var.unraw().to_string()));
                }
                Subscript::Index(e) => {
                    match self.eval_int(e.root()) {
                        Some(v) => ranges.push((v, v + 1)),
                        None => ok = false,
                    }
                    vars.push(None);
                }
            }
        }
        if !ok {
            return None;
        }
        Some(
            range_product(&ranges)
                .into_iter()
                .map(|values| {
                    let bound = vars
                        .iter()
                        .zip(&values)
                        .filter_map(|(v, k)| v.clone().map(|v| (v, *k)))
                        .collect();
                    (bound, values)
                })
                .collect(),
        )
    }

    /// The outputs an entry of `references` or `tracking` names: `y` (the output `y`, or
    /// every element of the output family `y`), `y[2]`, or `y[i in 0..N]`; per output the
    /// index variables bound for it.
    fn target_outputs(
        &mut self,
        name: &Ident,
        subscripts: &[Subscript],
        outputs: &[Output],
        hint: &str,
    ) -> Option<Vec<(usize, Bound)>> {
        let base = name.unraw().to_string();
        if subscripts.is_empty() {
            if let Some(i) = outputs.iter().position(|o| o.label == base) {
                return Some(vec![(i, Vec::new())]);
            }
            let prefix = format!("{base}[");
            let all: Vec<(usize, Vec<(String, i64)>)> = outputs
                .iter()
                .enumerate()
                .filter(|(_, o)| o.label.starts_with(&prefix))
                .map(|(i, _)| (i, Vec::new()))
                .collect();
            if all.is_empty() {
                self.cx
                    .error_spanned_by(name, format!("`{name}` is not an output; {hint}"));
                return None;
            }
            return Some(all);
        }
        let mut out = Vec::new();
        for (bound, values) in self.subscript_combinations(subscripts)? {
            let label = format!(
                "{base}{}",
                values.iter().map(|k| format!("[{k}]")).collect::<String>()
            );
            match outputs.iter().position(|o| o.label == label) {
                Some(i) => out.push((i, bound)),
                None => {
                    self.cx
                        .error_spanned_by(name, format!("`{label}` is not an output; {hint}"));
                    return None;
                }
            }
        }
        Some(out)
    }

    /// The unit of the bare output `o` for the variable `variable` (its label): the
    /// variable's, or the one written on the output if the variable has none; a different
    /// unit on both is an error on the output's unit.
    fn bare_output_unit(
        &mut self,
        o: &crate::parse::OutputDef,
        variable: &str,
        decls: [&[Decl]; 3],
        params: &[Param],
    ) -> Option<String> {
        let declared = decls
            .iter()
            .flat_map(|d| d.iter())
            .find(|d| d.label == variable)
            .map(|d| d.unit.clone())
            .or_else(|| {
                params
                    .iter()
                    .find(|p| p.label == variable)
                    .map(|p| p.unit.clone())
            })
            .flatten();
        let written = unit_text(o.unit.as_ref());
        match (declared, written) {
            (Some(d), Some(w)) if d != w => {
                if let Some(lit) = &o.unit {
                    self.cx.error_spanned_by(
                        lit,
                        format!(
                            "output `{variable}` is the variable `{variable}`, declared in `{d}`, but is given the unit `{w}`; leave the unit out here"
                        ),
                    );
                }
                Some(d)
            }
            (d, w) => d.or(w),
        }
    }

    /// One output, or one per element of an output family: `(label, code name, expression,
    /// text)`.
    fn lower_output(
        &mut self,
        o: &crate::parse::OutputDef,
    ) -> Vec<(String, Ident, ExprId, String)> {
        let mut out = Vec::new();
        let base = o.name.unraw().to_string();
        if o.subscripts.is_empty() {
            if let (None, Some((Binding::Family(f), _))) = (&o.expr, self.env.get(&base).copied()) {
                // A bare family name: one output per element.
                let dims = self.families[f].dims.clone();
                for ix in multi_indices(&dims) {
                    let (label, name) = element_names(&o.name, &ix);
                    let values: Vec<i64> = ix.iter().map(|&k| k as i64).collect();
                    let Some((binding, _)) = self.family_element(&o.name, &values, &[], &o.name)
                    else {
                        continue;
                    };
                    if let Some(e) = self.lower_binding(binding, &o.name, &label, Place::Output) {
                        out.push((label.clone(), name, e, label));
                    }
                }
                return out;
            }
            let lowered = match &o.expr {
                Some(e) => self
                    .lower_expr(e.root(), Place::Output)
                    .map(|x| (x, expr_text(e.root()))),
                None => match self.env.get(&base) {
                    Some(_) => self
                        .lower_name(&o.name, Place::Output)
                        .map(|x| (x, base.clone())),
                    None => {
                        self.cx.error_spanned_by(
                            &o.name,
                            format!(
                                "output `{}` is not a declared name; write `{0} = <expression>` to define it",
                                o.name
                            ),
                        );
                        None
                    }
                },
            };
            if let Some((expr, text)) = lowered {
                out.push((base, o.name.clone(), expr, text));
            }
            return out;
        }
        let Some(combinations) = self.subscript_combinations(&o.subscripts) else {
            return out;
        };
        for (bound, values) in combinations {
            if values.iter().any(|&k| k < 0) {
                self.cx.error_spanned_by(
                    &o.name,
                    format!("the indices of the output family `{}` start at 0", o.name),
                );
                return out;
            }
            let ix: Vec<usize> = values.iter().map(|&k| k as usize).collect();
            let (label, name) = element_names(&o.name, &ix);
            let depth = self.indices.len();
            self.indices.extend(bound);
            let lowered = match &o.expr {
                Some(e) => {
                    let text = self.indexed_text(e.root());
                    self.lower_expr(e.root(), Place::Output).map(|x| (x, text))
                }
                None => self
                    .family_element(&o.name, &values, &[], &o.name)
                    .and_then(|(b, l)| {
                        self.lower_binding(b, &o.name, &l, Place::Output)
                            .map(|x| (x, l))
                    }),
            };
            self.indices.truncate(depth);
            if let Some((expr, text)) = lowered {
                out.push((label, name, expr, text));
            }
        }
        out
    }

    /// The element of the family `base` at `values`, validated (number of indices, range,
    /// defined), with its label; errors on `subscripts[k]` for index `k` (if given) or on
    /// `whole`.
    fn family_element(
        &mut self,
        base: &Ident,
        values: &[i64],
        subscripts: &[ExprRef<'_>],
        whole: &dyn ToTokens,
    ) -> Option<(Binding, String)> {
        let s = base.unraw().to_string();
        let f = match self.env.get(&s).copied() {
            Some((Binding::Family(f), _)) => f,
            Some((b, _)) => {
                self.cx.error_spanned_by(
                    whole,
                    format!(
                        "`{s}` is {}, not an indexed family, and takes no `[...]`",
                        b.describe()
                    ),
                );
                return None;
            }
            None => {
                let msg = self.unknown_name_message(&s);
                self.cx.error_spanned_by(base, msg);
                return None;
            }
        };
        let fam = &self.families[f];
        if fam.poisoned {
            return None;
        }
        let family_text = format!(
            "`{s}`, a family of {} {} (`{s}{}`)",
            fam.elements.len(),
            fam.plural,
            fam.dims
                .iter()
                .map(|d| format!("[{d}]"))
                .collect::<String>()
        );
        if values.len() != fam.dims.len() {
            let msg = format!(
                "{family_text}, takes {} ind{}, found {}",
                fam.dims.len(),
                if fam.dims.len() == 1 { "ex" } else { "ices" },
                values.len()
            );
            self.cx.error_spanned_by(whole, msg);
            return None;
        }
        let mut offset = 0usize;
        let mut ok = true;
        let mut errors = Vec::new();
        for (k, (&v, &d)) in values.iter().zip(&fam.dims).enumerate() {
            if v < 0 || v as usize >= d {
                let context = subscripts
                    .get(k)
                    .map(|e| self.index_context(*e))
                    .unwrap_or_default();
                let which = match (fam.dims.len(), k) {
                    (1, _) => String::new(),
                    (_, 0) => "first ".into(),
                    (_, 1) => "second ".into(),
                    (_, 2) => "third ".into(),
                    (_, k) => format!("{}th ", k + 1),
                };
                errors.push((
                    k,
                    format!(
                        "index {v} is out of range for {family_text}: the {which}index must be in 0..{d}{context}"
                    ),
                ));
                ok = false;
            } else {
                offset = offset * d + v as usize;
            }
        }
        for (k, msg) in errors {
            match subscripts.get(k) {
                Some(e) => self.cx.error_spanned_by(e, msg),
                None => self.cx.error_spanned_by(whole, msg),
            }
        }
        if !ok {
            return None;
        }
        let fam = &self.families[f];
        let label = format!(
            "{s}{}",
            values.iter().map(|k| format!("[{k}]")).collect::<String>()
        );
        match fam.elements[offset] {
            Some(b) => Some((b, label)),
            None if fam.failed.contains(&offset) => None,
            None => {
                let defined = fam.defined.clone().unwrap_or_default();
                self.cx.error_spanned_by(
                    whole,
                    format!(
                        "`{label}` is not defined: the `let` family defines `{s}{defined}`, and an element may use only earlier elements of its own family"
                    ),
                );
                None
            }
        }
    }

    /// ` (with i = 2)`: the index variables an index expression uses, with their values.
    fn index_context(&self, e: ExprRef<'_>) -> String {
        let text = expr_text(e);
        let used: Vec<String> = self
            .indices
            .iter()
            .filter(|(n, _)| {
                text.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .any(|w| w == n)
            })
            .map(|(n, v)| format!("{n} = {v}"))
            .collect();
        if used.is_empty() {
            String::new()
        } else {
            format!(" (here with {})", used.join(", "))
        }
    }

    /// `q[i][j + 1]`: the element it names, with its label, or `None` with errors recorded.
    fn resolve_element(&mut self, e: ExprRef<'_>) -> Option<(Binding, String)> {
        let mut subscripts: Vec<ExprRef<'_>> = Vec::new();
        let mut cur = e;
        while let ExprKind::Index { base, index } = cur.strip_parentheses().kind() {
            let ix = cur.strip_parentheses();
            subscripts.push(ix.at(*index));
            cur = ix.at(*base);
        }
        subscripts.reverse();
        let Some(base) = cur.path_ident() else {
            self.cx.error_spanned_by(
                cur,
                format!(
                    "only declared families can be indexed, found `{}`",
                    expr_text(cur)
                ),
            );
            return None;
        };
        let values: Vec<Option<i64>> = subscripts.iter().map(|s| self.eval_int(*s)).collect();
        let values: Vec<i64> = values.into_iter().collect::<Option<_>>()?;
        self.family_element(base, &values, &subscripts, &e)
    }

    /// `sum(a..b, |j| expr)`: the sum of `expr` over `j`, unrolled (0 for an empty range).
    /// Pushes the total so far and, per index, the tasks that lower the term and add it.
    fn lower_sum<'a>(
        &mut self,
        c: ExprRef<'a>,
        tasks: &mut Vec<Task<'a>>,
        values: &mut Vec<Option<ExprId>>,
    ) {
        let ExprKind::Call { args, .. } = c.kind() else {
            values.push(None);
            return;
        };
        let usage = "write sums as `sum(0..N, |j| expr)`";
        if args.len() != 2 {
            self.cx.error_spanned_by(
                c,
                format!(
                    "`sum` takes a range and a closure, found {} argument{}; {usage}",
                    args.len(),
                    plural(args.len())
                ),
            );
            values.push(None);
            return;
        }
        let range = self.eval_range(c.at(args[0]));
        let second = c.at(args[1]);
        let closure = second.strip_parentheses();
        let ExprKind::Closure {
            params,
            params_spans,
            body,
        } = closure.kind()
        else {
            self.cx.error_spanned_by(
                second,
                format!("the second argument of `sum` is a closure naming the index, found `{}`; {usage}", expr_text(second)),
            );
            values.push(None);
            return;
        };
        let var = match params.as_slice() {
            [ClosureParam {
                ident: Some(var), ..
            }] => var,
            _ => {
                self.cx.error_spanned_by(
                    params_spans,
                    format!("the closure of `sum` takes exactly one index variable, e.g. `|j|`; {usage}"),
                );
                values.push(None);
                return;
            }
        };
        if !self.check_index_var(var) {
            values.push(None);
            return;
        }
        let Some((a, b)) = range else {
            values.push(None);
            return;
        };
        let total = self.graph.constant(0.0);
        values.push(Some(total));
        let name = var.unraw().to_string();
        for k in (a..b).rev() {
            tasks.push(Task::AddTerm);
            tasks.push(Task::Unbind);
            tasks.push(Task::Lower(closure.at(*body)));
            tasks.push(Task::Bind(name.clone(), k));
        }
    }
}

/// Index variables bound to values, for one element of a target.
type Bound = Vec<(String, i64)>;

/// The largest number of elements of one indexed family.
const MAX_FAMILY_ELEMENTS: usize = 1 << 16;
