//! Hirschorn steps through implicit equations: `FlexibleJointMass{,3,4}` write the flexible
//! joint's link and motor equations implicitly (`I der(w) == ...`), so a third and fourth step
//! need `der2(w_link)` and `der3(w_link)`, which the macro obtains by differentiating the
//! implicit link equation (index reduction) instead of inverting the inertia. Their tracking
//! DAEs must control the plant exactly as those of the explicit `FlexibleJoint` with the same
//! steps do.

mod common;

use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::design::{design, DesignOptions};
use dpc::core::linear_analysis::AnalysisOptions;
use dpc::core::linear_solver::{LinearSolver, NalgebraLu};
use dpc::core::model::DaeModel;
use dpc::core::prefeedback::SteadyMotion;
use dpc::core::simulate::{simulate, ClosedLoopOptions};
use dpc::core::{Reference, TrackingDae};
use dpc::nalgebra::Complex;
use dpc_models::{
    FlexibleJoint, FlexibleJointMass, FlexibleJointMass3, FlexibleJointMass3Reference,
    FlexibleJointMass3Tracking, FlexibleJointMass4, FlexibleJointMass4Reference,
    FlexibleJointMass4Tracking, FlexibleJointMassReference, FlexibleJointMassTracking,
    FlexibleJointParams, FlexibleJointReference, FlexibleJointTracking,
};

dpc::model! {
    /// The explicit flexible joint with three steps.
    pub Explicit3 {
        params { i_link = 1.0, j_motor = 0.5, k = 40.0, m = 1.0, l = 0.5, g = 9.81 }
        states { q_link, w_link, q_motor, w_motor }
        inputs { u }
        equations {
            der(q_link) = w_link;
            der(w_link) = (-m * g * l * sin(q_link) - k * (q_link - q_motor)) / i_link;
            der(q_motor) = w_motor;
            der(w_motor) = (k * (q_link - q_motor) + u) / j_motor;
        }
        outputs { q_link }
        references { q_link = 0.5 * sin(2.0 * t) }
        tracking Explicit3Tracking { q_link: [2.0, 3.0, 4.0] }
    }
}

dpc::model! {
    /// The explicit flexible joint with four steps.
    pub Explicit4 {
        params { i_link = 1.0, j_motor = 0.5, k = 40.0, m = 1.0, l = 0.5, g = 9.81 }
        states { q_link, w_link, q_motor, w_motor }
        inputs { u }
        equations {
            der(q_link) = w_link;
            der(w_link) = (-m * g * l * sin(q_link) - k * (q_link - q_motor)) / i_link;
            der(q_motor) = w_motor;
            der(w_motor) = (k * (q_link - q_motor) + u) / j_motor;
        }
        outputs { q_link }
        references { q_link = 0.5 * sin(2.0 * t) }
        tracking Explicit4Tracking { q_link: [2.0, 3.0, 4.0, 5.0] }
    }
}

/// The flexible joint's right-hand side (explicit form) with the input held.
fn plant_rhs(p: &FlexibleJointParams, x: &[f64; 4], u: f64) -> [f64; 4] {
    let [q, w, qm, wm] = *x;
    [
        w,
        (-p.m * p.g * p.l * q.sin() - p.k * (q - qm)) / p.i_link,
        wm,
        (p.k * (q - qm) + u) / p.j_motor,
    ]
}

/// A closed loop of `t_end` on the (explicit) flexible joint from `x0`, controlled by DPC on
/// `model` with the preliminary feedback designed on `plant` (its own form of the plant) about
/// the hanging rest where the steps leave a relative degree (plain DPC is unstable on this
/// plant, as the linear analysis predicts): the controls and the states at the samples, and
/// the largest tracking error over the last quarter.
fn closed_loop<P: DaeModel, T: TrackingDae, R: Reference, L: LinearSolver>(
    plant: &P,
    model: T,
    reference: R,
    solver: L,
    t_end: f64,
    (residual_tolerance, control_tolerance): (f64, f64),
) -> Loop {
    let h = H;
    let roots: Vec<f64> = {
        let c = model.default_w_coefficients(0);
        // The roots of the models' W: 2, 3, 4, 5 up to the degree.
        (0..c.len() - 1).map(|k| 2.0 + k as f64).collect()
    };
    let remaining = model.remaining_relative_degree().unwrap();
    let opts = DpcOptions {
        residual_tolerance,
        control_tolerance,
        ..DpcOptions::default()
    };
    let mut dpc = Dpc::new(model, reference, solver, opts).unwrap();
    if remaining > 0 {
        let rest = SteadyMotion {
            state: vec![0.0; 4],
            rate: vec![0.0; 4],
            algebraic: vec![],
            input: vec![0.0],
        };
        let designed = design(
            plant,
            &rest,
            &DesignOptions {
                analysis: AnalysisOptions {
                    w: Some(vec![roots]),
                    poles: Some(vec![Complex::new(-40.0, 0.0); remaining]),
                    ..AnalysisOptions::default()
                },
                horizon: 5.0,
                relative_degrees: vec![Some(4)],
            },
        )
        .unwrap();
        dpc = dpc
            .with_prefeedback(designed.prefeedback().unwrap())
            .unwrap();
    }
    let run = simulate(
        &FlexibleJoint::default(),
        &mut dpc,
        &[0.1, 0.0, 0.1, 0.0],
        &ClosedLoopOptions {
            h,
            t_end,
            ..ClosedLoopOptions::default()
        },
    )
    .unwrap();
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    let controls = run.samples.iter().map(|s| s.u[0]).collect();
    let states = run
        .samples
        .iter()
        .map(|s| [s.x[0], s.x[1], s.x[2], s.x[3]])
        .collect();
    (controls, states, run.max_abs_error_since(0.75 * t_end)[0])
}

