//! Plant files that cannot be used give typed errors, one `FILE:LINE:COLUMN: message` line
//! per problem (all of them), and never panic; good files give working models.

use dpc_core::{DaeModel, Reference, TrackingDae};
use dpc_runtime::{load, parse, PlantFileError};

const CART: &str = "/// A cart on a spring.
pub Cart {
    params { m = 2.0, k = 0.5 }
    states { x, v }
    inputs { f }
    equations {
        der(x) = v;
        m * der(v) == -k * x + f;
    }
    outputs { x }
    references { x = sin(t) }
    tracking CartTracking { x: [3.0, 4.0] }
}
";

/// The diagnostics of an invalid text, as `(line, column, message)`.
fn diagnostics(text: &str) -> Vec<(usize, usize, String)> {
    match parse("plant.dpc", text) {
        Err(PlantFileError::Invalid { path, diagnostics }) => {
            assert_eq!(path, "plant.dpc");
            diagnostics
                .into_iter()
                .map(|d| (d.line, d.column, d.message))
                .collect()
        }
        Err(other) => panic!("expected diagnostics, got {other}"),
        Ok(m) => panic!("expected diagnostics, `{}` compiled", m.name()),
    }
}

#[test]
fn a_good_file_evaluates_and_tracks() {
    let model = parse("cart.dpc", CART).unwrap();
    assert_eq!(model.name(), "Cart");
    let plant = model.plant();
    let s = plant.structure();
    assert_eq!(s.states, ["x", "v"]);
    assert_eq!(s.params, ["m", "k"]);
    let mut r = [0.0; 2];
    // der(x) - v = 0.3 - 0.25; m der(v) + k x - f = 2 * 1.5 + 0.5 * 1.0 - 0.5.
    plant.residual(0.0, &[1.0, 0.25], &[0.3, 1.5], &[], &[0.5], &mut r);
    assert!(
        (r[0] - 0.05).abs() < 1e-15 && (r[1] - 3.0).abs() < 1e-15,
        "{r:?}"
    );

    let mut tracking = model.tracking().unwrap();
    assert_eq!(tracking.structure().name, "CartTracking");
    assert_eq!(tracking.structure().algebraic, ["f"]);
    assert_eq!(tracking.structure().inputs, ["w_x"]);
    // W = (s + 3)(s + 4) = s^2 + 7 s + 12.
    assert_eq!(tracking.w_coefficients(0), &[12.0, 7.0, 1.0]);
    assert_eq!(tracking.relative_degrees(), &[Some(2)]);
    tracking.set_w_roots(0, &[1.0, 2.0]).unwrap();
    assert_eq!(tracking.w_coefficients(0), &[2.0, 3.0, 1.0]);
    assert!(tracking.set_w_roots(0, &[1.0]).is_err());
    assert!(tracking.set_w_coefficients(0, &[2.0, -3.0, 1.0]).is_err());
    assert_eq!(tracking.w_coefficients(0), &[2.0, 3.0, 1.0]);
    // The constraint row is der(v) + 3 v + 2 x - w (row 2): `der(x) = v` is explicit, the
    // equation of v is implicit, so der(v) stays an unknown of the row.
    let mut r = [0.0; 3];
    let (x, v, vdot, f, w) = (0.7, -0.2, 0.3, 1.1, 0.4);
    tracking.residual(0.0, &[x, v], &[v, vdot], &[f], &[w], &mut r);
    let want = vdot + 3.0 * v + 2.0 * x - w;
    assert!((r[2] - want).abs() < 1e-15, "{} vs {want}", r[2]);

    // Parameters by name, shared by plant and tracking DAE.
    let mut p = plant.params().clone();
    dpc_core::model::set_parameter_by_name(&plant, &mut p, "m", 4.0).unwrap();
    assert_eq!(p.values(), &[4.0, 0.5]);
    let err = dpc_core::model::set_parameter_by_name(&plant, &mut p, "mass", 4.0).unwrap_err();
    assert!(err.to_string().contains("`mass`"), "{err}");
    assert!(format!("{p:?}").contains("\"m\": 4.0"), "{p:?}");

    let reference = model.reference().unwrap();
    assert_eq!(reference.max_order(), 3);
    let mut out = [0.0; 4];
    reference.derivatives(0.5, 3, &mut out).unwrap();
    let t: f64 = 0.5;
    let want = [t.sin(), t.cos(), -t.sin(), -t.cos()];
    for (a, b) in out.iter().zip(want) {
        assert!((a - b).abs() < 1e-15, "{out:?}");
    }
    assert!(reference.derivatives(0.5, 4, &mut [0.0; 5]).is_err());
    assert!(reference.derivatives(0.5, 1, &mut [0.0; 3]).is_err());
    assert!(
        model
            .listing()
            .contains("output x: W(s) = (s + 3.0)(s + 4.0)"),
        "{}",
        model.listing()
    );
}

