//! Every user- or model-caused failure of the integrator is a typed error, never a panic.

#[path = "common/bdf_problems.rs"]
mod problems;

#[path = "common/no_solution.rs"]
mod no_solution;

use dpc_core::bdf::{consistent_initial_values, Bdf, BdfError, FixedBdf, Options, Tolerance};
use dpc_core::linear_solver::{FaerDenseLu, FaerSparseLu, NalgebraLu};
use dpc_core::{ImplicitDae, MatrixSink};
use no_solution::NoSolution;
use problems::Robertson;

/// `y0' + y0 = 0` and a second equation chosen by `kind`:
/// 0: `0 = y0 - 1` (the unknown `z` appears nowhere: singular column);
/// 1: `0 = 0` (an empty equation: singular row);
/// 2: `0 = z - y0` but the residual is NaN for `t > 0.5`;
/// 3: `0 = z - y0` with a wrong iteration matrix (`dF/dz = 0.1` for 1).
struct Broken {
    kind: u8,
}

impl ImplicitDae for Broken {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] + y[0];
        out[1] = match self.kind {
            0 => y[0] - 1.0,
            1 => 0.0,
            _ => {
                if t > 0.5 && self.kind == 2 {
                    f64::NAN
                } else {
                    y[1] - y[0]
                }
            }
        };
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, 1.0 + c);
        match self.kind {
            0 => m.set(1, 0, 1.0),
            1 => {}
            _ => {
                m.set(1, 1, if self.kind == 3 { 0.1 } else { 1.0 });
                m.set(1, 0, -1.0);
            }
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        i == 0
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
    y0: [f64; 2],
) -> Result<(), BdfError> {
    let yp0 = [-y0[0], 0.0];
    let mut bdf = Bdf::new(Broken { kind }, ls, Options::default(), 0.0, &y0, &yp0)?;
    let mut y = [0.0; 2];
    bdf.solve_to(1.0, &mut y, None).map(|_| ())
}

#[test]
fn singular_column_names_the_unknown() {
    for err in [
        run(0, NalgebraLu::<2>::new(), [1.0, 0.0]).unwrap_err(),
        run(0, FaerDenseLu::new(2), [1.0, 0.0]).unwrap_err(),
    ] {
        match err {
            BdfError::SingularMatrix { unknown, .. } => assert_eq!(unknown.as_deref(), Some("z")),
            e => panic!("unexpected {e:?}"),
        }
    }
    let sparse = FaerSparseLu::new(2, &[(0, 0), (1, 0)]).unwrap();
    match run(0, sparse, [1.0, 0.0]).unwrap_err() {
        BdfError::SingularMatrix { unknown, .. } => assert_eq!(unknown.as_deref(), Some("z")),
        e => panic!("unexpected {e:?}"),
    }
}

#[test]
fn singular_row_names_the_equation() {
    match run(1, NalgebraLu::<2>::new(), [1.0, 0.0]).unwrap_err() {
        BdfError::SingularMatrix { equation, .. } => {
            assert_eq!(equation.as_deref(), Some("constraint"))
        }
        e => panic!("unexpected {e:?}"),
    }
    let sparse = FaerSparseLu::new(2, &[(0, 0)]).unwrap();
    match run(1, sparse, [1.0, 0.0]).unwrap_err() {
        BdfError::SingularMatrix { equation, .. } => {
            assert_eq!(equation.as_deref(), Some("constraint"))
        }
        e => panic!("unexpected {e:?}"),
    }
}

#[test]
fn nan_residual_names_the_equation() {
    match run(2, NalgebraLu::<2>::new(), [1.0, 1.0]).unwrap_err() {
        BdfError::NonFiniteResidual { equation, t } => {
            assert_eq!(equation, "constraint");
            assert!(t > 0.5);
        }
        e => panic!("unexpected {e:?}"),
    }
    // Non-finite at the initial point is reported at construction.
    let r = Bdf::new(
        Broken { kind: 2 },
        NalgebraLu::<2>::new(),
        Options::default(),
        1.0,
        &[1.0, 1.0],
        &[0.0; 2],
    );
    assert!(matches!(r, Err(BdfError::NonFiniteResidual { .. })));
}

