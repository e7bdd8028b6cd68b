//! DAEs from the literature with exact solutions that the other tests do not use, written as a
//! user would write them (`tests/common/literature.rs`: residual, exact iteration matrix and
//! mass matrix, which unknowns are differential, no constraint derivatives), solved with the
//! documented options only: Kværnø's fully implicit index-1 problem, Jay's index-2 problem, a
//! particle on a circular track (index 3) as declared with Radau's index-3 scaling and through
//! `Stabilised::detect` with Radau and the BDF, and a knife edge on an inclined plane (a
//! nonholonomic velocity constraint, index 2).
//!
//! Each test sweeps `rtol = atol = tol` over 1e-4, 1e-6 and 1e-8, each jittered by
//! `x (0.9, 1, 1.1)`, scores the end point against the exact solution with the Test Set's
//! significant correct digits (`scd`, `tests/common/testset_index3.rs`), prints the medians
//! (`--nocapture`; the table of docs/integrators.md, "Problems from the literature") and checks
//! them against floors set about half a digit below the measured medians, and that the error
//! falls from 1e-4 to 1e-8 by a measured number of digits. What the integrators do not do
//! (fewer digits than the tolerance suggests, no decrease) is pinned by `#[ignore]`d tests
//! with the reason.

#[path = "common/literature.rs"]
mod literature;
#[path = "common/testset_index3.rs"]
mod testset_index3;

use dpc_core::linear_solver::FaerDenseLu;
use dpc_core::stabilised::Stabilised;
use dpc_core::{bdf, radau, ImplicitDae};
use literature::*;
use nalgebra::DMatrix;
use testset_index3::scd;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Code {
    Bdf,
    Radau,
}

/// The end value of one integration and its work.
#[derive(Debug, Clone)]
struct Run {
    y: Vec<f64>,
    steps: usize,
    rejected: usize,
    newton_failures: usize,
}

/// Integrate `dae` from `(t0, y0, y0')` to `t1` at `rtol = atol = tol` with the `index` option
/// (the documented default options otherwise): the end value and the work, or the integrator's
/// error message.
#[allow(clippy::too_many_arguments)]
fn solve<D: ImplicitDae>(
    dae: D,
    code: Code,
    tol: f64,
    index: Vec<u8>,
    t0: f64,
    t1: f64,
    y0: &[f64],
    yp0: &[f64],
) -> Result<Run, String> {
    let n = y0.len();
    let mut y = vec![0.0; n];
    match code {
        Code::Bdf => {
            let opts = bdf::Options {
                index,
                ..bdf::Options::with_tolerances(tol, tol)
            };
            let mut b = bdf::Bdf::new(dae, FaerDenseLu::new(n), opts, t0, y0, yp0)
                .map_err(|e| e.to_string())?;
            b.set_stop_time(t1).map_err(|e| e.to_string())?;
            b.solve_to(t1, &mut y, None).map_err(|e| e.to_string())?;
            let s = b.stats();
            Ok(Run {
                y,
                steps: s.steps,
                rejected: s.error_test_failures,
                newton_failures: s.newton_failures,
            })
        }
        Code::Radau => {
            let opts = radau::Options {
                index,
                ..radau::Options::with_tolerances(tol, tol)
            };
            let mut r = radau::Radau::new(dae, FaerDenseLu::new(n), opts, t0, y0, yp0)
                .map_err(|e| e.to_string())?;
            r.set_stop_time(t1).map_err(|e| e.to_string())?;
            r.solve_to(t1, &mut y, None).map_err(|e| e.to_string())?;
            let s = r.stats();
            Ok(Run {
                y,
                steps: s.steps,
                rejected: s.error_test_failures,
                newton_failures: s.newton_failures,
            })
        }
    }
}

/// `Stabilised::detect` at the starting point, then `code` on the detected form with
/// `Stabilised::index()` (docs/integrators.md, "The same problems in the stabilised index-2
/// form"); the end value is cut to the wrapped DAE's unknowns.
fn solve_stabilised<D: ImplicitDae>(
    dae: D,
    code: Code,
    tol: f64,
    t0: f64,
    t1: f64,
    y0: &[f64],
    yp0: &[f64],
) -> Result<Run, String> {
    let s = Stabilised::detect(dae, t0, y0, yp0).map_err(|e| e.to_string())?;
    let index = s.index();
    let (y, yp) = s.extend(y0, yp0);
    let mut run = solve(s, code, tol, index, t0, t1, &y, &yp)?;
    run.y.truncate(y0.len());
    Ok(run)
}

