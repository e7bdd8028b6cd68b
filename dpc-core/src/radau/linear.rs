//! The two linear systems of the transformed stage equations and their factorisations.
//!
//! The simplified Newton matrix of the Radau IIA stage system for `F(t, y, y') = 0` is
//! `I ⊗ J + (A^{-1}/h) ⊗ M` with `J = dF/dy` and `M = dF/dy'` frozen at the start of the step.
//! With `A^{-1} = T Λ T^{-1}` (see [`super::tableau`]) it decouples into
//!
//! * the real `n x n` matrix `E_1 = J + (gamma/h) M`, factorised by the caller's
//!   [`LinearSolver`] (fixed-size, dense, banded or sparse), and
//! * the complex `n x n` matrix `E_2 = J + ((alpha - i beta)/h) M`, which has `E_1`'s
//!   structure, factorised
//!   - within the band of the real solver when it is banded ([`LinearSolver::band`]);
//!   - by faer's sparse LU over `c64` in the real solver's pattern when it has one
//!     ([`LinearSolver::pattern`], [`crate::linear_solver::FaerSparseLu`]), the symbolic
//!     analysis done once at construction and shared by every numeric factorisation; like
//!     the real sparse LU, each numeric factorisation allocates (faer's high-level sparse
//!     API), so a step that refactorises is not allocation-free on this path;
//!   - otherwise by a dense complex partial-pivoting LU (faer) whose storage is allocated
//!     once.
//!
//! `J` is the model's `iteration_matrix(t, y, y', c) = J + c M` at `c = 0`; `M` its
//! [`ImplicitDae::mass_matrix`] when the model supplies one, else the same entry point at
//! `c = 1` less `J` (`M = (J + M) - J`). Both are kept, in the real solver's storage kind
//! (dense, its band, or its compressed-column pattern: memory in the number of non-zeros),
//! so that a change of `h` only refactorises, without evaluating the Jacobian again (as
//! RADAU5 does). The subtraction is exact where `J` has no entry; where both have one the
//! error is a round-off of `|J_ij|`, the size of the round-off of the matrix entry
//! `J_ij + c M_ij` itself.
//!
//! With a band or a pattern, a non-zero entry the model writes outside it is not stored but
//! remembered, and the next factorisation reports it ([`SetupFailure::OutsidePattern`], which
//! the integrator returns as [`super::RadauError::OutsidePattern`]) instead of dropping it.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{c64, Mat, MatMut, Par};

use super::band::ComplexBandLu;
use super::error::StageSystem;
use crate::linear_solver::faer_sparse::{
    first_column_without_pivot, first_empty_row, ReusedSparseLu, SparseLuFailure,
};
use crate::linear_solver::{
    BandMatrix, FactorError, LinearSolver, PatternMatrix, UNBLOCKED_MAX_DIMENSION,
};
use crate::sink::MatrixSink;
use crate::ImplicitDae;

/// Dense complex LU with partial pivoting, workspace allocated at construction: up to
/// [`UNBLOCKED_MAX_DIMENSION`] an unblocked elimination with the dimension a constant (as the
/// real [`crate::linear_solver::FaerDenseLu`] does; faer's blocked LU spent most of a small system's
/// solve in set-up), above it faer's blocked LU.
pub(crate) struct ComplexLu {
    matrix: Mat<c64>,
    factors: ComplexFactors,
    factored: bool,
}

/// The factors of [`ComplexLu`] and their work memory.
enum ComplexFactors {
    /// Column-major factors and LAPACK-style row interchanges.
    Unblocked { lu: Vec<c64>, pivots: Vec<usize> },
    /// faer's blocked LU (in place in the matrix).
    Blocked {
        perm: Vec<usize>,
        perm_inv: Vec<usize>,
        mem: MemBuffer,
    },
}

impl ComplexLu {
    pub fn new(n: usize) -> Self {
        let factors = if n <= UNBLOCKED_MAX_DIMENSION {
            ComplexFactors::Unblocked {
                lu: vec![c64::new(0.0, 0.0); n * n],
                pivots: vec![0; n],
            }
        } else {
            let par = Par::Seq;
            let req = factor::lu_in_place_scratch::<usize, c64>(n, n, par, Default::default())
                .or(solve::solve_in_place_scratch::<usize, c64>(n, 1, par));
            ComplexFactors::Blocked {
                perm: vec![0; n],
                perm_inv: vec![0; n],
                mem: MemBuffer::new(req),
            }
        };
        Self {
            matrix: Mat::zeros(n, n),
            factors,
            factored: false,
        }
    }

