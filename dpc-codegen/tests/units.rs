//! Units per variable in the DSL: parsed, carried into the model and shown in the listing.

use proc_macro2::TokenStream;

fn tokens(src: &str) -> TokenStream {
    src.parse().expect("test model tokenises")
}

fn errors(src: &str) -> Vec<String> {
    match dpc_codegen::derive_model(tokens(src)) {
        Ok(_) => Vec::new(),
        Err(e) => e.into_iter().map(|e| e.to_string()).collect(),
    }
}

const ARM: &str = r#"Arm {
    consts { N = 2 }
    params { m: "kg" = 1.0, l[N]: "m" = 0.5, g = 9.81 }
    states { q[N]: "rad", w[N]: "rad/s" }
    inputs { tau[N]: "N m" }
    equations {
        for i in 0..N {
            der(q[i]) = w[i];
            m * l[i] * der(w[i]) == tau[i] - g * sin(q[i]);
        }
    }
    outputs { q, tip: " m " = l[0] * sin(q[0]) + l[1] * sin(q[1]), e = q[0] - q[1] }
}"#;

#[test]
fn units_reach_every_element_and_the_listing() {
    let (model, _) = dpc_codegen::derive_model(tokens(ARM)).unwrap_or_else(|e| panic!("{e}"));
    let units = model.units();
    let unit = |name: &str| {
        units
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, u)| u.as_str())
    };
    assert_eq!(unit("m"), Some("kg"));
    assert_eq!(unit("l[1]"), Some("m"));
    assert_eq!(unit("g"), None, "a parameter without a unit has none");
    assert_eq!(unit("q[0]"), Some("rad"));
    assert_eq!(unit("w[1]"), Some("rad/s"));
    assert_eq!(unit("tau[0]"), Some("N m"));
    // A bare output takes its variable's unit; a written one is trimmed.
    assert_eq!(model.outputs[1].unit.as_deref(), Some("rad"));
    assert_eq!(unit("tip"), Some("m"));
    assert_eq!(unit("e"), None);
    let listing = dpc_codegen::derive::listing(&model);
    assert!(
        listing.contains("params     m [kg] = 1.0, l[0] [m] = 0.5, l[1] [m] = 0.5, g = 9.81"),
        "{listing}"
    );
    assert!(
        listing.contains("states     q[0] [rad], q[1] [rad], w[0] [rad/s], w[1] [rad/s]"),
        "{listing}"
    );
    assert!(
        listing.contains("inputs     tau[0] [N m], tau[1] [N m]"),
        "{listing}"
    );
    assert!(
        listing.contains("    tip [m] = l[0] * sin(q[0])"),
        "{listing}"
    );
    assert!(listing.contains("    e = q[0] - q[1]"), "{listing}");
}

#[test]
fn malformed_units_are_errors_on_the_unit() {
    let model = |decl: &str| {
        format!("M {{ states {{ {decl} }} equations {{ der(x) = -x; }} outputs {{ x }} }}")
    };
    let cases = [
        (
            r#"x: rad"#,
            "expected the unit of `x` as a string literal, e.g. `x: \"rad\"`",
        ),
        (r#"x: 1.0"#, "expected the unit of `x` as a string literal"),
        (r#"x: """#, "the unit of `x` is empty"),
        (r#"x: "  ""#, "the unit of `x` is empty"),
        (r#"x: "a]b""#, "the unit of `x` contains `[` or `]`"),
        ("x: \"ra\nd\"", "the unit of `x` spans more than one line"),
    ];
    for (decl, expected) in cases {
        let errs = errors(&model(decl));
        assert_eq!(errs.len(), 1, "{decl}: {errs:?}");
        assert!(errs[0].starts_with(expected), "{decl}: {errs:?}");
    }
}

#[test]
fn a_bare_output_with_another_unit_than_its_variable_is_an_error() {
    let errs = errors(r#"M { states { x: "m" } equations { der(x) = -x; } outputs { x: "mm" } }"#);
    assert_eq!(
        errs,
        ["output `x` is the variable `x`, declared in `m`, but is given the unit `mm`; leave the unit out here"]
    );
    // The same unit, or a unit only on the output, is fine.
    assert!(
        errors(r#"M { states { x: "m" } equations { der(x) = -x; } outputs { x: "m" } }"#)
            .is_empty()
    );
    let (model, _) = dpc_codegen::derive_model(tokens(
        r#"M { states { x } equations { der(x) = -x; } outputs { x: "m" } }"#,
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.units(), [("x".to_string(), "m".to_string())]);
}
