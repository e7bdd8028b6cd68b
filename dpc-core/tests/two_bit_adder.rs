//! The BDF and Radau IIA on the Test Set's two bit adding unit (350 unknowns, index 1 by the
//! Test Set, 13 directions of index 2 in its form (`common/two_bit_adder.rs`), constant
//! mass matrix `diag(I, 0)`, ten MOS gates driven by trapezoidal pulses), run from corner to
//! corner of the inputs and scored on the three outputs as the Test Set scores them, against
//! the reference of `common/two_bit_adder.rs`. The iteration matrix is checked against
//! differences of the residual; the runs at tighter tolerances are `#[ignore]`d (seconds in
//! release):
//!
//! ```sh
//! cargo test --release -p dpc-core --test two_bit_adder -- --ignored --nocapture
//! ```

#[path = "common/testset_index3.rs"]
mod testset_index3;
#[path = "common/two_bit_adder.rs"]
mod two_bit_adder;

use dpc_core::bdf::Bdf;
use dpc_core::linear_solver::{FaerLu, LinearSolver};
use dpc_core::radau::Radau;
use dpc_core::{bdf, radau, ImplicitDae, MatrixSink};
use nalgebra::DMatrix;
use testset_index3::median_scd_over_jitter;
use two_bit_adder::*;

/// `$name(dae, ls, (y0, yp0), opts, breaks)`: `$solver` from `t = 0` through the stop times
/// `breaks` (the last is the end), continuing across each: `(y(end), statistics)`, or the
/// error's message.
macro_rules! piecewise {
    ($name:ident, $solver:ident, $options:ty, $stats:ty) => {
        fn $name<L: LinearSolver>(
            dae: TwoBitAdder,
            ls: L,
            (y0, yp0): (&[f64], &[f64]),
            opts: $options,
            breaks: &[f64],
        ) -> Result<(Vec<f64>, $stats), String> {
            let mut s = $solver::new(dae, ls, opts, 0.0, y0, yp0).map_err(|e| e.to_string())?;
            let mut y = vec![0.0; TBA_N];
            for &tb in breaks {
                s.set_stop_time(tb).map_err(|e| e.to_string())?;
                s.solve_to(tb, &mut y, None).map_err(|e| e.to_string())?;
            }
            Ok((y, s.stats()))
        }
    };
}

piecewise!(bdf_piecewise, Bdf, bdf::Options, bdf::Stats);
piecewise!(radau_piecewise, Radau, radau::Options, radau::Stats);

/// The adder at `rtol = atol = tol` from `t = 0` to `t_end` by the BDF (`radau = false`) or
/// Radau, with faer's LU chosen from the declared pattern (sparse): `y(t_end)` or the error's
/// message (statistics printed).
fn run(tol: f64, radau: bool, t_end: f64) -> Result<Vec<f64>, String> {
    let dae = TwoBitAdder::new();
    let (y0, yp0) = dae.initial();
    let start = (&y0[..], &yp0[..]);
    let breaks: Vec<f64> = tba_breaks().into_iter().filter(|&b| b <= t_end).collect();
    let ls = FaerLu::for_dae(&dae);
    assert!(ls.is_sparse());
    if radau {
        let opts = radau::Options::with_tolerances(tol, tol);
        let (y, s) = radau_piecewise(dae, ls, start, opts, &breaks)?;
        println!("  adder Radau tol {tol:e} to {t_end}: {s:?}");
        Ok(y)
    } else {
        let opts = bdf::Options::with_tolerances(tol, tol);
        let (y, s) = bdf_piecewise(dae, ls, start, opts, &breaks)?;
        println!("  adder BDF tol {tol:e} to {t_end}: {s:?}");
        Ok(y)
    }
}

/// Dense `dF/dy + c dF/dy'` of `dae` at `(t, y, yp)`.
fn dense_matrix<D: ImplicitDae>(dae: &D, t: f64, y: &[f64], yp: &[f64], c: f64) -> Vec<Vec<f64>> {
    struct Dense(Vec<Vec<f64>>);
    impl MatrixSink for Dense {
        fn rows(&self) -> usize {
            self.0.len()
        }
        fn cols(&self) -> usize {
            self.0.len()
        }
        fn set(&mut self, r: usize, k: usize, v: f64) {
            self.0[r][k] = v;
        }
        fn add(&mut self, r: usize, k: usize, v: f64) {
            self.0[r][k] += v;
        }
        fn fill_zero(&mut self) {
            self.0.iter_mut().for_each(|r| r.fill(0.0));
        }
    }
    let n = dae.dimension();
    let mut m = Dense(vec![vec![0.0; n]; n]);
    dae.iteration_matrix(t, y, yp, c, &mut m);
    m.0
}

