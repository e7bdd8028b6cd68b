//! The command line never hangs, crashes or lies (issue 13): sizes that set the work of a run
//! are checked before it starts, a quantity that cannot be computed is an error or an
//! explicit marker, messages quote short excerpts with readable numbers, and results reach
//! their directory whole or not at all.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn wheel() -> PathBuf {
    repo().join("scenarios").join("wheel.toml")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("dpc-cli-reliability-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn dpc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(args)
        .output()
        .expect("dpc runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// `dpc simulate FILE --out OUT --set S...`.
fn simulate(file: &Path, out: &Path, sets: &[&str]) -> Output {
    let mut args = vec![
        "simulate".to_string(),
        file.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ];
    for s in sets {
        args.extend(["--set".to_string(), s.to_string()]);
    }
    Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(&args)
        .output()
        .expect("dpc runs")
}

/// A failure with one short error line, no panic.
fn one_error_line(o: &Output) -> String {
    let err = stderr(o);
    assert!(!o.status.success(), "should fail: {}", stdout(o));
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    err
}

/// Every file under `dir` with its contents, for comparing result directories.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

const SHORT: [&str; 2] = ["t_end=1", "compare=[]"];

#[test]
fn sizes_are_checked_before_any_work_with_a_way_to_raise_them() {
    let out = scratch("limits").join("out");
    let fj = repo().join("scenarios").join("flexible-joint.toml");
    let err = one_error_line(&simulate(&fj, &out, &["t_end=1e12"]));
    assert!(err.contains("`limits.samples` = 100000"), "{err}");
    assert!(err.contains("5.00e13 samples"), "{err}");
    assert!(err.contains("--set limits.samples="), "{err}");

    let err = one_error_line(&simulate(&fj, &out, &["nu=100000000"]));
    assert!(
        err.contains("`nu` = 100000000 exceeds the limit `limits.nu`"),
        "{err}"
    );

    let err = one_error_line(&simulate(
        &wheel(),
        &out,
        &["controller.retry.growth=1.0000000000000002"],
    ));
    assert!(err.contains("`limits.retries`"), "{err}");

    // The limit is the scenario's to raise: 21 samples fail under 20 and run under 21.
    let err = one_error_line(&simulate(
        &wheel(),
        &out,
        &["t_end=1", "compare=[]", "limits.samples=20"],
    ));
    assert!(err.contains("gives 21 samples"), "{err}");
    let o = simulate(
        &wheel(),
        &out,
        &["t_end=1", "compare=[]", "limits.samples=21"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = one_error_line(&simulate(&wheel(), &out, &["limits.steps=1"]));
    assert!(err.contains("unknown field `steps`"), "{err}");
}

#[test]
fn a_huge_sweep_is_refused_at_once_and_the_limit_can_be_raised() {
    let dir = scratch("huge-sweep");
    let mut args: Vec<String> = vec!["sweep".into(), wheel().display().to_string()];
    for i in 0..22 {
        args.extend(["--set".into(), format!("plant.params.k{i}=1,2")]);
    }
    args.extend(["--out".into(), dir.join("out").display().to_string()]);
    let start = std::time::Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(&args)
        .output()
        .unwrap();
    let err = one_error_line(&o);
    assert!(start.elapsed().as_secs() < 30, "took {:?}", start.elapsed());
    assert!(err.contains("4194304 combinations"), "{err}");
    assert!(err.contains("--max-runs = 10000"), "{err}");
    assert!(!dir.join("out").exists());

    let err = one_error_line(&dpc(&[
        "sweep",
        wheel().to_str().unwrap(),
        "--set",
        "h=0.05,0.1",
        "--set",
        "t_end=1,2",
        "--max-runs",
        "3",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]));
    assert!(err.contains("4 combinations (2 x 2)"), "{err}");
}

#[test]
fn messages_quote_short_excerpts_and_readable_numbers() {
    let dir = scratch("messages");
    let out = dir.join("out");
    // A 200k-element array is not quoted back.
    let wheel_text = std::fs::read_to_string(wheel()).unwrap();
    let long: Vec<String> = (0..200_000).map(|i| format!("{i}.5")).collect();
    let body: String = wheel_text
        .lines()
        .filter(|l| !l.starts_with("x0 ="))
        .collect::<Vec<_>>()
        .join("\n");
    let big = dir.join("big.toml");
    std::fs::write(&big, format!("x0 = [{}]\n{body}\n", long.join(", "))).unwrap();
    let err = one_error_line(&simulate(&big, &out, &[]));
    assert!(err.contains("`x0` has 200000 entries"), "{err}");
    assert!(err.len() < 400, "{} bytes", err.len());
    let nan = dir.join("nan.toml");
    std::fs::write(
        &nan,
        format!("x0 = [{}, nan]\n{body}\n", long[..199_999].join(", ")),
    )
    .unwrap();
    let err = one_error_line(&simulate(&nan, &out, &[]));
    assert!(
        err.contains("`x0` has a non-finite entry NaN at index 199999"),
        "{err}"
    );
    assert!(err.contains("... (200000 entries)]"), "{err}");
    assert!(err.len() < 400, "{} bytes", err.len());

    let err = one_error_line(&simulate(&wheel(), &out, &["h=1e-300"]));
    assert!(err.contains("`h` (1e-300)"), "{err}");
    assert!(!err.contains("0000000"), "{err}");

    let err = one_error_line(&simulate(
        &wheel(),
        &out,
        &["design.poles=[1e308, -1.0, -1.0]"],
    ));
    assert!(
        err.contains("`design.poles[0]` = 1e308 is beyond 1.3e154"),
        "{err}"
    );
    let err = one_error_line(&simulate(&wheel(), &out, &["w.theta=[1e308]"]));
    assert!(
        err.contains("`w.theta[0]` = 1e308 is beyond 1.3e154"),
        "{err}"
    );
    for rtol in ["1e-300", "1000"] {
        let err = one_error_line(&simulate(&wheel(), &out, &[&format!("plant.rtol={rtol}")]));
        assert!(
            err.contains(&format!(
                "`plant.rtol` must lie between the machine epsilon 2.2e-16 and 1, found {rtol}"
            )),
            "{err}"
        );
    }
    let err = one_error_line(&simulate(&wheel(), &out, &["w.theta=[inf]"]));
    assert!(err.contains("`w.theta[0]` is non-finite (inf)"), "{err}");
    assert!(!out.exists(), "failed runs wrote {}", out.display());

    // A run that diverges at once on a huge state says so in numbers one can read.
    let o = simulate(
        &wheel(),
        &out,
        &["t_end=0.5", "compare=[]", "x0=[1e300, 0.0, 0.0, 0.0, -6.0]"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let report = stdout(&o);
    assert!(report.contains("DIVERGED at t = 0: tracking error of theta = 1e300 exceeds the bound |theta - ref| <= 1000"), "{report}");
    assert!(!report.contains("0000000"), "{report}");
}

const LINEAR: &str = "a = [[0.0, 0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, -3.0, 0.0], [6.54, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 0.0]]
b = [[0.0, 0.0], [0.0, 0.0], [2.0, 0.0], [0.0, 0.0], [0.0, 0.8]]
c = [[1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0, 0.0]]
";

fn analyze(dir: &Path, name: &str, text: &str, json: bool) -> Output {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let p = path.to_str().unwrap();
    if json {
        dpc(&["analyze", p, "--json"])
    } else {
        dpc(&["analyze", p])
    }
}

#[test]
fn analyze_reports_errors_and_poles_never_nan() {
    let dir = scratch("analyze");
    for (name, extra, needle) in [
        (
            "nan.toml",
            "points = [nan]\n",
            "`points[0]` is non-finite (NaN)",
        ),
        (
            "pair.toml",
            "points = [[0.0, inf]]\n",
            "`points[0]` is non-finite (inf)",
        ),
        (
            "poles.toml",
            "w = [[5.0], [5.0]]\npoles = [1e308, -1.0, -1.0]\n",
            "`poles[0]` = 1e308 is beyond 1.3e154",
        ),
        (
            "w.toml",
            "w = [[1e308], [5.0]]\n",
            "`w[0][0]` = 1e308 is beyond",
        ),
        (
            "triple.toml",
            "points = [[1.0, 2.0, 3.0]]\n",
            ":4:10: a real number or an [re, im] pair",
        ),
    ] {
        let err = one_error_line(&analyze(&dir, name, &format!("{LINEAR}{extra}"), false));
        assert!(err.contains(needle), "{name}: {err}");
    }
    // B scaled by 1e-300: products underflow, so no verdict is given.
    let tiny = LINEAR
        .replace("2.0, 0.0]", "2e-300, 0.0]")
        .replace("0.8]", "0.8e-300]");
    let err = one_error_line(&analyze(
        &dir,
        "tiny.toml",
        &format!("{tiny}w = [[5.0], [5.0]]\n"),
        false,
    ));
    assert!(
        err.contains("`b[2][0]` = 2e-300 is below 1.5e-154"),
        "{err}"
    );

    // Points at a pole (0 is an eigenvalue of A; 1e-100 is one to working precision) are
    // reported as poles, beside an ordinary point.
    let text = format!("{LINEAR}points = [0.0, 1e-100, [0.0, 1.0]]\n");
    let o = analyze(&dir, "points.toml", &text, false);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = stdout(&o);
    assert!(!report.contains("NaN"), "{report}");
    assert!(
        report.contains("H(s) at s = 0: pole (s is an eigenvalue of A to working precision)"),
        "{report}"
    );
    assert_eq!(report.matches(": pole (").count(), 2, "{report}");
    assert!(report.contains("H(s) at s = 0 + 1i: real part"), "{report}");
    let o = analyze(&dir, "points.toml", &text, true);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = stdout(&o);
    // `w` is absent from the input (null: no partial stabilisation); no number is null.
    let without_w = json.replace("\"w\": null", "");
    assert!(
        !without_w.contains("null") && !json.contains("NaN"),
        "{json}"
    );
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let transfer = v["transfer"].as_array().unwrap();
    assert_eq!(transfer.len(), 3);
    assert_eq!(transfer[0]["pole"], true);
    assert_eq!(transfer[1]["pole"], true);
    assert_eq!(transfer[1]["s"][0], 1e-100);
    assert!(transfer[2].get("pole").is_none());
    assert_eq!(transfer[2]["re"][1][1], -0.8);
}

#[test]
fn roundoff_beyond_the_largest_double_is_written_as_inf_and_said() {
    let out = scratch("roundoff").join("out");
    let o = simulate(
        &wheel(),
        &out,
        &["t_end=0.2", "compare=[]", "nu=1000", "limits.nu=1000"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("the controls carry no correct digit"),
        "{}",
        stdout(&o)
    );
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(!text.contains("NaN"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["roundoff_level"], "inf");
    assert!(v["max_abs_error"]["theta"].is_number(), "{text}");

    // A bound that is off is written as "inf", not null.
    let o = simulate(
        &wheel(),
        &out,
        &["t_end=0.2", "compare=[]", "divergence.tracking_error=inf"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["scenario"]["divergence"]["tracking_error"], "inf");
}

#[test]
fn a_state_outside_its_bound_at_t0_reports_the_errors_at_t0() {
    let out = scratch("t0").join("out");
    let o = simulate(
        &wheel(),
        &out,
        &[
            "t_end=1",
            "compare=[]",
            "divergence.state.dphi=0.1",
            "x0=[1.5, 0.0, 0.5, 0.0, -6.0]",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["diverged"], true);
    assert_eq!(v["t_diverged"], 0.0);
    assert_eq!(
        v["divergence_cause"],
        "state dphi = 0.5 left the domain |dphi| <= 0.1"
    );
    // theta(0) = 1.5 against the reference pi/2.
    let e = v["final_error"]["theta"].as_f64().unwrap();
    assert!(
        (e - (1.5 - std::f64::consts::FRAC_PI_2)).abs() < 1e-12,
        "{v}"
    );
    assert_eq!(v["final_error"]["psi"], 0.0);
    assert_eq!(v["samples"], 1);
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
}

#[test]
fn a_failing_comparison_run_leaves_the_previous_results_intact() {
    let out = scratch("compare-fails").join("out");
    let o = simulate(&wheel(), &out, &["t_end=1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("compare").join("prefeedback=false").is_dir());
    let before = snapshot(&out);

    // The main run succeeds, the comparison run cannot start: nothing of either is kept.
    let err = one_error_line(&simulate(
        &wheel(),
        &out,
        &["t_end=2", "compare=[\"w.phi=[1.0]\"]"],
    ));
    assert!(err.contains("no output `phi`"), "{err}");
    assert!(
        err.contains(&format!(
            "the previous results in {} are unchanged",
            out.display()
        )),
        "{err}"
    );
    assert_eq!(snapshot(&out), before);
    let siblings: Vec<_> = std::fs::read_dir(out.parent().unwrap()).unwrap().collect();
    assert_eq!(siblings.len(), 1, "{siblings:?}");

    // A rerun without comparisons leaves no stale compare/.
    let o = simulate(&wheel(), &out, &SHORT);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("compare").exists());
    assert!(out.join("closed-loop.png").is_file());

    // A directory that is not a result directory is never replaced.
    let foreign = out.parent().unwrap().join("notes");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let err = one_error_line(&simulate(&wheel(), &foreign, &SHORT));
    assert!(err.contains("holds no summary.json"), "{err}");
    assert_eq!(
        std::fs::read_to_string(foreign.join("notes.txt")).unwrap(),
        "mine"
    );
}

/// `dpc simulate` under a file-size limit of 8 blocks, so that a file is cut short while the
/// results are being written; `ignore` makes the write fail with an error instead of the
/// signal that kills the process.
fn simulate_with_file_limit(out: &Path, ignore: bool) -> Output {
    let script = format!(
        "{}ulimit -f 8 && exec \"$0\" simulate \"$1\" --out \"$2\" --set t_end=4 --set 'compare=[]'",
        if ignore { "trap '' XFSZ; " } else { "" }
    );
    Command::new("sh")
        .args(["-c", &script, env!("CARGO_BIN_EXE_dpc")])
        .arg(wheel())
        .arg(out)
        .output()
        .expect("sh runs")
}

#[test]
fn an_interrupted_write_leaves_the_previous_results_intact() {
    if Command::new("sh")
        .arg("-c")
        .arg("ulimit -f 8")
        .status()
        .is_err()
    {
        return;
    }
    let out = scratch("interrupted").join("out");
    let o = simulate(&wheel(), &out, &SHORT);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = snapshot(&out);
    // The trajectory of 4 s is larger than the limit: writing fails part way.
    let o = simulate_with_file_limit(&out, true);
    let err = one_error_line(&o);
    assert!(err.contains("the previous results in"), "{err}");
    assert!(err.contains("are unchanged"), "{err}");
    assert_eq!(snapshot(&out), before);

    // Killed while writing (SIGXFSZ): the previous results stay, and the next run clears
    // what the killed one left beside them.
    let o = simulate_with_file_limit(&out, false);
    assert!(!o.status.success());
    assert_eq!(snapshot(&out), before);
    let o = simulate(&wheel(), &out, &["t_end=0.5", "compare=[]"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(snapshot(&out), before);
    let siblings: Vec<_> = std::fs::read_dir(out.parent().unwrap()).unwrap().collect();
    assert_eq!(siblings.len(), 1, "{siblings:?}");
}

#[test]
fn sweep_directories_never_collide_and_a_sweep_that_all_fails_exits_non_zero() {
    let dir = scratch("sweep");
    let out = dir.join("out");
    let sweep = |sets: &[&str]| {
        let mut args = vec!["sweep".to_string(), wheel().display().to_string()];
        for s in sets {
            args.extend(["--set".to_string(), s.to_string()]);
        }
        args.extend(["--out".to_string(), out.display().to_string()]);
        Command::new(env!("CARGO_BIN_EXE_dpc"))
            .args(&args)
            .output()
            .unwrap()
    };
    let o = sweep(&["title=a/b,a_b", "t_end=0.5", "compare=[]"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut runs: Vec<String> = std::fs::read_dir(out.join("runs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    runs.sort();
    assert_eq!(runs.len(), 2, "{runs:?}");
    let titles: Vec<String> = runs
        .iter()
        .map(|r| {
            let s = std::fs::read_to_string(out.join("runs").join(r).join("summary.json")).unwrap();
            let v: serde_json::Value = serde_json::from_str(&s).unwrap();
            v["title"].as_str().unwrap().to_string()
        })
        .collect();
    assert!(titles.contains(&"a/b".to_string()) && titles.contains(&"a_b".to_string()));
    let before = snapshot(&out);

    // Every run fails: exit status 1, the first error quoted, the earlier sweep kept.
    let o = sweep(&["h=0.0001,0.0005", "t_end=0.5"]);
    let err = one_error_line(&o);
    assert!(err.contains("all 2 runs of the sweep failed"), "{err}");
    assert!(
        err.contains("must be smaller than the sampling period"),
        "{err}"
    );
    assert!(err.contains("are unchanged"), "{err}");
    assert_eq!(snapshot(&out), before);

    // A rerun with fewer combinations leaves no stale runs/ entry.
    let o = sweep(&["t_end=0.5", "compare=[]"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(out.join("runs")).unwrap().count(), 1);
}

#[test]
fn roots_of_w_far_beyond_the_plant_are_named_when_the_analysis_fails() {
    let dir = scratch("w-scale");
    let path = dir.join("w.toml");
    let paper = std::fs::read_to_string(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../examples/linear/paper-4-1.toml"),
    )
    .unwrap();
    std::fs::write(
        &path,
        paper.replace("w = [[5.0], [5.0]]", "w = [[5.0], [5e7]]"),
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_dpc"))
        .arg("analyze")
        .arg(&path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("W of output 1 (`w[1]`) has a root at -5.000e7"),
        "{err}"
    );
    assert!(err.contains("times the plant's scale"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

#[test]
fn a_system_beyond_max_states_is_refused_before_the_analysis() {
    let dir = scratch("max-states");
    let paper = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/linear/paper-4-1.toml");
    let run = |args: &[&std::ffi::OsStr]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_dpc"))
            .arg("analyze")
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&[paper.as_os_str(), "--max-states".as_ref(), "3".as_ref()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`a` has 5 states, which exceeds --max-states = 3"),
        "{err}"
    );
    // A file longer than any system of that size is not even read.
    let big = dir.join("big.toml");
    std::fs::write(&big, "#".repeat(200_000)).unwrap();
    let out = run(&[big.as_os_str(), "--max-states".as_ref(), "3".as_ref()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("the file has 200000 bytes") && err.contains("--max-states = 3"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

#[test]
fn a_closed_standard_output_is_no_panic() {
    // `dpc model wheel | head -0`: the reader is gone before the listing is written.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(["model", "wheel"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.status.success(), "{err}");
}