/// The exact solution satisfies the residual to round-off, and the iteration matrix is
/// `dF/dy + c dF/dy'` (central differences), at five times.
fn check_fixture<D: ImplicitDae>(
    dae: &D,
    exact: impl Fn(f64) -> (Vec<f64>, Vec<f64>),
    ts: [f64; 5],
) {
    let n = dae.dimension();
    for t in ts {
        let (y, yp) = exact(t);
        let mut r = vec![0.0; n];
        dae.residual(t, &y, &yp, &mut r);
        assert!(r.iter().all(|v| v.abs() < 1e-12), "t = {t}: {r:?}");
        let c = 3.0;
        let mut m = DMatrix::<f64>::zeros(n, n);
        dae.iteration_matrix(t, &y, &yp, c, &mut m);
        for j in 0..n {
            let d = 1e-6 * (1.0 + y[j].abs() + yp[j].abs());
            let moved = |v: &[f64], s: f64| {
                let mut w = v.to_vec();
                w[j] += s * d;
                w
            };
            let mut f = [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]];
            dae.residual(t, &moved(&y, 1.0), &yp, &mut f[0]);
            dae.residual(t, &moved(&y, -1.0), &yp, &mut f[1]);
            dae.residual(t, &y, &moved(&yp, 1.0), &mut f[2]);
            dae.residual(t, &y, &moved(&yp, -1.0), &mut f[3]);
            for i in 0..n {
                let fd = (f[0][i] - f[1][i] + c * (f[2][i] - f[3][i])) / (2.0 * d);
                assert!(
                    (fd - m[(i, j)]).abs() < 1e-6 * (1.0 + fd.abs()),
                    "t = {t}: entry ({i}, {j}) {} against the difference {fd}",
                    m[(i, j)]
                );
            }
        }
    }
}

fn vecs<const N: usize>(p: ([f64; N], [f64; N])) -> (Vec<f64>, Vec<f64>) {
    (p.0.to_vec(), p.1.to_vec())
}

#[test]
fn the_exact_solutions_satisfy_the_equations() {
    check_fixture(
        &Kvaerno,
        |t| vecs(Kvaerno::exact(t)),
        [0.5, 0.6, 0.75, 0.9, 1.0],
    );
    for linear_multiplier in [false, true] {
        check_fixture(
            &Jay { linear_multiplier },
            |t| vecs(Jay::exact(t)),
            [0.0, 0.25, 0.5, 0.75, 1.0],
        );
    }
    check_fixture(
        &CircularTrack,
        |t| vecs(CircularTrack::exact(t)),
        [0.0, 0.5, 1.0, 1.5, 2.0],
    );
    check_fixture(&KNIFE, |t| vecs(KNIFE.exact(t)), [0.0, 0.7, 1.4, 2.2, 3.0]);
    for eta in [1.0, -0.2] {
        let p = Bcp { eta };
        check_fixture(&p, |t| vecs(p.exact(t)), [0.0, 0.7, 1.4, 2.2, 3.0]);
    }
    check_fixture(
        &AnalyticIndex2 { alpha: 10.0 },
        |t| vecs(AnalyticIndex2::exact(t)),
        [0.0, 0.25, 0.5, 0.75, 1.0],
    );
}

const TOLS: [f64; 3] = [1e-4, 1e-6, 1e-8];

/// One tolerance of a sweep: median digits per group of components over the jitter, and the
/// work at the unjittered tolerance.
#[derive(Debug)]
struct Row {
    tol: f64,
    digits: Vec<f64>,
    /// The three jittered runs' digits per group (for the printout).
    spread: Vec<[f64; 3]>,
    steps: usize,
    rejected: usize,
    newton_failures: usize,
}

