//! What the integrators add to a step failure of a DAE declared with every unknown of index 1:
//! the unknowns of undeclared higher index only where the iteration matrix shows them at the
//! failure and at the integration's start (a model of higher index throughout), and a
//! different, typed cause where only the failure point reads them so (a DAE that nearly loses
//! regularity there). The right diagnosis on higher-index models is also checked in
//! `literature_daes.rs` (`a_forgotten_index_option_is_named_in_the_error`).

use dpc_core::bdf::{self, Bdf, BdfError};
use dpc_core::linear_solver::NalgebraLu;
use dpc_core::radau::{self, Radau, RadauError};
use dpc_core::{ImplicitDae, MatrixSink};

/// A charge that cannot follow: `q' = 2 - u` (a source charging a node through a unit
/// conductance), `0 = q - (2u - u^2)` (the node's charge saturates at `q = 1`, `u = 1`, where
/// its capacitance `dq/du = 2 - 2u` vanishes). Index 1 wherever `u != 1`; from `u(0) = 0`,
/// `u' = (2 - u) / (2 - 2u)` grows without bound as `u -> 1`, reached at
/// `t* = 2 - 2 ln 2 = 0.6137`, where the source still charges (`q' = 1`) and no `u` gives a
/// larger charge: the solution ends there (an impasse point). Near it `G(c) = [[c, 1], [1,
/// -(2 - 2u)]]` has the inverse's `u` row growing like `c` up to `c ~ 1 / (2 - 2u)`, which the
/// index estimate reads as index 2 once `2 - 2u` is small enough.
struct SaturatingCharge;

impl ImplicitDae for SaturatingCharge {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] - 2.0 + y[1];
        out[1] = y[0] - (2.0 * y[1] - y[1] * y[1]);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, c);
        m.set(0, 1, 1.0);
        m.set(1, 0, 1.0);
        m.set(1, 1, -(2.0 - 2.0 * y[1]));
    }
    fn is_differential(&self, i: usize) -> bool {
        i == 0
    }
    fn unknown_name(&self, i: usize) -> String {
        ["q", "u"][i].to_string()
    }
}

/// The impasse point's time `2 - 2 ln 2`.
const T_IMPASSE: f64 = 0.613_705_638_880_109_4;

const START: ([f64; 2], [f64; 2]) = ([0.0, 0.0], [2.0, 1.0]);

#[test]
fn bdf_near_a_singular_point_is_not_told_of_an_undeclared_index() {
    let (y0, yp0) = START;
    // Where the last point reached is close enough to the impasse for the estimate to read
    // `u` as of index 2 (measured: the BDF at 1e-6 and 1e-8, Radau at 1e-4 and 1e-8; elsewhere
    // it reads index 1 and nothing is added).
    let mut read = 0;
    for tol in [1e-4, 1e-6, 1e-8] {
        let opts = bdf::Options::with_tolerances(tol, tol);
        let mut s = Bdf::new(
            SaturatingCharge,
            NalgebraLu::<2>::new(),
            opts,
            0.0,
            &y0,
            &yp0,
        )
        .unwrap();
        let mut y = [0.0; 2];
        let e = s
            .solve_to(1.0, &mut y, None)
            .expect_err("no solution past the impasse point");
        println!("BDF at {tol}: {e}");
        assert!(!matches!(e, BdfError::UndeclaredIndex { .. }), "{e}");
        let BdfError::SingularPoint { t, unknowns, .. } = &e else {
            continue;
        };
        read += 1;
        assert!((t - T_IMPASSE).abs() < 1e-3, "{e}");
        assert_eq!(unknowns, &[("u".to_string(), 2)]);
        assert!(e.to_string().contains("nearly singular"), "{e}");
    }
    assert!(read > 0, "no failure point read as of higher index");
}

#[test]
fn radau_near_a_singular_point_is_not_told_of_an_undeclared_index() {
    let (y0, yp0) = START;
    // Where the last point reached is close enough to the impasse for the estimate to read
    // `u` as of index 2 (measured: the BDF at 1e-6 and 1e-8, Radau at 1e-4 and 1e-8; elsewhere
    // it reads index 1 and nothing is added).
    let mut read = 0;
    for tol in [1e-4, 1e-6, 1e-8] {
        let opts = radau::Options::with_tolerances(tol, tol);
        let mut s = Radau::new(
            SaturatingCharge,
            NalgebraLu::<2>::new(),
            opts,
            0.0,
            &y0,
            &yp0,
        )
        .unwrap();
        let mut y = [0.0; 2];
        let e = s
            .solve_to(1.0, &mut y, None)
            .expect_err("no solution past the impasse point");
        println!("Radau at {tol}: {e}");
        assert!(!matches!(e, RadauError::UndeclaredIndex { .. }), "{e}");
        let RadauError::SingularPoint { t, unknowns, .. } = &e else {
            continue;
        };
        read += 1;
        assert!((t - T_IMPASSE).abs() < 1e-3, "{e}");
        assert_eq!(unknowns, &[("u".to_string(), 2)]);
        assert!(e.to_string().contains("nearly singular"), "{e}");
    }
    assert!(read > 0, "no failure point read as of higher index");
}
