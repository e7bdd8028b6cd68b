//! Lowering: from the parsed syntax to the checked model IR.
//!
//! Resolves every name, lowers expressions into the symbolic graph, and runs the structural
//! checks of a well-formed plant (section order, duplicates, counts, `der()` usage, states
//! that are never differentiated). All errors are collected in the [`Ctxt`] and reported
//! together, each spanning the offending tokens and saying what was expected.

use crate::ctxt::Ctxt;
use crate::ir::{
    Decl, Equation, Intermediate, Model, Output, Param, Reference, Symbol, Symbols, Tracking,
    TrackingEntry,
};
use crate::parse::{Item, ModelDef, SectionBody, SECTION_ORDER};
use crate::symbolic::{ExprId, Func, Graph};
use crate::text::expr_text;
use proc_macro2::Span;
use quote::ToTokens;
use std::collections::{HashMap, HashSet};
use syn::ext::IdentExt;
use syn::spanned::Spanned;
use syn::{Attribute, BinOp, Expr, Ident, Lit, UnOp};

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
const BINARY_FUNCTIONS: &[&str] = &["atan2", "hypot", "powi", "powf"];

/// Functions of one argument.
const UNARY_FUNCTIONS: &[&str] = &[
    "sqrt", "exp", "ln", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "abs",
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
    Let { expr: ExprId, uses_der: bool },
}

impl Binding {
    fn describe(self) -> &'static str {
        match self {
            Binding::Param(_) => "a parameter",
            Binding::State(_) => "a state",
            Binding::Algebraic(_) => "an algebraic unknown",
            Binding::Input(_) => "an input",
            Binding::Let { .. } => "a `let` intermediate",
        }
    }
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
}