#[test]
fn bad_tolerances_are_rejected() {
    let y0 = [1.0, 0.0, 0.0];
    let yp0 = [-0.04, 0.04, 0.0];
    let bad = [
        Options::with_tolerances(-1e-6, 1e-8),
        Options::with_tolerances(1e-6, f64::NAN),
        Options::with_tolerances(0.0, 0.0),
    ];
    for opts in bad {
        let r = Bdf::new(
            Robertson,
            NalgebraLu::<3>::new(),
            opts.clone(),
            0.0,
            &y0,
            &yp0,
        );
        assert!(
            matches!(r, Err(BdfError::InvalidTolerance { .. })),
            "{opts:?}"
        );
    }
    let opts = Options {
        atol: Tolerance::Vector(vec![1e-8; 2]),
        ..Options::default()
    };
    let r = Bdf::new(Robertson, NalgebraLu::<3>::new(), opts, 0.0, &y0, &yp0);
    assert!(matches!(
        r,
        Err(BdfError::DimensionMismatch { what: "atol", .. })
    ));
    // A weight that becomes infinite (pure relative tolerance, component at zero).
    let opts = Options::with_tolerances(1e-6, 0.0);
    let mut bdf = Bdf::new(
        Robertson,
        NalgebraLu::<3>::new(),
        opts,
        0.0,
        &[1.0, 0.5, 0.0],
        &yp0,
    );
    if let Ok(b) = &mut bdf {
        let mut y = [0.0; 3];
        assert!(matches!(
            b.solve_to(1.0, &mut y, None),
            Err(BdfError::InvalidTolerance { .. })
        ));
    } else {
        assert!(matches!(bdf, Err(BdfError::InvalidTolerance { .. })));
    }
}

#[test]
fn bad_options_are_rejected() {
    let y0 = [1.0, 0.0, 0.0];
    let yp0 = [-0.04, 0.04, 0.0];
    for opts in [
        Options {
            max_order: 6,
            ..Options::default()
        },
        Options {
            max_order: 0,
            ..Options::default()
        },
        Options {
            initial_step: Some(-1.0),
            ..Options::default()
        },
        Options {
            index: vec![1, 1, 4],
            ..Options::default()
        },
    ] {
        let r = Bdf::new(
            Robertson,
            NalgebraLu::<3>::new(),
            opts.clone(),
            0.0,
            &y0,
            &yp0,
        );
        assert!(matches!(r, Err(BdfError::InvalidOption(_))), "{opts:?}");
    }
    let r = FixedBdf::new(
        Robertson,
        NalgebraLu::<3>::new(),
        Options::default(),
        6,
        0.1,
        0.0,
        &y0,
    );
    assert!(matches!(r, Err(BdfError::InvalidOption(ref o)) if o.name == "order"));
    let r = FixedBdf::new(
        Robertson,
        NalgebraLu::<3>::new(),
        Options::default(),
        2,
        0.0,
        0.0,
        &y0,
    );
    assert!(matches!(r, Err(BdfError::InvalidOption(ref o)) if o.name == "h"));
}

#[test]
fn dimension_mismatches_are_rejected() {
    let r = Bdf::new(
        Robertson,
        NalgebraLu::<3>::new(),
        Options::default(),
        0.0,
        &[1.0, 0.0],
        &[0.0; 3],
    );
    assert!(matches!(
        r,
        Err(BdfError::DimensionMismatch {
            what: "y0",
            expected: 3,
            found: 2
        })
    ));
    let r = Bdf::new(
        Robertson,
        NalgebraLu::<2>::new(),
        Options::default(),
        0.0,
        &[1.0, 0.0, 0.0],
        &[0.0; 3],
    );
    assert!(matches!(
        r,
        Err(BdfError::DimensionMismatch {
            what: "linear solver",
            ..
        })
    ));
    let r = FixedBdf::new(
        Robertson,
        FaerDenseLu::new(4),
        Options::default(),
        1,
        0.1,
        0.0,
        &[1.0, 0.0, 0.0],
    );
    assert!(matches!(r, Err(BdfError::DimensionMismatch { .. })));
    let mut bdf = Bdf::new(
        Robertson,
        NalgebraLu::<3>::new(),
        Options::default(),
        0.0,
        &[1.0, 0.0, 0.0],
        &[-0.04, 0.04, 0.0],
    )
    .unwrap();
    let mut y = [0.0; 3];
    assert!(matches!(
        bdf.solve_to(f64::NAN, &mut y, None),
        Err(BdfError::TimeOutOfRange { .. })
    ));
    let mut short = [0.0; 2];
    assert!(matches!(
        bdf.solve_to(1.0, &mut short, None),
        Err(BdfError::DimensionMismatch { .. })
    ));
}

