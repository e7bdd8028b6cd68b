//! The Test Set's stiff ODEs (`common/stiff_odes.rs`: Van der Pol with `eps = 1e-6`, OREGO,
//! Pollution, the ring modulator), written as `F = y' - f(t, y)`, by the BDF and Radau IIA:
//! their iteration and mass matrices against differences of the residual, and the digits the
//! integrators reach, scored as the Test Set scores them (all components, `rtol = atol`, the
//! median over the tolerance jitter 0.9, 1, 1.1), with floors half a digit below the measured
//! medians. Accuracy and work are printed (`--nocapture`).

#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/stiff_odes.rs"]
mod stiff_odes;
#[path = "common/testset_index3.rs"]
mod testset_index3;

use dpc_core::linear_solver::NalgebraLu;
use dpc_core::{bdf, radau, ImplicitDae};
use matrix_check::{check_mass_matrix, matrix_error, perturbed};
use stiff_odes::*;
use testset_index3::{median_over_jitter, scd};

/// The BDF with the stack LU from the Test Set's `y(0)` to the interval's end at
/// `rtol = atol = tol` (10^6 steps allowed): `(y(t_end), stats)`.
fn bdf_run<P: StiffOde, const N: usize>(p: P, tol: f64) -> (Vec<f64>, bdf::Stats) {
    bdf_run_aged::<P, N>(p, tol, None)
}

/// [`bdf_run`] with iteration matrices serving at most `max_matrix_age` corrector solves
/// (`Some(0)`: IDA's rule, a new matrix only for a new `cj` or after a Newton failure).
fn bdf_run_aged<P: StiffOde, const N: usize>(
    p: P,
    tol: f64,
    max_matrix_age: Option<usize>,
) -> (Vec<f64>, bdf::Stats) {
    let dae = Ode(p);
    let (y0, yp0) = dae.initial();
    let opts = bdf::Options {
        max_steps: 1_000_000,
        max_matrix_age,
        ..bdf::Options::with_tolerances(tol, tol)
    };
    let mut s = bdf::Bdf::new(dae, NalgebraLu::<N>::new(), opts, 0.0, &y0, &yp0).unwrap();
    s.set_stop_time(P::T_END).unwrap();
    let mut y = vec![0.0; N];
    s.solve_to(P::T_END, &mut y, None)
        .unwrap_or_else(|e| panic!("BDF, tol {tol:e}: {e}"));
    (y, s.stats())
}

/// Radau IIA as [`bdf_run`].
fn radau_run<P: StiffOde, const N: usize>(p: P, tol: f64) -> (Vec<f64>, radau::Stats) {
    let dae = Ode(p);
    let (y0, yp0) = dae.initial();
    let opts = radau::Options {
        max_steps: 1_000_000,
        ..radau::Options::with_tolerances(tol, tol)
    };
    let mut s = radau::Radau::new(dae, NalgebraLu::<N>::new(), opts, 0.0, &y0, &yp0).unwrap();
    s.set_stop_time(P::T_END).unwrap();
    let mut y = vec![0.0; N];
    s.solve_to(P::T_END, &mut y, None)
        .unwrap_or_else(|e| panic!("Radau, tol {tol:e}: {e}"));
    (y, s.stats())
}

/// The Test Set's digits: scd over every component against the reference.
fn digits<P: StiffOde>(p: &P, y: &[f64]) -> f64 {
    let all: Vec<usize> = (0..P::N).collect();
    scd(y, &p.reference(), &all)
}

