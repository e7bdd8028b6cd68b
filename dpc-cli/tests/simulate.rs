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

/// The rows of `trajectory.csv` after its header.
fn rows(dir: &Path) -> (String, Vec<String>) {
    let text = std::fs::read_to_string(dir.join("trajectory.csv")).expect("trajectory.csv");
    let mut lines = text.lines().map(str::to_string);
    let header = lines.next().expect("a header");
    (header, lines.collect())
}

#[test]
fn output_step_writes_the_motion_between_samples_with_a_sample_column() {
    let plain_dir = out_dir("plain");
    let out = simulate(&plain_dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (plain_header, plain) = rows(&plain_dir);
    let _ = std::fs::remove_dir_all(&plain_dir);

    let dense_dir = out_dir("dense");
    let out = simulate(&dense_dir, &["output_step=0.01"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Not a terminal: no progress bar, nothing at all on stderr.
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (header, dense) = rows(&dense_dir);
    let _ = std::fs::remove_dir_all(&dense_dir);

    assert_eq!(header, format!("{plain_header},sample"));
    // 41 samples at k * 0.05 and the four points between each two.
    assert_eq!(plain.len(), 41);
    assert_eq!(dense.len(), 201);
    let samples: Vec<&str> = dense.iter().filter_map(|r| r.strip_suffix(",1")).collect();
    assert_eq!(samples.len(), 41);
    assert_eq!(dense.iter().filter(|r| r.ends_with(",0")).count(), 160);
    // The sample rows are those of the run without an output step, digit for digit.
    assert_eq!(
        samples,
        plain.iter().map(String::as_str).collect::<Vec<_>>()
    );
    let times: Vec<f64> = dense
        .iter()
        .map(|r| r.split(',').next().unwrap().parse().unwrap())
        .collect();
    for (j, t) in times.iter().enumerate() {
        assert!((t - 0.01 * j as f64).abs() < 1e-12, "row {j}: t = {t}");
    }
}

#[test]
fn a_bad_output_step_or_too_many_rows_is_one_located_error_line() {
    let err = one_error_line(&simulate(&out_dir("zero"), &["output_step=0"]));
    assert!(err.contains("(--set output_step)"), "{err}");
    assert!(
        err.contains("`output_step` must be a positive finite number, found 0"),
        "{err}"
    );

    let err = one_error_line(&simulate(&out_dir("tiny"), &["output_step=1e-15"]));
    assert!(
        err.contains("`output_step` (1e-15) must be at least 1e-12 times `t_end` (2)"),
        "{err}"
    );

    // 2 s every 1e-6: two million rows, over the default limit of a million.
    let err = one_error_line(&simulate(&out_dir("rows"), &["output_step=1e-6"]));
    assert!(err.contains("2000001 rows of trajectory.csv"), "{err}");
    assert!(err.contains("`limits.rows` = 1000000"), "{err}");
    assert!(err.contains("--set limits.rows=N"), "{err}");

    // Written in the file: its line and column.
    let dir = out_dir("file");
    std::fs::create_dir_all(&dir).unwrap();
    let wheel = std::fs::read_to_string(wheel_scenario()).unwrap();
    let text = wheel.replacen("h = ", "output_step = -0.5\nh = ", 1);
    let line = text
        .lines()
        .position(|l| l.starts_with("output_step"))
        .unwrap()
        + 1;
    let path = dir.join("bad-step.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_dpc"))
        .arg("simulate")
        .arg(&path)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .expect("dpc runs");
    let err = one_error_line(&out);
    let at = format!(
        "bad-step.toml:{line}:15: `output_step` must be a positive finite number, found -0.5"
    );
    assert!(err.contains(&at), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
