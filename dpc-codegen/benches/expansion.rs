//! Expansion time of `model!` against model size: `dpc_codegen::try_expand` on generated
//! nonlinear chains of 10 to 200 states, each with an output of full relative degree and a
//! tracking section (one Hirschorn step). Before the structural relative degrees, a 16-state
//! chain took 105 s; the table in README.md comes from this benchmark.
//!
//! Run with `cargo bench -p dpc-codegen --bench expansion`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use proc_macro2::TokenStream;
use std::hint::black_box;
use std::time::Duration;

/// `der(x_i) = sin(x_{i+1}) - 0.5 x_i`, `der(x_n) = u - x_n^3`, output `y = x_1` (relative
/// degree `n`) and the tracking DAE with `W(s) = s + 2`.
fn chain(n: usize) -> TokenStream {
    let states: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    let mut equations = String::new();
    for i in 1..n {
        equations += &format!("der(x{i}) = k * x{}.sin() - 0.5 * x{i};\n", i + 1);
    }
    equations += &format!("der(x{n}) = u - x{n}.powi(3);\n");
    format!(
        "Chain {{
            params {{ k = 1.5 }}
            states {{ {} }}
            inputs {{ u }}
            equations {{ {equations} }}
            outputs {{ y = x1 }}
            tracking ChainTracking {{ y: [2.0] }}
        }}",
        states.join(", ")
    )
    .parse()
    .expect("generated model tokenises")
}

fn expansion(c: &mut Criterion) {
    let mut group = c.benchmark_group("expansion");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for n in [10, 20, 50, 100, 200] {
        let tokens = chain(n);
        group.bench_with_input(BenchmarkId::new("chain", n), &tokens, |b, tokens| {
            b.iter(|| dpc_codegen::try_expand(black_box(tokens.clone())).expect("expands"))
        });
    }
    group.finish();
}

criterion_group!(benches, expansion);
criterion_main!(benches);
