//! Dense output of the closed loop (`ClosedLoopOptions::output_step`): the plant's motion
//! between the samples, interpolated inside the plant integrator's steps.
//!
//! * The samples, the controller's work and the plant integrator's work are bit for bit those
//!   of the same run without an output step (no extra step is taken), for both holds and for
//!   a constrained plant (integrated by Radau).
//! * Each dense point lies on the plant's solution: the plant integrated afresh from the
//!   sample before it, with the input held there, to the point's time at a much tighter
//!   tolerance, agrees to the loop's tolerance.
//! * A bad output step is a typed error before the run.

use dpc::core::bdf::{consistent_initial_values, Bdf, Options};
use dpc::core::controller::{Dpc, DpcOptions};
use dpc::core::linear_solver::{FaerDenseLu, NalgebraLu};
use dpc::core::simulate::{
    simulate, simulate_with_progress, ClosedLoop, ClosedLoopOptions, Hold, OutputStepProblem,
    SimulateError,
};
use dpc::core::{DaeModel, ImplicitDae, MatrixSink};
use dpc_models::wheel_design;
use dpc_models::{
    CartPendulum, CartPendulumReference, CartPendulumTracking, Wheel, WheelReference, WheelTracking,
};

const X0: [f64; 5] = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];

/// The wheel's DPC without a preliminary feedback (the tests of the loop's plumbing).
fn plain_wheel_controller(
) -> Dpc<WheelTracking, WheelReference, NalgebraLu<{ WheelTracking::N_EQUATIONS }>> {
    Dpc::new(
        WheelTracking::default(),
        WheelReference::default(),
        NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new(),
        DpcOptions::default(),
    )
    .expect("controller")
}

/// The paper's wheel with the preliminary feedback about the nominal, `h = 0.05`.
fn wheel_run(hold: Hold, t_end: f64, output_step: Option<f64>) -> ClosedLoop {
    let mut dpc = Dpc::new(
        WheelTracking::default(),
        WheelReference::default(),
        NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new(),
        DpcOptions::default(),
    )
    .expect("controller")
    .with_prefeedback(wheel_design::prefeedback(&Wheel::default()).expect("design"))
    .expect("prefeedback");
    let opts = ClosedLoopOptions {
        h: 0.05,
        t_end,
        hold,
        output_step,
        ..ClosedLoopOptions::default()
    };
    simulate(&Wheel::default(), &mut dpc, &X0, &opts).expect("run starts")
}

/// Every number of the samples, as bits (NaN compares equal to itself).
fn sample_bits(run: &ClosedLoop) -> Vec<u64> {
    run.samples
        .iter()
        .flat_map(|s| {
            std::iter::once(s.t)
                .chain(s.x.iter().copied())
                .chain(s.u.iter().copied())
                .chain(s.y.iter().copied())
                .chain(s.reference.iter().copied())
                .chain(s.error.iter().copied())
        })
        .map(f64::to_bits)
        .collect()
}

fn assert_same_samples(without: &ClosedLoop, with: &ClosedLoop, what: &str) {
    assert_eq!(without.samples.len(), with.samples.len(), "{what}");
    assert!(
        sample_bits(without) == sample_bits(with),
        "{what}: samples differ"
    );
    assert_eq!(without.plant_work, with.plant_work, "{what}: plant work");
    assert_eq!(
        without.newton_iterations, with.newton_iterations,
        "{what}: controller work"
    );
    assert_eq!(without.divergence, with.divergence, "{what}");
    assert!(without.dense.is_empty());
}

#[test]
fn the_samples_are_bit_identical_with_and_without_dense_output() {
    for hold in [Hold::Input, Hold::Correction] {
        let without = wheel_run(hold, 2.0, None);
        let with = wheel_run(hold, 2.0, Some(0.01));
        assert!(with.divergence.is_none(), "{:?}", with.divergence);
        assert_same_samples(&without, &with, &format!("{hold:?}"));
        // 41 samples at k * 0.05; four points between each two, at j * 0.01.
        assert_eq!(with.dense.len(), 40 * 4, "{hold:?}");
        let points: Vec<_> = with.trajectory().collect();
        assert_eq!(points.len(), 41 + 160);
        assert!(points.windows(2).all(|w| w[0].t < w[1].t));
        for (j, p) in points.iter().enumerate() {
            assert_eq!(p.sample, j % 5 == 0, "point {j} at t = {}", p.t);
            assert!((p.t - 0.01 * j as f64).abs() < 1e-12, "{j}: {}", p.t);
        }
        // Between samples the input is the held one, or under the correction hold the
        // preliminary feedback of the moving state (only v is held).
        let moving = points
            .windows(2)
            .filter(|w| !w[1].sample && w[0].u != w[1].u)
            .count();
        match hold {
            Hold::Input => assert_eq!(moving, 0),
            Hold::Correction => assert_eq!(moving, 160),
        }
    }
}

