//! Readable infix printing for listings and error messages.
//!
//! Parentheses are inserted by precedence only where the mathematical meaning needs them
//! (`a + (b + c)` prints as `a + b + c`, unlike the emitted Rust, which must keep the
//! evaluation order). Stored forms are turned back into conventional ones: `a + (-1) * b`
//! prints as `a - b`, `(-1) * a` as `-a`, `a^n` for integer powers. [`Graph::display`] prints
//! shared subexpressions in full at every use, so the text of a heavily shared DAG can be
//! exponentially long; [`Graph::display_shared`] names them instead, following the CSE
//! [`Schedule`].

use super::graph::{ExprId, Graph, Node, Var};
use super::schedule::Schedule;

/// Precedence of a printed form; an operand printed at a lower level gets parentheses.
const SUM: u8 = 1;
/// A product with a leading minus (`-x * y`, `-2`): fine at the start of a sum or product.
const NEG: u8 = 2;
const PROD: u8 = 3;
const POW: u8 = 4;
const ATOM: u8 = 5;

struct Printer<'a> {
    g: &'a Graph,
    name_of: &'a dyn Fn(Var) -> String,
    /// Named subexpressions (schedule temporaries) and the prefix of their names.
    named: Option<(&'a Schedule, &'a str)>,
}

impl Graph {
    /// Readable infix text, variables named by `name_of`, minimal parentheses, e.g.
    /// `m * r^2 * sin(theta)`.
    pub fn display(&self, e: ExprId, name_of: &dyn Fn(Var) -> String) -> String {
        let p = Printer {
            g: self,
            name_of,
            named: None,
        };
        p.expr(e).0
    }

    /// Readable listing of several roots in which every subexpression the CSE schedule binds
    /// to a temporary is printed once, as `{prefix}k = ...`. Returns those definitions (in
    /// order, each line `"{prefix}k = expr"`) and one text per root. Linear in the DAG size.
    pub fn display_shared(
        &self,
        roots: &[ExprId],
        name_of: &dyn Fn(Var) -> String,
        prefix: &str,
    ) -> (Vec<String>, Vec<String>) {
        let s = self.schedule(roots);
        let p = Printer {
            g: self,
            name_of,
            named: Some((&s, prefix)),
        };
        let defs = s
            .temps
            .iter()
            .enumerate()
            .map(|(k, &t)| format!("{prefix}{k} = {}", p.node_text(t).0))
            .collect();
        let texts = roots.iter().map(|&r| p.expr(r).0).collect();
        (defs, texts)
    }

    /// `e = -k * t` with a constant `k > 0`: `Some((k, t))`, where `t` is `None` for a
    /// negative constant `e = -k`.
    pub(super) fn negative_term(&self, e: ExprId) -> Option<(f64, Option<ExprId>)> {
        match *self.node(e) {
            Node::Const(c) if c < 0.0 => Some((-c, None)),
            Node::Mul(c, t) => match self.as_constant(c) {
                Some(c) if c < 0.0 => Some((-c, Some(t))),
                _ => None,
            },
            _ => None,
        }
    }
}

fn number(v: f64) -> String {
    format!("{v}")
}

