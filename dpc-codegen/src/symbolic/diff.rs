//! Partial derivatives: forward symbolic differentiation over the DAG.
//!
//! The reachable nodes are visited in id order (children first); the derivative of each node is
//! built from its children's derivatives by the chain rule and memoised per `(node, var)` for
//! the lifetime of the graph, so one call costs time linear in the DAG size and repeated calls
//! (a whole Jacobian, higher derivatives) reuse earlier work. A node whose operands all have a
//! zero derivative gets zero without building anything, so derivatives do not litter the graph.
//! The rules reuse the node itself where it appears in its derivative (`exp`, `sqrt`, `tan`,
//! `tanh`, `hypot`, `powf`, `/`), which CSE then shares with the residual. `max` and `min`
//! are differentiated through exact weights built from `signum` (see [`Graph::diff`]).

use std::collections::HashSet;

use super::func::Func;
use super::graph::{ExprId, Graph, Node, Var};

impl Graph {
    /// Partial derivative `∂e/∂wrt`, folded and hash-consed like any other expression.
    /// Memoised across calls. Conventions: `d|a|/da = signum(a)` (so `±1` at `a = ±0`),
    /// `d signum(a)/da = 0`, and `d max(a, b) = s a' + (1 - s) b'` (`min` with the weights
    /// swapped) where `s` is exactly `1` for `a > b`, `0` for `a < b` and `1/2` at a tie, the
    /// mean of the one-sided derivatives; `s` is built from `signum`, so its own derivative
    /// is `0` and second derivatives are `s a'' + (1 - s) b''`.
    pub fn diff(&mut self, e: ExprId, wrt: Var) -> ExprId {
        if let Some(&d) = self.diff_memo.get(&(e, wrt)) {
            return d;
        }
        let zero = self.constant(0.0);
        if !self.may_depend_on(e, wrt) {
            return zero;
        }
        // Nodes below `e` whose derivative is not memoised yet; the walk stops at memoised
        // ones, so differentiating every entry of a Jacobian row costs one pass in total.
        let mut todo = vec![e];
        let mut seen: HashSet<ExprId> = HashSet::from([e]);
        let mut stack = vec![e];
        while let Some(n) = stack.pop() {
            for c in self.node(n).children() {
                if self.may_depend_on(c, wrt)
                    && !self.diff_memo.contains_key(&(c, wrt))
                    && seen.insert(c)
                {
                    todo.push(c);
                    stack.push(c);
                }
            }
        }
        todo.sort_unstable();
        for n in todo {
            let node = *self.node(n);
            let memo = &self.diff_memo;
            let g = &*self;
            let dc = |c: ExprId| {
                if g.may_depend_on(c, wrt) {
                    memo[&(c, wrt)]
                } else {
                    zero
                }
            };
            let d = match node {
                Node::Const(_) => zero,
                Node::Var(v) => self.constant(if v == wrt { 1.0 } else { 0.0 }),
                _ if node.children().all(|c| dc(c) == zero) => zero,
                _ => {
                    let dcs: Vec<(ExprId, ExprId)> = node.children().map(|c| (c, dc(c))).collect();
                    let d = |c: ExprId| dcs.iter().find(|p| p.0 == c).expect("operand").1;
                    self.diff_rule(n, node, &d)
                }
            };
            self.diff_memo.insert((n, wrt), d);
        }
        self.diff_memo[&(e, wrt)]
    }

    /// Structurally nonzero entries `(i, j, ∂fs[i]/∂wrt[j])` of the Jacobian, row-major.
    /// Entries that are identically zero after folding are left out, so the index pairs are
    /// the sparsity pattern.
    pub fn jacobian(&mut self, fs: &[ExprId], wrt: &[Var]) -> Vec<(usize, usize, ExprId)> {
        let mut out = Vec::new();
        for (i, &f) in fs.iter().enumerate() {
            for (j, &v) in wrt.iter().enumerate() {
                let d = self.diff(f, v);
                if !self.is_zero(d) {
                    out.push((i, j, d));
                }
            }
        }
        out
    }

