//! The Test Set's Medical Akzo Nobel problem (`common/medakzo.rs`: 400 unknowns, a banded
//! Jacobian, the boundary input switched off at `t = 5`) by the BDF and Radau IIA with the
//! banded LU [`FaerLu::for_dae`] picks from the declared pattern: the fixture's iteration and
//! mass matrices against differences of its residual, and the digits both integrators reach at
//! `t = 20` against the Test Set's reference (all 400 components, mixed error; the median over
//! the tolerance jitter 0.9, 1, 1.1), with floors half a digit below the measured medians.
//! Accuracy and work are printed (`--nocapture`).
//!
//! The runs stop at `t = 5`, where the input jumps, and restart there (as the peer table's
//! rows); Radau and the BDF at `1e-12` check the reference. Every treatment of the jump
//! (restart, continue, straight through) at `1e-4` to `1e-12` is printed by an ignored test:
//!
//! ```sh
//! cargo test --release -p dpc-core --test medakzo -- --ignored --nocapture
//! ```

#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/medakzo.rs"]
mod medakzo;
#[path = "common/testset_index3.rs"]
mod testset_index3;

use dpc_core::linear_solver::{half_bandwidths, FaerLu};
use dpc_core::{bdf, radau, ImplicitDae};
use matrix_check::{check_mass_matrix, matrix_error, perturbed};
use medakzo::*;
use testset_index3::median_over_jitter;

/// The integrators under test.
#[derive(Clone, Copy, Debug)]
enum Code {
    Bdf,
    Radau,
}

/// How a run treats the input's switch at `t = 5`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Switch {
    /// Stop at `t = 5` and restart there from `(y(5), f(5+, y(5)))` (the table's rows).
    Restart,
    /// Stop at `t = 5` and continue with the history.
    Continue,
    /// Integrate straight through.
    Through,
}

/// `code` with the banded LU from the Test Set's start to `t = 20` at `rtol = atol = tol`,
/// treating the switch as `switch`: `(y(20), statistics printed as text)`.
fn run_with(code: Code, tol: f64, switch: Switch) -> Result<(Vec<f64>, String), String> {
    let (y0, yp0) = Medakzo::initial();
    let ls = FaerLu::for_dae(&Medakzo);
    assert!(ls.is_band(), "FaerLu::for_dae did not pick the banded LU");
    let mut y = vec![0.0; MEDAKZO_DIM];
    macro_rules! go {
        ($solver:expr) => {{
            let mut s = $solver.map_err(|e| e.to_string())?;
            if switch != Switch::Through {
                s.set_stop_time(MEDAKZO_T_SWITCH)
                    .map_err(|e| e.to_string())?;
                s.solve_to(MEDAKZO_T_SWITCH, &mut y, None)
                    .map_err(|e| e.to_string())?;
                if switch == Switch::Restart {
                    let yp = Medakzo::slope_after_switch(&y);
                    s.reinit(MEDAKZO_T_SWITCH, &y, &yp)
                        .map_err(|e| e.to_string())?;
                }
            }
            s.set_stop_time(MEDAKZO_T_END).map_err(|e| e.to_string())?;
            s.solve_to(MEDAKZO_T_END, &mut y, None)
                .map_err(|e| e.to_string())?;
            format!("{:?}", s.stats())
        }};
    }
    let stats = match code {
        Code::Bdf => go!(bdf::Bdf::new(
            Medakzo,
            ls,
            bdf::Options::with_tolerances(tol, tol),
            0.0,
            &y0,
            &yp0
        )),
        Code::Radau => go!(radau::Radau::new(
            Medakzo,
            ls,
            radau::Options::with_tolerances(tol, tol),
            0.0,
            &y0,
            &yp0
        )),
    };
    Ok((y, stats))
}

/// The component of the largest mixed error of `y` against the reference, and that error.
fn worst(y: &[f64]) -> (usize, f64) {
    y.iter()
        .zip(&MEDAKZO_REF)
        .map(|(y, r)| (y - r).abs() / (1.0 + r.abs()))
        .enumerate()
        .fold((0, 0.0), |m, (i, e)| if e > m.1 { (i, e) } else { m })
}

/// [`run_with`] restarting at the switch, as the table; a failure panics.
fn run(code: Code, tol: f64) -> (Vec<f64>, String) {
    run_with(code, tol, Switch::Restart).unwrap_or_else(|e| panic!("{code:?}, tol {tol:e}: {e}"))
}

/// The median digits of `code` over the jitter at `tol` (stopping at the switch), printed with
/// the work at `tol` itself.
fn median(code: Code, tol: f64) -> f64 {
    let d = median_over_jitter(tol, |t| medakzo_scd(&run(code, t).0));
    let (_, stats) = run(code, tol);
    println!("medakzo {code:?} tol {tol:e}: median scd {d:.2}, {stats}");
    d
}

