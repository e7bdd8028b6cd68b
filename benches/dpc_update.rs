//! One DPC control update for the paper's wheel (tracking DAE with `W = s + 5` on both
//! outputs, `delta = 1e-3`, fixed-size LU), without and with the paper's preliminary
//! feedback: the cost of the controller per sample.
//!
//! Run with `cargo bench --bench dpc_update`.

use criterion::{criterion_group, criterion_main, Criterion};
use dpc::core::dpc::{Dpc, DpcOptions, Extraction};
use dpc::core::linalg::NalgebraLu;
use dpc_models::wheel_design;
use dpc_models::{Wheel, WheelReference, WheelTracking};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("wheel DPC update");
    let cases = [false, true]
        .into_iter()
        .flat_map(|pf| [Extraction::FirstUsable, Extraction::Extrapolated].map(move |e| (pf, e)));
    for (with_prefeedback, extraction) in cases {
        let mut dpc = Dpc::new(
            WheelTracking::default(),
            WheelReference::default(),
            NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new(),
            DpcOptions {
                extraction,
                ..DpcOptions::default()
            },
        )
        .expect("controller");
        if with_prefeedback {
            let law = wheel_design::prefeedback(&Wheel::default()).expect("design");
            dpc = dpc.with_prefeedback(law).expect("prefeedback");
        }
        let x = [std::f64::consts::FRAC_PI_2 + 0.01, -0.3, 0.0, 0.0, -6.0];
        let mut u = [0.0; 2];
        dpc.control(0.05, &x, &mut u).expect("warm-up update");
        let name = if with_prefeedback {
            format!("{extraction:?} with preliminary feedback")
        } else {
            format!("{extraction:?}")
        };
        group.bench_function(name, |b| {
            b.iter(|| dpc.control(black_box(0.05), black_box(&x), &mut u))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
