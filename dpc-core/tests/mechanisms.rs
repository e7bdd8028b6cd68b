//! Index-3 mechanisms the other tests do not have (`common/mechanisms.rs`: the rigid slider
//! crank, the four-bar linkage, the spherical pendulum), written as a user writes them and
//! checked against their minimal-coordinate ODEs: the fixtures' matrices and consistent starts,
//! and the ways a user solves them (Radau with the index declared, the BDF with
//! `HigherIndexControl::Scale` and with its default `Exclude`, the BDF and Radau on the form
//! `Stabilised::detect` finds), with digit floors at `1e-6`. The ignored tests recompute the
//! references, print the table of docs/integrators.md ("Index-3 mechanisms") at `1e-4`,
//! `1e-6`, `1e-8` and check that the digits grow, and run the same codes on the minimal ODEs
//! (run them in release: `cargo test --release -p dpc-core --test mechanisms -- --ignored
//! --nocapture`).

#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/mechanisms.rs"]
mod mechanisms;

use dpc_core::bdf::{self, Bdf, HigherIndexControl};
use dpc_core::linear_solver::FaerDenseLu;
use dpc_core::radau::{self, Radau};
use dpc_core::stabilised::Stabilised;
use dpc_core::ImplicitDae;
use mechanisms::*;

/// A mechanism under test: its name, fixture, start in minimal coordinates, end time and
/// stored reference `(q, q')` at the end.
struct Case<M> {
    name: &'static str,
    mechanism: M,
    start: (Vec<f64>, Vec<f64>),
    t_end: f64,
    reference: &'static [f64],
}

fn slider_crank_case() -> Case<Planar> {
    Case {
        name: "slider crank",
        mechanism: slider_crank(),
        start: (vec![SLIDER_CRANK_START.0], vec![SLIDER_CRANK_START.1]),
        t_end: SLIDER_CRANK_T_END,
        reference: &SLIDER_CRANK_REF,
    }
}

fn four_bar_case() -> Case<Planar> {
    Case {
        name: "four-bar",
        mechanism: four_bar(),
        start: (vec![FOUR_BAR_START.0], vec![FOUR_BAR_START.1]),
        t_end: FOUR_BAR_T_END,
        reference: &FOUR_BAR_REF,
    }
}

fn spherical_case() -> Case<SphericalPendulum> {
    Case {
        name: "spherical pendulum",
        mechanism: SPHERICAL,
        start: (SPHERICAL_START.0.to_vec(), SPHERICAL_START.1.to_vec()),
        t_end: SPHERICAL_T_END,
        reference: &SPHERICAL_REF,
    }
}

/// Significant correct digits of `y[..n]` against `reference` (relative to each component's
/// size, with a floor of 1e-2 on the size, as `tests/double_pendulum.rs`: a component passing
/// near zero, or the slider's height that is zero, does not decide).
fn digits(y: &[f64], reference: &[f64]) -> f64 {
    -reference
        .iter()
        .zip(y)
        .map(|(r, v)| (v - r).abs() / r.abs().max(1e-2))
        .fold(0.0f64, |m, e| if e.is_nan() { f64::NAN } else { m.max(e) })
        .log10()
}

/// The codes a user runs on an index-3 mechanism.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Code {
    /// Radau IIA on the index-3 form with the index declared.
    Radau,
    /// The BDF on the index-3 form with `HigherIndexControl::Scale`.
    BdfScale,
    /// The BDF on the index-3 form with its default `HigherIndexControl::Exclude`.
    BdfExclude,
    /// The BDF on `Stabilised::detect`'s form.
    BdfStabilised,
    /// Radau on `Stabilised::detect`'s form.
    RadauStabilised,
}

/// One run's outcome: `(q, q')` at the end, steps, error-test failures, Newton failures,
/// Jacobians, wall time (ms).
#[derive(Debug)]
struct Outcome {
    y: Vec<f64>,
    steps: usize,
    error_failures: usize,
    newton_failures: usize,
    jacobians: usize,
    ms: f64,
}