    /// Factorise the matrix; the first column whose pivot is zero or not finite is an error.
    /// The blocked LU works in place (the caller can rebuild the matrix from `J` and `M` to
    /// name a zero row).
    fn factor(&mut self) -> Result<(), Option<usize>> {
        let n = self.matrix.nrows();
        self.factored = false;
        let regular = |d: c64| d != c64::new(0.0, 0.0) && d.re.is_finite() && d.im.is_finite();
        let first_irregular = match &mut self.factors {
            ComplexFactors::Unblocked { lu, pivots } => {
                for j in 0..n {
                    lu[j * n..(j + 1) * n].copy_from_slice(self.matrix.col_as_slice(j));
                }
                complex_factor_dispatched(lu, n, pivots);
                (0..n).find(|&k| !regular(lu[k * n + k]))
            }
            ComplexFactors::Blocked {
                perm,
                perm_inv,
                mem,
            } => {
                factor::lu_in_place(
                    self.matrix.as_mut(),
                    perm,
                    perm_inv,
                    Par::Seq,
                    MemStack::new(mem),
                    Default::default(),
                );
                (0..n).find(|&k| !regular(self.matrix[(k, k)]))
            }
        };
        if let Some(k) = first_irregular {
            return Err(Some(k));
        }
        self.factored = true;
        Ok(())
    }

    fn solve_in_place(&mut self, b: &mut [c64]) {
        if !self.factored {
            return;
        }
        let n = b.len();
        match &mut self.factors {
            ComplexFactors::Unblocked { lu, pivots } => {
                complex_solve_dispatched(lu, n, pivots, b);
            }
            ComplexFactors::Blocked {
                perm,
                perm_inv,
                mem,
            } => {
                let perm = PermRef::new_checked(perm, perm_inv, n);
                let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
                solve::solve_in_place(
                    self.matrix.as_ref(),
                    self.matrix.as_ref(),
                    perm,
                    rhs,
                    Par::Seq,
                    MemStack::new(mem),
                );
            }
        }
    }
}

/// `|re| + |im|`, the pivot size of LAPACK's complex LU.
#[inline(always)]
fn abs1(v: c64) -> f64 {
    v.re.abs() + v.im.abs()
}

/// `P A = L U` in place for the column-major `n x n` complex `a` (as the real
/// [`crate::linear_solver::unblocked`] elimination), `pivots[k]` the row interchanged with row `k`. A
/// zero pivot is left in place (the caller checks the diagonal); elimination stops there.
#[inline(always)]
fn complex_factor(a: &mut [c64], n: usize, pivots: &mut [usize]) {
    let a = &mut a[..n * n];
    let pivots = &mut pivots[..n];
    for k in 0..n {
        let (left, right) = a.split_at_mut((k + 1) * n);
        let col_k = &mut left[k * n..];
        let mut pivot_row = k;
        let mut best = abs1(col_k[k]);
        for (i, v) in col_k.iter().enumerate().skip(k + 1) {
            if abs1(*v) > best {
                best = abs1(*v);
                pivot_row = i;
            }
        }
        pivots[k] = pivot_row;
        if !(best > 0.0 && best.is_finite()) {
            // Singular or overflowed: leave the rest (the diagonal check reports column k).
            pivots[k + 1..]
                .iter_mut()
                .enumerate()
                .for_each(|(i, p)| *p = k + 1 + i);
            return;
        }
        if pivot_row != k {
            for col in left.chunks_exact_mut(n).chain(right.chunks_exact_mut(n)) {
                col.swap(k, pivot_row);
            }
        }
        let (_, col_k) = left.split_at_mut(k * n);
        let d = col_k[k].finv();
        for v in &mut col_k[k + 1..] {
            *v *= d;
        }
        let multipliers = &col_k[k + 1..];
        for col in right.chunks_exact_mut(n) {
            let akj = col[k];
            if akj != c64::new(0.0, 0.0) {
                for (c, l) in col[k + 1..].iter_mut().zip(multipliers) {
                    *c -= l * akj;
                }
            }
        }
    }
}

/// [`complex_factor`] for `N` below 10 on an array of `N` columns, every step inlined with `k`
/// a literal so that all loop bounds are constants and the short loops unroll (as the real
/// `unblocked::factor_columns`): the same operations in the same order, so the same factors.
#[inline(always)]
fn complex_factor_columns<const N: usize>(a: &mut [[c64; N]; N], pivots: &mut [usize; N]) {
    macro_rules! steps {
        ($($k:literal)*) => {
            $(if $k < N && !complex_elimination_step::<N>(a, pivots, $k) {
                return;
            })*
        };
    }
    steps!(0 1 2 3 4 5 6 7 8);
    for k in 9..N {
        if !complex_elimination_step::<N>(a, pivots, k) {
            return;
        }
    }
}

/// Step `k` of [`complex_factor_columns`]; `false` at a zero or non-finite pivot (the rest
/// left, the pivots from `k + 1` on the identity, as [`complex_factor`]). Index loops on
/// purpose: with `k` a literal their bounds are constants.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn complex_elimination_step<const N: usize>(
    a: &mut [[c64; N]; N],
    pivots: &mut [usize; N],
    k: usize,
) -> bool {
    let mut pivot_row = k;
    let mut best = abs1(a[k][k]);
    for i in k + 1..N {
        if abs1(a[k][i]) > best {
            best = abs1(a[k][i]);
            pivot_row = i;
        }
    }
    pivots[k] = pivot_row;
    if !(best > 0.0 && best.is_finite()) {
        for i in k + 1..N {
            pivots[i] = i;
        }
        return false;
    }
    if pivot_row != k {
        for col in a.iter_mut() {
            col.swap(k, pivot_row);
        }
    }
    let (left, right) = a.split_at_mut(k + 1);
    let col_k = &mut left[k];
    let d = col_k[k].finv();
    for i in k + 1..N {
        col_k[i] *= d;
    }
    for col in right.iter_mut() {
        let akj = col[k];
        if akj != c64::new(0.0, 0.0) {
            for i in k + 1..N {
                col[i] -= col_k[i] * akj;
            }
        }
    }
    true
}

