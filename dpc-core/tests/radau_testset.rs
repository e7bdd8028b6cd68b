//! The Radau IIA integrator on index-3 problems as declared: Andrews' squeezing mechanism and
//! the car axis (Test Set for IVP Solvers, index-3 forms, scored as the Test Set does) and the
//! Cartesian pendulum. Accuracy is printed (`--nocapture`) and checked against floors set below
//! the measured values; work counters are pinned with insta.

#[path = "common/bdf_problems.rs"]
mod bdf_problems;
#[path = "common/testset_index3.rs"]
mod testset;

use bdf_problems::{Pendulum, PENDULUM_INDEX};
use dpc_core::linalg::{FaerDenseLu, FaerSparseLu, LinearSolver, NalgebraLu};
use dpc_core::radau::{Options, Radau, Stats};
use dpc_core::ImplicitDae;
use testset::*;

/// Andrews to `t = 0.03` at `rtol = atol = tol`: (y(0.03), stats).
fn andrews(tol: f64) -> ([f64; 27], Stats) {
    let (y0, yp0) = Andrews::initial();
    let opts = Options {
        index: andrews_index(),
        ..Options::with_tolerances(tol, tol)
    };
    let mut r = Radau::new(Andrews, FaerDenseLu::new(27), opts, 0.0, &y0, &yp0).unwrap();
    r.set_stop_time(ANDREWS_T_END).unwrap();
    let mut y = [0.0; 27];
    r.solve_to(ANDREWS_T_END, &mut y, None).unwrap();
    (y, r.stats())
}

/// Car axis to `t = 3` at `rtol = atol = tol`.
fn car_axis<L: LinearSolver>(tol: f64, ls: L) -> ([f64; 10], Stats) {
    let p = CarAxis::default();
    let (y0, yp0) = p.initial();
    let opts = Options {
        index: CAR_AXIS_INDEX.to_vec(),
        ..Options::with_tolerances(tol, tol)
    };
    let mut r = Radau::new(p, ls, opts, 0.0, &y0, &yp0).unwrap();
    r.set_stop_time(CAR_AXIS_T_END).unwrap();
    let mut y = [0.0; 10];
    r.solve_to(CAR_AXIS_T_END, &mut y, None).unwrap();
    (y, r.stats())
}

#[test]
fn andrews_index3_reaches_test_set_accuracy() {
    // Measured scd (mescd) on y1..y7: 0.49 (1.56) at 1e-4, 3.93 (4.43) at 1e-6, 5.11 (5.62) at
    // 1e-8, in 73, 74 and 124 steps. Floors are about half a digit below.
    for (tol, floor) in [(1e-4, 0.0), (1e-6, 3.4), (1e-8, 4.6)] {
        let (y, s) = andrews(tol);
        let d = scd(&y, &ANDREWS_REF, &ANDREWS_SCORED);
        let m = mescd(&y, &ANDREWS_REF, &ANDREWS_SCORED, tol, tol);
        println!("Andrews tol {tol:e}: scd {d:.2}, mescd {m:.2}, {s:?}");
        assert!(d >= floor, "tol {tol}: scd {d}");
    }
}

#[test]
fn car_axis_index3_reaches_test_set_accuracy() {
    // All ten components are scored. Measured scd (mescd): 0.21 (1.35) at 1e-4, 1.88 (2.93)
    // at 1e-6, 2.81 (4.54) at 1e-8 in 97, 199 and 417 steps; the worst components are the
    // velocities and multipliers (index 2 and 3, whose error weights are scaled by h and h^2),
    // the positions alone reach 3.9 and 5.4 digits at 1e-6 and 1e-8.
    let all: Vec<usize> = (0..10).collect();
    let positions = [0, 1, 2, 3];
    for (tol, floor, floor_pos) in [(1e-4, 0.0, 1.0), (1e-6, 1.4, 3.4), (1e-8, 2.3, 4.9)] {
        let (y, s) = car_axis(tol, NalgebraLu::<10>::new());
        let d = scd(&y, &CAR_AXIS_REF, &all);
        let m = mescd(&y, &CAR_AXIS_REF, &all, tol, tol);
        let dp = scd(&y, &CAR_AXIS_REF, &positions);
        println!("car axis tol {tol:e}: scd {d:.2} (positions {dp:.2}), mescd {m:.2}, {s:?}");
        assert!(d >= floor, "tol {tol}: scd {d}");
        assert!(dp >= floor_pos, "tol {tol}: scd of the positions {dp}");
    }
}