/// Lower a parsed model, recording every problem in `cx`. Returns `None` if there were
/// errors that make the IR meaningless.
pub fn lower(def: ModelDef, cx: &mut Ctxt) -> Option<Model> {
    let mut lw = Lowerer {
        cx,
        graph: Graph::new(),
        symbols: Symbols::default(),
        env: HashMap::new(),
        pending_lets: HashSet::new(),
    };
    let attrs = lw.doc_attrs(&def.attrs, "the model");
    check_section_order(&def, lw.cx);

    let mut params = Vec::new();
    let mut states = Vec::new();
    let mut algebraic = Vec::new();
    let mut inputs = Vec::new();
    let mut intermediates = Vec::new();
    let mut equations = Vec::new();
    let mut outputs: Vec<Output> = Vec::new();
    let mut references = Vec::new();
    let mut tracking = None;
    let mut equations_keyword: Option<Ident> = None;

    for item in &def.items {
        if let Item::Let(l) = item {
            lw.pending_lets.insert(l.name.to_string());
        }
    }

    for item in &def.items {
        match item {
            Item::Let(l) => {
                lw.pending_lets.remove(&l.name.to_string());
                let text = expr_text(&l.expr);
                if let Some(expr) = lw.lower_expr(&l.expr, Place::Let) {
                    let uses_der = lw.uses_derivatives(expr);
                    lw.declare(&l.name, Binding::Let { expr, uses_der });
                }
                intermediates.push(Intermediate {
                    name: l.name.clone(),
                    text,
                });
            }
            Item::Section(section) => {
                let empty = match &section.body {
                    SectionBody::Params(v) => v.is_empty(),
                    SectionBody::States(v) | SectionBody::Algebraic(v) | SectionBody::Inputs(v) => {
                        v.is_empty()
                    }
                    SectionBody::Equations(v) => v.is_empty(),
                    SectionBody::Outputs(v) => v.is_empty(),
                    SectionBody::References(v) => v.is_empty(),
                    SectionBody::Tracking(t) => t.entries.is_empty(),
                };
                if empty {
                    lw.cx.error_at(
                        section.brace_span,
                        format!(
                            "empty section `{}`: declare at least one entry or remove the section",
                            section.keyword
                        ),
                    );
                }
                match &section.body {
                    SectionBody::Params(list) => {
                        for p in list {
                            let docs = lw.doc_attrs(&p.attrs, "a parameter");
                            let default = match numeric_literal(&p.default) {
                                Some(v) if !v.is_finite() => {
                                    lw.cx.error_spanned_by(
                                        &p.default,
                                        format!(
                                            "the default of parameter `{}` is out of range for `f64`: `{}` overflows to infinity (the largest finite value is about 1.8e308)",
                                            p.name,
                                            expr_text(&p.default)
                                        ),
                                    );
                                    Some(0.0)
                                }
                                other => other,
                            };
                            let default = default.unwrap_or_else(|| {
                                lw.cx.error_spanned_by(
                                    &p.default,
                                    format!(
                                        "the default of parameter `{}` must be a number such as `1.0` or `-9.81`, found `{}`",
                                        p.name,
                                        expr_text(&p.default)
                                    ),
                                );
                                0.0
                            });
                            lw.declare(&p.name, Binding::Param(params.len()));
                            params.push(Param {
                                name: p.name.clone(),
                                default,
                                docs,
                            });
                        }
                    }
                    SectionBody::States(list) => {
                        for n in list {
                            lw.declare(&n.name, Binding::State(states.len()));
                            states.push(Decl {
                                name: n.name.clone(),
                                docs: lw.doc_attrs(&n.attrs, "a state"),
                            });
                        }
                    }
                    SectionBody::Algebraic(list) => {
                        for n in list {
                            lw.declare(&n.name, Binding::Algebraic(algebraic.len()));
                            algebraic.push(Decl {
                                name: n.name.clone(),
                                docs: lw.doc_attrs(&n.attrs, "an algebraic unknown"),
                            });
                        }
                    }
                    SectionBody::Inputs(list) => {
                        for n in list {
                            lw.declare(&n.name, Binding::Input(inputs.len()));
                            inputs.push(Decl {
                                name: n.name.clone(),
                                docs: lw.doc_attrs(&n.attrs, "an input"),
                            });
                        }
                    }
                    SectionBody::Equations(list) => {
                        equations_keyword = Some(section.keyword.clone());
                        let mut explicit_seen: HashMap<usize, Span> = HashMap::new();
                        for e in list {
                            if let Some(eq) = lw.lower_equation(e) {
                                if let Some((j, _)) = eq.explicit {
                                    if let Some(prev) = explicit_seen.insert(j, eq.span) {
                                        let mut err = syn::Error::new(
                                            eq.span,
                                            format!(
                                                "state `{}` has a second explicit equation `der({0}) = ...`; write at most one per state (make the other implicit with `==`)",
                                                states[j].name
                                            ),
                                        );
                                        err.combine(syn::Error::new(
                                            prev,
                                            "first explicit equation here",
                                        ));
                                        lw.cx.push(err);
                                    }
                                }
                                equations.push(eq);
                            }
                        }
                    }
                    SectionBody::Outputs(list) => {
                        for o in list {
                            if outputs.iter().any(|p| p.name == o.name) {
                                lw.cx.error_spanned_by(
                                    &o.name,
                                    format!("duplicate output `{}`", o.name),
                                );
                                continue;
                            }
                            if let Some(msg) = crate::names::check(&o.name, "an output") {
                                lw.cx.error_spanned_by(&o.name, msg);
                                continue;
                            }
                            let docs = lw.doc_attrs(&o.attrs, "an output");
                            let lowered = match &o.expr {
                                Some(e) => {
                                    lw.lower_expr(e, Place::Output).map(|x| (x, expr_text(e)))
                                }
                                None => {
                                    let name = &o.name;
                                    let path: Expr = syn::parse_quote_spanned!(name.span()=> #name);
                                    match lw.env.get(&o.name.to_string()) {
                                        Some(_) => lw
                                            .lower_expr(&path, Place::Output)
                                            .map(|x| (x, o.name.to_string())),
                                        None => {
                                            lw.cx.error_spanned_by(
                                                &o.name,
                                                format!(
                                                    "output `{}` is not a declared name; write `{0} = <expression>` to define it",
                                                    o.name
                                                ),
                                            );
                                            None
                                        }
                                    }
                                }
                            };
                            if let Some((expr, text)) = lowered {
                                outputs.push(Output {
                                    name: o.name.clone(),
                                    expr,
                                    text,
                                    docs,
                                });
                            }
                        }
                    }
                    SectionBody::References(list) => {
                        let mut seen = HashSet::new();
                        for r in list {
                            let Some(index) = outputs.iter().position(|o| o.name == r.output)
                            else {
                                lw.cx.error_spanned_by(
                                    &r.output,
                                    format!(
                                        "`{}` is not an output; references are given per output",
                                        r.output
                                    ),
                                );
                                continue;
                            };
                            if !seen.insert(index) {
                                lw.cx.error_spanned_by(
                                    &r.output,
                                    format!("duplicate reference for output `{}`", r.output),
                                );
                                continue;
                            }
                            if let Some(expr) = lw.lower_expr(&r.expr, Place::Reference) {
                                references.push(Reference {
                                    output: index,
                                    expr,
                                    text: expr_text(&r.expr),
                                });
                            }
                        }
                        let missing: Vec<String> = outputs
                            .iter()
                            .enumerate()
                            .filter(|(i, _)| !seen.contains(i))
                            .map(|(_, o)| format!("`{}`", o.name))
                            .collect();
                        if !missing.is_empty() && !list.is_empty() {
                            lw.cx.error_spanned_by(
                                &section.keyword,
                                format!(
                                    "`references` must give every output a reference; missing: {}",
                                    missing.join(", ")
                                ),
                            );
                        }
                    }
                    SectionBody::Tracking(t) => {
                        let mut entries: Vec<TrackingEntry> = Vec::new();
                        for entry in &t.entries {
                            let Some(index) = outputs.iter().position(|o| o.name == entry.output)
                            else {
                                lw.cx.error_spanned_by(
                                    &entry.output,
                                    format!(
                                        "`{}` is not an output; `tracking` names outputs declared in `outputs`",
                                        entry.output
                                    ),
                                );
                                continue;
                            };
                            if entries.iter().any(|e| e.output == index) {
                                lw.cx.error_spanned_by(
                                    &entry.output,
                                    format!(
                                        "duplicate tracking entry for output `{}`",
                                        entry.output
                                    ),
                                );
                                continue;
                            }
                            let mut roots = Vec::new();
                            for r in &entry.roots {
                                match numeric_literal(r) {
                                    Some(a) if !a.is_finite() => lw.cx.error_spanned_by(
                                        r,
                                        format!(
                                            "`{}` is out of range for `f64` (it overflows to infinity); a negated root of W(s) must be a finite number",
                                            expr_text(r)
                                        ),
                                    ),
                                    Some(a) if a >= 0.0 => roots.push(a),
                                    Some(a) => lw.cx.error_spanned_by(
                                        r,
                                        format!(
                                            "`{a}` would put a root of W(s) at s = {}, which is unstable; entries are the negated roots and must be >= 0 (e.g. `5.0` for `s + 5`, `0.0` for plain differentiation)",
                                            -a
                                        ),
                                    ),
                                    None => lw.cx.error_spanned_by(
                                        r,
                                        format!(
                                            "expected a number (a negated root of W(s), e.g. `5.0` for `s + 5`), found `{}`",
                                            expr_text(r)
                                        ),
                                    ),
                                }
                            }
                            let coefficients =
                                crate::hirschorn::polynomial_from_negated_roots(&roots);
                            if coefficients.iter().any(|c| !c.is_finite()) {
                                lw.cx.error_at(
                                    entry.bracket_span,
                                    format!(
                                        "the coefficients of W(s) = {} overflow `f64`; use smaller roots",
                                        crate::hirschorn::polynomial_text(&roots)
                                    ),
                                );
                            }
                            let span = entry
                                .output
                                .span()
                                .join(entry.bracket_span)
                                .unwrap_or_else(|| entry.output.span());
                            entries.push(TrackingEntry {
                                output: index,
                                roots,
                                span,
                            });
                        }
                        entries.sort_by_key(|e| e.output);
                        tracking = Some(Tracking {
                            type_name: t.type_name.clone(),
                            entries,
                            span: section.keyword.span(),
                        });
                    }
                }
            }
        }
    }

    check_generated_names(&def, &tracking, !references.is_empty(), lw.cx);

    // Required sections.
    if states.is_empty() && !def.items.iter().any(|i| is_section(i, "states")) {
        lw.cx.error_spanned_by(
            &def.name,
            format!("model `{}` has no `states` section; declare its differential unknowns, e.g. `states {{ x, v }}`", def.name),
        );
    }
    let Some(equations_keyword) = equations_keyword else {
        lw.cx.error_spanned_by(
            &def.name,
            format!(
                "model `{}` has no `equations` section; add `equations {{ der(x) = ...; }}`",
                def.name
            ),
        );
        return None;
    };

    // Count: as many equations as unknowns.
    let unknowns = states.len() + algebraic.len();
    if !equations.is_empty() && !lw.cx.has_errors() && equations.len() != unknowns {
        lw.cx.error_spanned_by(
            &equations_keyword,
            format!(
                "found {} equation{} for {} unknown{} ({} state{} + {} algebraic); the number of equations must equal the number of unknowns",
                equations.len(),
                plural(equations.len()),
                unknowns,
                plural(unknowns),
                states.len(),
                plural(states.len()),
                algebraic.len()
            ),
        );
    }

    // Every state differentiated, every algebraic unknown used.
    if !lw.cx.has_errors() {
        let mut used = HashSet::new();
        for eq in &equations {
            for v in lw.graph.vars(eq.residual) {
                used.insert(lw.symbols.symbol(v));
            }
        }
        for (i, s) in states.iter().enumerate() {
            if !used.contains(&Symbol::StateDot(i)) {
                lw.cx.error_spanned_by(
                    &s.name,
                    format!(
                        "state `{}` is never differentiated: no equation contains `der({0})`; add its equation or declare it in `algebraic`",
                        s.name
                    ),
                );
            }
        }
        for (i, a) in algebraic.iter().enumerate() {
            if !used.contains(&Symbol::Algebraic(i)) {
                lw.cx.error_spanned_by(
                    &a.name,
                    format!("algebraic unknown `{}` appears in no equation, so the system cannot determine it", a.name),
                );
            }
        }
    }

    if lw.cx.has_errors() {
        return None;
    }
    Some(Model {
        attrs,
        vis: def.vis,
        name: def.name,
        params,
        states,
        algebraic,
        inputs,
        intermediates,
        equations,
        outputs,
        references,
        tracking,
        graph: lw.graph,
        symbols: lw.symbols,
    })
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

/// The value of a numeric literal, optionally negated (`1.0`, `2`, `-9.81`).
pub fn numeric_literal(e: &Expr) -> Option<f64> {
    match e {
        Expr::Lit(l) => match &l.lit {
            Lit::Float(f) if matches!(f.suffix(), "" | "f64") => f.base10_parse::<f64>().ok(),
            Lit::Int(i) if matches!(i.suffix(), "" | "f64") => i.base10_parse::<f64>().ok(),
            _ => None,
        },
        Expr::Unary(u) if matches!(u.op, UnOp::Neg(_)) => numeric_literal(&u.expr).map(|v| -v),
        Expr::Paren(p) => numeric_literal(&p.expr),
        Expr::Group(g) => numeric_literal(&g.expr),
        _ => None,
    }
}

/// The value of an integer literal, optionally negated, if it fits `i32`.
fn integer_literal(e: &Expr) -> Option<i32> {
    match e {
        Expr::Lit(l) => match &l.lit {
            Lit::Int(i) if matches!(i.suffix(), "" | "i32") => i.base10_parse::<i32>().ok(),
            _ => None,
        },
        Expr::Unary(u) if matches!(u.op, UnOp::Neg(_)) => integer_literal(&u.expr).map(|v| -v),
        Expr::Paren(p) => integer_literal(&p.expr),
        Expr::Group(g) => integer_literal(&g.expr),
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
        if let Some(msg) = crate::names::check(name, binding.describe()) {
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
                Symbol::StateDot(_) | Symbol::AlgebraicDot(_) | Symbol::InputDot(_)
            )
        })
    }

    fn symbol(&mut self, s: Symbol) -> ExprId {
        let v = self.symbols.var(s);
        self.graph.var(v)
    }

    fn lower_equation(&mut self, e: &Expr) -> Option<Equation> {
        let text = expr_text(e);
        let span = e.span();
        match e {
            Expr::Assign(a) => {
                let state = match &*a.left {
                    Expr::Call(c) if call_name(c).as_deref() == Some("der") => {
                        let d = self.lower_expr(&a.left, Place::Equation)?;
                        let c_arg = c.args.first()?;
                        let name = path_ident(c_arg)?;
                        match self.env.get(&name.to_string()) {
                            Some((Binding::State(j), _)) => {
                                let j = *j;
                                Some((j, d))
                            }
                            _ => None,
                        }
                    }
                    other => {
                        self.cx.error_spanned_by(
                            other,
                            format!(
                                "the left side of `=` must be `der(state)`, found `{}`; write implicit equations as `lhs == rhs`",
                                expr_text(other)
                            ),
                        );
                        None
                    }
                };
                let rhs = self.lower_expr(&a.right, Place::Equation);
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
            Expr::Binary(b) if matches!(b.op, BinOp::Eq(_)) => {
                let lhs = self.lower_expr(&b.left, Place::Equation);
                let rhs = self.lower_expr(&b.right, Place::Equation);
                let (lhs, rhs) = (lhs?, rhs?);
                let residual = self.graph.sub(lhs, rhs);
                Some(Equation {
                    residual,
                    text,
                    explicit: None,
                    span,
                })
            }
            other => {
                self.cx.error_spanned_by(
                    other,
                    format!(
                        "expected an equation, either explicit `der(x) = expr` or implicit `lhs == rhs`, found `{}`",
                        expr_text(other)
                    ),
                );
                None
            }
        }
    }

    fn lower_expr(&mut self, e: &Expr, place: Place) -> Option<ExprId> {
        match e {
            Expr::Paren(p) => self.lower_expr(&p.expr, place),
            Expr::Group(g) => self.lower_expr(&g.expr, place),
            Expr::Lit(l) => match numeric_literal(e) {
                Some(v) if !v.is_finite() => {
                    self.cx.error_spanned_by(
                        l,
                        format!(
                            "the literal `{}` is out of range for `f64`: it overflows to infinity (the largest finite value is about 1.8e308)",
                            l.lit.to_token_stream()
                        ),
                    );
                    None
                }
                Some(v) => Some(self.graph.constant(v)),
                None => {
                    self.cx.error_spanned_by(
                        l,
                        format!("expected a number, found `{}`", l.lit.to_token_stream()),
                    );
                    None
                }
            },
            Expr::Path(p) => {
                let Some(ident) = p.path.get_ident().filter(|_| p.qself.is_none()) else {
                    if let Some(v) = std_constant(&p.path) {
                        return Some(self.graph.constant(v));
                    }
                    self.cx.error_spanned_by(
                        p,
                        format!(
                            "expected a declared name or a constant such as `PI`, found the path `{}`",
                            expr_text(e)
                        ),
                    );
                    return None;
                };
                self.lower_name(ident, place)
            }
            Expr::Unary(u) => match u.op {
                UnOp::Neg(_) => {
                    let a = self.lower_expr(&u.expr, place)?;
                    Some(self.graph.neg(a))
                }
                _ => {
                    self.cx.error_spanned_by(
                        u.op,
                        "unsupported operator; expected `-` (negation) or one of `+ - * /`",
                    );
                    None
                }
            },
            Expr::Binary(b) => {
                let op = match b.op {
                    BinOp::Add(_) | BinOp::Sub(_) | BinOp::Mul(_) | BinOp::Div(_) => b.op,
                    BinOp::Eq(_) => {
                        self.cx.error_spanned_by(
                            b.op,
                            format!("`==` may appear only once, at the top of an equation, not inside {}", place.describe()),
                        );
                        return None;
                    }
                    _ => {
                        self.cx.error_spanned_by(
                            b.op,
                            format!(
                                "unsupported operator `{}`; expected `+`, `-`, `*` or `/` (use `powi`/`powf` for powers)",
                                b.op.to_token_stream()
                            ),
                        );
                        return None;
                    }
                };
                let l = self.lower_expr(&b.left, place);
                let r = self.lower_expr(&b.right, place);
                let (l, r) = (l?, r?);
                Some(match op {
                    BinOp::Add(_) => self.graph.add(l, r),
                    BinOp::Sub(_) => self.graph.sub(l, r),
                    BinOp::Mul(_) => self.graph.mul(l, r),
                    _ => self.graph.div(l, r),
                })
            }
            Expr::Call(c) => {
                let Some(name) = call_name(c) else {
                    self.cx.error_spanned_by(
                        &c.func,
                        format!(
                            "expected a function name ({}), found `{}`",
                            supported_functions(),
                            expr_text(&c.func)
                        ),
                    );
                    return None;
                };
                let args: Vec<&Expr> = c.args.iter().collect();
                if name == "der" {
                    return self.lower_der(c, place);
                }
                self.lower_call(&name, &c.func, &args, place, false)
            }
            Expr::MethodCall(m) => {
                if let Some(tf) = &m.turbofish {
                    self.cx.error_spanned_by(
                        tf,
                        "type arguments are not supported in model expressions",
                    );
                    return None;
                }
                let name = m.method.to_string();
                if name == "der" {
                    self.cx.error_spanned_by(
                        &m.method,
                        "write derivatives as `der(x)`, not `x.der()`",
                    );
                    return None;
                }
                let mut args: Vec<&Expr> = vec![&m.receiver];
                args.extend(m.args.iter());
                self.lower_call(&name, &m.method, &args, place, true)
            }
            Expr::Assign(a) => {
                self.cx.error_spanned_by(
                    a,
                    format!("`=` may appear only at the top of an explicit equation `der(x) = expr`, not inside {}", place.describe()),
                );
                None
            }
            other => {
                self.cx.error_spanned_by(
                    other,
                    "unsupported expression; expected numbers, declared names, `+ - * /`, unary `-`, parentheses and function calls",
                );
                None
            }
        }
    }

    fn lower_name(&mut self, ident: &Ident, place: Place) -> Option<ExprId> {
        let s = ident.unraw().to_string();
        if s == "t" {
            return Some(self.symbol(Symbol::Time));
        }
        let Some((binding, _)) = self.env.get(&s).copied() else {
            if let Some((_, v)) = CONSTANTS.iter().find(|(c, _)| *c == s) {
                return Some(self.graph.constant(*v));
            }
            let msg = if self.pending_lets.contains(&s) {
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
            };
            self.cx.error_spanned_by(ident, msg);
            return None;
        };
        if place == Place::Reference && !matches!(binding, Binding::Param(_)) {
            self.cx.error_spanned_by(
                ident,
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
            Binding::Let { expr, uses_der } => {
                if uses_der && place == Place::Output {
                    self.cx.error_spanned_by(
                        ident,
                        format!("`{s}` uses `der()`, which an output may not depend on"),
                    );
                    return None;
                }
                expr
            }
        })
    }

    fn lower_der(&mut self, c: &syn::ExprCall, place: Place) -> Option<ExprId> {
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
        if c.args.len() != 1 {
            self.cx.error_spanned_by(
                c,
                format!(
                    "`der` takes exactly one state name, found {} arguments",
                    c.args.len()
                ),
            );
            return None;
        }
        let arg = &c.args[0];
        if let Expr::Call(inner) = arg {
            if call_name(inner).as_deref() == Some("der") {
                self.cx.error_spanned_by(
                    c,
                    "nested `der(der(..))` is not supported; introduce a state for the first derivative (e.g. `der(x) = v; der(v) = ...`)",
                );
                return None;
            }
        }
        let Some(ident) = path_ident(arg) else {
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

    fn lower_call(
        &mut self,
        name: &str,
        name_tokens: &dyn ToTokens,
        args: &[&Expr],
        place: Place,
        method: bool,
    ) -> Option<ExprId> {
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
            return None;
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
            return None;
        }
        if name == "powi" {
            let base = self.lower_expr(args[0], place);
            let Some(n) = integer_literal(args[1]) else {
                self.cx.error_spanned_by(
                    args[1],
                    format!(
                        "`powi` needs an integer literal exponent such as `2` or `-1`, found `{}`; use `powf` for real or variable exponents",
                        expr_text(args[1])
                    ),
                );
                return None;
            };
            return Some(self.graph.powi(base?, n));
        }
        let lowered: Vec<Option<ExprId>> = args.iter().map(|a| self.lower_expr(a, place)).collect();
        let lowered: Vec<ExprId> = lowered.into_iter().collect::<Option<_>>()?;
        Some(match name {
            "atan2" => self.graph.atan2(lowered[0], lowered[1]),
            "hypot" => self.graph.hypot(lowered[0], lowered[1]),
            "powf" => self.graph.powf(lowered[0], lowered[1]),
            _ => {
                let f = Func::from_name(name)?;
                self.graph.func(f, lowered[0])
            }
        })
    }
}

fn call_name(c: &syn::ExprCall) -> Option<String> {
    path_ident(&c.func).map(|i| i.to_string())
}

fn path_ident(e: &Expr) -> Option<&Ident> {
    match e {
        Expr::Path(p) if p.qself.is_none() => p.path.get_ident(),
        Expr::Paren(p) => path_ident(&p.expr),
        Expr::Group(g) => path_ident(&g.expr),
        _ => None,
    }
}

/// `std::f64::consts::PI`, `core::f64::consts::PI` and `f64::consts::PI`.
fn std_constant(path: &syn::Path) -> Option<f64> {
    let segs: Vec<String> = path.segments.iter().map(|s| s.ident.to_string()).collect();
    let tail = match segs.as_slice() {
        [a, b, c, d] if (a == "std" || a == "core") && b == "f64" && c == "consts" => d,
        [b, c, d] if b == "f64" && c == "consts" => d,
        _ => return None,
    };
    CONSTANTS.iter().find(|(n, _)| n == tail).map(|(_, v)| *v)
}
