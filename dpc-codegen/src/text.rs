//! Normalised text of DSL expressions, for the equation listing of generated models.
//!
//! Prints the supported subset of Rust expressions with single spaces around binary
//! operators and only the parentheses that precedence requires, so that the listing reads
//! like the model as written, independent of the user's formatting.

use quote::ToTokens;
use syn::{BinOp, Expr, Lit, UnOp};

/// Precedence levels, higher binds tighter.
const ASSIGN: u8 = 0;
const COMPARE: u8 = 1;
const SUM: u8 = 2;
const PRODUCT: u8 = 3;
const PREFIX: u8 = 4;
const POSTFIX: u8 = 5;

/// Normalised text of `expr`.
pub fn expr_text(expr: &Expr) -> String {
    let mut s = String::new();
    write_expr(expr, &mut s);
    s
}

fn precedence(expr: &Expr) -> u8 {
    match expr {
        Expr::Assign(_) => ASSIGN,
        Expr::Binary(b) => match b.op {
            BinOp::Add(_) | BinOp::Sub(_) => SUM,
            BinOp::Mul(_) | BinOp::Div(_) | BinOp::Rem(_) => PRODUCT,
            _ => COMPARE,
        },
        Expr::Unary(_) => PREFIX,
        Expr::Paren(_) | Expr::Group(_) => precedence(strip_parentheses(expr)),
        Expr::Lit(l) if lit_is_negative(&l.lit) => PREFIX,
        _ => POSTFIX,
    }
}

/// `expr` without the parentheses (and invisible groups) around it.
pub fn strip_parentheses(mut expr: &Expr) -> &Expr {
    loop {
        match expr {
            Expr::Paren(p) => expr = &p.expr,
            Expr::Group(g) => expr = &g.expr,
            _ => return expr,
        }
    }
}

fn lit_is_negative(lit: &Lit) -> bool {
    lit.to_token_stream().to_string().starts_with('-')
}

/// One piece of pending output: text, or an expression still to be written.
enum Piece<'a> {
    Text(&'static str),
    Owned(String),
    /// An expression, parenthesised if it binds more loosely than the given level.
    Operand(&'a Expr, u8),
}

/// Writes `expr` with an explicit stack of pending pieces (pushed in reverse), so that the
/// depth of the user's expression costs heap, not call stack.
fn write_expr(expr: &Expr, out: &mut String) {
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
        let expr = strip_parentheses(expr);
        // Pieces are pushed last first.
        match expr {
            Expr::Assign(a) => {
                todo.push(Piece::Operand(&a.right, ASSIGN));
                todo.push(Piece::Text(" = "));
                todo.push(Piece::Operand(&a.left, ASSIGN));
            }
            Expr::Binary(b) => {
                let p = precedence(expr);
                // Left-associative: the left operand may share the level, the right may not
                // (also for `+` and `*`: `a + (b + c)` keeps the user's grouping).
                todo.push(Piece::Operand(&b.right, p + 1));
                todo.push(Piece::Text(" "));
                todo.push(Piece::Owned(b.op.to_token_stream().to_string()));
                todo.push(Piece::Text(" "));
                todo.push(Piece::Operand(&b.left, p));
            }
            Expr::Unary(u) => {
                todo.push(Piece::Operand(&u.expr, PREFIX));
                todo.push(Piece::Text(match u.op {
                    UnOp::Neg(_) => "-",
                    UnOp::Not(_) => "!",
                    _ => "*",
                }));
            }
            Expr::Call(c) => {
                todo.push(Piece::Text(")"));
                push_arguments(&mut todo, c.args.iter());
                todo.push(Piece::Text("("));
                todo.push(Piece::Operand(&c.func, ASSIGN));
            }
            Expr::MethodCall(m) => {
                todo.push(Piece::Text(")"));
                push_arguments(&mut todo, m.args.iter());
                todo.push(Piece::Text("("));
                todo.push(Piece::Owned(m.method.to_string()));
                todo.push(Piece::Text("."));
                todo.push(Piece::Operand(&m.receiver, POSTFIX));
            }
            Expr::Path(p) => {
                let segs: Vec<String> = p
                    .path
                    .segments
                    .iter()
                    .map(|s| s.ident.to_string())
                    .collect();
                out.push_str(&segs.join("::"));
            }
            Expr::Lit(l) => out.push_str(&l.lit.to_token_stream().to_string()),
            other => out.push_str(&other.to_token_stream().to_string()),
        }
    }
}

/// Pushes `a, b, c` (reversed, for the stack).
fn push_arguments<'a>(todo: &mut Vec<Piece<'a>>, args: impl DoubleEndedIterator<Item = &'a Expr>) {
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

    fn t(src: &str) -> String {
        expr_text(&syn::parse_str(src).unwrap())
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
    }
}
