//! The expression parser against `syn`: the same tree shape (precedence, associativity,
//! postfix chains) for hand-written expressions and for every expression of the models in
//! `models/`, spans on the offending tokens, and depth without recursion.

use super::*;
use syn::parse::Parser as _;

fn ours(src: &str) -> syn::Result<Expr> {
    (|input: syn::parse::ParseStream| parse_expr(input)).parse_str(src)
}

/// A fully parenthesised shape of our tree, built bottom-up in node order.
fn shape(e: &Expr) -> String {
    let mut text: Vec<String> = Vec::with_capacity(e.nodes().len());
    for node in e.nodes() {
        let t = |id: &NodeId| text[*id].clone();
        let list = |ids: &[NodeId]| {
            ids.iter()
                .map(|i| text[*i].clone())
                .collect::<Vec<_>>()
                .join(" ")
        };
        let s = match &node.kind {
            ExprKind::Lit(l) => l.to_token_stream().to_string(),
            ExprKind::Path { segments, .. } => segments
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join("::"),
            ExprKind::Paren(c) => format!("(paren {})", t(c)),
            ExprKind::Unary { op, operand, .. } => format!("({} {})", op.as_str(), t(operand)),
            ExprKind::Binary {
                op, left, right, ..
            } => format!("({} {} {})", op.as_str(), t(left), t(right)),
            ExprKind::Assign { left, right } => format!("(= {} {})", t(left), t(right)),
            ExprKind::Call { func, args } => format!("(call {} [{}])", t(func), list(args)),
            ExprKind::MethodCall {
                receiver,
                method,
                args,
                ..
            } => format!("(method {method} {} [{}])", t(receiver), list(args)),
            ExprKind::Index { base, index } => format!("(index {} {})", t(base), t(index)),
            ExprKind::Range { start, end, closed } => format!(
                "({} {} {})",
                if *closed { "..=" } else { ".." },
                start.as_ref().map_or("_".into(), t),
                end.as_ref().map_or("_".into(), t)
            ),
            ExprKind::Closure { params, body, .. } => format!(
                "(closure [{}] {})",
                params
                    .iter()
                    .map(|p| p.text.clone())
                    .collect::<Vec<_>>()
                    .join(" "),
                t(body)
            ),
            ExprKind::Array(items) => format!("(array [{}])", list(items)),
            ExprKind::Other(_) => "other".into(),
        };
        text.push(s);
    }
    text.pop().unwrap_or_default()
}

/// The same shape of `syn`'s tree (recursive; test inputs are shallow).
fn syn_shape(e: &syn::Expr) -> String {
    use syn::Expr as E;
    let list = |args: &mut dyn Iterator<Item = &syn::Expr>| {
        args.map(syn_shape).collect::<Vec<_>>().join(" ")
    };
    match e {
        E::Lit(l) => l.lit.to_token_stream().to_string(),
        E::Path(p)
            if p.qself.is_none() && p.path.segments.iter().all(|s| s.arguments.is_none()) =>
        {
            p.path
                .segments
                .iter()
                .map(|s| s.ident.to_string())
                .collect::<Vec<_>>()
                .join("::")
        }
        E::Paren(p) => format!("(paren {})", syn_shape(&p.expr)),
        E::Group(g) => format!("(paren {})", syn_shape(&g.expr)),
        E::Unary(u) => format!("({} {})", u.op.to_token_stream(), syn_shape(&u.expr)),
        E::Reference(r) if r.mutability.is_none() => format!("(& {})", syn_shape(&r.expr)),
        E::Binary(b) => format!(
            "({} {} {})",
            b.op.to_token_stream().to_string().replace(' ', ""),
            syn_shape(&b.left),
            syn_shape(&b.right)
        ),
        E::Assign(a) => format!("(= {} {})", syn_shape(&a.left), syn_shape(&a.right)),
        E::Call(c) => format!(
            "(call {} [{}])",
            syn_shape(&c.func),
            list(&mut c.args.iter())
        ),
        E::MethodCall(m) => format!(
            "(method {} {} [{}])",
            m.method,
            syn_shape(&m.receiver),
            list(&mut m.args.iter())
        ),
        E::Index(i) => format!("(index {} {})", syn_shape(&i.expr), syn_shape(&i.index)),
        E::Range(r) => format!(
            "({} {} {})",
            match r.limits {
                syn::RangeLimits::HalfOpen(_) => "..",
                syn::RangeLimits::Closed(_) => "..=",
            },
            r.start.as_deref().map_or("_".into(), syn_shape),
            r.end.as_deref().map_or("_".into(), syn_shape)
        ),
        E::Closure(c) => format!(
            "(closure [{}] {})",
            c.inputs
                .iter()
                .map(|p| p.to_token_stream().to_string())
                .collect::<Vec<_>>()
                .join(" "),
            syn_shape(&c.body)
        ),
        E::Array(a) => format!("(array [{}])", list(&mut a.elems.iter())),
        _ => "other".into(),
    }
}

