//! The paper's Section 4 example (4.1) with `W = s + 5` on both outputs. Only invariants are
//! compared (eigenvalues, transfer matrices, `R_xi`), never coordinate-dependent entries: the
//! paper's printed `Kbar_n` has a sign error with its printed `Q`.

use dpc_core::linear_analysis::{
    analyze, eigenvalues, transfer::polynomial_at, transfer::transfer_matrix, zeros,
    AnalysisOptions, LinearSystem,
};
use nalgebra::DMatrix;
use num_complex::Complex;

type C64 = Complex<f64>;

fn paper_system(g1: f64, g2: f64) -> LinearSystem {
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(5, 5, &[
        0.0, 0.0, 0.0, 1.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 1.0,
        0.0, 0.0, 0.0, -3.0, 0.0,
        6.54, 0.0, 5.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    #[rustfmt::skip]
    let b = DMatrix::from_row_slice(5, 2, &[
        0.0, 0.0,
        0.0, 0.0,
        g1, 0.0,
        0.0, 0.0,
        0.0, g2,
    ]);
    #[rustfmt::skip]
    let c = DMatrix::from_row_slice(2, 5, &[
        1.0, 0.0, 0.0, 0.0, 0.0,
        0.0, 1.0, 0.0, 0.0, 0.0,
    ]);
    LinearSystem::without_feedthrough(a, b, c).unwrap()
}

fn opts() -> AnalysisOptions {
    AnalysisOptions {
        w: Some(vec![vec![5.0], vec![5.0]]),
        poles: Some(vec![C64::new(-5.0, 0.0); 3]),
        ..Default::default()
    }
}

/// Every expected value is matched by a distinct computed one within `tol` (multiset match).
fn assert_same_set(got: &[C64], want: &[C64], tol: f64) {
    assert_eq!(got.len(), want.len(), "got {got:?}, want {want:?}");
    let mut used = vec![false; got.len()];
    for w in want {
        let k = (0..got.len())
            .filter(|&k| !used[k])
            .min_by(|&i, &j| (got[i] - w).norm().total_cmp(&(got[j] - w).norm()))
            .unwrap();
        assert!((got[k] - w).norm() < tol, "got {got:?}, want {want:?}");
        used[k] = true;
    }
}

fn c(re: f64, im: f64) -> C64 {
    C64::new(re, im)
}

#[test]
fn transfer_matrix_of_the_original_system() {
    let sys = paper_system(1.0, 1.0);
    for s in [c(0.3, 1.1), c(-2.0, 0.5), c(4.0, 0.0)] {
        let h = transfer_matrix(&sys, s).unwrap();
        let h11 = C64::from(5.0) / (s * s * s + 8.46 * s);
        let h22 = C64::from(1.0) / (s * s);
        assert!((h[(0, 0)] - h11).norm() < 1e-12 * (1.0 + h11.norm()));
        assert!((h[(1, 1)] - h22).norm() < 1e-12 * (1.0 + h22.norm()));
        assert!(h[(0, 1)].norm() < 1e-12 && h[(1, 0)].norm() < 1e-12);
    }
}

#[test]
fn paper_example_abar4_zeros_and_verdict() {
    let sys = paper_system(1.0, 1.0);
    let r = analyze(&sys, &opts()).unwrap();
    assert_eq!((r.n, r.m), (5, 2));
    assert_eq!(r.finite_dim, 2);
    assert_eq!(r.nu, 2);
    assert_same_set(&r.transmission_zeros, &[c(-5.0, 0.0), c(-5.0, 0.0)], 1e-6);
    assert_same_set(
        &r.abar4_eigenvalues,
        &[c(5.0, 0.0), c(2.5, 5.2163), c(2.5, -5.2163)],
        1e-3,
    );
    assert!(!r.dpc_stable);
    assert!(r.minimum_phase);
    // Closed loop of plain DPC = zeros ∪ eig(Abar_4).
    let mut both = r.transmission_zeros.clone();
    both.extend(&r.abar4_eigenvalues);
    assert_same_set(&r.closed_loop_eigenvalues, &both, 1e-6);
    // Zeros are where the Rosenbrock matrix of the stabilised system loses rank.
    let hat = sys.stabilise(&[vec![5.0], vec![5.0]]).unwrap();
    assert!(zeros::rosenbrock_sigma_min(&hat, c(-5.0, 0.0)) < 1e-12);
    assert!(zeros::rosenbrock_sigma_min(&hat, c(-4.0, 0.0)) > 1e-6);
    // Theorem 3.1 and 3.3 identities.
    assert!(
        r.law.theorem_3_1_residual < 1e-12,
        "{}",
        r.law.theorem_3_1_residual
    );
    assert!(r.law.vstar_distance < 1e-10, "{}", r.law.vstar_distance);
    assert_eq!(r.law.vstar_dim, 2);
    assert!(
        r.law.theorem_3_3_residual < 1e-10,
        "{}",
        r.law.theorem_3_3_residual
    );
}

#[test]
fn paper_example_prefeedback() {
    let sys = paper_system(1.0, 1.0);
    let r = analyze(&sys, &opts()).unwrap();
    let k_n = r.k_n.clone().expect("Abar_4 is unstable, so K_n is built");
    let k_j = r.k_j.clone();
    let k_j2 = r.k_j_prefeedback.clone().unwrap();
    // K_J' = K_J: K_n vanishes on the finite part.
    assert!((&k_j2 - &k_j).amax() < 1e-9 * (1.0 + k_j.amax()));
    let law2 = r.law_prefeedback.as_ref().unwrap();
    assert_same_set(&law2.abar4_eigenvalues, &[c(-5.0, 0.0); 3], 1e-3);
    let cl = r.closed_loop_eigenvalues_prefeedback.clone().unwrap();
    assert!(cl.iter().all(|z| z.re < -1.0), "{cl:?}");
    assert_eq!(r.dpc_stable_prefeedback, Some(true));

    // K_J alone and K_n alone leave the plant unstable; together they stabilise it.
    let alone_j = eigenvalues(&(&sys.a + &sys.b * &k_j)).unwrap();
    let alone_n = eigenvalues(&(&sys.a + &sys.b * &k_n)).unwrap();
    let both = eigenvalues(&(&sys.a + &sys.b * (&k_j + &k_n))).unwrap();
    assert!(alone_j.iter().any(|z| z.re > 0.0), "{alone_j:?}");
    assert!(alone_n.iter().any(|z| z.re > 0.0), "{alone_n:?}");
    assert!(both.iter().all(|z| z.re < 0.0), "{both:?}");

    // R_xi(s) = diag(5 + 2s + 0.2 s^2, 5 + s) after the preliminary feedback.
    let rx = r.r_xi_prefeedback.clone().unwrap();
    for s in [c(0.0, 0.0), c(1.0, 0.0), c(-0.7, 2.0), c(3.0, -1.0)] {
        let got = polynomial_at(&rx, s);
        let want11 = 5.0 + 2.0 * s + 0.2 * s * s;
        let want22 = 5.0 + s;
        assert!((got[(0, 0)] - want11).norm() < 1e-8, "{got}");
        assert!((got[(1, 1)] - want22).norm() < 1e-8, "{got}");
        assert!(
            got[(0, 1)].norm() < 1e-8 && got[(1, 0)].norm() < 1e-8,
            "{got}"
        );
    }
    assert!(law2.theorem_3_3_residual < 1e-10);
}

#[test]
fn wheel_linearisation_has_the_same_structure() {
    let sys = paper_system(2.0, 0.8);
    let r = analyze(&sys, &opts()).unwrap();
    assert_same_set(&r.transmission_zeros, &[c(-5.0, 0.0); 2], 1e-6);
    assert!(!r.dpc_stable);
    assert_eq!(r.dpc_stable_prefeedback, Some(true));
    let h = transfer_matrix(&sys, c(0.4, 0.9)).unwrap();
    let s = c(0.4, 0.9);
    assert!((h[(0, 0)] - 10.0 / (s * s * s + 8.46 * s)).norm() < 1e-12);
    assert!((h[(1, 1)] - 0.8 / (s * s)).norm() < 1e-12);
}
