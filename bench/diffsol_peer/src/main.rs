//! The BDF of the Rust crate diffsol (0.19, dense nalgebra LU but for the sparse faer LU of the
//! Medical Akzo Nobel problem, mass-matrix form) on the problems of dpc-core's work-precision
//! example: diffsol's rows of the peer table that `bench/peers.sh` merges with dpc-core's and
//! SUNDIALS IDA's (same row format, sort keys, scoring and timing, from
//! `dpc-core/tests/common/peer_table.rs`).
//!
//! ```sh
//! bash bench/peers.sh diffsol           # or, from bench/diffsol_peer:
//! cargo run --release
//! cargo run --release -- 1.1 OREGO      # rtol = atol = 1.1e-k, the rows of one problem
//! ```
//!
//! diffsol takes `M y' = phi(t, y)` with a constant mass matrix `M`. Robertson, the transistor
//! amplifier, the chemical Akzo Nobel problem (`M = diag(1, 1, 1, 1, 1, 0)`) and HIRES (an ODE,
//! no mass matrix) are written out with their analytic Jacobians. Ascher and Petzold's index-2
//! problem has no row: its mass matrix is constant, but diffsol's initialisation and error test
//! fail on index 2 as on the stabilised mechanisms (below). The pendulum, Andrews' mechanism
//! and the car axis (index 3, and the stabilised index-2 forms of `dpc_core::stabilised`) are
//! given through their dpc-core residual `F(t, y, y') = M y' - phi(t, y)`: `phi = -F(t, y, 0)`,
//! `M` from the iteration matrix (`dF/dy + c dF/dy'` at `c = 1` minus `c = 0`) and
//! `d phi / d y = -dF/dy` (the iteration matrix at `c = 0`, cached per point). For these diffsol
//! is run twice: as its API intends (`problem.bdf()`, which first makes the algebraic unknowns
//! consistent by solving the algebraic rows for them), and from the Test Set's consistent
//! `(y0, y0')` given to an uninitialised state (`OdeSolverState::new_without_initialise`).
//!
//! diffsol 0.19 solves none of these higher-index problems: its initialisation solves the
//! algebraic rows (zero rows of `M`) for the algebraic unknowns, a singular system when the
//! constraints do not contain the multipliers (index 2 and 3: "LU solve failed"), and its error
//! test takes every unknown at its plain weight (there is no way to exclude or scale the
//! unknowns of index 2 and 3, as IDA's `suppressalg` or RADAU5's index scaling do), so that
//! from the given consistent values the steps shrink until they fail.
//!
//! The Test Set's NAND gate (row 12 of dpc-core's table) has no row here: its capacitance
//! matrix `C(y)` depends on the state, which diffsol's constant mass matrix cannot express. The
//! charge pump (row 14) has a constant mass matrix and is run both ways, with the fixture's
//! exact Jacobian and the Test Set driver's tolerances, from corner to corner of its input;
//! it is of index 2 (the current `y9`, which jumps where the gate charge changes branch at
//! `t = 50.1 ns`), and diffsol fails on it as on the other index-2 problems.
//!
//! The Test Set's water tube system (row 15) has a constant diagonal mass matrix and is run
//! both ways as well, with the fixture's exact Jacobian and the Test Set driver's tolerances
//! (`1e6 tol` on the pressures). diffsol's initialisation fails on it as on the other index-2
//! problems (the algebraic rows do not contain the eleven pressures of index 2); from the
//! consistent `(y0, y0')` it solves it, with those pressures in its error test at their plain
//! weight (which the driver's `atol` on the pressures, about `10 tol` relative, makes loose).
//!
//! The Test Set's wheelset (row 16 of dpc-core's table) has no row here: its mass matrix holds
//! `cos(phi)` and `sin(phi)` of the roll angle, which a constant mass matrix cannot express.
//!
//! The Test Set's two bit adding unit (row 17; index 1, 350 unknowns, `M = diag(I, 0)`) is run
//! both ways at 1e-4 and 1e-6 with the fixture's exact Jacobian entries: diffsol's
//! initialisation fails on it ("LU solve failed"); from the consistent `(y0, y0')` it runs at
//! 1e-4. At 1e-8 dpc-core's BDF and IDA fail, and it is not run.
//!
//! SUNDIALS' dense example `idaSlCrank_dns` (row 24; `dpc-core/tests/common/ida_slider_crank.rs`,
//! the GGL form with the constant mass matrix `diag(1, 1, 1, J1, m2, J2, 0, 0, 0, 0)`) is run
//! both ways through its dpc-core residual, as the mechanisms above, scored on the six
//! positions and velocities; its `lambda, mu` (index 2) stay in diffsol's error test.
//!
//! The Test Set's Medical Akzo Nobel problem (row 28; `dpc-core/tests/common/medakzo.rs`, an
//! ODE of 400 unknowns with a band Jacobian) is given as an ODE without mass matrix as the stiff
//! ODEs below, but in faer's sparse matrix with faer's sparse LU (`FaerSparseMat`,
//! `FaerSparseLU`) rather than the dense nalgebra LU of the other rows, so that diffsol does not
//! factor a dense 400 x 400 matrix; it is restarted at the input switch `t = 5` as dpc's and
//! IDA's rows.
//!
//! The Test Set's stiff ODEs (rows 18-21: Van der Pol with `eps = 1e-6`, OREGO, Pollution, the
//! ring modulator; `dpc-core/tests/common/stiff_odes.rs`) are given as diffsol intends an ODE:
//! `y' = f(t, y)` without a mass matrix, with the fixtures' exact Jacobians `df/dy`, at
//! `rtol = atol = tol`.

