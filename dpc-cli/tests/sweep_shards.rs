//! A sweep split for a batch system (`dpc sweep ... --shard K/N`) and joined again
//! (`dpc sweep merge DIR... --out DIR`) gives the table, the figure and the runs of a single
//! run of the whole sweep; parts that are not the complete parts of one sweep are refused with
//! one line saying why.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dpc-cli-shards-{}", std::process::id()));
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

fn ok(args: &[&str]) {
    let out = dpc(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn error_line(args: &[&str]) -> String {
    let out = dpc(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    err
}

/// `summary.csv` without the wall-clock column, which differs between runs.
fn table(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let wall = header.iter().position(|h| *h == "wall_time_s").unwrap();
    text.lines()
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| *i != wall)
                .map(|(_, f)| f)
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect()
}

#[test]
fn merged_parts_equal_the_whole_sweep() {
    let root = scratch();
    let scenario = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios/wheel.toml")
        .display()
        .to_string();
    let dir = |name: &str| root.join(name).display().to_string();
    // Seven combinations, one of them invalid (delta above h): recorded, not fatal.
    let sweep = |out: &str, shard: Option<&str>| {
        let mut args = vec![
            "sweep",
            scenario.as_str(),
            "--set",
            "delta=0.0005,0.001,0.002,0.2",
            "--set",
            "h=0.05,0.1",
            "--set",
            "t_end=0.5",
            "--set",
            "compare=[]",
            "--out",
            out,
        ];
        if let Some(s) = shard {
            args.extend(["--shard", s]);
        }
        ok(&args);
    };
    sweep(&dir("whole"), None);
    for k in 1..=3 {
        sweep(&dir(&format!("part{k}")), Some(&format!("{k}/3")));
    }
    // Any order of the parts.
    ok(&[
        "sweep",
        "merge",
        &dir("part3"),
        &dir("part1"),
        &dir("part2"),
        "--out",
        &dir("merged"),
    ]);
    let (whole, merged) = (root.join("whole"), root.join("merged"));
    assert_eq!(table(&whole), table(&merged));
    assert_eq!(table(&whole).len(), 1 + 8);
    assert!(table(&merged)
        .iter()
        .any(|row| row.contains("error") && row.contains("delta")));
    for file in ["sweep.svg", "sweep.png", "sweep.json"] {
        assert!(merged.join(file).is_file(), "{file}");
    }
    let runs = |d: &Path| {
        let mut names: Vec<_> = std::fs::read_dir(d.join("runs"))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        names
    };
    assert_eq!(runs(&whole), runs(&merged));
    // Each part ran only its share.
    assert_eq!(table(&root.join("part1")).len(), 1 + 3);

    // What cannot be merged.
    let e = error_line(&[
        "sweep",
        "merge",
        &dir("part1"),
        &dir("part2"),
        "--out",
        &dir("x"),
    ]);
    assert!(e.contains("part 3 of 3 is missing"), "{e}");
    let e = error_line(&[
        "sweep",
        "merge",
        &dir("part1"),
        &dir("part1"),
        &dir("part2"),
        "--out",
        &dir("x"),
    ]);
    assert!(e.contains("part 1 of 3 is given twice"), "{e}");
    let e = error_line(&[
        "sweep",
        "merge",
        &dir("part1"),
        &dir("whole"),
        "--out",
        &dir("x"),
    ]);
    assert!(e.contains("differs"), "{e}");
    let e = error_line(&[
        "sweep",
        "merge",
        &root.display().to_string(),
        "--out",
        &dir("x"),
    ]);
    assert!(e.contains("sweep.json"), "{e}");
    let e = error_line(&[
        "sweep",
        scenario.as_str(),
        "--set",
        "h=0.05",
        "--shard",
        "4/3",
        "--out",
        &dir("x"),
    ]);
    assert!(e.contains("--shard 4/3: expected K/N"), "{e}");
    assert!(!root.join("x").exists());
    let _ = std::fs::remove_dir_all(&root);
}
