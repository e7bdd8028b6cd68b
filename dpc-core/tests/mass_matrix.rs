//! Every fixture's mass matrix `dF/dy'` ([`ImplicitDae::mass_matrix`]) is the `c`-part of its
//! iteration matrix: `J(c) = J(0) + c M` entry by entry, relative to the row's largest term,
//! for `c = 1` and `c = 1e3`, at the fixture's initial point and at a point moved by a small
//! pseudo-random amount (fixed seed; `tests/common/matrix_check.rs`), within its iteration
//! pattern when it declares one. Radau relies on it (it takes `M` from it instead of a second
//! iteration matrix), and so does `Stabilised` (the kinematic rows' `c_j`). The stabilised
//! forms of the index-3 fixtures (`Stabilised`, which forwards the wrapped DAE's) are checked
//! the same way, with
//! exact constraint derivatives (Andrews, the car axis, the pendulum, Fekete) and without them
//! (the circular track through `Stabilised::detect`).

#[path = "common/bdf_problems.rs"]
mod bdf_problems;
#[path = "common/fekete.rs"]
mod fekete;
#[path = "common/literature.rs"]
mod literature;
#[path = "common/matrix_check.rs"]
mod matrix_check;
#[path = "common/nand.rs"]
mod nand;
#[path = "common/pump.rs"]
mod pump;
#[path = "common/slider_crank.rs"]
mod slider_crank;
#[path = "common/standard_dae.rs"]
mod standard_dae;
#[path = "common/testset_index1.rs"]
mod testset_index1;
#[path = "common/testset_index3.rs"]
mod testset_index3;
#[path = "common/two_bit_adder.rs"]
mod two_bit_adder;
#[path = "common/water_tube.rs"]
mod water_tube;
#[path = "common/wheelset.rs"]
mod wheelset;

use dpc_core::stabilised::Stabilised;
use dpc_core::{ImplicitDae, MatrixSink};
use matrix_check::{check_mass_matrix, check_mass_matrix_within, mass_matrix_error, MASS_TOL};

/// [`check_mass_matrix`] at `(t, y, yp)`, the largest error printed (`--nocapture`).
fn check<D: ImplicitDae>(name: &str, dae: &D, t: f64, y: &[f64], yp: &[f64]) {
    let worst = check_mass_matrix(name, dae, t, y, yp);
    println!(
        "{name:<28} n = {:>3}: largest |J(c) - J(0) - c M| / row {worst:.1e}",
        dae.dimension()
    );
}

/// [`check`] on `dae`'s stabilised form at the stabilised `(y, mu = 0)`, within `(1 + c)`
/// times [`MASS_TOL`]: the hidden velocity constraints' `c`-terms in `J(c)`, `c G_aj` and
/// `-c G_aj dF_i/dy'_j / c_j`, cancel (their `dF/dy'` is zero) up to rounding: terms `c`
/// times as large as the `G_aj` in the velocity columns of the row (and a few ulps more where
/// `Stabilised` takes `c_j` from a difference of residuals, for a DAE without a mass matrix).
fn check_stabilised<D: ImplicitDae>(name: &str, s: &Stabilised<D>, t: f64, y: &[f64], yp: &[f64]) {
    let (ys, yps) = s.extend(y, yp);
    let worst = check_mass_matrix_within(name, s, (t, &ys, &yps), |c| (1.0 + c) * MASS_TOL);
    println!(
        "{name:<28} n = {:>3}: largest |J(c) - J(0) - c M| / row {worst:.1e}",
        s.dimension()
    );
}

#[test]
fn standard_problems() {
    let (y, yp) = standard_dae::ChemAkzo::initial();
    check("chemical Akzo Nobel", &standard_dae::ChemAkzo, 0.0, &y, &yp);
    let (y, yp) = standard_dae::Hires::initial();
    check("HIRES", &standard_dae::Hires, 0.0, &y, &yp);
    let (y, yp) = standard_dae::AscherPetzold::exact(0.0);
    check(
        "Ascher-Petzold",
        &standard_dae::AscherPetzold::default(),
        0.0,
        &y,
        &yp,
    );
    let (y, yp) = testset_index1::TransistorAmplifier::initial();
    check(
        "transistor amplifier",
        &testset_index1::TransistorAmplifier,
        0.0,
        &y,
        &yp,
    );
}

