//! Normalised text of DSL expressions, for the equation listing of generated models.
//!
//! Prints the supported subset of Rust expressions with single spaces around binary
//! operators and only the parentheses that precedence requires, so that the listing reads
//! like the model as written, independent of the user's formatting.

use crate::expr::{BinaryOp, ExprKind, ExprRef, OtherPart, UnaryOp};
use quote::ToTokens;

/// Precedence levels, higher binds tighter.
const ASSIGN: u8 = 0;
const COMPARE: u8 = 1;
const SUM: u8 = 2;
const PRODUCT: u8 = 3;
const PREFIX: u8 = 4;
const POSTFIX: u8 = 5;

/// Normalised text of `expr`.
pub fn expr_text(expr: ExprRef<'_>) -> String {
    expr_text_with(expr, &|_| None, &|_| None)
}

/// Normalised text of `expr` for one index of a family: a name `values` knows (an index
/// variable such as `i`) is written as its value, and a subscript whose value is known from
/// `values` and `constants` is written as the number (`q[i + 1]` with `i = 2` reads `q[3]`,
/// `q[N - 1]` with `N = 3` reads `q[2]`).
pub fn expr_text_with(
    expr: ExprRef<'_>,
    values: &dyn Fn(&str) -> Option<i64>,
    constants: &dyn Fn(&str) -> Option<i64>,
) -> String {
    let mut s = String::new();
    let known = |s: &str| values(s).or_else(|| constants(s));
    write_expr(expr, values, &known, &mut s);
    s
}

/// The value of an integer expression of literals, names known to `values`, `+ - *`,
/// unary `-`, parentheses, `min` and `max`; `None` if any part is unknown or it overflows.
///
/// Evaluated with an explicit stack: operands are visited first, their values kept on a
/// value stack.
pub fn int_value(expr: ExprRef<'_>, values: &dyn Fn(&str) -> Option<i64>) -> Option<i64> {
    // (node, whether its operands are already on the value stack)
    let mut todo = vec![(expr, false)];
    let mut stack: Vec<Option<i64>> = Vec::new();
    while let Some((e, ready)) = todo.pop() {
        let e = e.strip_parentheses();
        let operands: Vec<ExprRef<'_>> = match e.kind() {
            ExprKind::Unary {
                op: UnaryOp::Neg,
                operand,
                ..
            } => vec![e.at(*operand)],
            ExprKind::Binary {
                op: BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul,
                left,
                right,
                ..
            } => vec![e.at(*left), e.at(*right)],
            ExprKind::Call { args, .. }
                if args.len() == 2 && matches!(e.call_name().as_deref(), Some("min" | "max")) =>
            {
                vec![e.at(args[0]), e.at(args[1])]
            }
            ExprKind::Lit(syn::Lit::Int(i)) => {
                stack.push(i.base10_parse::<i64>().ok());
                continue;
            }
            ExprKind::Path { .. } => {
                stack.push(e.path_ident().and_then(|i| values(&i.to_string())));
                continue;
            }
            _ => {
                stack.push(None);
                continue;
            }
        };
        if !ready {
            todo.push((e, true));
            todo.extend(operands.into_iter().rev().map(|o| (o, false)));
            continue;
        }
        let n = operands.len();
        let args: Vec<Option<i64>> = stack.split_off(stack.len().saturating_sub(n));
        let value = match (e.kind(), args.as_slice()) {
            (ExprKind::Unary { .. }, [a]) => a.and_then(i64::checked_neg),
            (ExprKind::Binary { op, .. }, [Some(l), Some(r)]) => match op {
                BinaryOp::Add => l.checked_add(*r),
                BinaryOp::Sub => l.checked_sub(*r),
                _ => l.checked_mul(*r),
            },
            (ExprKind::Call { .. }, [Some(a), Some(b)]) => {
                if e.call_name().as_deref() == Some("min") {
                    Some(*a.min(b))
                } else {
                    Some(*a.max(b))
                }
            }
            _ => None,
        };
        stack.push(value);
    }
    stack.pop().flatten()
}