#[path = "../../../dpc-core/tests/common/bdf_problems.rs"]
mod bdf_problems;
#[path = "../../../dpc-core/tests/common/ida_slider_crank.rs"]
mod ida_slider_crank;
#[path = "../../../dpc-core/tests/common/medakzo.rs"]
mod medakzo;
#[path = "../../../dpc-core/tests/common/peer_table.rs"]
mod peer_table;
#[path = "../../../dpc-core/tests/common/pump.rs"]
mod pump;
#[path = "../../../dpc-core/tests/common/standard_dae.rs"]
mod standard_dae;
#[path = "../../../dpc-core/tests/common/stiff_odes.rs"]
mod stiff_odes;
#[path = "../../../dpc-core/tests/common/testset_index1.rs"]
mod testset_index1;
#[path = "../../../dpc-core/tests/common/testset_index3.rs"]
mod testset_index3;
#[path = "../../../dpc-core/tests/common/two_bit_adder.rs"]
mod two_bit_adder;
#[path = "../../../dpc-core/tests/common/water_tube.rs"]
mod water_tube;

use bdf_problems::{robertson_atol, Pendulum, PENDULUM_T, ROBERTSON_REF, ROBERTSON_T_END, THETA0};
use diffsol::{
    BdfState, NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverProblem,
    OdeSolverState,
};
use dpc_core::ImplicitDae;
use nalgebra::DMatrix;
use peer_table::Run;
use standard_dae::{ChemAkzo, Hires, AKZO_REF, AKZO_T_END, HIRES_REF, HIRES_T_END};
use std::cell::RefCell;
use testset_index1::{TransistorAmplifier, TRANSAMP_REF, TRANSAMP_T_END};
use testset_index3::*;

type M = NalgebraMat<f64>;

/// Steps diffsol's BDF to `t_end` exactly and returns its counters and end state.
fn finish<'a, Eqn, S>(solver: S, t_end: f64, n: usize) -> Result<Run, String>
where
    Eqn: diffsol::OdeEquationsImplicit<T = f64> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
    Eqn::V: diffsol::Vector<T = f64>,
{
    finish_breaks(solver, &[t_end], n)
}

