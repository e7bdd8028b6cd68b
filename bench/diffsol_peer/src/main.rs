//! dpc-core's BDF side by side with the BDF of the Rust crate diffsol on the same equations:
//! the Test Set's transistor amplifier (index 1, singular non-diagonal mass matrix) and
//! Robertson (index 1). Per tolerance: accepted steps, error-test failures, Newton failures,
//! Jacobian (iteration-matrix) setups, significant correct digits against the Test Set's
//! reference and the mean time per solve.
//!
//! ```sh
//! bash bench/diffsol_peer.sh            # or, from bench/diffsol_peer:
//! cargo run --release
//! ```
//!
//! Both codes get the problem in mass-matrix form `M y' = phi(t, y)` with the analytic
//! Jacobian `d phi / d y` (dpc-core as `F = M y' - phi` with `dF/dy + c dF/dy'`, diffsol as
//! Jacobian-vector product and mass-matrix product closures on dense nalgebra matrices), the
//! same initial values, `rtol` and `atol`, and integrate to the Test Set's end time, stopping
//! there exactly.

#[path = "../../../dpc-core/tests/common/bdf_problems.rs"]
mod bdf_problems;
#[path = "../../../dpc-core/tests/common/testset_index1.rs"]
mod testset_index1;

use bdf_problems::{robertson_atol, Robertson, ROBERTSON_REF, ROBERTSON_T_END};
use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod};
use dpc_core::bdf::{Bdf, Options, Tolerance};
use dpc_core::linear_solver::NalgebraLu;
use dpc_core::ImplicitDae;
use std::time::Instant;
use testset_index1::{TransistorAmplifier, TRANSAMP_REF, TRANSAMP_T_END};

/// One run's counters.
#[derive(Debug, Clone, Copy)]
struct Run {
    steps: usize,
    error_test_failures: usize,
    newton_failures: usize,
    jacobians: usize,
    scd: f64,
    ms: f64,
}

/// Significant correct digits over all components (Test Set's scd).
fn scd(y: &[f64], reference: &[f64]) -> f64 {
    -y.iter()
        .zip(reference)
        .map(|(a, r)| (a - r).abs() / r.abs())
        .fold(0.0, f64::max)
        .log10()
}

/// Time `f` as the mean over repetitions filling at least 0.3 s (at least 3).
fn timed<F: FnMut() -> Option<Run>>(mut f: F) -> Option<Run> {
    let mut run = f()?;
    let start = Instant::now();
    let mut reps = 0u32;
    while reps < 3 || start.elapsed().as_secs_f64() < 0.3 {
        f()?;
        reps += 1;
    }
    run.ms = start.elapsed().as_secs_f64() * 1e3 / f64::from(reps);
    Some(run)
}

fn dpc<D: ImplicitDae, const N: usize>(
    dae: D,
    y0: &[f64; N],
    yp0: &[f64; N],
    opts: Options,
    t_end: f64,
    reference: &[f64],
) -> Option<Run> {
    let mut bdf = Bdf::new(dae, NalgebraLu::<N>::new(), opts, 0.0, y0, yp0).ok()?;
    bdf.set_stop_time(t_end).ok()?;
    let mut y = [0.0; N];
    if let Err(e) = bdf.solve_to(t_end, &mut y, None) {
        eprintln!("dpc-core: {e}");
        return None;
    }
    let s = bdf.stats();
    Some(Run {
        steps: s.steps,
        error_test_failures: s.error_test_failures,
        newton_failures: s.newton_failures,
        jacobians: s.jacobian_evaluations,
        scd: scd(&y, reference),
        ms: 0.0,
    })
}

type M = NalgebraMat<f64>;

/// Step diffsol's BDF to `t_end` exactly and score the result.
fn finish<'a, Eqn, S>(mut solver: S, t_end: f64, reference: &[f64]) -> Option<Run>
where
    Eqn: diffsol::OdeEquationsImplicit<T = f64> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
    Eqn::V: diffsol::Vector<T = f64>,
{
    use diffsol::{OdeSolverConfig as _, Vector as _};
    // diffsol's default step limit (5 000 per solve) is below what the transistor amplifier
    // needs at tight tolerances; dpc-core allows 100 000 per call.
    *solver.config_mut().as_base_mut().maximum_number_timesteps = 1_000_000;
    solver.set_stop_time(t_end).ok()?;
    loop {
        match solver.step() {
            Ok(diffsol::OdeSolverStopReason::TstopReached) => break,
            Ok(_) => {}
            Err(e) => {
                eprintln!("diffsol: {e}");
                return None;
            }
        }
    }
    let y: Vec<f64> = (0..reference.len())
        .map(|i| solver.state().y.get_index(i))
        .collect();
    let s = solver.get_statistics();
    Some(Run {
        steps: s.number_of_steps,
        error_test_failures: s.number_of_error_test_failures,
        newton_failures: s.number_of_nonlinear_solver_fails,
        jacobians: s.number_of_linear_solver_setups,
        scd: scd(&y, reference),
        ms: 0.0,
    })
}

