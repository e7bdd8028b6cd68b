//! End-to-end tests of `dpc simulate` and `dpc sweep` on the scenario files of the
//! repository: what they write, the linear verdict they report, and one clear error line
//! (never a panic) for a bad scenario.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scenarios() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenarios")
}

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("dpc-cli-scenarios-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn dpc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(args)
        .output()
        .expect("dpc runs")
}

/// `dpc simulate FILE --out OUT --set S ...` for each of `sets`, which must succeed.
fn simulate(file: &Path, out: &Path, sets: &[&str]) -> Output {
    let mut args = vec![
        "simulate",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    let o = dpc(&args);
    assert!(o.status.success(), "{}: {}", file.display(), stderr(&o));
    o
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("valid JSON")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn the_wheel_scenario_writes_summary_trajectory_and_plots() {
    let out = out_dir("wheel");
    let file = scenarios().join("wheel.toml");
    simulate(&file, &out, &["t_end=2"]);
    let s = summary(&out);
    assert_eq!(s["diverged"], false);
    assert_eq!(s["samples"], 41);
    let design = &s["linear_design"];
    assert_eq!(design["dpc_stable_without_prefeedback"], false);
    assert_eq!(design["dpc_stable_with_prefeedback"], true);
    // psi is cyclic: the linearisation is the same all along x0(t) = [pi/2, -6t, 0, 0, -6].
    assert_eq!(design["linearisation_drift"], 0.0);
    let h_star = design["sampled"]["critical_period"]["at"].as_f64().unwrap();
    assert!((h_star - 0.1333).abs() < 1e-3, "{h_star}");
    for key in ["final_error", "max_abs_error"] {
        assert!(
            s[key]["theta"].is_number() && s[key]["psi"].is_number(),
            "{key}"
        );
    }
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(
        header,
        "t [s],theta [rad],psi [rad],dphi [rad/s],dtheta [rad/s],dpsi [rad/s],u1 [N m],u2 [N m],ref_theta [rad],ref_psi [rad],err_theta [rad],err_psi [rad]"
    );
    assert_eq!(csv.lines().count(), 42);
    for f in ["closed-loop.svg", "closed-loop.png"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 1000, "{f}");
    }
    // The comparison run without preliminary feedback has its own summary.
    let compare = summary(&out.join("compare").join("prefeedback=false"));
    assert_eq!(
        compare["linear_design"]["sampled"]["critical_period"],
        "unstable-at-any-period"
    );
}

#[test]
fn the_correction_hold_about_the_reference_is_far_more_accurate_than_about_the_nominal() {
    let out = out_dir("hold-correction");
    let file = scenarios().join("wheel-hold-correction.toml");
    simulate(&file, &out, &["t_end=8"]);
    let psi = |s: &serde_json::Value| s["max_abs_error"]["psi"].as_f64().unwrap();
    let about_reference = summary(&out);
    let about_nominal = summary(&out.join("compare").join("design.about=nominal"));
    assert!(
        psi(&about_reference) < 0.01 * psi(&about_nominal),
        "{} vs {}",
        psi(&about_reference),
        psi(&about_nominal)
    );
}

#[test]
fn a_nominal_along_which_the_linearisation_changes_is_reported() {
    let out = out_dir("drift");
    let file = scenarios().join("wheel.toml");
    let o = simulate(
        &file,
        &out,
        &[
            "t_end=1",
            "compare=[]",
            // Leaning over at 0.05 rad/s: consistent at t = 0 (the trim solver computes
            // the accelerations), but theta enters the equations, so the motion is not
            // steady and the linearisation changes along it.
            "design.nominal.state=[1.5707963267948966, 0.0, 0.0, 0.05, -6.0]",
            "design.nominal.rate={theta = 0.05, psi = -6.0}",
        ],
    );
    let design = &summary(&out)["linear_design"];
    let drift = design["linearisation_drift"].as_f64().unwrap();
    assert!(drift > 1e-4, "{drift}");
    let nominal = &design["nominal"];
    assert_eq!(
        nominal["solved_for"],
        serde_json::json!(["der(dphi)", "der(dtheta)", "der(dpsi)"])
    );
    let not_steady = nominal["not_steady"].as_str().unwrap();
    assert!(not_steady.contains("at t = 1"), "{not_steady}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("the linearisation changes along the nominal"),
        "{stdout}"
    );
}

/// The paper's nominal from a partial specification: upright, heading rate -6, no torque;
/// the trim solver finds the spin rate and the heading's rate, and the design is the one
/// the full specification gives.
#[test]
fn a_partial_nominal_is_trimmed_and_reported() {
    let file = scenarios().join("wheel.toml");
    let full = out_dir("nominal-full");
    simulate(&file, &full, &["t_end=1", "compare=[]"]);
    let partial = out_dir("nominal-partial");
    simulate(
        &file,
        &partial,
        &[
            "t_end=1",
            "compare=[]",
            "design.nominal.state={theta = 1.5707963267948966, psi = 0.0, dtheta = 0.0, dpsi = -6.0}",
            "design.nominal.rate={theta = 0.0, dtheta = 0.0, dphi = 0.0, dpsi = 0.0}",
            "design.nominal.guess={dphi = 0.7}",
        ],
    );
    let (a, b) = (
        &summary(&full)["linear_design"],
        &summary(&partial)["linear_design"],
    );
    let nominal = &b["nominal"];
    assert_eq!(
        nominal["solved_for"],
        serde_json::json!(["dphi", "der(psi)"])
    );
    assert!(nominal["state"]["dphi"].as_f64().unwrap().abs() < 1e-12);
    assert!((nominal["rate"]["psi"].as_f64().unwrap() + 6.0).abs() < 1e-12);
    assert_eq!(nominal["free_directions"], 0);
    assert!(nominal["not_steady"].is_null());
    assert_eq!(a["nominal"]["solved_for"], serde_json::json!([]));
    fn close(x: &serde_json::Value, y: &serde_json::Value) -> bool {
        match (x, y) {
            (serde_json::Value::Array(x), serde_json::Value::Array(y)) => {
                x.len() == y.len() && x.iter().zip(y).all(|(x, y)| close(x, y))
            }
            (x, y) => (x.as_f64().unwrap() - y.as_f64().unwrap()).abs() < 1e-9,
        }
    }
    for key in ["abar4_eigenvalues", "k_n"] {
        assert!(close(&a[key], &b[key]), "{key}: {} vs {}", a[key], b[key]);
    }
}

/// A tracking DAE whose compiled relative degree is not the plant's at the nominal is
/// refused before the loop runs, naming the output: the wheel upright at rest (no heading
/// rate, no spin) is an equilibrium, but there the steering torque no longer tilts it in the
/// linearisation, so the lean's relative degree 3 (through the spin) does not hold.
#[test]
fn a_relative_degree_that_differs_at_the_nominal_is_an_error() {
    let file = scenarios().join("wheel.toml");
    let out = out_dir("relative-degree");
    let o = dpc(&[
        "simulate",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "design.nominal.state=[1.5707963267948966, 0.0, 0.0, 0.0, 0.0]",
        "--set",
        "design.nominal.rate=[0.0, 0.0, 0.0, 0.0, 0.0]",
        "--set",
        "design.nominal.input={}",
    ]);
    let err = stderr(&o);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("output `theta`: no input reaches it at the nominal, relative degree 3 assumed by the tracking DAE"),
        "{err}"
    );
}

