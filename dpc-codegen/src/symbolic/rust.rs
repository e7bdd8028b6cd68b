//! Emission of a [`Schedule`] as straight-line Rust: `let` statements for the temporaries,
//! then one expression per root.
//!
//! Only `f64` operators and inherent methods are used (`a.sin()`, `a.powi(3)`,
//! `y.atan2(x)`, `a.hypot(b)`, `a.signum()`, `a.max(b)`), so the code needs no imports and does not
//! allocate. Parentheses follow Rust precedence exactly and keep the DAG's evaluation order
//! (`a + (b + c)` stays), so the emitted code computes the same bits as [`Graph::eval`]
//! (checked by compiling emitted code for random expressions: identical without
//! optimisation; with optimisation LLVM may expand a constant `powi` differently, by an ulp).
//! `a + (-k) * b` is written `a - k * b` and `(-1) * a` as `-a`, which is exact in IEEE
//! arithmetic.

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;

use super::graph::{ExprId, Graph, Node, Var};
use super::schedule::Schedule;

/// Straight-line Rust code that evaluates many roots with shared subexpressions (CSE across
/// all roots).
#[derive(Clone, Debug)]
pub struct RustCode {
    /// `let tK = ...;` statements, in evaluation order.
    pub statements: Vec<TokenStream>,
    /// One expression per root, in the order given: a temporary's name, a variable, a literal
    /// or an inline expression over those.
    pub roots: Vec<TokenStream>,
}

/// Rust precedence levels of an emitted expression.
const SUM: u8 = 1;
const PROD: u8 = 2;
const UNARY: u8 = 3;
const POSTFIX: u8 = 4;

struct Emitter<'a> {
    g: &'a Graph,
    s: &'a Schedule,
    var_tokens: &'a dyn Fn(Var) -> TokenStream,
    prefix: &'a str,
}

impl Graph {
    /// Emit `let` statements for every node used more than once among all `roots` (or cut
    /// from a deep chain, see [`Graph::schedule`]), in topological order, followed by one
    /// expression per root. Variables become `var_tokens(v)`, which must be a single
    /// postfix-level expression (`x[3]`, `p.m`, `u`). Temporaries are `t0, t1, ...`.
    /// Constants are `f64` literals (`2.0_f64`, with `f64::INFINITY`/`f64::NAN` for non-finite
    /// ones). Deterministic: same graph and roots, same tokens.
    pub fn emit_rust(&self, roots: &[ExprId], var_tokens: &dyn Fn(Var) -> TokenStream) -> RustCode {
        self.emit_rust_prefixed(roots, var_tokens, "t")
    }

    /// [`Graph::emit_rust`] with temporaries named `{prefix}0, {prefix}1, ...`.
    pub fn emit_rust_prefixed(
        &self,
        roots: &[ExprId],
        var_tokens: &dyn Fn(Var) -> TokenStream,
        prefix: &str,
    ) -> RustCode {
        let s = self.schedule(roots);
        self.emit_schedule(&s, var_tokens, prefix)
    }

