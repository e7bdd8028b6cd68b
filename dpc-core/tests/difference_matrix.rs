//! The library's difference-quotient iteration matrix (`dpc_core::difference`) against the
//! exact matrices of fixtures that have one: entry errors of the formula's order relative to
//! the matrix, grouped and ungrouped columns alike, integrations that reach the digits of the
//! exact matrix with about its work, no allocation per matrix once set up, and a non-finite
//! residual at a perturbed point reaching the integrator as a failed matrix (a smaller step),
//! never as a finite wrong entry.

#[path = "common/bdf_problems.rs"]
mod bdf_problems;
#[path = "common/counting_allocator.rs"]
mod counting_allocator;
#[path = "common/differenced.rs"]
mod differenced;
#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/testset_index1.rs"]
mod testset_index1;
#[path = "common/testset_index3.rs"]
mod testset_index3;
#[path = "common/two_bit_adder.rs"]
mod two_bit_adder;
#[path = "common/water_tube.rs"]
mod water_tube;

use std::cell::Cell;

use bdf_problems::{
    robertson_atol, robertson_options, significant_digits, Robertson, ROBERTSON_REF,
};
use differenced::Differenced;
use dpc_core::bdf::{self, Bdf};
use dpc_core::difference::{DifferenceQuotients, Formula, Prepared};
use dpc_core::linear_solver::{FaerDenseLu, FaerLu, NalgebraLu};
use dpc_core::radau::{self, Radau};
use dpc_core::{ImplicitDae, MatrixSink};
use nalgebra::DMatrix;
use testset_index1::{TransistorAmplifier, TRANSAMP_REF, TRANSAMP_T_END};
use testset_index3::{
    andrews_index, scd, Andrews, CarAxis, ANDREWS_REF, ANDREWS_SCORED, ANDREWS_T_END,
    CAR_AXIS_INDEX,
};
use two_bit_adder::TwoBitAdder;
use water_tube::WaterTube;

/// Robertson's difference quotients with IDA's floor, the absolute tolerances of the run at
/// `rtol` (`y2` is of order `1e-5`, far from the default typical magnitude 1).
fn robertson_differences(rtol: f64) -> DifferenceQuotients {
    DifferenceQuotients::with_absolute_tolerance(&robertson_atol(rtol))
        .expect("positive tolerances")
}

/// The DAE stays `Send` and `Sync` with its difference quotients inside.
#[test]
fn a_dae_holding_differences_is_send_and_sync() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Differenced<Robertson>>();
    send_sync::<DifferenceQuotients>();
}

/// `(exact, differenced)` iteration matrices of `dae` at a point and `c`.
fn both<D: ImplicitDae>(
    dae: &D,
    dq: &DifferenceQuotients,
    (t, y, yp): (f64, &[f64], &[f64]),
    c: f64,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = dae.dimension();
    let (mut exact, mut diff) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    dae.iteration_matrix(t, y, yp, c, &mut exact);
    dq.iteration_matrix(dae, t, y, yp, c, &mut diff);
    (exact, diff)
}

/// The largest entry error relative to the matrix's largest entry.
fn relative_error(exact: &DMatrix<f64>, diff: &DMatrix<f64>) -> f64 {
    let norm = exact.amax();
    (exact - diff).amax() / norm
}

/// Fixture points: the initial one and one moved by a small pseudo-random amount.
fn points(y: &[f64], yp: &[f64]) -> Vec<(f64, Vec<f64>, Vec<f64>)> {
    vec![
        (0.0, y.to_vec(), yp.to_vec()),
        matrix_check::perturbed(0.0, y, yp, matrix_check::MASS_SEED),
    ]
}