/// Steps diffsol's BDF through the stop times `breaks` (the last is the end), continuing
/// across each, and returns its counters and end state.
fn finish_breaks<'a, Eqn, S>(mut solver: S, breaks: &[f64], n: usize) -> Result<Run, String>
where
    Eqn: diffsol::OdeEquationsImplicit<T = f64> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
    Eqn::V: diffsol::Vector<T = f64>,
{
    use diffsol::{OdeSolverConfig as _, Vector as _};
    // diffsol's default step limit (5 000 per solve) is below what the transistor amplifier
    // needs at tight tolerances; dpc-core allows 100 000 per call.
    *solver.config_mut().as_base_mut().maximum_number_timesteps = 1_000_000;
    for &tb in breaks {
        solver.set_stop_time(tb).map_err(|e| e.to_string())?;
        loop {
            match solver.step() {
                Ok(diffsol::OdeSolverStopReason::TstopReached) => break,
                Ok(_) => {}
                // diffsol's errors name the time they occurred at.
                Err(e) => return Err(e.to_string()),
            }
        }
    }
    let y = (0..n).map(|i| solver.state().y.get_index(i)).collect();
    let s = solver.get_statistics();
    Ok(Run {
        steps: s.number_of_steps,
        error_test_failures: s.number_of_error_test_failures,
        newton_failures: s.number_of_nonlinear_solver_fails,
        jacobians: s.number_of_linear_solver_setups,
        y,
    })
}

/// The Test Set's charge pump (`dpc-core/tests/common/pump.rs`) as `M y' = phi(t, y)`: `M` has
/// the rows `y1'`, `y2' + y3'`, `y4' + y5'` and six zero rows, `phi = -F(t, y, 0)` with the
/// fixture's exact Jacobian; `rtol = tol` and the Test Set driver's `atol`, from corner to
/// corner of `vin`. diffsol takes `y9` (index 2) in its error test at the plain weight. `given`
/// starts from the Test Set's consistent `(y0, y0')` without diffsol's initialisation.
fn pump(tol: f64, given: bool) -> Result<Run, String> {
    use pump::{pump_atol, pump_breaks, Pump};
    let zeros = [0.0; 9];
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol(pump_atol(tol))
        .rhs_implicit(
            move |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
                Pump.residual(t, y, &zeros, out);
                for o in out.iter_mut() {
                    *o = -*o;
                }
            },
            move |y: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
                let mut j = DMatrix::<f64>::zeros(9, 9);
                Pump.iteration_matrix(t, y, &zeros, 0.0, &mut j);
                for (i, o) in out.iter_mut().enumerate() {
                    *o = -(0..9).map(|k| j[(i, k)] * v[k]).sum::<f64>();
                }
            },
        )
        .mass(
            |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                for o in out.iter_mut() {
                    *o *= beta;
                }
                out[0] += v[0];
                out[1] += v[1] + v[2];
                out[2] += v[3] + v[4];
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&Pump::initial().0),
            9,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = if given {
        start_from(&problem, &Pump::initial().1, tol)?
    } else {
        problem
            .bdf::<NalgebraLU<f64>>()
            .map_err(|e| format!("initialisation: {e}"))?
    };
    finish_breaks(solver, &pump_breaks(), 9)
}

/// The Test Set's water tube system (`dpc-core/tests/common/water_tube.rs`) as
/// `M y' = phi(t, y)`: `M = diag(V, ..., V, 0, ..., 0, C, C, 0, ..., 0)` (the flows and the
/// buffered pressures `p5, p8`), `phi = -F(t, y, 0)` with the fixture's exact Jacobian; `rtol =
/// tol` and the Test Set driver's `atol`. `given` starts from the Test Set's consistent
/// `(y0, y0')` without diffsol's initialisation.
fn water_tube(tol: f64, given: bool) -> Result<Run, String> {
    use water_tube::{water_atol, WaterTube, WATER_DIM, WATER_T_END};
    const N: usize = WATER_DIM;
    let zeros = [0.0; N];
    // The diagonal of M: dF/dy' (the iteration matrix at c = 1 minus c = 0; constant).
    let (y0, yp0) = WaterTube::initial();
    let mut m1 = DMatrix::<f64>::zeros(N, N);
    let mut m0 = DMatrix::<f64>::zeros(N, N);
    WaterTube.iteration_matrix(0.0, &y0, &yp0, 1.0, &mut m1);
    WaterTube.iteration_matrix(0.0, &y0, &yp0, 0.0, &mut m0);
    let mass: Vec<f64> = (0..N).map(|i| m1[(i, i)] - m0[(i, i)]).collect();
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol(water_atol(tol))
        .rhs_implicit(
            move |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
                WaterTube.residual(t, y, &zeros, out);
                for o in out.iter_mut() {
                    *o = -*o;
                }
            },
            move |y: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
                let mut j = DMatrix::<f64>::zeros(N, N);
                WaterTube.iteration_matrix(t, y, &zeros, 0.0, &mut j);
                for (i, o) in out.iter_mut().enumerate() {
                    *o = -(0..N).map(|k| j[(i, k)] * v[k]).sum::<f64>();
                }
            },
        )
        .mass(
            move |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = beta * *o + mass[i] * v[i];
                }
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&WaterTube::initial().0),
            N,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = if given {
        start_from(&problem, &yp0, tol)?
    } else {
        problem
            .bdf::<NalgebraLU<f64>>()
            .map_err(|e| format!("initialisation: {e}"))?
    };
    finish(solver, WATER_T_END, N)
}

