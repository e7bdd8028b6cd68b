//! An operator-precedence parser for DSL expressions over `proc_macro2` token trees.
//!
//! The parser is a shunting-yard loop: per group of tokens being read (the expression itself,
//! the inside of `( )`, `[ ]`, call arguments) a `Frame` on an explicit stack holds the
//! pending operators and finished operands; entering a group pushes a frame, leaving it pops
//! one. Nothing recurses, so the depth of the expression costs heap only. Precedence and
//! associativity are Rust's (as `syn` parses them): `=` (right), `..`, `||`, `&&`,
//! comparisons, `|`, `^`, `&`, `<< >>`, `+ -`, `* / %`, `as`, prefix operators, then calls,
//! indexing, method calls and fields. A closure's body extends as far right as possible.
//!
//! `syn` parses the outer structure of a model. Its token buffer is built by recursion over
//! nested groups, so before `syn` sees the model, [`with_stash`] replaces groups nested
//! deeper than a few levels by placeholder identifiers and keeps the groups aside; the
//! expression parser puts them back when it reads a placeholder.

use super::{BinaryOp, ClosureParam, Expr, ExprKind, Node, NodeId, OtherPart, Spans, UnaryOp};
use proc_macro2::{Delimiter, Group, Ident, Spacing, Span, TokenStream, TokenTree};
use std::cell::RefCell;
use syn::parse::ParseStream;

/// Binding strength of operators, higher binds tighter.
mod prec {
    pub const CLOSURE: u8 = 0;
    pub const ASSIGN: u8 = 1;
    pub const RANGE: u8 = 2;
    pub const OR: u8 = 3;
    pub const AND: u8 = 4;
    pub const COMPARE: u8 = 5;
    pub const BIT_OR: u8 = 6;
    pub const BIT_XOR: u8 = 7;
    pub const BIT_AND: u8 = 8;
    pub const SHIFT: u8 = 9;
    pub const SUM: u8 = 10;
    pub const PRODUCT: u8 = 11;
    pub const CAST: u8 = 12;
    pub const PREFIX: u8 = 13;
}

/// Precedence levels of the listing text ([`crate::text`]), used for the parts of
/// unsupported constructs.
const TEXT_ASSIGN: u8 = 0;
const TEXT_POSTFIX: u8 = 5;

fn binary_precedence(op: BinaryOp) -> u8 {
    use BinaryOp::*;
    match op {
        Add | Sub => prec::SUM,
        Mul | Div | Rem => prec::PRODUCT,
        And => prec::AND,
        Or => prec::OR,
        BitXor => prec::BIT_XOR,
        BitAnd => prec::BIT_AND,
        BitOr => prec::BIT_OR,
        Shl | Shr => prec::SHIFT,
        Eq | Lt | Le | Ne | Ge | Gt => prec::COMPARE,
        AddAssign | SubAssign | MulAssign | DivAssign | RemAssign | BitXorAssign | BitAndAssign
        | BitOrAssign | ShlAssign | ShrAssign => prec::ASSIGN,
    }
}

/// Parse one expression from `input`, up to a `,` or `;` at its level or the end.
pub fn parse_expr(input: ParseStream) -> syn::Result<Expr> {
    parse_top(input, true)
}

/// Like [`parse_expr`], but a `{ ... }` ends the expression (the range of `for i in a..b {`).
pub fn parse_expr_without_brace(input: ParseStream) -> syn::Result<Expr> {
    parse_top(input, false)
}

fn parse_top(input: ParseStream, braces: bool) -> syn::Result<Expr> {
    let mut tokens = Vec::new();
    let mut cursor = input.cursor();
    while let Some((tt, next)) = cursor.token_tree() {
        let stop = match &tt {
            TokenTree::Punct(p) => matches!(p.as_char(), ',' | ';'),
            TokenTree::Group(g) => !braces && g.delimiter() == Delimiter::Brace,
            _ => false,
        };
        if stop {
            break;
        }
        tokens.push(unstash(tt));
        cursor = next;
    }
    let outcome = Parser::new(tokens, braces).run()?;
    let consumed = match &outcome {
        Outcome::Done { consumed, .. } | Outcome::MissingOperand { consumed } => *consumed,
    };
    input.step(|c| {
        let mut rest = *c;
        for _ in 0..consumed {
            if let Some((_, next)) = rest.token_tree() {
                rest = next;
            }
        }
        Ok(((), rest))
    })?;
    match outcome {
        Outcome::Done { expr, .. } => Ok(expr),
        Outcome::MissingOperand { .. } => Err(input.error("expected an expression")),
    }
}

/// How a top-level parse ended.
enum Outcome {
    /// An expression, from the first `consumed` tokens.
    Done { expr: Expr, consumed: usize },
    /// The tokens ended (or reached one that cannot continue an expression) where an operand
    /// was expected.
    MissingOperand { consumed: usize },
}

/// What a frame reads.
enum FrameKind {
    /// The expression itself; `braces` says whether `{ ... }` may start an operand.
    Top { braces: bool },
    /// `( ... )` or an invisible group: a parenthesised expression or a tuple.
    Paren { group: Span },
    /// `[a, b]`.
    Array { group: Span },
    /// The arguments of a call; the function is the parent's last operand.
    CallArgs { group: Span },
    /// The arguments of a method call; the receiver is the parent's last operand.
    MethodArgs {
        group: Span,
        method: Ident,
        turbofish: Option<Spans>,
    },
    /// `[i]` after an operand, which is the parent's last operand.
    Index { group: Span },
}