/// Forward differences leave about `sqrt(eps)` (1.5e-8) of the matrix, central ones about
/// `eps^(2/3)` (3.7e-11), times the curvature of the residual over the unknowns' scale; both
/// also carry the rounding of `y'_j + c inc_j`, a relative `eps |y'_j| / (c inc_j)` of the
/// `c dF/dy'` part (the module documentation): bounds of 1000 times the sum relative to the
/// largest entry (the curvature factor is the problem's: the two bit adder's MOS currents take
/// central differences to 105 times `eps^(2/3)`, the others stay below 100), at `c` from 0
/// (Radau's `dF/dy`) to `1e6` (the BDF's first steps).
#[test]
fn differences_match_the_exact_matrices() {
    let eps = f64::EPSILON;
    let check = |name: &str, dae: &dyn Fn(&DifferenceQuotients, f64, usize) -> (f64, f64)| {
        for c in [0.0, 1.0, 1e3, 1e6] {
            for point in 0..2 {
                let (ef, rounding) = dae(&differenced::unit_scale(), c, point);
                let (ec, _) = dae(&differenced::unit_scale().central(), c, point);
                let forward_bound = 1000.0 * (eps.sqrt() + rounding / eps.sqrt());
                let central_bound = 1000.0 * (eps.powf(2.0 / 3.0) + rounding / eps.cbrt());
                println!(
                    "{name} c {c:e} point {point}: forward {ef:.1e} (bound {forward_bound:.1e}), \
                     central {ec:.1e} (bound {central_bound:.1e})"
                );
                assert!(
                    ef <= forward_bound,
                    "{name} c {c} point {point}: forward {ef:e}"
                );
                assert!(
                    ec <= central_bound,
                    "{name} c {c} point {point}: central {ec:e}"
                );
            }
        }
    };
    /// The relative entry error, and `eps max_j |y'_j| max|dF/dy'| / max|J|`: the rounding
    /// of `y'` times the increment over the unknown's scale (at least 1 here).
    fn run<D: ImplicitDae>(
        dae: &D,
        at: &[(f64, Vec<f64>, Vec<f64>)],
        dq: &DifferenceQuotients,
        c: f64,
        point: usize,
    ) -> (f64, f64) {
        let (t, y, yp) = &at[point];
        let (exact, diff) = both(dae, dq, (*t, y, yp), c);
        let n = dae.dimension();
        let (mut j0, mut j1) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
        dae.iteration_matrix(*t, y, yp, 0.0, &mut j0);
        dae.iteration_matrix(*t, y, yp, 1.0, &mut j1);
        let mass = (j1 - j0).amax();
        let yp_max = yp.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let rounding = if c > 0.0 {
            f64::EPSILON * yp_max * mass / exact.amax()
        } else {
            0.0
        };
        (relative_error(&exact, &diff), rounding)
    }
    // Robertson: the state after the initial transient as the moved point's base.
    let rob = points(&[0.9, 2e-5, 0.1], &[-0.01, 1e-6, 0.01]);
    check("Robertson", &|dq, c, p| {
        let floored =
            DifferenceQuotients::with_absolute_tolerance(&robertson_atol(1e-6)).expect("valid");
        let typical = match dq.formula() {
            Formula::Central => floored.central(),
            Formula::Forward => floored,
        };
        run(&Robertson, &rob, &typical, c, p)
    });
    let (y, yp) = TransistorAmplifier::initial();
    let amp = points(&y, &yp);
    check("amplifier", &|dq, c, p| {
        run(&TransistorAmplifier, &amp, dq, c, p)
    });
    let (y, yp) = Andrews::initial();
    let andrews = points(&y, &yp);
    check("Andrews", &|dq, c, p| run(&Andrews, &andrews, dq, c, p));
    let car = CarAxis::default();
    let (y, yp) = car.initial();
    let car_points = points(&y, &yp);
    check("car axis", &|dq, c, p| run(&car, &car_points, dq, c, p));
    let tba = TwoBitAdder::new();
    let (y, yp) = tba.initial();
    let tba_points = points(&y, &yp);
    check("two bit adder (grouped)", &|dq, c, p| {
        run(&tba, &tba_points, dq, c, p)
    });
}