#[test]
fn iteration_matrices_match_differences_of_the_residual() {
    let (y0, yp0) = Medakzo::initial();
    let yr = MEDAKZO_REF.to_vec();
    let mut ypr = vec![0.0; MEDAKZO_DIM];
    Medakzo.f(MEDAKZO_T_END, &yr, &mut ypr);
    for (point, (t, y, yp)) in [("start", (0.0, y0, yp0)), ("end", (MEDAKZO_T_END, yr, ypr))] {
        let (tm, ym, ypm) = perturbed(t, &y, &yp, 11);
        for (moved, at) in [
            ("", (t, &y[..], &yp[..])),
            (" moved", (tm, &ym[..], &ypm[..])),
        ] {
            for c in [1.0, 1e3] {
                // f is quadratic in y: central differences are exact but for round-off.
                let e = matrix_error(&Medakzo, at, c, (1e-6, 1e-3));
                println!("{point}{moved}, c = {c}: {e:.1e}");
                assert!(e <= 1e-7, "{point}{moved}, c = {c}: {e:e} of the row");
            }
        }
        check_mass_matrix("medakzo", &Medakzo, t, &y, &yp);
    }
}

#[test]
fn pattern_is_the_test_sets_band() {
    let p = Medakzo.iteration_pattern().unwrap();
    assert_eq!(p.len(), 1197);
    assert_eq!(half_bandwidths(MEDAKZO_DIM, &p), Ok((2, 2)));
    assert_eq!(MEDAKZO_HALF_BANDWIDTH, 2);
    // Every entry once, and the diagonal in it.
    let mut q = p.clone();
    q.sort_unstable();
    q.dedup();
    assert_eq!(q.len(), p.len());
    assert!((0..MEDAKZO_DIM).all(|i| p.contains(&(i, i))));
}

#[test]
fn initial_values_and_reference_are_the_test_sets() {
    let (y, yp) = Medakzo::initial();
    let mut r = vec![1.0; MEDAKZO_DIM];
    Medakzo.residual(0.0, &y, &yp, &mut r);
    assert!(r.iter().all(|v| *v == 0.0));
    // Only the first grid point feels the input: u_1' = phi (beta_1 / dz^2 - alpha_1 / (2 dz)).
    assert!(yp[0] > 4.9e3 && yp[0] < 5.0e3, "{}", yp[0]);
    assert!(yp[1..].iter().all(|v| *v == 0.0));
    assert_eq!(medakzo_phi(5.0), 2.0);
    assert_eq!(medakzo_phi(5.0 + 1e-12), 0.0);
    // Spot checks of the transcription of `solut`.
    assert_eq!(MEDAKZO_REF[0], 0.5113983840919909e-5);
    assert_eq!(MEDAKZO_REF[142], 0.3619760735583436e-3);
    assert_eq!(MEDAKZO_REF[207], 0.1548747348410801);
    assert_eq!(MEDAKZO_REF[398], 0.0);
    assert_eq!(MEDAKZO_REF[399], 1.0);
    assert_eq!(Medakzo.unknown_name(207), "v104");
}

#[test]
fn ida_peer_reference_is_the_fixtures() {
    // bench/ida_peer.c includes the same reference as C literals: they must not drift apart.
    let header = include_str!("../../bench/ida_peer_medakzo_ref.h");
    let body = &header[header.find("*/").expect("the header's comment") + 2..];
    let values: Vec<f64> = body
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap_or_else(|e| panic!("'{s}': {e}")))
        .collect();
    assert_eq!(values, MEDAKZO_REF.to_vec());
}

#[test]
fn bdf_and_radau_reach_the_reference() {
    // Measured medians (BDF, Radau): (3.27, 4.09) at 1e-4, (5.46, 5.50) at 1e-6, (6.92, 7.59)
    // at 1e-8. The BDF's were IDA's with IDA's matrix rule (3.86 / 5.01 / 6.62, the same 377
    // steps at 1e-4; before `Bdf::reinit` took the default first step after a strong jump of
    // `y'`, 3.38 / 5.11 / 6.74); since its matrices serve at most `DEFAULT_MAX_MATRIX_AGE`
    // solves it takes 748 / 1 447 steps for 891 / 1 844 at 1e-6 / 1e-8. The floors are about
    // half a digit below.
    for (tol, floor_bdf, floor_radau) in [(1e-4, 2.8, 3.5), (1e-6, 5.0, 5.0), (1e-8, 6.4, 7.0)] {
        let b = median(Code::Bdf, tol);
        let r = median(Code::Radau, tol);
        assert!(
            b >= floor_bdf,
            "BDF tol {tol:e}: median scd {b:.2} below {floor_bdf}"
        );
        assert!(
            r >= floor_radau,
            "Radau tol {tol:e}: median scd {r:.2} below {floor_radau}"
        );
    }
}

