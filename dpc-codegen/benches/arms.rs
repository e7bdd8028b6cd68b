//! Expansion of the planar n-link flexible-joint arm of `models/src/arm.rs` for growing `n`
//! and numbers of stabilised Hirschorn steps per joint: the time of the macro's passes
//! (`dpc_codegen::try_expand`: parse, lower, relative degrees, the tracking rows, derive and
//! emit), and the generated code's size in lines (formatted with prettyplease). The arm is
//! the repository's own declaration (`models/src/arm_declaration.rs`) with `n` links, so the
//! numbers are those of the models users compile. Prints the table of `docs/arms.md`.
//!
//! Run with `cargo bench -p dpc-codegen --bench arms` (`-- 16` for a different largest `n`).

use proc_macro2::TokenStream;
use std::time::{Duration, Instant};

#[path = "../../tests/common/model_text.rs"]
mod model_text;

/// The arm's declaration (`models/src/arm_declaration.rs`, the one `models/src/arm.rs`
/// instantiates) as text.
fn arm_template() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/src/arm_declaration.rs"
    );
    std::fs::read_to_string(path).expect("models/src/arm_declaration.rs")
}

/// The arm with `n` links, instantiated from the declaration as `models/src/arm.rs` does,
/// with `steps` roots `4.0` in `W` per joint (the declaration has two).
fn arm(template: &str, n: usize, steps: usize) -> TokenStream {
    let call = format!("flexible_joint_arm!(\"The arm.\", Arm{n}, Arm{n}Tracking, {n});");
    let [model] = &model_text::template_models(&call, template)[..] else {
        panic!("one model in the declaration");
    };
    let roots = vec!["4.0"; steps].join(", ");
    let text = model.replace("[4.0, 4.0]", &format!("[{roots}]"));
    assert!(
        text.contains(&format!("N = {n}")) && text.contains(&format!("[{roots}]")),
        "the template changed: {text}"
    );
    text.parse().expect("arm tokenises")
}

/// Median of the times of `f` over at least 3 runs and about a second.
fn median(mut f: impl FnMut()) -> Duration {
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 3 || (start.elapsed() < Duration::from_secs(1) && times.len() < 50) {
        let t = Instant::now();
        f();
        times.push(t.elapsed());
    }
    times.sort();
    times[times.len() / 2]
}

fn main() {
    let largest: usize = std::env::args()
        .filter_map(|a| a.parse().ok())
        .next()
        .unwrap_or(16);
    let template = arm_template();
    println!("| links n | steps per joint | expansion | generated lines | result |");
    println!("| --- | --- | --- | --- | --- |");
    for n in [1, 2, 4, 6, 8, 12, 16, 24, 32]
        .into_iter()
        .filter(|&n| n <= largest)
    {
        for steps in [2, 3, 4] {
            let tokens = arm(&template, n, steps);
            match dpc_codegen::try_expand(tokens.clone()) {
                Ok(out) => {
                    let time = median(|| {
                        std::hint::black_box(
                            dpc_codegen::try_expand(tokens.clone()).expect("expands"),
                        );
                    });
                    let file: syn::File = syn::parse2(out).expect("generated code parses");
                    let lines = prettyplease::unparse(&file).lines().count();
                    println!("| {n} | {steps} | {time:.2?} | {lines} | expands |");
                }
                Err(e) => {
                    let message = e.to_string();
                    let short: String = message.chars().take(90).collect();
                    println!("| {n} | {steps} | - | - | refused: {short}... |");
                }
            }
        }
    }
}