#[test]
fn an_output_step_that_does_not_divide_the_period_keeps_its_own_grid() {
    // 0.03 against h = 0.05: the points are j * 0.03 except where one meets a sample (0.15).
    let without = wheel_run(Hold::Input, 0.5, None);
    let with = wheel_run(Hold::Input, 0.5, Some(0.03));
    assert_same_samples(&without, &with, "0.03");
    let times = with.dense.times();
    let expected: Vec<f64> = (1..=16)
        .map(|j| j as f64 * 0.03)
        .filter(|t| ((t / 0.05).round() * 0.05 - t).abs() > 1e-9)
        .collect();
    assert_eq!(times.len(), expected.len(), "{times:?}");
    for (t, e) in times.iter().zip(&expected) {
        assert!((t - e).abs() < 1e-12, "{times:?}");
    }
    // A step longer than the period: some intervals have no point.
    let sparse = wheel_run(Hold::Input, 0.5, Some(0.12));
    assert_same_samples(&without, &sparse, "0.12");
    assert_eq!(sparse.dense.len(), 4);
    // The count made before a run (for the reservation and the command line's row limit)
    // is the number of points the run records.
    for (step, run) in [(0.03, &with), (0.12, &sparse)] {
        let opts = ClosedLoopOptions {
            h: 0.05,
            t_end: 0.5,
            output_step: Some(step),
            ..ClosedLoopOptions::default()
        };
        assert_eq!(opts.dense_points(), run.dense.len(), "{step}");
    }
}

/// The plant with its input held constant, as an implicit DAE in `(x, z)`.
struct Held<'a, M: DaeModel> {
    model: &'a M,
    u: Vec<f64>,
}

impl<M: DaeModel> ImplicitDae for Held<'_, M> {
    fn dimension(&self) -> usize {
        self.model.structure().n_equations()
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let nx = self.model.structure().n_states();
        let (x, z) = y.split_at(nx);
        self.model.residual(t, x, &yp[..nx], z, &self.u, out);
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let nx = self.model.structure().n_states();
        let (x, z) = y.split_at(nx);
        self.model
            .iteration_matrix(t, x, &yp[..nx], z, &self.u, c, out);
    }

    fn is_differential(&self, i: usize) -> bool {
        i < self.model.structure().n_states()
    }
}

/// The plant's state at `t`, integrated from the state `x` at `t0` with `u` held, at a
/// tolerance far below the loop's.
fn reference_solution(x: &[f64], u: &[f64], t0: f64, t: f64) -> Vec<f64> {
    let plant = Wheel::default();
    let held = Held {
        model: &plant,
        u: u.to_vec(),
    };
    let n = held.dimension();
    let opts = Options::with_tolerances(1e-13, 1e-15);
    let mut y = x.to_vec();
    let mut yp = vec![0.0; n];
    consistent_initial_values(&held, &mut FaerDenseLu::new(n), &opts, t0, &mut y, &mut yp)
        .expect("consistent");
    let mut bdf = Bdf::new(&held, FaerDenseLu::new(n), opts, t0, &y, &yp).expect("integrator");
    bdf.solve_to(t, &mut y, None).expect("integrates");
    y
}

#[test]
fn dense_points_lie_on_the_plants_solution_to_its_tolerance() {
    let run = wheel_run(Hold::Input, 2.0, Some(0.01));
    let opts = ClosedLoopOptions::default();
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for p in run.dense.points() {
        // The sample that starts the point's interval, whose input is held over it.
        let sample = run
            .samples
            .iter()
            .rev()
            .find(|s| s.t < p.t)
            .expect("a sample before every point");
        assert_eq!(p.u, &sample.u[..], "the held input at t = {}", p.t);
        let exact = reference_solution(&sample.x, &sample.u, sample.t, p.t);
        let norm = exact.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let difference =
            p.x.iter()
                .zip(&exact)
                .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        // Relative to what the loop's integrator is asked for over one interval.
        let relative = difference / (opts.rtol * norm + opts.atol);
        worst = worst.max(relative);
        checked += 1;
        // The outputs and errors recorded with the point are those of its state.
        let mut y = [0.0; 2];
        Wheel::default().outputs(p.t, p.x, &[], p.u, &mut y);
        assert_eq!(p.y, &y[..]);
        for i in 0..2 {
            assert_eq!(p.error[i], p.y[i] - p.reference[i]);
        }
    }
    assert_eq!(checked, 160);
    eprintln!("dense output vs the plant's solution: worst {worst:.3} x (rtol |x| + atol)");
    assert!(
        worst < 10.0,
        "worst error {worst} x (rtol |x| + atol) of the loop's tolerance"
    );
}

