//! Radau IIA's steps allocate nothing after set-up with a fixed-size model (its real and
//! complex stage matrices, Newton, the error estimate and dense output), and faer's sparse LU,
//! as the BDF and Radau use it, allocates nothing once its factors have their size:
//! `linear_solver::FaerSparseLu` and Radau's complex LU in the same pattern keep faer's numeric
//! factors, row permutation and work space from one factorisation to the next (the BDF's
//! fixed-size and banded paths: `tests/bdf_alloc.rs`).
//!
//! A counting global allocator (in its own test binary, so no other test interferes) records
//! every allocation of the test's thread. The Test Set's two bit adding unit (350 unknowns, a
//! pattern that `FaerLu::for_dae` gives to the sparse LU) is integrated for a while, so that
//! the factors reach their largest fill, then for a further stretch in which nothing may be
//! allocated.

#[path = "common/counting_allocator.rs"]
mod counting_allocator;
#[path = "common/bdf_problems.rs"]
mod problems;
#[path = "common/two_bit_adder.rs"]
mod two_bit_adder;

use counting_allocator::allocations;
use dpc_core::bdf::{self, Bdf};
use dpc_core::linear_solver::{FaerDenseLu, FaerLu, FaerSparseLu, LinearSolver, NalgebraLu};
use dpc_core::radau::{self, Radau};
use dpc_core::MatrixSink;
use problems::{robertson_atol, Pendulum, Robertson, PENDULUM_INDEX, ROBERTSON_START};
use two_bit_adder::{TwoBitAdder, TBA_N};

#[test]
fn radau_steps_after_setup_do_not_allocate() {
    // Robertson (index 1) over 16 decades of `t`: rejections, Newton failures, Jacobian
    // reuse and refreshes, interpolated outputs with their derivatives.
    let (y0, yp0) = ROBERTSON_START;
    let opts = radau::Options {
        atol: dpc_core::bdf::Tolerance::Vector(robertson_atol(1e-6)),
        ..radau::Options::with_tolerances(1e-6, 1e-6)
    };
    let mut s = Radau::new(Robertson, NalgebraLu::<3>::new(), opts, 0.0, &y0, &yp0).unwrap();
    let (mut y, mut yp) = ([0.0; 3], [0.0; 3]);
    s.solve_to(1e-6, &mut y, Some(&mut yp)).unwrap();
    let before = allocations();
    let mut t = 1e-5;
    while t <= 1e10 {
        s.solve_to(t, &mut y, Some(&mut yp)).unwrap();
        t *= 10.0;
    }
    let st = s.stats();
    assert!(st.steps > 50 && st.factorisations > 10, "{st:?}");
    assert_eq!(allocations() - before, 0, "{st:?}");

    // The index-3 pendulum, its index declared (RADAU5's scaled error estimate), to `t = 3`
    // with output every 0.1; then the same on faer's dense LU.
    let p = Pendulum::default();
    let (y0, yp0) = p.initial(1.0);
    let opts = radau::Options {
        index: PENDULUM_INDEX.to_vec(),
        ..radau::Options::with_tolerances(1e-6, 1e-6)
    };
    let mut s = Radau::new(p, NalgebraLu::<5>::new(), opts.clone(), 0.0, &y0, &yp0).unwrap();
    let mut y = [0.0; 5];
    s.step().unwrap();
    let before = allocations();
    for k in 1..=30 {
        s.solve_to(0.1 * f64::from(k), &mut y, None).unwrap();
    }
    assert!(s.stats().steps > 30, "{:?}", s.stats());
    assert_eq!(allocations() - before, 0, "pendulum, fixed size");
    let mut s = Radau::new(p, FaerDenseLu::new(5), opts, 0.0, &y0, &yp0).unwrap();
    s.step().unwrap();
    let before = allocations();
    for k in 1..=30 {
        s.solve_to(0.1 * f64::from(k), &mut y, None).unwrap();
    }
    assert_eq!(allocations() - before, 0, "pendulum, faer's dense LU");
}

