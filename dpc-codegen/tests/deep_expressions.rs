//! Expressions as deep as the user writes them. The whole expansion runs on a thread with a
//! 256 KiB stack, a thirty-second of what `rustc` gives a procedural macro, on expressions
//! twenty times deeper than the 1000 levels that used to crash `rustc`, and nothing grows
//! the stack: the front end parses expressions with its own iterative parser into a flat
//! tree (`dpc_codegen::expr`), hides deep groups from `syn`'s recursive token buffer, and
//! lowers and prints them with explicit stacks; every later pass (differentiation, Hirschorn
//! steps, CSE, emission) works on the hash-consed graph without recursing along the depth.
//! `tests/ui-pass/deep_expressions.rs` checks the same through `rustc`.

use proc_macro2::TokenStream;

/// Nesting levels of the test expressions.
const DEPTH: usize = 20_000;

/// Stack of the expanding thread.
const STACK: usize = 256 << 10;

/// `((( ... (x) ... )))` with `DEPTH` pairs of parentheses.
fn nested_parentheses() -> String {
    format!("{}x{}", "(".repeat(DEPTH), ")".repeat(DEPTH))
}

/// `c0 + x * (c1 + x * (c2 + ...))`, a polynomial of degree `DEPTH` in Horner form.
fn horner() -> String {
    let mut s = String::new();
    for k in 0..DEPTH {
        s += &format!("{}.0 / {}.0 + x * (", k % 7 + 1, k + 2);
    }
    s += "1.0";
    s += &")".repeat(DEPTH);
    s
}

/// `- - - ... - x`: prefix operators nest without any group.
fn negations() -> String {
    format!("{}x", "- ".repeat(DEPTH))
}

/// `sin(sin(...sin(x)...))`: nested calls, each a group inside the previous one.
fn nested_calls() -> String {
    format!("{}x{}", "sin(".repeat(DEPTH), ")".repeat(DEPTH))
}

fn model(rhs: &str) -> TokenStream {
    format!(
        "Deep {{
            states {{ x }}
            inputs {{ u }}
            equations {{ der(x) = -({rhs}) * 1.0e-3 + u; }}
            outputs {{ y = x }}
            tracking DeepTracking {{ y: [] }}
        }}"
    )
    .parse()
    .expect("tokenises")
}

fn expands_on_a_small_stack(rhs: String) {
    let handle = std::thread::Builder::new()
        .stack_size(STACK)
        .spawn(move || {
            let tokens = model(&rhs);
            dpc_codegen::try_expand(tokens)
                .map(|t| t.to_string().len())
                .map_err(|e| e.to_string())
        })
        .expect("thread spawns");
    let len = handle
        .join()
        .expect("expansion does not overflow")
        .expect("model expands");
    assert!(len > 0);
}

#[test]
fn deeply_nested_parentheses_expand() {
    expands_on_a_small_stack(nested_parentheses());
}

#[test]
fn deep_horner_expression_expands() {
    expands_on_a_small_stack(horner());
}

#[test]
fn deep_prefix_negations_expand() {
    expands_on_a_small_stack(negations());
}

#[test]
fn deeply_nested_calls_expand() {
    expands_on_a_small_stack(nested_calls());
}

/// A deep expression with a mistake at the bottom is reported on its tokens, not lost or
/// crashed on.
#[test]
fn errors_deep_inside_are_reported() {
    let handle = std::thread::Builder::new()
        .stack_size(STACK)
        .spawn(|| {
            let rhs = format!("{}x % 2.0{}", "(".repeat(DEPTH), ")".repeat(DEPTH));
            dpc_codegen::try_expand(model(&rhs))
                .map(|_| ())
                .map_err(|e| e.to_string())
        })
        .expect("thread spawns");
    let err = handle
        .join()
        .expect("no stack overflow")
        .expect_err("`%` is refused");
    assert!(err.contains("unsupported operator `%`"), "{err}");
}