/// `a` and `b` agree to `tolerance` relative to the largest magnitude in them; the largest
/// relative difference.
fn assert_close(what: &str, a: &[f64], b: &[f64], tolerance: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().chain(b).fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut largest = 0.0_f64;
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tolerance * scale,
            "{what}[{k}]: implicit {x}, explicit {y} (scale {scale})"
        );
        largest = largest.max((x - y).abs() / scale);
    }
    largest
}

/// The controls, the states at the samples and the late tracking error of a closed loop.
type Loop = (Vec<f64>, Vec<[f64; 4]>, f64);

/// The implicit form's loop against the explicit one's: controls and states agree to
/// `tolerance` (relative to their largest magnitudes); the implicit loop's late tracking error.
fn compare(steps: usize, implicit: Loop, explicit: Loop, tolerance: f64) -> f64 {
    let du = assert_close(
        &format!("{steps} steps: u"),
        &implicit.0,
        &explicit.0,
        tolerance,
    );
    let flat = |s: &[[f64; 4]]| s.iter().flatten().copied().collect::<Vec<_>>();
    let dx = assert_close(
        &format!("{steps} steps: x"),
        &flat(&implicit.1),
        &flat(&explicit.1),
        tolerance,
    );
    println!(
        "{steps} steps: relative differences u {du:.1e}, x {dx:.1e}; late tracking errors {:.2e} (implicit), {:.2e} (explicit)",
        implicit.2, explicit.2
    );
    implicit.2
}

/// The sampling period and the length of the runs.
const H: f64 = 0.01;
const T_END: f64 = 6.0;

/// The two forms' tracking DAEs are different equations with the same solution, and DPC's
/// Newton iterations stop wherever their residual first passes the tolerance in each: the
/// controls agree to about that tolerance, amplified by `1 / delta^nu` where the steps leave a
/// relative degree `nu` (the inputs of a tracking DAE of index `nu + 1` are `nu`
/// differentiations away from its residual). The comparison is of the two formulations, not
/// of where Newton happens to stop, so each test runs both forms with tolerances whose
/// stopping error is far below the agreement it asserts (see the constants per test).
const TOLERANCE: f64 = 1e-6;
/// The agreement for two steps.
const TOLERANCE_INDEX_3: f64 = 1e-5;
/// Newton's tolerances (scaled residual, control residual) for two steps (`nu = 2`,
/// `delta = 1e-3`): the default scaled `1e-10` would allow `1e-10 / delta^2 = 1e-4` in the
/// controls, above the `1e-5` asserted; `1e-13` allows `1e-7` (measured differences
/// `1.3e-6`, the rest being the two forms' rounding amplified by `delta^-2`).
const TOLERANCES_INDEX_3: (f64, f64) = (1e-13, 1e-7);
/// Newton's tolerances for three steps (`nu = 1`, `delta = 1e-3`): the default scaled `1e-10`
/// allows `1e-10 / delta = 1e-7` in the controls (and the default control tolerance `1e-7`
/// as much), within a decade of the `1e-6` asserted: a step that stops just inside its
/// tolerance in one form and overshoots it in the other differs by `1.3e-6`. `1e-13` and a
/// control tolerance of `1e-10` allow `1e-13 / delta = 1e-10`, four decades below the bound
/// (measured differences `1e-12`).
const TOLERANCES_INDEX_2: (f64, f64) = (1e-13, 1e-10);
/// Newton's tolerances for four steps (`nu = 0`): the defaults, scaled `1e-10`
/// (`1e-10 / delta^0 = 1e-10` in the controls) and the control tolerance `1e-7`, which holds
/// the residual reaching the control a decade or more below the `1e-6` asserted (measured
/// differences `6e-10`).
fn tolerances_index_1() -> (f64, f64) {
    let defaults = DpcOptions::default();
    (defaults.residual_tolerance, defaults.control_tolerance)
}

