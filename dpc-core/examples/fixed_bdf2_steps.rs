//! The fixed-step workload of the `bdf` benchmark run once, for an instruction count:
//! 1000 steps of BDF2 at `h = 1e-3` on the Cartesian pendulum (index 3) from rest at 1 rad,
//! with `NalgebraLu<5>` (`docs/bdf.md`, "The cost of the shared Newton").
//!
//! ```sh
//! cargo build --release -p dpc-core --example fixed_bdf2_steps
//! valgrind --tool=callgrind --toggle-collect='fixed_bdf2_steps::run*' \
//!     target/release/examples/fixed_bdf2_steps
//! ```

#[path = "../tests/common/bdf_problems.rs"]
mod problems;

use dpc_core::bdf::{FixedBdf, Options};
use dpc_core::linear_solver::NalgebraLu;
use problems::{Pendulum, PENDULUM_INDEX, THETA0};
use std::hint::black_box;

/// The benchmark's loop: build the integrator, take 1000 steps.
#[inline(never)]
fn run(p: Pendulum, y0: &[f64; 5]) -> f64 {
    let opts = Options {
        index: PENDULUM_INDEX.to_vec(),
        ..Options::default()
    };
    let mut f =
        FixedBdf::new(p, NalgebraLu::<5>::new(), opts, 2, 1e-3, 0.0, y0).expect("valid options");
    for _ in 0..1000 {
        f.step().expect("the pendulum steps");
    }
    f.y()[0]
}

fn main() {
    let p = Pendulum::default();
    let (y0, _) = p.initial(THETA0);
    println!("{}", black_box(run(black_box(p), &y0)));
}
