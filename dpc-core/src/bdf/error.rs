//! The integrator's error type.

use crate::numeric::{IndexedUnknowns, Readable, Time};

/// Everything that can stop the BDF integrator. No model- or user-caused condition panics.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BdfError {
    /// A tolerance is negative, non-finite, or an error weight `1/(rtol |y_i| + atol_i)` is not
    /// positive and finite.
    #[error("invalid tolerance {which} of component {component}: {}", Readable(*value))]
    InvalidTolerance {
        /// `"rtol"`, `"atol"`, `"rtol and atol"` or `"error weight"`.
        which: &'static str,
        /// Component index.
        component: usize,
        /// The offending value (`rtol |y_i| + atol_i` for an error weight).
        value: f64,
    },
    /// A vector or solver has the wrong length.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// Which argument.
        what: &'static str,
        /// Length the DAE requires.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// An option or argument is out of range (order, step size, tolerance of Newton, ...).
    #[error("invalid option: {0}")]
    InvalidOption(#[from] crate::error::InvalidOption),
    /// `index` gives every unknown index 2 or 3 and `higher_index` is
    /// [`HigherIndexControl::Exclude`](super::HigherIndexControl::Exclude): no unknown would be
    /// in the error test, so nothing would bound the step and the result could be wrong without
    /// any sign of it.
    #[error(
        "every unknown has index 2 or 3 in `index` and `higher_index = Exclude` leaves none in \
         the error test, so nothing would bound the step: give the unknowns that appear \
         differentiated index 1, or use `HigherIndexControl::Scale`"
    )]
    NothingInErrorTest,
    /// A time argument lies outside where it can be served: an output time behind the
    /// integrator, an interpolation time outside the last step, a stop time not ahead.
    #[error("time {} is outside [{}, {}]", Time(*t), Time(*from), Time(*to))]
    TimeOutOfRange {
        /// The time asked for.
        t: f64,
        /// Start of the admissible interval.
        from: f64,
        /// End of the admissible interval (infinity when open).
        to: f64,
    },
    /// The model wrote an iteration-matrix entry outside the pattern it declared.
    #[error("iteration matrix entry ({equation}, {unknown}) lies outside the declared pattern")]
    OutsidePattern {
        /// Name of the row's equation.
        equation: String,
        /// Name of the column's unknown.
        unknown: String,
    },
    /// The iteration matrix is singular and reducing the step did not help.
    #[error(
        "singular iteration matrix at t = {}: {}; {}",
        Time(*t),
        unknown.as_deref().map_or("the vanishing pivot is not identified".to_string(), |u| format!("the pivot of unknown `{u}` vanished")),
        equation.as_deref().map_or("no equation's row is zero".to_string(), |e| format!("the row of equation `{e}` is zero"))
    )]
    SingularMatrix {
        /// Time of the failure.
        t: f64,
        /// Name of the unknown whose pivot vanished, when known.
        unknown: Option<String>,
        /// Name of an equation whose row is identically zero, when there is one.
        equation: Option<String>,
    },
    /// The model's iteration matrix has a NaN or infinite entry, and reducing the step (a
    /// matrix at another point) did not help: `dF/dy + c dF/dy'` cannot be formed there (for
    /// a difference-quotient matrix, a residual that is not finite at a perturbed point).
    #[error(
        "non-finite iteration-matrix entry at t = {}: the derivative of equation `{equation}` with respect to `{unknown}`",
        Time(*t)
    )]
    NonFiniteMatrix {
        /// Time of the failure.
        t: f64,
        /// Name of the entry's equation (its row).
        equation: String,
        /// Name of the entry's unknown (its column).
        unknown: String,
    },
    /// The model's residual returned NaN or an infinity.
    #[error("non-finite residual at t = {} in {equation}", Time(*t))]
    NonFiniteResidual {
        /// Time of the evaluation.
        t: f64,
        /// Name of the first offending equation.
        equation: String,
    },
    /// Newton's method failed repeatedly, down to the minimum step (variable-step mode) or at
    /// the given step (fixed-step mode).
    #[error("Newton iteration failed at t = {} with step {}", Time(*t), Time(*h))]
    NewtonFailed {
        /// Time the step tried to reach.
        t: f64,
        /// Step size of the last attempt.
        h: f64,
    },
    /// Newton's method failed ([`BdfError::NewtonFailed`]) while its convergence rate stayed
    /// at least 0.5 as the step was cut by a factor of 1 000 or more: the iteration matrix
    /// does not describe the equations near the point reached at any step size. For a smooth
    /// model with its exact iteration matrix the rate falls with the step. So either the
    /// residual's derivative jumps there (an equation that switches between expressions) or
    /// the model's iteration matrix is not the derivative of its residual. A point reached off
    /// a constraint is named instead ([`BdfError::OffConstraint`]).
    #[error(
        "{source}; Newton's convergence rate was still {rate:.2} after the step fell from {} \
         to {}: the iteration matrix does not describe the equations near t = {} at any step \
         size. Either the residual's derivative jumps there (an equation that switches \
         between expressions) or the model's iteration matrix is not the derivative of its \
         residual (compare it with `DifferenceQuotients`)",
        Time(*h_first),
        Time(*h_last),
        Time(*t)
    )]
    StalledNewton {
        /// Start of the step that failed.
        t: f64,
        /// Step size of the first failure that measured a rate.
        h_first: f64,
        /// Step size of the last one.
        h_last: f64,
        /// The last rate measured.
        rate: f64,
        /// The failure itself.
        #[source]
        source: Box<BdfError>,
    },
    /// Newton's method failed ([`BdfError::NewtonFailed`]) at every step down to a thousandth
    /// of the first that measured a rate, at a point that meets a constraint (an
    /// equation without derivatives and without algebraic unknowns, or a position constraint's
    /// hidden velocity constraint) only to at least a tenth of what the tolerances allow it
    /// (`sum_j |dh/dy_j| (rtol_j |y_j| + atol_j)`): a step was accepted that far off the
    /// constraint, and every later step must move the unknowns back onto it within the step,
    /// which fails the error test at every step size and, at the smallest, Newton's iteration
    /// (on Jay's index-2 problem, docs/integrators.md).
    #[error(
        "{source}; the point reached at t = {} meets {equation} only to {}, {:.2} of what \
         the tolerances allow it ({}): a step was accepted that far off it, and the unknowns \
         cannot move back onto it within a step (Newton failed at every step from {} down to \
         {})",
        Time(*t),
        Readable(*residual),
        residual.abs() / bound,
        Readable(*bound),
        Time(*h_first),
        Time(*h_last)
    )]
    OffConstraint {
        /// Start of the step that failed.
        t: f64,
        /// The constraint's name ([`crate::ImplicitDae::equation_name`]; "the hidden velocity
        /// constraint of ..." for the derivative of a position constraint).
        equation: String,
        /// Its residual at `t`.
        residual: f64,
        /// What moving every unknown by its tolerance can change it by.
        bound: f64,
        /// Step size of the first failure that measured a rate.
        h_first: f64,
        /// Step size of the last one.
        h_last: f64,
        /// The failure itself.
        #[source]
        source: Box<BdfError>,
    },
    /// Newton's method failed on the first step of a problem with index-3 unknowns whose error
    /// the BDF excludes from its test ([`super::HigherIndexControl::Exclude`], the default):
    /// the iteration matrix has condition `O(h^-3)` and Newton's test keeps those unknowns'
    /// plain weights, so every smaller step is worse. Integrate such a problem with
    /// [`crate::radau::Radau`], which solves index-3 DAEs as declared (the integrator the
    /// closed loop uses for constrained plants), or choose
    /// [`super::HigherIndexControl::Scale`].
    #[error(
        "the BDF cannot start this index-3 problem (unknown {unknown} has index 3): Newton failed \
         at t = {} with step {}; integrate it with dpc_core::radau::Radau, which solves index-3 \
         DAEs as declared, or set higher_index: HigherIndexControl::Scale",
        Time(*t),
        Time(*h)
    )]
    IndexThreeStart {
        /// Time the first step tried to reach.
        t: f64,
        /// Step size of the last attempt.
        h: f64,
        /// Name of the first unknown declared with index 3.
        unknown: String,
    },
    /// The local error test failed repeatedly, down to the minimum step.
    #[error("error test failed repeatedly at t = {} with step {}", Time(*t), Time(*h))]
    ErrorTestFailed {
        /// Time the step tried to reach.
        t: f64,
        /// Step size of the last attempt.
        h: f64,
    },
    /// More steps than [`super::Options::max_steps`] were needed to reach an output time.
    #[error("too many steps ({max_steps}) before reaching t = {}; stopped at t = {}", Time(*tout), Time(*t))]
    TooManySteps {
        /// The step limit.
        max_steps: usize,
        /// The requested output time.
        tout: f64,
        /// Where the integrator stopped.
        t: f64,
    },
    /// A step failed ([`BdfError::NewtonFailed`], [`BdfError::ErrorTestFailed`],
    /// [`BdfError::TooManySteps`]) on a DAE whose [`super::Options::index`] gives every
    /// unknown index at most 1 (the default), while its iteration matrix shows unknowns of
    /// index 2 or 3 at the last point reached and at the integration's start
    /// ([`crate::index_estimate::unknown_indices`]; those read so at both points are named):
    /// the likely cause, since the error test and Newton's test then hold those unknowns to a
    /// tolerance they cannot meet as `h` shrinks. Where only the last point reads them so,
    /// the error is [`BdfError::SingularPoint`]. Read for DAEs of at most 500 unknowns (the
    /// estimate decomposes dense `n x n` matrices); a larger DAE's failure is reported as it is.
    #[error(
        "{source}; at t = {} the DAE has unknowns of higher index than `Options::index` \
         declares (every unknown of index 1): {}; declare them in `index`, or integrate with \
         dpc_core::radau::Radau (with the same option) or in the stabilised form of \
         dpc_core::stabilised::Stabilised::detect",
        Time(*t),
        IndexedUnknowns(unknowns)
    )]
    UndeclaredIndex {
        /// Time of the last point reached, where the index was estimated.
        t: f64,
        /// The unknowns estimated of index 2 or 3 there, by name, with their index.
        unknowns: Vec<(String, u8)>,
        /// The failure itself.
        #[source]
        source: Box<BdfError>,
    },
    /// A step failed ([`BdfError::NewtonFailed`], [`BdfError::ErrorTestFailed`],
    /// [`BdfError::TooManySteps`]) on a DAE whose [`super::Options::index`] gives every
    /// unknown index at most 1, at a point where the iteration matrix reads some unknowns as of
    /// index 2 or 3 while at the integration's start it read every unknown as of index 1
    /// ([`crate::index_estimate::unknown_indices`] at both points): not a model of undeclared
    /// index ([`BdfError::UndeclaredIndex`]) but one whose algebraic part is nearly singular
    /// where it failed (a capacitance, mass or gain that nearly vanishes, an impasse point
    /// where the solution ends, branches of the model that meet), which reads like a higher
    /// index over the decades of `c` the estimate samples.
    #[error(
        "{source}; at t = {} the iteration matrix reads {} as of higher index, while at the \
         start (t = {}) every unknown read index 1: the DAE's algebraic part is nearly \
         singular there (a capacitance, mass or gain that nearly vanishes, or a point where \
         the solution cannot continue), which declaring an index does not remove; look at \
         the model near t = {}",
        Time(*t),
        IndexedUnknowns(unknowns),
        Time(*t_start),
        Time(*t)
    )]
    SingularPoint {
        /// Time of the last point reached, where the index was estimated.
        t: f64,
        /// Time of the integration's start (the last `new` or `reinit`), where every unknown
        /// read index 1.
        t_start: f64,
        /// The unknowns read of index 2 or 3 at `t`, by name, with that reading.
        unknowns: Vec<(String, u8)>,
        /// The failure itself.
        #[source]
        source: Box<BdfError>,
    },
    /// [`crate::bdf::Bdf::stabilised`]: the constraint structure of the DAE cannot be read at
    /// the start ([`crate::stabilised::Stabilised::detect`]'s error).
    #[error("the DAE's constraint structure cannot be read at the start: {0}")]
    Structure(#[from] crate::stabilised::StabilisedError),
    /// The integrator was given initial values, for a DAE declared with unknowns of index 2
    /// or 3, that miss a constraint by more than the tolerances allow: a constraint row
    /// (an equation without derivatives and without algebraic unknowns, which restricts the
    /// differential unknowns themselves) or the hidden velocity constraint of a position
    /// constraint (its derivative along the motion). Its residual exceeds what moving every
    /// unknown by its tolerance (`rtol |y| + atol`) can change it by: an integrator started
    /// there would jump onto the constraint within its first step and return the solution of
    /// other initial values, without an error. Checked by `new` only (not by `reinit`, the
    /// allocation-free restart), from the structure [`crate::stabilised::Stabilised::detect`]
    /// reads, for DAEs of any size (the structure is read from the entries the DAE writes,
    /// never from dense `n x n` matrices).
    #[error(
        "the initial values miss {equation}: its residual at t = {} is {}, more than moving \
         every unknown by its tolerance (rtol |y| + atol) can change ({}); an integrator \
         would jump onto the constraint in its first step. Start from values that satisfy \
         every constraint and, for a position constraint, its hidden velocity constraint",
        Time(*t),
        Readable(*residual),
        Readable(*bound)
    )]
    InconsistentConstraint {
        /// The start time.
        t: f64,
        /// The constraint's name ([`crate::ImplicitDae::equation_name`]; "the hidden velocity
        /// constraint of ..." for the derivative of a position constraint).
        equation: String,
        /// Its residual at the start.
        residual: f64,
        /// What moving every unknown by its tolerance can change it by: `sum_j |dh/dy_j|
        /// (rtol_j |y_j| + atol_j)` over the constraint's gradient `dh/dy` (at least 1 000
        /// times its round-off bound).
        bound: f64,
    },
    /// A step failed before the first step was taken ([`BdfError::NewtonFailed`],
    /// [`BdfError::ErrorTestFailed`], [`BdfError::TooManySteps`]) and the initial values
    /// do not satisfy an equation: its residual at the start exceeds its round-off bound by
    /// more than a factor of 1 000 (the equation named is the one with the largest such
    /// residual; the bound takes every unknown at the largest magnitude among them). An
    /// integrator cannot move a constrained unknown that cannot jump (a position under a
    /// constraint of index 3) onto its constraint within a step; the initial values must
    /// satisfy every equation, and a constraint of index 2 or 3 also its derivatives.
    #[error(
        "{source}; the initial values do not satisfy {equation}: its residual at t = {} is {} \
         (round-off would leave at most {}); start from values that satisfy every equation \
         (for a position constraint also its derivative, the velocity constraint)",
        Time(*t),
        Readable(*residual),
        Readable(*bound)
    )]
    InconsistentStart {
        /// The start time.
        t: f64,
        /// The equation's name ([`crate::ImplicitDae::equation_name`]).
        equation: String,
        /// Its residual at the start.
        residual: f64,
        /// Its round-off bound, `10 eps (sum_j |dF/dy_j| max_k |y_k| + sum_j |dF/dy'_j| max_k
        /// |y'_k|)`.
        bound: f64,
        /// The failure itself.
        #[source]
        source: Box<BdfError>,
    },
    /// A step failed before the first step was taken ([`BdfError::NewtonFailed`],
    /// [`BdfError::ErrorTestFailed`], [`BdfError::TooManySteps`]), and the
    /// initial values meet a constraint (an equation without derivatives and without
    /// algebraic unknowns, or a position constraint's hidden velocity constraint) only to a
    /// large share of what the tolerances allow it: at least a tenth of `sum_j |dh/dy_j|
    /// (rtol_j |y_j| + atol_j)`, the most moving every unknown by its tolerance can change it.
    /// The first step must put the unknowns on the constraint and spends that much of their
    /// tolerance doing so, at every step size. Named when no equation is off by more than
    /// round-off permits ([`BdfError::InconsistentStart`] first); checked for DAEs of any
    /// size, whatever index is declared.
    #[error(
        "{source}; the initial values meet {equation} only to {} at t = {}, {:.2} of what \
         the tolerances allow it ({}): the first step must also move the unknowns onto it. \
         Start from values consistent to well within the tolerances (or loosen them)",
        Readable(*residual),
        Time(*t),
        residual.abs() / bound,
        Readable(*bound)
    )]
    StartNearTolerance {
        /// The start time.
        t: f64,
        /// The constraint's name ([`crate::ImplicitDae::equation_name`]; "the hidden velocity
        /// constraint of ..." for the derivative of a position constraint).
        equation: String,
        /// Its residual at the start.
        residual: f64,
        /// What moving every unknown by its tolerance can change it by, `sum_j |dh/dy_j|
        /// (rtol_j |y_j| + atol_j)` (at least 1 000 times its round-off bound).
        bound: f64,
        /// The failure itself.
        #[source]
        source: Box<BdfError>,
    },
    /// Consistent initialisation's Newton iteration did not converge.
    #[error(
        "consistent initialisation failed: Newton did not converge ({iterations} iterations, residual 2-norm {})",
        Readable(*residual_norm)
    )]
    InitialisationFailed {
        /// Iterations taken.
        iterations: usize,
        /// The 2-norm of the residual at the last iterate.
        residual_norm: f64,
    },
}

impl BdfError {
    /// [`BdfError::DimensionMismatch`] for the first of `lengths` (`(what, found)`) that is
    /// not `expected`.
    pub(crate) fn check_lengths(
        expected: usize,
        lengths: &[(&'static str, usize)],
    ) -> Result<(), BdfError> {
        match lengths.iter().find(|(_, found)| *found != expected) {
            Some(&(what, found)) => Err(BdfError::DimensionMismatch {
                what,
                expected,
                found,
            }),
            None => Ok(()),
        }
    }
}
