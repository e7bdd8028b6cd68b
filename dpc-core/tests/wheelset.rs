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

#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/testset_index3.rs"]
mod testset_index3;
#[path = "common/wheelset.rs"]
mod wheelset;

use dpc::core::DaeModel;
use dpc_core::bdf::{self, Bdf, MatrixUpdate};
use dpc_core::linear_solver::NalgebraLu;
use dpc_core::radau::{self, Radau};
use dpc_core::ImplicitDae;
use matrix_check::{matrix_error, perturbed};
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

/// A point `(t, y, y')`.
type Point = (f64, Vec<f64>, Vec<f64>);

/// Points `(t, y, y')` the checks of the generated model use: the Test Set's start, three
/// small pseudo-random moves of it ([`perturbed`]), and the BDF's solution at
/// `t = 1, 2, ..., 10` at `rtol = atol = 1e-4` (where the creep forces have left their
/// initial state).
fn check_points() -> Vec<Point> {
    let (y0, yp0) = Wheelset::initial();
    let mut points = vec![(0.0, y0.to_vec(), yp0.to_vec())];
    for seed in [1, 2, 3] {
        points.push(perturbed(0.0, &y0, &yp0, seed));
    }
    let opts = bdf::Options {
        index: WHEEL_INDEX.to_vec(),
        ..bdf::Options::with_tolerances(1e-4, 1e-4)
    };
    let ls = NalgebraLu::<WHEEL_DIM>::new();
    let mut s = Bdf::new(Wheelset, ls, opts, 0.0, &y0, &yp0).expect("starts");
    for k in 1..=10 {
        let t = f64::from(k);
        let (mut y, mut yp) = (vec![0.0; WHEEL_DIM], vec![0.0; WHEEL_DIM]);
        s.solve_to(t, &mut y, Some(&mut yp)).expect("solves");
        points.push((t, y, yp));
    }
    points
}

/// The largest difference between the generated residual ([`WheelsetModel`]) and the
/// transcription's ([`Wheelset`]) at `(t, y, y')`, relative to the largest term of the
/// transcription (the largest entry of `F(t, y, 0)` or `F(t, y, y') - F(t, y, 0)`: the
/// residual itself nearly vanishes on the solution).
fn residual_difference(t: f64, y: &[f64], yp: &[f64]) -> f64 {
    let (mut transcribed, mut generated, mut at_rest) =
        ([0.0; WHEEL_DIM], [0.0; WHEEL_DIM], [0.0; WHEEL_DIM]);
    Wheelset.residual(t, y, yp, &mut transcribed);
    Wheelset.residual(t, y, &[0.0; WHEEL_DIM], &mut at_rest);
    let (x, z) = y.split_at(WheelsetModel::N_STATES);
    WheelsetModel::default().residual(t, x, &yp[..WheelsetModel::N_STATES], z, &[], &mut generated);
    let scale = (0..WHEEL_DIM)
        .map(|i| at_rest[i].abs().max((transcribed[i] - at_rest[i]).abs()))
        .fold(0.0, f64::max);
    (0..WHEEL_DIM)
        .map(|i| (generated[i] - transcribed[i]).abs() / scale)
        .fold(0.0, f64::max)
}

#[test]
fn generated_residual_equals_the_transcription() {
    // A few hundred roundings of the largest term: the two evaluate the same expressions in
    // different orders (constants folded, `x / |x|` for the slopes, the saturation as a
    // division by `max(1, u)`).
    let mut worst = 0.0f64;
    for (t, y, yp) in check_points() {
        let e = residual_difference(t, &y, &yp);
        assert!(e <= 1e3 * f64::EPSILON, "t = {t}: {e:e}");
        worst = worst.max(e);
    }
    println!("wheelset: generated residual within {worst:.1e} of the largest term");
    // Derailed (a contact point at `xi = 0`, where the wheel's slope is `0 / 0`): NaN in both.
    let (mut y, yp) = Wheelset::initial();
    y[14] = 0.0;
    let mut r = [0.0; WHEEL_DIM];
    let (x, z) = y.split_at(WheelsetModel::N_STATES);
    WheelsetModel::default().residual(0.0, x, &yp[..WheelsetModel::N_STATES], z, &[], &mut r);
    assert!(r.iter().any(|v| v.is_nan()), "{r:?}");
}

