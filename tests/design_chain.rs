//! The design chain on plants the toolkit was not written for: a quadruple-tank process whose
//! flows are algebraic unknowns (trimmed from its pump voltages, and checked against the same
//! plant written as an ODE), and an overhead crane in cart/angle form whose load position has a
//! structural relative degree of 2 but a true one of 4 at rest.

use dpc::core::design::{
    check_relative_degrees, design, trim, DesignError, DesignOptions, TrimOptions, TrimProblem,
    TrimValue,
};
use dpc::core::linear_analysis::AnalysisOptions;
use dpc::core::{DaeModel, TrackingDae};

dpc::model! {
    /// Johansson's quadruple tank: levels `h1..h4`, outflows `q1..q4` (Torricelli), pump
    /// voltages `v1, v2` split by the valves `gamma1, gamma2`; outputs the lower levels.
    QuadTank {
        params {
            a1 = 0.071, a2 = 0.057, a3 = 0.071, a4 = 0.057,
            c1 = 28.0, c2 = 32.0, c3 = 28.0, c4 = 32.0,
            k1 = 3.33, k2 = 3.35, gamma1 = 0.7, gamma2 = 0.6, g = 981.0,
        }
        states { h1, h2, h3, h4 }
        algebraic { q1, q2, q3, q4 }
        inputs { v1, v2 }
        equations {
            c1 * der(h1) == -q1 + q3 + gamma1 * k1 * v1;
            c2 * der(h2) == -q2 + q4 + gamma2 * k2 * v2;
            c3 * der(h3) == -q3 + (1.0 - gamma2) * k2 * v2;
            c4 * der(h4) == -q4 + (1.0 - gamma1) * k1 * v1;
            0.0 == q1 - a1 * sqrt(2.0 * g * h1);
            0.0 == q2 - a2 * sqrt(2.0 * g * h2);
            0.0 == q3 - a3 * sqrt(2.0 * g * h3);
            0.0 == q4 - a4 * sqrt(2.0 * g * h4);
        }
        outputs { h1, h2 }
    }
}

dpc::model! {
    /// The same tank with the flows substituted: an ODE.
    QuadTankOde {
        params {
            a1 = 0.071, a2 = 0.057, a3 = 0.071, a4 = 0.057,
            c1 = 28.0, c2 = 32.0, c3 = 28.0, c4 = 32.0,
            k1 = 3.33, k2 = 3.35, gamma1 = 0.7, gamma2 = 0.6, g = 981.0,
        }
        states { h1, h2, h3, h4 }
        inputs { v1, v2 }
        let q1 = a1 * sqrt(2.0 * g * h1);
        let q2 = a2 * sqrt(2.0 * g * h2);
        let q3 = a3 * sqrt(2.0 * g * h3);
        let q4 = a4 * sqrt(2.0 * g * h4);
        equations {
            c1 * der(h1) == -q1 + q3 + gamma1 * k1 * v1;
            c2 * der(h2) == -q2 + q4 + gamma2 * k2 * v2;
            c3 * der(h3) == -q3 + (1.0 - gamma2) * k2 * v2;
            c4 * der(h4) == -q4 + (1.0 - gamma1) * k1 * v1;
        }
        outputs { h1, h2 }
    }
}

dpc::model! {
    /// An overhead crane: cart position `xc`, rope angle `th` from the vertical, a force `f`
    /// on the cart; the output is the load's horizontal position.
    Crane {
        params { mc = 1.0, ml = 0.5, l = 1.0, g = 9.81 }
        states { xc, th, vc, w }
        inputs { f }
        equations {
            der(xc) = vc;
            der(th) = w;
            (mc + ml) * der(vc) + ml * l * cos(th) * der(w) == f + ml * l * w.powi(2) * sin(th);
            ml * l * cos(th) * der(vc) + ml * l.powi(2) * der(w) == -ml * g * l * sin(th);
        }
        outputs { xl = xc + l * sin(th) }
        tracking CraneTracking { xl: [2.0] }
    }
}

fn equilibrium_from_inputs(v: [f64; 2]) -> TrimProblem {
    let tank = QuadTank::default();
    let mut p = TrimProblem::equilibrium(tank.structure());
    for (name, value) in [("v1", v[0]), ("v2", v[1])] {
        p.set(tank.structure(), name, TrimValue::Fixed(value))
            .unwrap();
    }
    // Levels must start positive: sqrt has no derivative at 0.
    for name in ["h1", "h2", "h3", "h4"] {
        p.set(tank.structure(), name, TrimValue::Free(10.0))
            .unwrap();
    }
    p
}