fn transamp(tol: f64) -> Result<Run, String> {
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
        .map_err(|e| e.to_string())?;
    let solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    finish(solver, TRANSAMP_T_END, 8)
}

fn robertson(rtol: f64) -> Result<Run, String> {
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
        .map_err(|e| e.to_string())?;
    let solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    finish(solver, ROBERTSON_T_END, 3)
}

fn akzo(tol: f64) -> Result<Run, String> {
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol([tol; 6])
        .rhs_implicit(
            |y: &[f64], _p: &[f64], _t: f64, out: &mut [f64]| {
                out.copy_from_slice(&ChemAkzo::f(y));
            },
            |y: &[f64], _p: &[f64], _t: f64, v: &[f64], out: &mut [f64]| {
                let j = ChemAkzo::f_jacobian(y);
                for (o, row) in out.iter_mut().zip(&j) {
                    *o = row.iter().zip(v).map(|(a, b)| a * b).sum();
                }
            },
        )
        .mass(
            |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                for i in 0..5 {
                    out[i] = v[i] + beta * out[i];
                }
                out[5] *= beta;
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| {
                y.copy_from_slice(&ChemAkzo::initial().0);
            },
            6,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    finish(solver, AKZO_T_END, 6)
}

fn hires(tol: f64) -> Result<Run, String> {
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol([tol; 8])
        .rhs_implicit(
            |y: &[f64], _p: &[f64], _t: f64, out: &mut [f64]| {
                out.copy_from_slice(&Hires::f(y));
            },
            |y: &[f64], _p: &[f64], _t: f64, v: &[f64], out: &mut [f64]| {
                out.fill(0.0);
                for (r, c, a) in Hires::f_jacobian(y) {
                    out[r] += a * v[c];
                }
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| {
                y.copy_from_slice(&Hires::initial().0);
            },
            8,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    finish(solver, HIRES_T_END, 8)
}

/// A stiff ODE of the Test Set (`stiff_odes.rs`) as diffsol's `y' = f(t, y)` with its exact
/// Jacobian, at `rtol = atol = tol`, to its interval's end.
fn stiff_ode<P: stiff_odes::StiffOde + Copy + 'static>(p: P, tol: f64) -> Result<Run, String> {
    let n = P::N;
    let y0 = p.y0();
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol(vec![tol; n])
        .rhs_implicit(
            move |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| p.f(t, y, out),
            move |y: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
                out.fill(0.0);
                p.jacobian(t, y, |r, c, a| out[r] += a * v[c]);
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y0),
            n,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    finish(solver, P::T_END, n)
}

/// The Test Set's Medical Akzo Nobel problem (`dpc-core/tests/common/medakzo.rs`) as diffsol's
/// `y' = f(t, y)` without a mass matrix, with the fixture's exact Jacobian entries, at
/// `rtol = atol = tol`, in faer's sparse matrices with faer's sparse LU (`FaerSparseMat`,
/// `FaerSparseLU`): diffsol finds the Jacobian's pattern (the band of half-bandwidths 2) by
/// probing the Jacobian action with NaN and assembles the matrix by colouring (5 actions per
/// Jacobian), as it does for any closure on a sparse matrix type. Stopped where the boundary
/// input switches off (`t = 5`) and restarted there from `(y(5), f(5+, y(5)))` in a new state
/// and solver, as dpc's rows (`reinit`) and IDA's (`IDAReInit`); the counters of both added.
fn medakzo(tol: f64) -> Result<Run, String> {
    use diffsol::{FaerSparseLU, FaerSparseMat, Vector as _};
    use medakzo::{Medakzo, MEDAKZO_DIM, MEDAKZO_T_END, MEDAKZO_T_SWITCH};
    const N: usize = MEDAKZO_DIM;
    let (y0, _) = Medakzo::initial();
    let problem = OdeBuilder::<FaerSparseMat<f64>>::new()
        .rtol(tol)
        .atol(vec![tol; N])
        .rhs_implicit(
            |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| Medakzo.f(t, y, out),
            |y: &[f64], _p: &[f64], _t: f64, v: &[f64], out: &mut [f64]| {
                out.fill(0.0);
                Medakzo.jacobian(y, |r, c, a| out[r] += a * v[c]);
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y0),
            N,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = problem
        .bdf::<FaerSparseLU<f64>>()
        .map_err(|e| e.to_string())?;
    let first = finish(solver, MEDAKZO_T_SWITCH, N)?;
    let mut state = BdfState::new_without_initialise(&problem).map_err(|e| e.to_string())?;
    {
        let s = state.as_mut();
        *s.t = MEDAKZO_T_SWITCH;
        for (i, (y, yp)) in first
            .y
            .iter()
            .zip(Medakzo::slope_after_switch(&first.y))
            .enumerate()
        {
            s.y.set_index(i, *y);
            s.dy.set_index(i, yp);
        }
    }
    state.set_step_size(problem.h0, &problem.atol, tol, &problem.eqn, 1);
    let solver = problem
        .bdf_solver::<FaerSparseLU<f64>>(state)
        .map_err(|e| e.to_string())?;
    let second = finish(solver, MEDAKZO_T_END, N)?;
    Ok(Run {
        steps: first.steps + second.steps,
        error_test_failures: first.error_test_failures + second.error_test_failures,
        newton_failures: first.newton_failures + second.newton_failures,
        jacobians: first.jacobians + second.jacobians,
        y: second.y,
    })
}

/// `dF/dy` of `dae` at `(t, y)` (the iteration matrix at `c = 0`), cached for the last point:
/// diffsol asks for `d phi / d y` one column at a time.
struct JacobianCache {
    at: Vec<f64>,
    matrix: DMatrix<f64>,
}

/// A dpc-core DAE `F(t, y, y') = M y' - phi(t, y)` with constant `M` as a diffsol problem
/// integrated from its consistent `(y0, y0')` to `t_end` at `rtol = atol = tol`; `given` skips
/// diffsol's own initialisation and starts from `(y0, y0')` as they are.
fn general<D: ImplicitDae>(
    dae: D,
    (y0, yp0): (&[f64], &[f64]),
    t_end: f64,
    tol: f64,
    given: bool,
) -> Result<Run, String> {
    let n = dae.dimension();
    let mut m1 = DMatrix::<f64>::zeros(n, n);
    let mut m0 = DMatrix::<f64>::zeros(n, n);
    dae.iteration_matrix(0.0, y0, yp0, 1.0, &mut m1);
    dae.iteration_matrix(0.0, y0, yp0, 0.0, &mut m0);
    let mass = m1 - m0;
    let cache = RefCell::new(JacobianCache {
        at: vec![f64::NAN; n + 1],
        matrix: DMatrix::zeros(n, n),
    });
    let zeros = vec![0.0; n];
    let d1 = std::rc::Rc::new(dae);
    let d2 = d1.clone();
    let y0v = y0.to_vec();
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol(vec![tol; n])
        .rhs_implicit(
            move |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
                d1.residual(t, y, &zeros, out);
                for o in out.iter_mut() {
                    *o = -*o;
                }
            },
            move |y: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
                let mut c = cache.borrow_mut();
                if c.at[0] != t || c.at[1..] != *y {
                    c.at[0] = t;
                    c.at[1..].copy_from_slice(y);
                    c.matrix.fill(0.0);
                    let mut jac = std::mem::replace(&mut c.matrix, DMatrix::zeros(0, 0));
                    d2.iteration_matrix(t, y, &vec![0.0; y.len()], 0.0, &mut jac);
                    c.matrix = jac;
                }
                for (i, o) in out.iter_mut().enumerate() {
                    *o = -(0..v.len()).map(|j| c.matrix[(i, j)] * v[j]).sum::<f64>();
                }
            },
        )
        .mass(
            move |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = beta * *o + (0..v.len()).map(|j| mass[(i, j)] * v[j]).sum::<f64>();
                }
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y0v),
            n,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = if given {
        start_from(&problem, yp0, tol)?
    } else {
        problem
            .bdf::<NalgebraLU<f64>>()
            .map_err(|e| format!("initialisation: {e}"))?
    };
    finish(solver, t_end, n)
}

