//! The hash-consed expression DAG and its constructors.
//!
//! Every node is interned: constructing a node that already exists returns the existing
//! [`ExprId`], so structural equality is id equality and common subexpressions are shared from
//! the start. Because a node can only refer to nodes that existed before it, ids are a
//! topological order of the DAG; every pass (diff, substitution, evaluation, scheduling) walks
//! the reachable nodes in increasing id order instead of recursing.
//!
//! Constructors fold constants and apply identities before interning (see [`Graph::add`],
//! [`Graph::mul`], ...). The identities are the usual symbolic ones and deliberately ignore
//! IEEE special cases: `0 * a = 0`, `0 / a = 0`, `a / a = 1`, `a - a = 0` and `a^n * a^-n = 1`
//! hold even where `a` would evaluate to NaN, infinity or zero. Folding a fully constant
//! subexpression is skipped when the result is not finite (`ln(0)`, `1/0`, `sqrt(-1)`), so such
//! a value stays visible as an expression and is computed (as inf/NaN) at run time.

use std::collections::{HashMap, HashSet};

use super::func::Func;

/// Index of a variable in a table owned by the caller (the graph does not know what it means).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Var(pub u32);

/// Handle to a node in a [`Graph`]. Ids are only meaningful in the graph that made them.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(u32);

impl ExprId {
    /// Position of the node in its graph; children always have smaller indices than parents.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// One node of the DAG, as stored. Read it with [`Graph::node`].
///
/// Canonical forms: in [`Node::Add`] a constant operand comes second, in [`Node::Mul`] first;
/// otherwise operands of commutative nodes are sorted by id. Subtraction is `a + (-1) * b` and
/// negation `(-1) * a`; printing and emission turn these back into `a - b` and `-a`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Node {
    /// A constant; never `-0.0`.
    Const(f64),
    /// A caller-defined variable.
    Var(Var),
    /// `a + b`.
    Add(ExprId, ExprId),
    /// `a * b`.
    Mul(ExprId, ExprId),
    /// `a / b`.
    Div(ExprId, ExprId),
    /// `a^n` for an integer `n` (`f64::powi`).
    Powi(ExprId, i32),
    /// `a^b` (`f64::powf`).
    Powf(ExprId, ExprId),
    /// `f(a)` for an elementary function.
    Func(Func, ExprId),
    /// `atan2(y, x)`, the angle of the point `(x, y)` (`y.atan2(x)`).
    Atan2(ExprId, ExprId),
    /// `sqrt(a^2 + b^2)` without overflow (`a.hypot(b)`).
    Hypot(ExprId, ExprId),
    /// The larger of `a` and `b`, ignoring a NaN operand (`a.max(b)`, `f64::max`).
    Max(ExprId, ExprId),
    /// The smaller of `a` and `b`, ignoring a NaN operand (`a.min(b)`, `f64::min`).
    Min(ExprId, ExprId),
}

/// The bit standing for `v` in dependency masks (variables share bits modulo 64).
fn var_bit(v: Var) -> u64 {
    1 << (v.0 % 64)
}

/// Interning key: a node with its constant as bits, so it can be hashed.
type Key = (u8, u64, u64);

impl Node {
    fn key(&self) -> Key {
        let id = |e: ExprId| u64::from(e.0);
        match *self {
            Node::Const(v) => (0, v.to_bits(), 0),
            Node::Var(v) => (1, u64::from(v.0), 0),
            Node::Add(a, b) => (2, id(a), id(b)),
            Node::Mul(a, b) => (3, id(a), id(b)),
            Node::Div(a, b) => (4, id(a), id(b)),
            Node::Powi(a, n) => (5, id(a), u64::from(n as u32)),
            Node::Powf(a, b) => (6, id(a), id(b)),
            Node::Func(f, a) => (7, id(a), f as u64),
            Node::Atan2(a, b) => (8, id(a), id(b)),
            Node::Hypot(a, b) => (9, id(a), id(b)),
            Node::Max(a, b) => (10, id(a), id(b)),
            Node::Min(a, b) => (11, id(a), id(b)),
        }
    }