    /// Directional derivative `Σ_v ∂e/∂v · dir_v`, e.g. the total time derivative
    /// `d/dt h = Σ_j ∂h/∂x_j · x_j' + ∂h/∂t` with `dirs = [(x_j, x_j'), ..., (t, 1)]`.
    /// Variables listed twice contribute twice.
    pub fn directional_derivative(&mut self, e: ExprId, dirs: &[(Var, ExprId)]) -> ExprId {
        let mut sum = self.constant(0.0);
        for &(v, dv) in dirs {
            let d = self.diff(e, v);
            let term = self.mul(d, dv);
            sum = self.add(sum, term);
        }
        sum
    }

    /// The chain rule for node `e = node`, given the derivatives `d(child)` of its operands
    /// (not all zero).
    fn diff_rule(&mut self, e: ExprId, node: Node, d: &dyn Fn(ExprId) -> ExprId) -> ExprId {
        match node {
            Node::Const(_) | Node::Var(_) => unreachable!("handled by diff"),
            Node::Add(a, b) => self.add(d(a), d(b)),
            // a' b + a b'
            Node::Mul(a, b) => {
                let l = self.mul(d(a), b);
                let r = self.mul(a, d(b));
                self.add(l, r)
            }
            // (a' - (a/b) b') / b, reusing e = a/b
            Node::Div(a, b) => {
                let (da, db) = (d(a), d(b));
                let eb = self.mul(e, db);
                let num = self.sub(da, eb);
                self.div(num, b)
            }
            // n a^(n-1) a'
            Node::Powi(a, n) => {
                let p = match n.checked_sub(1) {
                    Some(m) => self.powi(a, m),
                    None => {
                        let m = self.constant(f64::from(n) - 1.0);
                        self.powf(a, m)
                    }
                };
                let k = self.constant(f64::from(n));
                let kp = self.mul(k, p);
                self.mul(kp, d(a))
            }
            Node::Powf(a, b) => {
                let (da, db) = (d(a), d(b));
                if self.is_zero(db) {
                    // Constant exponent: b a^(b-1) a', valid for negative a where a^b is.
                    let one = self.constant(1.0);
                    let bm1 = self.sub(b, one);
                    let p = self.powf(a, bm1);
                    let bp = self.mul(b, p);
                    self.mul(bp, da)
                } else {
                    // a^b (b' ln a + b a' / a)
                    let la = self.func(super::Func::Ln, a);
                    let t1 = self.mul(db, la);
                    let ba = self.mul(b, da);
                    let t2 = self.div(ba, a);
                    let s = self.add(t1, t2);
                    self.mul(e, s)
                }
            }
            Node::Func(f, a) => {
                let fp = f.derivative(self, a, e);
                self.mul(fp, d(a))
            }
            // (x y' - y x') / (x^2 + y^2)
            Node::Atan2(y, x) => {
                let l = self.mul(x, d(y));
                let r = self.mul(y, d(x));
                let num = self.sub(l, r);
                let x2 = self.powi(x, 2);
                let y2 = self.powi(y, 2);
                let den = self.add(x2, y2);
                self.div(num, den)
            }
            // (a a' + b b') / hypot(a, b)
            Node::Hypot(a, b) => {
                let l = self.mul(a, d(a));
                let r = self.mul(b, d(b));
                let num = self.add(l, r);
                self.div(num, e)
            }
            // s a' + (1 - s) b' for max, (1 - s) a' + s b' for min
            Node::Max(a, b) | Node::Min(a, b) => {
                let (s, r) = self.max_weights(a, b);
                let (wa, wb) = if matches!(node, Node::Max(..)) {
                    (s, r)
                } else {
                    (r, s)
                };
                let l = self.mul(wa, d(a));
                let r = self.mul(wb, d(b));
                self.add(l, r)
            }
        }
    }

    /// The weights `(s, 1 - s)` of `a'` and `b'` in the derivative of `max(a, b)`:
    /// `s = 1/2 + (signum(a - b) - signum(b - a)) / 4`. Both `a - b` and `b - a` are `+0` at
    /// a tie and `signum(+0) = 1`, so `s` is exactly `1`, `0` or `1/2` (the mean of the
    /// one-sided derivatives), with no rounding: `s a' + (1 - s) b'` is exactly `a'` or `b'`
    /// away from ties, whatever their magnitudes. (`(1 + signum(a - b)) / 2` would be `1` at
    /// a tie.) A NaN operand makes both weights NaN.
    fn max_weights(&mut self, a: ExprId, b: ExprId) -> (ExprId, ExprId) {
        let ab = self.sub(a, b);
        let ba = self.sub(b, a);
        let sab = self.func(Func::Sign, ab);
        let sba = self.func(Func::Sign, ba);
        let k = self.sub(sab, sba);
        let quarter = self.constant(0.25);
        let qk = self.mul(quarter, k);
        let half = self.constant(0.5);
        (self.add(half, qk), self.sub(half, qk))
    }
}