fn run<M: Minimal + Clone>(case: &Case<M>, code: Code, tol: f64) -> Result<Outcome, String> {
    let (y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    run_from(case, code, tol, (&y0, &yp0))
}

/// [`run`] from the start `(y0, y0')` of the index-3 form instead of the case's.
fn run_from<M: Minimal + Clone>(
    case: &Case<M>,
    code: Code,
    tol: f64,
    (y0, yp0): (&[f64], &[f64]),
) -> Result<Outcome, String> {
    let dae = IndexThree(case.mechanism.clone());
    let nq = case.mechanism.nq();
    let clock = std::time::Instant::now();
    let (y, steps, error_failures, newton_failures, jacobians) = match code {
        Code::Radau | Code::RadauStabilised => {
            let (y, s) = if code == Code::Radau {
                let opts = radau::Options {
                    index: dae.index(),
                    ..radau::Options::with_tolerances(tol, tol)
                };
                radau_run(dae, opts, (y0, yp0), case.t_end)?
            } else {
                let s = Stabilised::detect(dae, 0.0, y0, yp0).map_err(|e| e.to_string())?;
                let (y, yp) = s.extend(y0, yp0);
                let opts = radau::Options {
                    index: s.index(),
                    ..radau::Options::with_tolerances(tol, tol)
                };
                radau_run(s, opts, (&y, &yp), case.t_end)?
            };
            (
                y,
                s.steps,
                s.error_test_failures,
                s.newton_failures,
                s.jacobian_evaluations,
            )
        }
        Code::BdfScale | Code::BdfExclude | Code::BdfStabilised => {
            let (y, s) = if code != Code::BdfStabilised {
                let opts = bdf::Options {
                    index: dae.index(),
                    higher_index: if code == Code::BdfScale {
                        HigherIndexControl::Scale
                    } else {
                        HigherIndexControl::Exclude
                    },
                    ..bdf::Options::with_tolerances(tol, tol)
                };
                bdf_run(dae, opts, (y0, yp0), case.t_end)?
            } else {
                let s = Stabilised::detect(dae, 0.0, y0, yp0).map_err(|e| e.to_string())?;
                let (y, yp) = s.extend(y0, yp0);
                let opts = bdf::Options {
                    index: s.index(),
                    ..bdf::Options::with_tolerances(tol, tol)
                };
                bdf_run(s, opts, (&y, &yp), case.t_end)?
            };
            (
                y,
                s.steps,
                s.error_test_failures,
                s.newton_failures,
                s.jacobian_evaluations,
            )
        }
    };
    Ok(Outcome {
        y: y[..2 * nq].to_vec(),
        steps,
        error_failures,
        newton_failures,
        jacobians,
        ms: clock.elapsed().as_secs_f64() * 1e3,
    })
}

fn radau_run<D: ImplicitDae>(
    dae: D,
    opts: radau::Options,
    (y0, yp0): (&[f64], &[f64]),
    t_end: f64,
) -> Result<(Vec<f64>, radau::Stats), String> {
    let n = dae.dimension();
    let mut r =
        Radau::new(dae, FaerDenseLu::new(n), opts, 0.0, y0, yp0).map_err(|e| e.to_string())?;
    r.set_stop_time(t_end).map_err(|e| e.to_string())?;
    let mut y = vec![0.0; n];
    r.solve_to(t_end, &mut y, None).map_err(|e| e.to_string())?;
    Ok((y, r.stats()))
}

fn bdf_run<D: ImplicitDae>(
    dae: D,
    opts: bdf::Options,
    (y0, yp0): (&[f64], &[f64]),
    t_end: f64,
) -> Result<(Vec<f64>, bdf::Stats), String> {
    let n = dae.dimension();
    let mut b =
        Bdf::new(dae, FaerDenseLu::new(n), opts, 0.0, y0, yp0).map_err(|e| e.to_string())?;
    b.set_stop_time(t_end).map_err(|e| e.to_string())?;
    let mut y = vec![0.0; n];
    b.solve_to(t_end, &mut y, None).map_err(|e| e.to_string())?;
    Ok((y, b.stats()))
}

const CODES: [Code; 5] = [
    Code::Radau,
    Code::BdfScale,
    Code::BdfExclude,
    Code::BdfStabilised,
    Code::RadauStabilised,
];

/// The largest residual of the index-3 form at `(y0, y0')`, of each of its three blocks
/// (kinematic rows, momentum rows, constraints), relative to the largest term of the row.
fn start_residuals<M: Minimal + Clone>(case: &Case<M>) -> [f64; 3] {
    let dae = IndexThree(case.mechanism.clone());
    let (y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    let mut res = vec![0.0; dae.dimension()];
    dae.residual(0.0, &y0, &yp0, &mut res);
    let nq = case.mechanism.nq();
    let size = |i: usize| {
        let r = if i < 2 * nq { i % nq } else { 0 };
        (y0[nq + r].abs() + yp0[r].abs())
            .max(yp0[nq + r].abs() * case.mechanism.mass(r))
            .max(1.0)
    };
    let block = |range: std::ops::Range<usize>| {
        range.map(|i| res[i].abs() / size(i)).fold(0.0f64, f64::max)
    };
    [
        block(0..nq),
        block(nq..2 * nq),
        block(2 * nq..dae.dimension()),
    ]
}

fn check_start<M: Minimal + Clone>(case: &Case<M>) {
    let m = &case.mechanism;
    let (nq, nc) = (m.nq(), m.nc());
    let (y0, yp0) = m.initial(&case.start.0, &case.start.1);
    let (q, v, lambda) = (&y0[..nq], &y0[nq..2 * nq], &y0[2 * nq..]);
    let a = &yp0[nq..2 * nq];
    // Positions on the constraints, velocities tangent (G v = 0), and the minimal ODE's
    // accelerations with the least-squares multipliers solve the momentum rows: the two
    // formulations give the same motion.
    let [kinematic, momentum, position] = start_residuals(case);
    let g = gradient_matrix(m, q);
    let gv = (&g * nalgebra::DVector::from_column_slice(v)).amax();
    println!(
        "{}: residuals {kinematic:.1e} (q' = v), {momentum:.1e} (momentum), {position:.1e} (g), |G v| {gv:.1e}",
        case.name
    );
    assert!(kinematic == 0.0, "{}: {kinematic}", case.name);
    assert!(momentum < 1e-13, "{}: momentum rows {momentum}", case.name);
    assert!(position < 1e-15, "{}: constraints {position}", case.name);
    assert!(gv < 1e-14, "{}: G v = {gv}", case.name);
    // The acceleration level from positions and velocities alone (the saddle-point system of
    // the constraints differentiated twice): the same accelerations and multipliers.
    let (a_saddle, lambda_saddle) = saddle_point(m, q, v);
    let scale_a = a.iter().fold(1.0f64, |s, x| s.max(x.abs()));
    let scale_l = lambda.iter().fold(1.0f64, |s, x| s.max(x.abs()));
    for j in 0..nq {
        assert!(
            (a[j] - a_saddle[j]).abs() < 1e-12 * scale_a,
            "{}: acceleration {j}: {} vs {}",
            case.name,
            a[j],
            a_saddle[j]
        );
    }
    for k in 0..nc {
        assert!(
            (lambda[k] - lambda_saddle[k]).abs() < 1e-12 * scale_l,
            "{}: multiplier {k}: {} vs {}",
            case.name,
            lambda[k],
            lambda_saddle[k]
        );
    }
}

#[test]
fn starts_are_consistent_at_every_level() {
    check_start(&slider_crank_case());
    check_start(&four_bar_case());
    check_start(&spherical_case());
}

#[test]
fn spherical_lagrange_equations_match_the_general_form() {
    // The closed-form equations against J^T M (J s'' + J' s') = J^T f with the hand-written
    // kinematics, at the start and at a few other states.
    for (s, sd) in [
        (SPHERICAL_START.0, SPHERICAL_START.1),
        ([0.7, 2.0], [1.5, -2.0]),
        ([2.2, -1.0], [-0.3, 4.0]),
    ] {
        let closed = SPHERICAL.lagrange(&s, &sd);
        let general = general_acceleration(&SPHERICAL, &s, &sd);
        for k in 0..2 {
            assert!(
                (closed[k] - general[k]).abs() < 1e-13 * (1.0 + closed[k].abs()),
                "{k}: {closed:?} vs {general:?}"
            );
        }
    }
}

fn check_matrices<M: Minimal + Clone>(case: &Case<M>) {
    let dae = IndexThree(case.mechanism.clone());
    let (y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    let mut worst = 0.0f64;
    for seed in [1, 2, 3] {
        let (t, y, yp) = matrix_check::perturbed(0.0, &y0, &yp0, seed);
        for c in [0.0, 1.0, 1e3] {
            // Central differences with a step of 1e-5 max(|y_j|, 0.1): truncation about 1e-10
            // of the row, round-off about 1e-11.
            let e = matrix_check::matrix_error(&dae, (t, &y, &yp), c, (1e-5, 0.1));
            worst = worst.max(e);
        }
    }
    let mass = matrix_check::check_mass_matrix(case.name, &dae, 0.0, &y0, &yp0);
    println!(
        "{}: iteration matrix {worst:.1e}, mass matrix {mass:.1e}",
        case.name
    );
    // Measured 1.6e-10, 2.5e-9, 1.4e-10 (slider crank, four-bar, spherical pendulum).
    assert!(worst < 1e-8, "{}: {worst}", case.name);
}

#[test]
fn iteration_and_mass_matrices_match_differences() {
    check_matrices(&slider_crank_case());
    check_matrices(&four_bar_case());
    check_matrices(&spherical_case());
}

/// Digits of positions and velocities at `1e-6` of each code (floors about 0.35 below the
/// measured values, which are in the comments and in docs/integrators.md).
fn check_floors<M: Minimal + Clone>(case: &Case<M>, floors: [(Code, f64); 5]) {
    for (code, floor) in floors {
        let o = run(case, code, 1e-6).unwrap_or_else(|e| panic!("{} {code:?}: {e}", case.name));
        let d = digits(&o.y, case.reference);
        println!(
            "{} {code:?} 1e-6: {d:.2} digits, {} steps, {} error-test and {} Newton failures, {} Jacobians",
            case.name, o.steps, o.error_failures, o.newton_failures, o.jacobians
        );
        assert!(d >= floor, "{} {code:?}: {d} digits", case.name);
    }
}

#[test]
fn slider_crank_floors_at_1e6() {
    // Measured: Radau 4.86, BDF Scale 0.34, BDF Exclude 1.65, BDF stabilised 2.77, Radau
    // stabilised 4.41.
    check_floors(
        &slider_crank_case(),
        [
            (Code::Radau, 4.5),
            (Code::BdfScale, 0.0),
            (Code::BdfExclude, 1.3),
            (Code::BdfStabilised, 2.4),
            (Code::RadauStabilised, 4.1),
        ],
    );
}

#[test]
fn four_bar_floors_at_1e6() {
    // Measured: Radau 5.09, BDF Scale 1.31, BDF Exclude 1.46, BDF stabilised 2.11, Radau
    // stabilised 4.13.
    check_floors(
        &four_bar_case(),
        [
            (Code::Radau, 4.7),
            (Code::BdfScale, 1.0),
            (Code::BdfExclude, 1.1),
            (Code::BdfStabilised, 1.8),
            (Code::RadauStabilised, 3.8),
        ],
    );
}

#[test]
fn spherical_pendulum_floors_at_1e6() {
    // Measured: Radau 5.46, BDF Scale 3.41, BDF Exclude 2.77, BDF stabilised 4.04, Radau
    // stabilised 5.93.
    check_floors(
        &spherical_case(),
        [
            (Code::Radau, 5.1),
            (Code::BdfScale, 3.0),
            (Code::BdfExclude, 2.4),
            (Code::BdfStabilised, 3.7),
            (Code::RadauStabilised, 5.6),
        ],
    );
}

#[test]
#[ignore]
fn references_recomputed() {
    fn check<M: Minimal + Clone>(case: &Case<M>) {
        let fine = case
            .mechanism
            .reference(&case.start.0, &case.start.1, case.t_end, 64_000);
        let coarse = case
            .mechanism
            .reference(&case.start.0, &case.start.1, case.t_end, 32_000);
        let agree = digits(&coarse, &fine);
        println!(
            "{}: 32 000 and 64 000 steps agree to {agree:.2} digits",
            case.name
        );
        assert!(agree > 10.0, "{}: {agree}", case.name);
        assert_eq!(fine, case.reference, "{}: the stored reference", case.name);
    }
    check(&slider_crank_case());
    check(&four_bar_case());
    check(&spherical_case());
}

/// Prints the table rows of `case` (steps, error-test and Newton failures, Jacobians, digits
/// of positions / of positions and velocities, ms) and returns the digits per code at 1e-4,
/// 1e-6, 1e-8 (minus infinity for a failed run).
fn table<M: Minimal + Clone>(case: &Case<M>) -> Vec<(Code, [f64; 3])> {
    let nq = case.mechanism.nq();
    let mut out = Vec::new();
    for code in CODES {
        let mut d = [f64::NEG_INFINITY; 3];
        for (k, tol) in [1e-4, 1e-6, 1e-8].into_iter().enumerate() {
            match run(case, code, tol) {
                Ok(o) => {
                    d[k] = digits(&o.y, case.reference);
                    println!(
                        "| {} | {code:?} | {tol:.0e} | {} | {} | {} | {} | {:.2} | {:.2} | {:.1} |",
                        case.name,
                        o.steps,
                        o.error_failures,
                        o.newton_failures,
                        o.jacobians,
                        digits(&o.y[..nq], &case.reference[..nq]),
                        d[k],
                        o.ms
                    );
                }
                Err(e) => println!("| {} | {code:?} | {tol:.0e} | failed: {e} |", case.name),
            }
        }
        out.push((code, d));
    }
    out
}

#[test]
#[ignore]
fn digits_grow_with_the_tolerance() {
    // Every code finishes at every tolerance and gains at least a digit from 1e-4 to 1e-8
    // (measured gains 0.9-4.1).
    println!("| mechanism | code | tol | steps | error-test failures | Newton failures | Jacobians | digits (q) | digits (q, v) | ms |");
    let mut all = table(&slider_crank_case());
    all.extend(table(&four_bar_case()));
    all.extend(table(&spherical_case()));
    for (code, [d4, _, d8]) in all {
        assert!(d8.is_finite() && d4.is_finite(), "{code:?} failed");
        assert!(d8 >= d4 + 0.8, "{code:?}: {d4} at 1e-4, {d8} at 1e-8");
    }
}

/// The minimal ODE `s' = w, w' = a(s, w)` as an implicit DAE, for comparing the codes on the
/// same motion without constraints (its iteration matrix by central differences of `a`, step
/// `1e-6 max(|y_j|, 1)`: good to about 1e-10, ample for Newton).
#[derive(Clone)]
struct MinimalOde<M>(M);

impl<M: Minimal> ImplicitDae for MinimalOde<M> {
    fn dimension(&self) -> usize {
        2 * self.0.ns()
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let ns = self.0.ns();
        let a = self.0.minimal_acceleration(&y[..ns], &y[ns..]);
        for k in 0..ns {
            out[k] = yp[k] - y[ns + k];
            out[ns + k] = yp[ns + k] - a[k];
        }
    }
    fn iteration_matrix<S: dpc_core::MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let n = self.dimension();
        let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let h = 1e-6 * y[j].abs().max(1.0);
            let (mut y1, mut y2) = (y.to_vec(), y.to_vec());
            y1[j] += h;
            y2[j] -= h;
            self.residual(t, &y1, yp, &mut up);
            self.residual(t, &y2, yp, &mut down);
            for i in 0..n {
                out.add(i, j, (up[i] - down[i]) / (2.0 * h));
            }
            out.add(j, j, c);
        }
    }
}

#[test]
#[ignore]
fn minimal_odes_by_the_same_codes() {
    // The BDF and Radau on the minimal ODEs, scored like the index-3 forms (the ODE's end state
    // mapped to positions and velocities): what the codes reach on the motion itself.
    fn odes<M: Minimal + Clone>(case: &Case<M>) {
        let ns = case.mechanism.ns();
        let y0: Vec<f64> = case.start.0.iter().chain(&case.start.1).copied().collect();
        let a0 = case
            .mechanism
            .minimal_acceleration(&case.start.0, &case.start.1);
        let yp0: Vec<f64> = case.start.1.iter().copied().chain(a0).collect();
        let score = |y: &[f64]| {
            let [q, qd, _] = case
                .mechanism
                .kinematics(&y[..ns], &y[ns..], &vec![0.0; ns]);
            let qv: Vec<f64> = q.into_iter().chain(qd).collect();
            digits(&qv, case.reference)
        };
        for tol in [1e-4, 1e-6, 1e-8] {
            let ode = MinimalOde(case.mechanism.clone());
            let o = bdf::Options::with_tolerances(tol, tol);
            let (yb, sb) = bdf_run(ode.clone(), o, (&y0, &yp0), case.t_end).unwrap();
            let o = radau::Options::with_tolerances(tol, tol);
            let (yr, sr) = radau_run(ode, o, (&y0, &yp0), case.t_end).unwrap();
            println!(
                "| {} | {tol:.0e} | {:.2} ({} steps) | {:.2} ({} steps) |",
                case.name,
                score(&yb),
                sb.steps,
                score(&yr),
                sr.steps
            );
        }
    }
    println!("| mechanism | tol | BDF on the ODE | Radau on the ODE |");
    odes(&slider_crank_case());
    odes(&four_bar_case());
    odes(&spherical_case());
}

/// What every code of [`CODES`] does from `(y0, y0')` of the slider crank's index-3 form at
/// `rtol = atol = 1e-6`: the constraint its constructor names as missed
/// (`InconsistentConstraint`), or `None` when it runs to the end.
fn refusals(y0: &[f64], yp0: &[f64]) -> Vec<(Code, Option<String>)> {
    const MISSED: &str = "the initial values miss ";
    let case = slider_crank_case();
    CODES
        .iter()
        .map(|&code| match run_from(&case, code, 1e-6, (y0, yp0)) {
            Ok(_) => (code, None),
            Err(m) if m.starts_with(MISSED) => {
                let equation = m[MISSED.len()..].split(": its residual").next().unwrap();
                (code, Some(equation.to_string()))
            }
            Err(m) => panic!("{code:?}: {m}"),
        })
        .collect()
}

#[test]
fn a_position_off_its_constraint_is_refused_by_every_code() {
    // The slider crank's crank centre moved by 1e-3 along x, off the crank's pin to the ground
    // (constraint 0) and its pin to the rod (constraint 2): each code refuses the start when
    // it is built, naming one of those two constraints as the model names them.
    let case = slider_crank_case();
    let (mut y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    y0[0] += 1e-3;
    for (code, refused) in refusals(&y0, &yp0) {
        let equation = refused.unwrap_or_else(|| panic!("{code:?} ran"));
        assert!(
            ["constraint 0", "constraint 2"].contains(&equation.as_str()),
            "{code:?}: {equation}"
        );
    }
    // The typed errors carry the residual and the bound.
    let dae = IndexThree(case.mechanism.clone());
    let opts = radau::Options {
        index: dae.index(),
        ..radau::Options::with_tolerances(1e-6, 1e-6)
    };
    match Radau::new(dae.clone(), FaerDenseLu::new(23), opts, 0.0, &y0, &yp0) {
        Err(radau::RadauError::InconsistentConstraint {
            t, residual, bound, ..
        }) => {
            assert_eq!(t, 0.0);
            assert!((residual.abs() - 1e-3).abs() < 1e-9, "{residual}");
            assert!(bound > 0.0 && bound < 1e-4, "{bound}");
        }
        other => panic!("{:?}", other.err()),
    }
    let opts = bdf::Options {
        index: dae.index(),
        ..bdf::Options::with_tolerances(1e-6, 1e-6)
    };
    match Bdf::new(dae, FaerDenseLu::new(23), opts, 0.0, &y0, &yp0) {
        Err(bdf::BdfError::InconsistentConstraint {
            residual, bound, ..
        }) => {
            assert!((residual.abs() - 1e-3).abs() < 1e-9, "{residual}");
            assert!(bound > 0.0 && bound < 1e-4, "{bound}");
        }
        other => panic!("{:?}", other.err()),
    }
}

#[test]
fn a_velocity_off_its_hidden_constraint_is_refused_by_every_code() {
    // The crank centre's velocity (and its position's derivative with it) moved: the
    // positions satisfy their constraints, the velocities do not satisfy the constraints'
    // derivatives. By 1e-2 every code, on the index-3 form as on the stabilised one, refuses
    // the start and names a hidden velocity constraint (they used to run the index-3 form to
    // the solution of other initial values without an error); by 1e-8, a hundredth of the
    // tolerance, every code runs.
    let case = slider_crank_case();
    let (y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    let moved = |by: f64| {
        let (mut y, mut yp) = (y0.clone(), yp0.clone());
        y[8] += by;
        yp[0] += by;
        (y, yp)
    };
    let (y, yp) = moved(1e-2);
    for (code, refused) in refusals(&y, &yp) {
        let equation = refused.unwrap_or_else(|| panic!("{code:?} ran"));
        assert!(
            equation.starts_with("the hidden velocity constraint of constraint"),
            "{code:?}: {equation}"
        );
    }
    let (y, yp) = moved(1e-8);
    for (code, refused) in refusals(&y, &yp) {
        assert_eq!(refused, None, "{code:?}");
    }
}

#[test]
fn radau_stabilised_is_the_documented_recipe_in_one_call() {
    // `Radau::stabilised` against the recipe written out (`Stabilised::detect`, `extend`,
    // `Stabilised::index`, `FaerLu::for_dae`): the same steps and the same end values, bit for
    // bit; the DAE's unknowns first, then one `mu` per position constraint.
    use dpc_core::linear_solver::FaerLu;
    let case = slider_crank_case();
    let (y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    let opts = radau::Options::with_tolerances(1e-6, 1e-6);
    let mut one = Radau::stabilised(
        IndexThree(case.mechanism.clone()),
        opts.clone(),
        0.0,
        &y0,
        &yp0,
    )
    .unwrap();
    let s = Stabilised::detect(IndexThree(case.mechanism.clone()), 0.0, &y0, &yp0).unwrap();
    let (y, yp) = s.extend(&y0, &yp0);
    let ls = FaerLu::for_dae(&s);
    let (index, constraints) = (s.index(), s.constraint_rows().len());
    let mut recipe = Radau::new(s, ls, radau::Options { index, ..opts }, 0.0, &y, &yp).unwrap();
    assert_eq!(one.y().len(), y0.len() + constraints);
    let (mut a, mut b) = (vec![0.0; y.len()], vec![0.0; y.len()]);
    one.solve_to(case.t_end, &mut a, None).unwrap();
    recipe.solve_to(case.t_end, &mut b, None).unwrap();
    assert_eq!(a, b);
    assert_eq!(one.stats(), recipe.stats());
    // A start of the wrong length is the structure's error, named as such.
    let e = Radau::stabilised(
        IndexThree(case.mechanism.clone()),
        radau::Options::default(),
        0.0,
        &y0[1..],
        &yp0,
    )
    .err();
    assert!(matches!(e, Some(radau::RadauError::Structure(_))), "{e:?}");
}

#[test]
fn bdf_stabilised_is_the_documented_recipe_in_one_call() {
    // `Bdf::stabilised`, the BDF's counterpart, against the same recipe: bit for bit.
    use dpc_core::linear_solver::FaerLu;
    let case = slider_crank_case();
    let (y0, yp0) = case.mechanism.initial(&case.start.0, &case.start.1);
    let opts = bdf::Options::with_tolerances(1e-6, 1e-6);
    let dae = || IndexThree(case.mechanism.clone());
    let mut one = Bdf::stabilised(dae(), opts.clone(), 0.0, &y0, &yp0).unwrap();
    let s = Stabilised::detect(dae(), 0.0, &y0, &yp0).unwrap();
    let (y, yp) = s.extend(&y0, &yp0);
    let ls = FaerLu::for_dae(&s);
    let (index, constraints) = (s.index(), s.constraint_rows().len());
    let mut recipe = Bdf::new(s, ls, bdf::Options { index, ..opts }, 0.0, &y, &yp).unwrap();
    assert_eq!(one.y().len(), y0.len() + constraints);
    let (mut a, mut b) = (vec![0.0; y.len()], vec![0.0; y.len()]);
    one.solve_to(case.t_end, &mut a, None).unwrap();
    recipe.solve_to(case.t_end, &mut b, None).unwrap();
    assert_eq!(a, b);
    assert_eq!(one.stats(), recipe.stats());
    let e = Bdf::stabilised(dae(), bdf::Options::default(), 0.0, &y0[1..], &yp0).err();
    assert!(matches!(e, Some(bdf::BdfError::Structure(_))), "{e:?}");
}
