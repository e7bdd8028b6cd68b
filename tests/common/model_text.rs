//! The text inside each `model! { ... }` invocation of a Rust source file, cut out of the
//! file itself, so that a run-time model reads exactly the characters the macro received.

#![allow(dead_code)]

use std::str::FromStr;

use proc_macro2::{Delimiter, TokenStream, TokenTree};

/// One `model! { ... }` invocation.
pub struct Invocation {
    /// The text between the braces.
    pub body: String,
    /// The whole file with everything outside the braces blanked (newlines kept), so that
    /// line and column numbers in it are those of the file.
    pub in_place: String,
}

/// Every `model! { ... }` invocation in `source`, in order (nested items included).
pub fn invocations(source: &str) -> Vec<Invocation> {
    let tokens = TokenStream::from_str(source).expect("the Rust source lexes");
    let mut ranges = Vec::new();
    collect(tokens, &mut ranges);
    ranges
        .into_iter()
        .map(|(start, end)| Invocation {
            body: source[start..end].to_string(),
            in_place: source
                .char_indices()
                .map(|(i, c)| {
                    if (start..end).contains(&i) || c == '\n' {
                        c
                    } else {
                        ' '
                    }
                })
                .collect(),
        })
        .collect()
}

fn collect(tokens: TokenStream, out: &mut Vec<(usize, usize)>) {
    let trees: Vec<TokenTree> = tokens.into_iter().collect();
    for (k, tree) in trees.iter().enumerate() {
        if let TokenTree::Group(g) = tree {
            let is_model = k >= 2
                && matches!(&trees[k - 1], TokenTree::Punct(p) if p.as_char() == '!')
                && matches!(&trees[k - 2], TokenTree::Ident(i) if i == "model");
            if is_model && g.delimiter() == Delimiter::Brace {
                out.push((
                    g.span_open().byte_range().end,
                    g.span_close().byte_range().start,
                ));
            } else {
                collect(g.stream(), out);
            }
        }
    }
}

/// The models declared through a `macro_rules!` template of `templates` (a file such as
/// `models/src/arm_declaration.rs`, whose one rule wraps a `model! { ... }` in parameters
/// `$name:kind`): for every invocation `NAME!(arg, ...)` of such a template in `source`, the
/// template's model text with each `$param` replaced by its argument as written.
pub fn template_models(source: &str, templates: &str) -> Vec<String> {
    let rules = macro_rules(templates);
    let tokens = TokenStream::from_str(source).expect("the Rust source lexes");
    let trees: Vec<TokenTree> = tokens.into_iter().collect();
    let mut out = Vec::new();
    for (k, tree) in trees.iter().enumerate() {
        let TokenTree::Group(args) = tree else {
            continue;
        };
        let called = k >= 2
            && args.delimiter() == Delimiter::Parenthesis
            && matches!(&trees[k - 1], TokenTree::Punct(p) if p.as_char() == '!');
        let Some((_, params, body)) = rules.iter().find(|(name, _, _)| {
            called && matches!(&trees[k - 2], TokenTree::Ident(i) if i == name)
        }) else {
            continue;
        };
        let values: Vec<String> = args
            .stream()
            .into_iter()
            .filter(|t| !matches!(t, TokenTree::Punct(p) if p.as_char() == ','))
            .map(|t| t.to_string())
            .collect();
        assert_eq!(values.len(), params.len(), "arguments of a template call");
        // Longest parameter names first, so that `$n` does not cut into `$name`.
        let mut order: Vec<usize> = (0..params.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(params[i].len()));
        let mut text = body.clone();
        for i in order {
            text = text.replace(&format!("${}", params[i]), &values[i]);
        }
        out.extend(invocations(&text).into_iter().map(|m| m.body));
    }
    out
}

/// Every `macro_rules! NAME { (PARAMS) => { BODY } }` of `source` with one rule: its name,
/// its parameter names (without `$`) and the text of its body.
fn macro_rules(source: &str) -> Vec<(String, Vec<String>, String)> {
    let tokens = TokenStream::from_str(source).expect("the Rust source lexes");
    let trees: Vec<TokenTree> = tokens.into_iter().collect();
    let mut out = Vec::new();
    for k in 3..trees.len() {
        let (TokenTree::Ident(kw), TokenTree::Ident(name), TokenTree::Group(rule)) =
            (&trees[k - 3], &trees[k - 1], &trees[k])
        else {
            continue;
        };
        if kw != "macro_rules" {
            continue;
        }
        let parts: Vec<TokenTree> = rule.stream().into_iter().collect();
        let (Some(TokenTree::Group(pattern)), Some(TokenTree::Group(body))) =
            (parts.first(), parts.get(3))
        else {
            panic!("macro_rules! {name}: one rule `(PARAMS) => {{ BODY }}` expected");
        };
        let pattern: Vec<TokenTree> = pattern.stream().into_iter().collect();
        let params = pattern
            .windows(2)
            .filter_map(|w| match w {
                [TokenTree::Punct(dollar), TokenTree::Ident(param)] if dollar.as_char() == '$' => {
                    Some(param.to_string())
                }
                _ => None,
            })
            .collect();
        let range = body.span_open().byte_range().end..body.span_close().byte_range().start;
        out.push((name.to_string(), params, source[range].to_string()));
    }
    out
}
