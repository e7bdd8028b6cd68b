//! Work counters of the Radau integrator.

/// Counters of the work done by a [`super::Radau`] integrator since it was created.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Steps rejected by the local error test.
    pub error_test_failures: usize,
    /// Step attempts abandoned because Newton diverged, was predicted not to converge in time,
    /// met a singular matrix or a non-finite residual.
    pub newton_failures: usize,
    /// Simplified-Newton iterations (each one real and one complex solve).
    pub newton_iterations: usize,
    /// Residual evaluations (three per Newton iteration, one or two per error estimate; not
    /// those of `new`'s constraint check, for a DAE declared of index 2 or 3).
    pub residual_evaluations: usize,
    /// Jacobian evaluations (each gives `dF/dy` and `dF/dy'`: a call of `iteration_matrix`
    /// and one of `mass_matrix`, or two of `iteration_matrix` when the model supplies no
    /// `mass_matrix`; not those of `new`'s constraint check).
    pub jacobian_evaluations: usize,
    /// Factorisations of the stage matrices (each one real and one complex LU).
    pub factorisations: usize,
    /// Linear solves with the real matrix for the error estimate (one per step, a second one
    /// on the first step and after a rejection when the first estimate fails).
    pub error_estimate_solves: usize,
}