/// Grouped columns (Curtis-Powell-Reid by the declared pattern) give the matrix of one residual
/// per column, within the entries' round-off, in far fewer residuals: the two bit adding unit
/// (350 unknowns) and a tridiagonal heat equation. The water tube declares no pattern; its
/// groups are counted with the structure read off its exact matrices at the initial point and
/// at moved points.
#[test]
fn grouped_and_ungrouped_columns_agree() {
    let tba = TwoBitAdder::new();
    let grouped = differenced::unit_scale();
    let plain = differenced::unit_scale().ungrouped();
    let g = grouped.prepare(&tba).expect("prepared");
    let p = plain.prepare(&tba).expect("prepared");
    println!("two bit adder: {g:?}; ungrouped {p:?}");
    assert!(g.pattern && !p.pattern);
    assert_eq!(p.groups, two_bit_adder::TBA_N);
    assert!(g.groups * 10 < p.groups, "{} groups", g.groups);
    let (y, yp) = tba.initial();
    for (t, y, yp) in points(&y, &yp) {
        for c in [0.0, 1e4] {
            let (_, a) = both(&tba, &grouped, (t, &y, &yp), c);
            let (_, b) = both(&tba, &plain, (t, &y, &yp), c);
            let e = relative_error(&b, &a);
            println!("two bit adder c {c:e}: grouped vs ungrouped {e:.1e}");
            assert!(e <= 16.0 * f64::EPSILON, "c {c}: {e:e}");
        }
    }

    // The water tube: the structure of its exact matrices, as a user would declare it.
    let n = water_tube::WATER_DIM;
    let (y0, yp0) = WaterTube::initial();
    let mut structure = DMatrix::from_element(n, n, false);
    for seed in 0..8u64 {
        let (t, y, yp) = if seed == 0 {
            (0.0, y0.to_vec(), yp0.to_vec())
        } else {
            matrix_check::perturbed(3600.0 * seed as f64, &y0, &yp0, seed)
        };
        for c in [0.0, 1.0] {
            let mut m = DMatrix::zeros(n, n);
            WaterTube.iteration_matrix(t, &y, &yp, c, &mut m);
            for (k, v) in m.iter().enumerate() {
                if *v != 0.0 {
                    structure[(k % n, k / n)] = true;
                }
            }
        }
    }
    let pattern: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .filter(|&(i, j)| structure[(i, j)])
        .collect();
    struct Patterned<'a>(&'a [(usize, usize)]);
    impl ImplicitDae for Patterned<'_> {
        fn dimension(&self) -> usize {
            WaterTube.dimension()
        }
        fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            WaterTube.residual(t, y, yp, out);
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            y: &[f64],
            yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            WaterTube.iteration_matrix(t, y, yp, c, out);
        }
        fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
            Some(self.0.to_vec())
        }
    }
    let water = Patterned(&pattern);
    let w = differenced::unit_scale().prepare(&water).expect("prepared");
    println!(
        "water tube: {} entries in the pattern, {w:?}",
        pattern.len()
    );
    assert!(w.groups < n);
    let (_, a) = both(&water, &differenced::unit_scale(), (0.0, &y0, &yp0), 10.0);
    let (exact, b) = both(
        &water,
        &differenced::unit_scale().ungrouped(),
        (0.0, &y0, &yp0),
        10.0,
    );
    let e = relative_error(&b, &a);
    println!(
        "water tube: grouped vs ungrouped {e:.1e}, vs exact {:.1e}",
        relative_error(&exact, &a)
    );
    assert!(e <= 16.0 * f64::EPSILON, "{e:e}");
}

/// Residual evaluations of one matrix: `groups + 1` forward, `2 groups` central, and the
/// pair with the residual one fewer.
#[test]
fn a_matrix_costs_the_residuals_it_says() {
    struct Counted<D>(D, Cell<usize>);
    impl<D: ImplicitDae> ImplicitDae for Counted<D> {
        fn dimension(&self) -> usize {
            self.0.dimension()
        }
        fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            self.1.set(self.1.get() + 1);
            self.0.residual(t, y, yp, out);
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            y: &[f64],
            yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            self.0.iteration_matrix(t, y, yp, c, out);
        }
        fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
            self.0.iteration_pattern()
        }
    }
    let dae = Counted(TwoBitAdder::new(), Cell::new(0));
    let (y, yp) = dae.0.initial();
    let n = dae.dimension();
    let mut m = DMatrix::zeros(n, n);
    for dq in [
        differenced::unit_scale(),
        differenced::unit_scale().central(),
    ] {
        let Prepared {
            groups,
            residuals_per_matrix,
            ..
        } = dq.prepare(&dae).expect("prepared");
        dae.1.set(0);
        dq.iteration_matrix(&dae, 0.0, &y, &yp, 1.0, &mut m);
        assert_eq!(dae.1.get(), residuals_per_matrix, "{groups} groups");
        dae.1.set(0);
        let mut r = vec![0.0; n];
        dq.residual_and_iteration_matrix(&dae, 0.0, &y, &yp, 1.0, &mut r, &mut m);
        let extra = usize::from(dq.formula() == dpc_core::difference::Formula::Central);
        assert_eq!(dae.1.get(), residuals_per_matrix + extra);
    }
}

