//! Indexed families in the DSL: lowering unrolls them into scalars with readable names.

use proc_macro2::TokenStream;

fn tokens(src: &str) -> TokenStream {
    src.parse().expect("test model tokenises")
}

fn listing(src: &str) -> String {
    let (model, _) = dpc_codegen::derive_model(tokens(src)).unwrap_or_else(|e| panic!("{e}"));
    dpc_codegen::derive::listing(&model)
}

fn errors(src: &str) -> Vec<String> {
    match dpc_codegen::derive_model(tokens(src)) {
        Ok(_) => Vec::new(),
        Err(e) => e.into_iter().map(|e| e.to_string()).collect(),
    }
}

const CHAIN: &str = "Chain {
    consts { N = 3 }
    params { k[N] = [1.0, 2.0, 3.0], c = 0.5 }
    states { x[N], v[N] }
    inputs { u[N] }
    let s[i in 0..N] = sum(0..=i, |j| x[j]);
    equations {
        for i in 0..N {
            der(x[i]) = v[i];
        }
        for i in 0..N - 1 {
            der(v[i]) == -k[i] * (x[i] - x[i + 1]) - c * v[i] + u[i] + s[i];
        }
        der(v[N - 1]) == -k[N - 1] * x[N - 1] + u[N - 1];
    }
    outputs { x }
}";

#[test]
fn families_unroll_into_named_scalars() {
    let text = listing(CHAIN);
    println!("{text}");
    assert!(
        text.contains("params     k[0] = 1.0, k[1] = 2.0, k[2] = 3.0, c = 0.5"),
        "{text}"
    );
    assert!(
        text.contains("states     x[0], x[1], x[2], v[0], v[1], v[2]"),
        "{text}"
    );
    assert!(
        text.contains("[3] der(v[0]) == -k[0] * (x[0] - x[1]) - c * v[0] + u[0] + s[0]"),
        "{text}"
    );
    assert!(
        text.contains("let s[i in 0..N] = sum(0..=i, |j| x[j])"),
        "{text}"
    );
    assert!(text.contains("x[2] = x[2]"), "{text}");
}

/// A one-state family model with `decls`, `lets` and `equations` spliced in.
fn model(decls: &str, equations: &str) -> String {
    format!("M {{ {decls} equations {{ {equations} }} }}")
}

/// The single error of a model, asserted to be exactly one.
fn error(decls: &str, equations: &str) -> String {
    let errs = errors(&model(decls, equations));
    assert_eq!(errs.len(), 1, "{errs:#?}");
    errs.into_iter().next().unwrap_or_default()
}

#[test]
fn each_mistake_is_reported_once_on_its_tokens() {
    // Once, although the loop body is checked for every index.
    let e = error("states { q[2] }", "for i in 0..2 { der(q[j]) == 1.0; }");
    assert!(
        e.starts_with("unknown index variable `j` (in scope: i)"),
        "{e}"
    );
    // Out of range only where it is: for i = 2.
    let e = error(
        "consts { N = 3 } states { q[N] }",
        "for i in 0..N { der(q[i]) == q[i + 1]; }",
    );
    assert_eq!(e, "index 3 is out of range for `q`, a family of 3 states (`q[3]`): the index must be in 0..3 (here with i = 2)");
    let e = error(
        "params { M[2][3] = 0.0 } states { q[2] }",
        "der(q[0]) == M[1][3]; der(q[1]) == 0.0;",
    );
    assert_eq!(e, "index 3 is out of range for `M`, a family of 6 parameters (`M[2][3]`): the second index must be in 0..3");
    // A family whose length is not a constant is reported there, not at every use.
    let e = error("params { n = 3.0 } states { q[n] }", "der(q[0]) == 1.0;");
    assert!(e.starts_with("`n` is a parameter, not a constant"), "{e}");
    let e = error("states { q[2.0] }", "der(q[0]) == 1.0;");
    assert!(
        e.starts_with("lengths, ranges and indices are integers, found `2.0`"),
        "{e}"
    );
    let e = error("consts { N = 2 - 2 } states { q[N] }", "der(q[0]) == 1.0;");
    assert_eq!(
        e,
        "the length of an indexed family must be at least 1, found `N` = 0"
    );
    let e = error(
        "states { q[2] }",
        "for i in 0..2 { der(q[i]) == sum(0..3, |i| 1.0); }",
    );
    assert!(e.starts_with("`i` is already the index variable"), "{e}");
    let e = error(
        "states { q[2] }",
        "for i in 0..2 { der(q[i]) == sum(0, |j| 1.0); }",
    );
    assert!(
        e.starts_with("expected an index range such as `0..N`"),
        "{e}"
    );
    let e = error("states { q[2] }", "for i in 0.. { der(q[i]) == 1.0; }");
    assert!(e.starts_with("an index range needs both bounds"), "{e}");
    let e = error("states { q_[2] }", "for i in 0..2 { der(q_[i]) == 1.0; }");
    assert!(
        e.starts_with("the name of an indexed family may not end in `_`"),
        "{e}"
    );
    let e = error(
        "consts { N = 3 } params { m[N] = [1.0, 2.0] } states { q[N] }",
        "for i in 0..N { der(q[i]) == m[i]; }",
    );
    assert_eq!(
        e,
        "length mismatch: `m` has length 3 as declared, but its default lists 2 values"
    );
    let e = errors(&model(
        "params { m[2][2] = [1.0, 2.0] } states { q }",
        "der(q) == m[0][0];",
    ));
    assert_eq!(e.len(), 2, "{e:#?}");
    assert!(e[1].starts_with("the default of `m[1]` must be an array of 2 values such as `[1.0, 1.0]`, or one number for every element, found `2.0`"), "{e:#?}");
    let e = error(
        "states { q[2], q_1 }",
        "for i in 0..2 { der(q[i]) == 1.0; } der(q_1) = 0.0;",
    );
    assert_eq!(
        e,
        "`q_1` is the name the generated code gives to element `q[1]`; choose another name"
    );
    let e = error("states { q[2] }", "der(q) == 1.0; der(q[1]) == 0.0;");
    assert!(
        e.starts_with("`der()` applies to one state, but `q` is a family of 2 states"),
        "{e}"
    );
    let e = error(
        "states { q[2] } let s[i in 1..2] = q[i];",
        "der(q[0]) == s[0]; der(q[1]) == s[1];",
    );
    assert_eq!(e, "`s[0]` is not defined: the `let` family defines `s[i in 1..2]`, and an element may use only earlier elements of its own family");
    let e = error(
        "states { q[2] } let s[i in 0..2] = s[1] + q[i];",
        "der(q[0]) == s[0]; der(q[1]) == s[1];",
    );
    assert!(e.starts_with("`s[1]` is not defined"), "{e}");
    let e = error(
        "states { q[2] } let s[2] = q[0];",
        "der(q[0]) == s[0]; der(q[1]) == 0.0;",
    );
    assert!(
        e.starts_with("a `let` family names each index with its range"),
        "{e}"
    );
    let e = error(
        "states { q[2], x }",
        "der(x[0]) == 1.0; der(q[0]) == 0.0; der(q[1]) == 0.0;",
    );
    assert_eq!(
        e,
        "`x` is a state, not an indexed family, and takes no `[...]`"
    );
    let e = error(
        "consts { N = 2 } states { q[N] }",
        "for N in 0..2 { der(q[N]) == 1.0; }",
    );
    assert!(
        e.starts_with("`N` is already declared as a constant"),
        "{e}"
    );
}

