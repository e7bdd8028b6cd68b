//! Linearising the generated wheel about the paper's nominal trajectory reproduces (4.1)
//! (with the Appendix's input gains), and the linear analysis of that linearisation gives the
//! paper's invariants: `eig(Abar_4) = {5, 2.5 +- 5.2163 i}` with `W = s + 5`, DPC unstable
//! without preliminary feedback and stable with it.

use dpc::core::linear_analysis::{analyze, AnalysisOptions};
use dpc::core::linearize::{linearize, LinearizeError, OperatingPoint};
use dpc::nalgebra::DMatrix;
use dpc_models::{Pendulum, Wheel};

#[test]
fn wheel_linearisation_and_its_dpc_analysis() {
    let x0 = [std::f64::consts::FRAC_PI_2, -6.0 * 2.0, 0.0, 0.0, -6.0];
    let xdot0 = [0.0, -6.0, 0.0, 0.0, 0.0];
    let sys = linearize(
        &Wheel::default(),
        OperatingPoint {
            t: 2.0,
            x: &x0,
            xdot: &xdot0,
            z: &[],
            u: &[0.0, 0.0],
        },
    )
    .unwrap();
    let a = DMatrix::from_row_slice(
        5,
        5,
        &[
            0.0, 0.0, 0.0, 1.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, 1.0, //
            0.0, 0.0, 0.0, -3.0, 0.0, //
            6.54, 0.0, 5.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, 0.0,
        ],
    );
    assert!((&sys.a - &a).amax() < 1e-12, "A = {}", sys.a);
    let b = DMatrix::from_row_slice(5, 2, &[0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.8]);
    assert!((&sys.b - &b).amax() < 1e-12, "B = {}", sys.b);

    let analysis = analyze(
        &sys,
        &AnalysisOptions {
            w: Some(vec![vec![5.0], vec![5.0]]),
            poles: None,
            ..AnalysisOptions::default()
        },
    )
    .unwrap();
    let mut eig: Vec<(f64, f64)> = analysis
        .abar4_eigenvalues
        .iter()
        .map(|c| (c.re, c.im))
        .collect();
    eig.sort_by(|p, q| p.partial_cmp(q).unwrap());
    let expected = [(2.5, -5.2163), (2.5, 5.2163), (5.0, 0.0)];
    for (e, x) in eig.iter().zip(expected) {
        assert!(
            (e.0 - x.0).abs() < 1e-3 && (e.1 - x.1).abs() < 1e-3,
            "eig(Abar_4) = {eig:?}"
        );
    }
    assert!(!analysis.dpc_stable, "DPC alone is unstable on the wheel");
    assert!(analysis.k_n.is_some(), "a preliminary feedback is built");
    assert_eq!(analysis.dpc_stable_prefeedback, Some(true));
}

#[test]
fn higher_index_plants_have_no_state_space_linearisation() {
    let err = linearize(
        &Pendulum::default(),
        OperatingPoint {
            t: 0.0,
            x: &[0.0, -1.0, 0.0, 0.0],
            xdot: &[0.0; 4],
            z: &[9.81],
            u: &[0.0],
        },
    )
    .unwrap_err();
    assert!(matches!(err, LinearizeError::Singular { .. }), "{err}");
    let err = linearize(
        &Wheel::default(),
        OperatingPoint {
            t: 0.0,
            x: &[0.0; 4],
            xdot: &[0.0; 5],
            z: &[],
            u: &[0.0; 2],
        },
    )
    .unwrap_err();
    assert!(matches!(err, LinearizeError::Dimension { what: "x", .. }));
}