#[test]
fn too_many_steps() {
    let opts = Options {
        max_steps: 10,
        ..Options::default()
    };
    let mut bdf = Bdf::new(
        Robertson,
        NalgebraLu::<3>::new(),
        opts,
        0.0,
        &[1.0, 0.0, 0.0],
        &[-0.04, 0.04, 0.0],
    )
    .unwrap();
    let mut y = [0.0; 3];
    match bdf.solve_to(1e5, &mut y, None) {
        Err(BdfError::TooManySteps {
            max_steps: 10, t, ..
        }) => assert!(t > 0.0 && t < 1e5),
        r => panic!("unexpected {r:?}"),
    }
    // The integrator is still usable after the error.
    assert!(bdf.solve_to(bdf.t() + 1e-6, &mut y, None).is_ok());
}

#[test]
fn fixed_step_newton_failure_is_typed_and_leaves_state() {
    let mut f = FixedBdf::new(
        NoSolution,
        NalgebraLu::<1>::new(),
        Options::default(),
        1,
        0.1,
        0.0,
        &[1.0],
    )
    .unwrap();
    assert!(matches!(f.step(), Err(BdfError::NewtonFailed { .. })));
    assert_eq!(f.t(), 0.0);
    assert_eq!(f.y(), &[1.0]);
    // Variable-step: Newton fails down to the limit of failures, before the first step, from
    // a start that does not satisfy the equation (residual 2): the error says so, with the
    // failure as its source.
    let mut b = Bdf::new(
        NoSolution,
        NalgebraLu::<1>::new(),
        Options::default(),
        0.0,
        &[1.0],
        &[0.0],
    )
    .unwrap();
    let mut y = [0.0];
    match b.solve_to(1.0, &mut y, None) {
        Err(BdfError::InconsistentStart {
            equation,
            residual,
            source,
            ..
        }) => {
            assert_eq!(equation, "y squared plus one");
            assert_eq!(residual, 2.0);
            assert!(
                matches!(*source, BdfError::NewtonFailed { .. }),
                "{source:?}"
            );
        }
        Err(BdfError::SingularMatrix { .. }) => {}
        r => panic!("unexpected {r:?}"),
    }
}

#[test]
fn consistent_initialisation_rejects_higher_index() {
    // Index 2: `x' = -x + z`, `0 = x - 1`; z cannot be computed from x alone.
    struct Index2;
    impl ImplicitDae for Index2 {
        fn dimension(&self) -> usize {
            2
        }
        fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = yp[0] + y[0] - y[1];
            out[1] = y[0] - 1.0;
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            _: &[f64],
            _: &[f64],
            c: f64,
            m: &mut S,
        ) {
            m.set(0, 0, 1.0 + c);
            m.set(0, 1, -1.0);
            m.set(1, 0, 1.0);
        }
        fn is_differential(&self, i: usize) -> bool {
            i == 0
        }
        fn unknown_name(&self, i: usize) -> String {
            ["x", "z"][i].to_string()
        }
    }
    let (mut y, mut yp) = ([1.0, 0.0], [0.0, 0.0]);
    let r = consistent_initial_values(
        &Index2,
        &mut NalgebraLu::<2>::new(),
        &Options::default(),
        0.0,
        &mut y,
        &mut yp,
    );
    match r {
        Err(BdfError::SingularMatrix { equation, .. }) => {
            assert_eq!(equation.as_deref(), Some("equation 1"));
        }
        r => panic!("unexpected {r:?}"),
    }
}

