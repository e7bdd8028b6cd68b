//! The DSL's own expression syntax tree, stored flat.
//!
//! Expressions of a model are parsed by [`parser`] into an [`Expr`]: one vector of nodes in
//! which every node's children come before it (post-order), the root last. Nothing here
//! recurses along the depth of the user's expression: the parser keeps its state on
//! explicit stacks, the lowering ([`crate::lower`]) and the listing text ([`crate::text`])
//! walk the nodes with explicit stacks or in vector order, and dropping an `Expr` drops a
//! vector. A 100 000-deep expression costs heap proportional to its size and no call stack.
//!
//! `syn`'s expression types would recurse in parsing, printing and dropping, so the macro
//! needed a stack sized from the input (formerly grown with `stacker`); this tree is why it no
//! longer does. `syn` still parses the model's outer structure (sections, names, units).
//!
//! The tree covers what the DSL accepts (numbers, names and paths, `-`, `+ - * /`, `==` and
//! `=` at the top of an equation, calls and method calls, indexing, ranges, the closure of
//! `sum`, array literals for parameter defaults, parentheses) and also recognises the rest of
//! Rust's operators and a few other forms (comparisons, `%`, `!`, casts, field access,
//! blocks, `if`, ...) as nodes of their own, so that the lowering can refuse them with a
//! message on their tokens instead of a bare syntax error.
//!
//! Every node carries the spans of its first and last token ([`Spans`]), as `syn` does for
//! its expressions, so errors underline the same tokens as before.

pub mod parser;

use proc_macro2::{Ident, Punct, Spacing, Span, TokenStream};
use quote::ToTokens;

pub use parser::{parse_expr, parse_expr_without_brace};

/// Index of a node in its [`Expr`].
pub type NodeId = usize;

/// The spans of the first and last token of a piece of syntax; an error built from them
/// (`syn::Error::new_spanned`) underlines everything in between, as for `syn`'s own trees.
#[derive(Clone, Copy, Debug)]
pub struct Spans {
    /// Span of the first token (a whole group if it is one).
    pub first: Span,
    /// Span of the last token (a whole group if it is one).
    pub last: Span,
}

impl Spans {
    /// The spans of a single token.
    pub fn single(span: Span) -> Self {
        Spans {
            first: span,
            last: span,
        }
    }

    /// From the start of `self` to the end of `end`.
    pub fn to(self, end: Spans) -> Self {
        Spans {
            first: self.first,
            last: end.last,
        }
    }

    /// The span to report at when only one is possible: the first token's, joined with the
    /// last one's where the compiler supports it.
    pub fn joined(self) -> Span {
        self.first.join(self.last).unwrap_or(self.first)
    }
}

impl ToTokens for Spans {
    /// Two placeholder tokens carrying the first and last span: all `syn::Error::new_spanned`
    /// looks at.
    fn to_tokens(&self, tokens: &mut TokenStream) {
        for span in [self.first, self.last] {
            let mut p = Punct::new('#', Spacing::Alone);
            p.set_span(span);
            tokens.extend([proc_macro2::TokenTree::Punct(p)]);
        }
    }
}

/// Prefix operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnaryOp {
    /// `-x`, the only one the DSL accepts.
    Neg,
    /// `!x`.
    Not,
    /// `*x`.
    Deref,
    /// `&x`.
    Ref,
}

impl UnaryOp {
    /// The operator as written.
    pub fn as_str(self) -> &'static str {
        match self {
            UnaryOp::Neg => "-",
            UnaryOp::Not => "!",
            UnaryOp::Deref => "*",
            UnaryOp::Ref => "&",
        }
    }
}

/// Binary operators other than `=` (which is [`ExprKind::Assign`]) and ranges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum BinaryOp {
    Add,
    Sub,
    Mul,
    Div,
    Rem,
    And,
    Or,
    BitXor,
    BitAnd,
    BitOr,
    Shl,
    Shr,
    Eq,
    Lt,
    Le,
    Ne,
    Ge,
    Gt,
    AddAssign,
    SubAssign,
    MulAssign,
    DivAssign,
    RemAssign,
    BitXorAssign,
    BitAndAssign,
    BitOrAssign,
    ShlAssign,
    ShrAssign,
}