/// Robertson to `t = 1e11` by the BDF at `rtol` with `dae`: (digits, stats).
fn robertson_bdf<D: ImplicitDae>(dae: D, rtol: f64) -> (f64, bdf::Stats) {
    let (y, stats) = robertson_run(dae, rtol);
    let y = y.expect("integrated");
    (significant_digits(&y, &ROBERTSON_REF, &[0, 1, 2]), stats)
}

/// Robertson to its end by the BDF at `rtol` (IDA's `atol`): the end value or the error, and
/// the work.
fn robertson_run<D: ImplicitDae>(
    dae: D,
    rtol: f64,
) -> (Result<[f64; 3], bdf::BdfError>, bdf::Stats) {
    let opts = robertson_options(rtol);
    let t_end = bdf_problems::ROBERTSON_T_END;
    let mut s = Bdf::new(
        dae,
        NalgebraLu::<3>::new(),
        opts,
        0.0,
        &[1.0, 0.0, 0.0],
        &[-0.04, 0.04, 0.0],
    )
    .expect("set up");
    s.set_stop_time(t_end).expect("stop time");
    let mut y = [0.0; 3];
    let result = s.solve_to(t_end, &mut y, None).map(|_| y);
    (result, s.stats())
}

/// The transistor amplifier to `t = 0.2` by the BDF at `rtol = atol = tol`: (digits, stats).
fn amplifier_bdf<D: ImplicitDae>(dae: D, tol: f64) -> (f64, bdf::Stats) {
    let (y0, yp0) = TransistorAmplifier::initial();
    let opts = bdf::Options::with_tolerances(tol, tol);
    let mut s = Bdf::new(dae, NalgebraLu::<8>::new(), opts, 0.0, &y0, &yp0).expect("set up");
    s.set_stop_time(TRANSAMP_T_END).expect("stop time");
    let mut y = [0.0; 8];
    s.solve_to(TRANSAMP_T_END, &mut y, None)
        .expect("integrated");
    (
        significant_digits(&y, &TRANSAMP_REF, &[0, 1, 2, 3, 4, 5, 6, 7]),
        s.stats(),
    )
}

/// Andrews' mechanism (index 3) to `t = 0.03` by Radau at `tol`: (digits on y1..y7, stats).
fn andrews_radau<D: ImplicitDae>(dae: D, tol: f64) -> (f64, radau::Stats) {
    let (y0, yp0) = Andrews::initial();
    let opts = radau::Options {
        index: andrews_index(),
        ..radau::Options::with_tolerances(tol, tol)
    };
    let mut s = Radau::new(dae, FaerDenseLu::new(27), opts, 0.0, &y0, &yp0).expect("set up");
    s.set_stop_time(ANDREWS_T_END).expect("stop time");
    let mut y = [0.0; 27];
    s.solve_to(ANDREWS_T_END, &mut y, None).expect("integrated");
    (scd(&y, &ANDREWS_REF, &ANDREWS_SCORED), s.stats())
}

/// The car axis (index 3) to `t = 3` by Radau at `tol`: (digits on the positions, stats).
fn car_axis_radau<D: ImplicitDae>(dae: D, tol: f64) -> (f64, radau::Stats) {
    let (y0, yp0) = CarAxis::default().initial();
    let opts = radau::Options {
        index: CAR_AXIS_INDEX.to_vec(),
        ..radau::Options::with_tolerances(tol, tol)
    };
    let mut s = Radau::new(dae, NalgebraLu::<10>::new(), opts, 0.0, &y0, &yp0).expect("set up");
    s.set_stop_time(testset_index3::CAR_AXIS_T_END)
        .expect("stop time");
    let mut y = [0.0; 10];
    s.solve_to(testset_index3::CAR_AXIS_T_END, &mut y, None)
        .expect("integrated");
    (
        scd(&y, &testset_index3::CAR_AXIS_REF, &[0, 1, 2, 3]),
        s.stats(),
    )
}

