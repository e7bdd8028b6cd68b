//! End-to-end tests of `dpc analyze`: the readable report, the JSON keys, and one clear error
//! line (never a panic) for malformed input.

use std::path::PathBuf;
use std::process::{Command, Output};

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("examples")
        .join("linear")
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(args)
        .output()
        .expect("dpc runs")
}

fn run_text(name: &str, text: &str, json: bool) -> Output {
    let dir = std::env::temp_dir().join(format!("dpc-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let p = path.to_str().unwrap().to_string();
    if json {
        run(&["analyze", &p, "--json"])
    } else {
        run(&["analyze", &p])
    }
}

const WHEEL: &str = "a = [[0.0, 0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, -3.0, 0.0], [6.54, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 0.0]]
b = [[0.0, 0.0], [0.0, 0.0], [2.0, 0.0], [0.0, 0.0], [0.0, 0.8]]
c = [[1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0, 0.0]]
";

#[test]
fn readable_report_for_the_wheel() {
    let out = run(&[
        "analyze",
        examples().join("wheel-linearised.toml").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = String::from_utf8(out.stdout).unwrap();
    assert!(s.contains("index nu = 2"), "{s}");
    assert!(s.contains("transmission zeros (eig A_1): -5, -5"), "{s}");
    assert!(s.contains("verdict: DPC is UNSTABLE"), "{s}");
    assert!(
        s.contains("verdict: DPC with preliminary feedback is STABLE"),
        "{s}"
    );
}

#[test]
fn json_has_the_documented_keys() {
    let out = run(&[
        "analyze",
        examples().join("paper-4-1.toml").to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "n",
        "m",
        "nu",
        "transmission_zeros",
        "abar4_eigenvalues",
        "dpc_stable",
        "k_j",
        "r_xi",
        "closed_loop_eigenvalues",
        "k_n",
        "r_xi_prefeedback",
        "closed_loop_eigenvalues_prefeedback",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["n"], 5);
    assert_eq!(v["m"], 2);
    assert_eq!(v["nu"], 2);
    assert_eq!(v["dpc_stable"], false);
    assert_eq!(v["dpc_stable_prefeedback"], true);
    // Eigenvalues as [re, im] pairs, matrices as arrays of rows.
    let z = &v["transmission_zeros"][0];
    assert!((z[0].as_f64().unwrap() + 5.0).abs() < 1e-6 && z[1].as_f64().unwrap().abs() < 1e-6);
    assert_eq!(v["k_j"].as_array().unwrap().len(), 2);
    assert_eq!(v["k_j"][0].as_array().unwrap().len(), 5);
    // R_xi after the preliminary feedback: diag(5 + 2s + 0.2s^2, 5 + s).
    let r = &v["r_xi_prefeedback"];
    let at = |k: usize, i: usize, j: usize| r[k][i][j].as_f64().unwrap();
    assert!((at(0, 0, 0) - 5.0).abs() < 1e-8 && (at(1, 0, 0) - 2.0).abs() < 1e-8);
    assert!((at(2, 0, 0) - 0.2).abs() < 1e-8 && (at(0, 1, 1) - 5.0).abs() < 1e-8);
    assert!((at(1, 1, 1) - 1.0).abs() < 1e-8 && at(2, 1, 1).abs() < 1e-8);
}

#[test]
fn without_w_and_poles_the_defaults_apply() {
    let out = run_text("plain.toml", WHEEL, true);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // Without W the index is one higher and there are no zeros.
    assert_eq!(v["nu"], 3);
    assert_eq!(v["transmission_zeros"].as_array().unwrap().len(), 0);
}

fn assert_one_line_error(out: &Output, needle: &str) {
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.to_lowercase().contains(&needle.to_lowercase()),
        "expected {needle:?} in {err}"
    );
}

#[test]
fn malformed_files_give_one_error_line() {
    let cases: &[(&str, String, &str)] = &[
        ("bad.toml", "a = [[1.0, 2.0]\n".into(), "error"),
        ("missing.toml", "a = [[0.0]]\nb = [[1.0]]\n".into(), "missing field `c`"),
        (
            "ragged.toml",
            "a = [[0.0, 1.0], [0.0]]\nb = [[0.0], [1.0]]\nc = [[1.0, 0.0]]\n".into(),
            "ragged",
        ),
        (
            "dims.toml",
            "a = [[0.0, 1.0], [0.0, 0.0]]\nb = [[0.0], [1.0], [2.0]]\nc = [[1.0, 0.0]]\n".into(),
            "dimension mismatch",
        ),
        (
            "nonsquare.toml",
            "a = [[0.0, 1.0], [0.0, 0.0]]\nb = [[0.0], [1.0]]\nc = [[1.0, 0.0], [0.0, 1.0]]\n"
                .into(),
            "non-square",
        ),
        (
            "nan.toml",
            "a = [[0.0, nan], [0.0, 0.0]]\nb = [[0.0], [1.0]]\nc = [[1.0, 0.0]]\n".into(),
            "non-finite",
        ),
        (
            "unknown.toml",
            format!("{WHEEL}colour = \"red\"\n"),
            "unknown field",
        ),
        (
            "badw.toml",
            format!("{WHEEL}w = [[-1.0], [5.0]]\n"),
            "bad W",
        ),
        (
            "wdegree.toml",
            format!("{WHEEL}w = [[5.0, 5.0, 5.0, 5.0], [5.0]]\n"),
            "relative degree",
        ),
        (
            "badpoles.toml",
            format!("{WHEEL}w = [[5.0], [5.0]]\npoles = [-1.0]\n"),
            "bad poles",
        ),
        (
            "empty.toml",
            "a = []\nb = [[1.0]]\nc = [[1.0]]\n".into(),
            "no rows",
        ),
        (
            "singular.toml",
            "a = [[0.0, 0.0], [0.0, 0.0]]\nb = [[1.0, 0.0], [0.0, 1.0]]\nc = [[1.0, 0.0], [1.0, 0.0]]\n"
                .into(),
            "singular pencil",
        ),
    ];
    for (name, text, needle) in cases {
        let out = run_text(name, text, false);
        assert_one_line_error(&out, needle);
    }
    let out = run(&["analyze", "/nonexistent/system.toml"]);
    assert_one_line_error(&out, "cannot read");
}
