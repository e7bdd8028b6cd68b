//! The implicit DAE interface consumed by the integrator.
//!
//! A system `F(t, y, y') = 0` with `n` unknowns and `n` equations, as in DASSL and IDA
//! (Brenan, Campbell & Petzold 1989, ch. 5). The closed loop wraps a generated model with
//! its held inputs in one (`simulate`); hand-written test problems implement it directly.

use crate::sink::MatrixSink;

/// An implicit differential-algebraic system `F(t, y, y') = 0`.
pub trait ImplicitDae {
    /// Number of unknowns, equal to the number of equations.
    fn dimension(&self) -> usize;

    /// Evaluate `F(t, y, y')` into `out` (length [`dimension`](Self::dimension)).
    ///
    /// Non-finite values are allowed here; the integrator checks for them and reports a typed
    /// error naming the offending equation.
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]);

    /// Write the iteration matrix `dF/dy + c * dF/dy'` into `out`.
    ///
    /// The caller zeroes `out` before the call; implementations write only structurally
    /// non-zero entries (with [`MatrixSink::set`] or [`MatrixSink::add`]).
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    );

    /// The residual into `residual` and the iteration matrix into `out` (zeroed by the
    /// caller, as for [`iteration_matrix`](Self::iteration_matrix)) in one pass, for a Newton
    /// iteration that needs both at the same point. The default calls the two routines.
    fn residual_and_iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: &mut [f64],
        out: &mut S,
    ) {
        self.residual(t, y, yp, residual);
        self.iteration_matrix(t, y, yp, c, out);
    }

    /// Whether component `i` is differential (`y_i'` appears in `F`) rather than algebraic.
    ///
    /// Used by consistent initialisation (which keeps differential components and solves for
    /// algebraic ones). The default says every component is differential.
    fn is_differential(&self, i: usize) -> bool {
        let _ = i;
        true
    }

    /// The structural pattern `(row, col)` of the iteration matrix, when known, so a sparse
    /// back end can be set up once. `None` means dense.
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        None
    }

    /// A name for equation `i`, used in error messages (for example the singular rows of an
    /// iteration matrix). Defaults to `"equation i"`.
    fn equation_name(&self, i: usize) -> String {
        format!("equation {i}")
    }

    /// A name for unknown `i`, used in error messages. Defaults to `"y[i]"`.
    fn unknown_name(&self, i: usize) -> String {
        format!("y[{i}]")
    }
}

/// A shared reference to a DAE is a DAE, so an integrator can borrow the model it integrates.
impl<T: ImplicitDae + ?Sized> ImplicitDae for &T {
    fn dimension(&self) -> usize {
        (**self).dimension()
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        (**self).residual(t, y, yp, out);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        (**self).iteration_matrix(t, y, yp, c, out);
    }
    fn residual_and_iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: &mut [f64],
        out: &mut S,
    ) {
        (**self).residual_and_iteration_matrix(t, y, yp, c, residual, out);
    }
    fn is_differential(&self, i: usize) -> bool {
        (**self).is_differential(i)
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        (**self).iteration_pattern()
    }
    fn equation_name(&self, i: usize) -> String {
        (**self).equation_name(i)
    }
    fn unknown_name(&self, i: usize) -> String {
        (**self).unknown_name(i)
    }
}