/// Run `run(tol)` at every tolerance of [`TOLS`] times 0.9, 1 and 1.1 and score each group of
/// components against `reference`; an integrator error fails the test with its message.
fn sweep(
    label: &str,
    run: impl Fn(f64) -> Result<Run, String>,
    reference: &[f64],
    groups: &[(&str, &[usize])],
) -> Vec<Row> {
    let rows: Vec<Row> = TOLS
        .iter()
        .map(|&tol| {
            let runs: Vec<Run> = [0.9, 1.0, 1.1]
                .iter()
                .map(|f| run(tol * f).unwrap_or_else(|e| panic!("{label} at {}: {e}", tol * f)))
                .collect();
            let spread: Vec<[f64; 3]> = groups
                .iter()
                .map(|(_, c)| std::array::from_fn(|k| scd(&runs[k].y, reference, c)))
                .collect();
            let digits = spread.iter().map(|s| median3(*s)).collect();
            Row {
                tol,
                digits,
                spread,
                steps: runs[1].steps,
                rejected: runs[1].rejected,
                newton_failures: runs[1].newton_failures,
            }
        })
        .collect();
    for r in &rows {
        let groups: Vec<String> = groups
            .iter()
            .zip(&r.digits)
            .zip(&r.spread)
            .map(|(((name, _), d), s)| {
                format!("{name} {d:.2} ({:.2} / {:.2} / {:.2})", s[0], s[1], s[2])
            })
            .collect();
        println!(
            "| {label} | {:e} | {} | {} | {} | {} |",
            r.tol,
            groups.join("; "),
            r.steps,
            r.rejected,
            r.newton_failures
        );
    }
    rows
}

fn median3(mut v: [f64; 3]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[1]
}

/// Medians at 1e-6 at least `floor`, and from 1e-4 to 1e-8 a gain of at least `gain` digits,
/// for group `g`.
fn check(rows: &[Row], g: usize, floor: f64, gain: f64) {
    let d = &rows[1].digits[g];
    assert!(*d >= floor, "median digits {d} at 1e-6 below {floor}");
    let g48 = rows[2].digits[g] - rows[0].digits[g];
    assert!(
        g48 >= gain,
        "1e-4 -> 1e-8 gains {g48} digits, less than {gain}"
    );
}

fn kvaerno(code: Code) -> Vec<Row> {
    let (y0, yp0) = Kvaerno::exact(KVAERNO_T0);
    let (reference, _) = Kvaerno::exact(KVAERNO_T_END);
    sweep(
        &format!("Kvaerno, {code:?}"),
        |tol| {
            solve(
                Kvaerno,
                code,
                tol,
                vec![],
                KVAERNO_T0,
                KVAERNO_T_END,
                &y0,
                &yp0,
            )
        },
        &reference,
        &[("y1, y2", &[0, 1])],
    )
}

#[test]
fn kvaerno_index1_bdf() {
    // Measured medians 3.04 / 4.83 / 6.26 digits at 1e-4 / 1e-6 / 1e-8 (6.26 - 3.04 = 3.2
    // digits gained) in 26 / 52 / 78 steps; one rejected step in nine runs, no Newton failure.
    let rows = kvaerno(Code::Bdf);
    check(&rows, 0, 4.3, 2.5);
    assert!(rows[2].steps < 150, "{rows:?}");
}

#[test]
fn kvaerno_index1_radau() {
    // Measured medians 5.38 / 6.25 / 7.86 (2.5 digits gained) in 10 / 13 / 19 steps, no
    // rejected step, Newton failures in 5 / 5 / 3 (at 1e-6 where the step grows: 0.023 ->
    // 0.044 -> 0.064 -> 0.085).
    let rows = kvaerno(Code::Radau);
    check(&rows, 0, 5.7, 1.8);
    assert!(rows[2].steps < 40, "{rows:?}");
}

fn jay(code: Code, linear_multiplier: bool) -> Vec<Row> {
    let (y0, yp0) = Jay::exact(0.0);
    let (reference, _) = Jay::exact(JAY_T_END);
    // z is algebraic, of index 2: the documented `index` option.
    sweep(
        &format!("Jay (linear multiplier: {linear_multiplier}), {code:?}"),
        |tol| {
            let dae = Jay { linear_multiplier };
            solve(dae, code, tol, vec![1, 1, 2], 0.0, JAY_T_END, &y0, &yp0)
        },
        &reference,
        &[("y1, y2", &[0, 1]), ("z", &[2])],
    )
}

#[test]
fn jay_index2_bdf() {
    // Measured medians (y1, y2 / z): Jay's form 2.31 / 2.35 at 1e-4, 3.26 / 3.24 at 1e-6, 4.28 /
    // 4.25 at 1e-8 in 53 / 284 / 2325 steps with 3 / 63 / 627 rejected: far below the
    // tolerances (see `jay_index2_bdf_reaches_the_tolerance`). With the multiplier entering
    // linearly 2.89 / 2.30, 4.43 / 4.31, 5.94 / 5.70 in 34 / 104 / 158 steps (5 / 7 / 11
    // rejected).
    let rows = jay(Code::Bdf, false);
    check(&rows, 0, 2.8, 1.5);
    check(&rows, 1, 2.7, 1.5);
    let rows = jay(Code::Bdf, true);
    check(&rows, 0, 3.9, 2.5);
    check(&rows, 1, 3.8, 2.5);
    assert!(rows[2].steps < 400, "{rows:?}");
}

