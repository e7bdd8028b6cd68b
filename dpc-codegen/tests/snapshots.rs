//! Snapshots of the code `model!` generates for the plants in `models/`, formatted with
//! prettyplease. A change in emitted code shows up as a reviewable diff
//! (`cargo insta review`, or `INSTA_UPDATE=always` to accept).

use std::path::Path;

/// Every `model! { ... }` invocation in a source file of the `models` crate, by model name.
fn invocations(file: &str) -> Vec<(String, proc_macro2::TokenStream)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../models/src")
        .join(file);
    let src = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let parsed = syn::parse_file(&src).expect("models source parses");
    parsed
        .items
        .into_iter()
        .filter_map(|item| match item {
            syn::Item::Macro(m)
                if m.mac
                    .path
                    .segments
                    .last()
                    .is_some_and(|s| s.ident == "model") =>
            {
                let def: dpc_codegen::parse::ModelDef =
                    syn::parse2(m.mac.tokens.clone()).expect("model parses");
                Some((def.name.to_string(), m.mac.tokens))
            }
            _ => None,
        })
        .collect()
}

fn generated(tokens: proc_macro2::TokenStream) -> String {
    let out = dpc_codegen::try_expand(tokens).expect("model expands without errors");
    let file: syn::File = syn::parse2(out).expect("generated code is valid Rust");
    prettyplease::unparse(&file)
}

fn snapshot_file(file: &str, expected_models: &[&str]) {
    let found = invocations(file);
    let names: Vec<&str> = found.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, expected_models, "models declared in {file}");
    for (name, tokens) in found {
        let model = dpc_codegen::lower_model(tokens.clone()).expect("model lowers");
        insta::assert_snapshot!(
            format!("{name}_listing"),
            dpc_codegen::emit::listing(&model)
        );
        insta::assert_snapshot!(format!("{name}_generated"), generated(tokens));
    }
}

#[test]
fn wheel_models() {
    snapshot_file("wheel.rs", &["Wheel", "WheelLinear"]);
}

#[test]
fn pendulum_model() {
    snapshot_file("pendulum.rs", &["Pendulum"]);
}

#[test]
fn flexible_joint_model() {
    snapshot_file(
        "flexible_joint.rs",
        &[
            "FlexibleJoint",
            "FlexibleJointMass",
            "FlexibleJointMass3",
            "FlexibleJointMass4",
        ],
    );
}
