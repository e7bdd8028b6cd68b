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