/// An operator waiting for its right operand.
enum PendingKind {
    Prefix(UnaryOp),
    Binary(BinaryOp),
    Assign,
    Range {
        closed: bool,
    },
    RangePrefix {
        closed: bool,
    },
    Closure {
        params: Vec<ClosureParam>,
        params_spans: Spans,
    },
}

struct Pending {
    kind: PendingKind,
    prec: u8,
    spans: Spans,
}

/// The state of reading one group of tokens.
struct Frame {
    tokens: Vec<TokenTree>,
    pos: usize,
    kind: FrameKind,
    /// Where "unexpected end of input" is reported.
    close: Span,
    ops: Vec<Pending>,
    operands: Vec<NodeId>,
    expect_operand: bool,
    /// Finished comma-separated expressions.
    items: Vec<NodeId>,
    commas: usize,
}

impl Frame {
    fn new(tokens: Vec<TokenTree>, kind: FrameKind, close: Span) -> Self {
        Frame {
            tokens,
            pos: 0,
            kind,
            close,
            ops: Vec::new(),
            operands: Vec::new(),
            expect_operand: true,
            items: Vec::new(),
            commas: 0,
        }
    }

    fn for_group(group: &Group, kind: FrameKind) -> Self {
        let tokens = group.stream().into_iter().map(unstash).collect();
        Frame::new(tokens, kind, group.span_close())
    }

    fn peek(&self, ahead: usize) -> Option<&TokenTree> {
        self.tokens.get(self.pos + ahead)
    }

    fn punct_at(&self, ahead: usize, c: char) -> Option<&proc_macro2::Punct> {
        match self.peek(ahead) {
            Some(TokenTree::Punct(p)) if p.as_char() == c => Some(p),
            _ => None,
        }
    }

    /// Whether the tokens at `pos` are `::` (two joint colons).
    fn path_sep_at(&self, ahead: usize) -> bool {
        self.punct_at(ahead, ':')
            .is_some_and(|p| p.spacing() == Spacing::Joint)
            && self.punct_at(ahead + 1, ':').is_some()
    }

    fn is_list(&self) -> bool {
        matches!(
            self.kind,
            FrameKind::Paren { .. }
                | FrameKind::Array { .. }
                | FrameKind::CallArgs { .. }
                | FrameKind::MethodArgs { .. }
        )
    }

    fn braces_allowed(&self) -> bool {
        !matches!(self.kind, FrameKind::Top { braces: false })
    }
}

/// What one step of the loop did.
enum Step {
    Continue,
    Finished(Outcome),
}

struct Parser {
    nodes: Vec<Node>,
    frames: Vec<Frame>,
}

fn internal(span: Span) -> syn::Error {
    syn::Error::new(
        span,
        "internal error: the expression parser lost track of its operands",
    )
}

fn token_spans(tt: &TokenTree) -> Spans {
    Spans::single(tt.span())
}

/// The text of tokens as written (for constructs the DSL does not support).
fn tokens_text(tokens: &[TokenTree]) -> String {
    tokens.iter().cloned().collect::<TokenStream>().to_string()
}

impl Parser {
    fn new(tokens: Vec<TokenTree>, braces: bool) -> Self {
        let close = tokens
            .last()
            .map_or_else(Span::call_site, |t: &TokenTree| t.span());
        Parser {
            nodes: Vec::new(),
            frames: vec![Frame::new(tokens, FrameKind::Top { braces }, close)],
        }
    }

    fn frame(&mut self) -> syn::Result<&mut Frame> {
        self.frames
            .last_mut()
            .ok_or_else(|| internal(Span::call_site()))
    }

    fn run(mut self) -> syn::Result<Outcome> {
        loop {
            let expect_operand = self.frame()?.expect_operand;
            let step = if expect_operand {
                self.operand_step()?
            } else {
                self.operator_step()?
            };
            if let Step::Finished(outcome) = step {
                return Ok(outcome);
            }
        }
    }

    fn spans_of(&self, id: NodeId) -> Spans {
        self.nodes[id].spans
    }

    fn add(&mut self, kind: ExprKind, spans: Spans) -> NodeId {
        self.nodes.push(Node { kind, spans });
        self.nodes.len() - 1
    }

    /// Adds a finished operand to the current frame.
    fn push_operand(&mut self, kind: ExprKind, spans: Spans) -> syn::Result<()> {
        let id = self.add(kind, spans);
        let f = self.frame()?;
        f.operands.push(id);
        f.expect_operand = false;
        Ok(())
    }

    fn pop_operand(&mut self) -> syn::Result<NodeId> {
        let f = self.frame()?;
        let close = f.close;
        f.operands.pop().ok_or_else(|| internal(close))
    }

    fn push_op(&mut self, kind: PendingKind, prec: u8, spans: Spans) -> syn::Result<()> {
        let f = self.frame()?;
        f.ops.push(Pending { kind, prec, spans });
        f.expect_operand = true;
        Ok(())
    }