#[test]
fn a_restart_after_the_switch_is_a_new_integrators_start() {
    // `u_1'` jumps by about -4.9e3 at the switch: the curvature of the solution before it says
    // nothing of the one after, so `Bdf::reinit` takes the default first step, as a new
    // integrator from the same point does (and IDA's `IDAReInit`), and the rest of the run is
    // the new integrator's, step for step.
    for tol in [1e-4, 1e-6] {
        let (y0, yp0) = Medakzo::initial();
        let opts = bdf::Options::with_tolerances(tol, tol);
        let mut s = bdf::Bdf::new(
            Medakzo,
            FaerLu::for_dae(&Medakzo),
            opts.clone(),
            0.0,
            &y0,
            &yp0,
        )
        .expect("start");
        let mut y = vec![0.0; MEDAKZO_DIM];
        s.set_stop_time(MEDAKZO_T_SWITCH).expect("stop time");
        s.solve_to(MEDAKZO_T_SWITCH, &mut y, None)
            .expect("to the switch");
        let yp = Medakzo::slope_after_switch(&y);
        let before = s.stats();
        s.reinit(MEDAKZO_T_SWITCH, &y, &yp).expect("restart");
        let mut fresh = bdf::Bdf::new(
            Medakzo,
            FaerLu::for_dae(&Medakzo),
            opts,
            MEDAKZO_T_SWITCH,
            &y,
            &yp,
        )
        .expect("new start");
        let (mut a, mut b) = (vec![0.0; MEDAKZO_DIM], vec![0.0; MEDAKZO_DIM]);
        for (solver, out) in [(&mut s, &mut a), (&mut fresh, &mut b)] {
            solver.set_stop_time(MEDAKZO_T_END).expect("stop time");
            solver
                .solve_to(MEDAKZO_T_END, out, None)
                .expect("to the end");
        }
        let (restarted, new) = (s.stats(), fresh.stats());
        assert_eq!(
            (
                restarted.steps - before.steps,
                restarted.error_test_failures - before.error_test_failures
            ),
            (new.steps, new.error_test_failures),
            "tol {tol:e}"
        );
        assert_eq!(a, b, "tol {tol:e}");
    }
}

#[test]
fn reference_agrees_with_tight_runs() {
    let (r, sr) = run(Code::Radau, 1e-12);
    let (b, sb) = run(Code::Bdf, 1e-12);
    let (dr, db) = (medakzo_scd(&r), medakzo_scd(&b));
    // The two runs against each other, in the same mixed measure.
    let mutual = -r
        .iter()
        .zip(&b)
        .map(|(r, b)| (r - b).abs() / (1.0 + r.abs()))
        .fold(0.0f64, f64::max)
        .log10();
    println!("medakzo Radau tol 1e-12: scd {dr:.2}, {sr}");
    println!("medakzo Bdf tol 1e-12: scd {db:.2}, {sb}");
    println!("medakzo Radau against BDF at 1e-12: {mutual:.2} digits");
    // Measured: Radau 9.76, BDF 10.15, against each other 9.99: the reference (PSIDE at
    // 1e-10) and both tight runs agree to about 1e-10 of the mixed error, far beyond the
    // table's 1e-8. Floors half a digit below.
    assert!(
        dr >= 9.2,
        "Radau at 1e-12: {dr:.2} digits against the reference"
    );
    assert!(
        db >= 9.6,
        "BDF at 1e-12: {db:.2} digits against the reference"
    );
    assert!(
        mutual >= 9.4,
        "Radau and BDF at 1e-12 agree to {mutual:.2} digits only"
    );
}

#[test]
#[ignore = "every treatment of the switch at 1e-4..1e-12 (printed): cargo test --release -p dpc-core --test medakzo -- --ignored --nocapture"]
fn treatments_of_the_switch() {
    for code in [Code::Radau, Code::Bdf] {
        for tol in [0.9e-4, 1e-4, 1.1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
            for switch in [Switch::Restart, Switch::Continue, Switch::Through] {
                match run_with(code, tol, switch) {
                    Ok((y, stats)) => {
                        let (i, e) = worst(&y);
                        println!(
                            "medakzo {code:?} tol {tol:e} {switch:?}: scd {:.2} (worst {} = {:.4e}, \
                             reference {:.4e}, error {e:.1e}), {stats}",
                            medakzo_scd(&y),
                            Medakzo.unknown_name(i),
                            y[i],
                            MEDAKZO_REF[i]
                        )
                    }
                    Err(e) => println!("medakzo {code:?} tol {tol:e} {switch:?}: {e}"),
                }
            }
        }
    }
}
