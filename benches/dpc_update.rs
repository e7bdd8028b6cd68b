//! One DPC control update for the paper's wheel (tracking DAE with `W = s + 5` on both
//! outputs, `delta = 1e-3`, fixed-size LU): the cost of the controller per sample.
//!
//! Two workloads:
//!
//! * **warm start**: the same state at every call, without and with the paper's preliminary
//!   feedback. Every update after the first starts from its own solution, so this is the
//!   floor of an update, not what a closed loop sees.
//! * **closed-loop replay**: the measured states of the wheel scenario's own closed loop
//!   (`scenarios/wheel.toml`: preliminary feedback about the nominal motion, input held,
//!   `h = 0.05` s, 20 s), recorded once and replayed in order, so each update starts from the
//!   previous sample's solution as in the loop. The figure README quotes.
//!
//! Before criterion runs, the replay prints what an update does on average (Newton
//! iterations, iteration matrices) and the floor of its parts: iterations x
//! (fused residual and iteration matrix + 7x7 LU), with those parts timed on the replay's
//! own points.
//!
//! Run with `cargo bench --bench dpc_update`.

#[path = "../tests/common/wheel_loop.rs"]
mod wheel_loop;

use criterion::{criterion_group, Criterion};
use dpc::core::controller::{Dpc, DpcOptions, Extraction};
use dpc::core::linear_solver::{LinearSolver, NalgebraLu};
use dpc::core::model::DaeModel;
use dpc::core::simulate::Hold;
use dpc_models::wheel_design;
use dpc_models::{Wheel, WheelReference, WheelTracking};
use std::hint::black_box;
use std::time::Instant;

type Controller = Dpc<WheelTracking, WheelReference, NalgebraLu<{ WheelTracking::N_EQUATIONS }>>;

fn controller(with_prefeedback: bool, extraction: Extraction) -> Controller {
    let dpc = Dpc::new(
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
        dpc.with_prefeedback(law).expect("prefeedback")
    } else {
        dpc
    }
}

/// `(t, x)` at every sample of the wheel scenario's closed loop.
fn recorded_states(h: f64) -> Vec<(f64, [f64; 5])> {
    let run = wheel_loop::run(
        h,
        20.0,
        Some(wheel_loop::About::Nominal),
        Extraction::Extrapolated,
        Hold::Input,
    );
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    run.samples
        .iter()
        .map(|s| {
            let mut x = [0.0; 5];
            x.copy_from_slice(&s.x);
            (s.t, x)
        })
        .collect()
}

/// The replay's averages and the floor of its parts, printed before criterion runs.
fn replay_summary(states: &[(f64, [f64; 5])]) {
    let mut dpc = controller(true, Extraction::Extrapolated);
    let mut u = [0.0; 2];
    let (mut iterations, mut matrices) = (0, 0);
    let rounds = 20;
    let mut per_update = Vec::new();
    for _ in 0..rounds {
        dpc.reset();
        let start = Instant::now();
        for (t, x) in states {
            let r = dpc.control(*t, x, &mut u).expect("replayed update");
            iterations += r.newton_iterations;
            matrices += r.iteration_matrices;
        }
        per_update.push(start.elapsed().as_secs_f64() * 1e6 / states.len() as f64);
    }
    per_update.sort_by(f64::total_cmp);
    let n = (rounds * states.len()) as f64;
    let (it, mats) = (iterations as f64 / n, matrices as f64 / n);
    // The parts, on the points the replay visits (states with their zero-order derivatives
    // and the controls the updates return).
    let model = WheelTracking::default();
    let mut points = Vec::new();
    let mut probe = controller(true, Extraction::Extrapolated);
    for (t, x) in states {
        probe.control(*t, x, &mut u).expect("update");
        points.push((*x, u));
    }
    let mut lu = NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new();
    let mut res = [0.0; 7];
    let c = 1.0 / DpcOptions::default().delta;
    let w = [1.0, -6.0];
    let mut fused_ns = Vec::new();
    let mut factor_ns = Vec::new();
    for _ in 0..200 {
        let start = Instant::now();
        for (x, u) in &points {
            model.residual_and_iteration_matrix(
                0.0,
                black_box(x),
                &[0.0; 5],
                u,
                &w,
                c,
                &mut res,
                lu.matrix_mut(),
            );
        }
        fused_ns.push(start.elapsed().as_secs_f64() * 1e9 / points.len() as f64);
        let start = Instant::now();
        for _ in &points {
            black_box(&mut lu).factor().expect("regular");
        }
        factor_ns.push(start.elapsed().as_secs_f64() * 1e9 / points.len() as f64);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (fused, factor) = (median(&mut fused_ns), median(&mut factor_ns));
    let floor = it * (fused + factor) / 1e3;
    let update = per_update[per_update.len() / 2];
    println!(
        "closed-loop replay ({} states, preliminary feedback, extrapolated): {update:.2} us per update (median of {rounds} passes)",
        states.len()
    );
    println!(
        "  per update: {it:.2} Newton iterations, {mats:.2} iteration matrices (each evaluated with the residual and factorised once)"
    );
    println!(
        "  parts: fused residual + 7x7 iteration matrix {fused:.1} ns, 7x7 LU {factor:.1} ns; floor = iterations x (both) = {floor:.2} us; update / floor = {:.2}",
        update / floor
    );
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("wheel DPC update");
    let cases = [false, true]
        .into_iter()
        .flat_map(|pf| [Extraction::FirstUsable, Extraction::Extrapolated].map(move |e| (pf, e)));
    for (with_prefeedback, extraction) in cases {
        let mut dpc = controller(with_prefeedback, extraction);
        let x = [std::f64::consts::FRAC_PI_2 + 0.01, -0.3, 0.0, 0.0, -6.0];
        let mut u = [0.0; 2];
        dpc.control(0.05, &x, &mut u).expect("warm-up update");
        let name = if with_prefeedback {
            format!("warm start, {extraction:?} with preliminary feedback")
        } else {
            format!("warm start, {extraction:?}")
        };
        group.bench_function(name, |b| {
            b.iter(|| dpc.control(black_box(0.05), black_box(&x), &mut u))
        });
    }
    let states = recorded_states(0.05);
    let mut dpc = controller(true, Extraction::Extrapolated);
    let mut u = [0.0; 2];
    let mut k = 0;
    group.bench_function(
        "closed-loop replay, Extrapolated with preliminary feedback",
        |b| {
            b.iter(|| {
                let (t, x) = &states[k];
                k = (k + 1) % states.len();
                dpc.control(black_box(*t), black_box(x), &mut u)
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench);

fn main() {
    replay_summary(&recorded_states(0.05));
    benches();
    Criterion::default().configure_from_args().final_summary();
}
