//! The BDF and Radau IIA on two circuit problems of the Test Set for IVP Solvers that the peer
//! table did not have (issue 18's "standard index-1, 2 and 3 problems"): the NAND gate (14
//! unknowns, state-dependent regular capacitance matrix, index 0) and the charge pump (9
//! unknowns, index 2, constant singular mass matrix), each run from corner to corner of its
//! input pulses and scored as the Test Set's drivers do (NAND: `y5`; pump: `y1`). Floors are
//! half a digit below the medians measured over the jitter `tol x (0.9, 1, 1.1)` (printed with
//! `--nocapture`). The runs at tighter tolerances are `#[ignore]`d (seconds in release, too
//! slow in debug):
//!
//! ```sh
//! cargo test --release -p dpc-core --test circuits -- --ignored --nocapture
//! ```

#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/nand.rs"]
mod nand;
#[path = "common/pump.rs"]
mod pump;
#[path = "common/testset_index3.rs"]
mod testset_index3;

use dpc_core::linear_solver::NalgebraLu;
use dpc_core::{bdf, radau, ImplicitDae};
use matrix_check::matrix_error;
use nand::*;
use pump::*;
use testset_index3::median_scd_over_jitter as digits;

/// `$name::<N, D>(dae, (y0, yp0), opts, breaks)`: `$solver` from `t = 0` through the stop
/// times `breaks` (the last is the end), continuing across each: `(y(end), statistics)`, or the
/// error's message.
macro_rules! piecewise {
    ($name:ident, $solver:ty, $options:ty, $stats:ty) => {
        fn $name<const N: usize, D: ImplicitDae>(
            dae: D,
            (y0, yp0): (&[f64], &[f64]),
            opts: $options,
            breaks: &[f64],
        ) -> Result<(Vec<f64>, $stats), String> {
            let mut s = <$solver>::new(dae, NalgebraLu::<N>::new(), opts, 0.0, y0, yp0)
                .map_err(|e| e.to_string())?;
            let mut y = vec![0.0; N];
            for &tb in breaks {
                s.set_stop_time(tb).map_err(|e| e.to_string())?;
                s.solve_to(tb, &mut y, None).map_err(|e| e.to_string())?;
            }
            Ok((y, s.stats()))
        }
    };
}

piecewise!(bdf_piecewise, bdf::Bdf<D, NalgebraLu<N>>, bdf::Options, bdf::Stats);
piecewise!(radau_piecewise, radau::Radau<D, NalgebraLu<N>>, radau::Options, radau::Stats);

/// The NAND gate at `rtol = atol = tol` by the BDF (`radau = false`) or Radau: `y(80)` or the
/// error's message (statistics printed).
fn nand_run(tol: f64, radau: bool) -> Result<Vec<f64>, String> {
    let (y0, yp0) = Nand::initial();
    let start = (&y0[..], &yp0[..]);
    let breaks = nand_breaks();
    if radau {
        let opts = radau::Options::with_tolerances(tol, tol);
        let (y, s) = radau_piecewise::<14, _>(Nand, start, opts, &breaks)?;
        println!("  NAND Radau tol {tol:e}: {s:?}");
        Ok(y)
    } else {
        let opts = bdf::Options::with_tolerances(tol, tol);
        let (y, s) = bdf_piecewise::<14, _>(Nand, start, opts, &breaks)?;
        println!("  NAND BDF tol {tol:e}: {s:?}");
        Ok(y)
    }
}

/// The charge pump at `rtol = tol` with the Test Set's absolute tolerances and `y9` (index 2)
/// excluded from the error test: `y(1.2e-6)` or the error's message (statistics printed).
fn pump_run(tol: f64, radau: bool) -> Result<Vec<f64>, String> {
    let (y0, yp0) = Pump::initial();
    let start = (&y0[..], &yp0[..]);
    let breaks = pump_breaks();
    let rtol = dpc_core::bdf::Tolerance::Scalar(tol);
    let atol = dpc_core::bdf::Tolerance::Vector(pump_atol(tol));
    if radau {
        let opts = radau::Options {
            rtol,
            atol,
            index: PUMP_INDEX.to_vec(),
            ..radau::Options::default()
        };
        let (y, s) = radau_piecewise::<9, _>(Pump, start, opts, &breaks)?;
        println!("  pump Radau tol {tol:e}: {s:?}");
        Ok(y)
    } else {
        let opts = bdf::Options {
            rtol,
            atol,
            index: PUMP_INDEX.to_vec(),
            ..bdf::Options::default()
        };
        let (y, s) = bdf_piecewise::<9, _>(Pump, start, opts, &breaks)?;
        println!("  pump BDF tol {tol:e}: {s:?}");
        Ok(y)
    }
}

