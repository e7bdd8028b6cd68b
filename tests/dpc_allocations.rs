//! A DPC control update for a fixed-size generated model allocates nothing on the heap
//! after setup, and a closed-loop run allocates per sample only the vectors of the sample it
//! records (and for its dense output between samples nothing per point): counted with a
//! thread-local counting allocator (the tests take a lock as well).

use std::sync::{Arc, Mutex};

use dpc::core::controller::{Dpc, DpcOptions, Extraction};
use dpc::core::linear_solver::NalgebraLu;
use dpc::core::simulate::{simulate, ClosedLoopOptions, Hold};
use dpc_models::wheel_design;
use dpc_models::{Wheel, WheelReference, WheelTracking};

#[path = "../dpc-core/tests/common/counting_allocator.rs"]
mod counting_allocator;
use counting_allocator::allocations;

/// Held by each test while it counts.
static COUNTING: Mutex<()> = Mutex::new(());

/// How the controller of a test is set up.
#[derive(Debug, Clone, Copy)]
enum Feedback {
    /// Plain DPC.
    None,
    /// The paper's preliminary feedback about the nominal motion.
    AboutNominal,
    /// The same `K_n` about the reference (shared with the controller through an `Arc`).
    AboutReference,
}

#[test]
fn wheel_control_updates_do_not_allocate() {
    let _counting = COUNTING.lock().unwrap_or_else(|e| e.into_inner());
    let feedbacks = [
        Feedback::None,
        Feedback::AboutNominal,
        Feedback::AboutReference,
    ];
    for (feedback, extraction) in feedbacks
        .into_iter()
        .flat_map(|f| [(f, Extraction::FirstUsable), (f, Extraction::Extrapolated)])
    {
        let reference = Arc::new(WheelReference::default());
        let mut dpc = Dpc::new(
            WheelTracking::default(),
            reference.clone(),
            NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new(),
            DpcOptions {
                extraction,
                ..DpcOptions::default()
            },
        )
        .expect("controller");
        let mut law = wheel_design::prefeedback(&Wheel::default()).expect("design");
        match feedback {
            Feedback::None => {}
            Feedback::AboutNominal => dpc = dpc.with_prefeedback(law).expect("prefeedback"),
            Feedback::AboutReference => {
                law.nominal = Box::new(wheel_design::about_reference(reference).expect("map"));
                dpc = dpc.with_prefeedback(law).expect("prefeedback");
            }
        }
        let mut u = [0.0; 2];
        let mut x = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];
        // The first update warms up; every later one must not allocate.
        dpc.control(0.0, &x, &mut u).expect("first update");
        let before = allocations();
        for k in 1..50 {
            let t = k as f64 * 0.05;
            x[1] = -6.0 * t;
            x[0] += 0.001;
            dpc.control(t, &x, &mut u).expect("update");
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "allocations during 49 control updates ({feedback:?}, {extraction:?})"
        );
        assert!(u.iter().all(|v| v.is_finite()));
    }
}

/// Allocations of one closed-loop run of the paper's wheel (preliminary feedback about the
/// nominal, `h = 0.05`) to `t_end`, and the numbers of samples and dense points it recorded.
fn closed_loop_allocations(
    hold: Hold,
    t_end: f64,
    output_step: Option<f64>,
) -> (usize, usize, usize) {
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
    let x0 = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];
    let before = allocations();
    let run = simulate(&Wheel::default(), &mut dpc, &x0, &opts).expect("run starts");
    let after = allocations();
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    assert!(run.events.is_empty(), "{:?}", run.events);
    (after - before, run.samples.len(), run.dense.len())
}

#[test]
fn a_closed_loop_sample_allocates_only_its_record() {
    let _counting = COUNTING.lock().unwrap_or_else(|e| e.into_inner());
    // Each recorded sample owns five vectors (x, u, y, reference, error); the controller,
    // the hold, the consistent initialisation and the plant integrator allocate once per run,
    // so a run twice as long allocates exactly five more per extra sample.
    for hold in [Hold::Input, Hold::Correction] {
        let (short, n_short, _) = closed_loop_allocations(hold, 2.0, None);
        let (long, n_long, _) = closed_loop_allocations(hold, 4.0, None);
        assert_eq!((n_short, n_long), (41, 81));
        assert_eq!(
            long - short,
            5 * (n_long - n_short),
            "allocations: {short} for {n_short} samples, {long} for {n_long} ({hold:?})"
        );
    }
}

#[test]
fn dense_output_allocates_nothing_per_point() {
    let _counting = COUNTING.lock().unwrap_or_else(|e| e.into_inner());
    // The dense output is stored flat in arrays reserved before the run (and one work vector):
    // a run that records points allocates a fixed number more than one that does not, however
    // many points it records; a longer run still allocates only its samples' records.
    for hold in [Hold::Input, Hold::Correction] {
        let (plain, n_plain, _) = closed_loop_allocations(hold, 2.0, None);
        let (short, n_short, d_short) = closed_loop_allocations(hold, 2.0, Some(0.01));
        let (long, n_long, d_long) = closed_loop_allocations(hold, 4.0, Some(0.01));
        assert_eq!((n_plain, n_short, n_long), (41, 41, 81));
        assert_eq!((d_short, d_long), (160, 320));
        // Its six arrays (times, states, inputs, outputs, references, errors), the vector
        // the integrator interpolates into and three for a point's input, outputs and
        // references.
        assert_eq!(
            short - plain,
            10,
            "dense output of {d_short} points: {} allocations more ({hold:?})",
            short - plain
        );
        assert_eq!(
            long - short,
            5 * (n_long - n_short),
            "allocations: {short} for {n_short} samples and {d_short} points, {long} for {n_long} and {d_long} ({hold:?})"
        );
    }
}
