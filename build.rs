//! Prepares README.md and the pages of docs/ for rustdoc: the facade's front page is the
//! README and `dpc::guide` holds the pages, so every Rust snippet in them is a doctest of this
//! crate. Links are written for a reader of the repository (`docs/dsl.md`,
//! `scenarios/wheel.toml`); on the generated docs they become intra-doc links to the guide's
//! modules, and links to other files of the repository, which the docs do not contain, become
//! plain names in code format. Figures are referred to by their file.
//!
//! With the feature `casadi-peer` (never on in CI or `cargo test`), it also compiles CasADi's
//! generated C for the wheel (written by `bench/casadi/run.sh`, or found in the directory
//! `DPC_CASADI_DIR`) with `-O2` into the benchmark `benches/casadi_peer.rs`.

use std::path::Path;

/// The page of docs/ that is the documentation of `dpc::model!` itself.
const MACRO_PAGE: &str = "dsl";

/// The guide's pages: file stem in docs/ and module name in `dpc::guide`.
const PAGES: &[(&str, &str)] = &[
    ("tracking", "tracking"),
    ("controller", "controller"),
    ("closed-loop", "closed_loop"),
    ("own-plant", "own_plant"),
    ("plant-files", "plant_files"),
    ("constrained-plants", "constrained_plants"),
    ("linear-analysis", "linear_analysis"),
    ("sampling-period", "sampling_period"),
    ("integrators", "integrators"),
    ("bdf", "bdf"),
    ("jacobians", "jacobians"),
    ("performance", "performance"),
    ("arms", "arms"),
];

fn module_of(stem: &str) -> Option<&'static str> {
    PAGES.iter().find(|(s, _)| *s == stem).map(|(_, m)| *m)
}

/// The link target as rustdoc should see it, or `None` when the link is to be replaced by
/// its text. `dir` is the directory of the page the link is in, relative to the root.
fn rewrite_target(target: &str, dir: &str) -> Option<String> {
    if target.starts_with("http://") || target.starts_with("https://") || target.starts_with('#') {
        return Some(target.to_string());
    }
    let (path, anchor) = match target.split_once('#') {
        Some((p, a)) => (p, format!("#{a}")),
        None => (target, String::new()),
    };
    let resolved = normalise(&format!("{dir}{path}"));
    if resolved == "README.md" {
        return Some(format!("crate{anchor}"));
    }
    let stem = resolved.strip_prefix("docs/")?.strip_suffix(".md")?;
    if stem == MACRO_PAGE {
        return Some(format!("macro@crate::model{anchor}"));
    }
    module_of(stem).map(|m| format!("crate::guide::{m}{anchor}"))
}

/// `docs/../scenarios/x` -> `scenarios/x`.
fn normalise(path: &str) -> String {
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split('/') {
        match part {
            ".." => {
                parts.pop();
            }
            "." | "" => {}
            p => parts.push(p),
        }
    }
    parts.join("/")
}

/// Rewrite the markdown links and images of `text` (outside code blocks).
fn rewrite(text: &str, dir: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        }
        if in_code {
            out.push_str(line);
        } else {
            out.push_str(&escape_brackets(&rewrite_line(line, dir)));
        }
        out.push('\n');
    }
    out
}

/// Brackets that open no link (`t [s]`, `[is]` in a quotation) escaped outside code spans, so
/// that rustdoc does not take them for intra-doc links.
fn escape_brackets(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut in_code = false;
    let chars: Vec<char> = line.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        match c {
            '`' => {
                in_code = !in_code;
                out.push(c);
            }
            '[' if !in_code && !opens_link(&chars[i..]) => out.push_str("\\["),
            ']' if !in_code && !closes_link(&chars[i + 1..]) => out.push_str("\\]"),
            _ => out.push(c),
        }
    }
    out
}

/// Whether the `[` at the start of `rest` opens `[label](target)` (or an image).
fn opens_link(rest: &[char]) -> bool {
    let mut depth = 0;
    for (i, &c) in rest.iter().enumerate() {
        match c {
            '[' => depth += 1,
            ']' => {
                depth -= 1;
                if depth == 0 {
                    return rest.get(i + 1) == Some(&'(');
                }
            }
            _ => {}
        }
    }
    false
}

/// Whether a `]` followed by `after` closes a link label (it is followed by `(`).
fn closes_link(after: &[char]) -> bool {
    after.first() == Some(&'(')
}

fn rewrite_line(line: &str, dir: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(open) = rest.find('[') {
        let image = open > 0 && rest.as_bytes()[open - 1] == b'!';
        let Some(close) = rest[open..].find("](").map(|i| open + i) else {
            break;
        };
        let Some(end) = rest[close..].find(')').map(|i| close + i) else {
            break;
        };
        let label = &rest[open + 1..close];
        let target = &rest[close + 2..end];
        if label.contains('[') || target.contains(' ') {
            out.push_str(&rest[..open + 1]);
            rest = &rest[open + 1..];
            continue;
        }
        let before = if image {
            &rest[..open - 1]
        } else {
            &rest[..open]
        };
        out.push_str(before);
        if image {
            out.push_str(&format!(
                "*Figure: {label} (`{}` in the repository).*",
                normalise(&format!("{dir}{target}"))
            ));
        } else {
            match rewrite_target(target, dir) {
                Some(t) => out.push_str(&format!("[{label}]({t})")),
                None if label.starts_with('`') => out.push_str(label),
                None => out.push_str(&format!(
                    "{label} (`{}`)",
                    normalise(&format!("{dir}{target}"))
                )),
            }
        }
        rest = &rest[end + 1..];
    }
    out.push_str(rest);
    out
}

fn main() {
    guide_pages();
    #[cfg(feature = "casadi-peer")]
    casadi_peer();
}

#[cfg(feature = "casadi-peer")]
fn casadi_peer() {
    use std::path::PathBuf;
    println!("cargo:rerun-if-env-changed=DPC_CASADI_DIR");
    let dir = match std::env::var_os("DPC_CASADI_DIR") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"))
            .join("bench/casadi/generated"),
    };
    let source = dir.join("wheel_casadi.c");
    println!("cargo:rerun-if-changed={}", source.display());
    if !source.is_file() {
        panic!(
            "feature `casadi-peer`: {} does not exist; generate it with `bash bench/casadi/run.sh` \
             (or point DPC_CASADI_DIR at a directory holding wheel_casadi.c)",
            source.display()
        );
    }
    cc::Build::new()
        .file(&source)
        .opt_level(2)
        .warnings(false)
        .compile("wheel_casadi");
}

/// README.md and the guide's pages, rewritten for rustdoc into `OUT_DIR`.
fn guide_pages() {
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let out = Path::new(&out);
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-changed=README.md");
    let readme = std::fs::read_to_string("README.md").expect("README.md is readable");
    std::fs::write(out.join("README.md"), rewrite(&readme, "")).expect("OUT_DIR is writable");
    let path = format!("docs/{MACRO_PAGE}.md");
    println!("cargo::rerun-if-changed={path}");
    let text = std::fs::read_to_string(&path).expect("the DSL page exists");
    std::fs::write(out.join("model.md"), rewrite(&text, "docs/")).expect("OUT_DIR is writable");
    for (stem, module) in PAGES {
        let path = format!("docs/{stem}.md");
        println!("cargo::rerun-if-changed={path}");
        let text = std::fs::read_to_string(&path).expect("every page of the guide exists");
        std::fs::write(out.join(format!("{module}.md")), rewrite(&text, "docs/"))
            .expect("OUT_DIR is writable");
    }
}
