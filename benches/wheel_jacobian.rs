//! Residual + all Jacobians of the wheel: the generated analytic code against central
//! finite differences on the same generated residual. The ratio is quoted in README.md.
//!
//! Run with `cargo bench --bench wheel_jacobian`.

use criterion::{criterion_group, criterion_main, Criterion};
use dpc::core::model::DaeModel;
use dpc::nalgebra::{SMatrix, SVector};
use dpc_models::Wheel;
use std::hint::black_box;

const NX: usize = 5;
const NU: usize = 2;

fn point() -> ([f64; NX], [f64; NX], [f64; NU]) {
    (
        [1.4, -0.3, 0.2, 0.1, -6.0],
        [0.1, -6.0, 0.3, -0.2, 0.05],
        [0.5, -0.25],
    )
}

/// Central differences of the residual in x', x and u, with the residual itself.
fn finite_differences(
    wheel: &Wheel,
    x: &[f64; NX],
    xdot: &[f64; NX],
    u: &[f64; NU],
) -> (
    SVector<f64, NX>,
    [SMatrix<f64, NX, NX>; 2],
    SMatrix<f64, NX, NU>,
) {
    let mut r = SVector::<f64, NX>::zeros();
    wheel.residual(0.0, x, xdot, &[], u, r.as_mut_slice());
    let mut blocks = [SMatrix::<f64, NX, NX>::zeros(); 2];
    let mut f_u = SMatrix::<f64, NX, NU>::zeros();
    let (mut plus, mut minus) = ([0.0; NX], [0.0; NX]);
    for (b, block) in blocks.iter_mut().enumerate() {
        for j in 0..NX {
            let (mut xp, mut xm, mut dp, mut dm) = (*x, *x, *xdot, *xdot);
            let v = if b == 0 { xdot[j] } else { x[j] };
            let h = 1e-6 * (1.0 + v.abs());
            if b == 0 {
                dp[j] += h;
                dm[j] -= h;
            } else {
                xp[j] += h;
                xm[j] -= h;
            }
            wheel.residual(0.0, &xp, &dp, &[], u, &mut plus);
            wheel.residual(0.0, &xm, &dm, &[], u, &mut minus);
            for i in 0..NX {
                block[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
            }
        }
    }
    for j in 0..NU {
        let (mut up, mut um) = (*u, *u);
        let h = 1e-6 * (1.0 + u[j].abs());
        up[j] += h;
        um[j] -= h;
        wheel.residual(0.0, x, xdot, &[], &up, &mut plus);
        wheel.residual(0.0, x, xdot, &[], &um, &mut minus);
        for i in 0..NX {
            f_u[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    (r, blocks, f_u)
}

fn bench(c: &mut Criterion) {
    let wheel = Wheel::default();
    let (x, xdot, u) = point();
    let mut group = c.benchmark_group("wheel residual + Jacobians");
    group.bench_function("generated analytic", |b| {
        b.iter(|| {
            wheel.jacobians_fixed(
                black_box(0.0),
                &black_box(x).into(),
                &black_box(xdot).into(),
                &SVector::<f64, 0>::zeros(),
                &black_box(u).into(),
            )
        })
    });
    group.bench_function("central differences", |b| {
        b.iter(|| finite_differences(&wheel, &black_box(x), &black_box(xdot), &black_box(u)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
