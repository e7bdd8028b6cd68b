//! A seeded property test of the command line: random edits of the repository's scenarios (`--set` with values that are wrong in type, sign, magnitude or finiteness) never
//! panic, and a run that writes results never writes NaN, or null for a number, into
//! `summary.json` (the per-output errors, the final time, the round-off level).

use std::path::PathBuf;

use dpc::cli::registry::{Entry, Registry};
use dpc::core::linear_solver::NalgebraLu;
use dpc_models::{
    FlexibleJoint, FlexibleJointReference, FlexibleJointTracking, Wheel, WheelReference,
    WheelTracking,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// The wheel and the flexible-joint arm as the `dpc` binary registers them.
fn registry() -> Registry {
    Registry::new()
        .model(
            Entry::new(
                "wheel",
                "the paper's rolling wheel",
                Wheel::default(),
                WheelTracking::default(),
            )
            .reference(WheelReference::default())
            .solver(NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new),
        )
        .model(
            Entry::new(
                "flexible-joint",
                "a flexible-joint arm",
                FlexibleJoint::default(),
                FlexibleJointTracking::default(),
            )
            .reference(FlexibleJointReference::default())
            .solver(NalgebraLu::<{ FlexibleJointTracking::N_EQUATIONS }>::new),
        )
}

/// Positive times, tolerances and bounds, and what is wrong with them.
const SCALAR: &[&str] = &[
    "0.05", "0.02", "0.1", "0.2", "1", "2", "1e-300", "1e300", "nan", "inf", "-inf", "-1", "0",
];

/// Keys and the values tried for each: most of the key's type, some out of range.
const EDITS: &[(&str, &[&str])] = &[
    ("h", SCALAR),
    ("t_end", SCALAR),
    (
        "delta",
        &["1e-3", "1e-4", "1e-2", "1e-300", "0.04", "nan", "-1"],
    ),
    ("nu", &["0", "1", "2", "3", "20", "21", "1000"]),
    (
        "x0",
        &[
            "[1.5, 0.0, 0.0, 0.0, -6.0]",
            "[1.9, 0.0, 0.0, 0.0, -6.0]",
            "[1e300, 0.0, 0.0, 0.0, -6.0]",
            "[1.5, 0.0, 0.0, 0.0]",
            "[nan, 0.0, 0.0, 0.0, -6.0]",
        ],
    ),
    ("hold", &["input", "correction", "zero"]),
    ("extraction", &["first-usable", "extrapolated", "last"]),
    ("prefeedback", &["true", "false", "1"]),
    (
        "w.theta",
        &[
            "[5.0]",
            "[1.0]",
            "[0.0]",
            "[-2.0]",
            "[1e308]",
            "[nan]",
            "[1.0, 2.0]",
            "[]",
        ],
    ),
    ("w.psi", &["[5.0]", "[20.0]", "[1e100]"]),
    (
        "design.poles",
        &[
            "[-5.0, -5.0, -5.0]",
            "[-1.0, -2.0, -3.0]",
            "[-1e200, -1.0, -1.0]",
            "[0.0, 0.0, 0.0]",
            "[[-1.0, 1.0], [-1.0, -1.0], -2.0]",
        ],
    ),
    ("design.about", &["nominal", "reference", "elsewhere"]),
    (
        "plant.params.m",
        &["1.0", "1.2", "0.0", "-1.0", "1e300", "nan"],
    ),
    ("controller.params.r", &["0.5", "0.3", "1e-300"]),
    ("plant.rtol", SCALAR),
    ("plant.atol", SCALAR),
    ("plant.max_consecutive_failures", &["0", "1", "3", "100"]),
    ("plant.integrator", &["auto", "bdf", "radau", "euler"]),
    ("divergence.tracking_error", SCALAR),
    ("divergence.state.dphi", SCALAR),
    ("divergence.output.theta", SCALAR),
    (
        "controller.retry.growth",
        &["4.0", "1.5", "1.0", "1e300", "nan"],
    ),
    (
        "controller.retry.max_delta",
        &["0.05", "0.01", "1e-4", "inf"],
    ),
    ("controller.retry.retries", &["0", "1", "5", "1000"]),
    (
        "reference.theta",
        &[
            "[{ constant = 1.5 }]",
            "[{ polynomial = [1e300, 1e300] }]",
            "[{ sine = { amplitude = 1.0, omega = 1e300 } }]",
        ],
    ),
    (
        "reference.psi",
        &["[{ polynomial = [0.0, -6.0] }]", "[{ constant = 0.0 }]"],
    ),
    ("limits.samples", &["1", "5", "11", "2000"]),
    ("title", &["a/b", "\"\"", "\"x\""]),
];

#[test]
fn random_scenario_edits_never_panic_nor_write_nan() {
    let registry = registry();
    let scenarios = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenarios");
    let files = [
        scenarios.join("wheel.toml"),
        scenarios.join("wheel-hold-correction.toml"),
        scenarios.join("flexible-joint.toml"),
    ];
    let root = std::env::temp_dir().join(format!("dpc-cli-edits-{}", std::process::id()));
    let config = Config {
        cases: 128,
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[13; 32]));
    let edit = (0..EDITS.len(), any::<prop::sample::Index>()).prop_map(|(k, v)| {
        let (key, values) = EDITS[k];
        format!("{key}={}", values[v.index(values.len())])
    });
    let written = std::cell::Cell::new(0);
    runner
        .run(
            &(0..files.len(), proptest::collection::vec(edit, 1..4)),
            |(file, edits)| {
                let out = root.join("out");
                let _ = std::fs::remove_dir_all(&out);
                let mut args = vec![
                    "dpc".to_string(),
                    "simulate".into(),
                    files[file].display().to_string(),
                    "--out".into(),
                    out.display().to_string(),
                ];
                // Short runs; a larger edit meets the sample limit (an error, not a long run).
                for set in ["t_end=0.5", "compare=[]", "limits.samples=2000"]
                    .iter()
                    .map(|s| s.to_string())
                    .chain(edits.iter().cloned())
                {
                    args.extend(["--set".to_string(), set]);
                }
                dpc::cli::command::main_with_args(&registry, &args);
                let Ok(text) = std::fs::read_to_string(out.join("summary.json")) else {
                    return Ok(());
                };
                written.set(written.get() + 1);
                let v: serde_json::Value = serde_json::from_str(&text).unwrap();
                // No number is NaN (serde_json would have written null) nor written as "NaN".
                prop_assert!(!has_nan(&v), "{edits:?}: {text}");
                for key in ["t_final", "roundoff_level", "wall_time_s"] {
                    prop_assert!(number(&v[key]), "{edits:?}: {key} = {}", v[key]);
                }
                for key in ["final_error", "max_abs_error"] {
                    let map = v[key].as_object().unwrap();
                    prop_assert!(!map.is_empty(), "{:?}: {}", edits, key);
                    for (name, value) in map {
                        prop_assert!(number(value), "{edits:?}: {key}.{name} = {value}");
                    }
                }
                Ok(())
            },
        )
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    // The edits are not all rejected: some runs write results to check.
    assert!(
        written.get() >= 5,
        "only {} runs wrote results",
        written.get()
    );
}

/// Whether a value of the tree is the string "NaN" (the only way NaN could be spelled).
fn has_nan(v: &serde_json::Value) -> bool {
    match v {
        serde_json::Value::String(s) => s == "NaN" || s == "nan",
        serde_json::Value::Array(items) => items.iter().any(has_nan),
        serde_json::Value::Object(map) => map.values().any(has_nan),
        _ => false,
    }
}

/// A number, or the marker of an infinite one.
fn number(v: &serde_json::Value) -> bool {
    v.is_number() || v == "inf" || v == "-inf"
}
