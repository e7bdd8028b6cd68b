//! The verdict of Theorem 3.2 in the three typical situations: stable without help, stable only
//! with the preliminary feedback, and non-minimum phase (no preliminary feedback can help).

use dpc_core::linear_analysis::{analyze, AnalysisOptions, LinearSystem, PrefeedbackPolicy};
use nalgebra::DMatrix;
use num_complex::Complex;

fn m(r: usize, c: usize, v: &[f64]) -> DMatrix<f64> {
    DMatrix::from_row_slice(r, c, v)
}

#[test]
fn full_hirschorn_leaves_no_infinite_part() {
    // Double integrator, W = (s + 2)(s + 3): D_hat invertible, P1 = I, index 0.
    let sys = LinearSystem::without_feedthrough(
        m(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        m(2, 1, &[0.0, 1.0]),
        m(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    let opts = AnalysisOptions {
        w: Some(vec![vec![2.0, 3.0]]),
        ..Default::default()
    };
    let r = analyze(&sys, &opts).unwrap();
    assert_eq!((r.nu, r.finite_dim), (0, 2));
    assert!(r.abar4_eigenvalues.is_empty());
    assert!(r.dpc_stable);
    assert!(r.k_n.is_none());
    // u = K_J x + R_xi xi with R_xi = 1 / D_hat = 1: K_J = -(6, 5).
    assert!(
        (&r.k_j - m(1, 2, &[-6.0, -5.0])).amax() < 1e-10,
        "{}",
        r.k_j
    );
    assert_eq!(r.r_xi.len(), 1);
    assert!((r.r_xi[0][(0, 0)] - 1.0).abs() < 1e-12);
    let mut cl = r.closed_loop_eigenvalues.clone();
    cl.sort_by(|a, b| a.re.total_cmp(&b.re));
    assert!((cl[0] - Complex::new(-3.0, 0.0)).norm() < 1e-9);
    assert!((cl[1] - Complex::new(-2.0, 0.0)).norm() < 1e-9);
}

#[test]
fn non_minimum_phase_cannot_be_fixed_by_prefeedback() {
    // xi' = -xi + eta + u, eta' = eta + xi, y = xi: a zero at +1.
    let sys = LinearSystem::without_feedthrough(
        m(2, 2, &[-1.0, 1.0, 1.0, 1.0]),
        m(2, 1, &[1.0, 0.0]),
        m(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    let opts = AnalysisOptions {
        prefeedback: PrefeedbackPolicy::Always,
        ..Default::default()
    };
    let r = analyze(&sys, &opts).unwrap();
    assert!((r.transmission_zeros[0] - Complex::new(1.0, 0.0)).norm() < 1e-10);
    assert!(!r.minimum_phase);
    assert!(!r.dpc_stable);
    assert_eq!(r.dpc_stable_prefeedback, Some(false));
    let cl = r.closed_loop_eigenvalues_prefeedback.unwrap();
    assert!(cl
        .iter()
        .any(|z| (z - Complex::new(1.0, 0.0)).norm() < 1e-8));
}

#[test]
fn transfer_points_are_reported_for_the_original_system() {
    let sys = LinearSystem::without_feedthrough(
        m(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        m(2, 1, &[0.0, 1.0]),
        m(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    let opts = AnalysisOptions {
        w: Some(vec![vec![2.0]]),
        transfer_points: vec![Complex::new(0.0, 1.0), Complex::new(2.0, 0.0)],
        ..Default::default()
    };
    let r = analyze(&sys, &opts).unwrap();
    // H(s) = 1/s^2: -1 at s = i, 0.25 at s = 2.
    assert!((r.transfer[0].re[0][0] + 1.0).abs() < 1e-12 && r.transfer[0].im[0][0].abs() < 1e-12);
    assert!((r.transfer[1].re[0][0] - 0.25).abs() < 1e-12);
}
