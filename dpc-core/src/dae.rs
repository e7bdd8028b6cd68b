//! The implicit DAE interface consumed by the integrator.
//!
//! A system `F(t, y, y') = 0` with `n` unknowns and `n` equations, as in DASSL and IDA
//! (Brenan, Campbell & Petzold 1989, ch. 5). The closed loop wraps a generated model with
//! its held inputs in one (`simulate`); hand-written test problems implement it directly.

use crate::sink::{MatrixSink, Triplets};

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

    /// The mass matrix `dF/dy'` alone at `(t, y, y')`, when the DAE can supply it more cheaply
    /// than a second [`iteration_matrix`](Self::iteration_matrix): write its structurally
    /// non-zero entries into `out` (zeroed by the caller; [`MatrixSink::set`] or
    /// [`MatrixSink::add`], within [`iteration_pattern`](Self::iteration_pattern) when one is
    /// declared) and return `true`. The default supplies nothing and returns `false`.
    ///
    /// Radau, which keeps `dF/dy` and `dF/dy'` apart, takes `dF/dy'` from it instead of a
    /// second call of [`iteration_matrix`](Self::iteration_matrix) (half a Jacobian's cost
    /// when the matrix is formed by differences). It must be the `c`-part of
    /// [`iteration_matrix`](Self::iteration_matrix) exactly: `iteration_matrix` at `c` equals
    /// `iteration_matrix` at `0` plus `c` times this.
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        out: &mut S,
    ) -> bool {
        let _ = (t, y, yp, out);
        false
    }

    /// The gradients of the position constraints, `dF_g/dy` for each equation `g` that is a
    /// position constraint (an equation `0 = g(t, q)` of the unknowns alone, without `y'`), when
    /// the DAE supplies them exactly: index reduction ([`Stabilised`](crate::stabilised::Stabilised))
    /// then uses them instead of differences of [`iteration_matrix`](Self::iteration_matrix).
    ///
    /// Write `(g, j, dF_g/dy_j)` into `out` (an `n x n` destination zeroed by the caller, which
    /// keeps only the rows it stabilises) for every position-constraint row `g` and every
    /// unknown `j` the row depends on, and return `true`. The default supplies nothing and
    /// returns `false`.
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, t: f64, y: &[f64], out: &mut S) -> bool {
        let _ = (t, y, out);
        false
    }

    /// The explicit time derivatives `dF_g/dt` of the position constraints (a support that
    /// moves with time), when supplied exactly: write them into `out[g]` (`out` has length
    /// [`dimension`](Self::dimension) and is zeroed by the caller, which reads only the rows it
    /// stabilises) and return `true`. A DAE whose constraints do not depend on `t` writes
    /// nothing and returns `true`. The default returns `false` (the caller then differences
    /// the residual in `t`).
    fn constraint_time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) -> bool {
        let _ = (t, y, out);
        false
    }

    /// The curvature of the position constraints along the velocities `v`, when supplied
    /// exactly: the derivative in `y_k` of `sum_j dF_g/dy_j v_j + dF_g/dt` at fixed `v`,
    /// `sum_j d^2 F_g/(dy_j dy_k) v_j + d^2 F_g/(dt dy_k)`, written as `(g, k, value)` into `out`
    /// (`n x n`, zeroed by the caller) for every position-constraint row `g`; return `true`.
    /// `v` has length [`dimension`](Self::dimension) and is zero at every unknown that is not a
    /// position. This is the row of Newton's iteration matrix of the hidden velocity
    /// constraints `G(t, q) v + dg/dt = 0` in `q`. The default returns `false` (the caller then
    /// differences the constraint gradients along the motion).
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        v: &[f64],
        out: &mut S,
    ) -> bool {
        let _ = (t, y, v, out);
        false
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
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        out: &mut S,
    ) -> bool {
        (**self).mass_matrix(t, y, yp, out)
    }
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, t: f64, y: &[f64], out: &mut S) -> bool {
        (**self).constraint_gradient(t, y, out)
    }
    fn constraint_time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) -> bool {
        (**self).constraint_time_derivative(t, y, out)
    }
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        v: &[f64],
        out: &mut S,
    ) -> bool {
        (**self).constraint_curvature(t, y, v, out)
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

/// The iteration matrix `dF/dy + c dF/dy'` of `dae` at `(t, y, y')` as a dense matrix, or the
/// first entry `(row, column)` that is not finite: for set-up and analysis (structure
/// detection, index estimates, classification), never for a step.
pub(crate) fn dense_iteration_matrix<D: ImplicitDae + ?Sized>(
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
    c: f64,
) -> Result<nalgebra::DMatrix<f64>, (usize, usize)> {
    let n = dae.dimension();
    let mut m = nalgebra::DMatrix::zeros(n, n);
    dae.iteration_matrix(t, y, yp, c, &mut m);
    match m.iter().position(|v| !v.is_finite()) {
        // Column-major: entry k is row k % n, column k / n.
        Some(k) => Err((k % n, k / n)),
        None => Ok(m),
    }
}

/// Entries `(row, column, value)` of a matrix, sorted by row and column.
pub(crate) type Entries = Vec<(usize, usize, f64)>;

/// The iteration matrix `dF/dy + c dF/dy'` of `dae` at `(t, y, y')` as its written entries
/// `(row, column, value)`, sorted by row and column ([`Triplets::entries`]: the values a
/// zeroed dense matrix would hold), or the entry `(row, column)` that is not finite and comes
/// first in column-major order (the one [`dense_iteration_matrix`] names). For set-up and
/// analysis of DAEs of any size: its cost grows with the entries written, not with `n^2`.
pub(crate) fn sparse_iteration_matrix<D: ImplicitDae + ?Sized>(
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
    c: f64,
) -> Result<Entries, (usize, usize)> {
    let n = dae.dimension();
    let mut m = Triplets::new(n, n);
    dae.iteration_matrix(t, y, yp, c, &mut m);
    let entries = m.entries();
    match entries
        .iter()
        .filter(|e| !e.2.is_finite())
        .map(|&(i, j, _)| (j, i))
        .min()
    {
        Some((j, i)) => Err((i, j)),
        None => Ok(entries),
    }
}

/// Walk two sequences sorted by a key together: `f(key, a, b)` for every key in either, `a`
/// and `b` its values in each (zero where absent), keys ascending. `entry` splits an element
/// into its key and value.
pub(crate) fn merge_sorted<T, K: Ord + Copy>(
    a: impl IntoIterator<Item = T>,
    b: impl IntoIterator<Item = T>,
    entry: impl Fn(T) -> (K, f64),
    mut f: impl FnMut(K, f64, f64),
) {
    let mut a = a.into_iter().map(&entry).peekable();
    let mut b = b.into_iter().map(&entry).peekable();
    loop {
        match (a.peek().copied(), b.peek().copied()) {
            (Some((ka, va)), Some((kb, vb))) => {
                if ka == kb {
                    f(ka, va, vb);
                    a.next();
                    b.next();
                } else if ka < kb {
                    f(ka, va, 0.0);
                    a.next();
                } else {
                    f(kb, 0.0, vb);
                    b.next();
                }
            }
            (Some((ka, va)), None) => {
                f(ka, va, 0.0);
                a.next();
            }
            (None, Some((kb, vb))) => {
                f(kb, 0.0, vb);
                b.next();
            }
            (None, None) => break,
        }
    }
}
