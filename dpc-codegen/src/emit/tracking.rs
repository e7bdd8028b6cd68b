//! The tracking DAE type of a model with a `tracking` section.

use super::{emit_dae_type, option_list};
use crate::derive::TrackingDerivatives;
use crate::ir::Model;
use proc_macro2::TokenStream;
use quote::quote;

/// The tracking DAE type: the plant equations, the derivatives of implicit equations its
/// steps need, and one constraint row per output, in the unknowns `(X, [Z; D; U])` with the
/// inputs `w` (`D` the higher derivatives of states, see [`crate::hirschorn::tracking_rows`]).
pub(super) fn emit_tracking(
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
