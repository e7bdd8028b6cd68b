//! The model IR: declared names resolved, expressions lowered into one symbolic graph.
//!
//! Everything downstream (derivatives, the Hirschorn steps, emission) works on this
//! representation; spans are kept only where later passes can still report errors.

use crate::symbolic::{ExprId, Graph, Var};
use proc_macro2::Span;
use std::collections::HashMap;
use syn::{Attribute, Ident, Visibility};

/// What a symbolic variable stands for.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Symbol {
    /// Time `t`.
    Time,
    /// State `x_i`.
    State(usize),
    /// Its derivative `x_i'`.
    StateDot(usize),
    /// A higher derivative `x_i^(order)` (`order >= 2`) of a state whose equation is
    /// implicit: an algebraic unknown of a tracking DAE whose Hirschorn steps differentiate
    /// through implicit equations, determined by their total derivatives (see
    /// [`crate::hirschorn::tracking_rows`]).
    StateDerivative {
        /// Index of the state.
        state: usize,
        /// The order of the derivative, at least 2.
        order: usize,
    },
    /// Algebraic unknown `z_i`.
    Algebraic(usize),
    /// The derivative of an algebraic unknown (appears only after total time derivatives).
    AlgebraicDot(usize),
    /// Input `u_i`.
    Input(usize),
    /// The derivative of an input (appears only after total time derivatives).
    InputDot(usize),
    /// Parameter `p_i`.
    Param(usize),
    /// The coefficient `c` of the iteration matrix `dF/dy + c dF/dy'`.
    IterationCoefficient,
    /// Run-time input of a tracking DAE: `w_i = W_i(d/dt) xi_i` for output `i`.
    TrackingInput(usize),
    /// Coefficient of `s^power` in `W_output(s)` of a tracking DAE (`power < deg W`; the
    /// leading coefficient is the constant 1). Read at run time from the tracking value, so
    /// the roots of `W` can change without recompiling; a parameter of the tracking rows, not
    /// an unknown.
    TrackingCoefficient {
        /// Index of the output.
        output: usize,
        /// The power of `s` it multiplies.
        power: usize,
    },
}

/// The bijection between [`Symbol`]s and graph [`Var`]s.
#[derive(Default, Debug, Clone)]
pub struct Symbols {
    by_var: Vec<Symbol>,
    by_symbol: HashMap<Symbol, Var>,
}

impl Symbols {
    /// The variable standing for `symbol`, created on first use.
    pub fn var(&mut self, symbol: Symbol) -> Var {
        if let Some(v) = self.by_symbol.get(&symbol) {
            return *v;
        }
        let v = Var(self.by_var.len() as u32);
        self.by_var.push(symbol);
        self.by_symbol.insert(symbol, v);
        v
    }

    /// The variable of `symbol` if it was ever created.
    pub fn lookup(&self, symbol: Symbol) -> Option<Var> {
        self.by_symbol.get(&symbol).copied()
    }

    /// What `var` stands for.
    pub fn symbol(&self, var: Var) -> Symbol {
        self.by_var[var.0 as usize]
    }
}

/// A declared name (state, algebraic unknown, input) with its doc attributes. An element of
/// an indexed family is one of these: `label` `q[2]`, `name` `q_2`.
#[derive(Clone)]
pub struct Decl {
    /// The name in generated code: as declared for a scalar, `q_2` for element `q[2]` of a
    /// family.
    pub name: Ident,
    /// The name as the user writes it (`q`, `q[2]`), for listings, structures and messages.
    pub label: String,
    /// Its unit as declared (`"rad"`), if any.
    pub unit: Option<String>,
    /// Doc comments attached to it.
    pub docs: Vec<Attribute>,
}

/// A parameter with its default.
#[derive(Clone)]
pub struct Param {
    /// The name in generated code (a field of the parameter struct): as declared, or `m_2`
    /// for element `m[2]` of a family.
    pub name: Ident,
    /// The name as the user writes it (`m`, `m[2]`).
    pub label: String,
    /// Its unit as declared, if any.
    pub unit: Option<String>,
    /// Its default value.
    pub default: f64,
    /// Doc comments attached to it.
    pub docs: Vec<Attribute>,
}

/// One equation, lowered to a residual `lhs - rhs`.
#[derive(Clone)]
pub struct Equation {
    /// `lhs - rhs` in the graph.
    pub residual: ExprId,
    /// The equation as written, normalised (`der(x) = f` or `lhs == rhs`).
    pub text: String,
    /// For an explicit equation `der(x_j) = f_j` with `f_j` free of derivatives: `(j, f_j)`.
    pub explicit: Option<(usize, ExprId)>,
    /// Span of the whole equation.
    pub span: Span,
}

/// An output `y_i = h_i(t, x, z, u)`.
#[derive(Clone)]
pub struct Output {
    /// The output's name in generated code (`y`, `y_2`).
    pub name: Ident,
    /// The output's name as the user writes it (`y`, `y[2]`).
    pub label: String,
    /// Its unit: as declared, or for a bare output that of its variable; if any.
    pub unit: Option<String>,
    /// Its expression.
    pub expr: ExprId,
    /// Its expression as written.
    pub text: String,
    /// Doc comments attached to it.
    pub docs: Vec<Attribute>,
}

