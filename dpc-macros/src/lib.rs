//! The `model!` procedural macro.
//!
//! A thin shim: all parsing, symbolic work and emission live in the plain library
//! `dpc-codegen`, where they are unit-, snapshot- and property-tested. Users depend on the
//! facade crate `dpc`, which re-exports this macro as `dpc::model!`.
#![warn(missing_docs)]

use proc_macro::TokenStream;

/// Declare a DAE plant. The grammar, the generated items and the errors are documented on
/// the facade's re-export, `dpc::model!` (the page `docs/dsl.md` of the repository).
///
/// Expands to a parameter struct, a model type implementing `dpc::core::DaeModel` with
/// residual and analytic Jacobians, and (with a `tracking` block) the tracking DAE type.
/// Malformed models are reported as compile errors on the offending tokens.
#[proc_macro]
pub fn model(input: TokenStream) -> TokenStream {
    dpc_codegen::expand(input.into()).into()
}