#[test]
#[ignore = "fails: on Jay's problem (multiplier entering as z^2) the BDF stays at order 1-2 \
            with h ~ 1e-4 over [0, 0.13] at 1e-8 (2325 steps, 627 rejected) and ends with \
            y1 off by 2.6e-5 relative (4.3 digits); at 1e-6 3.2 digits in 284 steps. \
            HigherIndexControl::Scale: 1559 steps, 4.5 digits. The trouble lies in \
            t < 0.15: from t0 = 0.2 (to t0 + 1) 157 steps at 1e-8. Radau: 31 / 53 steps, \
            y1 and y2 to 8 / 10 digits."]
fn jay_index2_bdf_reaches_the_tolerance() {
    let rows = jay(Code::Bdf, false);
    // What the tolerance suggests and the linear-multiplier variant (and Radau) achieve.
    assert!(rows[1].digits[0] >= 4.5, "{rows:?}");
    assert!(rows[2].digits[0] >= 6.0, "{rows:?}");
    assert!(rows[2].steps < 500, "{rows:?}");
}

#[test]
fn jay_index2_radau() {
    // Measured medians (y1, y2 / z): 6.69 / 5.64 at 1e-4, 8.12 / 6.18 at 1e-6, 10.00 / 5.74 at
    // 1e-8 in 22 / 31 / 53 steps, no rejected step, Newton failures in 16 / 13 / 21 of them.
    // The multiplier's digits scatter by up to 2.5 over the jitter (6.18 / 7.36 / 4.91 at 1e-6)
    // and do not rise from 1e-6 to 1e-8 (`jay_index2_radau_multiplier_follows_the_tolerance`).
    let rows = jay(Code::Radau, false);
    check(&rows, 0, 7.6, 2.8);
    assert!(rows[1].digits[1] >= 5.5, "{rows:?}");
    // With the multiplier entering linearly: 6.26 / 5.21, 7.63 / 5.82, 9.26 / 6.46 in 28 / 34 /
    // 52 steps, Newton failures in 24 / 15 / 22.
    let rows = jay(Code::Radau, true);
    check(&rows, 0, 7.1, 2.5);
    assert!(rows[1].digits[1] >= 5.3, "{rows:?}");
}

