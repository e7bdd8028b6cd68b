//! The one helper behind every generated routine: straight-line code that evaluates a set of
//! roots with full common-subexpression elimination ([`crate::symbolic::Schedule`]) and writes
//! them into the routine's output slices.
//!
//! A routine whose computation is long (the Jacobians of a 16-link arm's tracking DAE have
//! some 16 000 operations) is split into parts: LLVM's optimisation and code generation of
//! one straight-line function grow faster than its length, and a function in one piece is
//! compiled on one thread. The temporaries, in their scheduled order, are cut into parts of
//! about [`PART_OPERATIONS`] operations; each part is a non-generic function of its own in a
//! module of the routine's parts (which `rustc` may put into a codegen unit of its own), and
//! each root is written by the part that computes the last temporary it reads. A temporary
//! read by a later part is stored into a scratch array (`__tmp`, on the stack of the
//! routine, its slots reused once their last reader has run) and read back there; the
//! parameters the parts read are handed over in an array (`__p`). Every value is computed by
//! the same expression as in one piece, so the results are the same bits; a routine short
//! enough stays one piece.

use crate::derive::{Layout, Source};
use crate::ir::{Model, Symbol};
use crate::symbolic::{ExprId, Graph, Node, Schedule, Var};
use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};
use std::collections::{BTreeMap, BTreeSet};

/// About how many arithmetic operations (and function calls) one part of a split routine
/// computes. Routines with fewer operations than this in all are not split.
pub const PART_OPERATIONS: usize = 2000;

/// The operation count per part: [`PART_OPERATIONS`], or for measurements the value of the
/// environment variable `DPC_PART_OPERATIONS` when the macro runs (`0`: never split).
fn part_operations() -> usize {
    match std::env::var("DPC_PART_OPERATIONS") {
        Ok(v) => match v.parse::<usize>() {
            Ok(0) => usize::MAX,
            Ok(n) => n,
            Err(_) => PART_OPERATIONS,
        },
        Err(_) => PART_OPERATIONS,
    }
}

/// Straight-line code for a set of roots, with the locals it needs bound from the
/// `__`-prefixed function parameters.
pub(super) struct Routine {
    /// The slices cut to their lengths and the locals bound.
    pub prelude: TokenStream,
    /// `let __sK = ...;` per temporary.
    pub statements: Vec<TokenStream>,
    /// One expression per root.
    pub roots: Vec<TokenStream>,
}

fn local_ident(model: &Model, symbol: Symbol) -> Ident {
    let span = Span::call_site();
    match symbol {
        Symbol::Time => Ident::new("t", span),
        Symbol::State(i) => model.states[i].name.clone(),
        Symbol::StateDot(i) => format_ident!("der__{}", model.states[i].name),
        Symbol::StateDerivative { state, order } => {
            format_ident!("der{}__{}", order, model.states[state].name)
        }
        Symbol::Algebraic(i) => model.algebraic[i].name.clone(),
        Symbol::AlgebraicDot(i) => format_ident!("der__{}", model.algebraic[i].name),
        Symbol::Input(i) => model.inputs[i].name.clone(),
        Symbol::InputDot(i) => format_ident!("der__{}", model.inputs[i].name),
        Symbol::Param(i) => model.params[i].name.clone(),
        Symbol::IterationCoefficient => Ident::new("__c", span),
        Symbol::TrackingInput(i) => format_ident!("w__{}", model.outputs[i].name),
        Symbol::TrackingCoefficient { output, power } => {
            format_ident!("coef__{}__{}", model.outputs[output].name, power)
        }
    }
}

