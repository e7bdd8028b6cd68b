//! Compiler behind `dpc::model!`.
//!
//! A plain library so that every pass can be unit-, snapshot- and property-tested without a
//! compiler invocation; `dpc-macros` is a thin shim over [`expand`]. The passes follow the
//! data flow:
//!
//! ```text
//! parse (syn + expr, spans) -> lower (names, checks, symbolic graph) -> derive -> emit (quote)
//! ```
//!
//! * [`parse`]: the DSL's syntax: the outer structure with `syn`, expressions with [`expr`];
//! * [`expr`]: the flat expression tree and its iterative parser, so that no pass recurses
//!   along the depth of the user's expressions;
//! * [`lower`]: name resolution, structural checks, lowering into [`ir::Model`];
//! * [`symbolic`]: the hash-consed expression graph, derivatives, CSE and Rust emission;
//! * [`hirschorn`]: relative degrees and the tracking rows of the stabilised Hirschorn steps;
//! * [`derive`](mod@derive): every root to be evaluated (residual, Jacobian blocks, iteration matrix,
//!   outputs, tracking DAE, references) as symbolic data, for emission and for run-time
//!   evaluation alike;
//! * [`emit`]: the derived roots as the generated parameter struct, model type and `DaeModel`
//!   implementation (tokens only).
#![warn(missing_docs)]

pub mod ctxt;
pub mod derive;
pub mod emit;
pub mod expr;
pub mod hirschorn;
pub mod ir;
pub mod lower;
pub mod names;
pub mod parse;
pub mod symbolic;
pub mod text;

use proc_macro2::TokenStream;

/// Expand the body of a `model!` invocation into Rust items, or into `compile_error!`s that
/// span the offending tokens.
pub fn expand(input: TokenStream) -> TokenStream {
    match try_expand(input) {
        Ok(tokens) => tokens,
        Err(err) => err.to_compile_error(),
    }
}

/// Like [`expand`], but returns the errors instead of turning them into tokens.
pub fn try_expand(input: TokenStream) -> syn::Result<TokenStream> {
    let (model, derived) = derive_model(input)?;
    Ok(emit::emit_model(&model, &derived))
}

/// Parse, lower, check and differentiate a model: the lowered model (whose graph holds every
/// expression) and everything to be evaluated ([`derive::Derived`]), or all errors found.
/// [`try_expand`] emits Rust from the result; a run-time model evaluates the same roots.
pub fn derive_model(input: TokenStream) -> syn::Result<(ir::Model, derive::Derived)> {
    let def = parse::parse_model(input)?;
    // One error context for the whole model: lowering, then (on a model that lowered
    // cleanly) the Hirschorn steps of its tracking section.
    let mut cx = ctxt::Ctxt::new();
    let lowered = lower::lower(def, &mut cx).map(|mut model| {
        let tracking = match model.tracking {
            Some(_) => hirschorn::tracking_rows(&mut model, &mut cx),
            None => None,
        };
        (model, tracking)
    });
    cx.check()?;
    let (mut model, tracking) = lowered.ok_or_else(lowering_without_diagnostic)?;
    let derived = derive::derive(&mut model, tracking.as_ref());
    Ok((model, derived))
}

/// The error of a lowering that failed without recording why (a bug of the macro, reported
/// as a compile error rather than a panic).
fn lowering_without_diagnostic() -> syn::Error {
    syn::Error::new(
        proc_macro2::Span::call_site(),
        "internal error: model lowering failed without a diagnostic",
    )
}

/// Lower a model without emitting code, for inspection and tests.
///
/// Expressions are parsed into flat trees ([`expr`]) and lowered and printed with explicit
/// stacks, and the passes after lowering work on the hash-consed graph: none recurses along
/// an expression's depth, so no stack has to be sized from the input.
pub fn lower_model(input: TokenStream) -> syn::Result<ir::Model> {
    let def = parse::parse_model(input)?;
    let mut cx = ctxt::Ctxt::new();
    let model = lower::lower(def, &mut cx);
    cx.check()?;
    model.ok_or_else(lowering_without_diagnostic)
}
