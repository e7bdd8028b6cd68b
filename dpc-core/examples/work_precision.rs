//! The BDF's work-precision table (README, "BDF integrator"): per tolerance, the steps, the
//! significant correct digits against the Test Set's reference and the time per solve, on
//! Robertson (index 1, to `t = 1e11`) and the Cartesian pendulum (index 3, to `t = 3`).
//! `bench/ida_peer.sh` prints SUNDIALS IDA's table on the same problems beside it.
//!
//! ```sh
//! cargo run --release -p dpc-core --example work_precision
//! ```

#[path = "../tests/common/bdf_problems.rs"]
mod problems;

use problems::{pendulum, robertson, Pendulum, PENDULUM_T, THETA0};
use std::time::Instant;

/// Solves per timing, the best of which is not taken: the mean over them is printed.
const REPETITIONS: u32 = 20;

fn main() {
    println!("| problem | rtol | steps | significant digits | time [ms] |");
    println!("|---|---|---|---|---|");
    for k in 4..=10 {
        let rtol = 10f64.powi(-k);
        let (scd, steps, _) = robertson(rtol);
        let start = Instant::now();
        for _ in 0..REPETITIONS {
            robertson(rtol);
        }
        let ms = start.elapsed().as_secs_f64() / f64::from(REPETITIONS) * 1e3;
        println!("| Robertson (t=1e11) | 1e-{k} | {steps} | {scd:.2} | {ms:.3} |");
    }
    let reference = Pendulum::default().reference(THETA0, PENDULUM_T);
    for k in 4..=10 {
        let rtol = 10f64.powi(-k);
        let (positions, all, steps, _) = pendulum(rtol, &reference);
        let start = Instant::now();
        for _ in 0..REPETITIONS {
            pendulum(rtol, &reference);
        }
        let ms = start.elapsed().as_secs_f64() / f64::from(REPETITIONS) * 1e3;
        println!(
            "| pendulum (t=3) | 1e-{k} | {steps} | {positions:.2} (x,y) / {all:.2} (all) | {ms:.3} |"
        );
    }
}