    /// The operands, in order (at most two).
    pub fn children(&self) -> impl Iterator<Item = ExprId> {
        let (a, b) = match *self {
            Node::Const(_) | Node::Var(_) => (None, None),
            Node::Powi(a, _) | Node::Func(_, a) => (Some(a), None),
            Node::Add(a, b)
            | Node::Mul(a, b)
            | Node::Div(a, b)
            | Node::Powf(a, b)
            | Node::Atan2(a, b)
            | Node::Hypot(a, b)
            | Node::Max(a, b)
            | Node::Min(a, b) => (Some(a), Some(b)),
        };
        a.into_iter().chain(b)
    }
}

/// Hash-consed store of expression nodes, with the derivative memo.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    nodes: Vec<Node>,
    /// Per node, the OR of `var_bit(v)` over the variables below it: a one-word filter that
    /// proves most "does not depend on v" questions without a traversal.
    masks: Vec<u64>,
    intern: HashMap<Key, ExprId>,
    pub(super) diff_memo: HashMap<(ExprId, Var), ExprId>,
}

impl Graph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// The stored node behind `e`.
    pub fn node(&self, e: ExprId) -> &Node {
        &self.nodes[e.index()]
    }

    /// Number of nodes ever created in this graph.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if no node was created yet.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    fn intern(&mut self, n: Node) -> ExprId {
        let key = n.key();
        if let Some(&e) = self.intern.get(&key) {
            return e;
        }
        let id = u32::try_from(self.nodes.len()).expect("symbolic graph exceeds u32 nodes");
        let e = ExprId(id);
        let mask = match n {
            Node::Var(v) => var_bit(v),
            _ => n.children().fold(0, |m, c| m | self.masks[c.index()]),
        };
        self.masks.push(mask);
        self.nodes.push(n);
        self.intern.insert(key, e);
        e
    }

    /// A constant. `-0.0` becomes `0.0` and every NaN the same NaN. Non-finite values are
    /// accepted (a literal may overflow) and are emitted as `f64::INFINITY` etc.
    pub fn constant(&mut self, v: f64) -> ExprId {
        let v = if v == 0.0 {
            0.0
        } else if v.is_nan() {
            f64::NAN
        } else {
            v
        };
        self.intern(Node::Const(v))
    }

    /// The constant `v` if it is finite, else `None` (folding must not create inf/NaN).
    fn folded(&mut self, v: f64) -> Option<ExprId> {
        v.is_finite().then(|| self.constant(v))
    }

    /// A variable.
    pub fn var(&mut self, v: Var) -> ExprId {
        self.intern(Node::Var(v))
    }

    /// The value of `e` if it is a constant node.
    pub fn as_constant(&self, e: ExprId) -> Option<f64> {
        match self.nodes[e.index()] {
            Node::Const(v) => Some(v),
            _ => None,
        }
    }

    /// True if `e` is the constant zero (so callers can skip structurally zero entries).
    pub fn is_zero(&self, e: ExprId) -> bool {
        self.as_constant(e) == Some(0.0)
    }

    fn is_const(&self, e: ExprId) -> bool {
        self.as_constant(e).is_some()
    }

    /// `(c, t)` with `e = c * t`: the constant factor of a product, else `(1, e)`.
    fn split_coeff(&self, e: ExprId) -> (f64, ExprId) {
        match self.nodes[e.index()] {
            Node::Mul(c, t) => match self.as_constant(c) {
                Some(c) => (c, t),
                None => (1.0, e),
            },
            _ => (1.0, e),
        }
    }

    /// `(x, n)` with `e = x^n`, else `(e, 1)`.
    fn split_pow(&self, e: ExprId) -> (ExprId, i32) {
        match self.nodes[e.index()] {
            Node::Powi(x, n) => (x, n),
            _ => (e, 1),
        }
    }

    /// `x + c` with a constant `c`: `Some((x, c))`.
    fn split_add_const(&self, e: ExprId) -> Option<(ExprId, ExprId)> {
        match self.nodes[e.index()] {
            Node::Add(x, c) if self.is_const(c) && !self.is_const(x) => Some((x, c)),
            _ => None,
        }
    }

    /// `a + b`. Folds constants, drops `0`, gathers constants into one trailing term
    /// (`(x + 1) + 2 = x + 3`) and combines like terms (`2x + 3x = 5x`, `a - a = 0`).
    pub fn add(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let (ca, cb) = (self.as_constant(a), self.as_constant(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            if let Some(e) = self.folded(x + y) {
                return e;
            }
        }
        if ca == Some(0.0) {
            return b;
        }
        if cb == Some(0.0) {
            return a;
        }
        // Constant second.
        let (a, b) = if ca.is_some() && cb.is_none() {
            (b, a)
        } else {
            (a, b)
        };
        if let (Some(cb), false) = (self.as_constant(b), self.is_const(a)) {
            if let Some((x, c1)) = self.split_add_const(a) {
                let c1 = self.as_constant(c1).unwrap_or(0.0);
                if let Some(c) = self.folded(c1 + cb) {
                    return self.add(x, c);
                }
            }
            return self.intern(Node::Add(a, b));
        }
        if !self.is_const(b) {
            // Rules below try operands in order; sort first so `a + b` and `b + a` agree.
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            // Like terms first: `s - s` must cancel even when `s` has a constant term.
            let (ka, ta) = self.split_coeff(a);
            let (kb, tb) = self.split_coeff(b);
            if ta == tb {
                if let Some(k) = self.folded(ka + kb) {
                    return self.mul(k, ta);
                }
            }
            if let Some((x, c)) = self.split_add_const(a) {
                let s = self.add(x, b);
                return self.add(s, c);
            }
            if let Some((x, c)) = self.split_add_const(b) {
                let s = self.add(a, x);
                return self.add(s, c);
            }
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(Node::Add(a, b))
    }

    /// `a - b`, stored as `a + (-1) * b`.
    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let nb = self.neg(b);
        self.add(a, nb)
    }

    /// `-a`, stored as `(-1) * a`; `--a = a`.
    pub fn neg(&mut self, a: ExprId) -> ExprId {
        let m1 = self.constant(-1.0);
        self.mul(m1, a)
    }

    /// `a * b`. Folds constants, `0 * a = 0` (even for inf/NaN `a`), `1 * a = a`, gathers
    /// constant factors in front (`2 * (3 * a) = 6 * a`, `a * (2 * b) = 2 * (a * b)`), merges
    /// integer powers of the same base (`x * x = x^2`) and rewrites `(k / b) * c` with a
    /// constant `k` as `k * (c / b)` (so `(1 / b) * c = c / b`).
    pub fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let (ca, cb) = (self.as_constant(a), self.as_constant(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            if let Some(e) = self.folded(x * y) {
                return e;
            }
            // An overflowing square stays symbolic in the same canonical form as any
            // other `x * x`, so that `c * c` and `powi(c, 2)` are one node.
            if a == b {
                return self.powi(a, 2);
            }
        }
        if ca == Some(0.0) || cb == Some(0.0) {
            return self.constant(0.0);
        }
        if ca == Some(1.0) {
            return b;
        }
        if cb == Some(1.0) {
            return a;
        }
        // Constant first.
        let (a, b) = if cb.is_some() && ca.is_none() {
            (b, a)
        } else {
            (a, b)
        };
        if let (Some(ca), false) = (self.as_constant(a), self.is_const(b)) {
            let (k, x) = self.split_coeff(b);
            if x != b {
                if let Some(c) = self.folded(ca * k) {
                    return self.mul(c, x);
                }
            }
            return self.intern(Node::Mul(a, b));
        }
        if !self.is_const(a) && !self.is_const(b) {
            // Rules below try operands in order; sort first so `a * b` and `b * a` agree.
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            for (p, q) in [(a, b), (b, a)] {
                let (k, x) = self.split_coeff(p);
                if x != p {
                    let c = self.constant(k);
                    let r = self.mul(x, q);
                    return self.mul(c, r);
                }
            }
            let (xa, na) = self.split_pow(a);
            let (xb, nb) = self.split_pow(b);
            if xa == xb {
                if let Some(n) = na.checked_add(nb) {
                    return self.powi(xa, n);
                }
            }
            // (k / d) * q = k * (q / d): turns the `1 / a` of derivative rules into `q / a`.
            // Only for constant numerators: `(a / b) * c` keeps `a / b`, which is often shared.
            for (p, q) in [(a, b), (b, a)] {
                if let Node::Div(n, d) = self.nodes[p.index()] {
                    if let Some(k) = self.as_constant(n) {
                        if k.is_finite() {
                            let r = self.div(q, d);
                            return self.mul(n, r);
                        }
                    }
                }
            }
            // x^n * (x^m * y) = x^(n+m) * y, one level deep: `r * (m * r) = m * r^2`.
            for (p, q) in [(a, b), (b, a)] {
                if let Node::Mul(q1, q2) = self.nodes[q.index()] {
                    let (xp, np) = self.split_pow(p);
                    for (r, other) in [(q1, q2), (q2, q1)] {
                        let (xr, nr) = self.split_pow(r);
                        if xr == xp {
                            if let Some(n) = np.checked_add(nr) {
                                let pw = self.powi(xp, n);
                                return self.mul(pw, other);
                            }
                        }
                    }
                }
            }
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(Node::Mul(a, b))
    }

    /// `a / b`. Folds constants when the quotient is finite (`1 / 0` stays), `a / 1 = a`,
    /// `a / -1 = -a`, `0 / a = 0` and `a / a = 1` (both ignoring `a = 0`, except that a
    /// literal zero denominator is always kept), and moves a constant factor of the numerator
    /// in front (`(2 * a) / b = 2 * (a / b)`).
    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let (ca, cb) = (self.as_constant(a), self.as_constant(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            if let Some(e) = self.folded(x / y) {
                return e;
            }
        }
        if cb == Some(0.0) {
            return self.intern(Node::Div(a, b));
        }
        if cb == Some(1.0) {
            return a;
        }
        if cb == Some(-1.0) {
            return self.neg(a);
        }
        if ca == Some(0.0) {
            return a;
        }
        if a == b {
            return self.constant(1.0);
        }
        let (k, x) = self.split_coeff(a);
        if x != a {
            let c = self.constant(k);
            let q = self.div(x, b);
            return self.mul(c, q);
        }
        self.intern(Node::Div(a, b))
    }

    /// `a^n` for integer `n`. `a^0 = 1` (even for `a = 0`), `a^1 = a`, `(a^m)^n = a^(mn)`,
    /// `(c a)^n = c^n a^n` for a constant `c`; constants fold when finite.
    pub fn powi(&mut self, a: ExprId, n: i32) -> ExprId {
        if n == 0 {
            return self.constant(1.0);
        }
        if n == 1 {
            return a;
        }
        if let Some(x) = self.as_constant(a) {
            if let Some(e) = self.folded(x.powi(n)) {
                return e;
            }
            return self.intern(Node::Powi(a, n));
        }
        match self.nodes[a.index()] {
            Node::Powi(x, m) => {
                if let Some(k) = m.checked_mul(n) {
                    return self.powi(x, k);
                }
            }
            Node::Mul(c, x) => {
                if let Some(c) = self.as_constant(c) {
                    if let Some(cn) = self.folded(c.powi(n)) {
                        let p = self.powi(x, n);
                        return self.mul(cn, p);
                    }
                }
            }
            _ => {}
        }
        self.intern(Node::Powi(a, n))
    }

    /// `a^b` for real `b`. A constant integral exponent becomes [`Graph::powi`] (valid for
    /// negative bases too); constants fold when finite.
    pub fn powf(&mut self, a: ExprId, b: ExprId) -> ExprId {
        if let Some(y) = self.as_constant(b) {
            if y.fract() == 0.0 && y.abs() <= f64::from(i32::MAX) {
                return self.powi(a, y as i32);
            }
            if let Some(x) = self.as_constant(a) {
                if let Some(e) = self.folded(x.powf(y)) {
                    return e;
                }
            }
        }
        self.intern(Node::Powf(a, b))
    }

    /// `f(a)`. Folds constants when the value is finite, and simplifies `abs(c * a)`,
    /// `abs(abs(a))`, `abs(a^(2k))`, `sqrt(a^2) = abs(a)`, `ln(exp(a)) = a`,
    /// `signum(signum(a))`.
    pub fn func(&mut self, f: Func, a: ExprId) -> ExprId {
        if let Some(x) = self.as_constant(a) {
            if let Some(e) = self.folded(f.apply(x)) {
                return e;
            }
            return self.intern(Node::Func(f, a));
        }
        match (f, self.nodes[a.index()]) {
            (Func::Abs, Node::Func(Func::Abs, _)) | (Func::Sign, Node::Func(Func::Sign, _)) => {
                return a
            }
            (Func::Abs, Node::Powi(_, n)) if n % 2 == 0 => return a,
            (Func::Abs, Node::Mul(c, x)) => {
                if let Some(c) = self.as_constant(c) {
                    let k = self.constant(c.abs());
                    let ax = self.func(Func::Abs, x);
                    return self.mul(k, ax);
                }
            }
            (Func::Sqrt, Node::Powi(x, 2)) => return self.func(Func::Abs, x),
            (Func::Ln, Node::Func(Func::Exp, x)) => return x,
            _ => {}
        }
        self.intern(Node::Func(f, a))
    }

    /// `atan2(y, x)` (emitted `y.atan2(x)`); constants fold.
    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        if let (Some(a), Some(b)) = (self.as_constant(y), self.as_constant(x)) {
            if let Some(e) = self.folded(a.atan2(b)) {
                return e;
            }
        }
        self.intern(Node::Atan2(y, x))
    }

    /// `hypot(a, b) = sqrt(a^2 + b^2)` (emitted `a.hypot(b)`); symmetric, so operands are
    /// sorted; `hypot(a, 0) = abs(a)`; constants fold.
    pub fn hypot(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let (ca, cb) = (self.as_constant(a), self.as_constant(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            if let Some(e) = self.folded(x.hypot(y)) {
                return e;
            }
        }
        if ca == Some(0.0) {
            return self.func(Func::Abs, b);
        }
        if cb == Some(0.0) {
            return self.func(Func::Abs, a);
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(Node::Hypot(a, b))
    }

    /// `max(a, b)` with the semantics of `f64::max` (emitted `a.max(b)`): a NaN operand is
    /// ignored, so the value is NaN only if both are, and which zero `max(-0, +0)` gives is
    /// unspecified, as in Rust. Symmetric, so operands are sorted; `max(a, a) = a`; constants
    /// fold.
    pub fn max(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.extremum(true, a, b)
    }

    /// `min(a, b)` with the semantics of `f64::min` (emitted `a.min(b)`); see [`Graph::max`].
    pub fn min(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.extremum(false, a, b)
    }

    /// [`Graph::max`] (`is_max`) or [`Graph::min`].
    fn extremum(&mut self, is_max: bool, a: ExprId, b: ExprId) -> ExprId {
        if let (Some(x), Some(y)) = (self.as_constant(a), self.as_constant(b)) {
            if let Some(e) = self.folded(if is_max { x.max(y) } else { x.min(y) }) {
                return e;
            }
        }
        if a == b {
            return a;
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(if is_max {
            Node::Max(a, b)
        } else {
            Node::Min(a, b)
        })
    }

    /// Rebuild `n` through the constructors with every child replaced by `f(child)`
    /// (so the result is folded and canonical again).
    pub(super) fn rebuild(&mut self, n: Node, f: impl Fn(ExprId) -> ExprId) -> ExprId {
        match n {
            Node::Const(v) => self.constant(v),
            Node::Var(v) => self.var(v),
            Node::Add(a, b) => self.add(f(a), f(b)),
            Node::Mul(a, b) => self.mul(f(a), f(b)),
            Node::Div(a, b) => self.div(f(a), f(b)),
            Node::Powi(a, k) => self.powi(f(a), k),
            Node::Powf(a, b) => self.powf(f(a), f(b)),
            Node::Func(g, a) => self.func(g, f(a)),
            Node::Atan2(a, b) => self.atan2(f(a), f(b)),
            Node::Hypot(a, b) => self.hypot(f(a), f(b)),
            Node::Max(a, b) => self.max(f(a), f(b)),
            Node::Min(a, b) => self.min(f(a), f(b)),
        }
    }

    /// All nodes reachable from `roots`, in increasing id order (a topological order:
    /// children before parents).
    pub fn reachable(&self, roots: &[ExprId]) -> Vec<ExprId> {
        let mut seen: HashSet<ExprId> = HashSet::new();
        let mut stack: Vec<ExprId> = Vec::new();
        for &r in roots {
            if seen.insert(r) {
                stack.push(r);
            }
        }
        while let Some(e) = stack.pop() {
            for c in self.nodes[e.index()].children() {
                if seen.insert(c) {
                    stack.push(c);
                }
            }
        }
        let mut order: Vec<ExprId> = seen.into_iter().collect();
        order.sort_unstable();
        order
    }

    /// Number of nodes reachable from `roots` (shared nodes counted once), to measure
    /// expression swell.
    pub fn size(&self, roots: &[ExprId]) -> usize {
        self.reachable(roots).len()
    }

    /// Variables `e` depends on structurally (a variable multiplied by zero is gone already).
    pub fn vars(&self, e: ExprId) -> std::collections::BTreeSet<Var> {
        self.reachable(&[e])
            .into_iter()
            .filter_map(|n| match self.nodes[n.index()] {
                Node::Var(v) => Some(v),
                _ => None,
            })
            .collect()
    }

    /// False if `v` certainly does not occur in `e` (constant time); true means "maybe".
    pub(super) fn may_depend_on(&self, e: ExprId, v: Var) -> bool {
        self.masks[e.index()] & var_bit(v) != 0
    }

    /// True if `v` occurs in `e`.
    pub fn depends_on(&self, e: ExprId, v: Var) -> bool {
        if !self.may_depend_on(e, v) {
            return false;
        }
        let mut seen: HashSet<ExprId> = HashSet::new();
        let mut stack = vec![e];
        seen.insert(e);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n.index()];
            if *node == Node::Var(v) {
                return true;
            }
            for c in node.children() {
                if self.may_depend_on(c, v) && seen.insert(c) {
                    stack.push(c);
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn xyz(g: &mut Graph) -> (ExprId, ExprId, ExprId) {
        (g.var(Var(0)), g.var(Var(1)), g.var(Var(2)))
    }

    #[test]
    fn hash_consing_shares_equal_nodes() {
        let mut g = Graph::new();
        let (x, y, _) = xyz(&mut g);
        let a = g.func(Func::Sin, x);
        let b = g.func(Func::Sin, x);
        assert_eq!(a, b);
        assert_eq!(g.add(x, y), g.add(y, x));
        assert_eq!(g.mul(x, y), g.mul(y, x));
        assert_eq!(g.hypot(x, y), g.hypot(y, x));
        assert_ne!(g.atan2(x, y), g.atan2(y, x));
        assert_eq!(g.max(x, y), g.max(y, x));
        assert_eq!(g.min(x, y), g.min(y, x));
        assert_ne!(g.max(x, y), g.min(x, y));
        assert_ne!(g.div(x, y), g.div(y, x));
        assert_eq!(g.var(Var(0)), x);
        assert_eq!(g.constant(-0.0), g.constant(0.0));
        assert_eq!(g.constant(f64::NAN), g.constant(f64::NAN));
    }

    #[test]
    fn identities() {
        let mut g = Graph::new();
        let (x, y, _) = xyz(&mut g);
        let (zero, one) = (g.constant(0.0), g.constant(1.0));
        assert_eq!(g.add(zero, x), x);
        assert_eq!(g.add(x, zero), x);
        assert_eq!(g.mul(x, one), x);
        assert_eq!(g.mul(one, x), x);
        assert!(g.is_zero(g.clone().mul(x, zero)));
        assert_eq!(g.mul(zero, x), zero);
        assert_eq!(g.sub(x, x), zero);
        assert_eq!(g.div(x, one), x);
        assert_eq!(g.div(x, x), one);
        assert_eq!(g.div(zero, x), zero);
        let nx = g.neg(x);
        assert_eq!(g.neg(nx), x);
        assert_eq!(g.powi(x, 0), one);
        assert_eq!(g.powi(x, 1), x);
        let x2 = g.powi(x, 2);
        let x6 = g.powi(x, 6);
        assert_eq!(g.powi(x2, 3), x6);
        assert_eq!(g.mul(x, x), x2);
        let x3 = g.powi(x, 3);
        assert_eq!(g.mul(x2, x), x3);
        let xy = g.mul(x, y);
        let x3y = g.mul(x3, y);
        assert_eq!(g.mul(x2, xy), x3y);
        let xm1 = g.powi(x, -1);
        assert_eq!(g.mul(xy, xm1), y);
        let xm2 = g.powi(x, -2);
        assert_eq!(g.mul(x2, xm2), one);
        // a - b - (a - b) = 0, also with a constant term
        let d = g.sub(x, y);
        assert_eq!(g.sub(d, d), zero);
        let half = g.constant(0.5);
        let xh = g.add(x, half);
        let s = g.add(x, xh);
        assert_eq!(g.sub(s, s), zero);
        // 2x + 3x = 5x
        let (two, three, five) = (g.constant(2.0), g.constant(3.0), g.constant(5.0));
        let tx = g.mul(two, x);
        let hx = g.mul(x, three);
        let fx = g.mul(five, x);
        assert_eq!(g.add(tx, hx), fx);
        // x + x = 2x
        assert_eq!(g.add(x, x), tx);
        // 2 * (3 * x) = 6 x, x * (2 * y) = 2 (x y)
        let six = g.constant(6.0);
        let sx = g.mul(six, x);
        assert_eq!(g.mul(two, hx), sx);
        let xy = g.mul(x, y);
        let ty = g.mul(two, y);
        let txy = g.mul(two, xy);
        assert_eq!(g.mul(x, ty), txy);
        // (x + 1) + 2 = x + 3, (x + 1) + y = (x + y) + 1
        let xp1 = g.add(x, one);
        let xp3 = {
            let c = g.constant(3.0);
            g.add(x, c)
        };
        assert_eq!(g.add(xp1, two), xp3);
        let a = g.add(xp1, y);
        let xpy = g.add(x, y);
        assert_eq!(a, g.add(xpy, one));
        // powf with integral constant exponent is powi
        assert_eq!(g.powf(x, two), x2);
        // sqrt(x^2) = |x|, |-2 x| = 2 |x|
        let ax = g.func(Func::Abs, x);
        assert_eq!(g.func(Func::Sqrt, x2), ax);
        let m2x = {
            let m2 = g.constant(-2.0);
            g.mul(m2, x)
        };
        let tax = g.mul(two, ax);
        assert_eq!(g.func(Func::Abs, m2x), tax);
        let ex = g.func(Func::Exp, x);
        assert_eq!(g.func(Func::Ln, ex), x);
        assert_eq!(g.hypot(x, zero), ax);
        assert_eq!(g.max(x, x), x);
        assert_eq!(g.min(x, x), x);
    }

    #[test]
    fn max_and_min_fold_constants_of_any_magnitude() {
        let mut g = Graph::new();
        let (big, one, m1) = (g.constant(1e20), g.constant(1.0), g.constant(-1.0));
        // `0.5 (a + b - |a - b|)` gives 0 here: the 1 is lost next to 1e20.
        let e = g.min(big, one);
        assert_eq!(g.as_constant(e), Some(1.0));
        let e = g.max(one, big);
        assert_eq!(g.as_constant(e), Some(1e20));
        let e = g.max(m1, one);
        assert_eq!(g.as_constant(e), Some(1.0));
        let e = g.min(one, m1);
        assert_eq!(g.as_constant(e), Some(-1.0));
        // an infinite operand stays symbolic, as other non-finite results do
        let zero = g.constant(0.0);
        let inf = g.div(one, zero);
        let e = g.max(inf, one);
        assert_eq!(g.as_constant(e), None);
        assert_eq!(g.eval(e, &|_| 0.0), f64::INFINITY);
    }

    #[test]
    fn overflowing_square_of_a_constant_is_a_power() {
        let mut g = Graph::new();
        let big = g.constant(1e200);
        let sq = g.mul(big, big);
        assert_eq!(sq, g.powi(big, 2));
        assert!(g.as_constant(sq).is_none(), "1e400 is not folded");
    }

    #[test]
    fn constant_folding_keeps_non_finite_symbolic() {
        let mut g = Graph::new();
        let (zero, one, two) = (g.constant(0.0), g.constant(1.0), g.constant(2.0));
        let three = g.add(one, two);
        assert_eq!(g.as_constant(three), Some(3.0));
        let s = g.func(Func::Sin, zero);
        assert_eq!(g.as_constant(s), Some(0.0));
        let l = g.func(Func::Ln, zero);
        assert_eq!(g.as_constant(l), None);
        let q = g.div(one, zero);
        assert_eq!(g.as_constant(q), None);
        let m1 = g.constant(-1.0);
        let r = g.func(Func::Sqrt, m1);
        assert_eq!(g.as_constant(r), None);
        let p = g.powi(zero, -1);
        assert_eq!(g.as_constant(p), None);
        let h = g.powf(two, three);
        assert_eq!(g.as_constant(h), Some(8.0));
        let half = g.constant(0.5);
        let rt = g.powf(m1, half);
        assert_eq!(g.as_constant(rt), None);
    }

    #[test]
    fn vars_and_depends_on() {
        let mut g = Graph::new();
        let (x, y, z) = xyz(&mut g);
        let s = g.func(Func::Sin, x);
        let e = g.mul(s, y);
        assert_eq!(
            g.vars(e).into_iter().collect::<Vec<_>>(),
            vec![Var(0), Var(1)]
        );
        assert!(g.depends_on(e, Var(1)));
        assert!(!g.depends_on(e, Var(2)));
        let zero = g.constant(0.0);
        let gone = g.mul(z, zero);
        let e2 = g.add(e, gone);
        assert!(!g.depends_on(e2, Var(2)));
        assert_eq!(g.size(&[e, e2]), 4);
    }
}