/// [`complex_factor_columns`] on the first `N * N` entries of a column-major slice.
#[inline(always)]
fn complex_factor_slice<const N: usize>(a: &mut [c64], pivots: &mut [usize]) {
    let (columns, _) = a[..N * N].as_chunks_mut::<N>();
    let columns: &mut [[c64; N]; N] = columns.try_into().expect("N columns of N entries");
    let pivots: &mut [usize; N] = (&mut pivots[..N]).try_into().expect("N pivots");
    complex_factor_columns(columns, pivots);
}

/// Overwrite `b` with the solution of `A x = b` from [`complex_factor`].
#[inline(always)]
fn complex_solve(lu: &[c64], n: usize, pivots: &[usize], b: &mut [c64]) {
    let lu = &lu[..n * n];
    let b = &mut b[..n];
    for (k, &p) in pivots[..n].iter().enumerate() {
        if p != k {
            b.swap(k, p);
        }
    }
    for j in 0..n {
        let col = &lu[j * n..j * n + n];
        let bj = b[j];
        for (bi, l) in b[j + 1..].iter_mut().zip(&col[j + 1..]) {
            *bi -= l * bj;
        }
    }
    for j in (0..n).rev() {
        let col = &lu[j * n..j * n + n];
        b[j] /= col[j];
        let bj = b[j];
        for (bi, u) in b[..j].iter_mut().zip(&col[..j]) {
            *bi -= u * bj;
        }
    }
}

/// [`complex_factor`] with `n` a constant for each size up to [`UNBLOCKED_MAX_DIMENSION`].
fn complex_factor_dispatched(a: &mut [c64], n: usize, pivots: &mut [usize]) {
    macro_rules! sizes {
        ($($c:literal)*; $($k:literal)*) => {
            match n {
                $($c => complex_factor_slice::<$c>(a, pivots),)*
                $($k => complex_factor(a, $k, pivots),)*
                _ => complex_factor(a, n, pivots),
            }
        };
    }
    // Below 10 the unrolled steps, as the real elimination.
    sizes!(1 2 3 4 5 6 7 8 9; 10 11 12 13 14 15 16)
}

/// [`complex_solve`] with `n` a constant, as [`complex_factor_dispatched`].
fn complex_solve_dispatched(lu: &[c64], n: usize, pivots: &[usize], b: &mut [c64]) {
    macro_rules! sizes {
        ($($k:literal)*) => {
            match n {
                $($k => complex_solve(lu, $k, pivots, b),)*
                _ => complex_solve(lu, n, pivots, b),
            }
        };
    }
    sizes!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// Sparse complex LU (faer's, over `c64`) in the real solver's compressed-column pattern
/// ([`LinearSolver::pattern`]): the symbolic analysis once at construction, shared by every
/// numeric factorisation (as [`crate::linear_solver::FaerSparseLu`] does for `f64`). Like that
/// one, each numeric factorisation allocates its factors and scratch memory (faer's
/// high-level sparse API).
pub(crate) struct ComplexSparseLu {
    lu: ReusedSparseLu<c64>,
    /// The matrix's values in pattern order.
    values: Vec<c64>,
}

impl ComplexSparseLu {
    /// For `n x n` matrices with entries at `(col_ptr, row_idx)`; `None` when the pattern is
    /// not a well-formed compressed-column one (rows ascending within a column, in range) or
    /// faer's symbolic analysis rejects it.
    fn new(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Option<Self> {
        let well_formed = col_ptr.len() == n + 1
            && col_ptr[0] == 0
            && col_ptr.windows(2).all(|w| w[0] <= w[1])
            && col_ptr[n] == row_idx.len()
            && (0..n).all(|j| {
                let rows = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                rows.windows(2).all(|w| w[0] < w[1]) && rows.iter().all(|&i| i < n)
            });
        if !well_formed {
            return None;
        }
        Some(Self {
            lu: ReusedSparseLu::new(n, col_ptr.to_vec(), row_idx.to_vec())?,
            values: vec![c64::new(0.0, 0.0); row_idx.len()],
        })
    }

    /// Factorise the values; an error names a column without a usable pivot when one is
    /// known (a column entirely zero, one holding a non-finite entry, or one whose pivot
    /// vanished, structurally or numerically: `ReusedSparseLu`'s test).
    fn factor(&mut self) -> Result<(), Option<usize>> {
        let irregular = |v: &c64| !(v.re.is_finite() && v.im.is_finite());
        if let Some(col) = first_column_without_pivot(self.lu.col_ptr(), &self.values, |column| {
            column.iter().all(|v| *v == c64::new(0.0, 0.0)) || column.iter().any(irregular)
        }) {
            self.lu.discard();
            return Err(Some(col));
        }
        match self.lu.factor(&self.values) {
            Ok(()) => Ok(()),
            Err(SparseLuFailure::ZeroPivot(column)) => Err(Some(column)),
            Err(SparseLuFailure::OutOfMemory) => Err(None),
        }
    }

    fn solve_in_place(&mut self, b: &mut [c64]) {
        self.lu.solve_in_place(b);
    }
}

/// A non-finite entry of `J` or `M` as the model gave them: a matrix the step's start point
/// fixes, which no smaller step changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NonFiniteEntry {
    /// Row (equation).
    pub row: usize,
    /// Column (unknown).
    pub col: usize,
}

/// Why the stage matrices could not be formed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum SetupFailure {
    /// A singular system: which one, pivot column, zero row.
    Singular(StageSystem, Option<usize>, Option<usize>),
    /// A non-finite entry of the real stage matrix (row, column) from finite `J` and `M`
    /// (an overflow of `gamma/h M`).
    NonFinite(usize, usize),
    /// An entry outside the declared pattern (row, column): not recoverable.
    OutsidePattern(usize, usize),
}