#[test]
fn a_file_without_tracking_has_no_tracking_dae() {
    let model = parse(
        "free.dpc",
        "Free { states { x } inputs { u } equations { der(x) = u; } }",
    )
    .unwrap();
    assert!(model.tracking().is_none());
    assert!(model.reference().is_none());
    // The tracking DAE made from its parameters is the empty one, and says so.
    let empty = <dpc_runtime::RuntimeTracking as DaeModel>::from_params(model.params());
    assert_eq!(empty.structure().name, "Free (no tracking section)");
    assert_eq!(empty.structure().n_equations(), 0);
    assert_eq!(empty.w_coefficients(0), &[] as &[f64]);
}

#[test]
fn every_error_of_a_file_is_reported_with_its_position() {
    let text = "Plant {
    params { k = 1.0, k = 2.0 }
    states { x }
    equations {
        der(x) = -k * y + foo(x) + x.powi(0.5);
    }
}";
    let d = diagnostics(text);
    assert_eq!(d.len(), 5, "{d:?}");
    assert_eq!((d[0].0, d[0].1), (2, 23), "{d:?}");
    assert!(d[0].2.contains("duplicate name `k`"), "{d:?}");
    assert_eq!((d[1].0, d[1].1), (2, 14), "{d:?}");
    assert!(d[1].2.contains("first declared here"), "{d:?}");
    assert!(d.iter().any(|e| e.0 == 5 && e.2.contains("`y`")), "{d:?}");
    assert!(d.iter().any(|e| e.0 == 5 && e.2.contains("`foo`")), "{d:?}");
    assert!(d.iter().any(|e| e.0 == 5 && e.2.contains("powi")), "{d:?}");
    // The error's text: one FILE:LINE:COLUMN line per problem.
    let err = parse("plant.dpc", text).unwrap_err().to_string();
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 5, "{err}");
    assert!(lines[0].starts_with("plant.dpc:2:23: "), "{err}");
    assert!(lines.iter().all(|l| l.starts_with("plant.dpc:")), "{err}");
}

#[test]
fn malformed_files_never_panic() {
    let cases: &[(&str, &str)] = &[
        ("empty file", ""),
        ("only a comment", "// nothing here\n"),
        ("unclosed brace", "Cart { states { x }"),
        ("unbalanced close", "Cart { states { x } } }"),
        ("unterminated string", "Cart { states { x \"oops } }"),
        ("stray character", "Cart { states { x } equations { der(x) = 1.0 $ 2.0; } }"),
        ("missing equations", "Cart { states { x } }"),
        ("unknown section", "Cart { states { x } equations { der(x) = 1.0; } widgets { a } }"),
        ("unknown function", "Cart { states { x } equations { der(x) = frob(x); } }"),
        ("overflowing literal", "Cart { states { x } equations { der(x) = 1e999 * x; } }"),
        ("overflowing default", "Cart { params { k = 1e400 } states { x } equations { der(x) = k; } }"),
        ("huge integer", "Cart { states { x } equations { der(x) = x.powi(99999999999999999999); } }"),
        ("tracking not square", "Cart { states { x } inputs { u, v } equations { der(x) = u + v; } outputs { x } tracking T { x: [1.0] } }"),
        ("tracking unknown output", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } tracking T { y: [1.0] } }"),
        ("tracking too many roots", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } tracking T { x: [1.0, 2.0] } }"),
        ("tracking negative root", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } tracking T { x: [-1.0] } }"),
        ("tracking not a list", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } tracking T { x: 1.0 } }"),
        ("tracking without name", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } tracking { x: [1.0] } }"),
        ("references of unknown output", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } references { y = t } }"),
        ("reference of a state", "Cart { states { x } inputs { u } equations { der(x) = u; } outputs { x } references { x = x } }"),
        ("rust code", "fn main() { println!(\"hi\"); }"),
        ("two models", "A { states { x } equations { der(x) = 1.0; } } B { states { y } equations { der(y) = 1.0; } }"),
        ("keyword name", "Cart { states { fn } equations { der(fn) = 1.0; } }"),
        ("deep nesting", &format!("Cart {{ states {{ x }} equations {{ der(x) = {}x{}; }} }}", "(".repeat(3000), ")".repeat(3000))),
    ];
    for (what, text) in cases {
        let result = std::panic::catch_unwind(|| parse("bad.dpc", text));
        let Ok(result) = result else {
            panic!("{what}: parse panicked");
        };
        if *what == "deep nesting" {
            // Deep but valid: as plain Rust accepts it, the file compiles.
            assert!(result.is_ok(), "{what}: {}", result.err().unwrap());
            continue;
        }
        let err = result.err().unwrap_or_else(|| panic!("{what}: accepted"));
        let text = err.to_string();
        assert!(!text.is_empty(), "{what}");
        for line in text.lines() {
            let mut parts = line.splitn(4, ':');
            assert_eq!(parts.next(), Some("bad.dpc"), "{what}: {line}");
            let l: usize = parts
                .next()
                .unwrap()
                .parse()
                .unwrap_or_else(|_| panic!("{what}: {line}"));
            let c: usize = parts
                .next()
                .unwrap()
                .parse()
                .unwrap_or_else(|_| panic!("{what}: {line}"));
            assert!(l >= 1 && c >= 1, "{what}: {line}");
            assert!(parts.next().is_some_and(|m| m.len() > 1), "{what}: {line}");
        }
    }
}

