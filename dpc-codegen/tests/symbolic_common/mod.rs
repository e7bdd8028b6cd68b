//! Random expression trees shared by the symbolic property tests: a tree type, a proptest
//! strategy covering every constructor and function (with arguments kept in domain, and
//! some subtrees used twice so the graph shares them), and its construction in a graph.
#![allow(dead_code)]

use dpc_codegen::symbolic::{ExprId, Func, Graph, Var};
use proptest::prelude::*;

pub const NVARS: u32 = 3;

/// A random expression, built into a graph through the public constructors.
#[derive(Clone, Debug)]
pub enum T {
    V(u32),
    C(f64),
    Add(Box<T>, Box<T>),
    Sub(Box<T>, Box<T>),
    Mul(Box<T>, Box<T>),
    Div(Box<T>, Box<T>),
    Neg(Box<T>),
    Powi(Box<T>, i32),
    Powf(Box<T>, Box<T>),
    F(Func, Box<T>),
    Atan2(Box<T>, Box<T>),
    Hypot(Box<T>, Box<T>),
    Max(Box<T>, Box<T>),
    Min(Box<T>, Box<T>),
}

fn bx(t: T) -> Box<T> {
    Box::new(t)
}

/// `t^2 + 1/2`: keeps arguments of sqrt, ln and powf bases positive.
fn positive(t: T) -> T {
    T::Add(bx(T::Powi(bx(t), 2)), bx(T::C(0.5)))
}

/// `0.9 tanh(t)`: keeps arguments of asin and acos inside (-1, 1).
fn unit(t: T) -> T {
    T::Mul(bx(T::C(0.9)), bx(T::F(Func::Tanh, bx(t))))
}

pub fn tree() -> impl Strategy<Value = T> {
    let leaf = prop_oneof![
        (0..NVARS).prop_map(T::V),
        (-6i32..=6).prop_map(|k| T::C(f64::from(k) * 0.5)),
    ];
    leaf.prop_recursive(4, 32, 2, |inner| {
        let pair = (inner.clone(), inner.clone());
        prop_oneof![
            pair.clone().prop_map(|(a, b)| T::Add(bx(a), bx(b))),
            pair.clone().prop_map(|(a, b)| T::Sub(bx(a), bx(b))),
            pair.clone().prop_map(|(a, b)| T::Mul(bx(a), bx(b))),
            pair.clone().prop_map(|(a, b)| T::Div(bx(a), bx(b))),
            inner.clone().prop_map(|a| T::Neg(bx(a))),
            (inner.clone(), -3i32..=4).prop_map(|(a, n)| T::Powi(bx(a), n)),
            pair.clone()
                .prop_map(|(a, b)| T::Powf(bx(positive(a)), bx(b))),
            // constant exponents on any base (negative bases are fine for integral ones)
            (inner.clone(), -4i32..=6)
                .prop_map(|(a, k)| T::Powf(bx(a), bx(T::C(f64::from(k) * 0.5)))),
            (inner.clone(), 0..Func::ALL.len()).prop_map(|(a, k)| {
                let f = Func::ALL[k];
                let a = match f {
                    Func::Sqrt | Func::Ln => positive(a),
                    Func::Asin | Func::Acos => unit(a),
                    _ => a,
                };
                T::F(f, bx(a))
            }),
            pair.clone().prop_map(|(a, b)| T::Atan2(bx(a), bx(b))),
            pair.clone().prop_map(|(a, b)| T::Hypot(bx(a), bx(b))),
            pair.clone().prop_map(|(a, b)| T::Max(bx(a), bx(b))),
            pair.clone().prop_map(|(a, b)| T::Min(bx(a), bx(b))),
            // the same subtree used twice: a shared node in the DAG
            inner
                .clone()
                .prop_map(|a| T::Mul(bx(T::F(Func::Sin, bx(a.clone()))), bx(a))),
            inner.clone().prop_map(|a| T::Div(
                bx(a.clone()),
                bx(T::Add(bx(T::C(1.0)), bx(T::Powi(bx(a), 2))))
            )),
            pair.prop_map(|(a, b)| T::Sub(
                bx(T::Mul(bx(a.clone()), bx(b.clone()))),
                bx(T::Hypot(bx(a), bx(b)))
            )),
        ]
    })
}

pub fn build(g: &mut Graph, t: &T) -> ExprId {
    match t {
        T::V(k) => g.var(Var(*k)),
        T::C(c) => g.constant(*c),
        T::Add(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.add(a, b)
        }
        T::Sub(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.sub(a, b)
        }
        T::Mul(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.mul(a, b)
        }
        T::Div(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.div(a, b)
        }
        T::Neg(a) => {
            let a = build(g, a);
            g.neg(a)
        }
        T::Powi(a, n) => {
            let a = build(g, a);
            g.powi(a, *n)
        }
        T::Powf(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.powf(a, b)
        }
        T::F(f, a) => {
            let a = build(g, a);
            g.func(*f, a)
        }
        T::Atan2(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.atan2(a, b)
        }
        T::Hypot(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.hypot(a, b)
        }
        T::Max(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.max(a, b)
        }
        T::Min(a, b) => {
            let (a, b) = (build(g, a), build(g, b));
            g.min(a, b)
        }
    }
}

/// A random point in [-2, 2]^NVARS.
pub fn point() -> impl Strategy<Value = Vec<f64>> {
    proptest::collection::vec(-2.0f64..2.0, NVARS as usize)
}