/// diffsol's BDF from the problem's `y0` and the given consistent `y0'`, without diffsol's
/// consistent initialisation.
fn start_from<'a, Eqn>(
    problem: &'a OdeSolverProblem<Eqn>,
    yp0: &[f64],
    tol: f64,
) -> Result<diffsol::Bdf<'a, Eqn, NalgebraLU<f64>>, String>
where
    Eqn: diffsol::OdeEquationsImplicit<
        T = f64,
        V = diffsol::NalgebraVec<f64>,
        M = M,
        C = diffsol::NalgebraContext,
    >,
{
    use diffsol::Vector as _;
    let mut state = BdfState::new_without_initialise(problem).map_err(|e| e.to_string())?;
    {
        let s = state.as_mut();
        for (i, v) in yp0.iter().enumerate() {
            s.dy.set_index(i, *v);
        }
    }
    state.set_step_size(problem.h0, &problem.atol, tol, &problem.eqn, 1);
    problem
        .bdf_solver::<NalgebraLU<f64>>(state)
        .map_err(|e| e.to_string())
}

/// `(row, column, value)` of `dF/dy + c dF/dy'` written through [`dpc_core::MatrixSink`].
struct Triplets(usize, Vec<(usize, usize, f64)>);

impl dpc_core::MatrixSink for Triplets {
    fn rows(&self) -> usize {
        self.0
    }
    fn cols(&self) -> usize {
        self.0
    }
    fn set(&mut self, r: usize, c: usize, v: f64) {
        self.1.push((r, c, v));
    }
    fn add(&mut self, r: usize, c: usize, v: f64) {
        self.1.push((r, c, v));
    }
    fn fill_zero(&mut self) {
        self.1.clear();
    }
}

