//! The variable-step BDF on rows `dpc BDF` of `work_precision`: the GGL-stabilised index-2
//! forms of the car axis (`car`) and Andrews' squeezing mechanism (`andrews`), and the index-1
//! transistor amplifier (`amplifier`) and Robertson (`robertson`), each solved `reps` times
//! without timing or printing in between: a workload for an instruction counter such as
//! callgrind, and wall time per solve for comparisons on a quiet machine. Prints the work, the
//! end state (for checking that a change left the results bit-identical) and, for the
//! stabilised forms, the significant correct digits. A fractional `k` (`7.95`) jitters the
//! tolerance: the car axis' step sequence is chaotic in rounding, so a change that moves it is
//! judged over several nearby tolerances (docs/integrators.md).
//!
//! ```sh
//! cargo run --release -p dpc-core --example bdf_workload -- car 6 1    # problem, k in rtol = 10^-k (6.1: jittered), reps
//! valgrind --tool=callgrind target/release/examples/bdf_workload car 6 1
//! ```

#[path = "../tests/common/bdf_problems.rs"]
mod problems;
#[path = "../tests/common/testset_index1.rs"]
mod testset_index1;
#[path = "../tests/common/testset_index3.rs"]
mod testset_index3;

use std::time::Instant;

use dpc_core::bdf::{self, Bdf, Tolerance};
use dpc_core::linear_solver::NalgebraLu;
use dpc_core::stabilised::Stabilised;
use dpc_core::ImplicitDae;
use problems::{robertson_atol, Robertson, ROBERTSON_T_END};
use testset_index1::{TransistorAmplifier, TRANSAMP_T_END};
use testset_index3::*;

/// One solve of `dae` from `(y0, yp0)` at `t = 0` to `t_end` with `opts`: (steps, residuals,
/// matrices, end state).
fn run<const N: usize, D: ImplicitDae>(
    dae: D,
    (y0, yp0): (&[f64], &[f64]),
    opts: bdf::Options,
    t_end: f64,
) -> (usize, usize, usize, Vec<f64>) {
    let mut b = Bdf::new(dae, NalgebraLu::<N>::new(), opts, 0.0, y0, yp0).expect("set-up");
    b.set_stop_time(t_end).expect("stop time");
    let mut y = vec![0.0; N];
    b.solve_to(t_end, &mut y, None).expect("solve");
    let st = b.stats();
    (
        st.steps,
        st.residual_evaluations,
        st.jacobian_evaluations,
        y,
    )
}

/// One solve of the stabilised form `s` from the declared form's `(y0, yp0)` to `t_end` with
/// the table's options (`rtol = atol = tol`, the first `differential` unknowns of index 1, the
/// rest 2): (steps, residuals, matrices, end state).
fn solve<const N: usize, D: ImplicitDae>(
    s: Stabilised<D>,
    (y0, yp0): (&[f64], &[f64]),
    differential: usize,
    tol: f64,
    t_end: f64,
) -> (usize, usize, usize, Vec<f64>) {
    let (y0, yp0) = s.extend(y0, yp0);
    let opts = bdf::Options {
        index: (0..N)
            .map(|i| if i < differential { 1 } else { 2 })
            .collect(),
        ..bdf::Options::with_tolerances(tol, tol)
    };
    run::<N, _>(s, (&y0, &yp0), opts, t_end)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let problem = args.get(1).map_or("car", String::as_str);
    let k: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(6.0);
    let reps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let tol = 10f64.powf(-k);
    let start = Instant::now();
    let mut last = None;
    for _ in 0..reps {
        last = Some(match problem {
            "amplifier" => {
                let (y0, yp0) = TransistorAmplifier::initial();
                run::<8, _>(
                    TransistorAmplifier,
                    (&y0, &yp0),
                    bdf::Options::with_tolerances(tol, tol),
                    TRANSAMP_T_END,
                )
            }
            "robertson" => {
                let opts = bdf::Options {
                    rtol: Tolerance::Scalar(tol),
                    atol: Tolerance::Vector(robertson_atol(tol)),
                    ..bdf::Options::default()
                };
                run::<3, _>(
                    Robertson,
                    (&[1.0, 0.0, 0.0], &[-0.04, 0.04, 0.0]),
                    opts,
                    ROBERTSON_T_END,
                )
            }
            "andrews" => {
                let (y0, yp0) = Andrews::initial();
                solve::<33, _>(Andrews::stabilised(), (&y0, &yp0), 14, tol, ANDREWS_T_END)
            }
            _ => {
                let car = CarAxis::default();
                let (y0, yp0) = car.initial();
                solve::<12, _>(
                    car.stabilised(),
                    (&y0, &yp0),
                    CarAxis::STABILISED_DIFFERENTIAL,
                    tol,
                    CAR_AXIS_T_END,
                )
            }
        });
    }
    let ms = start.elapsed().as_secs_f64() * 1e3 / reps.max(1) as f64;
    if let Some((steps, residuals, matrices, y)) = last {
        // Significant correct digits of the stabilised forms, scored as in `work_precision`.
        let digits = match problem {
            "andrews" => format!(", scd {:.2}", scd(&y, &ANDREWS_REF, &ANDREWS_SCORED)),
            "car" => format!(
                ", scd {:.2}",
                scd(&y, &CAR_AXIS_REF, &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9])
            ),
            _ => String::new(),
        };
        println!(
            "{problem} 1e-{k}: {steps} steps, {residuals} residuals, {matrices} matrices{digits}, \
             {ms:.3} ms per solve\ny = {y:?}"
        );
    }
}
