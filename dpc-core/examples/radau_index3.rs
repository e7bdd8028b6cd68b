//! The Radau IIA integrator on the index-3 Test Set problems (Andrews' squeezing mechanism and
//! the car axis) as the Test Set scores them: per tolerance, the median significant correct
//! digits (scd) over the tolerance jitter `tol * {0.9, 1, 1.1}`, the steps and the work.
//!
//! ```sh
//! cargo run --release -p dpc-core --example radau_index3
//! ```
//! With `-- --components` it also prints the digits of every component at `tol`. The car axis
//! row also gives the digits of the four positions at `tol` (the velocities and multipliers,
//! index 2 and 3, are the least accurate components).

#[path = "../tests/common/testset_index3.rs"]
mod testset;

use dpc_core::linalg::{FaerDenseLu, NalgebraLu};
use dpc_core::radau::{Options, Radau, Stats};
use testset::*;

fn andrews(tol: f64) -> Option<([f64; 27], Stats)> {
    let (y0, yp0) = Andrews::initial();
    let opts = Options {
        index: andrews_index(),
        ..Options::with_tolerances(tol, tol)
    };
    let mut r = Radau::new(Andrews, FaerDenseLu::new(27), opts, 0.0, &y0, &yp0).ok()?;
    r.set_stop_time(ANDREWS_T_END).ok()?;
    let mut y = [0.0; 27];
    match r.solve_to(ANDREWS_T_END, &mut y, None) {
        Ok(_) => Some((y, r.stats())),
        Err(e) => {
            eprintln!("Andrews at tol {tol:e}: {e}");
            None
        }
    }
}

fn car_axis(tol: f64) -> Option<([f64; 10], Stats)> {
    let p = CarAxis::default();
    let (y0, yp0) = p.initial();
    let opts = Options {
        index: CAR_AXIS_INDEX.to_vec(),
        ..Options::with_tolerances(tol, tol)
    };
    let mut r = Radau::new(p, NalgebraLu::<10>::new(), opts, 0.0, &y0, &yp0).ok()?;
    r.set_stop_time(CAR_AXIS_T_END).ok()?;
    let mut y = [0.0; 10];
    match r.solve_to(CAR_AXIS_T_END, &mut y, None) {
        Ok(_) => Some((y, r.stats())),
        Err(e) => {
            eprintln!("car axis at tol {tol:e}: {e}");
            None
        }
    }
}

/// Median of the scd over the jitter; a failed run counts as no digits (NaN sorts last).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let components = std::env::args().any(|a| a == "--components");
    println!("| problem | tol | scd (median of tol x 0.9, 1, 1.1) | steps | rejected | Newton failures | Jacobians |");
    println!("|---|---|---|---|---|---|---|");
    for k in [4, 5, 6, 7, 8, 9, 10] {
        let tol = 10f64.powi(-k);
        let d = median(
            [0.9, 1.0, 1.1]
                .iter()
                .map(|f| {
                    andrews(tol * f)
                        .map_or(f64::NAN, |(y, _)| scd(&y, &ANDREWS_REF, &ANDREWS_SCORED))
                })
                .collect(),
        );
        let Some((y, s)) = andrews(tol) else {
            println!("| Andrews (y1..y7) | 1e-{k} | failed | | | | |");
            continue;
        };
        println!(
            "| Andrews (y1..y7) | 1e-{k} | {d:.2} | {} | {} | {} | {} |",
            s.steps, s.error_test_failures, s.newton_failures, s.jacobian_evaluations
        );
        if components {
            let e: Vec<String> = (0..27)
                .map(|i| format!("{:.1}", scd(&y, &ANDREWS_REF, &[i])))
                .collect();
            println!("|   digits per component: {} |", e.join(" "));
        }
    }
    let all: Vec<usize> = (0..10).collect();
    for k in [4, 5, 6, 7, 8, 9, 10] {
        let tol = 10f64.powi(-k);
        let d = median(
            [0.9, 1.0, 1.1]
                .iter()
                .map(|f| car_axis(tol * f).map_or(f64::NAN, |(y, _)| scd(&y, &CAR_AXIS_REF, &all)))
                .collect(),
        );
        let Some((y, s)) = car_axis(tol) else {
            println!("| car axis (all) | 1e-{k} | failed | | | | |");
            continue;
        };
        println!(
            "| car axis (all; positions {:.2}) | 1e-{k} | {d:.2} | {} | {} | {} | {} |",
            scd(&y, &CAR_AXIS_REF, &[0, 1, 2, 3]),
            s.steps,
            s.error_test_failures,
            s.newton_failures,
            s.jacobian_evaluations
        );
        if components {
            let e: Vec<String> = (0..10)
                .map(|i| format!("{:.1}", scd(&y, &CAR_AXIS_REF, &[i])))
                .collect();
            println!("|   digits per component: {} |", e.join(" "));
        }
    }
}
