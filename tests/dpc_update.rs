//! One DPC update on the paper's linear example (4.1) with `W = s + 5`, where the exact
//! limit `delta -> 0` of the extracted control is known from the linear analysis:
//! `u = K_J x + R_xi(d/dt) xi` (paper, (3.8)-(3.10)).

use dpc::core::controller::{Dpc, DpcError, DpcOptions, Extraction};
use dpc::core::linear_analysis::{analyze, AnalysisOptions, LinearSystem};
use dpc::core::linear_solver::NalgebraLu;
use dpc::core::reference::{Components, Constant, Sinusoid};
use dpc::nalgebra::{DMatrix, DVector};
use dpc_models::WheelLinearTracking;

fn paper_system() -> LinearSystem {
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
    let b = DMatrix::from_row_slice(5, 2, &[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    let c = DMatrix::from_row_slice(2, 5, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    LinearSystem::new(a, b, c, DMatrix::zeros(2, 2)).unwrap()
}

fn zero_reference() -> Components {
    Components::new(2, vec![Box::new(Constant(0.0)), Box::new(Constant(0.0))]).unwrap()
}

fn dpc_control(x: &[f64], delta: f64, extraction: Extraction) -> [f64; 2] {
    let opts = DpcOptions {
        delta,
        extraction,
        ..DpcOptions::default()
    };
    let mut dpc = Dpc::new(
        WheelLinearTracking::default(),
        zero_reference(),
        NalgebraLu::<{ WheelLinearTracking::N_EQUATIONS }>::new(),
        opts,
    )
    .unwrap();
    assert_eq!(dpc.nu(), 2, "nu from the generated relative degrees");
    let mut u = [0.0; 2];
    dpc.control(0.0, x, &mut u).unwrap();
    u
}

#[test]
fn extracted_control_converges_to_the_linear_limit() {
    let analysis = analyze(
        &paper_system(),
        &AnalysisOptions {
            w: Some(vec![vec![5.0], vec![5.0]]),
            ..AnalysisOptions::default()
        },
    )
    .unwrap();
    assert_eq!(analysis.nu, 2);
    let x = [0.1, -0.2, 0.3, 0.05, -0.1];
    let exact = &analysis.k_j * DVector::from_column_slice(&x);
    let err = |delta: f64, e: Extraction| {
        let u = dpc_control(&x, delta, e);
        ((u[0] - exact[0]).powi(2) + (u[1] - exact[1]).powi(2)).sqrt()
    };
    let (e1, e2) = (
        err(2e-3, Extraction::FirstUsable),
        err(1e-3, Extraction::FirstUsable),
    );
    let (x1, x2) = (
        err(2e-3, Extraction::Extrapolated),
        err(1e-3, Extraction::Extrapolated),
    );
    // First usable: O(delta); extrapolated: O(delta^2), and much smaller.
    let p_first = (e1 / e2).log2();
    let p_extra = (x1 / x2).log2();
    assert!(
        (0.8..1.3).contains(&p_first),
        "first-usable order {p_first} ({e1:e}, {e2:e})"
    );
    assert!(
        (1.7..2.4).contains(&p_extra),
        "extrapolated order {p_extra} ({x1:e}, {x2:e})"
    );
    assert!(x2 < 0.1 * e2, "extrapolation helps: {x2:e} vs {e2:e}");
}

#[test]
fn reference_feedforward_matches_r_xi() {
    // With x = 0 and a sinusoidal reference the control is R_xi(d/dt) xi at t_k.
    let analysis = analyze(
        &paper_system(),
        &AnalysisOptions {
            w: Some(vec![vec![5.0], vec![5.0]]),
            ..AnalysisOptions::default()
        },
    )
    .unwrap();
    let sin = |phase: f64| Sinusoid {
        offset: 0.0,
        amplitude: 0.2,
        omega: 1.0,
        phase,
    };
    let reference = Components::new(2, vec![Box::new(sin(0.3)), Box::new(sin(1.1))]).unwrap();
    let mut dpc = Dpc::new(
        WheelLinearTracking::default(),
        reference,
        NalgebraLu::<{ WheelLinearTracking::N_EQUATIONS }>::new(),
        DpcOptions {
            delta: 5e-4,
            ..DpcOptions::default()
        },
    )
    .unwrap();
    let t = 0.7;
    let mut u = [0.0; 2];
    dpc.control(t, &[0.0; 5], &mut u).unwrap();
    // R_xi is computed for the partially stabilised system, so it acts on its reference
    // w = W(d/dt) xi = 5 xi + xi': u = sum_k R_k w^(k)(t).
    use dpc::core::reference::ScalarReference;
    let w_k = |r: Sinusoid, k: usize| 5.0 * r.derivative(t, k) + r.derivative(t, k + 1);
    let mut expected = DVector::zeros(2);
    for (k, rk) in analysis.r_xi.iter().enumerate() {
        expected += rk * DVector::from_vec(vec![w_k(sin(0.3), k), w_k(sin(1.1), k)]);
    }
    let err = ((u[0] - expected[0]).powi(2) + (u[1] - expected[1]).powi(2)).sqrt();
    assert!(
        err < 1e-3 * (1.0 + expected.norm()),
        "u = {u:?}, R_xi xi = {expected}"
    );
    assert_eq!(WheelLinearTracking::N_OUTPUTS, 2);
}

#[test]
fn bad_inputs_are_typed_errors() {
    let make = |opts: DpcOptions| {
        Dpc::new(
            WheelLinearTracking::default(),
            zero_reference(),
            NalgebraLu::<{ WheelLinearTracking::N_EQUATIONS }>::new(),
            opts,
        )
    };
    assert!(matches!(
        make(DpcOptions {
            delta: 0.0,
            ..DpcOptions::default()
        }),
        Err(DpcError::InvalidOption(ref o)) if o.name == "delta"
    ));
    assert!(matches!(
        make(DpcOptions {
            delta: 1e-3,
            max_delta: 1e-4,
            ..DpcOptions::default()
        }),
        Err(DpcError::InvalidOption(ref o)) if o.name == "max_delta"
    ));
    let mut dpc = make(DpcOptions::default()).unwrap();
    let mut u = [0.0; 2];
    assert!(matches!(
        dpc.control(0.0, &[0.0; 4], &mut u),
        Err(DpcError::Dimension { .. })
    ));
    assert!(matches!(
        dpc.control(0.0, &[f64::NAN, 0.0, 0.0, 0.0, 0.0], &mut u),
        Err(DpcError::NonFiniteState { index: 0, .. })
    ));
    assert!(matches!(
        Dpc::new(
            WheelLinearTracking::default(),
            zero_reference(),
            NalgebraLu::<{ WheelLinearTracking::N_EQUATIONS - 2 }>::new(),
            DpcOptions::default()
        ),
        Err(DpcError::Dimension { .. })
    ));
}

/// The origin as nominal trajectory.
struct Origin;

impl dpc::core::prefeedback::Nominal for Origin {
    fn state(&self, _t: f64, x0: &mut [f64]) {
        x0.fill(0.0);
    }
    fn input(&self, _t: f64, u0: &mut [f64]) {
        u0.fill(0.0);
    }
}

#[test]
fn with_prefeedback_the_update_converges_to_the_prefed_law() {
    // Paper, Section 4: poles of Abar_4 + Bbar_2 K_2 at -5; DPC on x' = (A + B K_n) x + B v.
    let analysis = analyze(
        &paper_system(),
        &AnalysisOptions {
            w: Some(vec![vec![5.0], vec![5.0]]),
            poles: Some(vec![dpc::nalgebra::Complex::new(-5.0, 0.0); 3]),
            ..AnalysisOptions::default()
        },
    )
    .unwrap();
    let k_n = analysis
        .k_n
        .clone()
        .expect("K_n is built for the unstable Abar_4");
    let k_j_pre = analysis.k_j_prefeedback.clone().expect("analysis redone");
    let mut dpc = Dpc::new(
        WheelLinearTracking::default(),
        zero_reference(),
        NalgebraLu::<{ WheelLinearTracking::N_EQUATIONS }>::new(),
        DpcOptions {
            delta: 5e-4,
            ..DpcOptions::default()
        },
    )
    .unwrap()
    .with_prefeedback(dpc::core::prefeedback::Prefeedback {
        k_n: k_n.clone(),
        nominal: Box::new(Origin),
    })
    .unwrap();
    let x = [0.1, -0.2, 0.3, 0.05, -0.1];
    let mut v = [0.0; 2];
    dpc.control(0.0, &x, &mut v).unwrap();
    let xv = DVector::from_column_slice(&x);
    let expected_v = &k_j_pre * &xv;
    let err = ((v[0] - expected_v[0]).powi(2) + (v[1] - expected_v[1]).powi(2)).sqrt();
    assert!(
        err < 1e-4 * (1.0 + expected_v.norm()),
        "v = {v:?}, K_J' x = {expected_v}"
    );
    // The plant input is u = K_n x + v: the closed loop A + B (K_n + K_J') is stable.
    let mut u = [0.0; 2];
    dpc.prefeedback()
        .unwrap()
        .input(0.0, &x, &v, &mut [0.0; 5], &mut u);
    let expected_u = (&k_n + &k_j_pre) * &xv;
    assert!((u[0] - expected_u[0]).abs() + (u[1] - expected_u[1]).abs() < 1e-3);
    assert_eq!(analysis.dpc_stable_prefeedback, Some(true));
}
