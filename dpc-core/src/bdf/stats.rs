//! Work counters.

/// Counters of the work done by an integrator since it was created.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Steps rejected by the local error test.
    pub error_test_failures: usize,
    /// Step attempts rejected because Newton did not converge (includes singular matrices and
    /// non-finite residuals).
    pub newton_failures: usize,
    /// Newton iterations (linear solves).
    pub newton_iterations: usize,
    /// Residual evaluations (not those of `new`'s constraint check, for a DAE declared of
    /// index 2 or 3).
    pub residual_evaluations: usize,
    /// Iteration-matrix (Jacobian) evaluations (not those of `new`'s constraint check).
    pub jacobian_evaluations: usize,
    /// LU factorisations.
    pub factorisations: usize,
}

impl Stats {
    /// Add the work of corrector solves: the Newton counters before and after them (each
    /// iteration matrix formed is factorised once).
    pub(crate) fn add_newton(
        &mut self,
        before: crate::newton::NewtonCounts,
        after: crate::newton::NewtonCounts,
    ) {
        let matrices = after.matrices - before.matrices;
        self.residual_evaluations += after.residuals - before.residuals;
        self.jacobian_evaluations += matrices;
        self.factorisations += matrices;
        self.newton_iterations += after.solves - before.solves;
    }
}
