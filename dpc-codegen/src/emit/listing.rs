//! The listing of a generated type (computed by [`crate::derive::listing`]) as its
//! documentation.

use proc_macro2::TokenStream;
use quote::quote;

/// `text` as a fenced `text` block of `#[doc]` lines.
pub(super) fn listing_doc(text: &str) -> TokenStream {
    let lines = format!("```text\n{text}```");
    let lines = lines.lines().map(|l| {
        let l = format!(" {l}");
        quote!(#[doc = #l])
    });
    quote!(#(#lines)*)
}