fn source_tokens(source: Source) -> TokenStream {
    match source {
        Source::Time => quote!(__t),
        Source::State(k) => quote!(__x[#k]),
        Source::StateDot(k) => quote!(__xdot[#k]),
        Source::Algebraic(k) => quote!(__z[#k]),
        Source::Input(k) => quote!(__u[#k]),
        Source::Param(_) | Source::WCoefficient(_) | Source::IterationCoefficient => {
            unreachable!("parameters and coefficients are bound by name")
        }
    }
}

/// Which slice argument a source reads (`__x`, `__xdot`, `__z`, `__u` in that order).
fn slice_index(source: Source) -> Option<usize> {
    match source {
        Source::State(_) => Some(0),
        Source::StateDot(_) => Some(1),
        Source::Algebraic(_) => Some(2),
        Source::Input(_) => Some(3),
        _ => None,
    }
}

/// Where the values of parameters and coefficients of `W` are read: from the value
/// (`self.params.m`, `self.w_coefficients[k]`), or in a part of a split routine from the
/// array `__p` it is handed (at the position the map gives).
enum ParamsFrom<'a> {
    SelfValue,
    Array(&'a BTreeMap<(u8, usize), usize>),
}

/// An ordering key for a [`Source`] (kind, index).
fn source_key(source: Source) -> (u8, usize) {
    match source {
        Source::Time => (0, 0),
        Source::State(k) => (1, k),
        Source::StateDot(k) => (2, k),
        Source::Algebraic(k) => (3, k),
        Source::Input(k) => (4, k),
        Source::Param(k) => (5, k),
        Source::WCoefficient(k) => (6, k),
        Source::IterationCoefficient => (7, 0),
    }
}

/// The slices cut to their lengths and one `let` per variable in `vars` (sorted by symbol).
fn bindings(
    model: &Model,
    layout: &Layout,
    vars: &BTreeSet<Var>,
    params: &ParamsFrom<'_>,
) -> TokenStream {
    let mut prelude = TokenStream::new();
    let mut symbols: Vec<Symbol> = vars.iter().map(|v| model.symbols.symbol(*v)).collect();
    symbols.sort();
    let degrees = crate::hirschorn::w_degrees(model);
    // Each slice read is cut to its layout's length once, so the reads below are proven in
    // bounds and compile without checks.
    let sources: Vec<Option<Source>> = symbols
        .iter()
        .map(|&s| layout.source(s, &degrees))
        .collect();
    let slices = [
        (quote!(__x), layout.states.len()),
        (quote!(__xdot), layout.states.len()),
        (quote!(__z), layout.algebraic.len()),
        (quote!(__u), layout.inputs.len()),
    ];
    for (k, (slice, len)) in slices.iter().enumerate() {
        if sources.iter().flatten().any(|&s| slice_index(s) == Some(k)) {
            prelude.extend(quote!(let #slice = &#slice[..#len];));
        }
    }
    for (s, source) in symbols.into_iter().zip(sources) {
        let local = local_ident(model, s);
        let value = match (source, params) {
            (Some(Source::IterationCoefficient), _) => continue,
            (Some(Source::Param(_)), ParamsFrom::SelfValue) => quote!(self.params.#local),
            (Some(Source::WCoefficient(k)), ParamsFrom::SelfValue) => {
                quote!(self.w_coefficients[#k])
            }
            (Some(p @ (Source::Param(_) | Source::WCoefficient(_))), ParamsFrom::Array(at)) => {
                let k = at[&source_key(p)];
                quote!(__p[#k])
            }
            (Some(source), _) => source_tokens(source),
            (None, _) => {
                unreachable!("symbol {s:?} has no place in this layout; the checks exclude it")
            }
        };
        prelude.extend(quote!(let #local: f64 = #value;));
    }
    prelude
}

fn var_tokens(model: &Model) -> impl Fn(Var) -> TokenStream + '_ {
    move |v| {
        let local = local_ident(model, model.symbols.symbol(v));
        quote!(#local)
    }
}

/// Straight-line code for `roots` in one piece, the roots as expressions (for routines that
/// return their values rather than write them).
pub(super) fn routine(model: &Model, layout: &Layout, roots: &[ExprId]) -> Routine {
    let mut used: BTreeSet<Var> = BTreeSet::new();
    for &r in roots {
        used.extend(model.graph.vars(r));
    }
    let prelude = bindings(model, layout, &used, &ParamsFrom::SelfValue);
    let code = model
        .graph
        .emit_rust_prefixed(roots, &var_tokens(model), "__s");
    Routine {
        prelude,
        statements: code.statements,
        roots: code.roots,
    }
}

/// One output slice of a routine: a `&mut [f64]` (or `&mut [f64; len]`) parameter of the
/// generated method, which receives `len` consecutive roots.
pub(super) struct Output {
    /// The parameter's name (`__out`, `__residual`, `__values`).
    pub name: TokenStream,
    /// How many roots it receives.
    pub len: usize,
    /// Whether the method's body cuts it to `len` first (a slice of unknown length; an array
    /// needs no cut).
    pub cut: bool,
}

/// The body of a routine's method and, when it is split, the module of its parts (emitted
/// beside the method's `impl`).
pub(super) struct RoutineCode {
    /// The method's body.
    pub body: TokenStream,
    /// The module of the parts, or nothing.
    pub parts: TokenStream,
}

/// The code of a method that evaluates `roots` and writes them, in order, into `outputs`
/// (the first `outputs[0].len` roots into the first output, and so on). Split into parts in
/// a module named `module` when long (see the module documentation).
pub(super) fn routine_writing(
    model: &Model,
    layout: &Layout,
    roots: &[ExprId],
    outputs: &[Output],
    module: &Ident,
) -> RoutineCode {
    debug_assert_eq!(outputs.iter().map(|o| o.len).sum::<usize>(), roots.len());
    let schedule = model.graph.schedule(roots);
    let code = model
        .graph
        .emit_schedule(&schedule, &var_tokens(model), "__s");
    // Root k goes to destinations[k].
    let destinations: Vec<TokenStream> = outputs
        .iter()
        .flat_map(|o| {
            let name = &o.name;
            (0..o.len).map(move |i| quote!(#name[#i]))
        })
        .collect();
    let plan = Plan::new(&model.graph, &schedule, part_operations());
    if plan.parts.len() <= 1 {
        let mut used: BTreeSet<Var> = BTreeSet::new();
        for &r in roots {
            used.extend(model.graph.vars(r));
        }
        let prelude = bindings(model, layout, &used, &ParamsFrom::SelfValue);
        let cuts = outputs.iter().filter(|o| o.cut).map(|o| {
            let (name, len) = (&o.name, o.len);
            quote!(let #name = &mut #name[..#len];)
        });
        let stmts = &code.statements;
        let writes = destinations
            .iter()
            .zip(&code.roots)
            .map(|(d, v)| quote!(#d = #v;));
        return RoutineCode {
            body: quote!(#prelude #(#cuts)* #(#stmts)* #(#writes)*),
            parts: TokenStream::new(),
        };
    }
    split_routine(model, layout, &code, &plan, &destinations, outputs, module)
}

/// Which part computes each temporary and writes each root, and the scratch slots of the
/// temporaries read by later parts.
struct Plan {
    parts: Vec<Part>,
    /// Per temporary, its scratch slot if a later part reads it.
    slot: Vec<Option<usize>>,
    /// Number of scratch slots.
    slots: usize,
}

#[derive(Default)]
struct Part {
    /// The temporaries it computes (consecutive).
    temps: std::ops::Range<usize>,
    /// The roots it writes, in order.
    roots: Vec<usize>,
    /// The variables it reads.
    vars: BTreeSet<Var>,
    /// The temporaries of earlier parts it reads.
    imports: BTreeSet<usize>,
}

/// The temporaries and variables the emitted expression of `e` reads, and its number of
/// operations (`top`: `e` is the node a temporary's statement defines, so it is expanded even
/// though it has a temporary).
fn reads(
    g: &Graph,
    s: &Schedule,
    e: ExprId,
    top: bool,
    temps: &mut BTreeSet<usize>,
    vars: &mut BTreeSet<Var>,
) -> usize {
    if !top {
        if let Some(k) = s.temp_of(e) {
            temps.insert(k);
            return 0;
        }
    }
    match *g.node(e) {
        Node::Var(v) => {
            vars.insert(v);
            0
        }
        Node::Const(_) => 0,
        ref node => {
            1 + node
                .children()
                .map(|c| reads(g, s, c, false, temps, vars))
                .sum::<usize>()
        }
    }
}

impl Plan {
    fn new(g: &Graph, s: &Schedule, per_part: usize) -> Plan {
        let n_temps = s.temps.len();
        let mut part_of = vec![0usize; n_temps];
        let mut parts: Vec<Part> = vec![Part::default()];
        let mut temp_reads: Vec<BTreeSet<usize>> = Vec::with_capacity(n_temps);
        let mut operations = 0usize;
        for (k, &t) in s.temps.iter().enumerate() {
            let mut temps = BTreeSet::new();
            let mut vars = BTreeSet::new();
            let cost = reads(g, s, t, true, &mut temps, &mut vars);
            if operations > 0 && operations + cost > per_part {
                parts.push(Part {
                    temps: k..k,
                    ..Part::default()
                });
                operations = 0;
            }
            operations += cost;
            let p = parts.len() - 1;
            part_of[k] = p;
            let part = &mut parts[p];
            part.temps.end = k + 1;
            part.vars.extend(vars);
            temp_reads.push(temps);
        }
        // Each root is written by the part of the last temporary it reads.
        let mut root_reads = Vec::with_capacity(s.roots.len());
        for (r, &e) in s.roots.iter().enumerate() {
            let mut temps = BTreeSet::new();
            let mut vars = BTreeSet::new();
            reads(g, s, e, false, &mut temps, &mut vars);
            let p = temps.iter().map(|&k| part_of[k]).max().unwrap_or(0);
            parts[p].roots.push(r);
            parts[p].vars.extend(vars);
            root_reads.push((p, temps));
        }
        // The last part reading each temporary, and each part's imports.
        let mut last_read = part_of.clone();
        let temp_readers = temp_reads.iter().enumerate().map(|(k, t)| (part_of[k], t));
        let root_readers = root_reads.iter().map(|(p, t)| (*p, t));
        for (p, temps) in temp_readers.chain(root_readers) {
            for &k in temps {
                if part_of[k] < p {
                    parts[p].imports.insert(k);
                    last_read[k] = last_read[k].max(p);
                }
            }
        }
        // Slots: a temporary read later gets one when its part runs; the slot is free again
        // for the temporaries of the part that reads it last (which reads it at its start and
        // stores its own at its end).
        let mut slot = vec![None; n_temps];
        let mut free: Vec<usize> = Vec::new();
        let mut slots = 0usize;
        let mut ending: Vec<Vec<usize>> = vec![Vec::new(); parts.len()];
        for k in 0..n_temps {
            if last_read[k] > part_of[k] {
                ending[last_read[k]].push(k);
            }
        }
        for (p, part) in parts.iter().enumerate() {
            for &k in &ending[p] {
                free.extend(slot[k]);
            }
            for k in part.temps.clone() {
                if last_read[k] > p {
                    let s = free.pop().unwrap_or_else(|| {
                        slots += 1;
                        slots - 1
                    });
                    slot[k] = Some(s);
                }
            }
        }
        Plan { parts, slot, slots }
    }
}

/// The method's body calling the parts, and the module of the parts.
fn split_routine(
    model: &Model,
    layout: &Layout,
    code: &crate::symbolic::RustCode,
    plan: &Plan,
    destinations: &[TokenStream],
    outputs: &[Output],
    module: &Ident,
) -> RoutineCode {
    let degrees = crate::hirschorn::w_degrees(model);
    // The parameters and coefficients any part reads, in one array.
    let all_vars: BTreeSet<Var> = plan.parts.iter().flat_map(|p| p.vars.clone()).collect();
    let mut by_key: BTreeMap<(u8, usize), Source> = BTreeMap::new();
    for &v in &all_vars {
        let symbol = model.symbols.symbol(v);
        if let Some(source) = layout.source(symbol, &degrees) {
            by_key.insert(source_key(source), source);
        }
    }
    let sources: Vec<Source> = by_key.into_values().collect();
    let params: Vec<Source> = sources
        .iter()
        .copied()
        .filter(|s| matches!(s, Source::Param(_) | Source::WCoefficient(_)))
        .collect();
    let position: BTreeMap<(u8, usize), usize> = params
        .iter()
        .enumerate()
        .map(|(i, &s)| (source_key(s), i))
        .collect();
    let param_values = params.iter().map(|&s| match s {
        Source::Param(k) => {
            let name = &model.params[k].name;
            quote!(self.params.#name)
        }
        Source::WCoefficient(k) => quote!(self.w_coefficients[#k]),
        _ => unreachable!("only parameters and coefficients are collected"),
    });
    let n_params = params.len();
    let n_slots = plan.slots;
    let reads = |f: fn(&Source) -> bool| sources.iter().any(f);
    let t_arg = if reads(|s| matches!(s, Source::Time)) {
        quote!(__t)
    } else {
        quote!(0.0)
    };
    let slice_arg = |name: TokenStream, f: fn(&Source) -> bool| {
        if reads(f) {
            name
        } else {
            quote!(&[])
        }
    };
    let x_arg = slice_arg(quote!(__x), |s| matches!(s, Source::State(_)));
    let xdot_arg = slice_arg(quote!(__xdot), |s| matches!(s, Source::StateDot(_)));
    let z_arg = slice_arg(quote!(__z), |s| matches!(s, Source::Algebraic(_)));
    let u_arg = slice_arg(quote!(__u), |s| matches!(s, Source::Input(_)));
    let c_arg = if reads(|s| matches!(s, Source::IterationCoefficient)) {
        quote!(__c)
    } else {
        quote!(0.0)
    };
    let out_names: Vec<&TokenStream> = outputs.iter().map(|o| &o.name).collect();
    // Root k is written to output `output_of[k]`.
    let output_of: Vec<usize> = outputs
        .iter()
        .enumerate()
        .flat_map(|(i, o)| std::iter::repeat_n(i, o.len))
        .collect();

    let mut functions = Vec::with_capacity(plan.parts.len());
    let mut calls = Vec::with_capacity(plan.parts.len());
    for (p, part) in plan.parts.iter().enumerate() {
        let name = format_ident!("part{}", p);
        let prelude = bindings(model, layout, &part.vars, &ParamsFrom::Array(&position));
        let imports = part.imports.iter().map(|&k| {
            let temp = format_ident!("__s{}", k);
            let slot = plan.slot[k].expect("a temporary read by a later part has a slot");
            quote!(let #temp: f64 = __tmp[#slot];)
        });
        let used_outputs: BTreeSet<usize> = part.roots.iter().map(|&r| output_of[r]).collect();
        let cuts = used_outputs.iter().map(|&i| {
            let (name, len) = (&outputs[i].name, outputs[i].len);
            quote!(let #name = &mut #name[..#len];)
        });
        let stmts = &code.statements[part.temps.clone()];
        let exports = part.temps.clone().filter_map(|k| {
            plan.slot[k].map(|slot| {
                let temp = format_ident!("__s{}", k);
                quote!(__tmp[#slot] = #temp;)
            })
        });
        let writes = part.roots.iter().map(|&r| {
            let (d, v) = (&destinations[r], &code.roots[r]);
            quote!(#d = #v;)
        });
        functions.push(quote! {
            #[inline(never)]
            pub fn #name(
                __t: f64,
                __x: &[f64],
                __xdot: &[f64],
                __z: &[f64],
                __u: &[f64],
                __c: f64,
                __p: &[f64; #n_params],
                __tmp: &mut [f64; #n_slots],
                #(#out_names: &mut [f64]),*
            ) {
                #prelude
                #(#imports)*
                #(#cuts)*
                #(#stmts)*
                #(#exports)*
                #(#writes)*
            }
        });
        calls.push(quote! {
            #module::#name(#t_arg, #x_arg, #xdot_arg, #z_arg, #u_arg, #c_arg, &__p, &mut __tmp, #(#out_names),*);
        });
    }
    RoutineCode {
        body: quote! {
            let __p: [f64; #n_params] = [#(#param_values),*];
            let mut __tmp = [0.0_f64; #n_slots];
            #(#calls)*
        },
        parts: quote! {
            #[doc(hidden)]
            #[allow(clippy::all, clippy::pedantic, unused_variables, unused_parens, non_snake_case)]
            mod #module {
                #(#functions)*
            }
        },
    }
}

/// The model texts of the repository's declarations, shared with the workspace's tests.
#[cfg(test)]
#[path = "../../../tests/common/model_text.rs"]
mod model_text;

#[cfg(test)]
mod tests {
    use super::{reads, Plan};
    use std::collections::BTreeSet;

    /// The arm of `models/src/arm.rs` with six links, instantiated from its declaration
    /// (`models/src/arm_declaration.rs`) as `models/src/arm.rs` does.
    fn six_link_arm() -> proc_macro2::TokenStream {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../models/src/arm_declaration.rs"
        );
        let source = std::fs::read_to_string(path).expect("models/src/arm_declaration.rs");
        let call = "flexible_joint_arm!(\"The arm.\", Arm6, Arm6Tracking, 6);";
        let [model] = &super::model_text::template_models(call, &source)[..] else {
            panic!("one model in the declaration");
        };
        model.parse().expect("the arm tokenises")
    }

    /// A split routine computes what the one piece computes: every part reads each temporary
    /// either from its own earlier statements or from the slot it was stored in (and not
    /// overwritten since), every variable it reads is bound, and every root is written once.
    #[test]
    fn parts_read_every_temporary_where_it_was_stored() {
        let (model, derived) = crate::derive_model(six_link_arm()).expect("the arm derives");
        let ty = &derived.tracking.as_ref().expect("a tracking DAE").dae;
        let roots = ty.residual_and_iteration_roots();
        let s = model.graph.schedule(&roots);
        for per_part in [1, 7, 100, 1000, usize::MAX] {
            let plan = Plan::new(&model.graph, &s, per_part);
            if per_part <= 100 {
                assert!(
                    plan.parts.len() > 5,
                    "{per_part}: {} parts",
                    plan.parts.len()
                );
            }
            let mut slots: Vec<Option<usize>> = vec![None; plan.slots];
            let mut next_temp = 0;
            for part in &plan.parts {
                assert_eq!(
                    part.temps.start, next_temp,
                    "the parts cover the temporaries"
                );
                next_temp = part.temps.end;
                for &k in &part.imports {
                    let slot = plan.slot[k].expect("an imported temporary has a slot");
                    assert_eq!(slots[slot], Some(k), "slot {slot} holds temporary {k}");
                }
                let available = |j: usize, before: usize| {
                    part.imports.contains(&j) || (part.temps.start..before).contains(&j)
                };
                for k in part.temps.clone() {
                    let (mut temps, mut vars) = (BTreeSet::new(), BTreeSet::new());
                    reads(&model.graph, &s, s.temps[k], true, &mut temps, &mut vars);
                    assert!(temps.iter().all(|&j| available(j, k)), "temporary {k}");
                    assert!(vars.is_subset(&part.vars), "temporary {k}");
                }
                for &r in &part.roots {
                    let (mut temps, mut vars) = (BTreeSet::new(), BTreeSet::new());
                    reads(&model.graph, &s, s.roots[r], false, &mut temps, &mut vars);
                    assert!(
                        temps.iter().all(|&j| available(j, part.temps.end)),
                        "root {r}"
                    );
                    assert!(vars.is_subset(&part.vars), "root {r}");
                }
                for k in part.temps.clone() {
                    if let Some(slot) = plan.slot[k] {
                        slots[slot] = Some(k);
                    }
                }
            }
            assert_eq!(next_temp, s.temps.len());
            let mut written: Vec<usize> = plan.parts.iter().flat_map(|p| p.roots.clone()).collect();
            written.sort_unstable();
            assert_eq!(written, (0..roots.len()).collect::<Vec<_>>());
        }
    }

    /// The model of `tests/split_routines.rs`, which checks split routines numerically, is
    /// long enough to be split.
    #[test]
    fn the_split_routines_test_model_is_split() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/split_routines.rs");
        let source = std::fs::read_to_string(path).expect("tests/split_routines.rs");
        let file = syn::parse_file(&source).expect("the test parses");
        let tokens = file
            .items
            .into_iter()
            .find_map(|item| match item {
                syn::Item::Macro(m)
                    if m.mac
                        .path
                        .segments
                        .last()
                        .is_some_and(|s| s.ident == "model") =>
                {
                    Some(m.mac.tokens)
                }
                _ => None,
            })
            .expect("a model! in tests/split_routines.rs");
        let code = crate::try_expand(tokens).expect("expands").to_string();
        for routine in ["fused", "iteration", "evaluate"] {
            for ty in ["Coupled", "CoupledTracking"] {
                let module = format!("mod __dpc_{ty}_{routine} ");
                assert!(code.contains(&module), "{module}");
            }
        }
    }
}