#[test]
fn generated_iteration_matrix_equals_central_differences() {
    // The exact matrix (`Wheelset::iteration_matrix`, generated) against central differences
    // of the transcription's residual (step `eps^(1/3) max(|y_j|, 1e-3)`, the old fixture's),
    // relative to the largest entry of each row. The difference is the quotients' truncation
    // error: it falls 100 times per tenfold smaller step from `rel = 1e-3` down to `1e-5` at
    // every point (largest 1.6e-2, 1.6e-4, 1.7e-6 at t = 7; 6.1e-7 at this step), until
    // rounding takes over below `1e-6`. A wrong entry above 1e-5 of its row fails.
    let mut worst = 0.0f64;
    for (t, y, yp) in check_points() {
        for c in [1.0, 1e3] {
            let e = matrix_error(&Wheelset, (t, &y, &yp), c, (f64::EPSILON.cbrt(), 1e-3));
            assert!(e <= 1e-5, "t = {t}, c = {c}: {e:e}");
            worst = worst.max(e);
        }
    }
    println!("wheelset: generated matrix within {worst:.1e} of central differences");
}

#[test]
fn bdf_reaches_test_set_accuracy() {
    // Median scd (all 17 unknowns) over tol x (0.9, 1, 1.1) at 1e-6, measured with the exact
    // matrix (2026-12-05): 2.80 (12 838 steps at tol; 2.75 and 12 870 with the central
    // differences before). Floor half a digit below.
    let d = digits(1e-6, false);
    println!("wheelset BDF tol 1e-6: median scd {d:.2}");
    assert!(d >= 2.30, "scd {d}");
}

#[test]
fn bdf_moving_its_matrix_evaluates_a_fraction_of_the_matrices() {
    // `MatrixUpdate::Move`: the matrix moved to new `cj` with the mass matrix, `dF/dy`
    // evaluated anew after 50 solves. Measured at 1e-6 with the exact matrix (2026-12-05): 310
    // evaluations and 1 776 moves where `Evaluate` evaluates 1 910; median scd 2.40
    // (`Evaluate`: 2.80). With the central differences before: 313 and 1 819 against 1 884,
    // 2.41 (266 and 1 569 before the age bound forced an evaluation without a new `cj` too).
    // Floor half a digit below.
    let update = (MatrixUpdate::Move, Some(50));
    let all: Vec<usize> = (0..WHEEL_DIM).collect();
    let d = median_scd_over_jitter(1e-6, |t| run_bdf(t, update).map(|r| r.0), &WHEEL_REF, &all);
    println!("wheelset BDF (moved matrices) tol 1e-6: median scd {d:.2}");
    assert!(d >= 1.90, "scd {d}");
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
    // As the BDF's test; measured with the exact matrix (2026-12-05): 3.74 (3 236 steps at
    // tol). With the central differences before: 3.61 (3 229 steps; this comment said 3.89).
    // Floor half a digit below.
    let d = digits(1e-6, true);
    println!("wheelset Radau tol 1e-6: median scd {d:.2}");
    assert!(d >= 3.24, "scd {d}");
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

#[test]
#[ignore = "a timing; run with --release -- --ignored --nocapture"]
fn matrix_cost_against_residual_cost() {
    // Mean time of one residual (the transcription's and the generated one) and one exact
    // iteration matrix over the check points; the central-difference matrix the fixture had
    // before cost 34 residuals.
    use std::hint::black_box;
    use std::time::Instant;
    let points = check_points();
    let reps = 20_000;
    let per_call = |f: &mut dyn FnMut(&Point)| {
        let start = Instant::now();
        for _ in 0..reps {
            for p in &points {
                f(black_box(p));
            }
        }
        start.elapsed().as_secs_f64() / (reps * points.len()) as f64 * 1e9
    };
    let mut r = [0.0; WHEEL_DIM];
    let model = WheelsetModel::default();
    let transcribed = per_call(&mut |(t, y, yp)| {
        Wheelset.residual(*t, y, yp, &mut r);
        black_box(&r);
    });
    let generated = per_call(&mut |(t, y, yp)| {
        let (x, z) = y.split_at(WheelsetModel::N_STATES);
        model.residual(*t, x, &yp[..WheelsetModel::N_STATES], z, &[], &mut r);
        black_box(&r);
    });
    let mut m = nalgebra::SMatrix::<f64, WHEEL_DIM, WHEEL_DIM>::zeros();
    let matrix = per_call(&mut |(t, y, yp)| {
        Wheelset.iteration_matrix(*t, y, yp, 1.0, &mut m);
        black_box(&m);
    });
    println!(
        "wheelset: residual {transcribed:.0} ns (generated {generated:.0} ns), exact matrix \
         {matrix:.0} ns = {:.1} residuals (central differences: 34)",
        matrix / transcribed
    );
}