#[test]
fn two_steps_through_the_mass_give_the_explicit_controls() {
    let implicit = closed_loop(
        &FlexibleJointMass::default(),
        FlexibleJointMassTracking::default(),
        FlexibleJointMassReference::default(),
        NalgebraLu::<{ FlexibleJointMassTracking::N_EQUATIONS }>::new(),
        T_END,
        TOLERANCES_INDEX_3,
    );
    let explicit = closed_loop(
        &FlexibleJoint::default(),
        FlexibleJointTracking::default(),
        FlexibleJointReference::default(),
        NalgebraLu::<{ FlexibleJointTracking::N_EQUATIONS }>::new(),
        T_END,
        TOLERANCES_INDEX_3,
    );
    let error = compare(2, implicit, explicit, TOLERANCE_INDEX_3);
    assert!(error < 0.05, "tracking error {error}");
}

#[test]
fn three_steps_through_the_mass_give_the_explicit_controls() {
    let implicit = closed_loop(
        &FlexibleJointMass3::default(),
        FlexibleJointMass3Tracking::default(),
        FlexibleJointMass3Reference::default(),
        NalgebraLu::<{ FlexibleJointMass3Tracking::N_EQUATIONS }>::new(),
        T_END,
        TOLERANCES_INDEX_2,
    );
    let explicit = closed_loop(
        &Explicit3::default(),
        Explicit3Tracking::default(),
        Explicit3Reference::default(),
        NalgebraLu::<{ Explicit3Tracking::N_EQUATIONS }>::new(),
        T_END,
        TOLERANCES_INDEX_2,
    );
    let error = compare(3, implicit, explicit, TOLERANCE);
    assert!(error < 0.05, "tracking error {error}");
}

#[test]
fn four_steps_through_the_mass_give_the_explicit_controls() {
    let implicit = closed_loop(
        &FlexibleJointMass4::default(),
        FlexibleJointMass4Tracking::default(),
        FlexibleJointMass4Reference::default(),
        NalgebraLu::<{ FlexibleJointMass4Tracking::N_EQUATIONS }>::new(),
        T_END,
        tolerances_index_1(),
    );
    let explicit = closed_loop(
        &Explicit4::default(),
        Explicit4Tracking::default(),
        Explicit4Reference::default(),
        NalgebraLu::<{ Explicit4Tracking::N_EQUATIONS }>::new(),
        T_END,
        tolerances_index_1(),
    );
    let error = compare(4, implicit, explicit, TOLERANCE);
    assert!(error < 0.05, "tracking error {error}");
}

#[test]
fn the_derivatives_of_the_link_equation_are_unknowns_before_the_input() {
    // Two steps: the plant's unknowns only.
    let two = FlexibleJointMassTracking::default();
    assert_eq!(two.structure().algebraic, ["u"]);
    assert_eq!(two.plant_algebraic(), 0);
    assert_eq!(two.plant_inputs(), 1);
    // Three steps: der2(w_link) and d/dt of the link equation join.
    let three = FlexibleJointMass3Tracking::default();
    assert_eq!(three.structure().algebraic, ["der2(w_link)", "u"]);
    assert_eq!(three.plant_algebraic(), 1);
    assert_eq!(three.plant_inputs(), 1);
    assert_eq!(FlexibleJointMass3Tracking::N_EQUATIONS, 4 + 1 + 1);
    assert!(three.structure().equations[4].starts_with("d/dt ((i_com"));
    // Four steps: der2 and der3, the first and second derivatives.
    let four = FlexibleJointMass4Tracking::default();
    assert_eq!(
        four.structure().algebraic,
        ["der2(w_link)", "der3(w_link)", "u"]
    );
    assert_eq!(four.plant_algebraic(), 2);
    assert_eq!(four.plant_inputs(), 1);
    assert_eq!(FlexibleJointMass4Tracking::N_EQUATIONS, 4 + 2 + 1);
    assert!(four.structure().equations[5].starts_with("d^2/dt^2 ((i_com"));
    // The plant's residual is the plant's; the relative degree the explicit one's.
    for degrees in [
        FlexibleJointMass::RELATIVE_DEGREES,
        FlexibleJointMass3::RELATIVE_DEGREES,
        FlexibleJointMass4::RELATIVE_DEGREES,
    ] {
        assert_eq!(degrees, FlexibleJoint::RELATIVE_DEGREES);
    }
    assert_eq!(FlexibleJointMass4::N_EQUATIONS, 4);
    assert_eq!(four.remaining_relative_degree(), Some(0));
    assert_eq!(three.remaining_relative_degree(), Some(1));
}

