//! diffsol's own versions of SUNDIALS' banded examples, run as diffsol's benchmarks run them,
//! beside dpc-core's BDF on the repository's versions of the same problems.
//!
//! diffsol 0.19 ships `idaHeat2D_bnd` and `idaFoodWeb_bnd` as test models
//! (`diffsol::ode_equations::test_models::{heat2d, foodweb}`) and benchmarks them (its
//! `benches/ode_solvers.rs`) with its BDF and faer's sparse LU: `problem.bdf::<FaerSparseLU>()`
//! (which first makes the algebraic unknowns consistent) and `solve_dense` at the problem's
//! output times, at the problem's own tolerances (heat: `rtol = atol = 1e-7` to `t = 10.24`;
//! food web on a 20 x 20 grid, 800 unknowns: `rtol = atol = 1e-5` to `t = 1`). Here they are
//! timed that way, and dpc-core's BDF (`FaerLu::for_dae`, which takes the band LU there)
//! integrates `dpc-core/tests/common/heat2d.rs` and `food_web.rs` (the same equations written
//! anew from SUNDIALS' examples; the heat equation from its consistent start, the food web from
//! the example's predators at `1e5`, made consistent by `dpc_core::bdf::consistent_initial_values`
//! inside the timed run as diffsol's `bdf()` does) through the same output times at the same
//! tolerances. Both runs' values at a common time are scored against the
//! repository's references (heat: the exact semi-discrete solution at `t = 0.16`, the 64
//! interior points; food web: every unknown at `t = 1`).
//!
//! ```sh
//! cd bench/diffsol_peer && cargo run --release --bin diffsol-own [REPEATS]
//! ```
//!
//! Times are the median of `REPEATS` (default 11) solves each, the two codes alternating.

#[path = "../../../dpc-core/tests/common/food_web.rs"]
mod food_web;
#[path = "../../../dpc-core/tests/common/heat2d.rs"]
mod heat2d;

use diffsol::ode_equations::test_models::{foodweb::foodweb_problem, heat2d::heat2d_problem};
use diffsol::{FaerSparseLU, FaerSparseMat, OdeSolverMethod, Vector as _};
use dpc_core::bdf::{Bdf, Options};
use dpc_core::linear_solver::FaerLu;
use dpc_core::ImplicitDae;
use std::time::Instant;

/// Significant correct digits of `y[k]` over `components` against `reference`.
fn scd(y: &[f64], reference: &[f64], components: &[usize]) -> f64 {
    -components
        .iter()
        .map(|&k| ((y[k] - reference[k]) / reference[k]).abs())
        .fold(0.0f64, f64::max)
        .log10()
}

/// One code's run: the values at each output time, steps, error-test failures, seconds.
struct Run {
    values: Vec<Vec<f64>>,
    steps: usize,
    failures: usize,
    seconds: f64,
}

/// dpc-core's BDF on `dae` from `(y0, y0')` through `times` at `rtol = atol = tol`.
/// With `initialise`, the algebraic unknowns of `y0` (and the derivatives of the differential
/// ones) are first made consistent (`dpc_core::bdf::consistent_initial_values`, timed).
fn dpc<D: ImplicitDae>(
    dae: D,
    (y0, yp0): (&[f64], &[f64]),
    times: &[f64],
    tol: f64,
    initialise: bool,
) -> Run {
    let clock = Instant::now();
    let mut ls = FaerLu::for_dae(&dae);
    let n = dae.dimension();
    let opts = Options::with_tolerances(tol, tol);
    let (mut y0, mut yp0) = (y0.to_vec(), yp0.to_vec());
    if initialise {
        dpc_core::bdf::consistent_initial_values(&dae, &mut ls, &opts, 0.0, &mut y0, &mut yp0)
            .unwrap();
    }
    let (y0, yp0) = (&y0[..], &yp0[..]);
    let mut b = Bdf::new(dae, ls, opts, 0.0, y0, yp0).unwrap();
    let mut values = Vec::new();
    for &t in times {
        let mut y = vec![0.0; n];
        if t > 0.0 {
            b.solve_to(t, &mut y, None).unwrap();
        } else {
            y.copy_from_slice(y0);
        }
        values.push(y);
    }
    let s = b.stats();
    Run {
        values,
        steps: s.steps,
        failures: s.error_test_failures,
        seconds: clock.elapsed().as_secs_f64(),
    }
}