impl BinaryOp {
    /// Every operator with its spelling, longest first where one is a prefix of another.
    pub const ALL: &'static [(&'static str, BinaryOp)] = &[
        ("<<=", BinaryOp::ShlAssign),
        (">>=", BinaryOp::ShrAssign),
        ("&&", BinaryOp::And),
        ("||", BinaryOp::Or),
        ("<<", BinaryOp::Shl),
        (">>", BinaryOp::Shr),
        ("==", BinaryOp::Eq),
        ("<=", BinaryOp::Le),
        ("!=", BinaryOp::Ne),
        (">=", BinaryOp::Ge),
        ("+=", BinaryOp::AddAssign),
        ("-=", BinaryOp::SubAssign),
        ("*=", BinaryOp::MulAssign),
        ("/=", BinaryOp::DivAssign),
        ("%=", BinaryOp::RemAssign),
        ("^=", BinaryOp::BitXorAssign),
        ("&=", BinaryOp::BitAndAssign),
        ("|=", BinaryOp::BitOrAssign),
        ("+", BinaryOp::Add),
        ("-", BinaryOp::Sub),
        ("*", BinaryOp::Mul),
        ("/", BinaryOp::Div),
        ("%", BinaryOp::Rem),
        ("^", BinaryOp::BitXor),
        ("&", BinaryOp::BitAnd),
        ("|", BinaryOp::BitOr),
        ("<", BinaryOp::Lt),
        (">", BinaryOp::Gt),
    ];

    /// The operator as written.
    pub fn as_str(self) -> &'static str {
        BinaryOp::ALL
            .iter()
            .find(|(_, op)| *op == self)
            .map_or("?", |(s, _)| s)
    }
}

/// A closure parameter (the DSL accepts exactly one plain name, in `sum(.., |j| ..)`).
#[derive(Clone, Debug)]
pub struct ClosureParam {
    /// The name, if the parameter is a plain identifier (not `_`, `mut j`, `j: usize`, ...).
    pub ident: Option<Ident>,
    /// The parameter as written, for the listing.
    pub text: String,
}

/// A piece of a construct the DSL does not support, kept for its text.
#[derive(Clone, Debug)]
pub enum OtherPart {
    /// Tokens as written.
    Text(String),
    /// A subexpression, printed in parentheses if it binds more loosely than the level.
    Child(NodeId, u8),
}

/// What a node is.
#[derive(Clone, Debug)]
pub enum ExprKind {
    /// A literal: a number, string, `true`, ...
    Lit(syn::Lit),
    /// A name or path: `x`, `PI`, `std::f64::consts::PI`.
    Path {
        /// Whether the path starts with `::`.
        leading_colon: bool,
        /// Its segments.
        segments: Vec<Ident>,
    },
    /// `( e )`, or an invisible group from a `macro_rules!` expansion.
    Paren(NodeId),
    /// `-x` and the other prefix operators.
    Unary {
        /// The operator.
        op: UnaryOp,
        /// Span of the operator.
        op_span: Span,
        /// The operand.
        operand: NodeId,
    },
    /// `a + b` and the other binary operators.
    Binary {
        /// The operator.
        op: BinaryOp,
        /// Spans of the operator's tokens.
        op_spans: Spans,
        /// Left operand.
        left: NodeId,
        /// Right operand.
        right: NodeId,
    },
    /// `a = b`.
    Assign {
        /// Left side.
        left: NodeId,
        /// Right side.
        right: NodeId,
    },
    /// `f(a, b)`.
    Call {
        /// The function.
        func: NodeId,
        /// The arguments.
        args: Vec<NodeId>,
    },
    /// `x.f(a)`.
    MethodCall {
        /// The receiver.
        receiver: NodeId,
        /// The method's name.
        method: Ident,
        /// Spans of a turbofish `::<..>`, if written.
        turbofish: Option<Spans>,
        /// The arguments after the receiver.
        args: Vec<NodeId>,
    },
    /// `q[i]`.
    Index {
        /// The indexed expression.
        base: NodeId,
        /// The index.
        index: NodeId,
    },
    /// `a..b`, `a..=b`, with either bound optional.
    Range {
        /// Start bound.
        start: Option<NodeId>,
        /// End bound.
        end: Option<NodeId>,
        /// `..=` rather than `..`.
        closed: bool,
    },
    /// `|j| body`.
    Closure {
        /// The parameters.
        params: Vec<ClosureParam>,
        /// Spans of the parameters (of the `|`s if there are none).
        params_spans: Spans,
        /// The body.
        body: NodeId,
    },
    /// `[a, b, c]`.
    Array(Vec<NodeId>),
    /// Anything else (a block, `if`, a cast, a field, a tuple, ...), which the lowering
    /// refuses as a whole: its text in pieces.
    Other(Vec<OtherPart>),
}