/// The trim from the pump voltages alone gives levels and flows that satisfy the closed-form
/// equilibrium of the tank: `q3 = (1 - gamma2) k2 v2`, `q1 = q3 + gamma1 k1 v1`, and so on,
/// with `h_i = (q_i / a_i)^2 / (2 g)`.
#[test]
fn the_tank_is_trimmed_from_its_inputs_alone() {
    let tank = QuadTank::default();
    let v = [3.0, 3.0];
    let t = trim(&tank, &equilibrium_from_inputs(v), &TrimOptions::default()).unwrap();
    let p = tank.params();
    let q3 = (1.0 - p.gamma2) * p.k2 * v[1];
    let q4 = (1.0 - p.gamma1) * p.k1 * v[0];
    let q1 = q3 + p.gamma1 * p.k1 * v[0];
    let q2 = q4 + p.gamma2 * p.k2 * v[1];
    let q = [q1, q2, q3, q4];
    let a = [p.a1, p.a2, p.a3, p.a4];
    for i in 0..4 {
        let h = (q[i] / a[i]).powi(2) / (2.0 * p.g);
        assert!(
            (t.motion.state[i] - h).abs() < 1e-9 * h,
            "h{}: {} vs {h}",
            i + 1,
            t.motion.state[i]
        );
        assert!((t.motion.algebraic[i] - q[i]).abs() < 1e-10 * q[i]);
    }
    assert_eq!(t.free_directions(), 0);
}

/// The design chain on the DAE form (its flows from the trim) and on the ODE form agree:
/// the same linearisation, the same analysis.
#[test]
fn the_dae_and_the_ode_form_of_the_tank_give_one_design() {
    let tank = QuadTank::default();
    let trimmed = trim(
        &tank,
        &equilibrium_from_inputs([3.0, 3.0]),
        &TrimOptions::default(),
    )
    .unwrap();
    let options = DesignOptions {
        analysis: AnalysisOptions {
            w: Some(vec![vec![0.05], vec![0.05]]),
            ..AnalysisOptions::default()
        },
        horizon: 100.0,
        relative_degrees: vec![Some(1), Some(1)],
    };
    let dae = design(&tank, &trimmed.motion, &options).unwrap();
    let mut ode_motion = trimmed.motion.clone();
    ode_motion.algebraic.clear();
    let ode = design(&QuadTankOde::default(), &ode_motion, &options).unwrap();
    for (m1, m2) in [
        (&dae.system.a, &ode.system.a),
        (&dae.system.b, &ode.system.b),
        (&dae.system.c, &ode.system.c),
        (&dae.system.d, &ode.system.d),
    ] {
        assert!(
            (m1 - m2).amax() <= 1e-12 * m2.amax().max(1.0),
            "{m1} vs {m2}"
        );
    }
    assert_eq!(dae.analysis.dpc_stable, ode.analysis.dpc_stable);
    assert_eq!(dae.linearisation_drift, 0.0);
    let mut e1: Vec<_> = dae
        .analysis
        .abar4_eigenvalues
        .iter()
        .map(|z| z.re)
        .collect();
    let mut e2: Vec<_> = ode
        .analysis
        .abar4_eigenvalues
        .iter()
        .map(|z| z.re)
        .collect();
    e1.sort_by(f64::total_cmp);
    e2.sort_by(f64::total_cmp);
    assert_eq!(e1.len(), e2.len());
    for (a, b) in e1.iter().zip(&e2) {
        assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "{e1:?} vs {e2:?}");
    }
}

/// A voltage the pumps cannot hold at a given level: with both levels and both voltages
/// fixed, the tank's equations cannot all hold, and the error names them.
#[test]
fn an_over_determined_tank_reports_the_equations_it_cannot_satisfy() {
    let tank = QuadTank::default();
    let mut p = equilibrium_from_inputs([3.0, 3.0]);
    p.set(tank.structure(), "h1", TrimValue::Fixed(1.0))
        .unwrap();
    let err = trim(&tank, &p, &TrimOptions::default()).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("unsatisfiable"), "{msg}");
    assert!(msg.contains("equation"), "{msg}");
}

/// The crane at rest: the load position's relative degree is 4 there (at `th = 0` the cart's
/// acceleration does not reach the load's in the second derivative), but the tracking DAE
/// was compiled for the structural 2; the check says so before any closed loop.
#[test]
fn a_structural_relative_degree_the_plant_does_not_have_is_reported() {
    let crane = Crane::default();
    let tracking = CraneTracking::default();
    let mut p = TrimProblem::equilibrium(crane.structure());
    p.set(crane.structure(), "xc", TrimValue::Fixed(0.0))
        .unwrap();
    let rest = trim(&crane, &p, &TrimOptions::default()).unwrap();
    assert!(rest.motion.state.iter().all(|v| v.abs() < 1e-12));
    assert_eq!(tracking.relative_degrees(), &[Some(2)]);
    // The design checks the degrees on the linearisation before it analyses it.
    let err = design(
        &crane,
        &rest.motion,
        &DesignOptions {
            analysis: AnalysisOptions::default(),
            horizon: 0.0,
            relative_degrees: tracking.relative_degrees().to_vec(),
        },
    )
    .unwrap_err();
    assert!(matches!(err, DesignError::RelativeDegree(_)), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains(
            "output `xl`: relative degree 4 at the nominal, 2 assumed by the tracking DAE"
        ),
        "{msg}"
    );
    // Away from rest (a leaning rope) the structural degree is the true one.
    let leaning = dpc::core::linearize::linearize(
        &crane,
        dpc::core::linearize::OperatingPoint {
            t: 0.0,
            x: &[0.0, 0.3, 0.0, 0.0],
            xdot: &[0.0; 4],
            z: &[],
            u: &[0.0],
        },
    )
    .unwrap();
    check_relative_degrees(
        &leaning,
        &crane.structure().outputs,
        tracking.relative_degrees(),
    )
    .unwrap();
}