#[test]
fn a_constrained_plant_records_its_motion_between_samples_too() {
    let run = |output_step| {
        let tracking = CartPendulumTracking::default();
        let n = tracking.structure().n_equations();
        let mut dpc = Dpc::new(
            tracking,
            CartPendulumReference::default(),
            FaerDenseLu::new(n),
            DpcOptions::default(),
        )
        .expect("controller");
        let l = 0.5_f64;
        let phi = 0.3_f64;
        let x0 = [0.0, l * phi.sin(), -l * phi.cos(), 0.0, 0.0, 0.0];
        let opts = ClosedLoopOptions {
            h: 0.01,
            t_end: 0.3,
            tracking_bounds: vec![Some(1.0)],
            output_step,
            ..ClosedLoopOptions::default()
        };
        simulate(&CartPendulum::default(), &mut dpc, &x0, &opts).expect("run starts")
    };
    let without = run(None);
    let with = run(Some(0.0025));
    assert_same_samples(&without, &with, "cart pendulum");
    assert_eq!(with.dense.len(), 3 * (with.samples.len() - 1));
    // The points lie between their neighbouring samples' positions (a smooth swing over
    // 0.01 s), and keep the rope's length to the loop's tolerance.
    for p in with.dense.points() {
        let (cart, load_x, load_y) = (p.x[0], p.x[1], p.x[2]);
        let rope = ((load_x - cart).powi(2) + load_y.powi(2)).sqrt();
        assert!((rope - 0.5).abs() < 1e-6, "rope {rope} at t = {}", p.t);
    }
}

#[test]
fn a_bad_output_step_is_a_typed_error() {
    let mut dpc = plain_wheel_controller();
    for (step, expected) in [
        (0.0, OutputStepProblem::NotPositive),
        (-0.01, OutputStepProblem::NotPositive),
        (f64::NAN, OutputStepProblem::NotPositive),
        (f64::INFINITY, OutputStepProblem::NotPositive),
        (1e-14, OutputStepProblem::TooSmall),
    ] {
        let opts = ClosedLoopOptions {
            t_end: 20.0,
            output_step: Some(step),
            ..ClosedLoopOptions::default()
        };
        let err = simulate(&Wheel::default(), &mut dpc, &X0, &opts).unwrap_err();
        match &err {
            SimulateError::OutputStep { step: s, problem } => {
                assert_eq!(*problem, expected, "{step}");
                assert!(s.to_bits() == step.to_bits(), "{step}");
            }
            other => panic!("{step}: {other:?}"),
        }
        let message = err.to_string();
        assert!(message.starts_with("output step "), "{message}");
        assert!(!message.contains('\n'), "{message}");
    }
}

#[test]
fn a_bad_initial_state_is_a_typed_error_naming_the_state() {
    let mut dpc = plain_wheel_controller();
    let opts = ClosedLoopOptions {
        t_end: 1.0,
        ..ClosedLoopOptions::default()
    };
    let plant = Wheel::default();
    match simulate(&plant, &mut dpc, &X0[..4], &opts).unwrap_err() {
        SimulateError::InitialStateLength { expected, found } => {
            assert_eq!((expected, found), (5, 4))
        }
        other => panic!("{other:?}"),
    }
    let mut x0 = X0;
    x0[2] = f64::NAN;
    let err = simulate(&plant, &mut dpc, &x0, &opts).unwrap_err();
    let name = plant.structure().states[2].to_string();
    match &err {
        SimulateError::NonFiniteInitialState { state, value } => {
            assert_eq!(state, &name);
            assert!(value.is_nan());
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains(&format!("`{name}`")), "{err}");
}

#[test]
fn progress_is_told_of_every_sample() {
    let mut dpc = plain_wheel_controller();
    let opts = ClosedLoopOptions {
        t_end: 0.5,
        ..ClosedLoopOptions::default()
    };
    let mut told = Vec::new();
    let run = simulate_with_progress(&Wheel::default(), &mut dpc, &X0, &opts, &mut |t, end| {
        told.push((t, end))
    })
    .expect("run starts");
    assert_eq!(told.len(), run.samples.len());
    for ((t, end), s) in told.iter().zip(&run.samples) {
        assert_eq!(*t, s.t);
        assert_eq!(*end, 0.5);
    }
}