/// The Test Set's two bit adding unit (`dpc-core/tests/common/two_bit_adder.rs`) as
/// `M y' = phi(t, y)` with `M = diag(I, 0)` (the charges' rows), `phi = -F(t, y, 0)` and
/// `d phi / dy` from the fixture's exact iteration matrix at `c = 0` (its entries, not a dense
/// matrix), from corner to corner of the inputs; diffsol's initialisation solves the charge
/// rows for the node potentials (index 1); `given` starts from the fixture's consistent
/// `(y0, y0')` without it.
fn two_bit_adder(tol: f64, given: bool) -> Result<Run, String> {
    use two_bit_adder::{tba_breaks, TwoBitAdder, NODES, TBA_N};
    let dae = TwoBitAdder::new();
    let (d1, d2, d3) = (dae.clone(), dae.clone(), dae.clone());
    let zeros = vec![0.0; TBA_N];
    let problem = OdeBuilder::<M>::new()
        .rtol(tol)
        .atol(vec![tol; TBA_N])
        .rhs_implicit(
            move |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
                d1.residual(t, y, &zeros, out);
                for o in out.iter_mut() {
                    *o = -*o;
                }
            },
            move |y: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
                let mut j = Triplets(TBA_N, Vec::new());
                d2.iteration_matrix(t, y, y, 0.0, &mut j);
                out.fill(0.0);
                for (r, c, a) in j.1 {
                    out[r] -= a * v[c];
                }
            },
        )
        .mass(
            |v: &[f64], _p: &[f64], _t: f64, beta: f64, out: &mut [f64]| {
                for o in out.iter_mut() {
                    *o *= beta;
                }
                for i in 0..NODES {
                    out[i] += v[i];
                }
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&d3.initial().0),
            TBA_N,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let solver = if given {
        start_from(&problem, &vec![0.0; TBA_N], tol)?
    } else {
        problem
            .bdf::<NalgebraLU<f64>>()
            .map_err(|e| format!("initialisation: {e}"))?
    };
    finish_breaks(solver, &tba_breaks(), TBA_N)
}