/// The complex stage system's LU: dense, banded when the real solver is
/// ([`LinearSolver::band`]), sparse in its pattern when it has one ([`LinearSolver::pattern`]).
enum ComplexSolver {
    Dense(ComplexLu),
    Band(ComplexBandLu),
    Sparse(Box<ComplexSparseLu>),
}

/// `J` or `M`: dense, in the real solver's band when it has one (an entry outside the band
/// is remembered, see [`BandMatrix`]), or in its sparsity pattern when it has one (an entry
/// outside the pattern is remembered, see [`PatternMatrix`]).
enum Jacobian {
    Dense(Mat<f64>),
    Band(BandMatrix),
    Sparse(PatternMatrix),
}

/// The rows of a column of a [`Jacobian`]: consecutive from a first one (dense, band) or
/// listed (sparse).
#[derive(Clone, Copy)]
enum Rows<'a> {
    From(usize),
    List(&'a [usize]),
}

impl Rows<'_> {
    /// The row of the column's `k`-th stored value.
    #[inline(always)]
    fn row(self, k: usize) -> usize {
        match self {
            Self::From(first) => first + k,
            Self::List(rows) => rows[k],
        }
    }
}

impl Jacobian {
    fn new(n: usize, band: Option<(usize, usize)>, pattern: Option<(&[usize], &[usize])>) -> Self {
        match (band, pattern) {
            (Some((kl, ku)), _) => Self::Band(BandMatrix::new(n, kl, ku)),
            (None, Some((col_ptr, row_idx))) => {
                Self::Sparse(PatternMatrix::with_pattern(n, col_ptr, row_idx))
            }
            (None, None) => Self::Dense(Mat::zeros(n, n)),
        }
    }

    /// The rows of column `j` that can hold an entry, and their values (dense: the whole
    /// column; band: from the band's first row to its last; sparse: the pattern's rows).
    #[inline]
    fn column(&self, j: usize) -> (Rows<'_>, &[f64]) {
        match self {
            Self::Dense(m) => (Rows::From(0), m.col_as_slice(j)),
            Self::Band(b) => {
                let (first, column) = b.column(j);
                (Rows::From(first), column)
            }
            Self::Sparse(p) => {
                let (rows, column) = p.column(j);
                (Rows::List(rows), column)
            }
        }
    }

    /// The entry `(i, j)` (zero outside the band or pattern).
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        match self {
            Self::Dense(m) => m[(i, j)],
            Self::Band(b) => b.get(i, j),
            Self::Sparse(p) => p.get(i, j),
        }
    }

    /// `self -= other` (the same storage).
    fn subtract(&mut self, other: &Self) {
        match (self, other) {
            (Self::Dense(a), Self::Dense(b)) => {
                let n = a.nrows();
                for j in 0..n {
                    for i in 0..n {
                        a[(i, j)] -= b[(i, j)];
                    }
                }
            }
            (Self::Band(a), Self::Band(b)) => a.subtract(b),
            (Self::Sparse(a), Self::Sparse(b)) => a.subtract(b),
            // Not built so (J and M share their storage kind), but well defined.
            (a, b) => {
                let n = a.rows();
                for j in 0..n {
                    for i in 0..n {
                        let v = a.get(i, j) - b.get(i, j);
                        a.set(i, j, v);
                    }
                }
            }
        }
    }

    /// A non-zero entry written outside the band or pattern.
    fn outside(&self) -> Option<(usize, usize)> {
        match self {
            Self::Dense(_) => None,
            Self::Band(b) => b.outside(),
            Self::Sparse(p) => p.outside(),
        }
    }
}

