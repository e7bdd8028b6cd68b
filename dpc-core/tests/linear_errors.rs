//! Every error of the linear analysis, with a message that says what was found.

use dpc_core::linear_analysis::{analyze, place, AnalysisOptions, LinearError, LinearSystem};
use nalgebra::DMatrix;
use num_complex::Complex;

fn m(r: usize, c: usize, v: &[f64]) -> DMatrix<f64> {
    DMatrix::from_row_slice(r, c, v)
}

fn double_integrator() -> LinearSystem {
    LinearSystem::without_feedthrough(
        m(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        m(2, 1, &[0.0, 1.0]),
        m(1, 2, &[1.0, 0.0]),
    )
    .unwrap()
}

#[test]
fn non_square_system() {
    let e = LinearSystem::without_feedthrough(
        m(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        m(2, 1, &[0.0, 1.0]),
        m(2, 2, &[1.0, 0.0, 0.0, 1.0]),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        LinearError::NonSquare {
            inputs: 1,
            outputs: 2
        }
    ));
    assert!(e.to_string().contains("1 inputs but 2 outputs"));
}

#[test]
fn dimension_mismatch() {
    let e = LinearSystem::without_feedthrough(
        m(2, 3, &[0.0; 6]),
        m(2, 1, &[0.0, 1.0]),
        m(1, 2, &[1.0, 0.0]),
    )
    .unwrap_err();
    assert!(e.to_string().contains("A is 2x3"), "{e}");
    let e = LinearSystem::new(
        m(2, 2, &[0.0; 4]),
        m(2, 1, &[0.0, 1.0]),
        m(1, 2, &[1.0, 0.0]),
        m(2, 2, &[0.0; 4]),
    )
    .unwrap_err();
    assert!(e.to_string().contains("D is 2x2"), "{e}");
}

#[test]
fn nan_input() {
    let e = LinearSystem::without_feedthrough(
        m(2, 2, &[0.0, f64::NAN, 0.0, 0.0]),
        m(2, 1, &[0.0, 1.0]),
        m(1, 2, &[1.0, 0.0]),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        LinearError::NonFinite {
            matrix: "A",
            row: 0,
            col: 1,
            ..
        }
    ));
}

#[test]
fn non_invertible_when_b_d_lose_rank() {
    let sys = LinearSystem::without_feedthrough(
        m(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        m(2, 2, &[1.0, 1.0, 0.0, 0.0]),
        m(2, 2, &[1.0, 0.0, 0.0, 1.0]),
    )
    .unwrap();
    let e = analyze(&sys, &AnalysisOptions::default()).unwrap_err();
    assert!(
        matches!(e, LinearError::NotInvertible { rank: 1, m: 2, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("rank [B; D] = 1 < m = 2"), "{e}");
}

#[test]
fn singular_pencil_when_the_transfer_matrix_is_singular() {
    // Two identical outputs: H(s) has rank 1.
    let sys = LinearSystem::without_feedthrough(
        m(2, 2, &[0.0; 4]),
        m(2, 2, &[1.0, 0.0, 0.0, 1.0]),
        m(2, 2, &[1.0, 0.0, 1.0, 0.0]),
    )
    .unwrap();
    let e = analyze(&sys, &AnalysisOptions::default()).unwrap_err();
    assert!(matches!(e, LinearError::SingularPencil { n: 2, .. }), "{e}");
}

#[test]
fn bad_w() {
    let sys = double_integrator();
    let neg = AnalysisOptions {
        w: Some(vec![vec![-1.0]]),
        ..Default::default()
    };
    assert!(matches!(
        analyze(&sys, &neg),
        Err(LinearError::BadW { output: 0, .. })
    ));
    let too_high = AnalysisOptions {
        w: Some(vec![vec![1.0, 2.0, 3.0]]),
        ..Default::default()
    };
    let e = analyze(&sys, &too_high).unwrap_err();
    assert!(e.to_string().contains("relative degree"), "{e}");
    let wrong_count = AnalysisOptions {
        w: Some(vec![vec![1.0], vec![1.0]]),
        ..Default::default()
    };
    assert!(matches!(
        analyze(&sys, &wrong_count),
        Err(LinearError::DimensionMismatch { .. })
    ));
    // A malformed W is reported as such even when one of its roots is far beyond the plant's
    // scale (only numerical failures are blamed on that scale).
    let wrong_count_far = AnalysisOptions {
        w: Some(vec![vec![1e9], vec![1.0]]),
        ..Default::default()
    };
    let e = analyze(&sys, &wrong_count_far).unwrap_err();
    assert!(matches!(e, LinearError::DimensionMismatch { .. }), "{e}");
    // Degree equal to the relative degree, and a zero entry (plain differentiation), are fine.
    let ok = AnalysisOptions {
        w: Some(vec![vec![0.0, 3.0]]),
        ..Default::default()
    };
    let r = analyze(&sys, &ok).unwrap();
    assert_eq!(r.nu, 0);
    assert_eq!(r.finite_dim, 2);
}

#[test]
fn uncontrollable_pair_when_k2_is_asked_for() {
    let a = m(2, 2, &[1.0, 0.0, 0.0, 2.0]);
    let b = m(2, 1, &[1.0, 0.0]);
    let e = place::place(&a, &b, &[Complex::new(-1.0, 0.0); 2], 100.0).unwrap_err();
    assert!(
        matches!(
            e,
            LinearError::Uncontrollable {
                controllable_dim: 1,
                dim: 2,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("dimension 1 of 2"), "{e}");
}

#[test]
fn bad_poles() {
    let sys = double_integrator();
    let opts = AnalysisOptions {
        poles: Some(vec![Complex::new(-1.0, 1.0), Complex::new(-2.0, 0.0)]),
        prefeedback: dpc_core::linear_analysis::PrefeedbackPolicy::Always,
        ..Default::default()
    };
    let e = analyze(&sys, &opts).unwrap_err();
    assert!(matches!(e, LinearError::BadPoles { .. }), "{e}");
    let opts = AnalysisOptions {
        poles: Some(vec![Complex::new(-1.0, 0.0)]),
        prefeedback: dpc_core::linear_analysis::PrefeedbackPolicy::Always,
        ..Default::default()
    };
    let e = analyze(&sys, &opts).unwrap_err();
    assert!(e.to_string().contains("1 poles given for a 2x2"), "{e}");
}

#[test]
fn place_handles_multiplicity_above_rank_b_and_complex_pairs() {
    // Triple integrator with one input: all poles at -2 (multiplicity 3 > rank B = 1).
    let a = m(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    let b = m(3, 1, &[0.0, 0.0, 1.0]);
    let k = place::place(&a, &b, &[Complex::new(-2.0, 0.0); 3], 100.0).unwrap();
    let cl = &a + &b * &k;
    // Characteristic polynomial (s + 2)^3: check (A + BK + 2I)^3 = 0.
    let shifted = &cl + DMatrix::identity(3, 3) * 2.0;
    assert!((&shifted * &shifted * &shifted).amax() < 1e-9);
    // Two inputs, complex pair plus a real pole.
    let b2 = m(3, 2, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let poles = [
        Complex::new(-1.0, 2.0),
        Complex::new(-1.0, -2.0),
        Complex::new(-3.0, 0.0),
    ];
    let k = place::place(&a, &b2, &poles, 100.0).unwrap();
    let ev = dpc_core::linear_analysis::eigenvalues(&(&a + &b2 * &k)).unwrap();
    for p in poles {
        assert!(ev.iter().any(|z| (z - p).norm() < 1e-8), "{ev:?}");
    }
}