#[test]
fn nand_start_is_consistent_and_matrix_matches_differences() {
    let (y0, yp0) = Nand::initial();
    let mut r = [0.0; 14];
    Nand.residual(0.0, &y0, &yp0, &mut r);
    assert!(r.iter().all(|v| v.abs() < 1e-14), "{r:?}");
    // Away from the transistor model's branch switches (at y0 the first transistor has
    // V_DS = 0, where the difference quotient straddles two branches): y0 moved off them, and
    // a state inside the run with the pulses rising; y' of a step with c = 1e3.
    let moved: [f64; 14] = std::array::from_fn(|j| y0[j] + 0.01 * (j as f64 + 1.0));
    let mut y = moved;
    y[5] = 1.2;
    y[10] = 0.3;
    y[4] = 4.2;
    let yp: [f64; 14] = std::array::from_fn(|j| 0.1 * (j as f64 - 6.0));
    for (t, y) in [(0.0, moved), (7.5, y), (17.5, moved)] {
        let e = matrix_error(&Nand, (t, &y, &yp), 1e3, (1e-6, 1e-6));
        assert!(e < 1e-6, "t = {t}: relative error {e:e}");
    }
}

#[test]
fn nand_capacitor_stamps_sum_to_the_test_set_matrix() {
    let (y0, _) = Nand::initial();
    let y: [f64; 14] = std::array::from_fn(|j| y0[j] + 0.3 * (j as f64 - 7.0));
    let dense = Nand::capacitance(&y);
    let mut sum = [[0.0; 14]; 14];
    for (a, b, c) in Nand::capacitors(&y) {
        sum[a][a] += c;
        if let Some(b) = b {
            sum[a][b] -= c;
            sum[b][a] -= c;
            sum[b][b] += c;
        }
    }
    for i in 0..14 {
        for j in 0..14 {
            assert!(
                (sum[i][j] - dense[i][j]).abs() <= 1e-15 * dense[i][i].abs(),
                "({i}, {j})"
            );
        }
    }
}

#[test]
fn pump_start_is_consistent_and_matrix_matches_differences() {
    let (y0, yp0) = Pump::initial();
    let mut r = [0.0; 9];
    Pump.residual(0.0, &y0, &yp0, &mut r);
    assert!(r.iter().all(|v| *v == 0.0), "{r:?}");
    assert!(
        (y0[0] - PUMP_REF[0]).abs() < 1e-14 * PUMP_REF[0],
        "{}",
        y0[0]
    );
    // In each branch of the charges: off (gate below threshold), on with the drain term off,
    // on with both terms, and with source and drain swapped.
    for (u1, u2, u3) in [
        (0.5, 0.1, 0.2),
        (5.0, 0.3, 4.9),
        (20.0, 1.0, 2.0),
        (20.0, 3.0, 1.0),
    ] {
        let mut y = y0;
        y[5] = u1;
        y[6] = u2;
        y[7] = u3;
        let e = matrix_error(&Pump, (55e-9, &y, &yp0), 1e9, (1e-6, 1e-6));
        assert!(e < 1e-6, "U = ({u1}, {u2}, {u3}): relative error {e:e}");
    }
}

#[test]
fn nand_bdf_reaches_test_set_accuracy() {
    // Median scd on y5 over tol x (0.9, 1, 1.1) at 1e-4, measured: 4.94 (878 steps at tol).
    // Floor half a digit below.
    let d = digits(1e-4, |t| nand_run(t, false), &NAND_REF, &NAND_SCORED);
    println!("NAND BDF tol 1e-4: median scd (y5) {d:.2}");
    assert!(d >= 4.4, "scd {d}");
}

#[test]
fn nand_radau_reaches_test_set_accuracy() {
    // Median scd on y5 over tol x (0.9, 1, 1.1) at 1e-4, measured: 4.85 (252 steps at tol).
    // Radau failed here until its steps starting at a corner of the inputs saw the piece they
    // integrate and its rejections read how the estimate fell. Floor half a digit below.
    let d = digits(1e-4, |t| nand_run(t, true), &NAND_REF, &NAND_SCORED);
    println!("NAND Radau tol 1e-4: median scd (y5) {d:.2}");
    assert!(d >= 4.35, "scd {d}");
}