    /// Applies the last pending operator to its operands.
    fn reduce_one(&mut self) -> syn::Result<()> {
        let f = self.frame()?;
        let close = f.close;
        let op = f.ops.pop().ok_or_else(|| internal(close))?;
        match op.kind {
            PendingKind::Prefix(unary) => {
                let operand = self.pop_operand()?;
                let spans = op.spans.to(self.spans_of(operand));
                let id = self.add(
                    ExprKind::Unary {
                        op: unary,
                        op_span: op.spans.first,
                        operand,
                    },
                    spans,
                );
                self.frame()?.operands.push(id);
            }
            PendingKind::Closure {
                params,
                params_spans,
            } => {
                let body = self.pop_operand()?;
                let spans = op.spans.to(self.spans_of(body));
                let id = self.add(
                    ExprKind::Closure {
                        params,
                        params_spans,
                        body,
                    },
                    spans,
                );
                self.frame()?.operands.push(id);
            }
            PendingKind::RangePrefix { closed } => {
                let end = self.pop_operand()?;
                let spans = op.spans.to(self.spans_of(end));
                let id = self.add(
                    ExprKind::Range {
                        start: None,
                        end: Some(end),
                        closed,
                    },
                    spans,
                );
                self.frame()?.operands.push(id);
            }
            PendingKind::Binary(_) | PendingKind::Assign | PendingKind::Range { .. } => {
                let right = self.pop_operand()?;
                let left = self.pop_operand()?;
                let spans = self.spans_of(left).to(self.spans_of(right));
                let kind = match op.kind {
                    PendingKind::Binary(bin) => ExprKind::Binary {
                        op: bin,
                        op_spans: op.spans,
                        left,
                        right,
                    },
                    PendingKind::Assign => ExprKind::Assign { left, right },
                    PendingKind::Range { closed } => ExprKind::Range {
                        start: Some(left),
                        end: Some(right),
                        closed,
                    },
                    _ => return Err(internal(op.spans.first)),
                };
                let id = self.add(kind, spans);
                self.frame()?.operands.push(id);
            }
        }
        Ok(())
    }

    /// Reduces the pending operators that bind at least as tightly as an incoming binary
    /// operator of precedence `p` (more tightly for the right-associative `=`).
    fn reduce_for(&mut self, p: u8) -> syn::Result<()> {
        loop {
            let f = self.frame()?;
            let Some(top) = f.ops.last() else {
                return Ok(());
            };
            let reduce = top.prec > p || (top.prec == p && p != prec::ASSIGN);
            if !reduce {
                return Ok(());
            }
            self.reduce_one()?;
        }
    }

    /// Ends the current expression of the frame: applies all pending operators; its node.
    fn finish_expression(&mut self) -> syn::Result<NodeId> {
        while !self.frame()?.ops.is_empty() {
            self.reduce_one()?;
        }
        let f = self.frame()?;
        let close = f.close;
        match (f.operands.pop(), f.operands.is_empty()) {
            (Some(id), true) => Ok(id),
            _ => Err(internal(close)),
        }
    }

    /// In operand position with nothing to read: closes a range without end (`a..`, `..`),
    /// or says there is none to close.
    fn close_open_range(&mut self) -> syn::Result<bool> {
        let f = self.frame()?;
        let closed_range = match f.ops.last().map(|o| &o.kind) {
            Some(PendingKind::Range { closed: false }) => false,
            Some(PendingKind::RangePrefix { closed: false }) => true,
            _ => return Ok(false),
        };
        let Some(op) = f.ops.pop() else {
            return Ok(false);
        };
        if closed_range {
            // `..` alone.
            self.push_operand(
                ExprKind::Range {
                    start: None,
                    end: None,
                    closed: false,
                },
                op.spans,
            )?;
        } else {
            let start = self.pop_operand()?;
            let spans = self.spans_of(start).to(op.spans);
            self.push_operand(
                ExprKind::Range {
                    start: Some(start),
                    end: None,
                    closed: false,
                },
                spans,
            )?;
        }
        Ok(true)
    }