fn precedence(expr: ExprRef<'_>) -> u8 {
    let expr = expr.strip_parentheses();
    match expr.kind() {
        ExprKind::Assign { .. } => ASSIGN,
        ExprKind::Binary { op, .. } => match op {
            BinaryOp::Add | BinaryOp::Sub => SUM,
            BinaryOp::Mul | BinaryOp::Div | BinaryOp::Rem => PRODUCT,
            _ => COMPARE,
        },
        ExprKind::Unary { .. } => PREFIX,
        ExprKind::Lit(l) if lit_is_negative(l) => PREFIX,
        _ => POSTFIX,
    }
}

/// `expr` without the parentheses (and invisible groups) around it.
pub fn strip_parentheses(expr: ExprRef<'_>) -> ExprRef<'_> {
    expr.strip_parentheses()
}

fn lit_is_negative(lit: &syn::Lit) -> bool {
    lit.to_token_stream().to_string().starts_with('-')
}

/// One piece of pending output: text, or an expression still to be written.
enum Piece<'a> {
    Text(&'static str),
    Owned(String),
    /// An expression, parenthesised if it binds more loosely than the given level.
    Operand(ExprRef<'a>, u8),
}

/// Writes `expr` with an explicit stack of pending pieces (pushed in reverse), so that the
/// depth of the user's expression costs heap, not call stack.
fn write_expr(
    expr: ExprRef<'_>,
    values: &dyn Fn(&str) -> Option<i64>,
    known: &dyn Fn(&str) -> Option<i64>,
    out: &mut String,
) {
    let mut todo = vec![Piece::Operand(expr, ASSIGN)];
    while let Some(piece) = todo.pop() {
        let (expr, min) = match piece {
            Piece::Text(t) => {
                out.push_str(t);
                continue;
            }
            Piece::Owned(t) => {
                out.push_str(&t);
                continue;
            }
            Piece::Operand(e, min) => (e, min),
        };
        if precedence(expr) < min {
            out.push('(');
            todo.push(Piece::Text(")"));
        }
        // Parentheses of the source are dropped; the precedence decides.
        let expr = expr.strip_parentheses();
        let at = |id: &usize| expr.at(*id);
        // Pieces are pushed last first.
        match expr.kind() {
            ExprKind::Assign { left, right } => {
                todo.push(Piece::Operand(at(right), ASSIGN));
                todo.push(Piece::Text(" = "));
                todo.push(Piece::Operand(at(left), ASSIGN));
            }
            ExprKind::Binary {
                op, left, right, ..
            } => {
                let p = precedence(expr);
                // Left-associative: the left operand may share the level, the right may not
                // (also for `+` and `*`: `a + (b + c)` keeps the user's grouping).
                todo.push(Piece::Operand(at(right), p + 1));
                todo.push(Piece::Text(" "));
                todo.push(Piece::Text(op.as_str()));
                todo.push(Piece::Text(" "));
                todo.push(Piece::Operand(at(left), p));
            }
            ExprKind::Unary { op, operand, .. } => {
                todo.push(Piece::Operand(at(operand), PREFIX));
                todo.push(Piece::Text(op.as_str()));
            }
            ExprKind::Call { func, args } => {
                todo.push(Piece::Text(")"));
                push_arguments(&mut todo, args.iter().map(at));
                todo.push(Piece::Text("("));
                todo.push(Piece::Operand(at(func), ASSIGN));
            }
            ExprKind::MethodCall {
                receiver,
                method,
                args,
                ..
            } => {
                todo.push(Piece::Text(")"));
                push_arguments(&mut todo, args.iter().map(at));
                todo.push(Piece::Text("("));
                todo.push(Piece::Owned(method.to_string()));
                todo.push(Piece::Text("."));
                todo.push(Piece::Operand(at(receiver), POSTFIX));
            }
            ExprKind::Path { .. }
                if expr
                    .path_ident()
                    .is_some_and(|i| values(&i.to_string()).is_some()) =>
            {
                let value = expr.path_ident().and_then(|i| values(&i.to_string()));
                out.push_str(&value.map(|v| v.to_string()).unwrap_or_default());
            }
            ExprKind::Index { base, index } => {
                todo.push(Piece::Text("]"));
                match int_value(at(index), known) {
                    Some(v) => todo.push(Piece::Owned(v.to_string())),
                    None => todo.push(Piece::Operand(at(index), ASSIGN)),
                }
                todo.push(Piece::Text("["));
                todo.push(Piece::Operand(at(base), POSTFIX));
            }
            ExprKind::Range { start, end, closed } => {
                if let Some(end) = end {
                    todo.push(Piece::Operand(at(end), SUM));
                }
                todo.push(Piece::Text(if *closed { "..=" } else { ".." }));
                if let Some(start) = start {
                    todo.push(Piece::Operand(at(start), SUM));
                }
            }
            ExprKind::Closure { params, body, .. } => {
                todo.push(Piece::Operand(at(body), ASSIGN));
                let inputs: Vec<&str> = params.iter().map(|p| p.text.as_str()).collect();
                todo.push(Piece::Owned(format!("|{}| ", inputs.join(", "))));
            }
            ExprKind::Path { segments, .. } => {
                let segs: Vec<String> = segments.iter().map(|s| s.to_string()).collect();
                out.push_str(&segs.join("::"));
            }
            ExprKind::Lit(l) => out.push_str(&l.to_token_stream().to_string()),
            ExprKind::Array(items) => {
                todo.push(Piece::Text("]"));
                push_arguments(&mut todo, items.iter().map(at));
                todo.push(Piece::Text("["));
            }
            ExprKind::Other(parts) => {
                for part in parts.iter().rev() {
                    match part {
                        OtherPart::Text(t) => todo.push(Piece::Owned(t.clone())),
                        OtherPart::Child(c, level) => todo.push(Piece::Operand(at(c), *level)),
                    }
                }
            }
            ExprKind::Paren(_) => {}
        }
    }
}

/// Pushes `a, b, c` (reversed, for the stack).
fn push_arguments<'a>(
    todo: &mut Vec<Piece<'a>>,
    args: impl DoubleEndedIterator<Item = ExprRef<'a>>,
) {
    let mut first = true;
    for a in args.rev() {
        if !first {
            todo.push(Piece::Text(", "));
        }
        first = false;
        todo.push(Piece::Operand(a, ASSIGN));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &str) -> crate::expr::Expr {
        use syn::parse::Parser;
        (|input: syn::parse::ParseStream| crate::expr::parse_expr(input))
            .parse_str(src)
            .expect("parses")
    }

    fn t(src: &str) -> String {
        expr_text(parse(src).root())
    }

    #[test]
    fn normalises_spacing_and_parentheses() {
        assert_eq!(t("a+b*c"), "a + b * c");
        assert_eq!(t("(a+b)*c"), "(a + b) * c");
        assert_eq!(t("((a))*((b))"), "a * b");
        assert_eq!(t("a-(b-c)"), "a - (b - c)");
        assert_eq!(t("(a-b)-c"), "a - b - c");
        assert_eq!(t("-(a+b)"), "-(a + b)");
        assert_eq!(t("sin( x ).powi( 2 )"), "sin(x).powi(2)");
        assert_eq!(t("(a+b).sin()"), "(a + b).sin()");
        assert_eq!(t("der(x)=y*2.0"), "der(x) = y * 2.0");
        assert_eq!(t("a*der(x)==u"), "a * der(x) == u");
        assert_eq!(t("atan2(y,x)"), "atan2(y, x)");
        assert_eq!(
            t("M[i][j+1]*sum(0..N,|k|x[k])"),
            "M[i][j + 1] * sum(0..N, |k| x[k])"
        );
    }

    #[test]
    fn writes_known_indices_as_numbers() {
        let e = parse("der(q[i]) == w[i + 1] * M[i][j] + i");
        let values = |s: &str| (s == "i").then_some(2);
        let constants = |s: &str| (s == "N").then_some(3);
        assert_eq!(
            expr_text_with(e.root(), &values, &constants),
            "der(q[2]) == w[3] * M[2][j] + 2"
        );
        let e = parse("v[N - 1] / N");
        assert_eq!(expr_text_with(e.root(), &values, &constants), "v[2] / N");
        let range = parse("min(i, 1)..=N - 1");
        assert_eq!(
            expr_text_with(range.root(), &values, &constants),
            "min(2, 1)..=N - 1"
        );
        assert_eq!(
            int_value(parse("max(i, 3) - 2 * (i + 1)").root(), &values),
            Some(-3)
        );
        assert_eq!(int_value(parse("i + n").root(), &values), None);
    }
}
