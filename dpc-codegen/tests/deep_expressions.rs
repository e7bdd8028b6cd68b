//! Expressions as deep as the user writes them. The expansion runs on a thread with a 2 MiB
//! stack, a quarter of what `rustc` gives a procedural macro, on expressions ten times deeper
//! than the 1000 levels that used to crash `rustc`: the front end (`syn`'s recursive parser
//! and lowering over its trees) gets a stack sized from the input, and every later pass
//! (differentiation, Hirschorn steps, CSE, emission) must not recurse along the depth, or
//! it overflows here. `tests/ui-pass/deep_expressions.rs` checks the same through `rustc`.

use proc_macro2::TokenStream;

/// Nesting levels of the test expressions.
const DEPTH: usize = 10_000;

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
        .stack_size(2 << 20)
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
fn ten_thousand_nested_parentheses_expand() {
    expands_on_a_small_stack(nested_parentheses());
}

#[test]
fn ten_thousand_deep_horner_expression_expands() {
    expands_on_a_small_stack(horner());
}
