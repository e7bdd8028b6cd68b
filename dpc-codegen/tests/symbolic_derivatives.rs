//! Property tests of the symbolic engine against independent oracles: random expression trees
//! over three variables using every function, evaluated at random points.
//!
//! - `diff` against forward-mode dual numbers written here (independent of `diff.rs`), and
//!   against central finite differences where those are well-conditioned;
//! - the constructors' folding against direct evaluation of the tree;
//! - the CSE schedule against `eval_many` (bit for bit) and for completeness of sharing;
//! - `substitute` against evaluation with the substituted value, and `vars`/`depends_on`.
//!
//! Points where any intermediate value of the tree is not finite are skipped: there the
//! graph's identities (`0 * a = 0`, `a / a = 1`) deliberately differ from IEEE evaluation.
//! So are points on discontinuities (`abs`/`signum` at 0, the `atan2` branch cut), where
//! `0 * a = +0` may differ from IEEE's `-0` and pick the other side, and ties of `max`/`min`
//! whose operands' derivatives differ (the kink, where the rule takes their mean).

use std::collections::HashMap;

mod symbolic_common;

use dpc_codegen::symbolic::{ExprId, Func, Graph, Var};
use proptest::prelude::*;
use symbolic_common::{build, point, tree, NVARS, T};

/// Forward-mode dual number `v + d ε`, written from the textbook rules.
#[derive(Copy, Clone, Debug)]
struct Dual {
    v: f64,
    d: f64,
}

fn finite(x: Dual) -> Option<Dual> {
    (x.v.is_finite() && x.d.is_finite() && x.v.abs() < 1e8 && x.d.abs() < 1e8).then_some(x)
}