#[test]
fn the_derivative_rows_vanish_along_a_plant_trajectory() {
    // At a point of the plant, with der(w) from the plant and der2, der3 of w_link by the
    // chain rule of the explicit form, the derivative rows of the four-step DAE are zero.
    let p = FlexibleJoint::default().params;
    let x = [0.3, -0.4, 0.1, 0.7];
    let u = 1.5;
    let xdot = plant_rhs(&p, &x, u);
    // d/dt of der(w_link) = f(q, qm): f_q w + f_qm wm; then once more (u held, so wm' has no u').
    let (k, mgl, i) = (p.k, p.m * p.g * p.l, p.i_link);
    let [q, w, _, wm] = x;
    let a = xdot[1];
    let d2 = (-mgl * q.cos() * w - k * (w - wm)) / i;
    let d3 = (mgl * q.sin() * w * w - mgl * q.cos() * a - k * (a - xdot[3])) / i;
    let four = FlexibleJointMass4Tracking::default();
    let mut g = [0.0; 7];
    four.residual(0.0, &x, &xdot, &[d2, d3, u], &[0.0], &mut g);
    let scale = 1.0 + d3.abs();
    for (row, value) in g.iter().enumerate().take(6) {
        assert!(value.abs() < 1e-12 * scale, "row {row}: {value}");
    }
}

/// The two-link arm of `models/src/arm.rs` (`Arm2`) with `steps` roots `4.0` in `W` per joint,
/// read at run time, in the closed loop of `scenarios/arm2.toml` over 6 s (with the preliminary
/// feedback, poles at -40, where the steps leave a relative degree): the largest tracking
/// error over `t` in `[4, 6]`. Two steps keep the mass matrix implicit (index 3); three and
/// four differentiate the link equations once and twice (index 2 and 1).
fn arm2_late_error(steps: usize) -> f64 {
    use dpc::core::linear_solver::FaerDenseLu;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/src");
    let source = std::fs::read_to_string(root.join("arm.rs")).unwrap();
    let template = std::fs::read_to_string(root.join("arm_declaration.rs")).unwrap();
    let body = common::model_text::template_models(&source, &template)
        .into_iter()
        .find(|b| b.contains("pub Arm2 {"))
        .expect("Arm2 in models/src/arm.rs");
    let roots = vec!["4.0"; steps].join(", ");
    let text = body.replace("q: [4.0, 4.0]", &format!("q: [{roots}]"));
    assert!(steps == 2 || text != body, "the template changed");
    let model = dpc::runtime::parse("arm2", &text).unwrap();
    let plant = model.plant();
    let tracking = model.tracking().unwrap();
    let n = tracking.structure().n_equations();
    let remaining = tracking.remaining_relative_degree().unwrap();
    let nx = plant.structure().n_states();
    let mut dpc = Dpc::new(
        tracking,
        model.reference().unwrap(),
        FaerDenseLu::new(n),
        DpcOptions::default(),
    )
    .unwrap();
    if remaining > 0 {
        let rest = SteadyMotion {
            state: vec![0.0; nx],
            rate: vec![0.0; nx],
            algebraic: vec![],
            input: vec![0.0; 2],
        };
        let designed = design(
            &plant,
            &rest,
            &DesignOptions {
                analysis: AnalysisOptions {
                    w: Some(vec![vec![4.0; steps]; 2]),
                    poles: Some(vec![Complex::new(-40.0, 0.0); 2 * remaining]),
                    ..AnalysisOptions::default()
                },
                horizon: 6.0,
                relative_degrees: vec![Some(4); 2],
            },
        )
        .unwrap();
        dpc = dpc
            .with_prefeedback(designed.prefeedback().unwrap())
            .unwrap();
    }
    let run = simulate(
        &plant,
        &mut dpc,
        &vec![0.0; nx],
        &ClosedLoopOptions {
            h: 0.01,
            t_end: 6.0,
            ..ClosedLoopOptions::default()
        },
    )
    .unwrap();
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    run.max_abs_error_since(4.0).into_iter().fold(0.0, f64::max)
}

/// The measurement of `docs/arms.md` (two, three and four steps per joint on the two-link
/// arm): `cargo test --test implicit_steps -- --nocapture arm2`. Each loop tracks; the errors
/// grow with the number of steps (see there).
#[test]
fn arm2_with_two_three_and_four_steps_per_joint() {
    for steps in [2, 3, 4] {
        let error = arm2_late_error(steps);
        println!("arm2, {steps} steps per joint: max error over t in [4, 6] {error:.1e}");
        assert!(error < 0.05, "{steps} steps: {error}");
    }
}