#[test]
fn outputs_references_and_tracking_take_families_and_elements() {
    // Lowered only: four outputs and two inputs make no square tracking DAE.
    let src = "Arm {
        consts { N = 2 }
        states { q[N], w[N] }
        inputs { u[N] }
        equations { for i in 0..N { der(q[i]) = w[i]; der(w[i]) = u[i] - q[i]; } }
        outputs { q, e[i in 0..N] = w[i] * i }
        references { q[i in 0..N] = sin(t + i), e = 0.0 }
        tracking ArmTracking { q: [1.0], e[1]: [2.0] }
    }";
    assert!(
        dpc_codegen::derive::listing(&dpc_codegen::lower_model(tokens(src)).expect("lowers"))
            .contains("e[1] = w[1] * 1")
    );
    let model = dpc_codegen::lower_model(tokens(src)).unwrap_or_else(|e| panic!("{e}"));
    let labels: Vec<&str> = model.outputs.iter().map(|o| o.label.as_str()).collect();
    assert_eq!(labels, ["q[0]", "q[1]", "e[0]", "e[1]"]);
    let names: Vec<String> = model.outputs.iter().map(|o| o.name.to_string()).collect();
    assert_eq!(names, ["q_0", "q_1", "e_0", "e_1"]);
    let refs: Vec<(usize, &str)> = model
        .references
        .iter()
        .map(|r| (r.output, r.text.as_str()))
        .collect();
    assert_eq!(
        refs,
        [(0, "sin(t + 0)"), (1, "sin(t + 1)"), (2, "0.0"), (3, "0.0")]
    );
    let tracking = model.tracking.as_ref().expect("tracking");
    let entries: Vec<(usize, Vec<f64>)> = tracking
        .entries
        .iter()
        .map(|e| (e.output, e.roots.clone()))
        .collect();
    assert_eq!(entries, [(0, vec![1.0]), (1, vec![1.0]), (3, vec![2.0])]);

    let bad = src.replace("e[1]: [2.0]", "e[2]: [2.0]");
    assert_eq!(
        errors(&bad),
        ["`e[2]` is not an output; `tracking` names outputs declared in `outputs`"]
    );
    let bad = src.replace("e = 0.0", "e[0] = 0.0");
    assert_eq!(
        errors(&bad),
        ["`references` must give every output a reference; missing: `e[1]`"]
    );
    let bad = src.replace(
        "tracking ArmTracking { q: [1.0], e[1]: [2.0] }",
        "tracking ArmTracking { q: [1.0], q[1]: [2.0] }",
    );
    assert_eq!(errors(&bad), ["duplicate tracking entry for output `q[1]`"]);
}

#[test]
fn scalar_models_are_unchanged_by_the_families() {
    // No `consts`, no families: names, listing and code are those of plain scalars.
    let src = "P { params { k = 1.0 } states { x } inputs { u } equations { der(x) = -k * x + u; } outputs { x } }";
    let text = listing(src);
    assert_eq!(
        text,
        "model P\n  params     k = 1.0\n  states     x\n  inputs     u\n  equations\n    [0] der(x) = -k * x + u\n  outputs\n    x = x\n"
    );
}
