//! A fixture with its Jacobian hidden, as a user who ported only `F(t, y, y')` writes it: the
//! iteration matrix by the library's difference quotients (`dpc_core::difference`) in one
//! line, no mass matrix, the fixture's pattern (so the columns are grouped when it declares
//! one). For `tests/difference_matrix.rs` and the work-precision rows.
#![allow(dead_code)]

use dpc_core::difference::DifferenceQuotients;
use dpc_core::{ImplicitDae, MatrixSink};

/// Forward differences with typical magnitude 1 for every unknown (the fixtures whose unknowns
/// are of order 1 or larger).
pub fn unit_scale() -> DifferenceQuotients {
    DifferenceQuotients::with_typical_magnitude(1.0).expect("a positive magnitude")
}

/// `dae` with its iteration matrix by `differences`.
pub struct Differenced<D> {
    /// The fixture (only its residual, pattern and names are used).
    pub dae: D,
    /// The difference quotients.
    pub differences: DifferenceQuotients,
}

impl<D: ImplicitDae> Differenced<D> {
    /// `dae` with `differences`.
    pub fn new(dae: D, differences: DifferenceQuotients) -> Self {
        Self { dae, differences }
    }
}

impl<D: ImplicitDae> ImplicitDae for Differenced<D> {
    fn dimension(&self) -> usize {
        self.dae.dimension()
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.dae.residual(t, y, yp, out);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        self.differences.iteration_matrix(self, t, y, yp, c, out);
    }
    fn is_differential(&self, i: usize) -> bool {
        self.dae.is_differential(i)
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        self.dae.iteration_pattern()
    }
    fn equation_name(&self, i: usize) -> String {
        self.dae.equation_name(i)
    }
    fn unknown_name(&self, i: usize) -> String {
        self.dae.unknown_name(i)
    }
}