fn assert_same_shape(src: &str) {
    let theirs: syn::Expr = syn::parse_str(src).unwrap_or_else(|e| panic!("syn: {src}: {e}"));
    let mine = ours(src).unwrap_or_else(|e| panic!("ours: {src}: {e}"));
    assert_eq!(shape(&mine), syn_shape(&theirs), "shape of `{src}`");
}

#[test]
fn precedence_and_associativity_match_syn() {
    for src in [
        "a + b * c",
        "a * b + c",
        "a - b - c",
        "a / b / c * d",
        "-a * b",
        "-a.powi(2)",
        "- - x",
        "-(a + b)",
        "a + -b",
        "2.0 * -x",
        "a == b + c",
        "der(x) = -k * y + u",
        "a = b = c",
        "x % 2.0",
        "a && b || c",
        "a | b ^ c & d << e >> f",
        "a < b",
        "a >= -b",
        "a != b",
        "a += b * c",
        "0..N",
        "0..=N - 1",
        "min(i, 1)..=N - 1",
        "a..",
        "..b",
        "..",
        "-1..2",
        "sin(x).powi(2) + cos(x).powi(2)",
        "x.atan2(y).abs()",
        "q[i][j + 1] * M[2]",
        "f(a)(b)[c]",
        "sum(0..N, |k| m[k] * x[k])",
        "sum(0..N, |k| sum(0..k, |j| a[j]) * b[k])",
        "sum(0..N, |k, j| x)",
        "std::f64::consts::PI * r.powi(2)",
        "f64::consts::FRAC_PI_2 - theta",
        "[1.0, 2.0, 3.0]",
        "[[1.0, 2.0], [3.0, 4.0]]",
        "[]",
        "f()",
        "f(a,)",
        "(a)",
        "((a))",
        "x.hypot(y)",
        "1.0e-3 * (1.0 / 2.0 + x * (2.0 / 3.0))",
        "true",
        "\"text\"",
        "!a",
        "*a + b",
        "&a",
        "a.b + c",
        "a as f64 + b",
        "-a as f64",
        "a * b as f64",
        "(a, b)",
        "()",
        "x?",
        "if x { 1.0 } else { 0.0 }",
        "{ x }",
        "a.0",
        "x.f::<f64>(2)",
    ] {
        assert_same_shape(src);
    }
}

/// Every expression in the `equations` and `let`s of the models in `models/src`.
fn model_expressions() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/src");
    let mut out = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("models directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    files.sort();
    for path in files {
        let src = std::fs::read_to_string(&path).expect("readable");
        let file = syn::parse_file(&src).expect("parses");
        for item in file.items {
            let syn::Item::Macro(m) = item else { continue };
            if !m.mac.path.is_ident("model")
                && !m.mac.path.segments.iter().any(|s| s.ident == "model")
            {
                continue;
            }
            collect(m.mac.tokens, &mut out);
        }
    }
    out
}

/// Statement-like pieces (`...;`, `= ...,`) of a model's tokens, searched in every brace
/// group.
fn collect(tokens: TokenStream, out: &mut Vec<String>) {
    let trees: Vec<proc_macro2::TokenTree> = tokens.into_iter().collect();
    let mut piece: Vec<proc_macro2::TokenTree> = Vec::new();
    let mut after_eq = false;
    for tt in trees {
        match &tt {
            proc_macro2::TokenTree::Group(g) if g.delimiter() == proc_macro2::Delimiter::Brace => {
                collect(g.stream(), out);
                piece.clear();
                after_eq = false;
            }
            proc_macro2::TokenTree::Punct(p) if p.as_char() == ';' || p.as_char() == ',' => {
                if !piece.is_empty() {
                    let s = piece.iter().cloned().collect::<TokenStream>().to_string();
                    if !s.starts_with("let") && !s.starts_with("for") && !s.starts_with('#') {
                        out.push(s);
                    }
                }
                piece.clear();
                after_eq = false;
            }
            proc_macro2::TokenTree::Punct(p)
                if p.as_char() == '='
                    && !after_eq
                    && p.spacing() == proc_macro2::Spacing::Alone =>
            {
                // `name = expr` or `let name = expr`: both the whole piece and the right side.
                after_eq = true;
                let s = piece.iter().cloned().collect::<TokenStream>().to_string();
                if s.starts_with("let") || s.starts_with("for") {
                    piece.clear();
                } else {
                    piece.push(tt.clone());
                }
            }
            _ => piece.push(tt.clone()),
        }
    }
}

