//! The API contract with the `model!` front end, pinned by signature: if a name or a
//! signature drifts, this file stops compiling.

use std::collections::{BTreeSet, HashMap};

use dpc_codegen::symbolic::{ExprId, Func, Graph, RustCode, Var};
use proc_macro2::TokenStream;

type VarTokens<'a> = &'a dyn Fn(Var) -> TokenStream;

#[test]
fn contract_signatures() {
    let _: fn() -> Graph = Graph::new;
    let _: fn(&mut Graph, f64) -> ExprId = Graph::constant;
    let _: fn(&mut Graph, Var) -> ExprId = Graph::var;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::add;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::sub;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::mul;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::div;
    let _: fn(&mut Graph, ExprId) -> ExprId = Graph::neg;
    let _: fn(&mut Graph, ExprId, i32) -> ExprId = Graph::powi;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::powf;
    let _: fn(&mut Graph, Func, ExprId) -> ExprId = Graph::func;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::atan2;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::hypot;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::max;
    let _: fn(&mut Graph, ExprId, ExprId) -> ExprId = Graph::min;
    let _: fn(&Graph, ExprId) -> Option<f64> = Graph::as_constant;
    let _: fn(&Graph, ExprId) -> bool = Graph::is_zero;
    let _: fn(&mut Graph, ExprId, Var) -> ExprId = Graph::diff;
    let _: fn(&mut Graph, ExprId, &HashMap<Var, ExprId>) -> ExprId = Graph::substitute;
    let _: fn(&Graph, ExprId) -> BTreeSet<Var> = Graph::vars;
    let _: fn(&Graph, ExprId, Var) -> bool = Graph::depends_on;
    let _: fn(&Graph, ExprId, &dyn Fn(Var) -> f64) -> f64 = Graph::eval;
    let _: fn(&Graph, &[ExprId]) -> usize = Graph::size;
    let _: fn(&Graph, ExprId, &dyn Fn(Var) -> String) -> String = Graph::display;
    let _: fn(&Graph, &[ExprId], VarTokens) -> RustCode = Graph::emit_rust;
    let _: fn(&str) -> Option<Func> = Func::from_name;
    let _: fn(Func) -> &'static str = Func::name;
    let code = RustCode {
        statements: Vec::<TokenStream>::new(),
        roots: Vec::<TokenStream>::new(),
    };
    assert!(code.statements.is_empty() && code.roots.is_empty());
    let v = Var(3);
    assert_eq!(v.0, 3);
    for (name, f) in [
        ("sqrt", Func::Sqrt),
        ("exp", Func::Exp),
        ("ln", Func::Ln),
        ("sin", Func::Sin),
        ("cos", Func::Cos),
        ("tan", Func::Tan),
        ("asin", Func::Asin),
        ("acos", Func::Acos),
        ("atan", Func::Atan),
        ("sinh", Func::Sinh),
        ("cosh", Func::Cosh),
        ("tanh", Func::Tanh),
        ("abs", Func::Abs),
    ] {
        assert_eq!(Func::from_name(name), Some(f));
        assert_eq!(f.name(), name);
    }
}