/// A fixture with its exact matrix times `1 + 1e-12`: a change of round-off size, to show how
/// far the digits of a run move with any change of the matrix.
struct Scaled<D>(D);

impl<D: ImplicitDae> ImplicitDae for Scaled<D> {
    fn dimension(&self) -> usize {
        self.0.dimension()
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.0.residual(t, y, yp, out);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let n = self.0.dimension();
        let mut m = DMatrix::zeros(n, n);
        self.0.iteration_matrix(t, y, yp, c, &mut m);
        for j in 0..n {
            for i in 0..n {
                if m[(i, j)] != 0.0 {
                    out.add(i, j, m[(i, j)] * (1.0 + 1e-12));
                }
            }
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        self.0.is_differential(i)
    }
}

/// Within `limit` (relative) of each other.
fn close(a: usize, b: usize, limit: f64) -> bool {
    (a as f64 - b as f64).abs() <= limit * (a.max(b) as f64)
}

/// With the difference matrix the integrations reach the digits of the exact matrix in about
/// its steps (within 10 % at the tolerance itself): a matrix a relative `sqrt(eps)` off
/// changes Newton's iterates by far less than its tolerance. Digits at one tolerance move by
/// up to a digit with any perturbation of the run: the amplifier at `1e-6` with its exact
/// matrix times `1 + 1e-12` reads 5.2 to 7.2 digits over the factors 0.8 to 1.2 of the
/// tolerance (5.2 to 6.3 unscaled, 4.7 to 6.2 with differences). So digits are compared as
/// medians over seven factors 0.8 to 1.2 of the tolerance, against the lower of the exact
/// matrix's median and that of the exact matrix times `1 + 1e-12` (a change of round-off
/// size, [`Scaled`]), and must not be more than half a digit below.
#[test]
fn integrations_with_differences_match_the_exact_matrix() {
    /// Medians over the jitter of the exact and the differenced runs, and the statistics
    /// of both at `tol` itself.
    fn compare<S: std::fmt::Debug>(
        name: &str,
        tol: f64,
        exact: impl Fn(f64) -> (f64, S),
        scaled: impl Fn(f64) -> (f64, S),
        differenced: impl Fn(f64) -> (f64, S),
        steps: impl Fn(&S) -> usize,
    ) {
        let median = |run: &dyn Fn(f64) -> f64| {
            let mut d: Vec<f64> = [0.8, 0.9, 0.95, 1.0, 1.05, 1.1, 1.2]
                .iter()
                .map(|f| run(f * tol))
                .collect();
            d.sort_by(f64::total_cmp);
            d[3]
        };
        let d0 = median(&|t| exact(t).0).min(median(&|t| scaled(t).0));
        let d1 = median(&|t| differenced(t).0);
        let (s0, s1) = (exact(tol).1, differenced(tol).1);
        println!("{name} tol {tol:e}: exact {d0:.2} {s0:?}\n  differences {d1:.2} {s1:?}");
        assert!(d1 >= d0 - 0.5, "{name} tol {tol}: {d1} vs {d0}");
        assert!(close(steps(&s1), steps(&s0), 0.1), "{name} tol {tol}");
    }
    let bdf_steps = |s: &bdf::Stats| s.steps;
    let radau_steps = |s: &radau::Stats| s.steps;
    for tol in [1e-4, 1e-6] {
        compare(
            "Robertson BDF",
            tol,
            |t| robertson_bdf(Robertson, t),
            |t| robertson_bdf(Scaled(Robertson), t),
            |t| robertson_bdf(Differenced::new(Robertson, robertson_differences(t)), t),
            bdf_steps,
        );
        compare(
            "amplifier BDF",
            tol,
            |t| amplifier_bdf(TransistorAmplifier, t),
            |t| amplifier_bdf(Scaled(TransistorAmplifier), t),
            |t| {
                amplifier_bdf(
                    Differenced::new(TransistorAmplifier, differenced::unit_scale()),
                    t,
                )
            },
            bdf_steps,
        );
        // Radau without a mass matrix from the model: `dF/dy'` as the difference of the
        // matrices at c = 1 and c = 0, exactly zero in the constraint rows (the same
        // increments at both).
        compare(
            "Andrews Radau",
            tol,
            |t| andrews_radau(Andrews, t),
            |t| andrews_radau(Scaled(Andrews), t),
            |t| andrews_radau(Differenced::new(Andrews, differenced::unit_scale()), t),
            radau_steps,
        );
        compare(
            "car axis Radau",
            tol,
            |t| car_axis_radau(CarAxis::default(), t),
            |t| car_axis_radau(Scaled(CarAxis::default()), t),
            |t| {
                car_axis_radau(
                    Differenced::new(CarAxis::default(), differenced::unit_scale()),
                    t,
                )
            },
            radau_steps,
        );
    }
}

/// The two bit adding unit by the BDF with grouped differences and faer's sparse LU, to the
/// first input switch: the exact matrix's steps and outputs.
#[test]
fn the_two_bit_adder_integrates_with_grouped_differences() {
    fn run<D: ImplicitDae>(dae: D, y0: &[f64], yp0: &[f64]) -> (Vec<f64>, bdf::Stats) {
        let ls = FaerLu::for_dae(&dae);
        let opts = bdf::Options::with_tolerances(1e-4, 1e-4);
        let mut s = Bdf::new(dae, ls, opts, 0.0, y0, yp0).expect("set up");
        let mut y = vec![0.0; y0.len()];
        let t_end = 10.0;
        s.set_stop_time(t_end).expect("stop time");
        s.solve_to(t_end, &mut y, None).expect("integrated");
        (y, s.stats())
    }
    let tba = TwoBitAdder::new();
    let (y0, yp0) = tba.initial();
    let (a, sa) = run(TwoBitAdder::new(), &y0, &yp0);
    let (b, sb) = run(
        Differenced::new(TwoBitAdder::new(), differenced::unit_scale()),
        &y0,
        &yp0,
    );
    let worst = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max);
    println!("two bit adder to t = 10: exact {sa:?}\n  differences {sb:?}\n  largest difference {worst:.1e}");
    assert!(close(sa.steps, sb.steps, 0.1));
    assert!(worst <= 1e-3, "{worst:e}");
}