#[test]
fn consistent_initialisation_without_a_solution_is_a_typed_failure() {
    // `x' = -x`, `0 = z^2 + 1`: no real `z` solves the constraint; Newton wanders (its
    // iteration is z -> (z - 1/z) / 2) and the failure carries its work and residual.
    struct NoRoot;
    impl ImplicitDae for NoRoot {
        fn dimension(&self) -> usize {
            2
        }
        fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = yp[0] + y[0];
            out[1] = y[1] * y[1] + 1.0;
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            y: &[f64],
            _: &[f64],
            c: f64,
            m: &mut S,
        ) {
            m.set(0, 0, 1.0 + c);
            m.set(1, 1, 2.0 * y[1]);
        }
        fn is_differential(&self, i: usize) -> bool {
            i == 0
        }
    }
    let (mut y, mut yp) = ([1.0, 0.3], [0.0, 0.0]);
    let r = consistent_initial_values(
        &NoRoot,
        &mut NalgebraLu::<2>::new(),
        &Options::default(),
        0.0,
        &mut y,
        &mut yp,
    );
    match r {
        Err(
            e @ BdfError::InitialisationFailed {
                iterations,
                residual_norm,
            },
        ) => {
            assert!(iterations >= 1, "{e}");
            assert!(residual_norm >= 1.0, "{e}");
            assert!(e.to_string().contains("did not converge"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_wrong_iteration_matrix_is_named_as_a_possible_cause() {
    // Newton with `dF/dz` ten times too small overshoots `z` ninefold at every step size: the
    // failure says that the matrix does not describe the equations at any step.
    let err = run(3, NalgebraLu::<2>::new(), [1.0, 1.0]).expect_err("Newton cannot converge");
    println!("{err}");
    let BdfError::StalledNewton {
        t,
        rate,
        h_first,
        h_last,
        ref source,
    } = err
    else {
        panic!("expected a stalled iteration, got {err:?}");
    };
    assert!(t < 1e-6, "{t}");
    assert!(rate >= 0.5 && h_last * 1e3 <= h_first, "{err:?}");
    assert!(
        matches!(**source, BdfError::NewtonFailed { .. }),
        "{source:?}"
    );
    assert!(err
        .to_string()
        .contains("not the derivative of its residual"));
}

/// 38 coupled decays and two algebraic unknowns `a(t) z1 + z2 = 1 + (a - 1) / 2`,
/// `z1 + z2 = 1` with `a = 1 + max(0, 1 - t)`: regular until `t = 1`, then the two rows are
/// equal (no zero row or column: elimination cancels a pivot exactly). 40 unknowns with a
/// declared pattern of density 0.05, so `FaerLu::for_dae` takes the sparse LU.
struct CancellingRows;

const CANCEL_N: usize = 40;

impl CancellingRows {
    fn a(t: f64) -> f64 {
        1.0 + (1.0 - t).max(0.0)
    }
    fn coupled(i: usize) -> usize {
        (7 * i + 3) % (CANCEL_N - 2)
    }
}

impl ImplicitDae for CancellingRows {
    fn dimension(&self) -> usize {
        CANCEL_N
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let n = CANCEL_N;
        for i in 0..n - 2 {
            out[i] = yp[i] + y[i] - 0.01 * y[Self::coupled(i)];
        }
        let a = Self::a(t);
        out[n - 2] = a * y[n - 2] + y[n - 1] - 1.0 - 0.5 * (a - 1.0);
        out[n - 1] = y[n - 2] + y[n - 1] - 1.0;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let n = CANCEL_N;
        for i in 0..n - 2 {
            m.set(i, i, c + 1.0);
            m.add(i, Self::coupled(i), -0.01);
        }
        m.set(n - 2, n - 2, Self::a(t));
        m.set(n - 2, n - 1, 1.0);
        m.set(n - 1, n - 2, 1.0);
        m.set(n - 1, n - 1, 1.0);
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let n = CANCEL_N;
        let mut p: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        p.extend((0..n - 2).map(|i| (i, Self::coupled(i))));
        p.extend([(n - 2, n - 1), (n - 1, n - 2)]);
        Some(p)
    }
}

#[test]
fn a_pivot_cancelled_in_the_sparse_lu_is_named_as_in_the_dense_one() {
    use dpc_core::linear_solver::FaerLu;
    let n = CANCEL_N;
    let mut y0 = vec![1.0; n];
    y0[n - 2] = 0.5;
    y0[n - 1] = 0.5;
    let mut yp0 = vec![0.0; n];
    let mut r = vec![0.0; n];
    CancellingRows.residual(0.0, &y0, &yp0, &mut r);
    for i in 0..n - 2 {
        yp0[i] = -r[i];
    }
    fn run<L: dpc_core::linear_solver::LinearSolver>(ls: L, y0: &[f64], yp0: &[f64]) -> BdfError {
        let opts = Options::with_tolerances(1e-6, 1e-6);
        let mut s = Bdf::new(CancellingRows, ls, opts, 0.0, y0, yp0).unwrap();
        s.set_stop_time(2.0).unwrap();
        let mut y = vec![0.0; CANCEL_N];
        s.solve_to(2.0, &mut y, None).unwrap_err()
    }
    let ls = FaerLu::for_dae(&CancellingRows);
    assert!(ls.is_sparse());
    let sparse = run(ls, &y0, &yp0);
    let dense = run(FaerDenseLu::new(n), &y0, &yp0);
    for e in [&sparse, &dense] {
        match e {
            BdfError::SingularMatrix {
                t,
                unknown: Some(u),
                equation: None,
            } => {
                assert!(*t >= 1.0 && *t < 1.1, "{e}");
                assert!(u == "y[38]" || u == "y[39]", "{e}");
            }
            other => panic!("{other}"),
        }
    }
}