/// One node: what it is and the spans of its tokens.
#[derive(Clone, Debug)]
pub struct Node {
    /// What it is; children are indices of earlier nodes.
    pub kind: ExprKind,
    /// First and last token.
    pub spans: Spans,
}

/// A parsed expression: its nodes in post-order (children before parents), root last.
#[derive(Clone, Debug)]
pub struct Expr {
    nodes: Vec<Node>,
}

impl Expr {
    /// A tree from nodes in post-order; `None` if empty or a child does not come before its
    /// parent.
    pub fn from_nodes(nodes: Vec<Node>) -> Option<Self> {
        let ok = !nodes.is_empty()
            && nodes
                .iter()
                .enumerate()
                .all(|(i, n)| children(&n.kind).into_iter().all(|c| c < i));
        ok.then_some(Expr { nodes })
    }

    /// The root node.
    pub fn root(&self) -> ExprRef<'_> {
        ExprRef {
            tree: self,
            id: self.nodes.len() - 1,
        }
    }

    /// All nodes, children before parents.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }
}

/// The children of a node, in source order.
pub fn children(kind: &ExprKind) -> Vec<NodeId> {
    match kind {
        ExprKind::Lit(_) | ExprKind::Path { .. } => Vec::new(),
        ExprKind::Paren(c) => vec![*c],
        ExprKind::Unary { operand, .. } => vec![*operand],
        ExprKind::Binary { left, right, .. } | ExprKind::Assign { left, right } => {
            vec![*left, *right]
        }
        ExprKind::Call { func, args } => {
            std::iter::once(*func).chain(args.iter().copied()).collect()
        }
        ExprKind::MethodCall { receiver, args, .. } => std::iter::once(*receiver)
            .chain(args.iter().copied())
            .collect(),
        ExprKind::Index { base, index } => vec![*base, *index],
        ExprKind::Range { start, end, .. } => start.iter().chain(end).copied().collect(),
        ExprKind::Closure { body, .. } => vec![*body],
        ExprKind::Array(items) => items.clone(),
        ExprKind::Other(parts) => parts
            .iter()
            .filter_map(|p| match p {
                OtherPart::Child(c, _) => Some(*c),
                OtherPart::Text(_) => None,
            })
            .collect(),
    }
}

/// A node of an [`Expr`] together with its tree, to walk from.
#[derive(Clone, Copy)]
pub struct ExprRef<'a> {
    tree: &'a Expr,
    id: NodeId,
}

impl<'a> ExprRef<'a> {
    /// What the node is.
    pub fn kind(self) -> &'a ExprKind {
        &self.tree.nodes[self.id].kind
    }

    /// Spans of its first and last token.
    pub fn spans(self) -> Spans {
        self.tree.nodes[self.id].spans
    }

    /// Its index in the tree.
    pub fn id(self) -> NodeId {
        self.id
    }

    /// Another node of the same tree.
    pub fn at(self, id: NodeId) -> ExprRef<'a> {
        ExprRef {
            tree: self.tree,
            id,
        }
    }

    /// The node without the parentheses (and invisible groups) around it.
    pub fn strip_parentheses(self) -> ExprRef<'a> {
        let mut e = self;
        while let ExprKind::Paren(inner) = e.kind() {
            e = e.at(*inner);
        }
        e
    }

    /// The identifier of a plain one-segment path (through parentheses).
    pub fn path_ident(self) -> Option<&'a Ident> {
        match self.strip_parentheses().kind() {
            ExprKind::Path {
                leading_colon: false,
                segments,
            } if segments.len() == 1 => segments.first(),
            _ => None,
        }
    }

    /// The name of the function of a call `f(..)`.
    pub fn call_name(self) -> Option<String> {
        match self.kind() {
            ExprKind::Call { func, .. } => self.at(*func).path_ident().map(|i| i.to_string()),
            _ => None,
        }
    }
}

impl ToTokens for ExprRef<'_> {
    fn to_tokens(&self, tokens: &mut TokenStream) {
        self.spans().to_tokens(tokens);
    }
}

impl ToTokens for Expr {
    fn to_tokens(&self, tokens: &mut TokenStream) {
        self.root().to_tokens(tokens);
    }
}

#[cfg(test)]
mod tests;