/// Once set up, a matrix allocates nothing: the work vectors live in the value, sized by the
/// first call.
#[test]
fn matrices_after_the_first_do_not_allocate() {
    let tba = TwoBitAdder::new();
    let (y, yp) = tba.initial();
    let n = tba.dimension();
    let mut m = DMatrix::zeros(n, n);
    for dq in [
        differenced::unit_scale(),
        differenced::unit_scale().central(),
        differenced::unit_scale().ungrouped(),
    ] {
        dq.iteration_matrix(&tba, 0.0, &y, &yp, 1.0, &mut m);
        let mut r = vec![0.0; n];
        let before = counting_allocator::allocations();
        for k in 0..20 {
            m.fill_zero();
            dq.iteration_matrix(&tba, 0.0, &y, &yp, f64::from(k), &mut m);
            dq.residual_and_iteration_matrix(&tba, 0.0, &y, &yp, 1.0, &mut r, &mut m);
        }
        let during = counting_allocator::allocations() - before;
        assert_eq!(during, 0, "{:?}: {during} allocations", dq.formula());
    }
    // In an integration: Robertson's BDF steps with the difference matrix allocate nothing.
    let opts = robertson_options(1e-6);
    let dae = Differenced::new(Robertson, robertson_differences(1e-6));
    let mut s = Bdf::new(
        dae,
        NalgebraLu::<3>::new(),
        opts,
        0.0,
        &[1.0, 0.0, 0.0],
        &[-0.04, 0.04, 0.0],
    )
    .expect("set up");
    let mut y = [0.0; 3];
    s.solve_to(1e-6, &mut y, None).expect("integrated");
    let before = counting_allocator::allocations();
    let mut t = 1e-5;
    while t <= 1e10 {
        s.solve_to(t, &mut y, None).expect("integrated");
        t *= 10.0;
    }
    let during = counting_allocator::allocations() - before;
    assert!(s.stats().jacobian_evaluations > 10);
    assert_eq!(during, 0, "{during} allocations in {:?}", s.stats());
}