    /// Reads an operand (or a prefix operator) at the frame's position.
    fn operand_step(&mut self) -> syn::Result<Step> {
        let f = self.frame()?;
        let next = f.peek(0).cloned();
        let starts_operand = match &next {
            None => false,
            Some(TokenTree::Punct(p)) => matches!(
                p.as_char(),
                '-' | '!' | '*' | '&' | '|' | '.' | ':' | '<' | '#'
            ),
            Some(TokenTree::Group(g)) => g.delimiter() != Delimiter::Brace || f.braces_allowed(),
            Some(_) => true,
        };
        if !starts_operand {
            if self.close_open_range()? {
                return Ok(Step::Continue);
            }
            let f = self.frame()?;
            let empty_list = f.is_list() && f.ops.is_empty() && f.operands.is_empty();
            return match next {
                None if empty_list => self.finish_frame(),
                None => match f.kind {
                    FrameKind::Top { .. } => {
                        Ok(Step::Finished(Outcome::MissingOperand { consumed: f.pos }))
                    }
                    _ => Err(syn::Error::new(
                        f.close,
                        "unexpected end of input, expected an expression",
                    )),
                },
                Some(tt) => match f.kind {
                    FrameKind::Top { .. } => {
                        Ok(Step::Finished(Outcome::MissingOperand { consumed: f.pos }))
                    }
                    _ => Err(syn::Error::new(tt.span(), "expected an expression")),
                },
            };
        }
        let Some(tt) = next else {
            return Ok(Step::Continue);
        };
        match tt {
            TokenTree::Literal(lit) => {
                self.frame()?.pos += 1;
                let spans = Spans::single(lit.span());
                self.push_operand(ExprKind::Lit(syn::Lit::new(lit)), spans)?;
            }
            TokenTree::Ident(ident) => self.ident_operand(ident)?,
            TokenTree::Punct(p) => self.punct_operand(p)?,
            TokenTree::Group(g) => {
                self.frame()?.pos += 1;
                match g.delimiter() {
                    Delimiter::Parenthesis | Delimiter::None => {
                        let frame = Frame::for_group(&g, FrameKind::Paren { group: g.span() });
                        self.frames.push(frame);
                    }
                    Delimiter::Bracket => {
                        let frame = Frame::for_group(&g, FrameKind::Array { group: g.span() });
                        self.frames.push(frame);
                    }
                    Delimiter::Brace => {
                        // A block: not supported, kept for its text.
                        let text = TokenTree::Group(g.clone()).to_string();
                        self.push_operand(
                            ExprKind::Other(vec![OtherPart::Text(text)]),
                            Spans::single(g.span()),
                        )?;
                    }
                }
            }
        }
        Ok(Step::Continue)
    }

    /// Swallows the rest of the current expression (up to a `,` in a list) as one
    /// unsupported construct: `if`, `match`, a qualified path, ...
    fn swallow_rest(&mut self) -> syn::Result<()> {
        let f = self.frame()?;
        let list = f.is_list();
        let start = f.pos;
        let mut end = start;
        while let Some(tt) = f.tokens.get(end) {
            if list && matches!(tt, TokenTree::Punct(p) if p.as_char() == ',') {
                break;
            }
            end += 1;
        }
        let swallowed = &f.tokens[start..end];
        let (Some(first), Some(last)) = (swallowed.first(), swallowed.last()) else {
            return Err(internal(f.close));
        };
        let spans = token_spans(first).to(token_spans(last));
        let text = tokens_text(swallowed);
        f.pos = end;
        self.push_operand(ExprKind::Other(vec![OtherPart::Text(text)]), spans)
    }

    fn ident_operand(&mut self, ident: Ident) -> syn::Result<()> {
        let s = ident.to_string();
        if s == "true" || s == "false" {
            self.frame()?.pos += 1;
            let lit = syn::Lit::Bool(syn::LitBool::new(s == "true", ident.span()));
            return self.push_operand(ExprKind::Lit(lit), Spans::single(ident.span()));
        }
        if is_keyword(&s) {
            return self.swallow_rest();
        }
        self.path_operand(false, Spans::single(ident.span()))
    }

    /// A path at the frame's position (after a leading `::` if `leading_colon`), with a macro
    /// call or struct literal after it taken as unsupported.
    fn path_operand(&mut self, leading_colon: bool, first: Spans) -> syn::Result<()> {
        let f = self.frame()?;
        let start = f.pos;
        let mut segments = Vec::new();
        match f.peek(0) {
            Some(TokenTree::Ident(i)) => segments.push(i.clone()),
            Some(tt) => return Err(syn::Error::new(tt.span(), "expected an identifier")),
            None => return Err(syn::Error::new(f.close, "expected an identifier")),
        }
        f.pos += 1;
        loop {
            if !f.path_sep_at(0) {
                break;
            }
            match f.peek(2) {
                Some(TokenTree::Ident(i)) => {
                    segments.push(i.clone());
                    f.pos += 3;
                }
                _ => {
                    // Generic arguments (`f::<T>`): not supported.
                    f.pos = start;
                    return self.swallow_rest();
                }
            }
        }
        let last = segments
            .last()
            .map_or(first, |i: &Ident| Spans::single(i.span()));
        let spans = first.to(last);
        let macro_call = f
            .punct_at(0, '!')
            .is_some_and(|p| p.spacing() == Spacing::Alone)
            && matches!(f.peek(1), Some(TokenTree::Group(_)));
        let struct_literal = f.braces_allowed()
            && matches!(f.peek(0), Some(TokenTree::Group(g)) if g.delimiter() == Delimiter::Brace);
        if macro_call || struct_literal {
            let take = if macro_call { 2 } else { 1 };
            let mut tokens: Vec<TokenTree> = Vec::new();
            let prefix = if leading_colon { "::" } else { "" };
            let path_text = segments
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join("::");
            tokens.extend(f.tokens[f.pos..f.pos + take].iter().cloned());
            let end = token_spans(&tokens[take - 1]);
            f.pos += take;
            let text = format!("{prefix}{path_text}{}", tokens_text(&tokens));
            return self.push_operand(ExprKind::Other(vec![OtherPart::Text(text)]), spans.to(end));
        }
        self.push_operand(
            ExprKind::Path {
                leading_colon,
                segments,
            },
            spans,
        )
    }