#[test]
fn sparse_factorisations_and_solves_do_not_allocate() {
    // A 200 x 200 arrow matrix (full first row and column, a diagonal): its fill depends on
    // the pivots, which change with the values below.
    let n = 200;
    let pattern: Vec<(usize, usize)> = (0..n).flat_map(|i| [(i, i), (0, i), (i, 0)]).collect();
    let mut ls = FaerSparseLu::new(n, &pattern).unwrap();
    let mut b = vec![0.0; n];
    let fill = |ls: &mut FaerSparseLu, s: f64| {
        let m = ls.matrix_mut();
        m.fill_zero();
        for i in 0..n {
            m.set(i, i, 2.0 + s * (i as f64).sin());
            if i > 0 {
                m.set(0, i, 1.0);
                m.set(i, 0, s);
            }
        }
    };
    // First factorisation: the factors get their storage.
    fill(&mut ls, 0.5);
    ls.factor().unwrap();
    ls.solve_in_place(&mut b);
    let before = allocations();
    for k in 0..20 {
        fill(&mut ls, 0.5 + 0.01 * f64::from(k));
        ls.factor().unwrap();
        b.iter_mut().enumerate().for_each(|(i, v)| *v = i as f64);
        ls.solve_in_place(&mut b);
        assert!(b.iter().all(|v| v.is_finite()));
    }
    assert_eq!(allocations() - before, 0);
}

#[test]
fn bdf_steps_on_the_sparse_lu_do_not_allocate() {
    let dae = TwoBitAdder::new();
    let (y0, yp0) = dae.initial();
    let ls = FaerLu::for_dae(&dae);
    assert!(ls.is_sparse());
    let opts = bdf::Options::with_tolerances(1e-4, 1e-4);
    let mut s = Bdf::new(dae, ls, opts, 0.0, &y0, &yp0).unwrap();
    let mut y = vec![0.0; TBA_N];
    s.set_stop_time(40.0).unwrap();
    s.solve_to(10.0, &mut y, None).unwrap();
    let (before, warm) = (allocations(), s.stats());
    s.solve_to(40.0, &mut y, None).unwrap();
    let st = s.stats();
    assert!(
        st.steps > warm.steps + 50 && st.factorisations > warm.factorisations + 5,
        "{warm:?} -> {st:?}"
    );
    assert_eq!(allocations() - before, 0, "{st:?}");
}

#[test]
fn radau_steps_on_the_sparse_lus_do_not_allocate() {
    // Radau's pivots move more than the BDF's: once on the way to `t = 40` (at step 157) a
    // factorisation needs more fill than every earlier one, and faer's four vectors of `L`
    // and `U` (indices and values) grow, each to at least twice its capacity; from there on
    // nothing is allocated.
    let dae = TwoBitAdder::new();
    let (y0, yp0) = dae.initial();
    let ls = FaerLu::for_dae(&dae);
    assert!(ls.is_sparse());
    let opts = radau::Options::with_tolerances(1e-4, 1e-4);
    let mut s = Radau::new(dae, ls, opts, 0.0, &y0, &yp0).unwrap();
    let mut y = vec![0.0; TBA_N];
    s.set_stop_time(80.0).unwrap();
    s.solve_to(10.0, &mut y, None).unwrap();
    let before = allocations();
    s.solve_to(40.0, &mut y, None).unwrap();
    let growth = allocations() - before;
    assert!(growth <= 4, "{growth} allocations");
    let (before, warm) = (allocations(), s.stats());
    s.solve_to(80.0, &mut y, None).unwrap();
    let st = s.stats();
    assert!(
        st.steps > warm.steps + 50 && st.factorisations > warm.factorisations + 20,
        "{warm:?} -> {st:?}"
    );
    assert_eq!(allocations() - before, 0, "{st:?}");
}
