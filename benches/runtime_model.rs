//! The cost of a plant file's evaluation against the compiled model of the same text: per
//! call of the residual plus the iteration matrix (what the integrator evaluates per Newton
//! iteration), for the wheel and for a chain of 12 masses. The ratios are quoted in README.md.
//!
//! Run with `cargo bench --bench runtime_model`.

use criterion::{criterion_group, criterion_main, Criterion};
use dpc::core::model::DaeModel;
use dpc::nalgebra::DMatrix;
use std::hint::black_box;

/// Declares the model with `dpc::model!` and keeps the same tokens as the plant file's text.
macro_rules! model_and_text {
    ($text:ident, $($body:tt)*) => {
        dpc::model! { $($body)* }
        const $text: &str = stringify!($($body)*);
    };
}

model_and_text! {
    CHAIN,
    /// A chain of 12 masses joined by springs with angle-dependent damping and quadratic
    /// drag, pulled at its free end by the input `u`; the output is the free end's position.
    pub Chain {
        params { m = 1.0, k = 4.0, c = 0.3, d = 0.05 }
        states { x1, x2, x3, x4, x5, x6, x7, x8, x9, x10, x11, x12, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12 }
        inputs { u }
        equations {
            der(x1) = v1;
            der(x2) = v2;
            der(x3) = v3;
            der(x4) = v4;
            der(x5) = v5;
            der(x6) = v6;
            der(x7) = v7;
            der(x8) = v8;
            der(x9) = v9;
            der(x10) = v10;
            der(x11) = v11;
            der(x12) = v12;
            m * der(v1) == -k * x1 - c * sin(x1) * v1 - d * v1 * abs(v1) + k * (x2 - x1) + c * sin(x2 - x1) * v2;
            m * der(v2) == -k * (x2 - x1) - c * sin((x2 - x1)) * v2 - d * v2 * abs(v2) + k * (x3 - x2) + c * sin(x3 - x2) * v3;
            m * der(v3) == -k * (x3 - x2) - c * sin((x3 - x2)) * v3 - d * v3 * abs(v3) + k * (x4 - x3) + c * sin(x4 - x3) * v4;
            m * der(v4) == -k * (x4 - x3) - c * sin((x4 - x3)) * v4 - d * v4 * abs(v4) + k * (x5 - x4) + c * sin(x5 - x4) * v5;
            m * der(v5) == -k * (x5 - x4) - c * sin((x5 - x4)) * v5 - d * v5 * abs(v5) + k * (x6 - x5) + c * sin(x6 - x5) * v6;
            m * der(v6) == -k * (x6 - x5) - c * sin((x6 - x5)) * v6 - d * v6 * abs(v6) + k * (x7 - x6) + c * sin(x7 - x6) * v7;
            m * der(v7) == -k * (x7 - x6) - c * sin((x7 - x6)) * v7 - d * v7 * abs(v7) + k * (x8 - x7) + c * sin(x8 - x7) * v8;
            m * der(v8) == -k * (x8 - x7) - c * sin((x8 - x7)) * v8 - d * v8 * abs(v8) + k * (x9 - x8) + c * sin(x9 - x8) * v9;
            m * der(v9) == -k * (x9 - x8) - c * sin((x9 - x8)) * v9 - d * v9 * abs(v9) + k * (x10 - x9) + c * sin(x10 - x9) * v10;
            m * der(v10) == -k * (x10 - x9) - c * sin((x10 - x9)) * v10 - d * v10 * abs(v10) + k * (x11 - x10) + c * sin(x11 - x10) * v11;
            m * der(v11) == -k * (x11 - x10) - c * sin((x11 - x10)) * v11 - d * v11 * abs(v11) + k * (x12 - x11) + c * sin(x12 - x11) * v12;
            m * der(v12) == -k * (x12 - x11) - c * sin((x12 - x11)) * v12 - d * v12 * abs(v12) + u;
        }
        outputs { y = x12 }
    }
}

/// The text of the compiled wheel, cut out of its source file.
fn wheel_text() -> String {
    let source = include_str!("../models/src/wheel.rs");
    let start = source.find("dpc::model! {").expect("the wheel's model!") + "dpc::model! {".len();
    let end = source[start..].find("\n}\n").expect("its end") + start;
    source[start..end].to_string()
}

/// Residual plus iteration matrix at a fixed point, for one model.
fn residual_and_iteration<M: DaeModel>(
    model: &M,
    x: &[f64],
    xdot: &[f64],
    u: &[f64],
    r: &mut [f64],
    m: &mut DMatrix<f64>,
) {
    model.residual(0.3, x, xdot, &[], u, r);
    model.iteration_matrix(0.3, x, xdot, &[], u, 20.0, m);
}

fn bench_pair<M: DaeModel>(c: &mut Criterion, name: &str, compiled: &M, text: &str) {
    let runtime = dpc::runtime::parse(name, text)
        .expect("the text reads as a plant file")
        .plant();
    let s = compiled.structure();
    let (nx, nu, ne) = (s.n_states(), s.n_inputs(), s.n_equations());
    let x: Vec<f64> = (0..nx).map(|i| 0.3 + 0.1 * i as f64).collect();
    let xdot: Vec<f64> = (0..nx).map(|i| -0.2 + 0.05 * i as f64).collect();
    let u: Vec<f64> = (0..nu).map(|i| 0.5 - 0.25 * i as f64).collect();
    let mut r = vec![0.0; ne];
    let mut m = DMatrix::<f64>::zeros(ne, ne);
    let mut group = c.benchmark_group(format!("{name}: residual + iteration matrix"));
    group.bench_function("compiled", |b| {
        b.iter(|| residual_and_iteration(black_box(compiled), &x, &xdot, &u, &mut r, &mut m))
    });
    group.bench_function("plant file", |b| {
        b.iter(|| residual_and_iteration(black_box(&runtime), &x, &xdot, &u, &mut r, &mut m))
    });
    group.finish();
}

fn runtime_model(c: &mut Criterion) {
    bench_pair(c, "wheel", &dpc_models::Wheel::default(), &wheel_text());
    bench_pair(c, "chain", &Chain::default(), CHAIN);
}

criterion_group!(benches, runtime_model);
criterion_main!(benches);