    fn punct_operand(&mut self, p: proc_macro2::Punct) -> syn::Result<()> {
        let span = Spans::single(p.span());
        let f = self.frame()?;
        match p.as_char() {
            '-' | '!' | '*' | '&' => {
                f.pos += 1;
                let op = match p.as_char() {
                    '-' => UnaryOp::Neg,
                    '!' => UnaryOp::Not,
                    '*' => UnaryOp::Deref,
                    _ => UnaryOp::Ref,
                };
                self.push_op(PendingKind::Prefix(op), prec::PREFIX, span)
            }
            '|' => self.closure_params(),
            '.' => {
                let dots = f.punct_at(1, '.').is_some() && p.spacing() == Spacing::Joint;
                if !dots {
                    return Err(syn::Error::new(p.span(), "expected an expression"));
                }
                let closed = f.punct_at(2, '=').is_some()
                    && f.punct_at(1, '.')
                        .is_some_and(|q| q.spacing() == Spacing::Joint);
                let n = if closed { 3 } else { 2 };
                let last = f.peek(n - 1).map_or(span, token_spans);
                f.pos += n;
                self.push_op(
                    PendingKind::RangePrefix { closed },
                    prec::RANGE,
                    span.to(last),
                )
            }
            ':' if f.path_sep_at(0) && matches!(f.peek(2), Some(TokenTree::Ident(_))) => {
                f.pos += 2;
                self.path_operand(true, span)
            }
            '<' | '#' => self.swallow_rest(),
            _ => Err(syn::Error::new(p.span(), "expected an expression")),
        }
    }

    /// `|a, b|` or `||` at the frame's position: the closure's parameters, pending its body.
    fn closure_params(&mut self) -> syn::Result<()> {
        let f = self.frame()?;
        let open = f
            .peek(0)
            .map(token_spans)
            .ok_or_else(|| internal(f.close))?;
        let empty = f
            .punct_at(0, '|')
            .is_some_and(|p| p.spacing() == Spacing::Joint)
            && f.punct_at(1, '|').is_some();
        let mut params = Vec::new();
        let params_spans;
        if empty {
            let close = f.peek(1).map_or(open, token_spans);
            params_spans = open.to(close);
            f.pos += 2;
        } else {
            f.pos += 1;
            let start = f.pos;
            let mut end = start;
            loop {
                match f.tokens.get(end) {
                    Some(TokenTree::Punct(q)) if q.as_char() == '|' => break,
                    Some(_) => end += 1,
                    None => {
                        return Err(syn::Error::new(
                            f.close,
                            "unexpected end of input, expected `|` after the closure's parameters",
                        ))
                    }
                }
            }
            let inside = &f.tokens[start..end];
            for param in inside.split(|t| matches!(t, TokenTree::Punct(q) if q.as_char() == ',')) {
                if param.is_empty() {
                    continue;
                }
                let ident = match param {
                    [TokenTree::Ident(i)] if i != "_" && !is_keyword(&i.to_string()) => {
                        Some(i.clone())
                    }
                    _ => None,
                };
                params.push(ClosureParam {
                    ident,
                    text: tokens_text(param),
                });
            }
            params_spans = match (inside.first(), inside.last()) {
                (Some(a), Some(b)) => token_spans(a).to(token_spans(b)),
                _ => open.to(token_spans(&f.tokens[end])),
            };
            f.pos = end + 1;
        }
        self.push_op(
            PendingKind::Closure {
                params,
                params_spans,
            },
            prec::CLOSURE,
            open,
        )
    }

    /// Reads an operator (or the end of the expression) at the frame's position.
    fn operator_step(&mut self) -> syn::Result<Step> {
        let f = self.frame()?;
        let Some(tt) = f.peek(0).cloned() else {
            return self.end_of_expression();
        };
        match tt {
            TokenTree::Punct(ref p) => {
                let (op, n) = read_operator(&f.tokens[f.pos..]);
                let spans = token_spans(&tt).to(token_spans(&f.tokens[f.pos + n - 1]));
                match op {
                    "," if f.is_list() => {
                        let item = self.finish_expression()?;
                        let f = self.frame()?;
                        f.items.push(item);
                        f.commas += 1;
                        f.pos += 1;
                        f.expect_operand = true;
                        Ok(Step::Continue)
                    }
                    "=" => {
                        f.pos += n;
                        self.reduce_for(prec::ASSIGN)?;
                        self.push_op(PendingKind::Assign, prec::ASSIGN, spans)?;
                        Ok(Step::Continue)
                    }
                    ".." | "..=" => {
                        f.pos += n;
                        self.reduce_for(prec::RANGE)?;
                        self.push_op(
                            PendingKind::Range {
                                closed: op == "..=",
                            },
                            prec::RANGE,
                            spans,
                        )?;
                        Ok(Step::Continue)
                    }
                    "." => self.member(p.span()),
                    "?" => {
                        f.pos += 1;
                        let base = self.pop_operand()?;
                        let spans = self.spans_of(base).to(spans);
                        self.push_operand(
                            ExprKind::Other(vec![
                                OtherPart::Child(base, TEXT_POSTFIX),
                                OtherPart::Text("?".into()),
                            ]),
                            spans,
                        )?;
                        Ok(Step::Continue)
                    }
                    _ => match BinaryOp::ALL.iter().find(|(s, _)| *s == op) {
                        Some(&(_, bin)) => {
                            f.pos += n;
                            let p = binary_precedence(bin);
                            self.reduce_for(p)?;
                            self.push_op(PendingKind::Binary(bin), p, spans)?;
                            Ok(Step::Continue)
                        }
                        None => self.unexpected(tt),
                    },
                }
            }
            TokenTree::Ident(ref i) if i == "as" => self.cast(i.span()),
            TokenTree::Group(ref g) if g.delimiter() == Delimiter::Parenthesis => {
                f.pos += 1;
                let frame = Frame::for_group(g, FrameKind::CallArgs { group: g.span() });
                self.frames.push(frame);
                Ok(Step::Continue)
            }
            TokenTree::Group(ref g) if g.delimiter() == Delimiter::Bracket => {
                f.pos += 1;
                let frame = Frame::for_group(g, FrameKind::Index { group: g.span() });
                self.frames.push(frame);
                Ok(Step::Continue)
            }
            other => self.unexpected(other),
        }
    }

