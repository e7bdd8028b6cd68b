//! Expansion of large valid models completes: relative degrees are structural first and
//! symbolic only within a budget, so a 50-state nonlinear chain (which took more than 120 s
//! when every relative degree was found by repeated symbolic differentiation) expands here.
//! No timing assertion: `cargo bench -p dpc-codegen --bench expansion` measures the time.

use dpc_codegen::hirschorn::{relative_degree_analysis, RelativeDegree};
use proc_macro2::TokenStream;

/// `der(x_i) = k sin(x_{i+1}) - 0.5 x_i`, `der(x_n) = u - x_n^3`, output `y = x_1` of
/// relative degree `n`, optionally with the tracking DAE for `W(s) = s + 2`.
fn chain(n: usize, tracking: bool) -> TokenStream {
    let states: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    let mut equations = String::new();
    for i in 1..n {
        equations += &format!("der(x{i}) = k * x{}.sin() - 0.5 * x{i};\n", i + 1);
    }
    equations += &format!("der(x{n}) = u - x{n}.powi(3);\n");
    let tracking = if tracking {
        "tracking ChainTracking { y: [2.0] }"
    } else {
        ""
    };
    format!(
        "Chain {{
            params {{ k = 1.5 }}
            states {{ {} }}
            inputs {{ u }}
            equations {{ {equations} }}
            outputs {{ y = x1 }}
            {tracking}
        }}",
        states.join(", ")
    )
    .parse()
    .expect("generated model tokenises")
}

#[test]
fn fifty_state_chain_expands() {
    for tracking in [false, true] {
        let tokens = dpc_codegen::try_expand(chain(50, tracking)).expect("chain expands");
        let text = tokens.to_string();
        // The generated model reports the relative degree it found: the chain's length.
        assert!(
            text.contains("50usize"),
            "relative degree 50 in the expansion"
        );
    }
}

#[test]
fn chain_relative_degree_is_its_length() {
    // Short chains are confirmed symbolically, long ones structurally (the derivatives of
    // the nested sines outgrow the budget); both give the chain's length.
    for (n, symbolic) in [(4, true), (50, false)] {
        let mut model = dpc_codegen::lower_model(chain(n, false)).expect("chain lowers");
        let found = relative_degree_analysis(&mut model);
        let expected = if symbolic {
            RelativeDegree::Symbolic(n)
        } else {
            RelativeDegree::Structural(n)
        };
        assert_eq!(found, vec![expected], "chain of {n}");
    }
}