/// Value and derivative of the tree with respect to `wrt` at `x`; `None` if any intermediate
/// is not finite (or huge).
fn dual(t: &T, x: &[f64], wrt: u32) -> Option<Dual> {
    let d = |v: f64, d: f64| finite(Dual { v, d });
    match t {
        T::V(k) => d(x[*k as usize], if *k == wrt { 1.0 } else { 0.0 }),
        T::C(c) => d(*c, 0.0),
        T::Add(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            d(a.v + b.v, a.d + b.d)
        }
        T::Sub(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            d(a.v - b.v, a.d - b.d)
        }
        T::Mul(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            d(a.v * b.v, a.d * b.v + a.v * b.d)
        }
        T::Div(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            d(a.v / b.v, (a.d * b.v - a.v * b.d) / (b.v * b.v))
        }
        T::Neg(a) => {
            let a = dual(a, x, wrt)?;
            d(-a.v, -a.d)
        }
        T::Powi(a, n) => {
            let a = dual(a, x, wrt)?;
            let dv = if *n == 0 {
                0.0
            } else {
                f64::from(*n) * a.v.powi(n - 1) * a.d
            };
            d(a.v.powi(*n), dv)
        }
        T::Powf(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            let v = a.v.powf(b.v);
            if b.d == 0.0 {
                d(v, b.v * a.v.powf(b.v - 1.0) * a.d)
            } else {
                d(v, v * (b.d * a.v.ln() + b.v * a.d / a.v))
            }
        }
        T::F(f, a) => {
            let a = dual(a, x, wrt)?;
            let (v, dv) = (a.v, a.d);
            if matches!(f, Func::Abs | Func::Sign) && v == 0.0 {
                return None; // kink/jump: one-sided by convention, and ±0 may differ
            }
            let (fv, fp) = match f {
                Func::Sqrt => (v.sqrt(), 0.5 / v.sqrt()),
                Func::Exp => (v.exp(), v.exp()),
                Func::Ln => (v.ln(), 1.0 / v),
                Func::Sin => (v.sin(), v.cos()),
                Func::Cos => (v.cos(), -v.sin()),
                Func::Tan => (v.tan(), 1.0 / (v.cos() * v.cos())),
                Func::Asin => (v.asin(), 1.0 / (1.0 - v * v).sqrt()),
                Func::Acos => (v.acos(), -1.0 / (1.0 - v * v).sqrt()),
                Func::Atan => (v.atan(), 1.0 / (1.0 + v * v)),
                Func::Sinh => (v.sinh(), v.cosh()),
                Func::Cosh => (v.cosh(), v.sinh()),
                Func::Tanh => (v.tanh(), 1.0 / (v.cosh() * v.cosh())),
                Func::Abs => (v.abs(), v.signum()),
                Func::Sign => (v.signum(), 0.0),
            };
            d(fv, fp * dv)
        }
        T::Atan2(y, xx) => {
            let (y, xx) = (dual(y, x, wrt)?, dual(xx, x, wrt)?);
            if y.v == 0.0 && xx.v <= 0.0 {
                return None; // branch cut, where the sign of a folded zero decides ±pi
            }
            let r2 = xx.v * xx.v + y.v * y.v;
            d(y.v.atan2(xx.v), (xx.v * y.d - y.v * xx.d) / r2)
        }
        T::Hypot(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            let h = a.v.hypot(b.v);
            d(h, (a.v * a.d + b.v * b.d) / h)
        }
        T::Max(a, b) | T::Min(a, b) => {
            let (a, b) = (dual(a, x, wrt)?, dual(b, x, wrt)?);
            if a.v == b.v && a.d != b.d {
                return None; // the kink
            }
            let a_wins = (a.v > b.v) == matches!(t, T::Max(..));
            let v = if matches!(t, T::Max(..)) {
                a.v.max(b.v)
            } else {
                a.v.min(b.v)
            };
            d(v, if a_wins { a.d } else { b.d })
        }
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * 1f64.max(a.abs()).max(b.abs())
}

/// The operands of a node (none for a variable or constant).
fn operands(t: &T) -> Vec<&T> {
    match t {
        T::V(_) | T::C(_) => vec![],
        T::Neg(a) | T::Powi(a, _) | T::F(_, a) => vec![a],
        T::Add(a, b)
        | T::Sub(a, b)
        | T::Mul(a, b)
        | T::Div(a, b)
        | T::Powf(a, b)
        | T::Atan2(a, b)
        | T::Hypot(a, b)
        | T::Max(a, b)
        | T::Min(a, b) => vec![a, b],
    }
}

/// The value's magnitude at `x` (0 where it is not finite).
fn magnitude(t: &T, x: &[f64]) -> f64 {
    dual(t, x, u32::MAX).map_or(0.0, |d| d.v.abs())
}

/// Magnitude of the tree's intermediate values (sum of |value| over nodes): a cheap scale for
/// rounding error in expressions with cancellation.
fn scale(t: &T, x: &[f64]) -> f64 {
    magnitude(t, x) + operands(t).into_iter().map(|a| scale(a, x)).sum::<f64>()
}

/// Largest magnitude of an argument of `sin`, `cos` or `tan` in the tree (0 if none). Those
/// functions amplify a relative rounding `eps` of their argument `v` into an absolute error of
/// up to `|v| eps`: at `v = 2.7e6` (`x^-2` at `x = 6e-4`) the folded `x^-2` and the oracle's
/// `powf` differ in the last bit and `sin` of them in the ninth digit.
fn largest_trig_argument(t: &T, x: &[f64]) -> f64 {
    let own = match t {
        T::F(Func::Sin | Func::Cos | Func::Tan, a) => magnitude(a, x),
        _ => 0.0,
    };
    operands(t)
        .into_iter()
        .map(|a| largest_trig_argument(a, x))
        .fold(own, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// Folding and identities at construction do not change the value.
    #[test]
    fn construction_preserves_value(t in tree(), x in point()) {
        let mut g = Graph::new();
        let e = build(&mut g, &t);
        if let Some(want) = dual(&t, &x, u32::MAX) {
            let got = g.eval(e, &|v| x[v.0 as usize]);
            // A folded subtree may round differently from the oracle's evaluation by an ulp;
            // a trigonometric function multiplies that by its argument's magnitude.
            let tol = 1e-10 * largest_trig_argument(&t, &x).max(1.0);
            prop_assert!(close(got, want.v, tol), "{got} vs {}: {}", want.v,
                g.display(e, &|v| format!("x{}", v.0)));
        }
    }

    /// Symbolic derivatives agree with dual numbers, for every variable.
    #[test]
    fn diff_matches_dual_numbers(t in tree(), x in point()) {
        let mut g = Graph::new();
        let e = build(&mut g, &t);
        for k in 0..NVARS {
            let Some(want) = dual(&t, &x, k) else { continue };
            let de = g.diff(e, Var(k));
            let got = g.eval(de, &|v| x[v.0 as usize]);
            prop_assert!(
                close(got, want.d, 1e-9) || (got - want.d).abs() <= 1e-12 * scale(&t, &x),
                "d/dx{k}: {got} vs {}\n  e = {}\n  de = {}", want.d,
                g.display(e, &|v| format!("x{}", v.0)),
                g.display(de, &|v| format!("x{}", v.0)));
        }
    }

    /// Symbolic derivatives agree with central differences where those are reliable
    /// (two step sizes agree, so no kink or jump is straddled).
    #[test]
    fn diff_matches_finite_differences(t in tree(), x in point()) {
        let mut g = Graph::new();
        let e = build(&mut g, &t);
        for k in 0..NVARS as usize {
            if dual(&t, &x, k as u32).is_none() { continue }
            let f = |dx: f64| {
                let mut y = x.clone();
                y[k] += dx;
                dual(&t, &y, u32::MAX).map(|d| d.v)
            };
            let h = 1e-5;
            let (Some(a), Some(b), Some(c), Some(d)) = (f(h), f(-h), f(2.0 * h), f(-2.0 * h))
                else { continue };
            let (fd1, fd2) = ((a - b) / (2.0 * h), (c - d) / (4.0 * h));
            // rounding noise of the differences, large when |f| is large
            let noise = 1e3 * f64::EPSILON * a.abs().max(b.abs()).max(c.abs()).max(d.abs()) / h;
            if !close(fd1, fd2, 1e-7) && (fd1 - fd2).abs() > noise { continue }
            let de = g.diff(e, Var(k as u32));
            let got = g.eval(de, &|v| x[v.0 as usize]);
            prop_assert!(close(got, fd1, 1e-6) || (got - fd1).abs() <= noise,
                "d/dx{k}: {got} vs fd {fd1}\n  e = {}",
                g.display(e, &|v| format!("x{}", v.0)));
        }
    }

    /// The CSE schedule computes exactly what eval computes, shares every repeated node, and
    /// emission is deterministic.
    #[test]
    fn schedule_round_trip(t in tree(), x in point()) {
        let mut g = Graph::new();
        let e = build(&mut g, &t);
        let mut roots = vec![e];
        for k in 0..NVARS {
            let d = g.diff(e, Var(k));
            roots.push(d);
            roots.push(g.diff(d, Var(0)));
        }
        let s = g.schedule(&roots);
        let value_of = |v: Var| x[v.0 as usize];
        let want = g.eval_many(&roots, &value_of);
        let got = g.eval_schedule(&s, &value_of);
        for (a, b) in got.iter().zip(&want) {
            prop_assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "{a} vs {b}");
        }
        let comps = s.computations(&g);
        let mut uniq = comps.clone();
        uniq.sort();
        uniq.dedup();
        prop_assert_eq!(comps.len(), uniq.len());
        let names = |v: Var| { let i = v.0 as usize; quote::quote!(x[#i]) };
        let text = |g: &Graph| {
            let c = g.emit_rust(&roots, &names);
            let mut s: Vec<String> = c.statements.iter().map(|t| t.to_string()).collect();
            s.extend(c.roots.iter().map(|t| t.to_string()));
            s
        };
        let first = text(&g);
        prop_assert_eq!(first, text(&g.clone()));
    }

    /// Substituting an expression for a variable equals evaluating with its value.
    #[test]
    fn substitute_matches_eval(t in tree(), s in tree(), x in point()) {
        let mut g = Graph::new();
        let e = build(&mut g, &t);
        let r = build(&mut g, &s);
        let sub = g.substitute(e, &HashMap::from([(Var(0), r)]));
        let Some(rv) = dual(&s, &x, u32::MAX) else { return Ok(()) };
        let mut y = x.clone();
        y[0] = rv.v;
        let Some(want) = dual(&t, &y, u32::MAX) else { return Ok(()) };
        let got = g.eval(sub, &|v| x[v.0 as usize]);
        prop_assert!(close(got, want.v, 1e-9) || (got - want.v).abs() <= 1e-12 * scale(&t, &y),
            "{got} vs {}", want.v);
        // x0 survives only through the substituted expression
        prop_assert_eq!(g.depends_on(sub, Var(0)), g.vars(sub).contains(&Var(0)));
        if !g.depends_on(r, Var(0)) {
            prop_assert!(!g.depends_on(sub, Var(0)));
        }
    }

    /// Canonical forms: commutative constructors ignore operand order, and the identities
    /// hold on arbitrary subexpressions, not just leaves.
    #[test]
    fn algebraic_laws_hold_structurally(a in tree(), b in tree()) {
        let mut g = Graph::new();
        let (ea, eb) = (build(&mut g, &a), build(&mut g, &b));
        prop_assert_eq!(g.add(ea, eb), g.add(eb, ea));
        prop_assert_eq!(g.mul(ea, eb), g.mul(eb, ea));
        prop_assert_eq!(g.hypot(ea, eb), g.hypot(eb, ea));
        prop_assert_eq!(g.max(ea, eb), g.max(eb, ea));
        prop_assert_eq!(g.min(ea, eb), g.min(eb, ea));
        prop_assert_eq!(g.max(ea, ea), ea);
        let d = g.sub(ea, ea);
        prop_assert!(g.is_zero(d));
        let n = g.neg(ea);
        prop_assert_eq!(g.neg(n), ea);
        let (zero, one) = (g.constant(0.0), g.constant(1.0));
        prop_assert_eq!(g.add(ea, zero), ea);
        prop_assert_eq!(g.mul(one, ea), ea);
        prop_assert_eq!(g.mul(ea, zero), zero);
        if !g.is_zero(ea) {
            let q = g.div(ea, ea);
            prop_assert_eq!(q, one);
        }
        prop_assert_eq!(g.powi(ea, 1), ea);
        // constants gather, powers merge
        let (c1, c2, c3, c6) = (g.constant(1.0), g.constant(2.0), g.constant(3.0), g.constant(6.0));
        // Folded constants may round differently ((c + 1) + 2 vs c + 3): same shape, and the
        // same value up to rounding. Rounding is relative to the magnitude of what was summed
        // (`magnitude`), not to the result, which may cancel to nearly nothing.
        const AT: [f64; NVARS as usize] = [0.3, -0.7, 1.1];
        let same = |g: &Graph, l: ExprId, r: ExprId, magnitude: f64| {
            let at = |v: Var| AT[v.0 as usize];
            let (vl, vr) = (g.eval(l, &at), g.eval(r, &at));
            let tol = 1e-14 * magnitude.max(vl.abs()).max(vr.abs());
            l == r
                || (g.size(&[l]) == g.size(&[r])
                    && (vl == vr || (vl - vr).abs() <= tol || (vl.is_nan() && vr.is_nan())))
        };
        let summed = scale(&a, &AT) + 3.0;
        let a1 = g.add(ea, c1);
        let lhs = g.add(a1, c2);
        let rhs = g.add(ea, c3);
        prop_assert!(same(&g, lhs, rhs, summed));
        let a3 = g.mul(c3, ea);
        let lhs = g.mul(c2, a3);
        let rhs = g.mul(c6, ea);
        prop_assert!(same(&g, lhs, rhs, 0.0));
        // (for constants, folding of c^2 but not of an overflowing c^6 may differ)
        if g.as_constant(ea).is_none() {
            let p2 = g.powi(ea, 2);
            let lhs = g.powi(p2, 3);
            prop_assert_eq!(lhs, g.powi(ea, 6));
        }
        let sq = g.mul(ea, ea);
        prop_assert_eq!(sq, g.powi(ea, 2));
        // identity substitution keeps the node
        let x0 = g.var(Var(0));
        let same = g.substitute(ea, &HashMap::from([(Var(0), x0)]));
        prop_assert_eq!(same, ea);
        // rebuilding the same tree in a fresh graph gives the same printed form
        let mut h = Graph::new();
        let ha = build(&mut h, &a);
        let name = |v: Var| format!("x{}", v.0);
        prop_assert_eq!(g.display(ea, &name), h.display(ha, &name));
    }

    /// `vars` is exactly the set `depends_on` accepts; a variable not in it has zero
    /// derivative.
    #[test]
    fn vars_are_consistent(t in tree()) {
        let mut g = Graph::new();
        let e = build(&mut g, &t);
        let vs = g.vars(e);
        for k in 0..NVARS {
            prop_assert_eq!(vs.contains(&Var(k)), g.depends_on(e, Var(k)));
            if !vs.contains(&Var(k)) {
                let d = g.diff(e, Var(k));
                prop_assert!(g.is_zero(d));
            }
        }
    }
}

/// `d max(a, b)` is exactly `a'` where `a > b` and `b'` where `a < b`, whatever the
/// magnitudes, and the mean of the two at a tie; `min` the other way round. The weights are
/// built from `signum`, so second derivatives are the chosen branch's.
#[test]
fn max_and_min_derivatives_pick_a_branch_exactly() {
    let mut g = Graph::new();
    let (x, y) = (g.var(Var(0)), g.var(Var(1)));
    let big = g.constant(1e20);
    let bx = g.mul(big, x);
    let hi = g.max(bx, y);
    let lo = g.min(bx, y);
    let at = |p: [f64; 2]| move |v: Var| p[v.0 as usize];
    let grad = |g: &mut Graph, e: ExprId, p: [f64; 2]| {
        let dx = g.diff(e, Var(0));
        let dy = g.diff(e, Var(1));
        [g.eval(dx, &at(p)), g.eval(dy, &at(p))]
    };
    // a = 1e20 x against b = y: above, below and at the tie (and across a sign change)
    for (p, a_above) in [
        ([1.0, 1.0], true),
        ([-1e-30, 1.0], false),
        ([1e-20, 1.0], false),
    ] {
        let (ga, gb) = ([1e20, 0.0], [0.0, 1.0]);
        if p == [1e-20, 1.0] {
            // 1e20 * 1e-20 rounds to exactly 1: a tie
            assert_eq!(g.eval(bx, &at(p)), 1.0);
            assert_eq!(grad(&mut g, hi, p), [0.5e20, 0.5]);
            assert_eq!(grad(&mut g, lo, p), [0.5e20, 0.5]);
            continue;
        }
        let (gh, gl) = if a_above { (ga, gb) } else { (gb, ga) };
        assert_eq!(grad(&mut g, hi, p), gh, "max at {p:?}");
        assert_eq!(grad(&mut g, lo, p), gl, "min at {p:?}");
    }
    // values of very different magnitude: no cancellation
    let one = g.constant(1.0);
    let e = g.min(bx, one);
    assert_eq!(g.eval(e, &at([1.0, 0.0])), 1.0);
    let e = g.max(bx, one);
    assert_eq!(g.eval(e, &at([1.0, 0.0])), 1e20);
    // second derivatives: of max(x^3, y) in x, 6 x above and 0 below
    let x3 = g.powi(x, 3);
    let e = g.max(x3, y);
    let d1 = g.diff(e, Var(0));
    let d2 = g.diff(d1, Var(0));
    assert_eq!(g.eval(d2, &at([2.0, 1.0])), 12.0);
    assert_eq!(g.eval(d2, &at([0.5, 1.0])), 0.0);
    let dxy = g.diff(d1, Var(1));
    assert!(
        g.is_zero(dxy),
        "the weights' derivatives vanish structurally"
    );
    // and the total derivative d/dt max(x^3, y) = 3 x^2 x' or y'
    let (xd, yd) = (g.var(Var(2)), g.var(Var(3)));
    let dt = g.directional_derivative(e, &[(Var(0), xd), (Var(1), yd)]);
    let at4 = |p: [f64; 4]| move |v: Var| p[v.0 as usize];
    assert_eq!(g.eval(dt, &at4([2.0, 1.0, 0.5, 7.0])), 6.0);
    assert_eq!(g.eval(dt, &at4([0.5, 1.0, 0.5, 7.0])), 7.0);
    // a NaN operand is ignored by the value, as by f64::max
    let nan = g.eval(e, &at([f64::NAN, 1.0]));
    assert_eq!(nan, 1.0);
}