#[test]
fn bdf_problems() {
    check(
        "Robertson",
        &bdf_problems::Robertson,
        0.0,
        &[1.0, 0.0, 0.0],
        &[-0.04, 0.04, 0.0],
    );
    let p = bdf_problems::Pendulum::default();
    let (y, yp) = p.initial(bdf_problems::THETA0);
    check("pendulum", &p, 0.0, &y, &yp);
    let heat = bdf_problems::Heat { m: 20 };
    let (mut u, mut up) = (vec![0.0; 21], vec![0.0; 21]);
    heat.exact(0.0, &mut u, &mut up);
    check("heat (m = 20)", &heat, 0.0, &u, &up);
}

#[test]
fn index3_test_set() {
    let (y, yp) = testset_index3::Andrews::initial();
    check("Andrews", &testset_index3::Andrews, 0.0, &y, &yp);
    let car = testset_index3::CarAxis::default();
    let (y, yp) = car.initial();
    check("car axis", &car, 0.0, &y, &yp);
    let (y, yp) = slider_crank::SliderCrank::initial();
    check("slider crank", &slider_crank::SliderCrank, 0.0, &y, &yp);
    let (y, yp) = wheelset::Wheelset::initial();
    check("wheelset", &wheelset::Wheelset, 0.0, &y, &yp);
}

#[test]
fn fekete() {
    let (y, yp) = fekete::Fekete::initial();
    check("Fekete (GGL)", &fekete::Fekete, 0.0, &y, &yp);
    let (y, yp) = fekete::FeketeIndex3::initial();
    check("Fekete (index 3)", &fekete::FeketeIndex3, 0.0, &y, &yp);
}

#[test]
fn circuits_and_networks() {
    let (y, yp) = nand::Nand::initial();
    check("NAND gate", &nand::Nand, 0.0, &y, &yp);
    let (y, yp) = pump::Pump::initial();
    check("charge pump", &pump::Pump, 0.0, &y, &yp);
    let (y, yp) = water_tube::WaterTube::initial();
    check("water tube", &water_tube::WaterTube, 0.0, &y, &yp);
    let tba = two_bit_adder::TwoBitAdder::new();
    let (y, yp) = tba.initial();
    check("two bit adding unit", &tba, 0.0, &y, &yp);
}

#[test]
fn literature() {
    use literature::*;
    let (y, yp) = Kvaerno::exact(KVAERNO_T0);
    check("Kvaerno", &Kvaerno, KVAERNO_T0, &y, &yp);
    let (y, yp) = Jay::exact(0.0);
    for linear_multiplier in [false, true] {
        let name = format!("Jay (linear multiplier {linear_multiplier})");
        check(&name, &Jay { linear_multiplier }, 0.0, &y, &yp);
    }
    let (y, yp) = CircularTrack::exact(0.0);
    check("circular track", &CircularTrack, 0.0, &y, &yp);
    let (y, yp) = KNIFE.exact(0.0);
    check("knife edge", &KNIFE, 0.0, &y, &yp);
    // Bcp's M depends on t (eta t): checked away from t = 0 too.
    for eta in [-0.5, 1.0] {
        let p = Bcp { eta };
        for t in [0.0, 0.7] {
            let (y, yp) = p.exact(t);
            check(&format!("Bcp (eta {eta}, t {t})"), &p, t, &y, &yp);
        }
    }
}

