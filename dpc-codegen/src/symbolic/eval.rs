//! Numerical evaluation in `f64`, with exactly the operations the emitted code performs (so
//! tests can compare the two bit for bit).

use std::collections::HashMap;

use super::graph::{ExprId, Graph, Node, Var};

impl Graph {
    /// Value of `e` with variables taken from `value_of` (for tests and diagnostics).
    pub fn eval(&self, e: ExprId, value_of: &dyn Fn(Var) -> f64) -> f64 {
        self.eval_many(&[e], value_of)[0]
    }

    /// Values of several roots, each shared node computed once.
    pub fn eval_many(&self, roots: &[ExprId], value_of: &dyn Fn(Var) -> f64) -> Vec<f64> {
        let mut val: HashMap<ExprId, f64> = HashMap::new();
        for n in self.reachable(roots) {
            let v = eval_node(self.node(n), &|c| val[&c], value_of);
            val.insert(n, v);
        }
        roots.iter().map(|r| val[r]).collect()
    }
}

/// Value of one node from its operands' values `val(child)`.
pub(super) fn eval_node(
    node: &Node,
    val: &dyn Fn(ExprId) -> f64,
    value_of: &dyn Fn(Var) -> f64,
) -> f64 {
    match *node {
        Node::Const(c) => c,
        Node::Var(v) => value_of(v),
        Node::Add(a, b) => val(a) + val(b),
        Node::Mul(a, b) => val(a) * val(b),
        Node::Div(a, b) => val(a) / val(b),
        Node::Powi(a, n) => val(a).powi(n),
        Node::Powf(a, b) => val(a).powf(val(b)),
        Node::Func(f, a) => f.apply(val(a)),
        Node::Atan2(y, x) => val(y).atan2(val(x)),
        Node::Hypot(a, b) => val(a).hypot(val(b)),
        Node::Max(a, b) => val(a).max(val(b)),
        Node::Min(a, b) => val(a).min(val(b)),
    }
}

#[cfg(test)]
mod tests {
    use super::super::Func;
    use super::*;

    #[test]
    fn evaluates_all_node_kinds() {
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(0)), g.var(Var(1)));
        let s = g.func(Func::Sin, x);
        let h = g.hypot(x, y);
        let a = g.atan2(y, x);
        let p = g.powf(x, y);
        let q = g.div(s, h);
        let m = g.mul(q, a);
        let e = g.sub(m, p);
        let hi = g.max(x, y);
        let lo = g.min(x, y);
        let e = g.add(e, hi);
        let e = g.sub(e, lo);
        let (xv, yv) = (0.7_f64, 1.3_f64);
        let want = xv.sin() / xv.hypot(yv) * yv.atan2(xv) - xv.powf(yv) + yv - xv;
        let got = g.eval(e, &|v| if v == Var(0) { xv } else { yv });
        assert!((got - want).abs() < 1e-14, "{got} vs {want}");
    }
}
