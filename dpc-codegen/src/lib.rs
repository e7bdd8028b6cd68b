//! Compiler behind `dpc::model!`: parse -> model IR -> symbolic DAG -> transforms -> emit.

pub mod symbolic;

use proc_macro2::TokenStream;

/// Expand the body of a `model!` invocation into Rust items, or into `compile_error!`s.
pub fn expand(input: TokenStream) -> TokenStream {
    let _ = input;
    quote::quote!(compile_error!("dpc::model! is not implemented yet");)
}