    /// A token that cannot continue the expression: at the top it ends the expression (the
    /// caller reports what it expected there), inside a group it is an error.
    fn unexpected(&mut self, tt: TokenTree) -> syn::Result<Step> {
        let f = self.frame()?;
        match f.kind {
            FrameKind::Top { .. } => self.end_of_expression(),
            FrameKind::Index { .. } => Err(syn::Error::new(tt.span(), "expected `]`")),
            _ => Err(syn::Error::new(tt.span(), "expected `,`")),
        }
    }

    /// The expression of the frame is complete.
    fn end_of_expression(&mut self) -> syn::Result<Step> {
        let item = self.finish_expression()?;
        let f = self.frame()?;
        if let FrameKind::Top { .. } = f.kind {
            let consumed = f.pos;
            let close = f.close;
            let nodes = std::mem::take(&mut self.nodes);
            if item + 1 != nodes.len() {
                return Err(internal(close));
            }
            let expr = Expr::from_nodes(nodes).ok_or_else(|| internal(close))?;
            return Ok(Step::Finished(Outcome::Done { expr, consumed }));
        }
        f.items.push(item);
        if f.pos < f.tokens.len() {
            return Err(internal(f.close));
        }
        self.finish_frame()
    }

    /// Leaves a finished group: its node becomes an operand of the enclosing frame.
    fn finish_frame(&mut self) -> syn::Result<Step> {
        let frame = self
            .frames
            .pop()
            .ok_or_else(|| internal(Span::call_site()))?;
        let items = frame.items;
        let single = items.len() == 1 && frame.commas == 0;
        match frame.kind {
            FrameKind::Top { .. } => return Err(internal(frame.close)),
            FrameKind::Paren { group } => {
                let spans = Spans::single(group);
                if single {
                    self.push_operand(ExprKind::Paren(items[0]), spans)?;
                } else {
                    // A tuple (or `()`): not supported, kept for its text.
                    let mut parts = vec![OtherPart::Text("(".into())];
                    for (k, item) in items.iter().enumerate() {
                        if k > 0 {
                            parts.push(OtherPart::Text(", ".into()));
                        }
                        parts.push(OtherPart::Child(*item, TEXT_ASSIGN));
                    }
                    if items.len() == 1 {
                        parts.push(OtherPart::Text(",".into()));
                    }
                    parts.push(OtherPart::Text(")".into()));
                    self.push_operand(ExprKind::Other(parts), spans)?;
                }
            }
            FrameKind::Array { group } => {
                self.push_operand(ExprKind::Array(items), Spans::single(group))?;
            }
            FrameKind::CallArgs { group } => {
                let func = self.pop_operand()?;
                let spans = self.spans_of(func).to(Spans::single(group));
                self.push_operand(ExprKind::Call { func, args: items }, spans)?;
            }
            FrameKind::MethodArgs {
                group,
                method,
                turbofish,
            } => {
                let receiver = self.pop_operand()?;
                let spans = self.spans_of(receiver).to(Spans::single(group));
                self.push_operand(
                    ExprKind::MethodCall {
                        receiver,
                        method,
                        turbofish,
                        args: items,
                    },
                    spans,
                )?;
            }
            FrameKind::Index { group } => {
                if !single {
                    return Err(syn::Error::new(
                        group,
                        "expected one index expression in `[ ]`",
                    ));
                }
                let base = self.pop_operand()?;
                let spans = self.spans_of(base).to(Spans::single(group));
                self.push_operand(
                    ExprKind::Index {
                        base,
                        index: items[0],
                    },
                    spans,
                )?;
            }
        }
        Ok(Step::Continue)
    }