impl MatrixSink for Jacobian {
    fn rows(&self) -> usize {
        match self {
            Self::Dense(m) => m.nrows(),
            Self::Band(b) => b.rows(),
            Self::Sparse(p) => p.rows(),
        }
    }
    fn cols(&self) -> usize {
        self.rows()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        match self {
            Self::Dense(m) => m.set(row, col, value),
            Self::Band(b) => b.set(row, col, value),
            Self::Sparse(p) => p.set(row, col, value),
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        match self {
            Self::Dense(m) => m.add(row, col, value),
            Self::Band(b) => b.add(row, col, value),
            Self::Sparse(p) => p.add(row, col, value),
        }
    }
    fn fill_zero(&mut self) {
        match self {
            Self::Dense(m) => m.fill_zero(),
            Self::Band(b) => b.fill_zero(),
            Self::Sparse(p) => p.fill_zero(),
        }
    }
}

/// `J`, `M` and the factorised stage matrices.
pub(crate) struct StageMatrices<L: LinearSolver> {
    ls: L,
    jy: Jacobian,
    jyp: Jacobian,
    complex: ComplexSolver,
    /// With a banded or sparse solver: the first entry of `J` or `M` outside its band or
    /// pattern, at the last evaluation.
    outside_pattern: Option<(usize, usize)>,
    /// A Jacobian has been evaluated (at some earlier step start, possibly stale).
    pub have_jacobian: bool,
    /// The Jacobian was evaluated at the start of the current step.
    pub current: bool,
    /// Both matrices are factorised for step [`h_factored`](Self::h_factored).
    pub factored: bool,
    /// The step size of the factorisations.
    pub h_factored: f64,
}

impl<L: LinearSolver> StageMatrices<L> {
    pub fn new(ls: L, n: usize) -> Self {
        let band = ls.band();
        // The sparse complex LU in the real solver's pattern; dense storage should faer's
        // symbolic analysis reject the pattern (it accepted it for the real system).
        let sparse = match (band, ls.pattern()) {
            (None, Some((col_ptr, row_idx))) => {
                ComplexSparseLu::new(n, col_ptr, row_idx).map(|lu| (lu, (col_ptr, row_idx)))
            }
            _ => None,
        };
        let pattern = sparse.as_ref().map(|(_, p)| *p);
        let (jy, jyp) = (
            Jacobian::new(n, band, pattern),
            Jacobian::new(n, band, pattern),
        );
        let complex = match (band, sparse) {
            (Some((kl, ku)), _) => ComplexSolver::Band(ComplexBandLu::new(n, kl, ku)),
            (None, Some((lu, _))) => ComplexSolver::Sparse(Box::new(lu)),
            (None, None) => ComplexSolver::Dense(ComplexLu::new(n)),
        };
        Self {
            ls,
            jy,
            jyp,
            complex,
            outside_pattern: None,
            have_jacobian: false,
            current: false,
            factored: false,
            h_factored: 0.0,
        }
    }