/// `c I - df/dy` against central differences of the residual (relative to the row's largest
/// entry) at the start, at the reference solution (`t_end`) and at both moved a little, for
/// `c = 1` and `c = 1e3`; the mass matrix is the identity, `c`-part of the iteration matrix.
fn check_matrices<P: StiffOde + Copy>(name: &str, p: P, floor: f64) {
    let dae = Ode(p);
    let (y0, yp0) = dae.initial();
    let yr = p.reference();
    let mut ypr = vec![0.0; P::N];
    p.f(P::T_END, &yr, &mut ypr);
    for (point, (t, y, yp)) in [("start", (0.0, y0, yp0)), ("end", (P::T_END, yr, ypr))] {
        let (tm, ym, ypm) = perturbed(t, &y, &yp, 7);
        for (moved, at) in [
            ("", (t, &y[..], &yp[..])),
            (" moved", (tm, &ym[..], &ypm[..])),
        ] {
            for c in [1.0, 1e3] {
                let e = matrix_error(&dae, at, c, (1e-6, floor));
                println!("{name} {point}{moved}, c = {c}: {e:.1e}");
                assert!(
                    e <= 1e-6,
                    "{name} {point}{moved}, c = {c}: {e:e} of the row"
                );
            }
        }
        check_mass_matrix(name, &dae, t, &y, &yp);
    }
}

#[test]
fn iteration_matrices_match_differences_of_the_residual() {
    // Measured: at most a few 1e-9 of the row (the differences' own truncation and round-off).
    check_matrices("Van der Pol", VanDerPol, 1e-3);
    check_matrices("OREGO", Orego, 1e-3);
    // f is quadratic in y: central differences are exact but for round-off, so steps of at
    // least 1e-9 (the concentrations reach 1e-17) keep that below the bound.
    check_matrices("Pollution", Pollution, 1e-3);
    check_matrices("ring modulator", RingModulator, 1e-3);
}

#[test]
fn initial_values_and_references_are_the_test_sets() {
    // The residual vanishes at (y0, f(0, y0)) and the reference solutions are those of the
    // Test Set's `solut` (spot checks on a transcription).
    fn consistent<P: StiffOde + Copy>(p: P) {
        let dae = Ode(p);
        let (y, yp) = dae.initial();
        let mut r = vec![1.0; P::N];
        dae.residual(0.0, &y, &yp, &mut r);
        assert!(r.iter().all(|v| *v == 0.0), "{r:?}");
        assert_eq!(p.reference().len(), P::N);
    }
    consistent(VanDerPol);
    consistent(Orego);
    consistent(Pollution);
    consistent(RingModulator);
    assert_eq!(Orego.reference()[1], 0.1228178521549917e4);
    assert_eq!(Pollution.reference()[15], 0.4352846369330103e-17);
    assert_eq!(RingModulator.reference()[6], 0.1106761861269975);
    assert_eq!(Ode(Pollution).unknown_name(15), "O1D");
}

/// The median digits over the jitter at `tol` of the BDF and of Radau on `p`, printed with the
/// work at `tol` itself.
fn medians<P: StiffOde + Copy, const N: usize>(name: &str, p: P, tol: f64) -> (f64, f64) {
    let b = median_over_jitter(tol, |t| digits(&p, &bdf_run::<P, N>(p, t).0));
    let r = median_over_jitter(tol, |t| digits(&p, &radau_run::<P, N>(p, t).0));
    let (_, sb) = bdf_run::<P, N>(p, tol);
    let (_, sr) = radau_run::<P, N>(p, tol);
    println!("{name} tol {tol:e}: BDF median scd {b:.2}, {sb:?}");
    println!("{name} tol {tol:e}: Radau median scd {r:.2}, {sr:?}");
    (b, r)
}

/// Checks the medians of [`medians`] at 1e-4, 1e-6, 1e-8 against `floors[k] = (bdf, radau)`.
fn check_digits<P: StiffOde + Copy, const N: usize>(name: &str, p: P, floors: [(f64, f64); 3]) {
    for (tol, (fb, fr)) in [1e-4, 1e-6, 1e-8].into_iter().zip(floors) {
        let (b, r) = medians::<P, N>(name, p, tol);
        assert!(
            b >= fb,
            "{name} BDF tol {tol:e}: median scd {b:.2} below {fb}"
        );
        assert!(
            r >= fr,
            "{name} Radau tol {tol:e}: median scd {r:.2} below {fr}"
        );
    }
}

