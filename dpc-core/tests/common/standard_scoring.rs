//! One scoring of the three standard problems of `standard_dae.rs` (Akzo Nobel, HIRES,
//! Ascher-Petzold) for every integrator under test: `bdf_testset.rs` and `radau_testset.rs` each
//! supply a [`Integrator`] and set their own digit floors on the medians it returns. Needs the
//! sibling modules `standard_dae` and `testset_index3` (for the Test Set's measures).
#![allow(dead_code)]

use super::standard_dae::*;
pub use super::testset_index3::median_over_jitter;
use super::testset_index3::{mescd, scd};
use dpc_core::ImplicitDae;

/// An integrator under test, as a user runs it on one problem.
pub trait Integrator {
    /// Its name in printed lines.
    const NAME: &'static str;
    /// Its statistics, printed with each result.
    type Stats: std::fmt::Debug;

    /// `dae` from `(y0, y0')` at `t = 0` to `t_end` at `rtol = atol = tol`, with `index` per
    /// unknown (empty: all 1): `(y(t_end), statistics)`.
    fn run<D: ImplicitDae>(
        &self,
        dae: D,
        start: (&[f64], &[f64]),
        index: &[u8],
        t_end: f64,
        tol: f64,
    ) -> (Vec<f64>, Self::Stats);
}

/// Median scd over the jitter at `tol` of Akzo Nobel (all components), HIRES (all) and
/// Ascher-Petzold (u1, u2 against the exact solution; w has index 2), in that order; prints
/// each with its mescd (Akzo, HIRES) or w's scd (Ascher-Petzold) and statistics at `tol`.
pub fn standard_dae_digits<I: Integrator>(integrator: &I, tol: f64) -> [f64; 3] {
    let ap = AscherPetzold::default();
    let (ay0, ayp0) = ChemAkzo::initial();
    let (hy0, hyp0) = Hires::initial();
    let (py0, pyp0) = AscherPetzold::exact(0.0);
    let (pref, _) = AscherPetzold::exact(AP_T_END);
    let all: Vec<usize> = (0..8).collect();
    let akzo = |t| integrator.run(ChemAkzo, (&ay0, &ayp0), &[], AKZO_T_END, t);
    let hires = |t| integrator.run(Hires, (&hy0, &hyp0), &[], HIRES_T_END, t);
    let apu = |t| integrator.run(ap, (&py0, &pyp0), &AP_INDEX, AP_T_END, t);
    let digits = [
        median_over_jitter(tol, |t| scd(&akzo(t).0, &AKZO_REF, &all[..6])),
        median_over_jitter(tol, |t| scd(&hires(t).0, &HIRES_REF, &all)),
        median_over_jitter(tol, |t| scd(&apu(t).0, &pref, &[0, 1])),
    ];
    let name = I::NAME;
    let (y, s) = akzo(tol);
    let m = mescd(&y, &AKZO_REF, &all[..6], tol, tol);
    println!(
        "Akzo {name} tol {tol:e}: median scd {:.2}, mescd {m:.2} at tol, {s:?}",
        digits[0]
    );
    let (y, s) = hires(tol);
    let m = mescd(&y, &HIRES_REF, &all, tol, tol);
    println!(
        "HIRES {name} tol {tol:e}: median scd {:.2}, mescd {m:.2} at tol, {s:?}",
        digits[1]
    );
    let (y, s) = apu(tol);
    let w = scd(&y, &pref, &[2]);
    println!(
        "Ascher-Petzold {name} tol {tol:e}: median scd (u) {:.2}, w {w:.2} at tol, {s:?}",
        digits[2]
    );
    digits
}

/// Ascher-Petzold at `tol`: the largest relative error of u1, u2 and that of w at `t = 1`
/// against the exact solution, with the statistics (printed).
pub fn ascher_petzold_errors<I: Integrator>(integrator: &I, tol: f64) -> (f64, f64, I::Stats) {
    let ap = AscherPetzold::default();
    let (py0, pyp0) = AscherPetzold::exact(0.0);
    let (pref, _) = AscherPetzold::exact(AP_T_END);
    let (y, s) = integrator.run(ap, (&py0, &pyp0), &AP_INDEX, AP_T_END, tol);
    let eu = (0..2)
        .map(|i| (y[i] - pref[i]).abs() / pref[i].abs())
        .fold(0.0, f64::max);
    let ew = (y[2] - pref[2]).abs() / pref[2].abs();
    println!(
        "Ascher-Petzold {} tol {tol:e}: error u {eu:.2e}, w {ew:.2e}, {s:?}",
        I::NAME
    );
    (eu, ew, s)
}