    /// `.name(args)`, `.name::<T>(args)`, or a field `.name` / `.0` after an operand.
    fn member(&mut self, dot: Span) -> syn::Result<Step> {
        let f = self.frame()?;
        let name = f.peek(1).cloned();
        let name_spans = match &name {
            Some(tt @ (TokenTree::Ident(_) | TokenTree::Literal(_))) => token_spans(tt),
            Some(tt) => {
                return Err(syn::Error::new(
                    tt.span(),
                    "expected a method or field name",
                ))
            }
            None => {
                return Err(syn::Error::new(
                    dot,
                    "unexpected end of input, expected a method name",
                ))
            }
        };
        f.pos += 2;
        let mut turbofish = None;
        if f.path_sep_at(0) && f.punct_at(2, '<').is_some() {
            let start = token_spans(&f.tokens[f.pos]);
            let mut depth = 0usize;
            let mut end = f.pos + 2;
            loop {
                match f.tokens.get(end) {
                    Some(TokenTree::Punct(q)) if q.as_char() == '<' => depth += 1,
                    Some(TokenTree::Punct(q)) if q.as_char() == '>' => {
                        depth = depth.saturating_sub(1);
                        if depth == 0 {
                            break;
                        }
                    }
                    Some(_) => {}
                    None => {
                        return Err(syn::Error::new(
                            f.close,
                            "unexpected end of input, expected `>`",
                        ))
                    }
                }
                end += 1;
            }
            turbofish = Some(start.to(token_spans(&f.tokens[end])));
            f.pos = end + 1;
        }
        let call_group = match (f.peek(0), &name) {
            (Some(TokenTree::Group(g)), Some(TokenTree::Ident(_)))
                if g.delimiter() == Delimiter::Parenthesis =>
            {
                Some(g.clone())
            }
            _ => None,
        };
        match (call_group, name) {
            (Some(g), Some(TokenTree::Ident(method))) => {
                f.pos += 1;
                let frame = Frame::for_group(
                    &g,
                    FrameKind::MethodArgs {
                        group: g.span(),
                        method,
                        turbofish,
                    },
                );
                self.frames.push(frame);
            }
            (_, name) => {
                // A field: not supported, kept for its text.
                let base = self.pop_operand()?;
                let spans = self.spans_of(base).to(name_spans);
                let text = name.map(|n| format!(".{n}")).unwrap_or_default();
                self.push_operand(
                    ExprKind::Other(vec![
                        OtherPart::Child(base, TEXT_POSTFIX),
                        OtherPart::Text(text),
                    ]),
                    spans,
                )?;
            }
        }
        Ok(Step::Continue)
    }

