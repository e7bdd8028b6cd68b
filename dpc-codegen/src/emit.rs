//! Emission: the checked model IR to Rust items.
//!
//! For a model `Name` this emits
//!
//! * `NameParams`, the parameter struct with `Default` from the declared defaults;
//! * `Name`, the model type, with inherent fixed-size conveniences (nalgebra `SVector` /
//!   `SMatrix`) and an implementation of `dpc::core::DaeModel` whose routines take slices
//!   and write Jacobian entries into `MatrixSink`s, and parameter access by index as
//!   `match`es;
//! * with a `tracking` section, the tracking DAE type, which also holds the coefficients of
//!   `W` in use in a fixed-size array (read in the routines' preludes, so nothing allocates)
//!   and implements `dpc::core::TrackingDae`.
//!
//! Each routine is one straight-line block: every root it needs (residual rows and Jacobian
//! entries) is scheduled together, so subexpressions are shared across the residual and all
//! Jacobians; structurally zero entries are never emitted, and the non-zero positions are
//! exported as pattern constants. `residual_and_iteration_matrix` schedules the residual and
//! the iteration matrix together for Newton loops. The routines that write into sinks are
//! generic over the sink type, so their computation is emitted once, as non-generic methods
//! (`__evaluate_values` and the like) that store the entries' values into an array, and the
//! generic methods only hand the values to the sinks in a loop over the pattern: `rustc` then
//! compiles the heavy straight-line code once per model, not once per sink type. Every slice a routine reads or writes is cut
//! to its length once at the top, so the indexing inside compiles without bounds checks.
//! Function parameters use `__`-prefixed names, which the DSL forbids in user names, so user
//! names can be bound as plain locals without shadowing.

use crate::derive::{
    Block, DaeDerivatives, Derived, Layout, ReferenceDerivatives, Source, TrackingDerivatives,
};
use crate::ir::{Model, Symbol};
use crate::symbolic::{ExprId, Var};
use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};
use std::collections::BTreeSet;