#[test]
fn an_empty_file_says_what_is_missing() {
    let d = diagnostics("\n\n");
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!((d[0].0, d[0].1), (1, 1), "{d:?}");
    assert!(d[0].2.contains("expected the model's name"), "{d:?}");
}

#[test]
fn unreadable_files_are_typed_errors() {
    let dir = std::env::temp_dir().join(format!("dpc-runtime-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let missing = dir.join("missing.dpc");
    let err = load(&missing).unwrap_err();
    assert!(
        matches!(
            err,
            PlantFileError::Read {
                kind: std::io::ErrorKind::NotFound,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string()
            .starts_with(&format!("{}: cannot read: ", missing.display())),
        "{err}"
    );

    let binary = dir.join("binary.dpc");
    std::fs::write(&binary, b"Cart {\n  states { x\xff }\n}").unwrap();
    let err = load(&binary).unwrap_err();
    match &err {
        PlantFileError::NotUtf8 {
            line,
            column,
            offset,
            ..
        } => {
            assert_eq!((*line, *column, *offset), (2, 13, 19), "{err}");
        }
        other => panic!("{other}"),
    }
    assert!(
        err.to_string()
            .starts_with(&format!("{}:2:13: ", binary.display())),
        "{err}"
    );

    let good = dir.join("cart.dpc");
    std::fs::write(&good, CART).unwrap();
    assert_eq!(load(&good).unwrap().origin(), good.display().to_string());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn values_are_send_sync_and_clone() {
    fn check<T: Send + Sync + Clone + 'static>() {}
    check::<dpc_runtime::RuntimeModel>();
    check::<dpc_runtime::RuntimePlant>();
    check::<dpc_runtime::RuntimeTracking>();
    check::<dpc_runtime::RuntimeReference>();
    check::<dpc_runtime::RuntimeParams>();
}

/// A buffer of the wrong length is a programming error that panics, as in generated code,
/// never a residual silently cut short.
#[test]
#[should_panic]
fn a_short_residual_buffer_panics() {
    let plant = parse("cart.dpc", CART).unwrap().plant();
    let mut r = [0.0; 1];
    plant.residual(0.0, &[1.0, 0.25], &[0.3, 1.5], &[], &[0.5], &mut r);
}

mod mutations {
    use super::CART;
    use proptest::prelude::*;

    /// Characters that matter to the grammar, to splice into a good file.
    const PIECES: &[&str] = &[
        "{", "}", "(", ")", "[", "]", ";", ",", "=", "==", "der(", "x", "v", "f", "k", "t", "-",
        "*", "/", ".powi(", "1e999", "0.0", "2", "tracking", "outputs", "let", "sin", "\"", "'",
        "//", "/*", "#", "é", "\u{0}",
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Any edit of a good file compiles or gives positioned diagnostics; nothing panics.
        #[test]
        fn edited_files_never_panic(
            edits in prop::collection::vec((0usize..400, 0usize..6, 0usize..PIECES.len()), 1..6)
        ) {
            let mut text = CART.to_string();
            for (at, cut, piece) in edits {
                let mut at = at.min(text.len());
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                let mut end = (at + cut).min(text.len());
                while !text.is_char_boundary(end) {
                    end += 1;
                }
                text.replace_range(at..end, PIECES[piece]);
            }
            let result = std::panic::catch_unwind(|| dpc_runtime::parse("edited.dpc", &text));
            prop_assert!(result.is_ok(), "panicked on:\n{text}");
            if let Ok(Err(err)) = result {
                let shown = err.to_string();
                prop_assert!(!shown.is_empty());
                for line in shown.lines() {
                    prop_assert!(line.starts_with("edited.dpc:"), "{line}");
                }
            }
        }
    }
}

#[test]
fn units_reach_the_structure_of_the_plant_and_its_tracking_dae() {
    let model = dpc_runtime::parse(
        "cart.dpc",
        r#"Cart {
            params { m: "kg" = 2.0, k = 0.5 }
            states { x: "m", v: "m/s" }
            inputs { f: "N" }
            equations { der(x) = v; m * der(v) == -k * x + f; }
            outputs { x }
            tracking CartTracking { x: [1.0, 2.0] }
        }"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let plant = model.plant();
    let s = dpc_core::DaeModel::structure(&plant);
    assert_eq!(s.unit("m"), Some("kg"));
    assert_eq!(s.unit("x"), Some("m"));
    assert_eq!(s.unit("v"), Some("m/s"));
    assert_eq!(s.unit("f"), Some("N"));
    assert_eq!(s.unit("k"), None);
    assert_eq!(s.units.len(), 4, "the bare output `x` is listed once");
    let tracking = model.tracking().expect("the model has a tracking section");
    let t = dpc_core::DaeModel::structure(&tracking);
    assert_eq!(t.unit("f"), Some("N"));
    assert!(
        model.listing().contains("states     x [m], v [m/s]"),
        "{}",
        model.listing()
    );
}