#[test]
fn stabilised_forms() {
    let (y, yp) = testset_index3::Andrews::initial();
    check_stabilised(
        "Andrews (stabilised)",
        &testset_index3::Andrews::stabilised(),
        0.0,
        &y,
        &yp,
    );
    let car = testset_index3::CarAxis::default();
    let (y, yp) = car.initial();
    check_stabilised("car axis (stabilised)", &car.stabilised(), 0.0, &y, &yp);
    let (y, yp) = fekete::FeketeIndex3::initial();
    let s = Stabilised::detect(fekete::FeketeIndex3, 0.0, &y, &yp).unwrap();
    check_stabilised("Fekete (detected)", &s, 0.0, &y, &yp);
    let p = bdf_problems::Pendulum::default();
    let (y, yp) = p.initial(bdf_problems::THETA0);
    let s = Stabilised::new(p, vec![4], vec![(0, 0), (1, 1)]).unwrap();
    check_stabilised("pendulum (stabilised)", &s, 0.0, &y, &yp);
    // Without constraint derivatives: G and c_j from the iteration matrices.
    let (y, yp) = literature::CircularTrack::exact(0.3);
    let s = Stabilised::detect(literature::CircularTrack, 0.3, &y, &yp).unwrap();
    assert_eq!(s.n_constraints(), 1);
    check_stabilised("circular track (detected)", &s, 0.3, &y, &yp);
}

/// A DAE that supplies no mass matrix: its stabilised form supplies none either.
#[test]
fn stabilised_form_of_a_dae_without_mass_matrix() {
    struct NoMass;
    impl ImplicitDae for NoMass {
        fn dimension(&self) -> usize {
            5
        }
        fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            bdf_problems::Pendulum::default().residual(t, y, yp, out);
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            y: &[f64],
            yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            bdf_problems::Pendulum::default().iteration_matrix(t, y, yp, c, out);
        }
    }
    let (y, yp) = bdf_problems::Pendulum::default().initial(1.0);
    let s = Stabilised::new(NoMass, vec![4], vec![(0, 0), (1, 1)]).unwrap();
    let (ys, yps) = s.extend(&y, &yp);
    assert_eq!(
        mass_matrix_error(&s, (0.0, &ys, &yps), 1.0),
        Err("no mass matrix supplied".to_string())
    );
}

/// The check fails on a mass matrix with one entry wrong by a part in a million (the car
/// axis' `k` on one velocity row), at both points, and on one written outside the declared
/// iteration pattern (the heat equation's boundary row).
#[test]
fn check_rejects_a_wrong_entry() {
    struct OneWrong<D>(D, (usize, usize), f64);
    impl<D: ImplicitDae> ImplicitDae for OneWrong<D> {
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
            self.0.iteration_matrix(t, y, yp, c, out);
        }
        fn mass_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            y: &[f64],
            yp: &[f64],
            out: &mut S,
        ) -> bool {
            let ok = self.0.mass_matrix(t, y, yp, out);
            out.add(self.1 .0, self.1 .1, self.2);
            ok
        }
        fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
            self.0.iteration_pattern()
        }
    }
    let car = testset_index3::CarAxis::default();
    let (y, yp) = car.initial();
    let k = car.m * car.eps * car.eps / 2.0;
    let wrong = OneWrong(car, (5, 5), 1e-6 * k);
    for p in [
        (0.0, &y[..], &yp[..]),
        (0.1, &matrix_check::perturbed(0.0, &y, &yp, 1).1, &yp[..]),
    ] {
        let e = mass_matrix_error(&wrong, p, 1e3).unwrap();
        assert!(e > matrix_check::MASS_TOL, "{e:e}");
    }
    let heat = bdf_problems::Heat { m: 4 };
    let wrong = OneWrong(heat, (0, 1), 1.0);
    let (mut u, mut up) = (vec![0.0; 5], vec![0.0; 5]);
    heat.exact(0.0, &mut u, &mut up);
    let e = mass_matrix_error(&wrong, (0.0, &u, &up), 1.0).unwrap_err();
    assert!(e.contains("outside the iteration pattern"), "{e}");
}
