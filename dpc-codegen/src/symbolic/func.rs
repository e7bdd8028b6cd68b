//! The table of elementary functions of one argument: names as written in the DSL (the Rust
//! `f64` method names), numerical evaluation, and the exact derivative rule `f'(a)` of each.

use super::graph::{ExprId, Graph};

/// Elementary functions of one argument.
///
/// The names are those of the `f64` methods, so that emission is `a.name()`. Binary
/// functions (`atan2`, `hypot`, `powi`, `powf`) are separate graph constructors.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    /// Square root.
    Sqrt,
    /// Natural exponential.
    Exp,
    /// Natural logarithm.
    Ln,
    /// Sine.
    Sin,
    /// Cosine.
    Cos,
    /// Tangent.
    Tan,
    /// Arc sine.
    Asin,
    /// Arc cosine.
    Acos,
    /// Arc tangent (one argument; see [`Graph::atan2`] for two).
    Atan,
    /// Hyperbolic sine.
    Sinh,
    /// Hyperbolic cosine.
    Cosh,
    /// Hyperbolic tangent.
    Tanh,
    /// Absolute value.
    Abs,
    /// `f64::signum`: `1` for `+0.0` and positive values, `-1` for `-0.0` and negative values.
    /// Appears as the derivative of [`Func::Abs`]; its own derivative is taken as `0`.
    Sign,
}

impl Func {
    /// Every function, in declaration order (for tests and tables).
    pub const ALL: [Func; 14] = [
        Func::Sqrt,
        Func::Exp,
        Func::Ln,
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
        Func::Abs,
        Func::Sign,
    ];

    /// The function called `name` (the `f64` method name, e.g. `"ln"`, `"signum"`), if any.
    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The name, which is also the `f64` method used in emitted code.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sqrt => "sqrt",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
            Func::Tanh => "tanh",
            Func::Abs => "abs",
            Func::Sign => "signum",
        }
    }

    /// Numerical value, exactly as the emitted `x.name()` computes it.
    #[inline]
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sqrt => x.sqrt(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Asin => x.asin(),
            Func::Acos => x.acos(),
            Func::Atan => x.atan(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
            Func::Tanh => x.tanh(),
            Func::Abs => x.abs(),
            Func::Sign => x.signum(),
        }
    }

    /// `f'(a)`, the derivative with respect to the argument, built in `g`.
    ///
    /// `e` is the node `f(a)` itself, reused where the rule contains it (`exp`, `sqrt`, `tan`,
    /// `tanh`) so that the derivative shares it instead of recomputing it.
    pub(crate) fn derivative(self, g: &mut Graph, a: ExprId, e: ExprId) -> ExprId {
        let one = g.constant(1.0);
        match self {
            // 1 / (2 sqrt(a))
            Func::Sqrt => {
                let two = g.constant(2.0);
                let d = g.mul(two, e);
                g.div(one, d)
            }
            Func::Exp => e,
            Func::Ln => g.div(one, a),
            Func::Sin => g.func(Func::Cos, a),
            Func::Cos => {
                let s = g.func(Func::Sin, a);
                g.neg(s)
            }
            // 1 + tan(a)^2: reuses tan(a), which the residual already computes.
            Func::Tan => {
                let t2 = g.powi(e, 2);
                g.add(one, t2)
            }
            // ±1 / sqrt(1 - a^2)
            Func::Asin | Func::Acos => {
                let a2 = g.powi(a, 2);
                let r = g.sub(one, a2);
                let s = g.func(Func::Sqrt, r);
                let d = g.div(one, s);
                if self == Func::Acos {
                    g.neg(d)
                } else {
                    d
                }
            }
            Func::Atan => {
                let a2 = g.powi(a, 2);
                let r = g.add(one, a2);
                g.div(one, r)
            }
            Func::Sinh => g.func(Func::Cosh, a),
            Func::Cosh => g.func(Func::Sinh, a),
            Func::Tanh => {
                let t2 = g.powi(e, 2);
                g.sub(one, t2)
            }
            // Convention: at a = 0 this is signum(±0) = ±1, a one-sided derivative.
            Func::Abs => g.func(Func::Sign, a),
            // Zero almost everywhere; the jump at 0 is ignored.
            Func::Sign => g.constant(0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for f in Func::ALL {
            assert_eq!(Func::from_name(f.name()), Some(f));
        }
        assert_eq!(Func::from_name("log"), None);
        assert_eq!(Func::from_name("atan2"), None);
    }
}