// Measured medians (BDF / Radau) at 1e-4, 1e-6, 1e-8; floors half a digit below, rounded
// down. IDA 6.4.1 (bench/ida_peer.c, the same equations and exact Jacobians) at the tolerance
// itself: Van der Pol 2.60 / 4.87 / 6.64, OREGO 2.83 / 4.64 / 6.48, Pollution 2.02 / 3.60 /
// 4.83, the ring modulator 0.47 / 1.77 / 3.28 (docs/integrators.md, "The Test Set's stiff
// ODEs").

#[test]
fn van_der_pol_reaches_its_floors() {
    // BDF 2.68 / 4.87 / 6.64 (766, 1 234, 3 024 steps), Radau 5.02 / 6.57 / 8.58 (251, 491,
    // 1 053 steps).
    let floors = [(2.1, 4.5), (4.3, 6.0), (6.1, 8.0)];
    check_digits::<_, 2>("Van der Pol", VanDerPol, floors);
}

#[test]
fn orego_reaches_its_floors() {
    // BDF 2.91 / 4.82 / 6.51 (856, 1 841, 3 783 steps), Radau 4.38 / 6.67 / 7.72 (269, 527,
    // 1 115 steps).
    let floors = [(2.4, 3.8), (4.3, 6.1), (6.0, 7.2)];
    check_digits::<_, 3>("OREGO", Orego, floors);
}

#[test]
fn pollution_reaches_its_floors() {
    // BDF 2.09 / 3.60 / 4.83 (37, 94, 249 steps), Radau 2.51 / 3.02 / 4.38 (19, 26, 35 steps).
    // The error is spread evenly over the 20 species (at 1e-8 by the BDF: 2e-7 .. 1.5e-5
    // relative, the quasi-steady O1D at 4e-17 included): the global error of the chemistry's
    // slow modes, three to four digits short of the tolerance in every code.
    let floors = [(1.5, 2.0), (3.1, 2.5), (4.3, 3.8)];
    check_digits::<_, 20>("Pollution", Pollution, floors);
}

#[test]
fn ring_modulator_reaches_its_floors() {
    // BDF 0.51 / 1.73 / 3.30 (85 249, 173 458, 359 928 steps), Radau 1.33 / 3.04 / 4.54
    // (29 007, 64 947, 133 354 steps): more than the default 10^5 steps at 1e-6 and 1e-8.
    let floors = [(0.0, 0.8), (1.2, 2.5), (2.8, 4.0)];
    check_digits::<_, 15>("ring modulator", RingModulator, floors);
}

#[test]
fn van_der_pol_and_pollution_by_the_bdf_take_idas_steps() {
    // An ODE (regular dF/dy' = I): the BDF keeps IDA's rules and, with IDA's matrix rule (no
    // age bound), takes IDA 6.4.1's steps and error-test failures (bench/ida_peer.c), as on
    // HIRES (bdf_testset.rs). OREGO differs a
    // little (856 / 1 841 / 3 783 steps against IDA's 893 / 1 844 / 3 688: IDA's Newton
    // iteration fails 20 / 22 / 12 times, the BDF's never).
    for (tol, steps, failures) in [(1e-4, 766, 22), (1e-6, 1_234, 35)] {
        let (_, s) = bdf_run_aged::<_, 2>(VanDerPol, tol, Some(0));
        assert_eq!(
            (s.steps, s.error_test_failures),
            (steps, failures),
            "Van der Pol, tol {tol:e}"
        );
    }
    for (tol, steps, failures) in [(1e-4, 37, 1), (1e-6, 94, 2), (1e-8, 249, 1)] {
        let (_, s) = bdf_run_aged::<_, 20>(Pollution, tol, Some(0));
        assert_eq!(
            (s.steps, s.error_test_failures),
            (steps, failures),
            "Pollution, tol {tol:e}"
        );
    }
}
