//! Every user- or model-caused failure of the Radau integrator is a typed error naming what the
//! user wrote, never a panic.

#[path = "common/no_solution.rs"]
mod no_solution;

use dpc_core::bdf::Tolerance;
use dpc_core::linear_solver::{FaerDenseLu, NalgebraLu};
use dpc_core::radau::{Options, Radau, RadauError, StageSystem, StepFailure};
use dpc_core::{ImplicitDae, MatrixSink};
use no_solution::NoSolution;

/// `x' + x = 0` and a second equation chosen by `kind`:
/// 0: `0 = x - 1` (the unknown `z` appears nowhere: singular column);
/// 1: `0 = 0` (an empty equation: singular row);
/// 2: `0 = z - x` but the residual is NaN for `t > 0.5`;
/// 3: `x' = x^2` instead of the decay (from `x(0) = 1` it blows up at `t = 1`), `0 = z - x`;
/// 4 (and any other): `0 = z - x`, the model solved without failure;
/// 5: `0 = z - x` with a wrong iteration matrix (`dF/dz = 0.1` for 1).
struct Broken {
    kind: u8,
}

impl ImplicitDae for Broken {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = if self.kind == 3 {
            yp[0] - y[0] * y[0]
        } else {
            yp[0] + y[0]
        };
        out[1] = match self.kind {
            0 => y[0] - 1.0,
            1 => 0.0,
            2 if t > 0.5 => f64::NAN,
            _ => y[1] - y[0],
        };
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(
            0,
            0,
            if self.kind == 3 {
                c - 2.0 * y[0]
            } else {
                1.0 + c
            },
        );
        match self.kind {
            0 => m.set(1, 0, 1.0),
            1 => {}
            _ => {
                m.set(1, 1, if self.kind == 5 { 0.1 } else { 1.0 });
                m.set(1, 0, -1.0);
            }
        }
    }
    fn equation_name(&self, i: usize) -> String {
        ["decay", "constraint"][i].to_string()
    }
    fn unknown_name(&self, i: usize) -> String {
        ["x", "z"][i].to_string()
    }
}

fn run<L: dpc_core::linear_solver::LinearSolver>(
    kind: u8,
    ls: L,
    opts: Options,
) -> Result<Radau<Broken, L>, RadauError> {
    let y0 = [1.0, 1.0];
    let yp0 = [-1.0, 0.0];
    let mut r = Radau::new(Broken { kind }, ls, opts, 0.0, &y0, &yp0)?;
    let mut y = [0.0; 2];
    r.solve_to(1.0, &mut y, None)?;
    Ok(r)
}

#[test]
fn singular_column_names_the_unknown() {
    for err in [
        run(0, NalgebraLu::<2>::new(), Options::default()).err(),
        run(0, FaerDenseLu::new(2), Options::default()).err(),
    ] {
        match err {
            Some(RadauError::SingularMatrix {
                unknown, system, ..
            }) => {
                assert_eq!(system, StageSystem::Real);
                assert_eq!(unknown.as_deref(), Some("z"));
            }
            other => panic!("expected a singular matrix, got {other:?}"),
        }
    }
}

#[test]
fn singular_row_names_the_equation() {
    let err = run(1, NalgebraLu::<2>::new(), Options::default()).err();
    match err {
        Some(e @ RadauError::SingularMatrix { .. }) => {
            let RadauError::SingularMatrix { ref equation, .. } = e else {
                unreachable!()
            };
            assert_eq!(equation.as_deref(), Some("constraint"));
            let msg = e.to_string();
            assert!(
                msg.contains("constraint") && !msg.contains("Some("),
                "{msg}"
            );
        }
        other => panic!("expected a singular matrix, got {other:?}"),
    }
}

#[test]
fn nan_residual_names_the_equation() {
    let err = run(2, NalgebraLu::<2>::new(), Options::default()).err();
    match err {
        Some(RadauError::NonFiniteResidual { t, equation }) => {
            assert_eq!(equation, "constraint");
            assert!(t > 0.5 && t < 0.6, "{t}");
        }
        other => panic!("expected a non-finite residual, got {other:?}"),
    }
}

#[test]
fn blow_up_stops_with_step_too_small() {
    let opts = Options {
        min_step: 1e-6,
        ..Options::with_tolerances(1e-6, 1e-6)
    };
    let err = run(3, NalgebraLu::<2>::new(), opts).err();
    match err {
        Some(ref e @ RadauError::StepTooSmall { t, h, cause }) => {
            println!("{e}");
            assert!(t < 1.0 && t > 0.99, "{t}");
            assert!(h < 1e-6, "{h}");
            assert!(matches!(
                cause,
                StepFailure::ErrorTest | StepFailure::Newton
            ));
        }
        other => panic!("expected a step failure, got {other:?}"),
    }
}

