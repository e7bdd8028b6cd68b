//! Emission: the derived roots of a checked model as Rust items (tokens only; every
//! derivative, Jacobian block and listing is computed before, by [`crate::derive`]).
//!
//! For a model `Name` this emits
//!
//! * `NameParams`, the parameter struct with `Default` from the declared defaults
//!   (`emit/params.rs`);
//! * `Name`, the model type, with inherent fixed-size conveniences (nalgebra `SVector` /
//!   `SMatrix`) and an implementation of `dpc::core::DaeModel` whose routines take slices
//!   and write Jacobian entries into `MatrixSink`s, and parameter access by index as
//!   `match`es (`emit/model_type.rs`; its documentation carries the listing,
//!   `emit/listing.rs`); for a plant with position-constraint rows also their exact gradient,
//!   time derivative and curvature (`DaeModel::constraint_gradient` and the like, from
//!   [`crate::derive::ConstraintDerivatives`]: the curvature's second derivatives are
//!   computed by a routine like the others, their sum along the velocities in the generic
//!   method, one expression per structural entry);
//! * with a `tracking` section, the tracking DAE type, which also holds the coefficients of
//!   `W` in use in a fixed-size array (read in the routines' preludes, so nothing allocates)
//!   and implements `dpc::core::TrackingDae` (`emit/tracking.rs`);
//! * with a `references` section, the reference type (`emit/references.rs`).
//!
//! Every routine's code comes from one helper, `emit/routine.rs`: all the roots a routine
//! needs (residual rows and Jacobian entries) are scheduled together, so subexpressions are
//! shared across the residual and all Jacobians; structurally zero entries are never emitted,
//! and the non-zero positions are exported as pattern constants.
//! `residual_and_iteration_matrix` schedules the residual and the iteration matrix together
//! for Newton loops. The routines that write into sinks are generic over the sink type, so
//! their computation is emitted once, as non-generic methods (`__evaluate_values` and the
//! like) that store the entries' values into an array, and the generic methods only hand the
//! values to the sinks in a loop over the pattern: `rustc` then compiles the heavy
//! straight-line code once per model, not once per sink type. A routine too long for the
//! optimiser to handle quickly is split into parts (see `emit/routine.rs`). Every slice a
//! routine reads or writes is cut to its length once at the top, so the indexing inside
//! compiles without bounds checks. Function parameters use `__`-prefixed names, which the DSL
//! forbids in user names, so user names can be bound as plain locals without shadowing.

mod listing;
mod model_type;
mod params;
mod references;
mod routine;
mod tracking;

use crate::derive::{Block, Derived};
use crate::ir::Model;
use proc_macro2::TokenStream;
use quote::quote;

pub use crate::derive::listing;
pub use model_type::emit_dae_type;

/// Emit all items for a lowered model from its derivatives ([`crate::derive::derive`]): the
/// parameter struct, the plant type, and, with a `tracking` section, the tracking DAE; with a
/// `references` section, the reference type.
pub fn emit_model(model: &Model, derived: &Derived) -> TokenStream {
    let params = params::emit_params(model);
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
        Some(t) => tracking::emit_tracking(model, t, &derived.relative_degrees),
        None => TokenStream::new(),
    };
    let references = match &derived.references {
        Some(r) => references::emit_references(model, r),
        None => TokenStream::new(),
    };
    quote!(#params #plant_tokens #diagnostics #tracking #references)
}

/// `&[Some(2usize), None, ...]`.
fn option_list(values: &[Option<usize>]) -> TokenStream {
    let items = values.iter().map(|v| match v {
        Some(r) => quote!(::core::option::Option::Some(#r)),
        None => quote!(::core::option::Option::None),
    });
    quote!(&[#(#items),*])
}

/// The structural non-zero positions of a block as a slice literal.
fn pattern(block: &Block) -> TokenStream {
    let items = block.entries.iter().map(|(i, j, _)| quote!((#i, #j)));
    quote!(&[#(#items),*])
}

/// `&["a", "b", ...]`.
fn str_list(items: impl IntoIterator<Item = String>) -> TokenStream {
    let items: Vec<String> = items.into_iter().collect();
    quote!(&[#(#items),*])
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