/// `y' = sqrt(1 - y)`, `y(0) = 0`: `y = 1 - (1 - t/2)^2` reaches 1 at `t = 2`, where the residual
/// stops being defined. The increment follows `y'` (upwards), so near `t = 2` the perturbed
/// point lies beyond 1 and its residual is NaN.
struct ToTheEdge;

impl ImplicitDae for ToTheEdge {
    fn dimension(&self) -> usize {
        1
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] - (1.0 - y[0]).sqrt();
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        _: f64,
        _: &mut S,
    ) {
    }
}

/// A non-finite residual at a perturbed point is a non-finite entry, never a finite one.
#[test]
fn a_non_finite_residual_at_a_perturbed_point_is_a_non_finite_entry() {
    let dq = differenced::unit_scale();
    let mut m = DMatrix::zeros(1, 1);
    let y = 1.0 - 1e-10;
    dq.iteration_matrix(&ToTheEdge, 0.0, &[y], &[(1e-10f64).sqrt()], 5.0, &mut m);
    assert!(!m[(0, 0)].is_finite(), "{}", m[(0, 0)]);
    // At y = 1 - 1e-10 moving down (y' < 0) the perturbed point stays inside: finite.
    m.fill_zero();
    dq.iteration_matrix(&ToTheEdge, 0.0, &[y], &[-1e-5], 5.0, &mut m);
    assert!(m[(0, 0)].is_finite(), "{}", m[(0, 0)]);
    // Away from the edge the entry is c + 1 / (2 sqrt(1 - y)).
    m.fill_zero();
    dq.iteration_matrix(&ToTheEdge, 0.0, &[0.75], &[0.5], 5.0, &mut m);
    assert!((m[(0, 0)] - 6.0).abs() < 1e-6, "{}", m[(0, 0)]);
}

/// `inner` whose difference matrices formed after `from` are poisoned, `shots` of them: the
/// residual is NaN at their perturbed points (as a model undefined just beyond the current
/// point would be), so the matrix's column of `y[0]` is not finite. The integrator's linear
/// solver refuses it; the BDF retries smaller with a fresh matrix, Radau stops.
struct Poisoned<D> {
    inner: D,
    differences: DifferenceQuotients,
    /// Matrices after this time are poisoned.
    from: f64,
    /// Matrices left to poison.
    shots: Cell<usize>,
    /// Matrices poisoned.
    poisoned: Cell<usize>,
}

impl<D> Poisoned<D> {
    fn new(inner: D, differences: DifferenceQuotients, from: f64, shots: usize) -> Self {
        Self {
            inner,
            differences,
            from,
            shots: Cell::new(shots),
            poisoned: Cell::new(0),
        }
    }
}

impl<D: ImplicitDae> ImplicitDae for Poisoned<D> {
    fn dimension(&self) -> usize {
        self.inner.dimension()
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.inner.residual(t, y, yp, out);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        if t > self.from && self.shots.get() > 0 {
            self.shots.set(self.shots.get() - 1);
            self.poisoned.set(self.poisoned.get() + 1);
            let edge = NanOffY0 {
                inner: &self.inner,
                y0: y[0],
            };
            self.differences.iteration_matrix(&edge, t, y, yp, c, out);
        } else {
            self.differences.iteration_matrix(self, t, y, yp, c, out);
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        self.inner.is_differential(i)
    }
}

/// `inner`'s residual, NaN wherever `y[0]` is not `y0`: column 0 of a difference matrix.
struct NanOffY0<'a, D> {
    inner: &'a D,
    y0: f64,
}

impl<D: ImplicitDae> ImplicitDae for NanOffY0<'_, D> {
    fn dimension(&self) -> usize {
        self.inner.dimension()
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.inner.residual(t, y, yp, out);
        if y[0] != self.y0 {
            out.fill(f64::NAN);
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        _: f64,
        _: &mut S,
    ) {
    }
}