/// A constrained plant (index 3) designed from a scenario: the nominal gives positions and
/// rates only, the trim solver computes the rope's multiplier and the cart force, the design
/// runs on the constraint manifold, and `K_n` is reported in the plant's six coordinates;
/// with it the loop tracks, without it (the comparison run) it diverges as predicted.
#[test]
fn a_descriptor_plant_is_designed_from_its_scenario() {
    let out = out_dir("crane");
    simulate(&scenarios().join("crane.toml"), &out, &["t_end=5"]);
    let s = summary(&out);
    let design = &s["linear_design"];
    assert_eq!(
        design["nominal"]["solved_for"],
        serde_json::json!(["lambda", "f"])
    );
    let lambda = design["nominal"]["algebraic"]["lambda"].as_f64().unwrap();
    assert!((lambda - 9.81).abs() < 1e-9, "{lambda}");
    assert_eq!(design["dpc_stable_without_prefeedback"], false);
    assert_eq!(design["dpc_stable_with_prefeedback"], true);
    let k_n = design["k_n"].as_array().unwrap();
    assert_eq!((k_n.len(), k_n[0].as_array().unwrap().len()), (1, 6));
    assert_eq!(s["constraints"]["index"], 3);
    assert_eq!(s["constraints"]["dof"], 4);
    assert_eq!(s["diverged"], false);
    let plain = summary(&out.join("compare").join("prefeedback=false"));
    assert_eq!(plain["diverged"], true);
    assert!(plain["t_diverged"].as_f64().unwrap() < 4.0);
}

