//! The type implementing `dpc::core::DaeModel` for a plant or its tracking DAE: the struct,
//! its fixed-size conveniences, the non-generic routines that compute the Jacobians' values
//! and the generic ones that hand them to sinks.

use super::listing::listing_doc;
use super::routine::{routine_writing, Output, RoutineCode};
use super::{pattern, str_list};
use crate::derive::{Block, DaeDerivatives};
use crate::ir::{Model, Symbol};
use crate::symbolic::ExprId;
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// The generic half of a routine's Jacobian writes: the values are stored into an array
/// `__values` in block order (by the non-generic method whose code [`routine_writing`]
/// emits, the heavy code compiled once per model), and a small generic loop hands them to the
/// sinks, block by block in row-major order, as the pattern constants list them. The sinks
/// receive the same `set` calls with the same values as from straight-line writes. Returns
/// the loop and the number of values.
fn sink_forwarding(blocks: &[(TokenStream, &Block)]) -> (TokenStream, usize) {
    let mut forward = TokenStream::new();
    let mut count = 0usize;
    for (sink, b) in blocks {
        let start = count;
        count += b.entries.len();
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
    (forward, count)
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

    // Routines: each schedules all of its roots together (CSE across them); the parts of
    // long ones go into modules named after the type and the routine.
    let mut parts = TokenStream::new();
    let mut code = |what: &str, roots: &[ExprId], outputs: &[Output]| {
        let module = format_ident!("__dpc_{}_{}", name, what);
        let RoutineCode { body, parts: p } =
            routine_writing(model, layout, roots, outputs, &module);
        parts.extend(p);
        body
    };
    let out = |name: TokenStream, len: usize, cut: bool| Output { name, len, cut };
    let residual_code = code("residual", residuals, &[out(quote!(__out), neq, true)]);
    // The routines that write into sinks: the body of the non-generic values method, the
    // generic forwarding and the values' count.
    let (fused_forward, fused_count) = sink_forwarding(&[(quote!(__out), &ty.iteration)]);
    let fused_values = code(
        "fused",
        &ty.residual_and_iteration_roots(),
        &[
            out(quote!(__residual), neq, true),
            out(quote!(__values), fused_count, false),
        ],
    );
    let (evaluate_forward, evaluate_count) = sink_forwarding(&[
        (quote!(__f_xdot), f_xdot),
        (quote!(__f_x), f_x),
        (quote!(__f_z), f_z),
        (quote!(__f_u), f_u),
    ]);
    let evaluate_values = code(
        "evaluate",
        &ty.evaluate_roots(),
        &[
            out(quote!(__residual), neq, true),
            out(quote!(__values), evaluate_count, false),
        ],
    );
    let (iteration_forward, iteration_count) = sink_forwarding(&[(quote!(__out), &ty.iteration)]);
    let iteration_values = code(
        "iteration",
        &ty.iteration.exprs().collect::<Vec<_>>(),
        &[out(quote!(__values), iteration_count, false)],
    );
    let (mass_forward, mass_count) = sink_forwarding(&[(quote!(__out), f_xdot)]);
    let mass_values = code(
        "mass",
        &f_xdot.exprs().collect::<Vec<_>>(),
        &[out(quote!(__values), mass_count, false)],
    );
    let outputs_code = code("outputs", &outputs, &[out(quote!(__out), ny, true)]);
    let (output_jac_forward, output_jac_count) = sink_forwarding(&[
        (quote!(__h_x), h_x),
        (quote!(__h_z), h_z),
        (quote!(__h_u), h_u),
    ]);
    let output_jac_values = code(
        "output_jacobians",
        &ty.output_jacobian_roots(),
        &[out(quote!(__values), output_jac_count, false)],
    );
    // The position constraints' exact derivatives (plants with such rows only).
    let c = &ty.constraints;
    let (constraint_values, constraint_methods) = if c.is_empty() {
        (TokenStream::new(), TokenStream::new())
    } else {
        let (gradient_forward, gradient_count) = sink_forwarding(&[(quote!(__out), &c.gradient)]);
        let gradient_values = code(
            "constraint_gradient",
            &c.gradient.exprs().collect::<Vec<_>>(),
            &[out(quote!(__values), gradient_count, false)],
        );
        let time_count = c.time_derivative.len();
        let (time_values, time_body) = if time_count == 0 {
            (TokenStream::new(), TokenStream::new())
        } else {
            let roots: Vec<ExprId> = c.time_derivative.iter().map(|d| d.1).collect();
            let values = code(
                "constraint_time_derivative",
                &roots,
                &[out(quote!(__values), time_count, false)],
            );
            let rows = c.time_derivative.iter().map(|d| d.0);
            (
                quote! {
                    #[inline(never)]
                    fn __constraint_time_derivative_values(&self, __t: f64, __x: &[f64], __values: &mut [f64; #time_count]) {
                        #values
                    }
                },
                quote! {
                    let mut __values = [0.0_f64; #time_count];
                    self.__constraint_time_derivative_values(__t, __x, &mut __values);
                    const __ROWS: &[usize] = &[#(#rows),*];
                    for (&__g, &__v) in __ROWS.iter().zip(&__values) {
                        __out[__g] = __v;
                    }
                },
            )
        };
        let curvature_roots = c.curvature_roots();
        let curvature_count = curvature_roots.len();
        let (curvature_values, curvature_body) = if curvature_count == 0 {
            (TokenStream::new(), TokenStream::new())
        } else {
            let values = code(
                "constraint_curvature",
                &curvature_roots,
                &[out(quote!(__values), curvature_count, false)],
            );
            // Per structural entry, sum_j H_jk v_j + H_tk over the non-zero terms.
            let sets = c.curvature_entries().into_iter().map(|e| {
                let (g, k) = (e.row, e.col);
                let terms = e.terms.iter().map(|&(r, j)| quote!(__values[#r] * __v[#j]));
                let time = e.time_term.map(|r| quote!(__values[#r]));
                let sum = terms.chain(time);
                quote!(__out.set(#g, #k, #(#sum)+*);)
            });
            (
                quote! {
                    #[inline(never)]
                    fn __constraint_curvature_values(&self, __t: f64, __x: &[f64], __values: &mut [f64; #curvature_count]) {
                        #values
                    }
                },
                quote! {
                    let __v = &__v[..#nx];
                    let mut __values = [0.0_f64; #curvature_count];
                    self.__constraint_curvature_values(__t, __x, &mut __values);
                    #(#sets)*
                },
            )
        };
        (
            quote! {
                // The position constraints' exact derivatives (`DaeModel::constraint_gradient`
                // and the like), computed once per model here.
                #[inline(never)]
                fn __constraint_gradient_values(&self, __t: f64, __x: &[f64], __values: &mut [f64; #gradient_count]) {
                    #gradient_values
                }
                #time_values
                #curvature_values
            },
            quote! {
                fn constraint_gradient<__S: ::dpc::core::MatrixSink + ?Sized>(
                    &self,
                    __t: f64,
                    __x: &[f64],
                    __z: &[f64],
                    __u: &[f64],
                    __out: &mut __S,
                ) -> bool {
                    let mut __values = [0.0_f64; #gradient_count];
                    self.__constraint_gradient_values(__t, __x, &mut __values);
                    #gradient_forward
                    true
                }

                fn constraint_time_derivative(
                    &self,
                    __t: f64,
                    __x: &[f64],
                    __z: &[f64],
                    __u: &[f64],
                    __out: &mut [f64],
                ) -> bool {
                    #time_body
                    true
                }

                fn constraint_curvature<__S: ::dpc::core::MatrixSink + ?Sized>(
                    &self,
                    __t: f64,
                    __x: &[f64],
                    __z: &[f64],
                    __u: &[f64],
                    __v: &[f64],
                    __out: &mut __S,
                ) -> bool {
                    #curvature_body
                    true
                }
            },
        )
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
    let listing_doc = listing_doc(&listing_text);
    let na = quote!(::dpc::nalgebra);

    quote! {
        #parts

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
            fn __mass_values(&self, __t: f64, __x: &[f64], __xdot: &[f64], __z: &[f64], __u: &[f64], __values: &mut [f64; #mass_count]) {
                #mass_values
            }

            #[inline(never)]
            fn __residual_and_iteration_values(&self, __t: f64, __x: &[f64], __xdot: &[f64], __z: &[f64], __u: &[f64], __c: f64, __residual: &mut [f64], __values: &mut [f64; #fused_count]) {
                #fused_values
            }

            #[inline(never)]
            fn __output_jacobian_values(&self, __t: f64, __x: &[f64], __z: &[f64], __u: &[f64], __values: &mut [f64; #output_jac_count]) {
                #output_jac_values
            }

            #constraint_values

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

            fn mass_matrix<__S: ::dpc::core::MatrixSink + ?Sized>(
                &self,
                __t: f64,
                __x: &[f64],
                __xdot: &[f64],
                __z: &[f64],
                __u: &[f64],
                __out: &mut __S,
            ) -> bool {
                let mut __values = [0.0_f64; #mass_count];
                self.__mass_values(__t, __x, __xdot, __z, __u, &mut __values);
                #mass_forward
                true
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

            #constraint_methods
        }
    }
}