/// A `let` intermediate, kept for the equation listing.
#[derive(Clone)]
pub struct Intermediate {
    /// The name.
    pub name: Ident,
    /// The name with the subscripts of a family as written (`c[i in 0..N]`), or the name.
    pub label: String,
    /// The expression as written.
    pub text: String,
}

/// A reference `xi_i(t)` written in the DSL.
#[derive(Clone)]
pub struct Reference {
    /// Index of the output it belongs to.
    pub output: usize,
    /// The expression of `t` and parameters.
    pub expr: ExprId,
    /// The expression as written.
    pub text: String,
}

/// One entry of the `tracking` section: `W_i(s) = prod_k (s + roots_k)`.
#[derive(Clone)]
pub struct TrackingEntry {
    /// Index of the output.
    pub output: usize,
    /// Negated roots of `W_i`.
    pub roots: Vec<f64>,
    /// Span of the entry, for diagnostics.
    pub span: Span,
}

/// The `tracking` section.
#[derive(Clone)]
pub struct Tracking {
    /// Name of the generated tracking type.
    pub type_name: Ident,
    /// Entries, in the order of the outputs they name.
    pub entries: Vec<TrackingEntry>,
    /// Span of the `tracking` keyword.
    pub span: Span,
}

/// A lowered, checked model.
pub struct Model {
    /// Outer attributes (doc comment).
    pub attrs: Vec<Attribute>,
    /// Visibility of the generated items.
    pub vis: Visibility,
    /// The model's name.
    pub name: Ident,
    /// Parameters in declaration order.
    pub params: Vec<Param>,
    /// States in declaration order.
    pub states: Vec<Decl>,
    /// Algebraic unknowns in declaration order.
    pub algebraic: Vec<Decl>,
    /// Inputs in declaration order.
    pub inputs: Vec<Decl>,
    /// `let` intermediates in declaration order.
    pub intermediates: Vec<Intermediate>,
    /// Equations in declaration order.
    pub equations: Vec<Equation>,
    /// Outputs in declaration order.
    pub outputs: Vec<Output>,
    /// References written in the DSL.
    pub references: Vec<Reference>,
    /// The `tracking` section, if any.
    pub tracking: Option<Tracking>,
    /// The symbolic graph holding every expression.
    pub graph: Graph,
    /// What each graph variable stands for.
    pub symbols: Symbols,
}

impl Model {
    /// The graph variable of `symbol` (created if needed).
    pub fn var(&mut self, symbol: Symbol) -> Var {
        self.symbols.var(symbol)
    }

    /// The readable name of a symbol, as used in equation listings.
    pub fn symbol_name(&self, symbol: Symbol) -> String {
        match symbol {
            Symbol::Time => "t".into(),
            Symbol::State(i) => self.states[i].label.clone(),
            Symbol::StateDot(i) => format!("der({})", self.states[i].label),
            Symbol::StateDerivative { state, order } => {
                format!("der{order}({})", self.states[state].label)
            }
            Symbol::Algebraic(i) => self.algebraic[i].label.clone(),
            Symbol::AlgebraicDot(i) => format!("der({})", self.algebraic[i].label),
            Symbol::Input(i) => self.inputs[i].label.clone(),
            Symbol::InputDot(i) => format!("der({})", self.inputs[i].label),
            Symbol::Param(i) => self.params[i].label.clone(),
            Symbol::IterationCoefficient => "c".into(),
            Symbol::TrackingInput(i) => format!("w_{}", self.outputs[i].label),
            Symbol::TrackingCoefficient { output, power } => {
                format!("W_{}[{power}]", self.outputs[output].label)
            }
        }
    }

    /// The unit of every parameter, state, algebraic unknown, input and output that has one,
    /// as `(name as written, unit)` in declaration order (an output of the same name as its
    /// variable appears with it once).
    pub fn units(&self) -> Vec<(String, String)> {
        let decls = |d: &[Decl]| {
            d.iter()
                .map(|x| (x.label.clone(), x.unit.clone()))
                .collect::<Vec<_>>()
        };
        let mut all = Vec::new();
        all.extend(
            self.params
                .iter()
                .map(|p| (p.label.clone(), p.unit.clone())),
        );
        all.extend(decls(&self.states));
        all.extend(decls(&self.algebraic));
        all.extend(decls(&self.inputs));
        all.extend(
            self.outputs
                .iter()
                .map(|o| (o.label.clone(), o.unit.clone())),
        );
        let mut out: Vec<(String, String)> = Vec::new();
        for (name, unit) in all {
            if let Some(unit) = unit {
                if !out.iter().any(|(n, _)| *n == name) {
                    out.push((name, unit));
                }
            }
        }
        out
    }

    /// Readable text of an expression of the graph.
    pub fn display(&self, e: ExprId) -> String {
        self.graph
            .display(e, &|v| self.symbol_name(self.symbols.symbol(v)))
    }
}
