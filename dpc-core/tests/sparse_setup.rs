//! The integrators' set-up and diagnosis paths scale with the number of non-zeros of the
//! iteration matrix, not with the square of the dimension: the BDF's set-up classification
//! (`dae_rules_apply`), [`Stabilised::detect`] and the start check of DAEs with constraints
//! (`start_violation`) on DAEs far too large for a dense `n x n` matrix.
//!
//! The problems: the 2-D heat equation of SUNDIALS' `idaHeat2D_bnd` on an `m x m` grid
//! (`common/grid_heat.rs`: on any grid, written by hand without a mass matrix), and a row of
//! independent planar pendulums in index-3 form. The default tests assert, with a counting
//! allocator, that no allocation anywhere near `n^2` values is made; the `#[ignore]`d ones run
//! 40 000 unknowns, time the set-up on growing grids and the stabilised form's step path
//! (release mode, one test at a time so that the timings do not share the cores;
//! docs/integrators.md, "Set-up and start checks without dense matrices"):
//!
//! ```sh
//! cargo test --release -p dpc-core --test sparse_setup -- --ignored --nocapture --test-threads=1
//! ```

#[path = "common/counting_allocator.rs"]
mod counting_allocator;
#[path = "common/grid_heat.rs"]
mod grid_heat;

use std::time::Instant;

use counting_allocator::{largest_allocation, reset_largest_allocation};

use dpc_core::bdf::{self, Bdf, BdfError};
use dpc_core::linear_solver::{BandLu, FaerSparseLu};
use dpc_core::stabilised::Stabilised;
use dpc_core::{ImplicitDae, MatrixSink};
use grid_heat::GridHeat;

/// `p` independent planar pendulums of length 1 in Cartesian coordinates, index 3: per
/// pendulum `(x, y, u, v, l)` with `x' = u`, `y' = v`, `u' = -x l`, `v' = -y l - 1`,
/// `0 = x^2 + y^2 - 1`.
struct Pendulums(usize);

impl Pendulums {
    /// At rest at angles spread over `(0, 1)` from the vertical, with the consistent
    /// multipliers and accelerations; the `miss`-th pendulum's `x` moved by `0.01` when given.
    fn initial(&self, miss: Option<usize>) -> (Vec<f64>, Vec<f64>) {
        let (mut y, mut yp) = (Vec::new(), Vec::new());
        for k in 0..self.0 {
            let angle = 0.1 + 0.8 * k as f64 / self.0 as f64;
            let (s, c) = angle.sin_cos();
            y.extend([s, -c, 0.0, 0.0, c]);
            yp.extend([0.0, 0.0, -c * s, c * c - 1.0, 0.0]);
        }
        if let Some(k) = miss {
            y[5 * k] += 0.01;
        }
        (y, yp)
    }
    fn index(&self) -> Vec<u8> {
        (0..self.0).flat_map(|_| [1, 1, 2, 2, 3]).collect()
    }
}

