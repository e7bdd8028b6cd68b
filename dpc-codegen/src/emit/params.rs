//! The parameter struct of a model.

use crate::ir::Model;
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// The parameter struct `NameParams` with `Default` from the declared values.
pub(super) fn emit_params(model: &Model) -> TokenStream {
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