fn diffsol_transamp(tol: f64) -> Option<Run> {
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol([tol; 8])
        .rhs_implicit(
            |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
                out.copy_from_slice(&TransistorAmplifier::phi(t, y));
            },
            |y: &[f64], _p: &[f64], _t: f64, v: &[f64], out: &mut [f64]| {
                out.fill(0.0);
                for (r, c, a) in TransistorAmplifier::phi_jacobian(y) {
                    out[r] += a * v[c];
                }
            },
        )
        .mass(
            |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                for o in out.iter_mut() {
                    *o *= beta;
                }
                for (r, c, a) in TransistorAmplifier::mass_entries() {
                    out[r] += a * v[c];
                }
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| {
                y.copy_from_slice(&TransistorAmplifier::initial().0);
            },
            8,
        )
        .build()
        .ok()?;
    let solver = match problem.bdf::<NalgebraLU<f64>>() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("diffsol: {e}");
            return None;
        }
    };
    finish(solver, TRANSAMP_T_END, &TRANSAMP_REF)
}

fn diffsol_robertson(rtol: f64) -> Option<Run> {
    let atol = robertson_atol(rtol);
    let problem = OdeBuilder::<M>::new()
        .rtol(rtol)
        .atol([atol[0], atol[1], atol[2]])
        .rhs_implicit(
            |y: &[f64], _p: &[f64], _t: f64, out: &mut [f64]| {
                out[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
                out[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1];
                out[2] = 1.0 - y[0] - y[1] - y[2];
            },
            |y: &[f64], _p: &[f64], _t: f64, v: &[f64], out: &mut [f64]| {
                out[0] = -0.04 * v[0] + 1e4 * (v[1] * y[2] + y[1] * v[2]);
                out[1] = 0.04 * v[0] - 1e4 * (v[1] * y[2] + y[1] * v[2]) - 6e7 * y[1] * v[1];
                out[2] = -v[0] - v[1] - v[2];
            },
        )
        .mass(
            |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                out[0] = v[0] + beta * out[0];
                out[1] = v[1] + beta * out[1];
                out[2] *= beta;
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| {
                y.copy_from_slice(&[1.0, 0.0, 0.0]);
            },
            3,
        )
        .build()
        .ok()?;
    let solver = problem.bdf::<NalgebraLU<f64>>().ok()?;
    finish(solver, ROBERTSON_T_END, &ROBERTSON_REF)
}

fn row(problem: &str, tol: f64, code: &str, r: Option<Run>) {
    match r {
        Some(r) => println!(
            "| {problem} | {tol:.0e} | {code} | {} | {} | {} | {} | {:.2} | {:.3} |",
            r.steps, r.error_test_failures, r.newton_failures, r.jacobians, r.scd, r.ms
        ),
        None => println!("| {problem} | {tol:.0e} | {code} | failed | | | | | |"),
    }
}

fn main() {
    println!(
        "| problem | rtol | code | steps | error-test failures | Newton failures | Jacobians | scd | time [ms] |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for k in [4, 6, 8] {
        let tol = 10f64.powi(-k);
        let (y0, yp0) = TransistorAmplifier::initial();
        let d = timed(|| {
            dpc(
                TransistorAmplifier,
                &y0,
                &yp0,
                Options::with_tolerances(tol, tol),
                TRANSAMP_T_END,
                &TRANSAMP_REF,
            )
        });
        row("transistor amplifier", tol, "dpc-core BDF", d);
        row(
            "transistor amplifier",
            tol,
            "diffsol BDF",
            timed(|| diffsol_transamp(tol)),
        );
    }
    for k in [4, 6, 8] {
        let rtol = 10f64.powi(-k);
        let opts = Options {
            rtol: Tolerance::Scalar(rtol),
            atol: Tolerance::Vector(robertson_atol(rtol)),
            ..Options::default()
        };
        let d = timed(|| {
            dpc(
                Robertson,
                &[1.0, 0.0, 0.0],
                &[-0.04, 0.04, 0.0],
                opts.clone(),
                ROBERTSON_T_END,
                &ROBERTSON_REF,
            )
        });
        row("Robertson (t=1e11)", rtol, "dpc-core BDF", d);
        row(
            "Robertson (t=1e11)",
            rtol,
            "diffsol BDF",
            timed(|| diffsol_robertson(rtol)),
        );
    }
}
