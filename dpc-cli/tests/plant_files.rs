//! Plant files through the command line: `dpc model FILE.dpc` for good and bad files, a
//! scenario naming a plant file (`model = "wheel.dpc"`), and the closed loop of the wheel
//! scenario on the plant file against the compiled wheel.

use std::path::PathBuf;
use std::process::{Command, Output};

use dpc::cli::registry::{Entry, Registry};
use dpc::cli::scenario::{Overrides, Scenario};
use dpc_models::{Wheel, WheelReference, WheelTracking};

fn scenarios() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenarios")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("dpc-cli-plant-files-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn dpc(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(args)
        .output()
        .expect("dpc runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn dpc_model_prints_a_plant_files_listing_degrees_and_diagnostics() {
    let file = scenarios().join("wheel.dpc");
    let out = dpc(&["model".as_ref(), file.as_os_str()]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        stdout.contains("tracking WheelTracking: the equations above"),
        "{stdout}"
    );
    assert!(
        stdout.contains("  output theta: relative degree 3, deg W = 1"),
        "{stdout}"
    );
    assert!(stdout.contains("nu = 2 unusable inner steps"), "{stdout}");
    assert!(
        stdout.contains("reference: the model's own (2 components"),
        "{stdout}"
    );
    assert!(
        stdout.contains("diagnostics:\n  output theta: relative degree 3, confirmed symbolically"),
        "{stdout}"
    );
}

#[test]
fn dpc_model_on_a_file_without_tracking_says_so() {
    let dir = temp_dir("no-tracking");
    let file = dir.join("free.dpc");
    std::fs::write(
        &file,
        "Free { states { x } inputs { u } equations { der(x) = u; } outputs { x } }",
    )
    .unwrap();
    let out = dpc(&["model".as_ref(), file.as_os_str()]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("no tracking section"), "{stdout}");
    assert!(stdout.contains("output x: relative degree 1"), "{stdout}");
}

#[test]
fn bad_plant_files_give_every_error_as_file_line_column_and_exit_1() {
    let dir = temp_dir("bad");
    let cases: &[(&str, &[u8], &[&str])] = &[
        (
            "names.dpc",
            b"Plant {\n  params { k = 1.0, k = 2.0 }\n  states { x }\n  equations {\n    der(x) = -k * y + foo(x);\n  }\n}\n",
            &[
                ":2:21: duplicate name `k`",
                ":2:12: `k` first declared here",
                ":5:19: unknown identifier `y`",
                ":5:23: unknown function `foo`",
            ],
        ),
        ("empty.dpc", b"", &[":1:1: expected the model's name"]),
        ("overflow.dpc", b"P {\n  states { x }\n  equations { der(x) = 1e999 * x; }\n}\n", &[":3:24: "]),
        (
            "tracking.dpc",
            b"P {\n  states { x }\n  inputs { u }\n  equations { der(x) = u; }\n  outputs { x }\n  tracking T { x: [1.0, 2.0] }\n}\n",
            &[":6:"],
        ),
        ("binary.dpc", b"P { states { x\xff } }", &[":1:15: the file is not UTF-8 text"]),
    ];
    for (name, contents, want) in cases {
        let file = dir.join(name);
        std::fs::write(&file, contents).unwrap();
        let out = dpc(&["model".as_ref(), file.as_os_str()]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(out.stdout.is_empty(), "{name}");
        let lines: Vec<&str> = stderr.lines().collect();
        assert_eq!(lines.len(), want.len(), "{name}: {stderr}");
        for (line, w) in lines.iter().zip(*want) {
            let prefix = format!("{}{w}", file.display());
            assert!(
                line.starts_with(&prefix),
                "{name}: `{line}` should start with `{prefix}`"
            );
        }
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
    let missing = dir.join("missing.dpc");
    let out = dpc(&["model".as_ref(), missing.as_os_str()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with(&format!("{}: cannot read: ", missing.display())),
        "{stderr}"
    );
}

#[test]
fn a_scenario_runs_on_a_plant_file_relative_to_it() {
    let dir = temp_dir("scenario");
    let out_dir = dir.join("out");
    let out = dpc(&[
        "simulate".as_ref(),
        scenarios().join("wheel-file.toml").as_os_str(),
        "--out".as_ref(),
        out_dir.as_os_str(),
        "--set".as_ref(),
        "t_end=1".as_ref(),
        "--set".as_ref(),
        "compare=[]".as_ref(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let summary = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    assert!(summary.contains("\"wheel.dpc\""), "{summary}");

    // A scenario naming a bad plant file, or one without tracking, is one clear error.
    std::fs::write(
        dir.join("bad.dpc"),
        "P { states { x } equations { der(x) = y; } }",
    )
    .unwrap();
    std::fs::write(
        dir.join("free.dpc"),
        "P { states { x } inputs { u } equations { der(x) = u; } outputs { x } }",
    )
    .unwrap();
    let scenario = |model: &str| {
        let path = dir.join(format!("{model}.toml"));
        std::fs::write(
            &path,
            format!("model = \"{model}\"\nx0 = [0.0]\nh = 0.1\nt_end = 1.0\n[reference]\nx = [{{ constant = 0.0 }}]\n"),
        )
        .unwrap();
        path
    };
    for (model, want) in [
        (
            "bad.dpc",
            format!(
                "{}:1:39: unknown identifier `y`",
                dir.join("bad.dpc").display()
            ),
        ),
        (
            "free.dpc",
            format!(
                "error: {}: the plant file has no `tracking` section",
                dir.join("free.dpc").display()
            ),
        ),
        (
            "missing.dpc",
            format!("{}: cannot read: ", dir.join("missing.dpc").display()),
        ),
    ] {
        let out = dpc(&[
            "simulate".as_ref(),
            scenario(model).as_os_str(),
            "--out".as_ref(),
            out_dir.as_os_str(),
        ]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{model}: {stderr}");
        assert!(
            stderr.starts_with(&want),
            "{model}: `{stderr}` should start with `{want}`"
        );
        if model == "bad.dpc" {
            // The file's lines, then what became of the output directory.
            let lines: Vec<&str> = stderr.lines().collect();
            assert_eq!(lines.len(), 2, "{stderr}");
            assert!(lines[1].starts_with("error: "), "{stderr}");
            assert!(
                lines[1].contains(&out_dir.display().to_string()),
                "{stderr}"
            );
        }
    }
}

/// A plant that exists only as a plant file tracks its reference: the late error stays an
/// order of magnitude below the reference's amplitude (0.2).
#[test]
fn the_tanks_scenario_tracks_on_a_plant_of_its_own() {
    let registry = Registry::new();
    let scenario = Scenario::load(
        &scenarios().join("tanks.toml"),
        &Overrides::parse(["t_end=10"]).unwrap(),
    )
    .unwrap();
    let run = registry.run(&scenario, "tanks").unwrap();
    let closed = &run.closed_loop;
    assert!(closed.divergence.is_none(), "{:?}", closed.divergence);
    assert!(closed.samples.last().unwrap().t >= 10.0 - scenario.h);
    let late = closed.max_abs_error_since(7.5);
    assert!(late[0] < 0.02, "late error {late:?}");
}

/// The closed loop of the wheel scenario on the plant file and on the compiled wheel agree to
/// the integrator's tolerance over the whole run.
#[test]
fn the_wheel_closed_loop_agrees_with_the_compiled_wheel() {
    let registry = Registry::new().model(
        Entry::new(
            "wheel",
            "the compiled wheel",
            Wheel::default(),
            WheelTracking::default(),
        )
        .reference(WheelReference::default()),
    );
    let none = Overrides::default();
    let compiled = Scenario::load(&scenarios().join("wheel.toml"), &none).unwrap();
    let from_file = Scenario::load(&scenarios().join("wheel-file.toml"), &none).unwrap();
    assert_eq!(from_file.model, "wheel.dpc");
    // The two scenario files differ only in their model and title.
    let mut same = from_file.clone();
    same.model = compiled.model.clone();
    same.title = compiled.title.clone();
    same.source = compiled.source.clone();
    assert_eq!(same, compiled);

    let a = registry.run(&compiled, "compiled").unwrap();
    let b = registry.run(&from_file, "file").unwrap();
    let (a, b) = (&a.closed_loop, &b.closed_loop);
    assert!(a.divergence.is_none() && b.divergence.is_none());
    assert_eq!(a.samples.len(), b.samples.len());
    assert!(a.samples.last().unwrap().t >= compiled.t_end - compiled.h);
    let (rtol, atol) = (compiled.plant.rtol, compiled.plant.atol);
    let mut worst = 0.0_f64;
    for (sa, sb) in a.samples.iter().zip(&b.samples) {
        assert_eq!(sa.t, sb.t);
        for (va, vb) in sa.x.iter().chain(&sa.u).zip(sb.x.iter().chain(&sb.u)) {
            let bound = rtol * va.abs().max(vb.abs()) + atol;
            worst = worst.max((va - vb).abs() / bound);
        }
    }
    assert!(
        worst <= 1.0,
        "states and inputs differ by {worst} times the integrator tolerance"
    );
}
