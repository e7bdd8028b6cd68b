//! Linear DPC analysis: the paper's 5-state example and random systems of 20, 50 and 100
//! states (normal form with zero dynamics, random orthogonal coordinates).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use dpc_core::linear_analysis::{analyze, AnalysisOptions, LinearSystem, PrefeedbackPolicy};
use nalgebra::DMatrix;

fn rng(seed: &mut u64) -> f64 {
    *seed ^= *seed >> 12;
    *seed ^= *seed << 25;
    *seed ^= *seed >> 27;
    let v = seed.wrapping_mul(0x2545_F491_4F6C_DD1D);
    (v >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// `m` chains of relative degree 2 and `n - 2m` states of stable zero dynamics, rotated.
fn random_system(n: usize, m: usize, seed: u64) -> LinearSystem {
    let mut s = seed | 1;
    let nxi = 2 * m;
    let mut a = DMatrix::zeros(n, n);
    let mut b = DMatrix::zeros(n, m);
    let mut c = DMatrix::zeros(m, n);
    for i in 0..m {
        a[(2 * i, 2 * i + 1)] = 1.0;
        for j in 0..n {
            a[(2 * i + 1, j)] = rng(&mut s);
        }
        b[(2 * i + 1, i)] = 1.0 + 0.5 * rng(&mut s);
        c[(i, 2 * i)] = 1.0;
    }
    for i in nxi..n {
        a[(i, i)] = -1.0 - (i - nxi) as f64 * 0.1;
        for j in 0..nxi {
            a[(i, j)] = 0.3 * rng(&mut s);
        }
    }
    let t = DMatrix::from_fn(n, n, |_, _| rng(&mut s)).qr().q();
    LinearSystem::without_feedthrough(t.transpose() * &a * &t, t.transpose() * &b, c * &t)
        .expect("well-formed")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("analyze");
    let opts = AnalysisOptions {
        prefeedback: PrefeedbackPolicy::Always,
        ..Default::default()
    };
    for n in [20usize, 50, 100] {
        let sys = random_system(n, 4, 42 + n as u64);
        group.bench_with_input(BenchmarkId::from_parameter(n), &sys, |bch, sys| {
            bch.iter(|| analyze(sys, &opts).expect("analysis"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
