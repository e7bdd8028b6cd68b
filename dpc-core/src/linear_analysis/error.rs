//! Errors of the linear DPC analysis. Every message says what was found (sizes, ranks,
//! tolerances), so a user can tell a modelling mistake from a numerical borderline case.

use thiserror::Error;

/// Why the linear DPC analysis could not be carried out.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LinearError {
    /// `A` is not square, or `B`, `C`, `D` do not fit `A` and each other.
    #[error("dimension mismatch: {what}")]
    DimensionMismatch {
        /// Which matrices disagree, with their shapes.
        what: String,
    },
    /// The number of outputs differs from the number of inputs.
    #[error("non-square system: {inputs} inputs but {outputs} outputs (DPC needs as many outputs as inputs)")]
    NonSquare {
        /// Columns of `B`.
        inputs: usize,
        /// Rows of `C`.
        outputs: usize,
    },
    /// A matrix entry is NaN or infinite.
    #[error("non-finite entry {value} in {matrix}[{row}][{col}]")]
    NonFinite {
        /// Name of the matrix.
        matrix: &'static str,
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
        /// The offending value.
        value: f64,
    },
    /// `[B; D]` does not have full column rank: some input combination acts on nothing.
    #[error("non-invertible system: rank [B; D] = {rank} < m = {m} (tolerance {tol:.3e}, singular values {singular_values:?})")]
    NotInvertible {
        /// Numerical rank found.
        rank: usize,
        /// Number of inputs.
        m: usize,
        /// Rank tolerance used.
        tol: f64,
        /// Singular values of `[B; D]`.
        singular_values: Vec<f64>,
    },
    /// The pencil `-Es + F` is singular: the system is not invertible.
    #[error("singular pencil -Es + F (system not invertible): finite part has dimension {finite_dim}, infinite part {infinite_dim}, n = {n}, smallest singular value of [V W] = {sigma_min:.3e} (tolerance {tol:.3e})")]
    SingularPencil {
        /// Dimension of the limit of the Wong sequence for the finite part.
        finite_dim: usize,
        /// Dimension of the limit of the Wong sequence for the infinite part.
        infinite_dim: usize,
        /// State dimension.
        n: usize,
        /// Smallest singular value of the candidate `Q = [V W]`.
        sigma_min: f64,
        /// Tolerance the decision used.
        tol: f64,
    },
    /// A stabilising polynomial `W_i(s)` is not usable.
    #[error("bad W for output {output}: {reason}")]
    BadW {
        /// Output index (0-based).
        output: usize,
        /// What is wrong.
        reason: String,
    },
    /// `(Abar_4, Bbar_2)` is not controllable, so no `K_2` can place all poles.
    #[error("uncontrollable (Abar_4, Bbar_2): controllable subspace has dimension {controllable_dim} of {dim} (rank tolerance {tol:.3e})")]
    Uncontrollable {
        /// Dimension of the controllable subspace found by the orthogonal staircase.
        controllable_dim: usize,
        /// Size of `Abar_4`.
        dim: usize,
        /// Rank tolerance used.
        tol: f64,
    },
    /// The requested closed-loop poles are unusable.
    #[error("bad poles: {reason}")]
    BadPoles {
        /// What is wrong.
        reason: String,
    },
    /// An argument is out of range (a non-positive sampling period, tolerance or count).
    #[error("invalid argument: {0}")]
    InvalidOption(#[from] crate::error::InvalidOption),
    /// An iterative decomposition (SVD, Schur) did not converge.
    #[error("{what} did not converge")]
    NoConvergence {
        /// Which decomposition.
        what: &'static str,
    },
    /// The analysis failed with roots of `W` so far beyond the plant's own scale that the
    /// partially stabilised system is singular or uncontrollable to working precision.
    #[error("W of output {output} (`w[{output}]`) has a root at -{root:.3e}, {ratio:.0e} times the plant's scale |A| = {scale:.4}: the partially stabilised system is numerically degenerate ({cause}); choose roots of W within a few decades of the plant's dynamics", ratio = root / scale)]
    WOutOfScale {
        /// The output whose `W` has the largest root.
        output: usize,
        /// That root's magnitude.
        root: f64,
        /// The plant's scale, the Frobenius norm of `A` (1 when `A` is zero).
        scale: f64,
        /// The failure it caused.
        cause: Box<LinearError>,
    },
}

impl LinearError {
    /// A failure of the numerics that the partial stabilisation `W` can cause (a singular
    /// pencil, an uncontrollable pair, a decomposition that did not converge), as opposed to a
    /// malformed system or option or a property of the plant alone.
    pub fn is_numerical(&self) -> bool {
        matches!(
            self,
            Self::SingularPencil { .. }
                | Self::Uncontrollable { .. }
                | Self::NoConvergence { .. }
                | Self::WOutOfScale { .. }
        )
    }
}