/// Straight-line code for a set of roots, with the locals it needs bound from the
/// `__`-prefixed function parameters.
struct Routine {
    prelude: TokenStream,
    statements: Vec<TokenStream>,
    roots: Vec<TokenStream>,
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

fn routine(model: &Model, layout: &Layout, roots: &[ExprId]) -> Routine {
    let mut used: BTreeSet<Var> = BTreeSet::new();
    for &r in roots {
        used.extend(model.graph.vars(r));
    }
    let mut prelude = TokenStream::new();
    let mut symbols: Vec<Symbol> = used.iter().map(|v| model.symbols.symbol(*v)).collect();
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
        let binding = match source {
            Some(Source::Param(_)) => quote!(let #local: f64 = self.params.#local;),
            Some(Source::WCoefficient(k)) => quote!(let #local: f64 = self.w_coefficients[#k];),
            Some(Source::IterationCoefficient) => continue,
            Some(source) => {
                let src = source_tokens(source);
                quote!(let #local: f64 = #src;)
            }
            None => unreachable!("symbol {s:?} has no place in this layout; the checks exclude it"),
        };
        prelude.extend(binding);
    }
    let code = model.graph.emit_rust_prefixed(
        roots,
        &|v| {
            let local = local_ident(model, model.symbols.symbol(v));
            quote!(#local)
        },
        "__s",
    );
    Routine {
        prelude,
        statements: code.statements,
        roots: code.roots,
    }
}

fn doc_lines(text: &str) -> TokenStream {
    let lines = text.lines().map(|l| {
        let l = format!(" {l}");
        quote!(#[doc = #l])
    });
    quote!(#(#lines)*)
}

/// The structural non-zero positions of a block as a slice literal.
fn pattern(block: &Block) -> TokenStream {
    let items = block.entries.iter().map(|(i, j, _)| quote!((#i, #j)));
    quote!(&[#(#items),*])
}

fn str_list(items: impl IntoIterator<Item = String>) -> TokenStream {
    let items: Vec<String> = items.into_iter().collect();
    quote!(&[#(#items),*])
}

pub use crate::derive::listing;

/// Emit all items for a lowered model from its derivatives ([`crate::derive::derive`]): the
/// parameter struct, the plant type, and, with a `tracking` section, the tracking DAE; with a
/// `references` section, the reference type.
pub fn emit_model(model: &Model, derived: &Derived) -> TokenStream {
    let params = emit_params(model);
    let plant_tokens = emit_dae_type(model, &derived.plant, &model.attrs, None);
    let degrees = option_list(&derived.relative_degrees);
    let name = &model.name;
    let diagnostics = quote! {
        impl #name {
            /// Per output, the relative degree: the number of total time derivatives after
            /// which an input appears (`None` where it is not defined). Computed at compile
            /// time, exactly along explicit equations and structurally through implicit ones.
            pub const RELATIVE_DEGREES: &'static [::core::option::Option<usize>] = #degrees;
        }
    };
    let tracking = match &derived.tracking {
        Some(t) => emit_tracking(model, t, &derived.relative_degrees),
        None => TokenStream::new(),
    };
    let references = match &derived.references {
        Some(r) => emit_references(model, r),
        None => TokenStream::new(),
    };
    quote!(#params #plant_tokens #diagnostics #tracking #references)
}

fn option_list(values: &[Option<usize>]) -> TokenStream {
    let items = values.iter().map(|v| match v {
        Some(r) => quote!(::core::option::Option::Some(#r)),
        None => quote!(::core::option::Option::None),
    });
    quote!(&[#(#items),*])
}

/// The tracking DAE type: the plant equations, the derivatives of implicit equations its
/// steps need, and one constraint row per output, in the unknowns `(X, [Z; D; U])` with the
/// inputs `w` (`D` the higher derivatives of states, see [`crate::hirschorn::tracking_rows`]).
fn emit_tracking(
    model: &Model,
    tracking: &TrackingDerivatives,
    relative_degrees: &[Option<usize>],
) -> TokenStream {
    let plant_name = model.name.clone();
    let doc = format!(
        " The tracking DAE of [`{plant_name}`]: its equations plus `W_i(d/dt) h_i = w_i` per output, in the unknowns (states, algebraic unknowns and inputs of the plant); the inputs are `w_i = W_i(d/dt) xi_i` (see `dpc::core::TrackingDae`). The degrees of the `W_i` are fixed at compile time; their coefficients are read from the value, start as the compiled ones and can be changed with `dpc::core::TrackingDae::set_w_roots`."
    );
    let mut docs: Vec<syn::Attribute> = vec![syn::parse_quote!(#[doc = #doc])];
    let higher = &tracking.dae.layout.algebraic[model.algebraic.len()..tracking.plant_algebraic];
    if !higher.is_empty() {
        let names: Vec<String> = higher
            .iter()
            .map(|s| format!("`{}`", model.symbol_name(*s)))
            .collect();
        let doc = format!(
            " Its steps differentiate through implicit equations: their total derivatives are equations of this type too, and the higher derivatives {} are algebraic unknowns after the plant's and before its inputs.",
            names.join(", ")
        );
        docs.push(syn::parse_quote!(#[doc = ""]));
        docs.push(syn::parse_quote!(#[doc = #doc]));
    }
    let tokens = emit_dae_type(model, &tracking.dae, &docs, Some(&tracking.w_defaults));
    let name = &tracking.dae.name;
    let coeffs = tracking.w_defaults.iter().map(|c| quote!(&[#(#c),*]));
    let degrees = option_list(relative_degrees);
    let plant_nz = tracking.plant_algebraic;
    // Output i owns w_coefficients[start..end]: its monic coefficients, lowest power first.
    let mut start = 0;
    let ranges: Vec<TokenStream> = tracking
        .w_defaults
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let end = start + c.len();
            let arm = quote!(#i => #start..#end,);
            start = end;
            arm
        })
        .collect();
    quote! {
        #tokens

        #[allow(clippy::all, clippy::pedantic)]
        impl ::dpc::core::TrackingDae for #name {
            type Plant = #plant_name;
            fn default_w_coefficients(&self, output: usize) -> &[f64] {
                const W_COEFFICIENTS: &[&[f64]] = &[#(#coeffs),*];
                match W_COEFFICIENTS.get(output) {
                    ::core::option::Option::Some(c) => c,
                    ::core::option::Option::None => &[],
                }
            }

            fn relative_degrees(&self) -> &[::core::option::Option<usize>] {
                #degrees
            }

            fn plant_algebraic(&self) -> usize {
                #plant_nz
            }

            fn w_coefficients(&self, output: usize) -> &[f64] {
                let range = match output {
                    #(#ranges)*
                    _ => 0..0,
                };
                &self.w_coefficients[range]
            }

            fn set_w_coefficients(
                &mut self,
                output: usize,
                coefficients: &[f64],
            ) -> ::core::result::Result<(), ::dpc::core::tracking::TrackingError> {
                ::dpc::core::tracking::check_w_coefficients(self, output, coefficients)?;
                let range = match output {
                    #(#ranges)*
                    _ => 0..0,
                };
                self.w_coefficients[range].copy_from_slice(coefficients);
                ::core::result::Result::Ok(())
            }
        }
    }
}

/// The reference type `NameReference` for a `references` section: `xi_i(t)` and its exact
/// derivatives up to one more than the tracking DAE needs.
fn emit_references(model: &Model, references: &ReferenceDerivatives) -> TokenStream {
    let m = model.outputs.len();
    let max_order = references.max_order;
    let roots = &references.roots;
    let layout = Layout::time_only();
    let r = routine(model, &layout, roots);
    let (prelude, stmts) = (r.prelude, r.statements);
    let n = roots.len();
    let values = r.roots;
    let name = format_ident!("{}Reference", model.name);
    let params_name = format_ident!("{}Params", model.name);
    let vis = &model.vis;
    let plant = &model.name;
    let texts: Vec<String> = references
        .texts
        .iter()
        .map(|t| format!(" * `{t}`"))
        .collect();
    let doc = format!(
        " The references declared for [`{plant}`], with exact derivatives up to order {max_order} generated symbolically:"
    );
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #(#[doc = #texts])*
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        #vis struct #name {
            /// The model's parameters (references may use them).
            pub params: #params_name,
        }

        #[allow(clippy::all, clippy::pedantic, unused_variables, unused_parens, non_snake_case)]
        impl #name {
            /// The highest derivative order provided.
            pub const MAX_ORDER: usize = #max_order;

            fn all_derivatives(&self, __t: f64) -> [f64; #n] {
                #prelude
                #(#stmts)*
                [#(#values),*]
            }
        }

        impl ::dpc::core::Reference for #name {
            fn dimension(&self) -> usize {
                #m
            }

            fn max_order(&self) -> usize {
                #max_order
            }

            fn derivatives(
                &self,
                t: f64,
                order: usize,
                out: &mut [f64],
            ) -> ::core::result::Result<(), ::dpc::core::reference::ReferenceError> {
                if order > #max_order {
                    return ::core::result::Result::Err(::dpc::core::reference::ReferenceError::OrderTooHigh {
                        name: ::core::stringify!(#name).into(),
                        max: #max_order,
                        requested: order,
                    });
                }
                ::dpc::core::reference::check_buffer(#m, order, out)?;
                let all = self.all_derivatives(t);
                out.copy_from_slice(&all[..(order + 1) * #m]);
                ::core::result::Result::Ok(())
            }
        }
    }
}

/// The parameter struct `NameParams` with `Default` from the declared values.
fn emit_params(model: &Model) -> TokenStream {
    let name = &model.name;
    let vis = &model.vis;
    let params_name = format_ident!("{}Params", name);
    let param_fields = model.params.iter().map(|p| {
        let n = &p.name;
        let docs = &p.docs;
        let default_doc = format!(" Default: `{:?}`.", p.default);
        quote!(#(#docs)* #[doc = #default_doc] pub #n: f64,)
    });
    let param_defaults = model.params.iter().map(|p| {
        let n = &p.name;
        let v = p.default;
        quote!(#n: #v,)
    });
    let params_doc = format!(" Parameters of [`{name}`], with `Default` from the declared values.");
    quote! {
        #[doc = #params_doc]
        #[derive(Debug, Clone, Copy, PartialEq)]
        #vis struct #params_name {
            #(#param_fields)*
        }

        impl ::core::default::Default for #params_name {
            fn default() -> Self {
                Self { #(#param_defaults)* }
            }
        }
    }
}

/// The writes of a routine's Jacobian entries, split in two so that the heavy code is compiled
/// once: the values are stored into an array `__values` in block order (in a non-generic
/// method), and a small generic loop hands them to the sinks, block by block in row-major
/// order, as the pattern constants list them. The sinks receive the same `set` calls with the
/// same values as from straight-line writes.
struct SinkWrites {
    /// Number of entries (the length of `__values`).
    count: usize,
    /// `__values[k] = ...;` per entry, in block order.
    stores: Vec<TokenStream>,
    /// The generic part: per block, its pattern and the loop over its values.
    forward: TokenStream,
}

fn sink_writes(
    roots: &mut impl Iterator<Item = TokenStream>,
    blocks: &[(TokenStream, &Block)],
) -> SinkWrites {
    let mut stores = Vec::new();
    let mut forward = TokenStream::new();
    let mut count = 0usize;
    for (sink, b) in blocks {
        let start = count;
        for _ in &b.entries {
            let v = roots.next().expect("one root per Jacobian entry");
            stores.push(quote!(__values[#count] = #v;));
            count += 1;
        }
        if start == count {
            continue;
        }
        let positions = pattern(b);
        forward.extend(quote! {
            {
                const __PATTERN: &[(usize, usize)] = #positions;
                for (&(__i, __j), &__v) in __PATTERN.iter().zip(&__values[#start..#count]) {
                    #sink.set(__i, __j, __v);
                }
            }
        });
    }
    SinkWrites {
        count,
        stores,
        forward,
    }
}

/// Emit one type implementing `DaeModel` with its fixed-size conveniences.
///
/// `docs` are the type's doc attributes; `w_defaults` (for a tracking DAE, per output the
/// compiled monic coefficients of `W_i`) gives the type a field `w_coefficients` holding the
/// coefficients in use.
pub fn emit_dae_type(
    model: &Model,
    ty: &DaeDerivatives,
    docs: &[syn::Attribute],
    w_defaults: Option<&[Vec<f64>]>,
) -> TokenStream {
    let name = ty.name.clone();
    let vis = model.vis.clone();
    let attrs = docs.to_vec();
    let params_name = format_ident!("{}Params", model.name);
    let layout = &ty.layout;

    let nx = layout.states.len();
    let nz = layout.algebraic.len();
    let nu = layout.inputs.len();
    let ny = ty.outputs.len();
    let neq = ty.residuals.len();

    let residuals = &ty.residuals;
    let (f_xdot, f_x, f_z, f_u) = (&ty.f_xdot, &ty.f_x, &ty.f_z, &ty.f_u);
    let (h_x, h_z, h_u) = (&ty.h_x, &ty.h_z, &ty.h_u);
    let outputs = ty.output_exprs();

    // Routines: each schedules all of its roots together (CSE across them).
    let residual_code = {
        let r = routine(model, layout, residuals);
        let (prelude, stmts) = (r.prelude, r.statements);
        let writes = r
            .roots
            .iter()
            .enumerate()
            .map(|(i, v)| quote!(__out[#i] = #v;));
        quote!(#prelude let __out = &mut __out[..#neq]; #(#stmts)* #(#writes)*)
    };
    // A routine whose roots are the residual rows followed by the entries of `blocks`: the
    // body of its non-generic values method, the generic forwarding and the values' count.
    let residual_and_blocks = |roots: &[ExprId], blocks: &[(TokenStream, &Block)]| {
        let r = routine(model, layout, roots);
        let (prelude, stmts) = (r.prelude, r.statements);
        let mut it = r.roots.into_iter();
        let residual_writes: Vec<TokenStream> = (0..neq)
            .map(|i| {
                let v = it.next().expect("one root per residual row");
                quote!(__residual[#i] = #v;)
            })
            .collect();
        let w = sink_writes(&mut it, blocks);
        let stores = &w.stores;
        (
            quote!(#prelude let __residual = &mut __residual[..#neq]; #(#stmts)* #(#residual_writes)* #(#stores)*),
            w.forward,
            w.count,
        )
    };
    let (fused_values, fused_forward, fused_count) = residual_and_blocks(
        &ty.residual_and_iteration_roots(),
        &[(quote!(__out), &ty.iteration)],
    );
    let (evaluate_values, evaluate_forward, evaluate_count) = residual_and_blocks(
        &ty.evaluate_roots(),
        &[
            (quote!(__f_xdot), f_xdot),
            (quote!(__f_x), f_x),
            (quote!(__f_z), f_z),
            (quote!(__f_u), f_u),
        ],
    );
    let (iteration_values, iteration_forward, iteration_count) = {
        let roots: Vec<ExprId> = ty.iteration.exprs().collect();
        let r = routine(model, layout, &roots);
        let (prelude, stmts) = (r.prelude, r.statements);
        let w = sink_writes(&mut r.roots.into_iter(), &[(quote!(__out), &ty.iteration)]);
        let stores = &w.stores;
        (quote!(#prelude #(#stmts)* #(#stores)*), w.forward, w.count)
    };
    let outputs_code = {
        let r = routine(model, layout, &outputs);
        let (prelude, stmts) = (r.prelude, r.statements);
        let writes = r
            .roots
            .iter()
            .enumerate()
            .map(|(i, v)| quote!(__out[#i] = #v;));
        quote!(#prelude let __out = &mut __out[..#ny]; #(#stmts)* #(#writes)*)
    };
    let (output_jac_values, output_jac_forward, output_jac_count) = {
        let blocks = [
            (quote!(__h_x), h_x),
            (quote!(__h_z), h_z),
            (quote!(__h_u), h_u),
        ];
        let r = routine(model, layout, &ty.output_jacobian_roots());
        let (prelude, stmts) = (r.prelude, r.statements);
        let w = sink_writes(&mut r.roots.into_iter(), &blocks);
        let stores = &w.stores;
        (quote!(#prelude #(#stmts)* #(#stores)*), w.forward, w.count)
    };
    // Constants.
    let sym_names = |list: &[Symbol]| str_list(list.iter().map(|s| model.symbol_name(*s)));
    let state_names = sym_names(&layout.states);
    let alg_names = sym_names(&layout.algebraic);
    let input_names = sym_names(&layout.inputs);
    let output_names = str_list(ty.outputs.iter().map(|o| o.0.clone()));
    let param_names = str_list(model.params.iter().map(|p| p.label.clone()));
    let equations = str_list(ty.equation_texts.iter().cloned());
    let units = model.units().into_iter().map(|(n, u)| quote!((#n, #u)));
    let (p_xdot, p_x, p_z, p_u, p_hx) = (
        pattern(f_xdot),
        pattern(f_x),
        pattern(f_z),
        pattern(f_u),
        pattern(h_x),
    );
    let model_name = name.to_string();
    let (param_get, param_set): (Vec<TokenStream>, Vec<TokenStream>) = model
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = &p.name;
            (
                quote!(#i => ::core::option::Option::Some(params.#n),),
                quote!(#i => { params.#n = value; true }),
            )
        })
        .unzip();
    // A tracking DAE carries the coefficients of W in use; a plant only its parameters.
    let (w_field, w_init, default_impl, derives, new_doc) = match w_defaults {
        Some(per_output) => {
            let all: Vec<f64> = per_output.iter().flatten().copied().collect();
            let n = all.len();
            (
                quote! {
                    /// The coefficients of `W_i` in use, all outputs concatenated (lowest power
                    /// first, each monic); read and set through `dpc::core::TrackingDae`.
                    w_coefficients: [f64; #n],
                },
                quote!(w_coefficients: [#(#all),*],),
                quote! {
                    impl ::core::default::Default for #name {
                        /// Default parameters and the compiled `W`.
                        fn default() -> Self {
                            Self::new(::core::default::Default::default())
                        }
                    }
                },
                quote!(#[derive(Debug, Clone, Copy, PartialEq)]),
                " The tracking DAE with the given parameters and the compiled `W`.",
            )
        }
        None => (
            TokenStream::new(),
            TokenStream::new(),
            TokenStream::new(),
            quote!(#[derive(Debug, Clone, Copy, PartialEq, Default)]),
            " The model with the given parameters.",
        ),
    };
    let listing_text = ty.listing.clone();
    let listing_doc = doc_lines(&format!("```text\n{listing_text}```"));
    let na = quote!(::dpc::nalgebra);

    quote! {
        #(#attrs)*
        ///
        /// Generated by `dpc::model!` from:
        ///
        #listing_doc
        #derives
        #vis struct #name {
            /// The model's parameters.
            pub params: #params_name,
            #w_field
        }

        #default_impl

        #[allow(clippy::all, clippy::pedantic, unused_variables, unused_parens, non_snake_case)]
        impl #name {
            /// Number of states.
            pub const N_STATES: usize = #nx;
            /// Number of algebraic unknowns.
            pub const N_ALGEBRAIC: usize = #nz;
            /// Number of inputs.
            pub const N_INPUTS: usize = #nu;
            /// Number of outputs.
            pub const N_OUTPUTS: usize = #ny;
            /// Number of equations (= states + algebraic unknowns).
            pub const N_EQUATIONS: usize = #neq;
            /// The declared model, equations and outputs as readable text.
            pub const LISTING: &'static str = #listing_text;

            #[doc = #new_doc]
            pub const fn new(params: #params_name) -> Self {
                Self { params, #w_init }
            }

            // The values of the Jacobian entries of the generic `DaeModel` routines, computed
            // once per model here instead of once per sink type.
            #[inline(never)]
            fn __evaluate_values(&self, __t: f64, __x: &[f64], __xdot: &[f64], __z: &[f64], __u: &[f64], __residual: &mut [f64], __values: &mut [f64; #evaluate_count]) {
                #evaluate_values
            }

            #[inline(never)]
            fn __iteration_values(&self, __t: f64, __x: &[f64], __xdot: &[f64], __z: &[f64], __u: &[f64], __c: f64, __values: &mut [f64; #iteration_count]) {
                #iteration_values
            }

            #[inline(never)]
            fn __residual_and_iteration_values(&self, __t: f64, __x: &[f64], __xdot: &[f64], __z: &[f64], __u: &[f64], __c: f64, __residual: &mut [f64], __values: &mut [f64; #fused_count]) {
                #fused_values
            }

            #[inline(never)]
            fn __output_jacobian_values(&self, __t: f64, __x: &[f64], __z: &[f64], __u: &[f64], __values: &mut [f64; #output_jac_count]) {
                #output_jac_values
            }

            /// Residual `F(t, x, x', z, u)` in fixed-size types.
            pub fn residual_fixed(
                &self,
                t: f64,
                x: &#na::SVector<f64, #nx>,
                xdot: &#na::SVector<f64, #nx>,
                z: &#na::SVector<f64, #nz>,
                u: &#na::SVector<f64, #nu>,
            ) -> #na::SVector<f64, #neq> {
                let mut out = #na::SVector::<f64, #neq>::zeros();
                ::dpc::core::DaeModel::residual(self, t, x.as_slice(), xdot.as_slice(), z.as_slice(), u.as_slice(), out.as_mut_slice());
                out
            }

            /// Residual and the Jacobians `dF/dx'`, `dF/dx`, `dF/dz`, `dF/du` in fixed-size types.
            pub fn jacobians_fixed(
                &self,
                t: f64,
                x: &#na::SVector<f64, #nx>,
                xdot: &#na::SVector<f64, #nx>,
                z: &#na::SVector<f64, #nz>,
                u: &#na::SVector<f64, #nu>,
            ) -> ::dpc::core::model::FixedJacobians<#neq, #nx, #nz, #nu> {
                let mut j = ::dpc::core::model::FixedJacobians::<#neq, #nx, #nz, #nu>::zeros();
                ::dpc::core::DaeModel::evaluate(
                    self, t, x.as_slice(), xdot.as_slice(), z.as_slice(), u.as_slice(),
                    j.residual.as_mut_slice(), &mut j.f_xdot, &mut j.f_x, &mut j.f_z, &mut j.f_u,
                );
                j
            }

            /// The iteration matrix `[dF/dx + c dF/dx' | dF/dz]` in fixed-size types.
            pub fn iteration_matrix_fixed(
                &self,
                t: f64,
                x: &#na::SVector<f64, #nx>,
                xdot: &#na::SVector<f64, #nx>,
                z: &#na::SVector<f64, #nz>,
                u: &#na::SVector<f64, #nu>,
                c: f64,
            ) -> #na::SMatrix<f64, #neq, #neq> {
                let mut m = #na::SMatrix::<f64, #neq, #neq>::zeros();
                ::dpc::core::DaeModel::iteration_matrix(self, t, x.as_slice(), xdot.as_slice(), z.as_slice(), u.as_slice(), c, &mut m);
                m
            }

            /// Outputs `y = h(t, x, z, u)` in fixed-size types.
            pub fn outputs_fixed(
                &self,
                t: f64,
                x: &#na::SVector<f64, #nx>,
                z: &#na::SVector<f64, #nz>,
                u: &#na::SVector<f64, #nu>,
            ) -> #na::SVector<f64, #ny> {
                let mut y = #na::SVector::<f64, #ny>::zeros();
                ::dpc::core::DaeModel::outputs(self, t, x.as_slice(), z.as_slice(), u.as_slice(), y.as_mut_slice());
                y
            }

            /// Output Jacobian `dh/dx` in fixed-size types.
            pub fn output_jacobian_fixed(
                &self,
                t: f64,
                x: &#na::SVector<f64, #nx>,
                z: &#na::SVector<f64, #nz>,
                u: &#na::SVector<f64, #nu>,
            ) -> #na::SMatrix<f64, #ny, #nx> {
                let mut h_x = #na::SMatrix::<f64, #ny, #nx>::zeros();
                let mut h_z = #na::SMatrix::<f64, #ny, #nz>::zeros();
                let mut h_u = #na::SMatrix::<f64, #ny, #nu>::zeros();
                ::dpc::core::DaeModel::output_jacobians(self, t, x.as_slice(), z.as_slice(), u.as_slice(), &mut h_x, &mut h_z, &mut h_u);
                h_x
            }
        }

        #[allow(clippy::all, clippy::pedantic, unused_variables, unused_mut, unused_parens, non_snake_case)]
        impl ::dpc::core::DaeModel for #name {
            type Params = #params_name;
            fn structure(&self) -> &::dpc::core::model::Structure {
                static STRUCTURE: ::dpc::core::model::Structure = ::dpc::core::model::Structure {
                    name: ::std::borrow::Cow::Borrowed(#model_name),
                    states: ::dpc::core::model::Names::Static(#state_names),
                    algebraic: ::dpc::core::model::Names::Static(#alg_names),
                    inputs: ::dpc::core::model::Names::Static(#input_names),
                    outputs: ::dpc::core::model::Names::Static(#output_names),
                    params: ::dpc::core::model::Names::Static(#param_names),
                    equations: ::dpc::core::model::Names::Static(#equations),
                    units: ::dpc::core::model::Units::Static(&[#(#units),*]),
                    pattern_f_xdot: ::std::borrow::Cow::Borrowed(#p_xdot),
                    pattern_f_x: ::std::borrow::Cow::Borrowed(#p_x),
                    pattern_f_z: ::std::borrow::Cow::Borrowed(#p_z),
                    pattern_f_u: ::std::borrow::Cow::Borrowed(#p_u),
                    pattern_h_x: ::std::borrow::Cow::Borrowed(#p_hx),
                };
                &STRUCTURE
            }

            fn from_params(params: Self::Params) -> Self {
                Self::new(params)
            }

            fn params(&self) -> &Self::Params {
                &self.params
            }

            fn parameter(params: &Self::Params, index: usize) -> ::core::option::Option<f64> {
                match index {
                    #(#param_get)*
                    _ => ::core::option::Option::None,
                }
            }

            fn set_parameter(params: &mut Self::Params, index: usize, value: f64) -> bool {
                match index {
                    #(#param_set)*
                    _ => false,
                }
            }

            fn residual(&self, __t: f64, __x: &[f64], __xdot: &[f64], __z: &[f64], __u: &[f64], __out: &mut [f64]) {
                #residual_code
            }

            fn evaluate<__A, __B, __C, __D>(
                &self,
                __t: f64,
                __x: &[f64],
                __xdot: &[f64],
                __z: &[f64],
                __u: &[f64],
                __residual: &mut [f64],
                __f_xdot: &mut __A,
                __f_x: &mut __B,
                __f_z: &mut __C,
                __f_u: &mut __D,
            ) where
                __A: ::dpc::core::MatrixSink + ?Sized,
                __B: ::dpc::core::MatrixSink + ?Sized,
                __C: ::dpc::core::MatrixSink + ?Sized,
                __D: ::dpc::core::MatrixSink + ?Sized,
            {
                let mut __values = [0.0_f64; #evaluate_count];
                self.__evaluate_values(__t, __x, __xdot, __z, __u, __residual, &mut __values);
                #evaluate_forward
            }

            fn iteration_matrix<__S: ::dpc::core::MatrixSink + ?Sized>(
                &self,
                __t: f64,
                __x: &[f64],
                __xdot: &[f64],
                __z: &[f64],
                __u: &[f64],
                __c: f64,
                __out: &mut __S,
            ) {
                let mut __values = [0.0_f64; #iteration_count];
                self.__iteration_values(__t, __x, __xdot, __z, __u, __c, &mut __values);
                #iteration_forward
            }

            fn residual_and_iteration_matrix<__S: ::dpc::core::MatrixSink + ?Sized>(
                &self,
                __t: f64,
                __x: &[f64],
                __xdot: &[f64],
                __z: &[f64],
                __u: &[f64],
                __c: f64,
                __residual: &mut [f64],
                __out: &mut __S,
            ) {
                let mut __values = [0.0_f64; #fused_count];
                self.__residual_and_iteration_values(__t, __x, __xdot, __z, __u, __c, __residual, &mut __values);
                #fused_forward
            }

            fn outputs(&self, __t: f64, __x: &[f64], __z: &[f64], __u: &[f64], __out: &mut [f64]) {
                #outputs_code
            }

            fn output_jacobians<__A, __B, __C>(
                &self,
                __t: f64,
                __x: &[f64],
                __z: &[f64],
                __u: &[f64],
                __h_x: &mut __A,
                __h_z: &mut __B,
                __h_u: &mut __C,
            ) where
                __A: ::dpc::core::MatrixSink + ?Sized,
                __B: ::dpc::core::MatrixSink + ?Sized,
                __C: ::dpc::core::MatrixSink + ?Sized,
            {
                let mut __values = [0.0_f64; #output_jac_count];
                self.__output_jacobian_values(__t, __x, __z, __u, &mut __values);
                #output_jac_forward
            }
        }
    }
}

#[cfg(test)]
mod tests {

    fn generated(tokens: proc_macro2::TokenStream) -> String {
        let out = crate::try_expand(tokens).expect("model expands");
        prettyplease::unparse(&syn::parse2(out).expect("valid Rust"))
    }

    /// The text of the field `name: ...,` of the `Structure` in the impl block that follows
    /// `marker`.
    fn structure_field_after<'a>(code: &'a str, marker: &str, name: &str) -> &'a str {
        let from = code.find(marker).expect("marker present");
        let rest = &code[from..];
        let start = rest.find(&format!("{name}:")).expect("field present");
        let rest = &rest[start..];
        &rest[..rest.find("])").expect("field ends")]
    }

    const CART: &str = "
        Cart {
            params { m = 2.0, k = 0.5 }
            states { x, v }
            inputs { f }
            equations {
                der(x) = v;
                m * der(v) == -k * x + f;
            }
            outputs { x }
            tracking CartTracking { x: [3.0, 0.0] }
        }";

    #[test]
    fn tracking_rows_read_w_from_the_value() {
        let code = generated(CART.parse().unwrap());
        // W = s^2 + 3 s + 0: both non-leading coefficients are read, the leading 1 is not.
        assert!(
            code.contains("let coef__x__0: f64 = self.w_coefficients[0usize];"),
            "{code}"
        );
        assert!(
            code.contains("let coef__x__1: f64 = self.w_coefficients[1usize];"),
            "{code}"
        );
        assert!(!code.contains("self.w_coefficients[2usize]"), "{code}");
        // The field holds the compiled W, and the plant has no such field.
        assert!(code.contains("w_coefficients: [f64; 3usize]"), "{code}");
        assert!(
            code.contains("w_coefficients: [0f64, 3f64, 1f64]"),
            "{code}"
        );
        assert_eq!(code.matches("w_coefficients: [f64;").count(), 1, "{code}");
        assert!(code.contains("0usize => 0usize..3usize"), "{code}");
        assert!(
            code.contains("check_w_coefficients(self, output, coefficients)?"),
            "{code}"
        );
        // The entry of x in the constraint row (row 2) is structural although its default
        // coefficient is 0.
        let pattern = structure_field_after(
            &code,
            "impl ::dpc::core::DaeModel for CartTracking",
            "pattern_f_x",
        );
        assert!(pattern.contains("(2usize, 0usize)"), "{pattern}");
        // The compiled value still shows in the listing and the equation text.
        assert!(code.contains("\"der(v) + 3 * v == w_x\""), "{code}");
        assert!(code.contains("output x: W(s) = (s + 3.0)s"), "{code}");
    }

    #[test]
    fn parameters_are_reachable_by_index() {
        let code = generated(CART.parse().unwrap());
        for ty in ["Cart", "CartTracking"] {
            let from = code
                .find(&format!("impl ::dpc::core::DaeModel for {ty} "))
                .expect("impl present");
            let body = &code[from..];
            assert!(
                body.contains("fn parameter(params: &Self::Params, index: usize)"),
                "{body}"
            );
            assert!(
                body.contains("0usize => ::core::option::Option::Some(params.m)"),
                "{body}"
            );
            assert!(
                body.contains("1usize => ::core::option::Option::Some(params.k)"),
                "{body}"
            );
            assert!(body.contains("params.k = value;"), "{body}");
        }
    }

    #[test]
    fn a_model_without_parameters_matches_nothing() {
        let code = generated(
            "Free { states { x } inputs { u } equations { der(x) = u; } outputs { x } }"
                .parse()
                .unwrap(),
        );
        assert!(code.contains("_ => ::core::option::Option::None"), "{code}");
        assert!(!code.contains("w_coefficients"), "{code}");
    }
}
