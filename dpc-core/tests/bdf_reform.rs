//! The BDF's re-formed iteration matrices: a model that supplies `dF/dy'`
//! ([`ImplicitDae::mass_matrix`]) has its matrix re-formed at a new `cj` from the kept
//! `dF/dy'` instead of a model call, with the same accuracy; a model whose `dF/dy'` cannot be
//! kept (written outside its declared pattern) is integrated as one that supplies none.

use dpc_core::bdf::{Bdf, Options, Stats};
use dpc_core::linear_solver::{FaerSparseLu, LinearSolver, NalgebraLu};
use dpc_core::{ImplicitDae, MatrixSink};

const K: f64 = 200.0;

/// `m_i(y) (y_i' - s_i'(t)) + K (y_i - s_i(t)) + (y_0 - s_0)(y_1 - s_1) = 0` with
/// `m_0 = 1 + y_1^2`, `m_1 = 2 + sin y_0`: a stiff DAE with a state-dependent mass matrix
/// whose solution from `y(0) = s(0)` is `s(t) = (sin t, cos 2t)`.
#[derive(Clone, Copy)]
struct Attracted {
    /// How `mass_matrix` behaves.
    mass: Mass,
}

#[derive(Clone, Copy, PartialEq)]
enum Mass {
    /// Exact `dF/dy'`.
    Exact,
    /// Not supplied (the trait's default).
    None,
    /// Exact, plus a zero written at (0, 1), which the declared pattern leaves out.
    OutsidePattern,
}

fn s(t: f64) -> [f64; 2] {
    [t.sin(), (2.0 * t).cos()]
}

fn sp(t: f64) -> [f64; 2] {
    [t.cos(), -2.0 * (2.0 * t).sin()]
}

fn masses(y: &[f64]) -> [f64; 2] {
    [1.0 + y[1] * y[1], 2.0 + y[0].sin()]
}

impl ImplicitDae for Attracted {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (s, sp, m) = (s(t), sp(t), masses(y));
        let coupling = (y[0] - s[0]) * (y[1] - s[1]);
        for i in 0..2 {
            out[i] = m[i] * (yp[i] - sp[i]) + K * (y[i] - s[i]) + coupling;
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let (s, sp, m) = (s(t), sp(t), masses(y));
        let (d0, d1) = (y[0] - s[0], y[1] - s[1]);
        // d/dy of m_0 (y_0' - s_0'): 2 y_1 (y_0' - s_0') in column 1; of m_1 (y_1' - s_1'):
        // cos y_0 (y_1' - s_1') in column 0; the coupling adds d1 to column 0, d0 to 1.
        out.set(0, 0, c * m[0] + K + d1);
        out.set(0, 1, 2.0 * y[1] * (yp[0] - sp[0]) + d0);
        out.set(1, 0, y[0].cos() * (yp[1] - sp[1]) + d1);
        out.set(1, 1, c * m[1] + K + d0);
    }
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        out: &mut S,
    ) -> bool {
        let m = masses(y);
        match self.mass {
            Mass::None => false,
            Mass::Exact | Mass::OutsidePattern => {
                out.set(0, 0, m[0]);
                out.set(1, 1, m[1]);
                if self.mass == Mass::OutsidePattern {
                    out.set(0, 1, 0.0);
                }
                true
            }
        }
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        // Every entry; the variant that writes `dF/dy'` outside its pattern declares (0, 1)
        // missing (the dense solvers ignore a pattern, the kept `dF/dy'` does not).
        let mut p = vec![(0, 0), (1, 1), (1, 0)];
        if self.mass != Mass::OutsidePattern {
            p.push((0, 1));
        }
        Some(p)
    }
}

/// Integrate to `t = 10` at rtol = atol = 1e-6 with `ls`; the state and the statistics.
fn run<L: LinearSolver>(dae: Attracted, ls: L) -> ([f64; 2], Stats) {
    let opts = Options::with_tolerances(1e-6, 1e-6);
    let y0 = s(0.0);
    let yp0 = sp(0.0);
    let mut bdf = Bdf::new(dae, ls, opts, 0.0, &y0, &yp0).unwrap();
    let mut y = [0.0; 2];
    bdf.solve_to(10.0, &mut y, None).unwrap();
    (y, bdf.stats())
}

fn error(y: &[f64; 2]) -> f64 {
    let e = s(10.0);
    (y[0] - e[0]).abs().max((y[1] - e[1]).abs())
}

#[test]
fn a_supplied_mass_matrix_replaces_model_calls_by_re_formed_matrices() {
    let (y_kept, kept) = run(Attracted { mass: Mass::Exact }, NalgebraLu::<2>::new());
    let (y_plain, plain) = run(Attracted { mass: Mass::None }, NalgebraLu::<2>::new());
    println!("kept dF/dy': {kept:?}, error {:.2e}", error(&y_kept));
    println!("none:        {plain:?}, error {:.2e}", error(&y_plain));
    // Re-formed matrices are factorised without a model call ...
    assert!(kept.factorisations > kept.jacobian_evaluations, "{kept:?}");
    assert_eq!(
        plain.factorisations, plain.jacobian_evaluations,
        "{plain:?}"
    );
    // ... in place of matrices the model would have formed ...
    assert!(kept.jacobian_evaluations < plain.jacobian_evaluations);
    // ... and the solution is as accurate (both well within 100 tolerance units).
    assert!(error(&y_kept) < 1e-4 && error(&y_plain) < 1e-4);
    // The sparse solver re-forms in its own storage the same way.
    let dae = Attracted { mass: Mass::Exact };
    let sparse = FaerSparseLu::new(2, &dae.iteration_pattern().unwrap()).unwrap();
    let (y_sparse, sparse) = run(dae, sparse);
    assert!(
        sparse.factorisations > sparse.jacobian_evaluations,
        "{sparse:?}"
    );
    assert!(error(&y_sparse) < 1e-4);
}

#[test]
fn a_mass_matrix_written_outside_the_pattern_is_not_kept() {
    let (y_out, out) = run(
        Attracted {
            mass: Mass::OutsidePattern,
        },
        NalgebraLu::<2>::new(),
    );
    let (y_plain, plain) = run(Attracted { mass: Mass::None }, NalgebraLu::<2>::new());
    assert_eq!(out, plain);
    assert_eq!(y_out, y_plain);
}