    /// Emit a given schedule (see [`Graph::emit_rust_prefixed`]).
    pub fn emit_schedule(
        &self,
        s: &Schedule,
        var_tokens: &dyn Fn(Var) -> TokenStream,
        prefix: &str,
    ) -> RustCode {
        let em = Emitter {
            g: self,
            s,
            var_tokens,
            prefix,
        };
        let statements = s
            .temps
            .iter()
            .enumerate()
            .map(|(k, &t)| {
                let name = em.temp(k);
                let value = em.node(t).0;
                quote!(let #name = #value;)
            })
            .collect();
        let roots = s.roots.iter().map(|&r| em.expr(r).0).collect();
        RustCode { statements, roots }
    }
}

/// A finite non-negative `f64` literal, `f64::INFINITY` or `f64::NAN`.
fn literal(v: f64) -> TokenStream {
    if v.is_nan() {
        quote!(f64::NAN)
    } else if v.is_infinite() {
        quote!(f64::INFINITY)
    } else {
        // `{:?}` is the shortest text that round-trips and always reads as a float literal
        // (`2.0`, `0.1`, `1e-7`), so `2.0_f64` carries the exact value.
        let lit: Literal = format!("{v:?}_f64")
            .parse()
            .expect("a finite f64 prints as a float literal");
        quote!(#lit)
    }
}

/// Tokens and precedence of a constant.
fn constant(v: f64) -> (TokenStream, u8) {
    if v < 0.0 {
        let m = literal(-v);
        (quote!(-#m), UNARY)
    } else {
        (literal(v), POSTFIX)
    }
}

impl Emitter<'_> {
    fn temp(&self, k: usize) -> Ident {
        Ident::new(&format!("{}{k}", self.prefix), Span::call_site())
    }

    /// The expression for `e` at a use site: its temporary if it has one.
    fn expr(&self, e: ExprId) -> (TokenStream, u8) {
        match self.s.temp_of(e) {
            Some(k) => {
                let t = self.temp(k);
                (quote!(#t), POSTFIX)
            }
            None => self.node(e),
        }
    }

    /// `e` in a context requiring precedence `min`, parenthesised if needed.
    fn operand(&self, e: ExprId, min: u8) -> TokenStream {
        let (t, p) = self.expr(e);
        if p < min {
            quote!((#t))
        } else {
            t
        }
    }

    /// `k * t` (the magnitude of an inlined negative term), with precedence.
    fn magnitude(&self, k: f64, t: Option<ExprId>) -> (TokenStream, u8) {
        match t {
            None => constant(k),
            Some(t) if k == 1.0 => self.expr(t),
            Some(t) => {
                let k = constant(k).0;
                let t = self.operand(t, UNARY);
                (quote!(#k * #t), PROD)
            }
        }
    }

    /// An inlined negative term `-k * t` (not a temporary, constant, or `+` term).
    fn negative_term(&self, e: ExprId) -> Option<(f64, Option<ExprId>)> {
        if self.s.temp_of(e).is_some() {
            return None;
        }
        self.g.negative_term(e)
    }

    /// The defining expression of node `e`.
    fn node(&self, e: ExprId) -> (TokenStream, u8) {
        match *self.g.node(e) {
            Node::Const(v) => constant(v),
            Node::Var(v) => ((self.var_tokens)(v), POSTFIX),
            Node::Add(a, b) => {
                let (a, b) = match (self.negative_term(a), self.negative_term(b)) {
                    (Some(_), None) => (b, a),
                    _ => (a, b),
                };
                let l = self.operand(a, SUM);
                match self.negative_term(b) {
                    Some((k, t)) => {
                        let (m, p) = self.magnitude(k, t);
                        let m = if p < PROD { quote!((#m)) } else { m };
                        (quote!(#l - #m), SUM)
                    }
                    None => {
                        let r = self.operand(b, PROD);
                        (quote!(#l + #r), SUM)
                    }
                }
            }
            Node::Mul(a, b) => {
                if self.g.as_constant(a) == Some(-1.0) {
                    let r = self.operand(b, UNARY);
                    (quote!(-#r), UNARY)
                } else {
                    let l = self.operand(a, PROD);
                    let r = self.operand(b, UNARY);
                    (quote!(#l * #r), PROD)
                }
            }
            Node::Div(a, b) => {
                let l = self.operand(a, PROD);
                let r = self.operand(b, UNARY);
                (quote!(#l / #r), PROD)
            }
            Node::Powi(a, n) => {
                let a = self.operand(a, POSTFIX);
                // A negative literal token is not portable across proc-macro back ends:
                // emit `-` and the magnitude.
                let m = Literal::u32_unsuffixed(n.unsigned_abs());
                let n = if n < 0 { quote!(-#m) } else { quote!(#m) };
                (quote!(#a.powi(#n)), POSTFIX)
            }
            Node::Powf(a, b) => {
                let a = self.operand(a, POSTFIX);
                let b = self.expr(b).0;
                (quote!(#a.powf(#b)), POSTFIX)
            }
            Node::Func(f, a) => {
                let a = self.operand(a, POSTFIX);
                let m = Ident::new(f.name(), Span::call_site());
                (quote!(#a.#m()), POSTFIX)
            }
            Node::Atan2(y, x) => {
                let y = self.operand(y, POSTFIX);
                let x = self.expr(x).0;
                (quote!(#y.atan2(#x)), POSTFIX)
            }
            Node::Hypot(a, b) => {
                let a = self.operand(a, POSTFIX);
                let b = self.expr(b).0;
                (quote!(#a.hypot(#b)), POSTFIX)
            }
            Node::Max(a, b) => {
                let a = self.operand(a, POSTFIX);
                let b = self.expr(b).0;
                (quote!(#a.max(#b)), POSTFIX)
            }
            Node::Min(a, b) => {
                let a = self.operand(a, POSTFIX);
                let b = self.expr(b).0;
                (quote!(#a.min(#b)), POSTFIX)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Func;
    use super::*;

    fn xv(v: Var) -> TokenStream {
        let i = Literal::usize_unsuffixed(v.0 as usize);
        quote!(x[#i])
    }

    fn text(code: &RustCode) -> String {
        let mut s = String::new();
        for st in &code.statements {
            s += &st.to_string();
            s += "\n";
        }
        for r in &code.roots {
            s += "=> ";
            s += &r.to_string();
            s += "\n";
        }
        s
    }

    #[test]
    fn emits_shared_temps_and_readable_expressions() {
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(0)), g.var(Var(1)));
        let s = g.func(Func::Sin, x);
        let e = g.mul(s, y);
        let two = g.constant(2.0);
        let ty = g.mul(two, y);
        let r = g.sub(e, ty);
        let dx = g.diff(r, Var(0));
        let dy = g.diff(r, Var(1));
        let code = g.emit_rust(&[r, dx, dy], &xv);
        assert_eq!(
            text(&code),
            "let t0 = x [0] . sin () ;\n\
             => x [1] * t0 - 2.0_f64 * x [1]\n\
             => x [1] * x [0] . cos ()\n\
             => t0 - 2.0_f64\n"
        );
    }

    #[test]
    fn precedence_and_negatives() {
        let mut g = Graph::new();
        let (x, y, z) = (g.var(Var(0)), g.var(Var(1)), g.var(Var(2)));
        let yz = g.add(y, z);
        let a = g.add(x, yz);
        let nx = g.neg(x);
        let p = g.mul(yz, x);
        let b = g.neg(p);
        let q = g.div(x, p);
        let m2 = g.constant(-2.0);
        let c = g.func(Func::Sin, nx);
        let d = g.powi(yz, 3);
        let l = g.func(Func::Ln, m2);
        let code = g.emit_rust(&[a, b, q, c, d, l], &xv);
        let t = text(&code);
        assert!(t.contains("let t0 = x [1] + x [2] ;"), "{t}");
        assert!(t.contains("let t1 = x [0] * t0 ;"), "{t}");
        assert!(t.contains("=> x [0] + t0\n"), "{t}");
        assert!(t.contains("=> - t1\n"), "{t}");
        assert!(t.contains("=> x [0] / t1\n"), "{t}");
        assert!(t.contains("=> (- x [0]) . sin ()\n"), "{t}");
        assert!(t.contains("=> t0 . powi (3)\n"), "{t}");
        let inv = g.powi(x, -2);
        let code = g.emit_rust(&[inv], &xv);
        assert_eq!(code.roots[0].to_string(), "x [0] . powi (- 2)");
        assert!(t.contains("=> (- 2.0_f64) . ln ()\n"), "{t}");
        let hi = g.max(nx, y);
        let lo = g.min(yz, x);
        let code = g.emit_rust(&[hi, lo], &xv);
        assert_eq!(code.roots[0].to_string(), "x [1] . max (- x [0])");
        assert_eq!(code.roots[1].to_string(), "x [0] . min (x [1] + x [2])");
    }
}
