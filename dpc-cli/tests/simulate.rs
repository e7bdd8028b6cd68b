//! End-to-end tests of `dpc simulate` with run-time changes of the model: parameters of the
//! simulated plant by name, the roots of `W`, and one clear error line for what cannot change
//! at run time. Runs are cut to two seconds of the wheel scenario without its comparison run.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn wheel_scenario() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenarios")
        .join("wheel.toml")
}

fn out_dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("dpc-cli-simulate-{}-{name}", std::process::id()))
}

/// `dpc simulate scenarios/wheel.toml --out DIR` for 2 s without comparison runs, with `sets`.
fn simulate(dir: &Path, sets: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_dpc"));
    cmd.arg("simulate")
        .arg(wheel_scenario())
        .arg("--out")
        .arg(dir)
        .args(["--set", "t_end=2", "--set", "compare=[]"]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd.output().expect("dpc runs")
}

fn summary(dir: &Path, sets: &[&str]) -> serde_json::Value {
    let out = simulate(dir, sets);
    assert!(
        out.status.success(),
        "{sets:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json written");
    let _ = std::fs::remove_dir_all(dir);
    serde_json::from_str(&text).expect("summary.json is JSON")
}

fn one_error_line(out: &Output) -> String {
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    err
}

#[test]
fn plant_parameters_and_w_change_at_run_time() {
    let base = summary(&out_dir("base"), &[]);
    assert_eq!(base["in_use"]["plant_params"]["m"], 1.0);
    assert_eq!(
        base["in_use"]["w_coefficients"]["theta"],
        serde_json::json!([5.0, 1.0])
    );
    assert!(base["t_final"].as_f64().unwrap() > 1.9, "{base}");

    // A heavier plant than the controller's model: the mismatch shows in the errors.
    let heavy = summary(&out_dir("heavy"), &["plant.params.m=1.1"]);
    assert_eq!(heavy["scenario"]["plant"]["params"]["m"], 1.1);
    assert_eq!(heavy["in_use"]["plant_params"]["m"], 1.1);
    assert_eq!(heavy["in_use"]["plant_params"]["g"], 9.81);
    assert_eq!(heavy["in_use"]["controller_params"]["m"], 1.0);
    assert!(heavy["samples"].as_u64().unwrap() >= 40, "{heavy}");
    assert_ne!(heavy["final_error"], base["final_error"]);

    // W = s + 3 on theta instead of the compiled s + 5; psi keeps s + 5.
    let slower = summary(&out_dir("w"), &["w.theta=[3.0]"]);
    assert_eq!(slower["scenario"]["w"]["theta"], serde_json::json!([3.0]));
    assert_eq!(
        slower["in_use"]["w_coefficients"]["theta"],
        serde_json::json!([3.0, 1.0])
    );
    assert_eq!(
        slower["in_use"]["w_coefficients"]["psi"],
        serde_json::json!([5.0, 1.0])
    );
    assert!(slower["samples"].as_u64().unwrap() >= 40, "{slower}");
    assert_ne!(slower["final_error"], base["final_error"]);
    // The design linearised the controller's model with the W in use.
    assert_ne!(
        slower["linear_design"]["abar4_eigenvalues"],
        base["linear_design"]["abar4_eigenvalues"]
    );
}

#[test]
fn what_cannot_change_gives_one_error_line() {
    let err = one_error_line(&simulate(&out_dir("nope"), &["plant.params.nope=1"]));
    assert!(err.contains("`plant.params.nope`"), "{err}");
    assert!(err.contains("m, r, i_r, i_n, g"), "{err}");

    let err = one_error_line(&simulate(&out_dir("cnope"), &["controller.params.mass=1"]));
    assert!(err.contains("`controller.params.mass`"), "{err}");
    assert!(err.contains("m, r, i_r, i_n, g"), "{err}");

    let err = one_error_line(&simulate(&out_dir("degree"), &["w.theta=[3.0, 4.0]"]));
    assert!(err.contains("deg W = 1"), "{err}");
    assert!(err.contains("`tracking` section"), "{err}");

    let err = one_error_line(&simulate(&out_dir("unstable"), &["w.psi=[-2.0]"]));
    assert!(err.contains("right half plane"), "{err}");

    let err = one_error_line(&simulate(&out_dir("output"), &["w.phi=[1.0]"]));
    assert!(err.contains("no output `phi`"), "{err}");
}
