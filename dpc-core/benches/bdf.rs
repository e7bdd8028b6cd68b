//! Criterion benchmarks of the BDF integrator on the standard problems of the tests:
//! Robertson (index 1) to `t = 1e11` and the Cartesian pendulum (index 3) to `t = 3`, with the
//! fixed-size nalgebra back end, plus the fixed-step mode on the pendulum (1000 steps of BDF2).
//!
//! Run with `cargo bench -p dpc-core --bench bdf`.

#[path = "../tests/common/bdf_problems.rs"]
mod problems;

use criterion::{criterion_group, criterion_main, Criterion};
use dpc_core::bdf::{Bdf, FixedBdf, Options, Tolerance};
use dpc_core::linear_solver::{FaerDenseLu, NalgebraLu};
use problems::*;
use std::hint::black_box;

fn robertson(c: &mut Criterion) {
    for rtol in [1e-4, 1e-6, 1e-8] {
        c.bench_function(&format!("robertson_1e11_rtol_{rtol:e}"), |b| {
            b.iter(|| {
                let opts = Options {
                    rtol: Tolerance::Scalar(rtol),
                    atol: Tolerance::Vector(robertson_atol(rtol)),
                    ..Options::default()
                };
                let mut bdf = Bdf::new(
                    Robertson,
                    NalgebraLu::<3>::new(),
                    opts,
                    0.0,
                    &[1.0, 0.0, 0.0],
                    &[-0.04, 0.04, 0.0],
                )
                .unwrap();
                bdf.set_stop_time(ROBERTSON_T_END).unwrap();
                let mut y = [0.0; 3];
                bdf.solve_to(ROBERTSON_T_END, &mut y, None).unwrap();
                black_box(y)
            });
        });
    }
    c.bench_function("robertson_1e11_rtol_1e-6_faer_dense", |b| {
        b.iter(|| {
            let rtol = 1e-6;
            let opts = Options {
                rtol: Tolerance::Scalar(rtol),
                atol: Tolerance::Vector(robertson_atol(rtol)),
                ..Options::default()
            };
            let mut bdf = Bdf::new(
                Robertson,
                FaerDenseLu::new(3),
                opts,
                0.0,
                &[1.0, 0.0, 0.0],
                &[-0.04, 0.04, 0.0],
            )
            .unwrap();
            bdf.set_stop_time(ROBERTSON_T_END).unwrap();
            let mut y = [0.0; 3];
            bdf.solve_to(ROBERTSON_T_END, &mut y, None).unwrap();
            black_box(y)
        });
    });
}

fn pendulum(c: &mut Criterion) {
    let p = Pendulum::default();
    let (y0, yp0) = p.initial(1.0);
    for rtol in [1e-4, 1e-6, 1e-8] {
        c.bench_function(&format!("pendulum_3s_rtol_{rtol:e}"), |b| {
            b.iter(|| {
                let opts = Options {
                    index: PENDULUM_INDEX.to_vec(),
                    ..Options::with_tolerances(rtol, rtol)
                };
                let mut bdf = Bdf::new(p, NalgebraLu::<5>::new(), opts, 0.0, &y0, &yp0).unwrap();
                bdf.set_stop_time(3.0).unwrap();
                let mut y = [0.0; 5];
                bdf.solve_to(3.0, &mut y, None).unwrap();
                black_box(y)
            });
        });
    }
    c.bench_function("pendulum_fixed_bdf2_1000_steps", |b| {
        b.iter(|| {
            let opts = Options {
                index: PENDULUM_INDEX.to_vec(),
                ..Options::default()
            };
            let mut f = FixedBdf::new(p, NalgebraLu::<5>::new(), opts, 2, 1e-3, 0.0, &y0).unwrap();
            for _ in 0..1000 {
                f.step().unwrap();
            }
            black_box(f.y()[0])
        });
    });
}

criterion_group!(benches, robertson, pendulum);
criterion_main!(benches);