    /// `operand as Type`: not supported, kept for its text.
    fn cast(&mut self, as_span: Span) -> syn::Result<Step> {
        self.reduce_for(prec::CAST)?;
        let f = self.frame()?;
        f.pos += 1;
        let start = f.pos;
        let mut end = start;
        // A type: names joined by `::`, then generic arguments in `< >`; or one group.
        loop {
            match f.tokens.get(end) {
                Some(TokenTree::Ident(_)) => end += 1,
                Some(TokenTree::Group(g)) if end == start && g.delimiter() != Delimiter::Brace => {
                    end += 1;
                    break;
                }
                _ => break,
            }
            let colons = matches!(f.tokens.get(end), Some(TokenTree::Punct(q)) if q.as_char() == ':' && q.spacing() == Spacing::Joint)
                && matches!(f.tokens.get(end + 1), Some(TokenTree::Punct(q)) if q.as_char() == ':');
            if colons {
                end += 2;
                continue;
            }
            if matches!(f.tokens.get(end), Some(TokenTree::Punct(q)) if q.as_char() == '<') {
                let mut depth = 0usize;
                while let Some(tt) = f.tokens.get(end) {
                    end += 1;
                    match tt {
                        TokenTree::Punct(q) if q.as_char() == '<' => depth += 1,
                        TokenTree::Punct(q) if q.as_char() == '>' => {
                            depth = depth.saturating_sub(1);
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                }
            }
            break;
        }
        if end == start {
            return Err(syn::Error::new(as_span, "expected a type after `as`"));
        }
        let ty = &f.tokens[start..end];
        let text = format!(" as {}", tokens_text(ty));
        let last = token_spans(&ty[ty.len() - 1]);
        f.pos = end;
        let operand = self.pop_operand()?;
        let spans = self.spans_of(operand).to(last);
        self.push_operand(
            ExprKind::Other(vec![
                OtherPart::Child(operand, TEXT_POSTFIX),
                OtherPart::Text(text),
            ]),
            spans,
        )?;
        Ok(Step::Continue)
    }
}

/// The operator spelled by the punctuation at the start of `tokens` (joined as the lexer
/// joined them) and how many tokens it takes.
fn read_operator(tokens: &[TokenTree]) -> (&'static str, usize) {
    let mut chars = String::new();
    for tt in tokens.iter().take(3) {
        let TokenTree::Punct(p) = tt else { break };
        chars.push(p.as_char());
        if p.spacing() == Spacing::Alone {
            break;
        }
    }
    const SPECIAL: &[&str] = &[
        "..=", "...", "..", "::", "=>", "->", "=", ".", "?", ",", ";",
    ];
    for len in (1..=chars.len()).rev() {
        let s = &chars[..len];
        if let Some(op) = SPECIAL.iter().find(|o| **o == s) {
            return (op, len);
        }
        if let Some((op, _)) = BinaryOp::ALL.iter().find(|(o, _)| *o == s) {
            return (op, len);
        }
    }
    ("", 1)
}

/// Rust's keywords that cannot start a path (`self`, `Self`, `super` and `crate` can).
fn is_keyword(s: &str) -> bool {
    matches!(
        s,
        "as" | "async"
            | "await"
            | "break"
            | "const"
            | "continue"
            | "dyn"
            | "else"
            | "enum"
            | "extern"
            | "fn"
            | "for"
            | "if"
            | "impl"
            | "in"
            | "let"
            | "loop"
            | "match"
            | "mod"
            | "move"
            | "mut"
            | "pub"
            | "ref"
            | "return"
            | "static"
            | "struct"
            | "trait"
            | "type"
            | "unsafe"
            | "use"
            | "where"
            | "while"
            | "yield"
            | "box"
            | "become"
            | "do"
            | "try"
    )
}

/// Groups set aside by [`with_stash`], and the prefix of their placeholders.
struct Stash {
    prefix: String,
    groups: Vec<Group>,
}

thread_local! {
    static STASH: RefCell<Option<Stash>> = const { RefCell::new(None) };
}

/// Nesting of non-brace groups beyond which a group is set aside.
const MAX_KEPT_NESTING: usize = 16;

/// Nesting of groups of any kind beyond which a group is set aside (deeply nested `for`
/// loops stay visible to `syn` up to here).
const MAX_KEPT_DEPTH: usize = 128;

/// The token of a placeholder as the group it stands for; other tokens as they are.
fn unstash(tt: TokenTree) -> TokenTree {
    let TokenTree::Ident(ident) = &tt else {
        return tt;
    };
    let found = STASH.with(|cell| {
        let stash = cell.borrow();
        let stash = stash.as_ref()?;
        let index: usize = ident
            .to_string()
            .strip_prefix(&stash.prefix)?
            .parse()
            .ok()?;
        stash.groups.get(index).cloned()
    });
    match found {
        Some(group) => TokenTree::Group(group),
        None => tt,
    }
}

/// Removes the stash when dropped, also on a panic.
struct StashGuard;

impl Drop for StashGuard {
    fn drop(&mut self) {
        STASH.with(|cell| cell.borrow_mut().take());
    }
}

/// Runs `f` on `input` with every group nested more than a few levels deep replaced by a
/// placeholder identifier; the expression parser reads the placeholders as the groups.
///
/// `syn`'s token buffer recurses once per nested group; after this, it only sees a bounded
/// nesting, whatever the depth of the user's expressions. Computed with an explicit stack.
pub fn with_stash<R>(input: TokenStream, f: impl FnOnce(TokenStream) -> R) -> R {
    let prefix = placeholder_prefix(&input);
    let mut groups = Vec::new();
    let flat = flatten(input, &prefix, &mut groups);
    let _guard = StashGuard;
    STASH.with(|cell| *cell.borrow_mut() = Some(Stash { prefix, groups }));
    f(flat)
}

/// One group being rebuilt by [`flatten`].
struct FlattenFrame {
    original: Option<Group>,
    tokens: proc_macro2::token_stream::IntoIter,
    out: Vec<TokenTree>,
    changed: bool,
    depth: usize,
    nesting: usize,
}

fn flatten(input: TokenStream, prefix: &str, groups: &mut Vec<Group>) -> TokenStream {
    let mut stack = vec![FlattenFrame {
        original: None,
        tokens: input.into_iter(),
        out: Vec::new(),
        changed: false,
        depth: 0,
        nesting: 0,
    }];
    loop {
        let Some(frame) = stack.last_mut() else {
            return TokenStream::new();
        };
        match frame.tokens.next() {
            Some(TokenTree::Group(g)) => {
                let brace = g.delimiter() == Delimiter::Brace;
                let depth = frame.depth + 1;
                let nesting = frame.nesting + usize::from(!brace);
                if depth > MAX_KEPT_DEPTH || nesting > MAX_KEPT_NESTING {
                    let name = format!("{prefix}{}", groups.len());
                    frame
                        .out
                        .push(TokenTree::Ident(Ident::new(&name, g.span())));
                    frame.changed = true;
                    groups.push(g);
                } else {
                    let tokens = g.stream().into_iter();
                    stack.push(FlattenFrame {
                        original: Some(g),
                        tokens,
                        out: Vec::new(),
                        changed: false,
                        depth,
                        nesting,
                    });
                }
            }
            Some(tt) => frame.out.push(tt),
            None => {
                let Some(done) = stack.pop() else {
                    return TokenStream::new();
                };
                let stream: TokenStream = done.out.into_iter().collect();
                let Some(original) = done.original else {
                    return stream;
                };
                let rebuilt = if done.changed {
                    let mut g = Group::new(original.delimiter(), stream);
                    g.set_span(original.span());
                    g
                } else {
                    original
                };
                if let Some(parent) = stack.last_mut() {
                    parent.changed |= done.changed;
                    parent.out.push(TokenTree::Group(rebuilt));
                }
            }
        }
    }
}

/// A prefix for placeholders that no identifier of `input` starts with.
fn placeholder_prefix(input: &TokenStream) -> String {
    let mut prefix = String::from("__dpc_group_");
    let mut idents = Vec::new();
    let mut stack = vec![input.clone().into_iter()];
    while let Some(tokens) = stack.last_mut() {
        match tokens.next() {
            Some(TokenTree::Ident(i)) => {
                let s = i.to_string();
                if s.starts_with("__dpc_group_") {
                    idents.push(s);
                }
            }
            Some(TokenTree::Group(g)) => stack.push(g.stream().into_iter()),
            Some(_) => {}
            None => {
                stack.pop();
            }
        }
    }
    while idents.iter().any(|s| s.starts_with(&prefix)) {
        prefix.push('x');
    }
    prefix
}
