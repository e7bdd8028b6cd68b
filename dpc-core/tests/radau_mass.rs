//! Radau takes `dF/dy'` from a model that supplies it ([`ImplicitDae::mass_matrix`]) instead
//! of a second call of `iteration_matrix`, with the same accuracy.

use std::cell::Cell;

use dpc_core::linear_solver::NalgebraLu;
use dpc_core::radau::{Options, Radau, Stats};
use dpc_core::{ImplicitDae, MatrixSink};

const K: f64 = 200.0;

/// `m_i(y) (y_i' - s_i'(t)) + K (y_i - s_i(t)) + (y_0 - s_0)(y_1 - s_1) = 0` with
/// `m_0 = 1 + y_1^2`, `m_1 = 2 + sin y_0`: a stiff DAE with a state-dependent mass matrix
/// whose solution from `y(0) = s(0)` is `s(t) = (sin t, cos 2t)`. Counts its calls of
/// `iteration_matrix`.
struct Attracted {
    /// Whether `mass_matrix` supplies `dF/dy'`.
    supplies_mass: bool,
    matrix_calls: Cell<usize>,
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
        self.matrix_calls.set(self.matrix_calls.get() + 1);
        let (s, sp, m) = (s(t), sp(t), masses(y));
        let (d0, d1) = (y[0] - s[0], y[1] - s[1]);
        // d/dy of m_0 (y_0' - s_0') is 2 y_1 (y_0' - s_0') in column 1, of m_1 (y_1' - s_1')
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
        if !self.supplies_mass {
            return false;
        }
        let m = masses(y);
        out.set(0, 0, m[0]);
        out.set(1, 1, m[1]);
        true
    }
}

/// Integrate to `t = 10` at rtol = atol = 1e-6: the error at the end, the statistics and the
/// calls of `iteration_matrix`.
fn run(supplies_mass: bool) -> (f64, Stats, usize) {
    let dae = Attracted {
        supplies_mass,
        matrix_calls: Cell::new(0),
    };
    let opts = Options::with_tolerances(1e-6, 1e-6);
    let mut radau = Radau::new(&dae, NalgebraLu::<2>::new(), opts, 0.0, &s(0.0), &sp(0.0)).unwrap();
    let mut y = [0.0; 2];
    radau.solve_to(10.0, &mut y, None).unwrap();
    let e = s(10.0);
    let error = (y[0] - e[0]).abs().max((y[1] - e[1]).abs());
    (error, radau.stats(), dae.matrix_calls.get())
}

#[test]
fn a_supplied_mass_matrix_saves_one_matrix_call_per_jacobian() {
    let (error_kept, kept, calls_kept) = run(true);
    let (error_plain, plain, calls_plain) = run(false);
    println!("mass supplied: {kept:?}, {calls_kept} calls, error {error_kept:.2e}");
    println!("not supplied:  {plain:?}, {calls_plain} calls, error {error_plain:.2e}");
    assert!(kept.jacobian_evaluations > 5, "{kept:?}");
    // One call of `iteration_matrix` per Jacobian with the mass matrix, two without.
    assert_eq!(calls_kept, kept.jacobian_evaluations);
    assert_eq!(calls_plain, 2 * plain.jacobian_evaluations);
    // The same solution up to rounding (`M` exact instead of a difference of two matrices),
    // within the global error a tolerance of 1e-6 gives over ten time units.
    assert!(error_plain < 1e-4, "{error_plain:e}");
    assert!(
        (error_kept - error_plain).abs() < 1e-3 * error_plain,
        "{error_kept:e} {error_plain:e}"
    );
}
