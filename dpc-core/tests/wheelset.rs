//! The BDF and Radau IIA on the Test Set's wheelset (index 2, 17 unknowns, creep forces;
//! `tests/common/wheelset.rs`) at `rtol = atol = tol`, the two normal forces of index 2
//! excluded from the BDF's error test, scored on all 17 unknowns at `t = 10` against the Test
//! Set's reference (DASSL at 1e-9: Radau at `1e-10` agrees with it to 5.3 digits, so scores
//! saturate there), the median over `tol x (0.9, 1, 1.1)`. Floors are half a digit below the
//! measured medians (printed with `--nocapture`); the tighter tolerances are `#[ignore]`d:
//!
//! ```sh
//! cargo test -p dpc-core --test wheelset -- --nocapture
//! cargo test --release -p dpc-core --test wheelset -- --ignored --nocapture
//! ```

#[path = "common/testset_index3.rs"]
mod testset_index3;
#[path = "common/wheelset.rs"]
mod wheelset;

use dpc_core::bdf::{self, Bdf, MatrixUpdate};
use dpc_core::linear_solver::NalgebraLu;
use dpc_core::radau::{self, Radau};
use dpc_core::ImplicitDae;
use testset_index3::median_scd_over_jitter;
use wheelset::*;

/// The BDF (`radau = false`) or Radau from the Test Set's start to [`WHEEL_T_END`] at
/// `rtol = atol = tol`, told the index of every unknown: `y(t_end)` or the error's message.
fn run(tol: f64, radau: bool) -> Result<Vec<f64>, String> {
    let (y0, yp0) = Wheelset::initial();
    let index = WHEEL_INDEX.to_vec();
    let mut y = vec![0.0; WHEEL_DIM];
    let ls = NalgebraLu::<WHEEL_DIM>::new();
    if radau {
        let opts = radau::Options {
            index,
            ..radau::Options::with_tolerances(tol, tol)
        };
        let mut s = Radau::new(Wheelset, ls, opts, 0.0, &y0, &yp0).map_err(|e| e.to_string())?;
        s.set_stop_time(WHEEL_T_END).map_err(|e| e.to_string())?;
        s.solve_to(WHEEL_T_END, &mut y, None)
            .map_err(|e| e.to_string())?;
        println!("  Radau tol {tol:e}: {:?}", s.stats());
    } else {
        y = run_bdf(tol, EVALUATE)?.0;
    }
    Ok(y)
}

/// The BDF as in [`run`] with the iteration matrix updated by `update`: `y(t_end)` and the
/// statistics, or the error's message.
fn run_bdf(
    tol: f64,
    (update, max_matrix_age): (MatrixUpdate, Option<usize>),
) -> Result<(Vec<f64>, bdf::Stats), String> {
    let (y0, yp0) = Wheelset::initial();
    let opts = bdf::Options {
        index: WHEEL_INDEX.to_vec(),
        matrix_update: update,
        max_matrix_age,
        ..bdf::Options::with_tolerances(tol, tol)
    };
    let ls = NalgebraLu::<WHEEL_DIM>::new();
    let mut s = Bdf::new(Wheelset, ls, opts, 0.0, &y0, &yp0).map_err(|e| e.to_string())?;
    s.set_stop_time(WHEEL_T_END).map_err(|e| e.to_string())?;
    let mut y = vec![0.0; WHEEL_DIM];
    s.solve_to(WHEEL_T_END, &mut y, None)
        .map_err(|e| e.to_string())?;
    println!("  BDF ({update:?}) tol {tol:e}: {:?}", s.stats());
    Ok((y, s.stats()))
}

/// The BDF's default matrix rule: evaluated at every new `cj` (on this DAE of index 2 without
/// an age bound).
const EVALUATE: (MatrixUpdate, Option<usize>) = (MatrixUpdate::Evaluate, None);

/// The median over `f = 0.9, 1, 1.1` of the scd of `run(tol f)` on all 17 unknowns; a failed
/// run scores minus infinity.
fn digits(tol: f64, radau: bool) -> f64 {
    let all: Vec<usize> = (0..WHEEL_DIM).collect();
    median_scd_over_jitter(tol, |t| run(t, radau), &WHEEL_REF, &all)
}

#[test]
fn start_is_consistent() {
    let (y0, yp0) = Wheelset::initial();
    let mut r = [0.0; WHEEL_DIM];
    Wheelset.residual(0.0, &y0, &yp0, &mut r);
    assert!(r.iter().all(|v| v.abs() < 1e-13), "{r:?}");
    // A contact point off the wheel profile (a derailment): a non-finite residual.
    let mut off = y0;
    off[14] = 5.0;
    Wheelset.residual(0.0, &off, &yp0, &mut r);
    assert!(r.iter().all(|v| v.is_nan()));
}

#[test]
fn bdf_reaches_test_set_accuracy() {
    // Median scd (all 17 unknowns) over tol x (0.9, 1, 1.1) at 1e-6, measured: 2.75 (12 870
    // steps at tol). Floor half a digit below.
    let d = digits(1e-6, false);
    println!("wheelset BDF tol 1e-6: median scd {d:.2}");
    assert!(d >= 2.25, "scd {d}");
}

#[test]
fn bdf_moving_its_matrix_evaluates_a_fraction_of_the_matrices() {
    // `MatrixUpdate::Move`: the matrix (34 residuals by central differences) moved to new
    // `cj` with the mass matrix, `dF/dy` evaluated anew after 50 solves. Measured at 1e-6: 313
    // evaluations and 1 819 moves where `Evaluate` evaluates 1 884 (266 and 1 569 before the
    // age bound forced an evaluation without a new `cj` too); median scd 2.41 (`Evaluate`:
    // 2.75). Floor half a digit below.
    let update = (MatrixUpdate::Move, Some(50));
    let all: Vec<usize> = (0..WHEEL_DIM).collect();
    let d = median_scd_over_jitter(1e-6, |t| run_bdf(t, update).map(|r| r.0), &WHEEL_REF, &all);
    println!("wheelset BDF (moved matrices) tol 1e-6: median scd {d:.2}");
    assert!(d >= 1.93, "scd {d}");
    let (_, moved) = run_bdf(1e-6, update).expect("runs");
    let (_, evaluated) = run_bdf(1e-6, EVALUATE).expect("runs");
    // Every matrix is factorised; only the evaluated ones count as Jacobian evaluations.
    assert_eq!(evaluated.factorisations, evaluated.jacobian_evaluations);
    assert!(
        moved.factorisations > 4 * moved.jacobian_evaluations,
        "{moved:?}"
    );
    assert!(4 * moved.jacobian_evaluations < evaluated.jacobian_evaluations);
}

#[test]
fn radau_reaches_test_set_accuracy() {
    // As the BDF's test; measured 3.89 (3 229 steps at tol). Floor half a digit below.
    let d = digits(1e-6, true);
    println!("wheelset Radau tol 1e-6: median scd {d:.2}");
    assert!(d >= 3.39, "scd {d}");
}

#[test]
#[ignore = "seconds in release; run with --release -- --ignored"]
fn bdf_and_radau_at_all_tolerances() {
    for tol in [1e-4, 1e-6, 1e-8] {
        for radau in [false, true] {
            let d = digits(tol, radau);
            println!("wheelset radau={radau} tol {tol:e}: median scd {d:.2}");
        }
    }
}