#[test]
fn pump_bdf_reaches_test_set_accuracy() {
    // Median scd on y1 over tol x (0.9, 1, 1.1) at 1e-4, measured: 15.40 (y1 is fixed by the
    // algebraic equation y1 = qgate(vin(t), ...) at the end; 904 steps at tol). Floor half a
    // digit below.
    let d = digits(1e-4, |t| pump_run(t, false), &PUMP_REF, &PUMP_SCORED);
    println!("pump BDF tol 1e-4: median scd (y1) {d:.2}");
    assert!(d >= 14.9, "scd {d}");
}

#[test]
#[ignore = "seconds in release; run with --release -- --ignored"]
fn nand_and_pump_at_all_tolerances() {
    let all: Vec<usize> = (0..14).collect();
    for tol in [1e-4, 1e-6, 1e-8] {
        for radau in [false, true] {
            let d = digits(tol, |t| nand_run(t, radau), &NAND_REF, &NAND_SCORED);
            let dall = digits(tol, |t| nand_run(t, radau), &NAND_REF, &all);
            println!("NAND radau={radau} tol {tol:e}: median scd (y5) {d:.2}, all {dall:.2}");
            let p = digits(tol, |t| pump_run(t, radau), &PUMP_REF, &PUMP_SCORED);
            println!("pump radau={radau} tol {tol:e}: median scd (y1) {p:.2}");
        }
    }
}

#[test]
fn nand_radau_passes_the_corners_at_tight_tolerances() {
    // At rtol = atol = 1e-10 Radau stopped at the input's corner t = 25 after ten consecutive
    // Newton failures (each halving the step; eleven were needed). With the default of twenty
    // (IDA's ten failures quarter the step each) it runs; median scd on y5 over
    // tol x (0.9, 1, 1.1) measured 9.29 (1 997 steps at tol). Floor half a digit below.
    let d = digits(1e-10, |t| nand_run(t, true), &NAND_REF, &NAND_SCORED);
    println!("NAND Radau tol 1e-10: median scd (y5) {d:.2}");
    assert!(d >= 8.8, "scd {d}");
    // The same run with the old limit still fails there: the count, not luck, is the change.
    let (y0, yp0) = Nand::initial();
    let opts = radau::Options {
        max_newton_failures: 10,
        ..radau::Options::with_tolerances(1e-10, 1e-10)
    };
    let failed = radau_piecewise::<14, _>(Nand, (&y0, &yp0), opts, &nand_breaks());
    assert!(
        failed.as_ref().is_err_and(|e| e.contains("t = 25")),
        "{failed:?}"
    );
}

#[test]
fn radau_names_the_switch_it_cannot_step_across_on_the_pump() {
    // Radau takes its matrix at the step's start; at t = 50.1 ns the gate charge changes
    // branch and Newton stalls at every step size (docs/integrators.md, "Which one"). The
    // failure says so, with the contraction and the steps it was measured over, and points at
    // the BDF, which integrates the pump at this tolerance (`pump_bdf_reaches_test_set_accuracy`).
    let (y0, yp0) = Pump::initial();
    let opts = radau::Options {
        rtol: dpc_core::bdf::Tolerance::Scalar(1e-6),
        atol: dpc_core::bdf::Tolerance::Vector(pump_atol(1e-6)),
        index: PUMP_INDEX.to_vec(),
        ..radau::Options::default()
    };
    let mut s = radau::Radau::new(Pump, NalgebraLu::<9>::new(), opts, 0.0, &y0, &yp0)
        .expect("a consistent start");
    let mut y = [0.0; 9];
    let mut failure = None;
    for tb in pump_breaks() {
        s.set_stop_time(tb).expect("ahead");
        if let Err(e) = s.solve_to(tb, &mut y, None) {
            failure = Some(e);
            break;
        }
    }
    let Some(e) = failure else {
        panic!("Radau integrated the pump at 1e-6 (it failed at 50.1 ns): update the docs");
    };
    println!("{e}");
    let radau::RadauError::StalledNewton {
        t,
        h_first,
        h_last,
        theta,
        ..
    } = &e
    else {
        panic!("not diagnosed as a stalled iteration: {e}");
    };
    assert!((5.0e-8..5.03e-8).contains(t), "t = {t}");
    assert!(*theta >= 0.5 && h_last * 1e3 <= *h_first, "{e:?}");
    assert!(e.to_string().contains("the BDF"), "{e}");
}
