//! The paper's wheel under DPC (Section 5), shared by `tests/wheel_closed_loop.rs` and the
//! sampling-period study `examples/sampling_period.rs`: the design, the closed loop and the
//! bisection of the period where it stops tracking.
#![allow(dead_code)]

use dpc::core::controller::{Dpc, DpcOptions, Extraction};
use dpc::core::linear_analysis::sampled::{CriticalPeriod, SampledLoop};
use dpc::core::linear_analysis::{Analysis, LinearSystem};
use dpc::core::linear_solver::NalgebraLu;
use dpc::core::prefeedback::{Nominal, Prefeedback};
use dpc::core::simulate::{simulate, ClosedLoop, ClosedLoopOptions, Hold};
use dpc_models::wheel_design;
use dpc_models::{Wheel, WheelReference, WheelTracking};
use std::f64::consts::FRAC_PI_2;

/// The paper's linearisation and analysis (`dpc_models::wheel_design`).
pub fn linear_design() -> (LinearSystem, Analysis) {
    let design = wheel_design::design(&Wheel::default()).expect("design");
    let (sys, analysis) = (design.system, design.analysis);
    assert!(
        !analysis.dpc_stable,
        "the linear analysis predicts DPC alone unstable"
    );
    (sys, analysis)
}

/// Where the preliminary feedback's deviation coordinates are taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum About {
    /// `x0(t) = [pi/2, -6t, 0, 0, -6]`.
    Nominal,
    /// `theta, psi, dtheta, dpsi` of `x0(t)` replaced by the reference and its derivative.
    Reference,
}

pub fn prefeedback(about: About) -> Prefeedback {
    let nominal: Box<dyn Nominal + Send + Sync> = match about {
        About::Nominal => Box::new(wheel_design::nominal()),
        About::Reference => Box::new(
            wheel_design::about_reference(WheelReference::default()).expect("reference map"),
        ),
    };
    Prefeedback {
        k_n: linear_design().1.k_n.expect("K_n"),
        nominal,
    }
}

pub fn run(
    h: f64,
    t_end: f64,
    prefeedback_about: Option<About>,
    extraction: Extraction,
    hold: Hold,
) -> ClosedLoop {
    let mut dpc = Dpc::new(
        WheelTracking::default(),
        WheelReference::default(),
        NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new(),
        DpcOptions {
            delta: 1e-3,
            extraction,
            ..DpcOptions::default()
        },
    )
    .expect("controller");
    if let Some(about) = prefeedback_about {
        dpc = dpc
            .with_prefeedback(prefeedback(about))
            .expect("prefeedback");
    }
    simulate(
        &Wheel::default(),
        &mut dpc,
        &[FRAC_PI_2, 0.0, 0.0, 0.0, -6.0],
        &ClosedLoopOptions {
            h,
            t_end,
            hold,
            ..ClosedLoopOptions::default()
        },
    )
    .expect("run starts")
}

/// The controller's work over a run, pinned as a snapshot (as the BDF's counters are): a
/// change of the Newton test, the warm start, the extrapolation or the retry ladder shows up
/// as a diff of `tests/snapshots/wheel_closed_loop__*.snap`.
#[derive(Debug)]
#[allow(dead_code)] // read through Debug by the snapshot
pub struct ControllerWork {
    samples: usize,
    newton_iterations: usize,
    retries: usize,
    retried_samples: usize,
    failed_samples: usize,
    diverged_at: Option<f64>,
}

pub fn work(run: &ClosedLoop) -> ControllerWork {
    ControllerWork {
        samples: run.samples.len(),
        newton_iterations: run.newton_iterations,
        retries: run.retries,
        retried_samples: run.retried_samples(),
        failed_samples: run.failed_samples(),
        diverged_at: run.divergence.as_ref().map(|d| d.t),
    }
}

/// Largest |error| per output over the last quarter of the run.
pub fn late_error(run: &ClosedLoop) -> [f64; 2] {
    let t_end = run.samples.last().unwrap().t;
    let m = run.max_abs_error_since(0.75 * t_end);
    [m[0], m[1]]
}

/// The linear sampled-data prediction: the period at which the spectral radius of the
/// linearised loop under the held limit law reaches 1.
pub fn predicted_critical_period(hold: Hold) -> f64 {
    let (sys, analysis) = linear_design();
    let sampled = SampledLoop::from_analysis(&sys, &analysis, hold).expect("sampled loop");
    match sampled
        .critical_period(3.0, 300, 1e-6)
        .expect("spectral radius")
    {
        CriticalPeriod::At(h) => h,
        other => panic!("the linearised loop should lose stability below h = 3: {other:?}"),
    }
}

/// Whether the nonlinear loop follows the path at period `h`: no divergence reported and
/// late errors below 0.1 rad (near the limit the errors grow for many seconds before a
/// state leaves the domain).
pub fn tracks(h: f64, about: About, hold: Hold) -> bool {
    let r = run(h, 20.0, Some(about), Extraction::Extrapolated, hold);
    r.divergence.is_none() && late_error(&r).iter().all(|e| *e < 0.1)
}

/// Whether the nonlinear loop runs to the end without a reported divergence (errors may be
/// large).
pub fn stays_bounded(h: f64, about: About, hold: Hold) -> bool {
    run(h, 20.0, Some(about), Extraction::Extrapolated, hold)
        .divergence
        .is_none()
}

/// Bisection of the period where `ok` switches from true (at `lo`) to false (at `hi`).
pub fn bisect(ok: impl Fn(f64) -> bool, mut lo: f64, mut hi: f64) -> f64 {
    assert!(ok(lo) && !ok(hi), "no switch in [{lo}, {hi}]");
    while hi - lo > 1e-3 * hi {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