impl ImplicitDae for Pendulums {
    fn dimension(&self) -> usize {
        5 * self.0
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for ((o, y), yp) in out
            .chunks_exact_mut(5)
            .zip(y.chunks_exact(5))
            .zip(yp.chunks_exact(5))
        {
            o[0] = yp[0] - y[2];
            o[1] = yp[1] - y[3];
            o[2] = yp[2] + y[0] * y[4];
            o[3] = yp[3] + y[1] * y[4] + 1.0;
            o[4] = y[0] * y[0] + y[1] * y[1] - 1.0;
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        out: &mut S,
    ) {
        for k in 0..self.0 {
            let b = 5 * k;
            let y = &y[b..b + 5];
            for i in 0..4 {
                out.set(b + i, b + i, c);
            }
            out.set(b, b + 2, -1.0);
            out.set(b + 1, b + 3, -1.0);
            out.set(b + 2, b, y[4]);
            out.set(b + 2, b + 4, y[0]);
            out.set(b + 3, b + 1, y[4]);
            out.set(b + 3, b + 4, y[1]);
            out.set(b + 4, b, 2.0 * y[0]);
            out.set(b + 4, b + 1, 2.0 * y[1]);
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        i % 5 != 4
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let mut p = Vec::new();
        for k in 0..self.0 {
            let b = 5 * k;
            for (i, j) in [
                (0, 0),
                (0, 2),
                (1, 1),
                (1, 3),
                (2, 0),
                (2, 2),
                (2, 4),
                (3, 1),
                (3, 3),
                (3, 4),
                (4, 0),
                (4, 1),
            ] {
                p.push((b + i, b + j));
            }
        }
        Some(p)
    }
    fn equation_name(&self, i: usize) -> String {
        match i % 5 {
            4 => format!("constraint of pendulum {}", i / 5),
            e => format!("equation {e} of pendulum {}", i / 5),
        }
    }
}

/// The BDF on the heat equation on an `m x m` grid: set up (`Bdf::new`, milliseconds) and a
/// short integration to `t = 0.01` (milliseconds, steps).
fn heat_run(m: usize) -> (f64, f64, usize) {
    let h = GridHeat(m);
    let n = m * m;
    let (y, yp) = h.initial();
    let opts = bdf::Options::with_tolerances(1e-6, 1e-6);
    let start = Instant::now();
    let mut s = Bdf::new(h, BandLu::new(n, m, m), opts, 0.0, &y, &yp).unwrap();
    let set_up = start.elapsed().as_secs_f64() * 1e3;
    let mut out = vec![0.0; n];
    s.solve_to(0.01, &mut out, None).unwrap();
    let total = start.elapsed().as_secs_f64() * 1e3;
    assert!(out.iter().all(|v| v.is_finite()));
    (set_up, total - set_up, s.stats().steps)
}

/// The BDF set up on `p` pendulums with their index declared (the start check), started on
/// the constraints or with pendulum `miss` off them: the error's message, if any.
fn pendulums_start(p: usize, miss: Option<usize>) -> Result<(), String> {
    let dae = Pendulums(p);
    let n = dae.dimension();
    let (y, yp) = dae.initial(miss);
    let opts = bdf::Options {
        index: dae.index(),
        ..bdf::Options::with_tolerances(1e-6, 1e-6)
    };
    let pattern = dae.iteration_pattern().unwrap();
    let ls = FaerSparseLu::new(n, &pattern).unwrap();
    match Bdf::new(dae, ls, opts, 0.0, &y, &yp) {
        Ok(_) => Ok(()),
        Err(e @ BdfError::InconsistentConstraint { .. }) => Err(e.to_string()),
        Err(e) => panic!("unexpected error {e}"),
    }
}

/// Times the set-up paths on growing problems: `Bdf::new` and a short run on the heat
/// equation, `Stabilised::detect` and the start check on rows of pendulums.
#[test]
#[ignore = "timing run: release mode"]
fn set_up_times_on_growing_problems() {
    for m in [10, 30, 50, 100, 200] {
        let (set_up, run, steps) = heat_run(m);
        println!(
            "heat m {m} n {}: Bdf::new {set_up:.3} ms, run to 0.01 {run:.2} ms ({steps} steps)",
            m * m
        );
    }
    for p in [20, 100, 200, 400, 2000] {
        let dae = Pendulums(p);
        let (y, yp) = dae.initial(None);
        let start = Instant::now();
        let s = Stabilised::detect(Pendulums(p), 0.0, &y, &yp).unwrap();
        let detect = start.elapsed().as_secs_f64() * 1e3;
        assert_eq!(s.n_constraints(), p);
        let start = Instant::now();
        let consistent = pendulums_start(p, None);
        let check = start.elapsed().as_secs_f64() * 1e3;
        let missed = pendulums_start(p, Some(p / 2));
        println!(
            "pendulums {p} n {}: detect {detect:.2} ms, Bdf::new with the start check {check:.2} ms \
             (consistent: {consistent:?}; one off: {})",
            5 * p,
            missed.is_err()
        );
    }
}

/// Whether `f` ran without any single allocation of `n^2 / 16` values (`f64`) or more: a
/// dense `n x n` matrix, or a dense block of a sixteenth of one, anywhere on the path. With
/// `f`'s result and its largest allocation in bytes.
fn without_dense<T>(n: usize, f: impl FnOnce() -> T) -> (T, usize) {
    reset_largest_allocation();
    let out = f();
    let largest = largest_allocation();
    assert!(
        largest < n * n / 16 * std::mem::size_of::<f64>(),
        "an allocation of {largest} bytes for {n} unknowns"
    );
    (out, largest)
}

/// The BDF's set-up on the heat equation without a mass matrix (the classification from the
/// two iteration matrices) and its first steps, on 6 400 unknowns: no allocation near a dense
/// `n x n` matrix (328 MB; the largest made is the band LU's storage).
#[test]
fn bdf_sets_up_and_steps_the_heat_equation_without_dense_matrices() {
    let m = 80;
    let n = m * m;
    let h = GridHeat(m);
    let (y, yp) = h.initial();
    let ((), largest) = without_dense(n, || {
        let opts = bdf::Options::with_tolerances(1e-6, 1e-6);
        let mut s = Bdf::new(h, BandLu::new(n, m, m), opts, 0.0, &y, &yp).unwrap();
        // The classification read both iteration matrices (the DAE rules apply: the edges
        // are algebraic, the DAE of index 1).
        assert_eq!(s.stats().jacobian_evaluations, 2);
        let mut out = vec![0.0; n];
        s.solve_to(1e-5, &mut out, None).unwrap();
        assert!(s.stats().steps >= 3, "{:?}", s.stats());
        assert!(out.iter().all(|v| v.is_finite()));
    });
    assert!(largest < 8 * n * (3 * m + 2), "{largest}");
}

/// `Stabilised::detect` and the start check (`Bdf::new` with the index declared) on 2 000
/// pendulums, 10 000 unknowns: the constraints found, a start off one named, a consistent one
/// accepted, without any allocation near a dense `n x n` matrix (800 MB).
#[test]
fn detect_and_the_start_check_read_large_daes_without_dense_matrices() {
    let p = 2000;
    let n = 5 * p;
    let (y, yp) = Pendulums(p).initial(None);
    without_dense(n, || {
        let s = Stabilised::detect(Pendulums(p), 0.0, &y, &yp).unwrap();
        assert_eq!(s.n_constraints(), p);
        assert_eq!(s.constraint_rows()[p - 1], n - 1);
        assert_eq!(s.kinematic_pairs().len(), 2 * p);
        assert_eq!(s.index()[..5], [1, 1, 1, 1, 2]);
    });
    without_dense(n, || {
        assert_eq!(pendulums_start(p, None), Ok(()));
        let missed = pendulums_start(p, Some(1234)).unwrap_err();
        assert!(missed.contains("constraint of pendulum 1234"), "{missed}");
    });
}

/// The same on 40 000 unknowns (a dense `n x n` matrix would take 12.8 GB): the BDF on the
/// heat equation on a `200 x 200` grid without a mass matrix (set-up and a few steps), and
/// `Stabilised::detect` and the start check on 8 000 pendulums. Seconds in release mode:
///
/// ```sh
/// cargo test --release -p dpc-core --test sparse_setup -- --ignored --nocapture forty
/// ```
#[test]
#[ignore = "seconds in release mode"]
fn forty_thousand_unknowns() {
    let m = 200;
    let n = m * m;
    let h = GridHeat(m);
    let (y, yp) = h.initial();
    let start = Instant::now();
    let (steps, largest) = without_dense(n, || {
        let opts = bdf::Options::with_tolerances(1e-6, 1e-6);
        let mut s = Bdf::new(h, BandLu::new(n, m, m), opts, 0.0, &y, &yp).unwrap();
        let mut out = vec![0.0; n];
        s.solve_to(1e-5, &mut out, None).unwrap();
        assert!(out.iter().all(|v| v.is_finite()));
        s.stats().steps
    });
    println!(
        "heat {n}: set-up and {steps} steps in {:.2} s, largest allocation {:.1} MB",
        start.elapsed().as_secs_f64(),
        largest as f64 / 1e6
    );
    let p = 8000;
    let n = 5 * p;
    let (y, yp) = Pendulums(p).initial(None);
    let start = Instant::now();
    let ((), largest) = without_dense(n, || {
        let s = Stabilised::detect(Pendulums(p), 0.0, &y, &yp).unwrap();
        assert_eq!(s.n_constraints(), p);
        assert_eq!(pendulums_start(p, None), Ok(()));
        let missed = pendulums_start(p, Some(7777)).unwrap_err();
        assert!(missed.contains("constraint of pendulum 7777"), "{missed}");
    });
    println!(
        "pendulums {n}: detect and two start checks in {:.2} s, largest allocation {:.1} MB",
        start.elapsed().as_secs_f64(),
        largest as f64 / 1e6
    );
}

/// Radau on the stabilised form of `p` pendulums (`Radau::stabilised`) to `t = 10` at `1e-8`:
/// (median wall times in ms over 21 runs of the set-up and of the integration, steps, a hash
/// of the bits of the final state). The step path of `Stabilised` keeps its results to the
/// bit when its storage changes: the hash is compared across versions.
fn stabilised_run(p: usize) -> (f64, f64, usize, u64) {
    let mut times = Vec::new();
    let mut set_up = Vec::new();
    let mut result = (0, 0);
    for _ in 0..21 {
        let (y, yp) = Pendulums(p).initial(None);
        let opts = dpc_core::radau::Options::with_tolerances(1e-8, 1e-8);
        let start = Instant::now();
        let mut s = dpc_core::radau::Radau::stabilised(Pendulums(p), opts, 0.0, &y, &yp).unwrap();
        set_up.push(start.elapsed().as_secs_f64() * 1e3);
        let start = Instant::now();
        let mut out = vec![0.0; 6 * p];
        s.solve_to(10.0, &mut out, None).unwrap();
        times.push(start.elapsed().as_secs_f64() * 1e3);
        let hash = out.iter().fold(0u64, |h, v| {
            h.rotate_left(5) ^ v.to_bits().wrapping_mul(0x9e37_79b9_7f4a_7c15)
        });
        result = (s.stats().steps, hash);
    }
    times.sort_by(f64::total_cmp);
    set_up.sort_by(f64::total_cmp);
    (set_up[10], times[10], result.0, result.1)
}

/// The step path of the stabilised form on 1, 4 and 40 pendulums: time, steps and the hash of
/// the final state (the same hash before and after a change of `Stabilised`'s storage). Since
/// the stabilised form declares its pattern (2026-12-05), 40 pendulums (240 unknowns) run on
/// the sparse LU instead of the dense one: their hash is not comparable with runs before that.
#[test]
#[ignore = "timing run: release mode"]
fn stabilised_step_path_times_and_bits() {
    for p in [1, 4, 40] {
        let (set_up, ms, steps, hash) = stabilised_run(p);
        println!(
            "stabilised pendulums {p}: set-up {set_up:.3} ms, run {ms:.3} ms, {steps} steps, \
             final state {hash:016x}"
        );
    }
}