/// diffsol's BDF with faer's sparse LU on its own problem, as its benchmark runs it
/// (`solve_dense` at the problem's output times; the values are its output function's), then,
/// untimed, the same solver's state at `scored_at` for the score.
macro_rules! diffsol_run {
    ($problem:expr, $scored_at:expr) => {{
        let (problem, soln) = $problem;
        let times: Vec<f64> = soln.solution_points.iter().map(|p| p.t).collect();
        let clock = Instant::now();
        let mut s = problem.bdf::<FaerSparseLU<f64>>().unwrap();
        let (dense, _) = s.solve_dense(&times).unwrap();
        let seconds = clock.elapsed().as_secs_f64();
        std::hint::black_box(dense);
        let st = s.get_statistics();
        let (steps, failures) = (st.number_of_steps, st.number_of_error_test_failures);
        let mut s = problem.bdf::<FaerSparseLU<f64>>().unwrap();
        s.set_stop_time($scored_at).unwrap();
        while !matches!(
            s.step().unwrap(),
            diffsol::OdeSolverStopReason::TstopReached
        ) {}
        let y = &s.state().y;
        let values = vec![(0..y.len()).map(|i| y.get_index(i)).collect()];
        (
            Run {
                values,
                steps,
                failures,
                seconds,
            },
            times,
        )
    }};
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(11);
    println!("| problem | code | steps | error-test failures | scd | ms (median of {repeats}) | dpc / diffsol |");
    println!("|---|---|---|---|---|---|---|");
    // The heat equation, 10 x 10.
    {
        let (y0, yp0) = heat2d::Heat2d::initial();
        let exact = heat2d::heat_exact(0.16);
        let scored = heat2d::heat_scored();
        let (mut td, mut tp) = (Vec::new(), Vec::new());
        let (mut last_d, mut last_p) = (None, None);
        for _ in 0..repeats {
            let (r, times) = diffsol_run!(heat2d_problem::<FaerSparseMat<f64>, 10>(1), 0.16);
            td.push(r.seconds);
            last_d = Some((r, times.clone()));
            let p = dpc(heat2d::Heat2d, (&y0, &yp0), &times, 1e-7, false);
            tp.push(p.seconds);
            last_p = Some(p);
        }
        let ((d, times), p) = (last_d.unwrap(), last_p.unwrap());
        let at = times.iter().position(|&t| t == 0.16).unwrap();
        let (md, mp) = (median(td) * 1e3, median(tp) * 1e3);
        println!(
            "| heat, idaHeat2D_bnd 10 x 10 (1e-7, to 10.24; scored at 0.16) | diffsol 0.19 BDF, faer sparse LU | {} | {} | {:.2} | {md:.3} | |",
            d.steps,
            d.failures,
            scd(&d.values[0], &exact, &scored)
        );
        println!(
            "| same | dpc BDF, FaerLu::for_dae | {} | {} | {:.2} | {mp:.3} | {:.2} |",
            p.steps,
            p.failures,
            scd(&p.values[at], &exact, &scored),
            mp / md
        );
    }
    // The food web, 20 x 20.
    {
        let web = food_web::FoodWeb::new();
        // The example's start: the predators at 1e5, made consistent by the integrator's
        // initialisation, as diffsol's `bdf()` does.
        let (mut y0, mut yp0) = web.initial();
        for k in (1..y0.len()).step_by(2) {
            y0[k] = 1e5;
        }
        yp0.fill(0.0);
        let n = food_web::WEB_N;
        let reference = &food_web::WEB_REF[n..];
        let all: Vec<usize> = (0..n).collect();
        let (mut td, mut tp) = (Vec::new(), Vec::new());
        let (mut last_d, mut last_p) = (None, None);
        for _ in 0..repeats {
            let (r, times) = diffsol_run!(
                foodweb_problem::<FaerSparseMat<f64>, 20>(1),
                food_web::WEB_T_END
            );
            td.push(r.seconds);
            last_d = Some((r, times.clone()));
            let p = dpc(web.clone(), (&y0, &yp0), &times, 1e-5, true);
            tp.push(p.seconds);
            last_p = Some(p);
        }
        let ((d, times), p) = (last_d.unwrap(), last_p.unwrap());
        let at = times.len() - 1;
        assert_eq!(times[at], food_web::WEB_T_END);
        let (md, mp) = (median(td) * 1e3, median(tp) * 1e3);
        println!(
            "| food web, idaFoodWeb_bnd 20 x 20 (1e-5, to 1; scored at 1) | diffsol 0.19 BDF, faer sparse LU | {} | {} | {:.2} | {md:.3} | |",
            d.steps,
            d.failures,
            scd(&d.values[0], reference, &all)
        );
        println!(
            "| same | dpc BDF, FaerLu::for_dae | {} | {} | {:.2} | {mp:.3} | {:.2} |",
            p.steps,
            p.failures,
            scd(&p.values[at], reference, &all),
            mp / md
        );
    }
}
