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
        Expr::Paren(p) => precedence(&p.expr),
        Expr::Group(g) => precedence(&g.expr),
        Expr::Lit(l) if lit_is_negative(&l.lit) => PREFIX,
        _ => POSTFIX,
    }
}

fn lit_is_negative(lit: &Lit) -> bool {
    lit.to_token_stream().to_string().starts_with('-')
}

fn write_operand(expr: &Expr, min: u8, out: &mut String) {
    if precedence(expr) < min {
        out.push('(');
        write_expr(expr, out);
        out.push(')');
    } else {
        write_expr(expr, out);
    }
}

fn write_expr(expr: &Expr, out: &mut String) {
    match expr {
        Expr::Paren(p) => write_expr(&p.expr, out),
        Expr::Group(g) => write_expr(&g.expr, out),
        Expr::Assign(a) => {
            write_expr(&a.left, out);
            out.push_str(" = ");
            write_expr(&a.right, out);
        }
        Expr::Binary(b) => {
            let p = precedence(expr);
            let op = b.op.to_token_stream().to_string();
            // Left-associative: the left operand may share the level, the right may not
            // (except for the associative `+` and `*`, where `a + (b + c)` reads as `a + b + c`
            // only if we print the parentheses; keep them to show the user's grouping).
            write_operand(&b.left, p, out);
            out.push(' ');
            out.push_str(&op);
            out.push(' ');
            write_operand(&b.right, p + 1, out);
        }
        Expr::Unary(u) => {
            match u.op {
                UnOp::Neg(_) => out.push('-'),
                UnOp::Not(_) => out.push('!'),
                _ => out.push('*'),
            }
            write_operand(&u.expr, PREFIX, out);
        }
        Expr::Call(c) => {
            write_expr(&c.func, out);
            out.push('(');
            for (i, a) in c.args.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_expr(a, out);
            }
            out.push(')');
        }
        Expr::MethodCall(m) => {
            write_operand(&m.receiver, POSTFIX, out);
            out.push('.');
            out.push_str(&m.method.to_string());
            out.push('(');
            for (i, a) in m.args.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_expr(a, out);
            }
            out.push(')');
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