#[test]
fn car_axis_back_ends_agree() {
    let p = CarAxis::default();
    let pattern: Vec<(usize, usize)> = {
        // The structural pattern: every entry the Jacobian writes at a generic point.
        let mut m = faer::Mat::<f64>::zeros(10, 10);
        let (y, yp) = p.initial();
        let y: Vec<f64> = y
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.01 * (i as f64 + 1.0))
            .collect();
        p.iteration_matrix(0.1, &y, &yp, 1.0, &mut m);
        (0..10)
            .flat_map(|i| (0..10).map(move |j| (i, j)))
            .filter(|&(i, j)| m[(i, j)] != 0.0)
            .collect()
    };
    let (a, sa) = car_axis(1e-6, NalgebraLu::<10>::new());
    let (b, sb) = car_axis(1e-6, FaerDenseLu::new(10));
    let (c, _) = car_axis(1e-6, FaerSparseLu::new(10, &pattern).unwrap());
    assert_eq!(sa, sb);
    for i in 0..10 {
        assert!((a[i] - b[i]).abs() < 1e-12, "{a:?} vs {b:?}");
        // The sparse LU pivots differently: agreement to well within the accuracy.
        assert!((a[i] - c[i]).abs() < 1e-6, "{a:?} vs {c:?}");
    }
}

const THETA0: f64 = 1.0;
const PENDULUM_T: f64 = 3.0;

/// Pendulum (index 3) to `t = 3`: (digits in x, y; digits in all components; stats).
fn pendulum(tol: f64, reference: &[f64; 5]) -> (f64, f64, Stats) {
    let p = Pendulum::default();
    let (y0, yp0) = p.initial(THETA0);
    let opts = Options {
        index: PENDULUM_INDEX.to_vec(),
        ..Options::with_tolerances(tol, tol)
    };
    let mut r = Radau::new(p, NalgebraLu::<5>::new(), opts, 0.0, &y0, &yp0).unwrap();
    r.set_stop_time(PENDULUM_T).unwrap();
    let mut y = [0.0; 5];
    r.solve_to(PENDULUM_T, &mut y, None).unwrap();
    (
        scd(&y, reference, &[0, 1]),
        scd(&y, reference, &[0, 1, 2, 3, 4]),
        r.stats(),
    )
}

#[test]
fn pendulum_index3_matches_independent_reference() {
    let reference = Pendulum::default().reference(THETA0, PENDULUM_T);
    // Measured digits (x, y / all five): 3.98 / 2.71 at 1e-4, 5.34 / 3.30 at 1e-6, 7.36 / 3.36 at
    // 1e-8 (44, 81, 170 steps); the multiplier (index 3) limits "all". Floors about half a
    // digit below.
    for (tol, floor, floor_all) in [(1e-4, 3.5, 2.2), (1e-6, 4.8, 2.8), (1e-8, 6.8, 2.9)] {
        let (pos, all, s) = pendulum(tol, &reference);
        println!("pendulum tol {tol:e}: {pos:.2} digits (x, y), {all:.2} (all), {s:?}");
        assert!(pos >= floor, "tol {tol}: {pos}");
        assert!(all >= floor_all, "tol {tol}: {all}");
    }
}

/// Work counters pinned as snapshots (`tests/snapshots/radau_testset__*.snap`): a change of the
/// step-size control, Jacobian reuse or Newton strategy shows up as a diff.
#[test]
fn work_counters_are_pinned() {
    insta::assert_debug_snapshot!("andrews_tol_1e-6", andrews(1e-6).1);
    insta::assert_debug_snapshot!(
        "car_axis_tol_1e-6",
        car_axis(1e-6, NalgebraLu::<10>::new()).1
    );
    // Only the counters are used here, so any reference will do.
    insta::assert_debug_snapshot!("pendulum_tol_1e-6", pendulum(1e-6, &[1.0; 5]).2);
}

/// `dF/dy + c dF/dy'` of the problems against central differences of the residual.
fn check_jacobian<D: ImplicitDae>(dae: &D, t: f64, y: &[f64], yp: &[f64]) {
    let n = dae.dimension();
    for c in [0.0, 1.0, 37.0] {
        let mut m = faer::Mat::<f64>::zeros(n, n);
        dae.iteration_matrix(t, y, yp, c, &mut m);
        let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
        let scale = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| m[(i, j)].abs())
            .fold(0.0, f64::max);
        for j in 0..n {
            let (mut y1, mut yp1) = (y.to_vec(), yp.to_vec());
            let d = 1e-6 * (1.0 + y[j].abs());
            // Perturb y_j by d and y'_j by c d: the derivative is dF/dy_j + c dF/dy'_j.
            y1[j] += d;
            yp1[j] += c * d;
            dae.residual(t, &y1, &yp1, &mut fp);
            y1[j] -= 2.0 * d;
            yp1[j] -= 2.0 * c * d;
            dae.residual(t, &y1, &yp1, &mut fm);
            for i in 0..n {
                let fd = (fp[i] - fm[i]) / (2.0 * d);
                assert!(
                    (fd - m[(i, j)]).abs() <= 1e-6 * scale,
                    "c {c}: entry ({i}, {j}) {} vs finite difference {fd}",
                    m[(i, j)]
                );
            }
        }
    }
}

#[test]
fn problem_jacobians_match_finite_differences() {
    let (y, yp) = Andrews::initial();
    check_jacobian(&Andrews, 0.0, &y, &yp);
    check_jacobian(&Andrews, 0.03, &ANDREWS_REF, &yp);
    let p = CarAxis::default();
    let (y, yp) = p.initial();
    check_jacobian(&p, 0.0, &y, &yp);
    check_jacobian(&p, 0.7, &CAR_AXIS_REF, &yp);
}
