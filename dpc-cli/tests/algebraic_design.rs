//! A scenario's `[design]` on a plant with algebraic unknowns, through the library entry
//! point a user crate uses: the quadruple tank (outflows as algebraic unknowns) with its
//! nominal given by the pump voltages alone. The trim solver computes the levels and the
//! flows; the design is checked against the same plant written as an ODE (the tank is
//! minimum-phase, so the analysis predicts plain DPC stable and builds no `K_n`), and both
//! closed loops track, on the same trajectory.

use dpc::cli::registry::{Entry, Registry};
use dpc::cli::run::RunResult;
use dpc::cli::scenario::{Overrides, Scenario};
use dpc::cli::ScenarioError;

dpc::model! {
    /// The quadruple tank: levels `h1..h4`, outflows `q1..q4` as algebraic unknowns.
    Tanks {
        params {
            a_1 = 28.0, a_2 = 32.0, a_3 = 28.0, a_4 = 32.0,
            o_1 = 0.071, o_2 = 0.057, o_3 = 0.071, o_4 = 0.057,
            k_1 = 3.33, k_2 = 3.35, gamma_1 = 0.7, gamma_2 = 0.6, g = 981.0,
        }
        states { h1, h2, h3, h4 }
        algebraic { q1, q2, q3, q4 }
        inputs { v1, v2 }
        equations {
            a_1 * der(h1) == -q1 + q3 + gamma_1 * k_1 * v1;
            a_2 * der(h2) == -q2 + q4 + gamma_2 * k_2 * v2;
            a_3 * der(h3) == -q3 + (1.0 - gamma_2) * k_2 * v2;
            a_4 * der(h4) == -q4 + (1.0 - gamma_1) * k_1 * v1;
            0.0 == q1 - o_1 * sqrt(2.0 * g * h1);
            0.0 == q2 - o_2 * sqrt(2.0 * g * h2);
            0.0 == q3 - o_3 * sqrt(2.0 * g * h3);
            0.0 == q4 - o_4 * sqrt(2.0 * g * h4);
        }
        outputs { h1, h2 }
        tracking TanksTracking { h1: [0.5], h2: [0.5] }
    }
}

dpc::model! {
    /// The same tank with the outflows substituted: an ODE.
    TanksOde {
        params {
            a_1 = 28.0, a_2 = 32.0, a_3 = 28.0, a_4 = 32.0,
            o_1 = 0.071, o_2 = 0.057, o_3 = 0.071, o_4 = 0.057,
            k_1 = 3.33, k_2 = 3.35, gamma_1 = 0.7, gamma_2 = 0.6, g = 981.0,
        }
        states { h1, h2, h3, h4 }
        inputs { v1, v2 }
        let q1 = o_1 * sqrt(2.0 * g * h1);
        let q2 = o_2 * sqrt(2.0 * g * h2);
        let q3 = o_3 * sqrt(2.0 * g * h3);
        let q4 = o_4 * sqrt(2.0 * g * h4);
        equations {
            a_1 * der(h1) == -q1 + q3 + gamma_1 * k_1 * v1;
            a_2 * der(h2) == -q2 + q4 + gamma_2 * k_2 * v2;
            a_3 * der(h3) == -q3 + (1.0 - gamma_2) * k_2 * v2;
            a_4 * der(h4) == -q4 + (1.0 - gamma_1) * k_1 * v1;
        }
        outputs { h1, h2 }
        tracking TanksOdeTracking { h1: [0.5], h2: [0.5] }
    }
}

fn registry() -> Registry {
    Registry::new()
        .model(Entry::new(
            "tanks",
            "quadruple tank, outflows algebraic",
            Tanks::default(),
            TanksTracking::default(),
        ))
        .model(Entry::new(
            "tanks-ode",
            "quadruple tank, outflows substituted",
            TanksOde::default(),
            TanksOdeTracking::default(),
        ))
}

/// Levels 1 cm off the operating point of 3 V on both pumps, following constant references
/// at that operating point; the nominal is given by the pump voltages alone.
const SCENARIO: &str = r#"
model = "tanks"
x0 = [13.0, 14.0, 2.5, 2.0]
h = 1.0
t_end = 120.0
delta = 0.01

