//! The user-crate entry point, proved from outside the workspace: `tests/user-crate` declares
//! a plant the repository does not have (a quadruple tank with algebraic outflows) with
//! `dpc::model!`, hands it to `dpc::cli::main` in a few lines, and gets `dpc simulate` and
//! `dpc model` for it.
//!
//! Building that crate takes a minute or two even with the workspace's target directory (the
//! dpc crates are compiled again as dependencies of a crate outside the workspace), so the test
//! is ignored by default:
//!
//!     cargo test -p dpc-cli --test user_crate -- --ignored

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The target directory this test was built in (`<target>/<profile>/deps/<test>`), shared
/// with the user crate so that third-party dependencies are not compiled again.
fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    exe.ancestors()
        .nth(3)
        .expect("the test executable lies in <target>/<profile>/deps")
        .to_path_buf()
}

/// `cargo run --profile test --manifest-path tests/user-crate/Cargo.toml -- ARGS`.
fn user_cli(args: &[&str]) -> Output {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    Command::new(cargo)
        .args(["run", "--quiet", "--profile", "test", "--manifest-path"])
        .arg(repository().join("tests/user-crate/Cargo.toml"))
        .env("CARGO_TARGET_DIR", target_dir())
        .arg("--")
        .args(args)
        .output()
        .expect("cargo runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn assert_nonempty(path: &Path) {
    let len = std::fs::metadata(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .len();
    assert!(len > 100, "{} has {len} bytes", path.display());
}

#[test]
#[ignore = "builds a crate outside the workspace (a minute or two): cargo test -p dpc-cli --test user_crate -- --ignored"]
fn a_user_crate_gets_the_whole_command_line_for_its_own_plant() {
    let out = std::env::temp_dir().join(format!("dpc-user-crate-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let scenario = repository().join("tests/user-crate/scenarios/tanks.toml");
    let o = user_cli(&[
        "simulate",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("scenario: no divergence"),
        "{}",
        text(&o.stdout)
    );
    for file in [
        "summary.json",
        "trajectory.csv",
        "closed-loop.svg",
        "closed-loop.png",
    ] {
        assert_nonempty(&out.join(file));
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["model"], "tanks");
    assert_eq!(summary["samples"], 61);
    // Levels 1 cm off at the start; within 1e-2 cm of the references over the last quarter.
    for output in ["h1", "h2"] {
        let e = summary["max_abs_error"][output].as_f64().unwrap();
        assert!(e < 1e-2, "{output}: {e}");
    }
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        "t [s],h1,h2,h3,h4,v1,v2,ref_h1,ref_h2,err_h1,err_h2"
    );
    let _ = std::fs::remove_dir_all(&out);

    let o = user_cli(&["models"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).starts_with("tanks "), "{}", text(&o.stdout));

    let o = user_cli(&["model", "tanks"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let listing = text(&o.stdout);
    assert!(listing.contains("algebraic  q1, q2, q3, q4"), "{listing}");
    assert!(
        listing.contains("output h1: relative degree 1"),
        "{listing}"
    );

    // Scenario errors name the user's model as they do the repository's.
    let o = user_cli(&[
        "simulate",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "x0=[1.0]",
    ]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("`x0` has 1 entries, but model `tanks` has 4 (h1, h2, h3, h4)"),
        "{err}"
    );
}