#[test]
fn every_scenario_in_the_repository_runs() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenarios())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for file in files {
        let name = file.file_stem().unwrap().to_str().unwrap().to_string();
        let out = out_dir(&format!("all-{name}"));
        simulate(&file, &out, &["t_end=1"]);
        let s = summary(&out);
        assert!(s["samples"].as_u64().unwrap() > 1, "{name}");
        assert!(
            s["linear_design"]["sampled"]["spectral_radius"].is_number(),
            "{name}"
        );
    }
}

#[test]
fn a_sweep_writes_one_row_per_combination() {
    let out = out_dir("sweep");
    let file = scenarios().join("wheel.toml");
    let o = dpc(&[
        "sweep",
        file.to_str().unwrap(),
        "--set",
        "h=0.05,0.2",
        "--set",
        "prefeedback=true,false",
        "--set",
        "t_end=3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows.len(), 5, "{table}");
    assert!(rows[0].starts_with("h,prefeedback,t_end,status,t_diverged"));
    // h = 0.05 with the feedback tracks; h = 0.2 (beyond the predicted 0.133) diverges.
    assert!(rows[1].starts_with("0.05,true,3,ok,"), "{}", rows[1]);
    assert!(rows[3].starts_with("0.2,true,3,diverged,"), "{}", rows[3]);
    for f in ["sweep.svg", "sweep.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
}

#[test]
fn bad_scenarios_give_one_error_line() {
    let dir = out_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let wheel = std::fs::read_to_string(scenarios().join("wheel.toml")).unwrap();
    let cases: Vec<(&str, String, Vec<&str>, &str)> = vec![
        (
            "model.toml",
            wheel.replace("model = \"wheel\"", "model = \"bicycle\""),
            vec![],
            "unknown model `bicycle`; the known models are: wheel",
        ),
        (
            "syntax.toml",
            "model = \"wheel\nh = 1\n".into(),
            vec![],
            "syntax.toml:1:",
        ),
        (
            "key.toml",
            format!("colour = \"red\"\n{wheel}"),
            vec![],
            "unknown field `colour`",
        ),
        (
            "x0.toml",
            wheel.clone(),
            vec!["--set", "x0=[1.0, 2.0]"],
            "`x0` has 2 entries, but model `wheel` has 5",
        ),
        (
            "delta.toml",
            wheel.clone(),
            vec!["--set", "delta=0.1"],
            "must be smaller than the sampling period",
        ),
        (
            "state.toml",
            wheel.clone(),
            vec![
                "--set",
                "design.about=reference",
                "--set",
                "design.reference_state.spin=\"theta\"",
            ],
            "model `wheel` has no state `spin`",
        ),
        (
            "output.toml",
            wheel.clone(),
            vec![
                "--set",
                "design.about=reference",
                "--set",
                "design.reference_state.dtheta=\"phi'\"",
            ],
            "has no output `phi`",
        ),
        (
            "bound-state.toml",
            wheel.clone(),
            vec!["--set", "divergence.state.spin=1.0"],
            "`divergence.state.spin`: model `wheel` has no state `spin`",
        ),
        (
            "bound-output.toml",
            wheel.clone(),
            vec!["--set", "divergence.output.phi=1.0"],
            "`divergence.output.phi`: model `wheel` has no output `phi`",
        ),
        (
            "bound-value.toml",
            wheel.clone(),
            vec!["--set", "divergence.tracking_error=0"],
            "`divergence.tracking_error` must be a positive number",
        ),
        (
            "growth.toml",
            wheel.clone(),
            vec!["--set", "controller.retry.growth=1.0"],
            "`controller.retry.growth` must be a number above 1",
        ),
        (
            "max-delta.toml",
            wheel.clone(),
            vec!["--set", "controller.retry.max_delta=1e-4"],
            "`controller.retry.max_delta` (0.0001) must be at least `delta` (0.001)",
        ),
        (
            "nominal-name.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.state={lean = 1.0}"],
            "`design.nominal.state.lean`: model `wheel` has no state `lean`; its states are theta, psi, dphi, dtheta, dpsi",
        ),
        (
            "nominal-input-name.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.input={theta = 1.0}"],
            "`design.nominal.input.theta`: model `wheel` has no input `theta`; its inputs are u1, u2",
        ),
        (
            "nominal-algebraic.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.algebraic={q = 1.0}"],
            "`design.nominal.algebraic.q`: model `wheel` has no algebraic unknown `q`; it has no algebraic unknowns",
        ),
        (
            "nominal-type.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.state=upright"],
            "an array of numbers (every entry, in the model's order) or a table of NAME = number",
        ),
        (
            "nominal-length.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.input=[0.0]"],
            "`design.nominal.input` has 1 entries, but model `wheel` has 2 (u1, u2)",
        ),
        (
            "nominal-guess-fixed.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.guess.theta=1.0"],
            "`design.nominal.guess.theta`: `theta` is fixed by the nominal",
        ),
        (
            "nominal-guess-unknown.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.guess.spin=1.0"],
            "`design.nominal.guess.spin`: model `Wheel` has no variable `spin`",
        ),
        (
            "nominal-guess-nan.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.guess.dphi=nan"],
            "`design.nominal.guess.dphi` is non-finite",
        ),
        (
            // A lean rate with the lean velocity fixed at zero: der(theta) = dtheta cannot
            // hold, and the message names that equation.
            "nominal-inconsistent.toml",
            wheel.clone(),
            vec!["--set", "design.nominal.rate=[0.05, -6.0, 0.0, 0.0, 0.0]"],
            "the fixed values leave these equations unsatisfiable: equation 0 (der(theta) = dtheta)",
        ),
    ];
    for (name, text, extra, expected) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = dir.join("out");
        let mut args = vec![
            "simulate",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = dpc(&args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{name} should fail");
        assert_eq!(err.lines().count(), 1, "{name}: {err}");
        assert!(err.starts_with("error: "), "{name}: {err}");
        assert!(err.contains(expected), "{name}: {err}");
    }
    let o = dpc(&[
        "simulate",
        "no/such/file.toml",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(
        err.starts_with("error: cannot read no/such/file.toml"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn a_long_wheel_run_that_tracks_is_not_a_divergence() {
    // psi = -6t - ... passes -1000 near t = 148; only the tracking errors and the rates decide.
    for name in ["wheel", "wheel-hold-correction"] {
        let out = out_dir(&format!("long-{name}"));
        let file = scenarios().join(format!("{name}.toml"));
        let o = simulate(&file, &out, &["t_end=400", "compare=[]"]);
        let s = summary(&out);
        assert_eq!(
            s["diverged"],
            false,
            "{name}: {}",
            String::from_utf8_lossy(&o.stdout)
        );
        assert_eq!(s["samples"], 8001, "{name}");
        assert_eq!(s["t_final"].as_f64().unwrap(), 400.0, "{name}");
        assert!(
            s["max_abs_error"]["psi"].as_f64().unwrap() < 1e-2,
            "{name}: {s}"
        );
    }
}

#[test]
fn tracking_error_and_state_bounds_stop_a_run_with_a_typed_cause() {
    let file = scenarios().join("wheel.toml");
    // A state bound that psi (about -6t - 0.22 t^2 early on) crosses just before t = 1.
    let out = out_dir("state-bound");
    simulate(
        &file,
        &out,
        &["t_end=2", "compare=[]", "divergence.state.psi=6.0"],
    );
    let s = summary(&out);
    assert_eq!(s["diverged"], true);
    let t = s["t_diverged"].as_f64().unwrap();
    assert!((t - 1.0).abs() < 0.06, "{t}");
    let cause = s["divergence_cause"].as_str().unwrap();
    assert!(cause.starts_with("state psi = -6.2"), "{cause}");
    assert!(cause.ends_with("left the domain |psi| <= 6"), "{cause}");

    // Without the preliminary feedback the wheel leaves the path: a tracking bound of 0.1 rad
    // on theta catches it where the old state bound waited for psi.
    let out = out_dir("tracking-bound");
    simulate(
        &file,
        &out,
        &[
            "t_end=20",
            "compare=[]",
            "prefeedback=false",
            "divergence.output.theta=0.1",
        ],
    );
    let s = summary(&out);
    assert_eq!(s["diverged"], true);
    let cause = s["divergence_cause"].as_str().unwrap();
    assert!(cause.starts_with("tracking error of theta = "), "{cause}");
    assert!(
        cause.ends_with("exceeds the bound |theta - ref| <= 0.1"),
        "{cause}"
    );
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let last = csv.lines().last().unwrap();
    let err_theta: f64 = last.split(',').nth(10).unwrap().parse().unwrap();
    assert!(err_theta.abs() > 0.1, "{last}");
}

#[test]
fn the_default_retry_ladder_solves_a_large_initial_inconsistency() {
    // theta(0) = pi/2 + 0.3: the first implicit-Euler step has no solution below delta ~ 0.03.
    // From delta = 1e-4 the default ladder (growth 4 up to max_delta = h = 0.05) ends at 0.05.
    let file = scenarios().join("wheel.toml");
    for delta in ["1e-3", "1e-4"] {
        let out = out_dir(&format!("retry-{delta}"));
        let delta_set = format!("delta={delta}");
        simulate(
            &file,
            &out,
            &[
                "t_end=1",
                "compare=[]",
                "x0=[1.8707963267948966, 0.0, 0.0, 0.0, -6.0]",
                &delta_set,
            ],
        );
        let s = summary(&out);
        assert_eq!(s["diverged"], false, "{delta}: {s}");
        assert_eq!(s["failed_samples"], 0, "{delta}: {s}");
        let first = &s["controller_events"][0];
        assert_eq!(first["event"], "retried", "{delta}: {first}");
        assert_eq!(first["t"], 0.0);
        let reached = first["delta"].as_f64().unwrap();
        assert!(reached >= 0.03, "{delta}: {first}");
        // Every retry is counted: the total is the sum over the reported events.
        let total: u64 = s["controller_events"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["retries"].as_u64().unwrap())
            .sum();
        assert_eq!(s["retries"].as_u64().unwrap(), total);
        assert_eq!(s["in_use"]["retry"]["max_delta"], 0.05);
    }

    // The old fixed ladder (four retries by 4 from 1e-4 ends at 0.0256) does not get there:
    // the controller fails and the failure is reported.
    let out = out_dir("retry-short");
    simulate(
        &file,
        &out,
        &[
            "t_end=1",
            "compare=[]",
            "x0=[1.8707963267948966, 0.0, 0.0, 0.0, -6.0]",
            "delta=1e-4",
            "controller.retry.retries=4",
        ],
    );
    let s = summary(&out);
    assert_eq!(s["controller_events"][0]["event"], "failed", "{s}");
    let message = s["controller_events"][0]["message"].as_str().unwrap();
    assert!(message.contains("after 4 retries"), "{message}");
}

#[test]
fn dpc_model_prints_the_listing_and_relative_degrees() {
    let o = dpc(&["model", "flexible-joint"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("model FlexibleJoint"), "{text}");
    assert!(text.contains("tracking FlexibleJointTracking"), "{text}");
    assert!(
        text.contains("output q_link: relative degree 4, deg W = 2"),
        "{text}"
    );
    assert!(text.contains("nu = 2"), "{text}");
    let o = dpc(&["model", "bicycle"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("unknown model `bicycle`"),
        "{}",
        stderr(&o)
    );
}