[reference]
h1 = [{ constant = 12.2604 }]
h2 = [{ constant = 12.7834 }]

[design]
nominal = { input = [3.0, 3.0] }
"#;

fn run(sets: &[&str]) -> Result<RunResult, ScenarioError> {
    let overrides = Overrides::parse(sets.iter().copied())?;
    let scenario = Scenario::parse("tanks.toml", SCENARIO, &overrides)?;
    registry().run(&scenario, "test")
}

#[test]
fn the_nominal_of_a_plant_with_algebraic_unknowns_is_trimmed_from_its_inputs() {
    let dae = run(&[]).unwrap();
    let design = dae.design.as_ref().unwrap();
    let n = &design.nominal;
    assert_eq!(
        n.solved_for,
        ["h1", "h2", "h3", "h4", "q1", "q2", "q3", "q4"]
    );
    assert_eq!(n.free_directions, 0);
    // The flows are the orifice law at the trimmed levels, and the levels balance the pumps.
    for (level, flow, area) in [
        ("h1", "q1", 0.071),
        ("h2", "q2", 0.057),
        ("h3", "q3", 0.071),
        ("h4", "q4", 0.057),
    ] {
        let q = area * (2.0 * 981.0 * n.state[level]).sqrt();
        assert!((n.algebraic[flow] - q).abs() < 1e-10 * q, "{flow}");
    }
    let q3 = (1.0 - 0.6) * 3.35 * 3.0;
    assert!((n.algebraic["q3"] - q3).abs() < 1e-10, "{:?}", n.algebraic);
    assert!((n.algebraic["q1"] - (q3 + 0.7 * 3.33 * 3.0)).abs() < 1e-10);

    // The ODE form of the same plant trims to the same levels and gives the same design.
    let ode = run(&["model=\"tanks-ode\""]).unwrap();
    let od = ode.design.as_ref().unwrap();
    for (name, h) in &n.state {
        assert!((od.nominal.state[name] - h).abs() < 1e-9, "{name}");
    }
    assert!(od.nominal.algebraic.is_empty());
    assert!(design.dpc_stable_without_prefeedback);
    assert_eq!(
        design.dpc_stable_without_prefeedback,
        od.dpc_stable_without_prefeedback
    );
    assert_eq!(design.abar4_eigenvalues, od.abar4_eigenvalues);
    let (ra, rb) = (design.sampled.spectral_radius, od.sampled.spectral_radius);
    assert!((ra - rb).abs() < 1e-9, "{ra} vs {rb}");
    assert!(ra < 1.0, "{ra}");

    // Both closed loops settle on the references, and on the same trajectory.
    for r in [&dae, &ode] {
        let cl = &r.closed_loop;
        assert!(cl.divergence.is_none(), "{:?}", cl.divergence);
        let late = cl.max_abs_error_since(90.0);
        assert!(late.iter().all(|e| *e < 1e-2), "{late:?}");
    }
    let (a, b) = (&dae.closed_loop.samples, &ode.closed_loop.samples);
    assert_eq!(a.len(), b.len());
    for (sa, sb) in a.iter().zip(b) {
        for (xa, xb) in sa.x.iter().zip(&sb.x) {
            assert!((xa - xb).abs() < 1e-3, "t = {}: {xa} vs {xb}", sa.t);
        }
    }
}

#[test]
fn poles_where_there_is_nothing_to_place_are_an_error() {
    // W = s + 0.5 matches both relative degrees: no infinite part, no K_n to design.
    let err = run(&["design.poles=[-1.0]"]).unwrap_err().to_string();
    assert!(
        err.contains("bad poles: 1 pole(s) given, but with this W the pencil has no infinite part"),
        "{err}"
    );
}

#[test]
fn an_unreachable_nominal_names_the_equations() {
    // Levels fixed apart from what the pumps can hold: the trim solver says which
    // equations cannot be satisfied.
    let err = run(&[
        "design.nominal.state={h3 = 5.0}",
        "design.nominal.input=[3.0, 3.0]",
    ])
    .unwrap_err()
    .to_string();
    assert!(err.starts_with("design: trim of `Tanks`"), "{err}");
    assert!(
        err.contains("c3 * der(h3)") || err.contains("der(h3)"),
        "{err}"
    );
}
