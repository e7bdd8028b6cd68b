// The arm and its measurement, shared by the benchmark `benches/arms.rs` and the compile-time
// examples `arm8.rs` and `arm16.rs` (each includes this file): `flexible_joint_arm!` (the
// declaration `models/src/arm.rs` instantiates, included) declares the arm with the number of
// links a macro argument, so that the larger ones are compiled only where they are measured,
// and `measure!` prints one row of the benchmark's table (docs/arms.md). The compile-time
// examples compile the whole of it: their compile time is what a user's crate with this arm
// and this use of it costs.

use dpc::core::design::{design, DesignOptions};
use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::linear_solver::NalgebraLu;
use dpc::core::linear_analysis::AnalysisOptions;
use dpc::core::prefeedback::SteadyMotion;
use dpc::core::simulate::{simulate, ClosedLoopOptions};
use dpc::core::DaeModel;
use std::hint::black_box;
use std::time::{Duration, Instant};

include!("../../models/src/arm_declaration.rs");

/// Median time of `f` over about half a second.
fn median(mut f: impl FnMut()) -> Duration {
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 5 || (start.elapsed() < Duration::from_millis(500) && times.len() < 100_000)
    {
        let t = Instant::now();
        f();
        times.push(t.elapsed());
    }
    times.sort();
    times[times.len() / 2]
}

macro_rules! measure {
    ($plant:ident, $tracking:ident, $reference:ident, $n:literal) => {{
        let plant = $plant::default();
        let tracking = $tracking::default();
        let ne = $tracking::N_EQUATIONS;
        // The tracking DAE's residual and iteration matrix at a point near the reference.
        let s = tracking.structure();
        let (nx, nz, nw) = (s.n_states(), s.n_algebraic(), s.n_inputs());
        let x: Vec<f64> = (0..nx).map(|k| 0.01 * k as f64).collect();
        let xdot = vec![0.0; nx];
        let z = vec![0.0; nz];
        let w = vec![0.1; nw];
        let mut r = vec![0.0; ne];
        let mut m = dpc::nalgebra::SMatrix::<
            f64,
            { $tracking::N_EQUATIONS },
            { $tracking::N_EQUATIONS },
        >::zeros();
        let eval = median(|| {
            tracking.residual(black_box(0.1), &x, &xdot, &z, &w, &mut r);
            tracking.iteration_matrix(black_box(0.1), &x, &xdot, &z, &w, 100.0, &mut m);
            black_box((&r, &m));
        });
        // The preliminary feedback about the hanging rest, poles at -40.
        let rest = SteadyMotion {
            state: vec![0.0; nx],
            rate: vec![0.0; nx],
            algebraic: vec![],
            input: vec![0.0; $n],
        };
        let designed = design(
            &plant,
            &rest,
            &DesignOptions {
                analysis: AnalysisOptions {
                    w: Some(vec![vec![4.0, 4.0]; $n]),
                    poles: Some(vec![dpc::nalgebra::Complex::new(-40.0, 0.0); 2 * $n]),
                    ..AnalysisOptions::default()
                },
                horizon: 6.0,
                relative_degrees: $plant::RELATIVE_DEGREES.to_vec(),
            },
        )
        .expect("design about the hanging rest");
        let controller = || {
            Dpc::new(
                $tracking::default(),
                $reference::default(),
                NalgebraLu::<{ $tracking::N_EQUATIONS }>::new(),
                DpcOptions {
                    delta: 1e-3,
                    ..DpcOptions::default()
                },
            )
            .expect("controller")
            .with_prefeedback(designed.prefeedback().expect("K_n"))
            .expect("prefeedback")
        };
        // One update, warm (after a first one at the same point).
        let mut dpc = controller();
        let x0 = vec![0.0; nx];
        let mut u = vec![0.0; $n];
        dpc.control(0.05, &x0, &mut u).expect("warm-up update");
        let update = median(|| {
            dpc.control(black_box(0.05), black_box(&x0), &mut u)
                .expect("update");
        });
        // The closed loop of scenarios/arm2.toml, 6 s.
        let mut dpc = controller();
        let run = simulate(
            &plant,
            &mut dpc,
            &x0,
            &ClosedLoopOptions {
                h: 0.01,
                t_end: 6.0,
                ..ClosedLoopOptions::default()
            },
        )
        .expect("run starts");
        let late = run
            .max_abs_error_since(4.0)
            .into_iter()
            .fold(0.0_f64, f64::max);
        let outcome = match &run.divergence {
            None => format!("{late:.1e}"),
            Some(d) => format!("diverged at t = {:.2}", d.t),
        };
        // The update's time per (equations)^3, the growth of its dense LU.
        let per_cube = update.as_secs_f64() * 1e9 / (ne as f64).powi(3);
        println!(
            "| {} | {ne} | {eval:.2?} | {update:.2?} | {per_cube:.3} | {outcome} |",
            $n
        );
    }};
}

/// The header of the table whose rows `measure!` prints.
fn print_header() {
    println!("| links n | equations | residual + iteration matrix | one DPC update | update / equations^3 (ns) | max error, t in [4, 6] |");
    println!("| --- | --- | --- | --- | --- | --- |");
}