#[cfg(test)]
mod tests {
    use super::super::Func;
    use super::*;

    fn show(g: &Graph, e: ExprId) -> String {
        g.display(e, &|v| ["x", "y", "z"][v.0 as usize].to_string())
    }

    #[test]
    fn simple_rules_read_well() {
        let mut g = Graph::new();
        let x = g.var(Var(0));
        let y = g.var(Var(1));
        let s = g.func(Func::Sin, x);
        let e = g.mul(s, y);
        let dx = g.diff(e, Var(0));
        assert_eq!(show(&g, dx), "y * cos(x)");
        let dy = g.diff(e, Var(1));
        assert_eq!(dy, s);
        let dz = g.diff(e, Var(2));
        assert!(g.is_zero(dz));
        let x3 = g.powi(x, 3);
        let d3 = g.diff(x3, Var(0));
        assert_eq!(show(&g, d3), "3 * x^2");
        let c = g.func(Func::Cos, x);
        let dc = g.diff(c, Var(0));
        assert_eq!(show(&g, dc), "-sin(x)");
        let l = g.func(Func::Ln, x);
        let dl = g.diff(l, Var(0));
        assert_eq!(show(&g, dl), "1 / x");
    }

    #[test]
    fn extreme_powi_exponents_do_not_overflow() {
        let mut g = Graph::new();
        let x = g.var(Var(0));
        let p = g.powi(x, i32::MIN);
        let d = g.diff(p, Var(0));
        let v = g.eval(d, &|_| 1.0);
        assert_eq!(v, f64::from(i32::MIN));
        let q = g.powi(p, 2); // (x^MIN)^2 cannot merge exponents
        assert!(matches!(g.node(q), Node::Powi(_, 2)));
    }

    #[test]
    fn total_time_derivative() {
        let mut g = Graph::new();
        let (x, xd, t) = (Var(0), Var(1), Var(2));
        let (xe, xde, te) = (g.var(x), g.var(xd), g.var(t));
        // h = x * sin(t): dh/dt = x' sin(t) + x cos(t)
        let s = g.func(Func::Sin, te);
        let h = g.mul(xe, s);
        let one = g.constant(1.0);
        let dh = g.directional_derivative(h, &[(x, xde), (t, one)]);
        let name = |v: Var| ["x", "der(x)", "t"][v.0 as usize].to_string();
        assert_eq!(g.display(dh, &name), "der(x) * sin(t) + x * cos(t)");
    }

    #[test]
    fn jacobian_lists_structural_nonzeros() {
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(0)), g.var(Var(1)));
        let s = g.func(Func::Sin, x);
        let f0 = g.mul(s, y);
        let f1 = g.sub(y, y);
        let f2 = g.add(x, s);
        let jac = g.jacobian(&[f0, f1, f2], &[Var(0), Var(1)]);
        let pattern: Vec<(usize, usize)> = jac.iter().map(|&(i, j, _)| (i, j)).collect();
        assert_eq!(pattern, vec![(0, 0), (0, 1), (2, 0)]);
        assert_eq!(jac[1].2, s);
    }

    #[test]
    fn deep_shared_dag_is_linear() {
        let mut g = Graph::new();
        let a = g.var(Var(0));
        let mut e = a;
        for _ in 0..200 {
            let sq = g.mul(e, e);
            e = g.func(Func::Sin, sq);
        }
        let before = g.len();
        let d = g.diff(e, Var(0));
        // A handful of new nodes per level, not 2^200.
        assert!(g.len() - before < 200 * 8, "{} nodes", g.len() - before);
        assert!(g.size(&[d]) < 200 * 8);
        let d2 = g.diff(d, Var(0));
        assert!(g.size(&[d2]) < 200 * 30);
        // memoised: same answer, no new nodes
        let n = g.len();
        assert_eq!(g.diff(e, Var(0)), d);
        assert_eq!(g.len(), n);
    }
}
