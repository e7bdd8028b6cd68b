//! `0 = y^2 + 1`, which no real `y` satisfies: a DAE on which every Newton iteration fails
//! (shared by the integrators' error tests).

use dpc_core::{ImplicitDae, MatrixSink};

/// `0 = y^2 + 1`, one algebraic unknown; its equation is named "y squared plus one".
pub struct NoSolution;

impl ImplicitDae for NoSolution {
    fn dimension(&self) -> usize {
        1
    }
    fn residual(&self, _: f64, y: &[f64], _: &[f64], out: &mut [f64]) {
        out[0] = y[0] * y[0] + 1.0;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        _: f64,
        m: &mut S,
    ) {
        m.set(0, 0, 2.0 * y[0]);
    }
    fn is_differential(&self, _: usize) -> bool {
        false
    }
    fn equation_name(&self, _: usize) -> String {
        "y squared plus one".to_string()
    }
}