/// The largest difference between the adder's iteration matrix and a central difference
/// quotient of its residual (in `y` and `y'` together, `y'` moving `c` times as far), relative
/// to the largest entry of its row; and whether every non-zero entry lies in the declared
/// pattern.
fn matrix_error(dae: &TwoBitAdder, t: f64, y: &[f64], yp: &[f64], c: f64) -> (f64, bool) {
    let n = dae.dimension();
    let m = dense_matrix(dae, t, y, yp, c);
    let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
    let mut dq = vec![vec![0.0; n]; n];
    for j in 0..n {
        let h = 1e-7 * y[j].abs().max(1.0);
        let (mut y1, mut p1, mut y2, mut p2) = (y.to_vec(), yp.to_vec(), y.to_vec(), yp.to_vec());
        y1[j] += h;
        p1[j] += c * h;
        y2[j] -= h;
        p2[j] -= c * h;
        dae.residual(t, &y1, &p1, &mut up);
        dae.residual(t, &y2, &p2, &mut down);
        for i in 0..n {
            dq[i][j] = (up[i] - down[i]) / (2.0 * h);
        }
    }
    let mut worst = 0.0f64;
    for i in 0..n {
        let scale = (0..n).map(|j| dq[i][j].abs()).fold(0.0, f64::max);
        for j in 0..n {
            worst = worst.max((m[i][j] - dq[i][j]).abs() / scale);
        }
    }
    let pattern = dae.iteration_pattern().unwrap_or_default();
    let mut inside = vec![vec![false; n]; n];
    for (r, k) in pattern {
        inside[r][k] = true;
    }
    let covered =
        (0..n).all(|i| (0..n).all(|j| inside[i][j] || (m[i][j] == 0.0 && dq[i][j] == 0.0)));
    (worst, covered)
}

#[test]
fn start_is_nearly_steady_and_every_node_has_equations() {
    let dae = TwoBitAdder::new();
    let (y0, yp0) = dae.initial();
    let mut r = vec![0.0; TBA_N];
    dae.residual(0.0, &y0, &yp0, &mut r);
    let worst = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!("largest |F(0, y0, 0)|: {worst:e}");
    // The charges are g(U0) exactly; the currents are the Test Set's steady state to the
    // digits it gives.
    assert!(r[NODES..].iter().all(|v| *v == 0.0));
    assert!(worst < 1e-6, "{worst:e}");
    // Every current and every charge depends on its own node.
    let m = dense_matrix(&dae, 0.0, &y0, &yp0, 1.0);
    for i in 0..NODES {
        assert!(m[i][NODES + i] != 0.0, "current {i}");
        assert!(m[NODES + i][NODES + i] != 0.0, "charge {i}");
    }
}

/// The null spaces of `dg/dU` at the start (right `V`, left `W`: the singular vectors of
/// singular values below `1e-10` of the largest), the smallest singular value above them
/// (relative), and `W^T df/dU V`.
fn charge_null_spaces() -> (DMatrix<f64>, DMatrix<f64>, f64, DMatrix<f64>) {
    let dae = TwoBitAdder::new();
    let (y0, yp0) = dae.initial();
    let mut g = DMatrix::zeros(TBA_N, TBA_N);
    dae.iteration_matrix(0.0, &y0, &yp0, 0.0, &mut g);
    // Rows 0..175 are `q' - f(U)`, rows 175..350 `q - g(U)`: `-f_U` and `-g_U` in the columns
    // of U.
    let f_u = -g.view((0, NODES), (NODES, NODES)).clone_owned();
    let g_u = -g.view((NODES, NODES), (NODES, NODES)).clone_owned();
    let svd = g_u.svd(true, true);
    let largest = svd.singular_values.max();
    let (null, rest): (Vec<usize>, Vec<usize>) =
        (0..NODES).partition(|&k| svd.singular_values[k] < 1e-10 * largest);
    let gap = rest
        .iter()
        .map(|&k| svd.singular_values[k] / largest)
        .fold(f64::INFINITY, f64::min);
    let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
    let v = DMatrix::from_fn(NODES, null.len(), |i, k| v_t[(null[k], i)]);
    let w = DMatrix::from_fn(NODES, null.len(), |i, k| u[(i, null[k])]);
    let coupling = w.transpose() * f_u * &v;
    (v, w, gap, coupling)
}

#[test]
fn thirteen_node_groups_float_capacitively_and_have_index_two() {
    // In the Test Set's form the charges of 13 groups of nodes depend on differences within
    // the group only (`dg/dU` singular, with a clear gap above its null space); the groups'
    // currents fix their common potentials (`W^T f_U V` regular): index 2 exactly there, and
    // 95 node potentials have a part in those directions. `unknown_indices` at the start reads
    // those 95 as of index 2 (measured in release, 1.5 s; the failure diagnosis names them).
    let (v, _, gap, coupling) = charge_null_spaces();
    assert_eq!(v.ncols(), 13);
    assert!(gap > 1e-4, "{gap:e}");
    let s = coupling.svd(false, false).singular_values;
    assert!(s.min() > 1e-3 * s.max(), "{s}");
    let with_part = (0..NODES).filter(|&i| v.row(i).norm() > 1e-8).count();
    assert_eq!(with_part, 95);
}