#[test]
fn a_wrong_iteration_matrix_is_named_as_a_possible_cause() {
    // Newton with `dF/dz` ten times too small overshoots `z` ninefold at every step size: the
    // failure says that the matrix does not describe the equations at any step.
    let err = run(5, NalgebraLu::<2>::new(), Options::default()).err();
    match err {
        Some(
            ref e @ RadauError::StalledNewton {
                t,
                theta,
                ref source,
                ..
            },
        ) => {
            println!("{e}");
            assert!(t < 1e-6, "{t}");
            assert!(theta >= 0.5, "{theta}");
            let msg = e.to_string();
            assert!(msg.contains("not the derivative of its residual"), "{msg}");
            assert!(matches!(
                **source,
                RadauError::StepTooSmall { .. } | RadauError::RepeatedFailures { .. }
            ));
        }
        other => panic!("expected a stalled iteration, got {other:?}"),
    }
}

#[test]
fn bad_input_is_rejected_before_integrating() {
    let y0 = [1.0, 1.0];
    let yp0 = [-1.0, 0.0];
    let make = |opts: Options| {
        Radau::new(
            Broken { kind: 4 },
            NalgebraLu::<2>::new(),
            opts,
            0.0,
            &y0,
            &yp0,
        )
        .err()
    };
    assert!(matches!(
        make(Options::with_tolerances(-1.0, 1e-8)),
        Some(RadauError::InvalidTolerance { which: "rtol", .. })
    ));
    assert!(matches!(
        make(Options::with_tolerances(0.0, 0.0)),
        Some(RadauError::InvalidTolerance { .. })
    ));
    assert!(matches!(
        make(Options {
            atol: Tolerance::Vector(vec![1e-8; 3]),
            ..Options::default()
        }),
        Some(RadauError::DimensionMismatch { what: "atol", .. })
    ));
    assert!(matches!(
        make(Options {
            index: vec![1, 4],
            ..Options::default()
        }),
        Some(RadauError::InvalidOption(ref o)) if o.name == "index"
    ));
    assert!(matches!(
        make(Options {
            initial_step: Some(-1.0),
            ..Options::default()
        }),
        Some(RadauError::InvalidOption(ref o)) if o.name == "initial_step"
    ));
    assert!(matches!(
        Radau::new(
            Broken { kind: 4 },
            NalgebraLu::<3>::new(),
            Options::default(),
            0.0,
            &y0,
            &yp0
        )
        .err(),
        Some(RadauError::DimensionMismatch {
            what: "linear solver",
            ..
        })
    ));
    // A NaN at the initial point names the equation.
    let err = Radau::new(
        Broken { kind: 2 },
        NalgebraLu::<2>::new(),
        Options::default(),
        1.0,
        &y0,
        &yp0,
    )
    .err();
    assert!(
        matches!(err, Some(RadauError::NonFiniteResidual { ref equation, .. }) if equation == "constraint"),
        "{err:?}"
    );
    // Output times behind the integrator and too many steps.
    let mut r = run(4, NalgebraLu::<2>::new(), Options::default()).unwrap();
    let mut y = [0.0; 2];
    assert!(matches!(
        r.solve_to(0.1, &mut y, None),
        Err(RadauError::TimeOutOfRange { .. })
    ));
    assert!(matches!(
        r.set_stop_time(0.5),
        Err(RadauError::TimeOutOfRange { .. })
    ));
    let mut r = Radau::new(
        Broken { kind: 4 },
        NalgebraLu::<2>::new(),
        Options {
            max_steps: 3,
            ..Options::with_tolerances(1e-10, 1e-10)
        },
        0.0,
        &y0,
        &yp0,
    )
    .unwrap();
    assert!(matches!(
        r.solve_to(100.0, &mut y, None),
        Err(RadauError::TooManySteps { max_steps: 3, .. })
    ));
}

#[test]
fn a_failure_from_a_start_off_an_equation_names_it() {
    // Newton fails at every step size from y = 1, where the residual is 2: the failure before
    // the first step says the initial values do not satisfy the equation, by its name, with
    // the failure as its source.
    let mut r = Radau::new(
        NoSolution,
        NalgebraLu::<1>::new(),
        Options::with_tolerances(1e-6, 1e-6),
        0.0,
        &[1.0],
        &[0.0],
    )
    .unwrap();
    let mut y = [0.0];
    match r.solve_to(1.0, &mut y, None) {
        Err(
            ref e @ RadauError::InconsistentStart {
                ref equation,
                residual,
                ref source,
                ..
            },
        ) => {
            println!("{e}");
            assert_eq!(equation, "y squared plus one");
            assert_eq!(residual, 2.0);
            assert!(
                matches!(
                    **source,
                    RadauError::StepTooSmall { .. } | RadauError::RepeatedFailures { .. }
                ),
                "{source:?}"
            );
        }
        other => panic!("unexpected {other:?}"),
    }
}
