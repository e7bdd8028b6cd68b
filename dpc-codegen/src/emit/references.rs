//! The reference type of a model with a `references` section.

use super::routine::routine;
use crate::derive::{Layout, ReferenceDerivatives};
use crate::ir::Model;
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// The reference type `NameReference` for a `references` section: `xi_i(t)` and its exact
/// derivatives up to one more than the tracking DAE needs.
pub(super) fn emit_references(model: &Model, references: &ReferenceDerivatives) -> TokenStream {
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