/// [`peer_table::row`], unless the command line's second argument is given and is not part of
/// the problem's label (`diffsol-peer 1 OREGO`: the OREGO rows alone).
fn row(
    key: (u8, &str),
    k: i32,
    code: (u8, &str),
    score: impl Fn(&[f64]) -> f64,
    solve: impl Fn() -> Result<Run, String>,
) {
    if let Some(only) = std::env::args().nth(2) {
        if !key.1.contains(only.as_str()) {
            return;
        }
    }
    peer_table::row(key, k, code, score, solve);
}

const CODE: (u8, &str) = (5, "diffsol 0.19 BDF");
const CODE_GIVEN: (u8, &str) = (6, "diffsol 0.19 BDF (y0' given)");

fn main() {
    let all10: Vec<usize> = (0..10).collect();
    let pendulum_ref = Pendulum::default().reference(THETA0, PENDULUM_T);
    let (ay0, ayp0) = Andrews::initial();
    let car = CarAxis::default();
    let (cy0, cyp0) = car.initial();
    let (gy0, gyp0) = Andrews::stabilised().extend(&ay0, &ayp0);
    let (hy0, hyp0) = car.stabilised().extend(&cy0, &cyp0);
    let p = Pendulum::default();
    let (py0, pyp0) = p.initial(THETA0);
    // The factor on every tolerance (the first argument, 1 by default), for the jitter scans.
    let factor: f64 = match std::env::args().nth(1) {
        None => 1.0,
        Some(a) => match a.parse::<f64>() {
            Ok(f) if f > 0.0 && f.is_finite() => f,
            _ => {
                eprintln!(
                    "diffsol_peer: the argument is a tolerance factor (a positive number), got '{a}'"
                );
                std::process::exit(2);
            }
        },
    };
    for k in [4, 6, 8] {
        let tol = 10f64.powi(-k) * factor;
        row(
            (1, "Robertson (index 1)"),
            k,
            CODE,
            |y| scd(y, &ROBERTSON_REF, &[0, 1, 2]),
            || robertson(tol),
        );
        row(
            (2, "transistor amplifier (index 1)"),
            k,
            CODE,
            |y| scd(y, &TRANSAMP_REF, &[0, 1, 2, 3, 4, 5, 6, 7]),
            || transamp(tol),
        );
        for (code, given) in [(CODE, false), (CODE_GIVEN, true)] {
            row(
                (3, "pendulum (index 3; x, y)"),
                k,
                code,
                |y| scd(y, &pendulum_ref, &[0, 1]),
                || general(p, (&py0, &pyp0), PENDULUM_T, tol, given),
            );
            row(
                (4, "Andrews (index 3; y1..y7)"),
                k,
                code,
                |y| scd(y, &ANDREWS_REF, &ANDREWS_SCORED),
                || general(Andrews, (&ay0, &ayp0), ANDREWS_T_END, tol, given),
            );
            row(
                (5, "Andrews (stabilised index 2; y1..y7)"),
                k,
                code,
                |y| scd(y, &ANDREWS_REF, &ANDREWS_SCORED),
                || {
                    general(
                        Andrews::stabilised(),
                        (&gy0, &gyp0),
                        ANDREWS_T_END,
                        tol,
                        given,
                    )
                },
            );
            row(
                (6, "car axis (index 3; all)"),
                k,
                code,
                |y| scd(y, &CAR_AXIS_REF, &all10),
                || general(car, (&cy0, &cyp0), CAR_AXIS_T_END, tol, given),
            );
            row(
                (7, "car axis (stabilised index 2; all)"),
                k,
                code,
                |y| scd(y, &CAR_AXIS_REF, &all10),
                || general(car.stabilised(), (&hy0, &hyp0), CAR_AXIS_T_END, tol, given),
            );
        }
        row(
            (8, "chemical Akzo Nobel (index 1; all)"),
            k,
            CODE,
            |y| scd(y, &AKZO_REF, &[0, 1, 2, 3, 4, 5]),
            || akzo(tol),
        );
        row(
            (9, "HIRES (ODE; all)"),
            k,
            CODE,
            |y| scd(y, &HIRES_REF, &[0, 1, 2, 3, 4, 5, 6, 7]),
            || hires(tol),
        );
        for (code, given) in [(CODE, false), (CODE_GIVEN, true)] {
            row(
                (14, "charge pump (index 2; y1)"),
                k,
                code,
                |y| scd(y, &pump::PUMP_REF, &pump::PUMP_SCORED),
                || pump(tol, given),
            );
        }
        for (code, given) in [(CODE, false), (CODE_GIVEN, true)] {
            row(
                (15, "water tube (index 2; all)"),
                k,
                code,
                |y| scd(y, &water_tube::WATER_REF, &water_tube::WATER_SCORED),
                || water_tube(tol, given),
            );
        }
        // The two bit adding unit at 1e-4 and 1e-6 (at 1e-8 dpc's BDF and IDA fail after
        // 10^5 / 10^6 steps near t = 5; not run here).
        if k < 8 {
            let reference = two_bit_adder::tba_full_reference(&two_bit_adder::TBA_REF);
            for (code, given) in [(CODE, false), (CODE_GIVEN, true)] {
                row(
                    (17, "two bit adding unit (index 1; S0, S1, C)"),
                    k,
                    code,
                    |y| scd(y, &reference, &two_bit_adder::TBA_SCORED),
                    || two_bit_adder(tol, given),
                );
            }
        }
        stiff_ode_rows(k, tol);
        // SUNDIALS' idaSlCrank_dns (row 24; GGL form, constant mass matrix
        // diag(1, 1, 1, J1, m2, J2, 0, 0, 0, 0)), scored on the six differential unknowns.
        let (sy0, syp0) = ida_slider_crank::slcrank_initial();
        for (code, given) in [(CODE, false), (CODE_GIVEN, true)] {
            row(
                (24, "slider crank, idaSlCrank_dns (index 2; q, v)"),
                k,
                code,
                |y| {
                    scd(
                        y,
                        &ida_slider_crank::SLCRANK_REF,
                        &ida_slider_crank::SLCRANK_SCORED,
                    )
                },
                || {
                    general(
                        ida_slider_crank::SlCrank,
                        (&sy0, &syp0),
                        ida_slider_crank::SLCRANK_T_END,
                        tol,
                        given,
                    )
                },
            );
        }
        // The Test Set's Medical Akzo Nobel problem (row 28; an ODE, faer's sparse LU),
        // restarted at the input switch, all 400 unknowns scored by the mixed error.
        row(
            (28, "medical Akzo Nobel (ODE; all, mixed error)"),
            k,
            CODE,
            medakzo::medakzo_scd,
            || medakzo(tol),
        );
    }
}

/// The rows of the Test Set's stiff ODEs (18-21 of dpc-core's table), all components scored.
fn stiff_ode_rows(k: i32, tol: f64) {
    use stiff_odes::{Orego, Pollution, RingModulator, StiffOde, VanDerPol};
    fn one<P: StiffOde + Copy + 'static>(key: (u8, &str), p: P, k: i32, tol: f64) {
        let reference = p.reference();
        let all: Vec<usize> = (0..P::N).collect();
        row(
            key,
            k,
            CODE,
            |y| scd(y, &reference, &all),
            || stiff_ode(p, tol),
        );
    }
    one(
        (18, "Van der Pol, eps = 1e-6 (ODE; all)"),
        VanDerPol,
        k,
        tol,
    );
    one((19, "OREGO (ODE; all)"), Orego, k, tol);
    one((20, "Pollution (ODE; all)"), Pollution, k, tol);
    one((21, "ring modulator (ODE; all)"), RingModulator, k, tol);
}