/// Robertson with `shots` matrices after `t = 1` poisoned.
fn poisoned_robertson(shots: usize) -> Poisoned<Robertson> {
    Poisoned::new(Robertson, robertson_differences(1e-6), 1.0, shots)
}

#[test]
fn a_non_finite_matrix_is_retried_by_the_bdf_and_reported_by_radau() {
    let rtol = 1e-6;
    let (d0, s0) = robertson_bdf(
        Differenced::new(Robertson, robertson_differences(rtol)),
        rtol,
    );
    for shots in [1, 3] {
        let dae = poisoned_robertson(shots);
        let (d, st) = robertson_bdf(&dae, rtol);
        println!("Robertson with {shots} NaN matrices: {d:.2} {st:?} (undisturbed {d0:.2} {s0:?})");
        assert_eq!(dae.poisoned.get(), shots);
        assert!(
            st.newton_failures >= s0.newton_failures + shots,
            "{st:?} vs {s0:?}"
        );
        // Robertson's floor at 1e-6 (half a digit below the exact matrix's 3.29 at the
        // tolerance itself; single runs vary by tenths, see the integration test above).
        assert!(d >= 2.8, "{d} (undisturbed {d0})");
    }
    // Every matrix after t = 1 poisoned: the retries (each at a new predicted point) end in a
    // typed error naming the entry, not a vanished pivot.
    match robertson_run(poisoned_robertson(usize::MAX), rtol).0 {
        Err(bdf::BdfError::NonFiniteMatrix {
            t,
            equation,
            unknown,
        }) => {
            assert!(t > 1.0, "{t}");
            assert_eq!(
                (equation.as_str(), unknown.as_str()),
                ("equation 0", "y[0]")
            );
        }
        other => panic!("{other:?}"),
    }
    // Radau: the same, on Andrews' mechanism with its matrices after t = 0.01 poisoned.
    // Radau forms its matrix at the step's start, which a smaller step does not move: the
    // first non-finite matrix ends the run at once, in a typed error naming the entry.
    let (y0, yp0) = Andrews::initial();
    let dae = Poisoned::new(Andrews, differenced::unit_scale(), 0.01, usize::MAX);
    let opts = radau::Options {
        index: andrews_index(),
        ..radau::Options::with_tolerances(1e-6, 1e-6)
    };
    let mut s =
        Radau::new(&dae, FaerDenseLu::new(27), opts.clone(), 0.0, &y0, &yp0).expect("set up");
    s.set_stop_time(ANDREWS_T_END).expect("stop time");
    let mut y = [0.0; 27];
    let before = dae.shots.get();
    match s.solve_to(ANDREWS_T_END, &mut y, None) {
        Err(radau::RadauError::NonFiniteMatrix {
            t,
            equation,
            unknown,
        }) => {
            println!("Andrews Radau with NaN matrices from t = 0.01: stopped at t = {t}");
            assert!(t > 0.01);
            // Every residual at a perturbed point is NaN: the first entry is column 0's first.
            assert_eq!(
                (equation.as_str(), unknown.as_str()),
                ("equation 0", "y[0]")
            );
            // One Jacobian: its two matrix calls (`c = 0` and `c = 1`, no mass matrix here).
            assert_eq!(before - dae.shots.get(), 2);
        }
        other => panic!("{other:?}"),
    }
    // Poisoned from the start: no factorisation of it is tried (none fails), no step is cut.
    let dae = Poisoned::new(
        Andrews,
        differenced::unit_scale(),
        f64::NEG_INFINITY,
        usize::MAX,
    );
    let mut s = Radau::new(&dae, FaerDenseLu::new(27), opts, 0.0, &y0, &yp0).expect("set up");
    let result = s.solve_to(ANDREWS_T_END, &mut y, None);
    assert!(
        matches!(
            result,
            Err(radau::RadauError::NonFiniteMatrix { t: 0.0, .. })
        ),
        "{result:?}"
    );
    let st = s.stats();
    assert_eq!(
        (
            st.jacobian_evaluations,
            st.factorisations,
            st.newton_failures
        ),
        (1, 0, 0),
        "{st:?}"
    );
}
