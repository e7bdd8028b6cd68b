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
    /// Residual evaluations.
    pub residual_evaluations: usize,
    /// Iteration-matrix (Jacobian) evaluations.
    pub jacobian_evaluations: usize,
    /// LU factorisations.
    pub factorisations: usize,
}