#[test]
fn matrix_matches_differences_and_pattern() {
    let dae = TwoBitAdder::new();
    let (y0, _) = dae.initial();
    // y0 moved off the transistor model's branch switches (V_DS = 0 at many transistors in
    // the steady state), at a time with two inputs rising (V1 on [0, 5]) and one falling
    // (V2 on [25, 30]), y' of a step with c = 1e2.
    let y: Vec<f64> = (0..TBA_N)
        .map(|j| y0[j] + 1e-3 * ((j * 37 % 101) as f64 - 50.0))
        .collect();
    let yp: Vec<f64> = (0..TBA_N).map(|j| 0.01 * ((j % 13) as f64 - 6.0)).collect();
    for t in [2.5, 27.5] {
        let (e, covered) = matrix_error(&dae, t, &y, &yp, 1e2);
        assert!(e < 1e-6, "t = {t}: relative error {e:e}");
        assert!(covered, "t = {t}: an entry outside the declared pattern");
    }
}

/// Median scd on the outputs over the jitter; a failed run scores minus infinity.
fn digits(tol: f64, radau: bool) -> f64 {
    let reference = tba_full_reference(&TBA_REF);
    median_scd_over_jitter(tol, |t| run(t, radau, TBA_T_END), &reference, &TBA_SCORED)
}

#[test]
fn bdf_reaches_test_set_accuracy() {
    // Median scd on the outputs over tol x (0.9, 1, 1.1) at 1e-4, measured: 4.47 (5 263 steps
    // at tol; the test profile is optimised, about 0.2 s a run). Floor half a digit below.
    // Since `Bdf::new` reads the singular algebraic block (13 node groups of index 2) and keeps
    // IDA's rules: 5.09 with the index-1 DAE rules before; over 15 tolerance factors 0.80 ...
    // 1.20 the medians are 4.64 against 4.84 (IDA 4.53), and at 1e-6 1 of the 15 factors
    // fails instead of 5 (IDA: 1; docs/integrators.md, "The Test Set's two bit adding unit").
    let d = digits(1e-4, false);
    println!("adder BDF tol 1e-4: median scd {d:.2}");
    assert!(d >= 3.97, "scd {d}");
}

#[test]
#[ignore = "Radau's complex system is a dense 350 x 350 LU: about 7 s a run"]
fn radau_reaches_test_set_accuracy() {
    // Median scd on the outputs over tol x (0.9, 1, 1.1) at 1e-4, measured: 5.64 (1 284 steps
    // at tol). Floor half a digit below.
    let d = digits(1e-4, true);
    println!("adder Radau tol 1e-4: median scd {d:.2}");
    assert!(d >= 5.1, "scd {d}");
}

#[test]
#[ignore = "seconds in release: run with --release -- --ignored"]
fn bdf_with_the_index_declared_solves_the_factors_that_failed() {
    // At rtol = 1e-6 x (0.89, 1.02, 1.08, 1.20) the BDF with every unknown declared of index 1
    // runs out of steps after a corner (the floating groups' potentials swing by volts where
    // the solution is smooth, docs/integrators.md); with the 95 potentials the estimate reads
    // as of index 2 declared (`Exclude`) it finishes, measured 6.04 / 5.84 / 6.10 / 5.47
    // digits in 14 697-16 684 steps. Floor: 5.0 on each.
    let dae = TwoBitAdder::new();
    let (y0, yp0) = dae.initial();
    let index = dpc_core::index_estimate::unknown_indices(&dae, 0.0, &y0, &yp0).unwrap();
    assert_eq!(index.iter().filter(|&&m| m == 2).count(), 95);
    let reference = tba_full_reference(&TBA_REF);
    for factor in [0.89, 1.02, 1.08, 1.20] {
        let tol = 1e-6 * factor;
        let opts = bdf::Options {
            index: index.clone(),
            ..bdf::Options::with_tolerances(tol, tol)
        };
        let ls = FaerLu::for_dae(&dae);
        let start = (&y0[..], &yp0[..]);
        let (y, stats) = bdf_piecewise(dae.clone(), ls, start, opts, &tba_breaks()).unwrap();
        let d = testset_index3::scd(&y, &reference, &TBA_SCORED);
        println!("adder BDF, index declared, tol {tol:e}: scd {d:.2}, {stats:?}");
        assert!(d >= 5.0, "tol {tol:e}: scd {d}");
    }
}

/// At 1e-8 the BDF (and IDA) do not get past `t = 5.2` (`5.6`) within their step limits: after
/// the first corner of the inputs both resolve a fast transient with steps near `1.6e-5` at
/// order 5 and no failures (`docs/integrators.md`), so the tolerances here stop at 1e-6.
#[test]
#[ignore = "minutes; run with --release -- --ignored"]
fn adder_at_all_tolerances() {
    for tol in [1e-4, 1e-6] {
        for radau in [false, true] {
            let d = digits(tol, radau);
            println!("adder radau={radau} tol {tol:e}: median scd {d:.2}");
        }
    }
}