#[test]
#[ignore = "fails: Radau's multiplier z on Jay's problem scatters over 2.5 digits between \
            tolerances 0.9x, 1x, 1.1x and its median does not rise from 1e-6 (6.2) to 1e-8 \
            (5.7): its error at the end is that of the last step (the car axis' multipliers do \
            the same, docs/integrators.md)"]
fn jay_index2_radau_multiplier_follows_the_tolerance() {
    let rows = jay(Code::Radau, false);
    assert!(rows[2].digits[1] >= rows[1].digits[1] + 1.0, "{rows:?}");
}

fn track(code: Code, stabilised: bool) -> Vec<Row> {
    let (y0, yp0) = CircularTrack::exact(0.0);
    let (reference, _) = CircularTrack::exact(TRACK_T_END);
    let label = if stabilised {
        "detected stabilised form"
    } else {
        "index 3 as declared"
    };
    sweep(
        &format!("circular track, {label}, {code:?}"),
        |tol| {
            if stabilised {
                solve_stabilised(CircularTrack, code, tol, 0.0, TRACK_T_END, &y0, &yp0)
            } else {
                // Radau's index-3 scaling: positions 1, velocities 2, the multiplier 3.
                let index = vec![1, 1, 2, 2, 3];
                solve(CircularTrack, code, tol, index, 0.0, TRACK_T_END, &y0, &yp0)
            }
        },
        &reference,
        &[
            ("positions", &[0, 1]),
            ("velocities", &[2, 3]),
            ("lambda", &[4]),
        ],
    )
}

#[test]
fn circular_track_detect_finds_the_constraint() {
    let (y0, yp0) = CircularTrack::exact(0.0);
    // At t = 0 the particle is at (0, 1): the gradient's entry 2x vanishes there.
    let s = Stabilised::detect(CircularTrack, 0.0, &y0, &yp0).unwrap();
    assert_eq!(s.constraint_rows(), &[4]);
    assert_eq!(s.kinematic_pairs(), &[(0, 0), (1, 1)]);
    assert_eq!(s.index(), vec![1, 1, 1, 1, 2, 2]);
}

#[test]
fn circular_track_index3_radau() {
    // Measured medians (positions / velocities / lambda): 5.22 / 4.04 / 2.56 at 1e-4, 6.13 /
    // 4.75 / 3.16 at 1e-6, 7.88 / 6.22 / 3.46 at 1e-8 in 33 / 53 / 100 steps with 1 / 3 / 9
    // rejected and Newton failures in 18 / 18 / 17. The multiplier gains 0.9 digits over four
    // decades (the index-3 form relaxes its weight by h^2, docs/integrators.md).
    let rows = track(Code::Radau, false);
    check(&rows, 0, 5.6, 2.0);
    check(&rows, 1, 4.2, 1.6);
    check(&rows, 2, 2.6, 0.4);
}

#[test]
fn circular_track_stabilised_radau() {
    // Measured medians (positions / velocities / lambda): 5.62 / 5.69 / 4.93 at 1e-4, 6.86 /
    // 6.78 / 5.03 at 1e-6, 8.26 / 8.21 / 6.33 at 1e-8 in 29 / 47 / 80 steps (0 / 1 / 1
    // rejected), Newton failures in 13 / 10 / 0. Against the form as declared: 0.7 / 2.0 / 1.9
    // digits more at 1e-6 in fewer steps.
    let rows = track(Code::Radau, true);
    check(&rows, 0, 6.3, 2.0);
    check(&rows, 1, 6.2, 2.0);
    check(&rows, 2, 4.5, 0.8);
}

#[test]
fn circular_track_stabilised_bdf() {
    // Measured medians (positions / velocities / lambda): 2.71 / 2.71 / 2.40 at 1e-4, 4.79 /
    // 4.84 / 4.56 at 1e-6, 6.76 / 6.66 / 6.85 at 1e-8 in 70 / 136 / 240 steps with 3 / 8 / 7
    // rejected, no Newton failure.
    let rows = track(Code::Bdf, true);
    check(&rows, 0, 4.3, 3.5);
    check(&rows, 1, 4.3, 3.4);
    check(&rows, 2, 4.0, 3.5);
}

#[test]
fn circular_track_index3_bdf() {
    // Not the documented way (docs/integrators.md: Radau, or the stabilised form), measured for
    // comparison with the default `HigherIndexControl::Exclude` and the index-3 `index` option.
    // Measured medians (positions / velocities / lambda): 1.59 / 1.45 / 1.74 at 1e-4, 3.85 /
    // 3.80 / 3.45 at 1e-6, 5.71 / 5.62 / 3.24 at 1e-8 in 50 / 81 / 135 steps (1 / 2 / 1
    // rejected, no Newton failure): the multiplier, excluded from the error test, gains nothing
    // from 1e-6 to 1e-8; positions and velocities do.
    let rows = track(Code::Bdf, false);
    check(&rows, 0, 3.3, 3.5);
    check(&rows, 1, 3.3, 3.5);
    assert!(rows[1].digits[2] >= 2.9, "{rows:?}");
}

fn knife_edge(code: Code) -> Vec<Row> {
    let (y0, yp0) = KNIFE.exact(0.0);
    let (reference, _) = KNIFE.exact(KNIFE_T_END);
    sweep(
        &format!("knife edge, {code:?}"),
        |tol| {
            // The side force is algebraic, of index 2: the documented `index` option.
            let index = vec![1, 1, 1, 1, 1, 1, 2];
            solve(KNIFE, code, tol, index, 0.0, KNIFE_T_END, &y0, &yp0)
        },
        &reference,
        &[
            ("x, y, phi", &[0, 1, 2]),
            ("u, v", &[3, 4]),
            ("lambda", &[6]),
        ],
    )
}

#[test]
fn knife_edge_detect_leaves_the_velocity_constraint() {
    // The constraint involves u and v, which have no kinematic rows (their rows hold lambda):
    // not a position constraint, left as declared, lambda of index 2.
    let (y0, yp0) = KNIFE.exact(0.0);
    let s = Stabilised::detect(KNIFE, 0.0, &y0, &yp0).unwrap();
    assert!(s.constraint_rows().is_empty(), "{:?}", s.constraint_rows());
    assert_eq!(s.index(), vec![1, 1, 1, 1, 1, 1, 2]);
}

#[test]
fn knife_edge_index2_radau() {
    // Measured medians (x, y, phi / u, v / lambda): 4.08 / 5.64 / 3.61 at 1e-4, 5.30 / 7.76 /
    // 4.50 at 1e-6, 6.89 / 9.54 / 4.81 at 1e-8 in 40 / 67 / 130 steps (0 / 0 / 1 rejected),
    // Newton failures in 15 / 8 / 6. The side force gains 1.2 digits over four decades and
    // scatters by 1.9 over the jitter at 1e-8 (as Jay's z).
    let rows = knife_edge(Code::Radau);
    check(&rows, 0, 4.8, 2.3);
    check(&rows, 1, 7.2, 3.0);
    check(&rows, 2, 4.0, 0.5);
}

#[test]
fn knife_edge_index2_bdf() {
    // Measured medians (x, y, phi / u, v / lambda): 1.50 / 2.45 / 2.00 at 1e-4, 3.62 / 4.58 /
    // 4.59 at 1e-6, 6.01 / 6.71 / 6.54 at 1e-8 in 129 / 248 / 426 steps (4 / 7 / 16 rejected),
    // no Newton failure.
    let rows = knife_edge(Code::Bdf);
    check(&rows, 0, 3.1, 3.8);
    check(&rows, 1, 4.1, 3.5);
    check(&rows, 2, 4.0, 3.5);
}

#[test]
fn a_forgotten_index_option_is_named_in_the_error() {
    // The circular track's index-3 form with the index option left empty (every unknown of
    // index at most 1) used to stop with messages that did not point at it (Radau "10
    // consecutive failures (error test failed) at t = 0.012", the BDF "error test failed
    // repeatedly" or "Newton iteration failed ... step 8.5e-20"); both now add the unknowns the
    // iteration matrix shows of index 2 and 3 there (`index_estimate::unknown_indices`).
    let (y0, yp0) = CircularTrack::exact(0.0);
    for code in [Code::Radau, Code::Bdf] {
        for tol in [1e-6, 1e-8] {
            let e = solve(
                CircularTrack,
                code,
                tol,
                vec![],
                0.0,
                TRACK_T_END,
                &y0,
                &yp0,
            )
            .expect_err("the index-3 form without its index option");
            assert!(e.contains("of index 3"), "{code:?} at {tol}: {e}");
            println!("{code:?} at {tol}: {e}");
        }
    }
    // Jay's problem without the option: the BDF ran out of steps at t = 3.8e-8 ("too many
    // steps (100000)") without a word on the cause; Radau solves it without the option.
    let (y0, yp0) = Jay::exact(0.0);
    let e = solve(
        Jay::default(),
        Code::Bdf,
        1e-8,
        vec![],
        0.0,
        JAY_T_END,
        &y0,
        &yp0,
    )
    .expect_err("Jay's problem by the BDF without its index option");
    assert!(e.contains("`y[2]` of index 2"), "{e}");
}

/// Gear and Petzold's problem on `[0, 3]` at 1e-6 with both integrators under every `index`
/// option a user might pick: `Ok(relative errors)` or the error message.
/// One run of [`bcp_runs`]: the code, the `index` option, the relative errors or the message.
type BcpRun = (Code, Vec<u8>, Result<Vec<f64>, String>);

fn bcp_runs(eta: f64) -> Vec<BcpRun> {
    let p = Bcp { eta };
    let (y0, yp0) = p.exact(0.0);
    let (reference, _) = p.exact(3.0);
    let mut out = Vec::new();
    for code in [Code::Bdf, Code::Radau] {
        for index in [vec![], vec![1, 2], vec![2, 2]] {
            let r = solve(p, code, 1e-6, index.clone(), 0.0, 3.0, &y0, &yp0).map(|r| {
                (0..2)
                    .map(|i| (r.y[i] - reference[i]).abs() / reference[i].abs())
                    .collect()
            });
            println!("Gear-Petzold eta {eta}, {code:?}, index {index:?}: {r:?}");
            out.push((code, index, r));
        }
    }
    out
}

#[test]
#[ignore = "fails: Gear and Petzold's index-2 problem (every unknown of index 2) at eta = 1 \
            and -0.2, 1e-6: no run of either integrator with index [], [1, 2] or [2, 2] ends \
            within 1e-2 of the exact solution. Radau stops after 1-5 steps with ten Newton \
            failures (its iteration matrix at one time serves stages where dF/dy2' = eta t \
            differs by eta c_i h, which the factor 1/h turns into O(eta): with eta t frozen \
            to a constant 1.5, Radau solves the same structure in 17-32 steps to 4-6 \
            digits under all three options); the BDF stops \
            (too many steps, Newton at h ~ 1e-18) or, with [2, 2], refuses the options \
            (bcp_with_every_unknown_excluded_is_not_silently_wrong); IDA 6.4.1 fails alike"]
fn bcp_index2_is_solved_by_some_documented_option() {
    for eta in [1.0, -0.2] {
        let runs = bcp_runs(eta);
        for code in [Code::Bdf, Code::Radau] {
            assert!(
                runs.iter()
                    .any(|(c, _, r)| *c == code
                        && r.as_ref().is_ok_and(|e| e.iter().all(|&e| e < 1e-2))),
                "eta {eta}, {code:?}: {runs:?}"
            );
        }
    }
}

#[test]
fn bcp_with_every_unknown_excluded_is_not_silently_wrong() {
    // With index [2, 2] under the default `HigherIndexControl::Exclude` no unknown would be in
    // the BDF's error test: before `BdfError::NothingInErrorTest` it returned Ok in 24 steps
    // with both unknowns 3-5 times off at eta = 1 (1e-6), and IDA with both unknowns
    // suppressed alike (11 steps, 50-70 % off). Now the set-up refuses; with `Scale` the run
    // is allowed (whether it reaches the tolerance is the ignored test above).
    let p = Bcp { eta: 1.0 };
    let (y0, yp0) = p.exact(0.0);
    let opts = bdf::Options {
        index: vec![2, 2],
        ..bdf::Options::with_tolerances(1e-6, 1e-6)
    };
    let e = bdf::Bdf::new(p, FaerDenseLu::new(2), opts.clone(), 0.0, &y0, &yp0)
        .err()
        .expect("every unknown excluded from the error test");
    assert_eq!(e, bdf::BdfError::NothingInErrorTest);
    assert!(e.to_string().contains("HigherIndexControl::Scale"), "{e}");
    let scaled = bdf::Options {
        higher_index: bdf::HigherIndexControl::Scale,
        ..opts
    };
    assert!(bdf::Bdf::new(p, FaerDenseLu::new(2), scaled, 0.0, &y0, &yp0).is_ok());
}

/// Ascher & Petzold's Example 10.2 with SUNDIALS' `alpha = 10`, from its exact start, with
/// `index` as the option (`[1, 2]`: `x2` of index 2; empty: every unknown in the error test,
/// as SUNDIALS' example runs IDA).
fn analytic_index2(code: Code, index: Vec<u8>) -> Vec<Row> {
    let (y0, yp0) = AnalyticIndex2::exact(0.0);
    let (reference, _) = AnalyticIndex2::exact(ANALYTIC_T_END);
    sweep(
        &format!("analytic index 2 (Ascher-Petzold 10.2; index {index:?}), {code:?}"),
        |tol| {
            let dae = AnalyticIndex2 { alpha: 10.0 };
            solve(
                dae,
                code,
                tol,
                index.clone(),
                0.0,
                ANALYTIC_T_END,
                &y0,
                &yp0,
            )
        },
        &reference,
        &[("x1", &[0]), ("x2", &[1])],
    )
}

#[test]
fn analytic_index2_index2_bdf() {
    // Measured medians (x1 / x2) with x2 declared of index 2: 15.79 / 4.49 at 1e-4, 9.42 /
    // 6.03 at 1e-6, 15.79 / 7.98 at 1e-8 (x1 is held by the constraint: exact up to
    // rounding) in 18 / 32 / 52 steps, one rejected step at 1e-6 and 1e-8.
    let rows = analytic_index2(Code::Bdf, vec![1, 2]);
    check(&rows, 1, 5.5, 3.0);
    check(&rows, 0, 8.5, -1.0);
    assert!(rows[2].steps < 100, "{rows:?}");
}

#[test]
fn analytic_index2_index2_radau() {
    // Measured medians (x1 / x2): 6.30 / 5.13, 8.84 / 6.78, 10.60 / 6.56 in 7 / 11 / 17
    // steps: x2 stops gaining below 1e-6 (the multiplier-like unknown follows the last step,
    // as Jay's `z`).
    let rows = analytic_index2(Code::Radau, vec![1, 2]);
    check(&rows, 1, 6.2, 1.0);
    check(&rows, 0, 8.3, 3.5);
    assert!(rows[2].steps < 40, "{rows:?}");
}

#[test]
fn analytic_index2_undeclared_radau() {
    // Without the index option (x2 in the error test as x1): 3.85 / 6.67 / 7.97 digits in x2
    // in 6 / 13 / 27 steps.
    let rows = analytic_index2(Code::Radau, vec![]);
    check(&rows, 1, 6.1, 3.0);
}

#[test]
fn analytic_index2_undeclared_bdf_takes_idas_steps() {
    // SUNDIALS runs IDA on this problem with nothing declared (x2 in the error test) at
    // `rtol = 1e-4`, `atol = 1e-9`: 343 steps, 232 error-test failures, x2 = -2.718640 at
    // t = 1 (3.9 digits). The BDF reads the DAE as of higher index than declared at its start
    // and keeps IDA's rules: 338 steps, 222 failures, 3.95 digits (with the rules of index-1
    // DAEs it took 895 steps). At `rtol = atol = 1e-6` 8 912 steps, 5.6 digits (IDA stops
    // at its 500 steps per output); at 1e-8 neither finishes, and the error names `x2` as of
    // index 2, the option that solves it in 52 steps (`analytic_index2_index2_bdf`).
    let (y0, yp0) = AnalyticIndex2::exact(0.0);
    let (reference, _) = AnalyticIndex2::exact(ANALYTIC_T_END);
    let run = |rtol: f64, atol: f64| {
        let opts = bdf::Options::with_tolerances(rtol, atol);
        let dae = AnalyticIndex2 { alpha: 10.0 };
        let mut b = bdf::Bdf::new(dae, FaerDenseLu::new(2), opts, 0.0, &y0, &yp0).unwrap();
        b.set_stop_time(ANALYTIC_T_END).unwrap();
        let mut y = vec![0.0; 2];
        let r = b.solve_to(ANALYTIC_T_END, &mut y, None);
        (r.map(|_| y), b.stats())
    };
    let (y, stats) = run(1e-4, 1e-9);
    let y = y.unwrap();
    let d = scd(&y, &reference, &[1]);
    println!("1e-4 / 1e-9: x2 {d:.2} digits, {stats:?}");
    assert!(d > 3.5, "{d}");
    assert!(stats.steps < 450, "{stats:?}");
    let (y, stats) = run(1e-6, 1e-6);
    let d = scd(&y.unwrap(), &reference, &[1]);
    println!("1e-6: x2 {d:.2} digits, {stats:?}");
    assert!(d > 5.0, "{d}");
    assert!(stats.steps < 15_000, "{stats:?}");
    match run(1e-8, 1e-8).0 {
        Err(e @ bdf::BdfError::UndeclaredIndex { .. }) => {
            let bdf::BdfError::UndeclaredIndex { ref unknowns, .. } = e else {
                unreachable!()
            };
            assert_eq!(unknowns, &[("x2".to_string(), 2)], "{e}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_step_accepted_off_jays_constraint_is_named_as_the_cause_of_the_failure() {
    // With `HigherIndexControl::Scale` at 1.07e-4 (the one run of 3 x 41 tolerance factors
    // `0.80 ... 1.20` x 1e-4 / 1e-6 / 1e-8 that fails; with the default `Exclude` none does)
    // the BDF accepts a step off the constraint `y1^2 y2 = 1` (equation 2) and then fails
    // (docs/integrators.md, "The BDF stopped on Jay's problem"): Newton's first updates grow as
    // the step falls (`z` must jump by the defect over `h`), which a matrix that does not
    // describe the equations (`BdfError::StalledNewton`) does not show. The failure names the
    // constraint and how far the point reached is off it.
    let (y0, yp0) = Jay::exact(0.0);
    let opts = bdf::Options {
        index: vec![1, 1, 2],
        higher_index: bdf::HigherIndexControl::Scale,
        ..bdf::Options::with_tolerances(1.07e-4, 1.07e-4)
    };
    let dae = Jay {
        linear_multiplier: false,
    };
    let mut s = bdf::Bdf::new(dae, FaerDenseLu::new(3), opts, 0.0, &y0, &yp0).expect("start");
    let mut y = [0.0; 3];
    let e = s
        .solve_to(JAY_T_END, &mut y, None)
        .expect_err("the run that fails (measured 2026-12-05)");
    println!("{e}");
    let bdf::BdfError::OffConstraint {
        ref equation,
        residual,
        bound,
        ref source,
        ..
    } = e
    else {
        panic!("not named as a step off the constraint: {e:?}");
    };
    assert_eq!(equation, "equation 2");
    // Off by more than a tenth of what the tolerances allow (the accepted steps before met it
    // to 4.1e-5, a twentieth, and better).
    assert!(
        residual.abs() >= 0.1 * bound && residual.abs() < bound,
        "{e:?}"
    );
    assert!(matches!(**source, bdf::BdfError::NewtonFailed { .. }));
}