impl Printer<'_> {
    /// The name of `e` if it is a named subexpression.
    fn name(&self, e: ExprId) -> Option<String> {
        let (s, prefix) = self.named?;
        s.temp_of(e).map(|k| format!("{prefix}{k}"))
    }

    /// [`Graph::negative_term`], except that a named subexpression is opaque.
    fn negative_term(&self, e: ExprId) -> Option<(f64, Option<ExprId>)> {
        match self.name(e) {
            Some(_) => None,
            None => self.g.negative_term(e),
        }
    }

    /// `e` printed in a context that needs at least precedence `min`; `lead` says whether the
    /// operand comes first (where a leading minus reads fine).
    fn operand(&self, e: ExprId, min: u8, lead: bool) -> String {
        let (s, p) = self.expr(e);
        if p < min || (!lead && s.starts_with('-')) {
            format!("({s})")
        } else {
            s
        }
    }

    /// `k * t` (the magnitude of a negative term), at product level.
    fn magnitude(&self, k: f64, t: Option<ExprId>) -> (String, u8) {
        match t {
            None => (number(k), ATOM),
            Some(t) if k == 1.0 => self.expr(t),
            Some(t) => (
                format!("{} * {}", number(k), self.operand(t, PROD, false)),
                PROD,
            ),
        }
    }

    /// Operands of a chain of associative nodes of one kind (`is_op`), left to right.
    fn flatten(&self, e: ExprId, is_op: &dyn Fn(&Node) -> bool, out: &mut Vec<ExprId>) {
        let node = self.g.node(e);
        if is_op(node) {
            for c in node.children() {
                if self.name(c).is_some() {
                    out.push(c);
                } else {
                    self.flatten(c, is_op, out);
                }
            }
        } else {
            out.push(e);
        }
    }

    /// Reading order of a factor in a product.
    fn rank(&self, f: ExprId) -> u8 {
        if self.name(f).is_some() {
            return 3;
        }
        match *self.g.node(f) {
            Node::Const(_) => 0,
            Node::Var(_) => 1,
            Node::Powi(a, _) if matches!(self.g.node(a), Node::Var(_)) => 2,
            Node::Func(..)
            | Node::Atan2(..)
            | Node::Hypot(..)
            | Node::Max(..)
            | Node::Min(..)
            | Node::Powi(..) => 3,
            _ => 4,
        }
    }

    /// `e` at a use site: its name if it has one, else its text.
    fn expr(&self, e: ExprId) -> (String, u8) {
        match self.name(e) {
            Some(n) => (n, ATOM),
            None => self.node_text(e),
        }
    }

    /// The text of node `e` itself.
    fn node_text(&self, e: ExprId) -> (String, u8) {
        let g = self.g;
        match *g.node(e) {
            Node::Const(c) if c < 0.0 => (number(c), NEG),
            Node::Const(c) => (number(c), ATOM),
            Node::Var(v) => ((self.name_of)(v), ATOM),
            Node::Add(..) => {
                // Terms in stored order, positive ones first; `-` for negative ones.
                let mut terms = Vec::new();
                self.flatten(e, &|n| matches!(n, Node::Add(..)), &mut terms);
                terms.sort_by_key(|&t| self.negative_term(t).is_some());
                let mut out = String::new();
                for (i, &t) in terms.iter().enumerate() {
                    match (i, self.negative_term(t)) {
                        (0, _) => out += &self.operand(t, SUM, true),
                        (_, Some((k, t))) => {
                            let (m, p) = self.magnitude(k, t);
                            out += " - ";
                            out += &if p < PROD { format!("({m})") } else { m };
                        }
                        (_, None) => {
                            out += " + ";
                            out += &self.operand(t, SUM, false);
                        }
                    }
                }
                (out, SUM)
            }
            Node::Mul(..) => match g.negative_term(e) {
                Some((k, t)) => {
                    let (m, p) = self.magnitude(k, t);
                    let m = if p < PROD { format!("({m})") } else { m };
                    (format!("-{m}"), NEG)
                }
                None => {
                    // Factors ordered for reading: constants, variables, powers, calls, rest.
                    let mut factors = Vec::new();
                    self.flatten(e, &|n| matches!(n, Node::Mul(..)), &mut factors);
                    factors.sort_by_key(|&f| self.rank(f));
                    let parts: Vec<String> = factors
                        .iter()
                        .enumerate()
                        .map(|(i, &f)| self.operand(f, if i == 0 { NEG } else { PROD }, i == 0))
                        .collect();
                    (parts.join(" * "), PROD)
                }
            },
            Node::Div(a, b) => (
                format!(
                    "{} / {}",
                    self.operand(a, NEG, true),
                    self.operand(b, POW, false)
                ),
                PROD,
            ),
            Node::Powi(a, n) => (format!("{}^{n}", self.operand(a, ATOM, false)), POW),
            Node::Powf(a, b) => (
                format!(
                    "{}^{}",
                    self.operand(a, ATOM, false),
                    self.operand(b, ATOM, false)
                ),
                POW,
            ),
            Node::Func(f, a) => (format!("{}({})", f.name(), self.expr(a).0), ATOM),
            Node::Atan2(y, x) => (
                format!("atan2({}, {})", self.expr(y).0, self.expr(x).0),
                ATOM,
            ),
            Node::Hypot(a, b) => (
                format!("hypot({}, {})", self.expr(a).0, self.expr(b).0),
                ATOM,
            ),
            Node::Max(a, b) => (format!("max({}, {})", self.expr(a).0, self.expr(b).0), ATOM),
            Node::Min(a, b) => (format!("min({}, {})", self.expr(a).0, self.expr(b).0), ATOM),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Func;
    use super::*;

    fn names(v: Var) -> String {
        ["m", "r", "theta", "x", "y"][v.0 as usize].to_string()
    }

    #[test]
    fn readable_output() {
        let mut g = Graph::new();
        let (m, r, th, x, y) = (
            g.var(Var(0)),
            g.var(Var(1)),
            g.var(Var(2)),
            g.var(Var(3)),
            g.var(Var(4)),
        );
        let show = |g: &Graph, e| g.display(e, &names);
        let r2 = g.powi(r, 2);
        let s = g.func(Func::Sin, th);
        let mr2 = g.mul(m, r2);
        let e = g.mul(mr2, s);
        assert_eq!(show(&g, e), "m * r^2 * sin(theta)");
        let d = g.sub(x, y);
        assert_eq!(show(&g, d), "x - y");
        let d2 = g.sub(y, x);
        assert_eq!(show(&g, d2), "y - x");
        let nx = g.neg(x);
        assert_eq!(show(&g, nx), "-x");
        let two = g.constant(2.0);
        let ty = g.mul(two, y);
        let e = g.sub(x, ty);
        assert_eq!(show(&g, e), "x - 2 * y");
        let one = g.constant(1.0);
        let e = g.sub(x, one);
        assert_eq!(show(&g, e), "x - 1");
        let s = g.add(x, y);
        let e = g.sub(m, s);
        assert_eq!(show(&g, e), "m - (x + y)");
        let e = g.mul(s, m);
        assert_eq!(show(&g, e), "m * (x + y)");
        let e = g.neg(s);
        assert_eq!(show(&g, e), "-(x + y)");
        let e = g.div(x, mr2);
        assert_eq!(show(&g, e), "x / (m * r^2)");
        let e = g.powi(s, -1);
        assert_eq!(show(&g, e), "(x + y)^-1");
        let e = g.powi(nx, 3);
        assert_eq!(show(&g, e), "-x^3");
        let e = g.atan2(y, nx);
        assert_eq!(show(&g, e), "atan2(y, -x)");
        let e = g.max(x, nx);
        assert_eq!(show(&g, e), "max(x, -x)");
        let e = g.min(s, two);
        assert_eq!(show(&g, e), "min(2, x + y)");
        let half = g.constant(0.5);
        let e = g.powf(s, half);
        assert_eq!(show(&g, e), "(x + y)^0.5");
        let ax = g.func(Func::Abs, x);
        let e = g.diff(ax, Var(3));
        assert_eq!(show(&g, e), "signum(x)");
        let nxy = g.mul(nx, y);
        let e = g.mul(nxy, th);
        assert_eq!(show(&g, e), "-theta * x * y");
    }

    #[test]
    fn shared_listing_names_repeated_subexpressions() {
        let mut g = Graph::new();
        let (x, y) = (g.var(Var(3)), g.var(Var(4)));
        let s = g.add(x, y);
        let c = g.func(Func::Cos, s);
        let two = g.constant(2.0);
        let c2 = g.mul(two, c);
        let e1 = g.sub(x, c2);
        let e2 = g.mul(c, y);
        let (defs, texts) = g.display_shared(&[e1, e2], &names, "s");
        assert_eq!(defs, vec!["s0 = cos(x + y)".to_string()]);
        assert_eq!(texts, vec!["x - 2 * s0".to_string(), "y * s0".to_string()]);
        // 60 levels of e -> sin(e) * e + e would print 2^60 copies in full.
        let mut e = x;
        for _ in 0..60 {
            let si = g.func(Func::Sin, e);
            let p = g.mul(si, e);
            e = g.add(p, e);
        }
        let (defs, texts) = g.display_shared(&[e], &names, "s");
        assert_eq!(defs.len(), 59); // every level but the root itself
        assert!(texts[0].len() < 40, "{}", texts[0]);
    }
}