    /// Evaluate `J = dF/dy` and `M = dF/dy'` at `(t, y, yp)`: `M` from the model's
    /// [`ImplicitDae::mass_matrix`] when it supplies one, else as the difference of the
    /// iteration matrices at `c = 1` and `c = 0`.
    pub fn evaluate<D: ImplicitDae>(
        &mut self,
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<(), NonFiniteEntry> {
        self.jy.fill_zero();
        dae.iteration_matrix(t, y, yp, 0.0, &mut self.jy);
        self.jyp.fill_zero();
        if !dae.mass_matrix(t, y, yp, &mut self.jyp) {
            self.jyp.fill_zero();
            dae.iteration_matrix(t, y, yp, 1.0, &mut self.jyp);
            self.jyp.subtract(&self.jy);
        }
        self.outside_pattern = self.jy.outside().or(self.jyp.outside());
        self.have_jacobian = true;
        self.current = true;
        self.factored = false;
        for j in 0..self.jy.cols() {
            let ((rows, jy), (_, jyp)) = (self.jy.column(j), self.jyp.column(j));
            if let Some(k) = jy
                .iter()
                .zip(jyp)
                .position(|(a, b)| !(a.is_finite() && b.is_finite()))
            {
                return Err(NonFiniteEntry {
                    row: rows.row(k),
                    col: j,
                });
            }
        }
        Ok(())
    }

    /// Form and factorise `E_1 = J + (gamma/h) M` and `E_2 = J + ((alpha - i beta)/h) M`.
    pub fn factor(
        &mut self,
        h: f64,
        gamma: f64,
        alpha: f64,
        beta: f64,
    ) -> Result<(), SetupFailure> {
        self.factored = false;
        let n = self.jy.rows();
        let (cr, ca, cb) = (gamma / h, alpha / h, -beta / h);
        // Rows of column j that can hold entries: the band's or the pattern's, when the
        // solver has one (an entry outside it was found when J and M were evaluated).
        if let Some((row, col)) = self.outside_pattern {
            return Err(SetupFailure::OutsidePattern(row, col));
        }
        let m = self.ls.matrix_mut();
        m.fill_zero();
        for j in 0..n {
            let ((rows, jy), (_, jyp)) = (self.jy.column(j), self.jyp.column(j));
            for (k, (&a, &b)) in jy.iter().zip(jyp).enumerate() {
                if a != 0.0 || b != 0.0 {
                    m.set(rows.row(k), j, a + cr * b);
                }
            }
        }
        match self.ls.factor() {
            Ok(()) => {}
            Err(FactorError::Singular { column, row }) => {
                return Err(SetupFailure::Singular(StageSystem::Real, column, row));
            }
            Err(FactorError::NonFinite { row, col }) => {
                return Err(SetupFailure::NonFinite(row, col));
            }
            Err(FactorError::OutsidePattern { row, col }) => {
                return Err(SetupFailure::OutsidePattern(row, col));
            }
        }
        let factored = match &mut self.complex {
            ComplexSolver::Dense(complex) => {
                for j in 0..n {
                    let ((_, jy), (_, jyp)) = (self.jy.column(j), self.jyp.column(j));
                    let column = complex.matrix.col_as_slice_mut(j);
                    for ((e, &a), &b) in column.iter_mut().zip(jy).zip(jyp) {
                        *e = c64::new(a + ca * b, cb * b);
                    }
                }
                complex.factor()
            }
            ComplexSolver::Band(complex) => {
                // The real system's band holds every entry of J and M (the real factorisation
                // above reported any outside it).
                complex.clear();
                for j in 0..n {
                    let ((rows, jy), (_, jyp)) = (self.jy.column(j), self.jyp.column(j));
                    for (k, (&a, &b)) in jy.iter().zip(jyp).enumerate() {
                        if a != 0.0 || b != 0.0 {
                            complex.set(rows.row(k), j, c64::new(a + ca * b, cb * b));
                        }
                    }
                }
                complex.factor().map_err(Some)
            }
            ComplexSolver::Sparse(complex) => match (&self.jy, &self.jyp) {
                // J, M and the complex matrix share the pattern: value by value.
                (Jacobian::Sparse(jy), Jacobian::Sparse(jyp)) => {
                    for ((e, &a), &b) in
                        complex.values.iter_mut().zip(jy.values()).zip(jyp.values())
                    {
                        *e = c64::new(a + ca * b, cb * b);
                    }
                    complex.factor()
                }
                // Not built so (the sparse complex LU comes with sparse J and M).
                _ => Err(None),
            },
        };
        if let Err(col) = factored {
            let row = match (&self.jy, &self.jyp) {
                (Jacobian::Sparse(jy), Jacobian::Sparse(jyp)) => {
                    // Over the pattern only (J and M share it, value by value).
                    let (a, b) = (jy.values(), jyp.values());
                    first_empty_row(&mut vec![false; n], jy.row_indices(), |k| {
                        (a[k] + ca * b[k]).abs() + (cb * b[k]).abs() != 0.0
                    })
                }
                (jy, jyp) => crate::linear_solver::zero_row(n, |i, j| {
                    (jy.get(i, j) + ca * jyp.get(i, j)).abs() + (cb * jyp.get(i, j)).abs()
                }),
            };
            return Err(SetupFailure::Singular(StageSystem::Complex, col, row));
        }
        self.factored = true;
        self.h_factored = h;
        Ok(())
    }

    /// Solve `E_1 x = b` in place.
    pub fn solve_real(&mut self, b: &mut [f64]) {
        self.ls.solve_in_place(b);
    }

    /// Solve `E_2 x = b` in place.
    pub fn solve_complex(&mut self, b: &mut [c64]) {
        match &mut self.complex {
            ComplexSolver::Dense(complex) => complex.solve_in_place(b),
            ComplexSolver::Band(complex) => complex.solve_in_place(b),
            ComplexSolver::Sparse(complex) => complex.solve_in_place(b),
        }
    }

    /// `out = 10 eps (|J| |y| + |M| |y'|)`, a bound of the round-off of `F(t, y, y')` (ten
    /// roundings of every term `J_ij y_j`, `M_ij y'_j`, the allowance of RADAU5's lower bound
    /// `10 eps / rtol` on Newton's tolerance), with the stored (possibly older) Jacobians.
    pub fn residual_roundoff(&self, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let n = out.len();
        match (&self.jy, &self.jyp) {
            (Jacobian::Dense(jy), Jacobian::Dense(jyp)) => {
                for (i, o) in out.iter_mut().enumerate() {
                    let mut s = 0.0;
                    for j in 0..n {
                        s += jy[(i, j)].abs() * y[j].abs() + jyp[(i, j)].abs() * yp[j].abs();
                    }
                    *o = 10.0 * f64::EPSILON * s;
                }
            }
            (Jacobian::Band(jy), Jacobian::Band(jyp)) => {
                // Column by column within the band.
                out.fill(0.0);
                for j in 0..n {
                    let ((first, cy), (_, cyp)) = (jy.column(j), jyp.column(j));
                    let (yj, ypj) = (y[j].abs(), yp[j].abs());
                    for ((o, a), b) in out[first..].iter_mut().zip(cy).zip(cyp) {
                        *o += a.abs() * yj + b.abs() * ypj;
                    }
                }
                for o in out.iter_mut() {
                    *o *= 10.0 * f64::EPSILON;
                }
            }
            (Jacobian::Sparse(jy), Jacobian::Sparse(jyp)) => {
                // Column by column over the pattern.
                out.fill(0.0);
                for j in 0..n {
                    let ((rows, cy), (_, cyp)) = (jy.column(j), jyp.column(j));
                    let (yj, ypj) = (y[j].abs(), yp[j].abs());
                    for ((&i, a), b) in rows.iter().zip(cy).zip(cyp) {
                        out[i] += a.abs() * yj + b.abs() * ypj;
                    }
                }
                for o in out.iter_mut() {
                    *o *= 10.0 * f64::EPSILON;
                }
            }
            // Not built so (J and M share their storage kind), but well defined.
            (jy, jyp) => {
                for (i, o) in out.iter_mut().enumerate() {
                    let s: f64 = (0..n)
                        .map(|j| {
                            jy.get(i, j).abs() * y[j].abs() + jyp.get(i, j).abs() * yp[j].abs()
                        })
                        .sum();
                    *o = 10.0 * f64::EPSILON * s;
                }
            }
        }
    }

    /// `out = M v` with the stored `M = dF/dy'`.
    #[cfg(test)]
    pub fn apply_mass(&self, v: &[f64], out: &mut [f64]) {
        let n = v.len();
        for (i, o) in out.iter_mut().enumerate() {
            *o = (0..n).map(|j| self.jyp.get(i, j) * v[j]).sum();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear_solver::NalgebraLu;

    /// `complex_factor_slice::<N>` against `complex_factor` on a random `N x N` complex matrix
    /// (interchanges included) and on the same with its first column zero (a zero pivot at
    /// the first step: both stop there, the pivots after it the identity): the same factors
    /// and pivots, bit for bit.
    fn unrolled_equals_generic<const N: usize>() {
        let mut state = 7 + N as u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let a: Vec<c64> = (0..N * N).map(|_| c64::new(next(), next())).collect();
        let mut zero_column = a.clone();
        zero_column[..N].fill(c64::new(0.0, 0.0));
        for a in [a, zero_column] {
            let (mut want, mut got) = (a.clone(), a.clone());
            let (mut want_pivots, mut got_pivots) = ([usize::MAX; N], [usize::MAX; N]);
            complex_factor(&mut want, N, &mut want_pivots);
            complex_factor_slice::<N>(&mut got, &mut got_pivots);
            assert_eq!(got_pivots, want_pivots, "N = {N}");
            for (g, w) in got.iter().zip(&want) {
                assert!(
                    g.re.to_bits() == w.re.to_bits() && g.im.to_bits() == w.im.to_bits(),
                    "N = {N}"
                );
            }
        }
    }

    #[test]
    fn the_unrolled_complex_factorisation_equals_the_generic_one() {
        unrolled_equals_generic::<1>();
        unrolled_equals_generic::<2>();
        unrolled_equals_generic::<3>();
        unrolled_equals_generic::<4>();
        unrolled_equals_generic::<5>();
        unrolled_equals_generic::<6>();
        unrolled_equals_generic::<7>();
        unrolled_equals_generic::<8>();
        unrolled_equals_generic::<9>();
        unrolled_equals_generic::<11>();
    }

    /// `F = M y' - K y` with a singular `M`, so `dF/dy' = M`, `dF/dy = -K`.
    struct Linear;
    const M: [[f64; 3]; 3] = [[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]];
    const K: [[f64; 3]; 3] = [[-1.0, 0.5, 0.0], [0.2, -3.0, 1.0], [1.0, 0.0, -1.0]];
    impl ImplicitDae for Linear {
        fn dimension(&self) -> usize {
            3
        }
        fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            for i in 0..3 {
                out[i] = (0..3).map(|j| M[i][j] * yp[j] - K[i][j] * y[j]).sum();
            }
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            _: &[f64],
            _: &[f64],
            c: f64,
            m: &mut S,
        ) {
            for i in 0..3 {
                for j in 0..3 {
                    m.add(i, j, c * M[i][j] - K[i][j]);
                }
            }
        }
    }

    #[test]
    fn both_systems_solve_what_they_should() {
        systems_solve_what_they_should(NalgebraLu::<3>::new());
        // The banded LU holding the whole matrix: the complex system banded too.
        systems_solve_what_they_should(crate::linear_solver::BandLu::new(3, 2, 2));
    }

    /// A banded real solver whose band misses an entry of `J`: the setup reports it.
    #[test]
    fn an_entry_outside_the_band_is_reported() {
        let mut sm = StageMatrices::new(crate::linear_solver::BandLu::new(3, 1, 1), 3);
        sm.evaluate(&Linear, 0.0, &[0.0; 3], &[0.0; 3]).unwrap();
        assert!(matches!(sm.complex, ComplexSolver::Band(_)));
        assert_eq!(
            sm.factor(0.1, 3.6, 2.7, 3.05),
            Err(SetupFailure::OutsidePattern(2, 0))
        );
    }

    /// The sparse LU with the whole `3 x 3` pattern: `J`, `M` and the complex system stored
    /// in it; and with a tridiagonal pattern that misses the entry `(2, 0)` of `J`: the
    /// set-up reports it (the value is not dropped).
    #[test]
    fn the_sparse_solver_stores_and_checks_its_pattern() {
        let full: Vec<(usize, usize)> = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).collect();
        let ls = crate::linear_solver::FaerSparseLu::new(3, &full).unwrap();
        let sm = StageMatrices::new(ls, 3);
        assert!(matches!(sm.complex, ComplexSolver::Sparse(_)));
        assert!(matches!(sm.jy, Jacobian::Sparse(_)));
        systems_solve_what_they_should(crate::linear_solver::FaerSparseLu::new(3, &full).unwrap());
        // The round-off bound with the pattern equals the dense one's.
        let mut sparse = StageMatrices::new(
            crate::linear_solver::FaerSparseLu::new(3, &full).unwrap(),
            3,
        );
        let mut dense = StageMatrices::new(NalgebraLu::<3>::new(), 3);
        let (y, yp) = ([1.0, -2.0, 0.5], [0.25, 3.0, -1.0]);
        sparse.evaluate(&Linear, 0.0, &y, &yp).unwrap();
        dense.evaluate(&Linear, 0.0, &y, &yp).unwrap();
        let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
        sparse.residual_roundoff(&y, &yp, &mut a);
        dense.residual_roundoff(&y, &yp, &mut b);
        for (a, b) in a.iter().zip(&b) {
            assert!((a - b).abs() <= 1e-15 * b.abs(), "{a} {b}");
        }

        let tridiagonal: Vec<(usize, usize)> = (0..3usize)
            .flat_map(|i| [(i, i.saturating_sub(1)), (i, i), (i, (i + 1).min(2))])
            .collect();
        let ls = crate::linear_solver::FaerSparseLu::new(3, &tridiagonal).unwrap();
        let mut sm = StageMatrices::new(ls, 3);
        sm.evaluate(&Linear, 0.0, &[0.0; 3], &[0.0; 3]).unwrap();
        assert!(matches!(sm.complex, ComplexSolver::Sparse(_)));
        assert_eq!(
            sm.factor(0.1, 3.6, 2.7, 3.05),
            Err(SetupFailure::OutsidePattern(2, 0))
        );
    }

    /// A malformed compressed-column pattern (from some other solver) is refused, not a
    /// panic: the stage matrices then fall back to dense storage.
    #[test]
    fn a_malformed_pattern_is_refused() {
        // Too few column pointers; a row out of range; rows not ascending.
        assert!(ComplexSparseLu::new(3, &[0, 1], &[0]).is_none());
        assert!(ComplexSparseLu::new(2, &[0, 1, 2], &[0, 2]).is_none());
        assert!(ComplexSparseLu::new(2, &[0, 2, 3], &[1, 0, 1]).is_none());
        assert!(ComplexSparseLu::new(2, &[0, 2, 3], &[0, 1, 1]).is_some());
    }

    fn systems_solve_what_they_should<L: LinearSolver>(ls: L) {
        let mut sm = StageMatrices::new(ls, 3);
        sm.evaluate(&Linear, 0.0, &[0.0; 3], &[0.0; 3]).unwrap();
        let mut mv = [0.0; 3];
        sm.apply_mass(&[1.0, 1.0, 1.0], &mut mv);
        assert_eq!(mv, [3.0, 1.0, 0.0]);
        let (h, g, a, b) = (0.1, 3.6, 2.7, 3.05);
        sm.factor(h, g, a, b).unwrap();
        // Real: (g/h M - K) x = r.
        let x = [0.3, -1.0, 2.0];
        let mut r = [0.0; 3];
        for i in 0..3 {
            r[i] = (0..3).map(|j| (g / h * M[i][j] - K[i][j]) * x[j]).sum();
        }
        sm.solve_real(&mut r);
        for i in 0..3 {
            assert!((r[i] - x[i]).abs() < 1e-13, "{r:?}");
        }
        // Complex: ((a - ib)/h M - K) z = r.
        let z = [c64::new(1.0, 2.0), c64::new(-0.5, 0.0), c64::new(0.0, 3.0)];
        let lam = c64::new(a, -b) / h;
        let mut rc = [c64::new(0.0, 0.0); 3];
        for i in 0..3 {
            rc[i] = (0..3)
                .map(|j| (lam * M[i][j] - K[i][j]) * z[j])
                .fold(c64::new(0.0, 0.0), |s, v| s + v);
        }
        sm.solve_complex(&mut rc);
        for i in 0..3 {
            assert!((rc[i] - z[i]).norm() < 1e-13, "{rc:?}");
        }
    }
}
