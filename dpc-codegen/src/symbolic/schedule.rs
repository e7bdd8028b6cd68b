//! Common-subexpression elimination for emission: which nodes get a temporary, and in which
//! order the statements run.
//!
//! Standard reference counting on the DAG: the graph is hash-consed, so every repeated
//! subexpression is one node; a non-trivial node referenced more than once (by other reachable
//! nodes or as a root, counted over *all* roots together) is bound to a temporary, everything
//! else is inlined into its single user. Temporaries are ordered by node id, which is a
//! topological order. Trivial nodes (variables, constants, and `-v` for a variable `v`) are
//! always inlined. A single-use chain is also cut into a temporary once its inlined depth
//! reaches [`MAX_INLINE_DEPTH`], to keep the emitted expressions readable and shallow.

use std::collections::HashMap;

use super::eval::eval_node;
use super::graph::{ExprId, Graph, Node, Var};

/// Inlined expressions deeper than this are bound to a temporary.
pub const MAX_INLINE_DEPTH: usize = 12;

/// The evaluation plan for a set of roots: temporaries in order, then one expression per root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Schedule {
    /// Nodes bound to temporaries; temporary `k` holds `temps[k]` and is computed after all
    /// temporaries before it.
    pub temps: Vec<ExprId>,
    /// The roots, as given.
    pub roots: Vec<ExprId>,
    slot: HashMap<ExprId, usize>,
}

impl Schedule {
    /// The temporary index bound to `e`, if any.
    pub fn temp_of(&self, e: ExprId) -> Option<usize> {
        self.slot.get(&e).copied()
    }

    /// Every arithmetic operation the straight-line code performs, one entry per computation,
    /// in execution order (trivial nodes excluded). CSE is complete iff there are no
    /// duplicates; the length is a measure of the emitted code's cost.
    pub fn computations(&self, g: &Graph) -> Vec<ExprId> {
        let mut out = Vec::new();
        for &t in &self.temps {
            self.inlined(g, t, true, &mut out);
        }
        for &r in &self.roots {
            self.inlined(g, r, false, &mut out);
        }
        out
    }

    /// Post-order walk of the expression emitted for `e` (`top`: the statement defining `e`).
    fn inlined(&self, g: &Graph, e: ExprId, top: bool, out: &mut Vec<ExprId>) {
        if g.is_trivial(e) || (!top && self.slot.contains_key(&e)) {
            return;
        }
        for c in g.node(e).children() {
            self.inlined(g, c, false, out);
        }
        out.push(e);
    }
}

impl Graph {
    /// True for nodes never worth a temporary: variables, constants, `-v` for a variable.
    pub fn is_trivial(&self, e: ExprId) -> bool {
        match *self.node(e) {
            Node::Const(_) | Node::Var(_) => true,
            Node::Mul(c, v) => {
                self.as_constant(c) == Some(-1.0) && matches!(self.node(v), Node::Var(_))
            }
            _ => false,
        }
    }

    /// Plan the evaluation of `roots` with full CSE across all of them (see the module doc).
    /// Deterministic: depends only on the graph and the roots.
    pub fn schedule(&self, roots: &[ExprId]) -> Schedule {
        let order = self.reachable(roots);
        let mut uses: HashMap<ExprId, usize> = HashMap::with_capacity(order.len());
        for &n in &order {
            for c in self.node(n).children() {
                *uses.entry(c).or_insert(0) += 1;
            }
        }
        for &r in roots {
            *uses.entry(r).or_insert(0) += 1;
        }
        let mut slot: HashMap<ExprId, usize> = HashMap::new();
        let mut temps = Vec::new();
        // Inlined depth of each node's expression at its use site (0: a name or literal).
        let mut depth: HashMap<ExprId, usize> = HashMap::with_capacity(order.len());
        for &n in &order {
            let d = if self.is_trivial(n) {
                0
            } else {
                let own = 1 + self
                    .node(n)
                    .children()
                    .map(|c| depth[&c])
                    .max()
                    .unwrap_or(0);
                if uses[&n] > 1 || own >= MAX_INLINE_DEPTH {
                    slot.insert(n, temps.len());
                    temps.push(n);
                    0
                } else {
                    own
                }
            };
            depth.insert(n, d);
        }
        Schedule {
            temps,
            roots: roots.to_vec(),
            slot,
        }
    }

    /// Interpret a schedule the way the emitted code runs it: temporaries in order (each from
    /// its inlined expression, reading earlier temporaries), then the roots. Returns the root
    /// values; equal to [`Graph::eval_many`] bit for bit.
    pub fn eval_schedule(&self, s: &Schedule, value_of: &dyn Fn(Var) -> f64) -> Vec<f64> {
        let mut temp = Vec::with_capacity(s.temps.len());
        for &t in &s.temps {
            let v = self.eval_inlined(s, t, true, &temp, value_of);
            temp.push(v);
        }
        s.roots
            .iter()
            .map(|&r| self.eval_inlined(s, r, false, &temp, value_of))
            .collect()
    }

    fn eval_inlined(
        &self,
        s: &Schedule,
        e: ExprId,
        top: bool,
        temp: &[f64],
        value_of: &dyn Fn(Var) -> f64,
    ) -> f64 {
        if !top {
            if let Some(k) = s.temp_of(e) {
                return temp[k];
            }
        }
        eval_node(
            self.node(e),
            &|c| self.eval_inlined(s, c, false, temp, value_of),
            value_of,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::Func;
    use super::*;

    #[test]
    fn shared_nodes_get_temps_and_nothing_is_computed_twice() {
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(0)), g.var(Var(1)));
        let s = g.func(Func::Sin, x);
        let e1 = g.mul(s, y);
        let e2 = g.add(s, y);
        let d = g.diff(e1, Var(0));
        let roots = [e1, e2, d, e1];
        let sch = g.schedule(&roots);
        assert_eq!(sch.temps, vec![s, e1]);
        let comps = sch.computations(&g);
        let mut dedup = comps.clone();
        dedup.sort();
        dedup.dedup();
        assert_eq!(comps.len(), dedup.len());
        let f = |v: Var| [0.3, -1.2][v.0 as usize];
        assert_eq!(g.eval_schedule(&sch, &f), g.eval_many(&roots, &f));
    }

    #[test]
    fn long_chains_are_cut() {
        let mut g = Graph::new();
        let mut e = g.var(Var(0));
        for _ in 0..40 {
            e = g.func(Func::Sin, e);
        }
        let sch = g.schedule(&[e]);
        assert_eq!(sch.temps.len(), 40 / MAX_INLINE_DEPTH);
        assert_eq!(sch.computations(&g).len(), 40);
    }
}
