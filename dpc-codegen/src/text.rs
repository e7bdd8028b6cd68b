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
    expr_text_with(expr, &|_| None, &|_| None)
}

/// Normalised text of `expr` for one index of a family: a name `values` knows (an index
/// variable such as `i`) is written as its value, and a subscript whose value is known from
/// `values` and `constants` is written as the number (`q[i + 1]` with `i = 2` reads `q[3]`,
/// `q[N - 1]` with `N = 3` reads `q[2]`).
pub fn expr_text_with(
    expr: &Expr,
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
pub fn int_value(expr: &Expr, values: &dyn Fn(&str) -> Option<i64>) -> Option<i64> {
    match strip_parentheses(expr) {
        Expr::Lit(l) => match &l.lit {
            Lit::Int(i) => i.base10_parse::<i64>().ok(),
            _ => None,
        },
        Expr::Path(p) => values(&p.path.get_ident()?.to_string()),
        Expr::Unary(u) if matches!(u.op, UnOp::Neg(_)) => int_value(&u.expr, values)?.checked_neg(),
        Expr::Binary(b) => {
            let (l, r) = (int_value(&b.left, values)?, int_value(&b.right, values)?);
            match b.op {
                BinOp::Add(_) => l.checked_add(r),
                BinOp::Sub(_) => l.checked_sub(r),
                BinOp::Mul(_) => l.checked_mul(r),
                _ => None,
            }
        }
        Expr::Call(c) if c.args.len() == 2 => {
            let Expr::Path(f) = &*c.func else { return None };
            let (a, b) = (
                int_value(&c.args[0], values)?,
                int_value(&c.args[1], values)?,
            );
            match f.path.get_ident()?.to_string().as_str() {
                "min" => Some(a.min(b)),
                "max" => Some(a.max(b)),
                _ => None,
            }
        }
        _ => None,
    }
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
fn write_expr(
    expr: &Expr,
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
            Expr::Path(p)
                if p.path
                    .get_ident()
                    .is_some_and(|i| values(&i.to_string()).is_some()) =>
            {
                let value = p.path.get_ident().and_then(|i| values(&i.to_string()));
                out.push_str(&value.map(|v| v.to_string()).unwrap_or_default());
            }
            Expr::Index(ix) => {
                todo.push(Piece::Text("]"));
                match int_value(&ix.index, known) {
                    Some(v) => todo.push(Piece::Owned(v.to_string())),
                    None => todo.push(Piece::Operand(&ix.index, ASSIGN)),
                }
                todo.push(Piece::Text("["));
                todo.push(Piece::Operand(&ix.expr, POSTFIX));
            }
            Expr::Range(r) => {
                if let Some(end) = &r.end {
                    todo.push(Piece::Operand(end, SUM));
                }
                todo.push(Piece::Text(match r.limits {
                    syn::RangeLimits::HalfOpen(_) => "..",
                    syn::RangeLimits::Closed(_) => "..=",
                }));
                if let Some(start) = &r.start {
                    todo.push(Piece::Operand(start, SUM));
                }
            }
            Expr::Closure(c) => {
                todo.push(Piece::Operand(&c.body, ASSIGN));
                let inputs: Vec<String> = c
                    .inputs
                    .iter()
                    .map(|p| p.to_token_stream().to_string())
                    .collect();
                todo.push(Piece::Owned(format!("|{}| ", inputs.join(", "))));
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
        assert_eq!(
            t("M[i][j+1]*sum(0..N,|k|x[k])"),
            "M[i][j + 1] * sum(0..N, |k| x[k])"
        );
    }

    #[test]
    fn writes_known_indices_as_numbers() {
        let e: Expr = syn::parse_str("der(q[i]) == w[i + 1] * M[i][j] + i").unwrap();
        let values = |s: &str| (s == "i").then_some(2);
        let constants = |s: &str| (s == "N").then_some(3);
        assert_eq!(
            expr_text_with(&e, &values, &constants),
            "der(q[2]) == w[3] * M[2][j] + 2"
        );
        let e: Expr = syn::parse_str("v[N - 1] / N").unwrap();
        assert_eq!(expr_text_with(&e, &values, &constants), "v[2] / N");
        let range: Expr = syn::parse_str("min(i, 1)..=N - 1").unwrap();
        assert_eq!(
            expr_text_with(&range, &values, &constants),
            "min(2, 1)..=N - 1"
        );
        assert_eq!(
            int_value(&syn::parse_str("max(i, 3) - 2 * (i + 1)").unwrap(), &values),
            Some(-3)
        );
        assert_eq!(int_value(&syn::parse_str("i + n").unwrap(), &values), None);
    }
}
