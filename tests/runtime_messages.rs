//! A plant file gives the macro's messages at the macro's positions: every malformed model of
//! `tests/ui/` (the trybuild cases, whose `.stderr` files hold what `rustc` reports for the
//! macro) is read as a plant file, in place (the file with everything outside the braces of
//! `model! { ... }` blanked, so lines and columns are the file's), and the run-time errors
//! must be exactly the `error:` lines of the `.stderr`, with their `-->` positions.

mod common;

use common::model_text::invocations;
use std::path::Path;

/// `(line, column, message)` of every `error:` in a trybuild `.stderr`.
fn expected(stderr: &str) -> Vec<(usize, usize, String)> {
    let mut out = Vec::new();
    let mut lines = stderr.lines();
    while let Some(line) = lines.next() {
        let Some(message) = line.strip_prefix("error: ") else {
            continue;
        };
        // The message may continue on following lines until the ` --> ` line.
        let mut message = message.to_string();
        for next in lines.by_ref() {
            if let Some(at) = next.trim_start().strip_prefix("--> ") {
                let mut parts = at.rsplitn(3, ':');
                let column = parts.next().unwrap().parse().unwrap();
                let line = parts.next().unwrap().parse().unwrap();
                out.push((line, column, message.clone()));
                break;
            }
            message.push('\n');
            message.push_str(next);
        }
    }
    out
}

#[test]
fn every_malformed_model_gives_the_macros_messages_at_its_positions() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui");
    let mut cases: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    cases.sort();
    assert!(cases.len() >= 40, "found {} cases", cases.len());
    let mut failures = Vec::new();
    let mut compared = 0;
    for case in &cases {
        let source = std::fs::read_to_string(case).unwrap();
        let stderr = std::fs::read_to_string(case.with_extension("stderr")).unwrap();
        let want = expected(&stderr);
        let models = invocations(&source);
        assert_eq!(models.len(), 1, "{}: one model! per case", case.display());
        let name = case.file_name().unwrap().to_string_lossy().to_string();
        let got = match dpc::runtime::parse(&name, &models[0].in_place) {
            Ok(_) => Vec::new(),
            Err(dpc::runtime::PlantFileError::Invalid { diagnostics, .. }) => diagnostics
                .into_iter()
                .map(|d| (d.line, d.column, d.message))
                .collect(),
            Err(other) => panic!("{name}: {other}"),
        };
        compared += want.len();
        if got != want {
            failures.push(format!("{name}:\n  macro:   {want:?}\n  runtime: {got:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(compared >= cases.len(), "only {compared} messages compared");
}