#[test]
fn model_expressions_parse_like_syn() {
    let exprs = model_expressions();
    assert!(exprs.len() > 50, "found only {} expressions", exprs.len());
    let mut checked = 0;
    for src in &exprs {
        // Pieces that are not expressions (declarations such as `q [N] : "rad"`) are skipped.
        if syn::parse_str::<syn::Expr>(src).is_ok() {
            assert_same_shape(src);
            checked += 1;
        }
    }
    assert!(checked > 50, "checked only {checked} expressions");
}

#[test]
fn spans_cover_the_tokens_of_each_node() {
    let e = ours("a + sin(b * c)").expect("parses");
    let root = e.root();
    let (first, last) = (root.spans().first.start(), root.spans().last.end());
    assert_eq!((first.column, last.column), (0, 14));
    let ExprKind::Binary {
        op_spans, right, ..
    } = root.kind()
    else {
        panic!("binary")
    };
    assert_eq!(op_spans.first.start().column, 2);
    let call = root.at(*right);
    assert_eq!(call.spans().first.start().column, 4);
    assert_eq!(call.spans().last.end().column, 14);
    let ExprKind::Call { args, .. } = call.kind() else {
        panic!("call")
    };
    let product = call.at(args[0]);
    assert_eq!(
        (
            product.spans().first.start().column,
            product.spans().last.end().column
        ),
        (8, 13)
    );
    let e = ours("x.powi( 2 )").expect("parses");
    let ExprKind::MethodCall { method, .. } = e.root().kind() else {
        panic!("method call")
    };
    assert_eq!(method.span().start().column, 2);
}

#[test]
fn syntax_errors_point_at_the_token() {
    let err = ours("f(a b)").expect_err("an error");
    assert_eq!(err.to_string(), "expected `,`");
    assert_eq!(err.span().start().column, 4);
    let err = ours("a + ").expect_err("an error");
    assert!(err.to_string().contains("expected an expression"), "{err}");
    let err = ours("q[]").expect_err("an error");
    assert!(err.to_string().contains("expected an expression"), "{err}");
}

#[test]
fn an_expression_ends_at_a_comma_or_semicolon() {
    let parse_two = |input: syn::parse::ParseStream| {
        let a = parse_expr(input)?;
        input.parse::<syn::Token![,]>()?;
        let b = parse_expr(input)?;
        input.parse::<syn::Token![;]>()?;
        Ok((a, b))
    };
    let (a, b) = parse_two.parse_str("x + 1, f(y, z);").expect("parses");
    assert_eq!(shape(&a), "(+ x 1)");
    assert_eq!(shape(&b), "(call f [y z])");
    let range_then_block = |input: syn::parse::ParseStream| {
        let r = parse_expr_without_brace(input)?;
        let body;
        syn::braced!(body in input);
        let _: TokenStream = body.parse()?;
        Ok(r)
    };
    let r = range_then_block.parse_str("0..N { x }").expect("parses");
    assert_eq!(shape(&r), "(.. 0 N)");
}

/// Parsing and dropping 100 000 levels on a 256 KiB stack: nothing recurses along the depth.
#[test]
fn deep_expressions_parse_on_a_small_stack() {
    const DEPTH: usize = 100_000;
    let handle = std::thread::Builder::new()
        .stack_size(256 << 10)
        .spawn(|| {
            let src = format!(
                "{}x{} + {}y",
                "(".repeat(DEPTH),
                ")".repeat(DEPTH),
                "-".repeat(DEPTH)
            );
            let tokens: TokenStream = src.parse().expect("tokenises");
            let tree = parser::with_stash(tokens, |flat| {
                (|input: syn::parse::ParseStream| parse_expr(input)).parse2(flat)
            })
            .expect("parses");
            let n = tree.nodes().len();
            drop(tree);
            n
        })
        .expect("thread spawns");
    let nodes = handle.join().expect("no stack overflow");
    assert_eq!(nodes, 2 * 100_000 + 3);
}
