//! The fixed-size back end makes integration steps allocation-free after setup.
//!
//! A counting global allocator (in its own test binary, so no other test interferes) records
//! every allocation of the test's thread; after the integrator is built and has taken its
//! first step, further steps, output requests and interpolation must not allocate at all.

#[path = "common/counting_allocator.rs"]
mod counting_allocator;
#[path = "common/heat2d.rs"]
mod heat2d;
#[path = "common/bdf_problems.rs"]
mod problems;

use counting_allocator::allocations;
use dpc_core::bdf::{Bdf, FixedBdf, MatrixUpdate, Options};
use dpc_core::linear_solver::{FaerDenseLu, NalgebraLu};
use problems::{robertson_bdf, robertson_options, Pendulum, Robertson, PENDULUM_INDEX};

#[test]
fn steps_after_setup_do_not_allocate() {
    // Variable step, Robertson (index 1): thousands of steps with rejections, order changes,
    // Jacobian refreshes and interpolation.
    let rtol = 1e-6;
    let opts = robertson_options(rtol);
    let mut bdf = robertson_bdf(Robertson, NalgebraLu::<3>::new(), opts).unwrap();
    let mut y = [0.0; 3];
    let mut yp = [0.0; 3];
    bdf.solve_to(1e-6, &mut y, Some(&mut yp)).unwrap();
    let before = allocations();
    let mut t = 1e-5;
    while t <= 1e10 {
        bdf.solve_to(t, &mut y, Some(&mut yp)).unwrap();
        t *= 10.0;
    }
    let steps = bdf.stats().steps;
    let during = allocations() - before;
    assert!(steps > 100, "{steps}");
    assert!(bdf.stats().error_test_failures > 0 && bdf.stats().factorisations > 10);
    assert_eq!(during, 0, "{during} allocations in {steps} steps");

    // Variable step, index-3 pendulum with excluded components.
    let p = Pendulum::default();
    let (y0, yp0) = p.initial(1.0);
    let opts = Options {
        index: PENDULUM_INDEX.to_vec(),
        ..Options::with_tolerances(1e-6, 1e-6)
    };
    let mut bdf = Bdf::new(p, NalgebraLu::<5>::new(), opts, 0.0, &y0, &yp0).unwrap();
    let mut y = [0.0; 5];
    bdf.step().unwrap();
    let before = allocations();
    for k in 1..=30 {
        bdf.solve_to(0.1 * f64::from(k), &mut y, None).unwrap();
    }
    assert_eq!(allocations() - before, 0);

    // Matrices moved to new `cj` with the mass matrix (`MatrixUpdate::Move`): the point of
    // evaluation is stored in vectors made at construction.
    let opts = Options {
        matrix_update: MatrixUpdate::Move,
        ..robertson_options(rtol)
    };
    let mut bdf = robertson_bdf(Robertson, NalgebraLu::<3>::new(), opts).unwrap();
    let mut y = [0.0; 3];
    bdf.solve_to(1e-6, &mut y, None).unwrap();
    let before = allocations();
    bdf.solve_to(1e10, &mut y, None).unwrap();
    let stats = bdf.stats();
    assert!(
        stats.factorisations > stats.jacobian_evaluations,
        "{stats:?}"
    );
    assert_eq!(allocations() - before, 0, "moved matrices");

    // The faer dense back end also keeps its workspace from construction on.
    let opts = robertson_options(rtol);
    let mut bdf = robertson_bdf(Robertson, FaerDenseLu::new(3), opts).unwrap();
    let mut y = [0.0; 3];
    bdf.solve_to(1e-6, &mut y, None).unwrap();
    let before = allocations();
    bdf.solve_to(1e10, &mut y, None).unwrap();
    assert!(bdf.stats().factorisations > 10);
    assert_eq!(allocations() - before, 0, "faer dense back end");

    // Fixed step from inconsistent values.
    let mut f = FixedBdf::new(
        p,
        NalgebraLu::<5>::new(),
        Options::default(),
        3,
        1e-3,
        0.0,
        &[0.8, -0.6, 1.0, 1.0, 0.0],
    )
    .unwrap();
    f.step().unwrap();
    let before = allocations();
    for _ in 0..1000 {
        f.step().unwrap();
    }
    assert_eq!(allocations() - before, 0);
}

/// The banded LU (`FaerLu::for_dae` on SUNDIALS' heat example) keeps its factors and
/// interchanges from construction on: steps, factorisations and solves allocate nothing.
#[test]
fn band_steps_do_not_allocate() {
    use dpc_core::linear_solver::FaerLu;
    use heat2d::{Heat2d, HEAT_N};
    let (y0, yp0) = Heat2d::initial();
    let ls = FaerLu::for_dae(&Heat2d);
    assert!(ls.is_band());
    let mut bdf = Bdf::new(
        Heat2d,
        ls,
        Options::with_tolerances(1e-8, 1e-8),
        0.0,
        &y0,
        &yp0,
    )
    .unwrap();
    let mut y = vec![0.0; HEAT_N];
    bdf.step().unwrap();
    let before = allocations();
    for k in 1..=16 {
        bdf.solve_to(0.01 * f64::from(k), &mut y, None).unwrap();
    }
    let st = bdf.stats();
    assert!(st.steps > 50 && st.factorisations > 5, "{st:?}");
    assert_eq!(allocations() - before, 0, "{st:?}");
}
