//! Simultaneous substitution of variables by expressions.
//!
//! One pass over the reachable nodes in id order (children first), rebuilding a node through
//! the folding constructors only when one of its operands changed; linear in the DAG size.
//! Simultaneous means the replacements are not themselves substituted again: with
//! `{x -> y, y -> x}`, `x - y` becomes `y - x`.

use std::collections::HashMap;

use super::graph::{ExprId, Graph, Node, Var};

impl Graph {
    /// Replace variables by expressions (simultaneous substitution); the result is folded
    /// again, so substituting constants evaluates what becomes constant.
    pub fn substitute(&mut self, e: ExprId, map: &HashMap<Var, ExprId>) -> ExprId {
        self.substitute_many(&[e], map)[0]
    }

    /// [`Graph::substitute`] for several roots at once, sharing the work on common nodes.
    pub fn substitute_many(&mut self, roots: &[ExprId], map: &HashMap<Var, ExprId>) -> Vec<ExprId> {
        if map.is_empty() {
            return roots.to_vec();
        }
        let mut new: HashMap<ExprId, ExprId> = HashMap::new();
        for n in self.reachable(roots) {
            let node = *self.node(n);
            let r = match node {
                Node::Var(v) => map.get(&v).copied().unwrap_or(n),
                Node::Const(_) => n,
                _ if node.children().all(|c| new[&c] == c) => n,
                _ => self.rebuild(node, |c| new[&c]),
            };
            new.insert(n, r);
        }
        roots.iter().map(|r| new[r]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::super::Func;
    use super::*;

    #[test]
    fn simultaneous_and_folding() {
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(0)), g.var(Var(1)));
        let d = g.sub(x, y);
        let swapped = g.substitute(d, &HashMap::from([(Var(0), y), (Var(1), x)]));
        assert_eq!(swapped, g.sub(y, x));
        // x - y with y := x is 0
        let z = g.substitute(d, &HashMap::from([(Var(1), x)]));
        assert!(g.is_zero(z));
        let s = g.func(Func::Sin, x);
        let e = g.mul(s, y);
        let zero = g.constant(0.0);
        let two = g.constant(2.0);
        let r = g.substitute(e, &HashMap::from([(Var(0), zero), (Var(1), two)]));
        assert_eq!(g.as_constant(r), Some(0.0));
        // untouched expression keeps its id
        assert_eq!(g.substitute(e, &HashMap::from([(Var(5), two)])), e);
    }

    #[test]
    fn deep_shared_dag_is_linear() {
        // e <- sin(e) * e + e, 200 times: a tree of 3^200 leaves, a DAG of ~600 nodes.
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(0)), g.var(Var(1)));
        let mut e = x;
        for _ in 0..200 {
            let s = g.func(Func::Sin, e);
            let p = g.mul(s, e);
            e = g.add(p, e);
        }
        let one = g.constant(1.0);
        let y1 = g.add(y, one);
        let before = g.len();
        let r = g.substitute(e, &HashMap::from([(Var(0), y1)]));
        // ~3 rebuilt nodes per level, +1 because the `+ 1` of y + 1 floats outward through
        // every sum: linear, nowhere near the tree size.
        let added = g.len() - before;
        assert!(added <= 4 * 200 + 1, "{added} new nodes");
        assert!(g.size(&[r]) <= 4 * 200 + 4, "{}", g.size(&[r]));
        // Compare near 0, where the iteration e(1 + sin e) is tame (far from 0 it amplifies
        // rounding chaotically over 200 levels).
        let v = g.eval(r, &|_| -0.999);
        let w = g.eval(e, &|_| 0.001);
        assert!((v - w).abs() <= 1e-12 * w.abs(), "{v} vs {w}");
    }
}
