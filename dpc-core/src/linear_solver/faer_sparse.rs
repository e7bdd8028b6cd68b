//! Sparse LU (faer) for iteration matrices with a known structural pattern.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::lu::simplicial::{self, SimplicialLu};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuSymbolicParams, SymbolicLu};
use faer::sparse::linalg::{LuError, SupernodalThreshold};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par};

use super::{FactorError, LinearSolver};
use crate::sink::MatrixSink;

/// Values of a sparse matrix laid out by a fixed compressed-column pattern; a [`MatrixSink`].
///
/// Writes to positions outside the pattern are not stored; the first one is remembered and
/// reported by [`FaerSparseLu::factor`] as [`FactorError::OutsidePattern`].
#[derive(Debug, Clone)]
pub struct PatternMatrix {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    outside: Option<(usize, usize)>,
}

impl PatternMatrix {
    fn slot(&self, row: usize, col: usize) -> Option<usize> {
        if col >= self.n {
            return None;
        }
        let (lo, hi) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[lo..hi]
            .binary_search(&row)
            .ok()
            .map(|k| lo + k)
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Zeros in the compressed-column pattern `(col_ptr, row_idx)` of an `n x n` matrix (as
    /// [`LinearSolver::pattern`] gives it).
    pub(crate) fn with_pattern(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Self {
        Self {
            n,
            col_ptr: col_ptr.to_vec(),
            row_idx: row_idx.to_vec(),
            values: vec![0.0; row_idx.len()],
            outside: None,
        }
    }

    /// The rows of column `j` and their values.
    #[inline]
    pub(crate) fn column(&self, j: usize) -> (&[usize], &[f64]) {
        let (lo, hi) = (self.col_ptr[j], self.col_ptr[j + 1]);
        (&self.row_idx[lo..hi], &self.values[lo..hi])
    }

    /// The entry `(i, j)` (zero outside the pattern).
    pub(crate) fn get(&self, i: usize, j: usize) -> f64 {
        self.slot(i, j).map_or(0.0, |k| self.values[k])
    }

    /// The values in pattern order (column by column).
    pub(crate) fn values(&self) -> &[f64] {
        &self.values
    }

    /// The row of each value, in pattern order.
    pub(crate) fn row_indices(&self) -> &[usize] {
        &self.row_idx
    }

    /// `self -= other`, both in the same pattern (entry by entry).
    pub(crate) fn subtract(&mut self, other: &Self) {
        for (a, b) in self.values.iter_mut().zip(&other.values) {
            *a -= b;
        }
    }

    /// The first non-zero entry written outside the pattern since the last zeroing.
    pub(crate) fn outside(&self) -> Option<(usize, usize)> {
        self.outside
    }
}

/// The first column of a compressed-column matrix (`col_ptr`, `values` in pattern order) whose
/// values `no_pivot` says cannot give a pivot (all zero, or not finite): the column a singular
/// sparse matrix is reported with.
pub(crate) fn first_column_without_pivot<T>(
    col_ptr: &[usize],
    values: &[T],
    no_pivot: impl Fn(&[T]) -> bool,
) -> Option<usize> {
    (0..col_ptr.len().saturating_sub(1)).find(|&c| no_pivot(&values[col_ptr[c]..col_ptr[c + 1]]))
}

/// The first of the rows that has no value for which `nonzero(k)` holds (`k` indexing the
/// values, whose rows are `row_idx`): the zero row a singular sparse matrix is reported with.
/// `filled` has one slot per row (its contents on entry do not matter): the caller's storage.
pub(crate) fn first_empty_row(
    filled: &mut [bool],
    row_idx: &[usize],
    nonzero: impl Fn(usize) -> bool,
) -> Option<usize> {
    filled.fill(false);
    for (k, &r) in row_idx.iter().enumerate() {
        filled[r] |= nonzero(k);
    }
    filled.iter().position(|&f| !f)
}

impl MatrixSink for PatternMatrix {
    fn rows(&self) -> usize {
        self.n
    }
    fn cols(&self) -> usize {
        self.n
    }
    fn set(&mut self, row: usize, col: usize, value: f64) {
        match self.slot(row, col) {
            Some(k) => self.values[k] = value,
            None => {
                if value != 0.0 {
                    self.outside.get_or_insert((row, col));
                }
            }
        }
    }
    fn add(&mut self, row: usize, col: usize, value: f64) {
        match self.slot(row, col) {
            Some(k) => self.values[k] += value,
            None => {
                if value != 0.0 {
                    self.outside.get_or_insert((row, col));
                }
            }
        }
    }
    fn fill_zero(&mut self) {
        self.values.fill(0.0);
        self.outside = None;
    }
}

/// The magnitude of a real or complex entry, for [`ReusedSparseLu`]'s pivot test.
pub(crate) trait Magnitude {
    /// `|self|`.
    fn magnitude(&self) -> f64;
}

impl Magnitude for f64 {
    fn magnitude(&self) -> f64 {
        self.abs()
    }
}

impl Magnitude for faer::c64 {
    fn magnitude(&self) -> f64 {
        self.norm()
    }
}

/// Why [`ReusedSparseLu::factor`] failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SparseLuFailure {
    /// The pivot of this column (the unknown's index) vanished: no row left to pivot on
    /// (structurally singular), or every candidate is exactly zero (numerically singular: the
    /// elimination cancelled the column), or it is not finite.
    ZeroPivot(usize),
    /// faer could not allocate its factors.
    OutOfMemory,
}

/// faer's sparse LU with partial pivoting over `T` (real or complex): faer's fill-reducing
/// column order (COLAMD) computed once, and its left-looking simplicial kernel run on the
/// numeric factors, row permutation and work space kept from one factorisation to the next,
/// so that after the first factorisation (and any later one whose pivots grow the fill beyond
/// every earlier one's) neither factorising nor solving allocates (faer's
/// `Lu::try_new_with_symbolic` allocates new factors and work space at every factorisation,
/// and its solve a work space at every solve). The simplicial kernel is the one faer itself
/// picks for every sparse iteration matrix of the tests (the two bit adding unit, the food
/// web, the chains of up to 80 links); with it the factors are at hand, so a numerically zero
/// pivot is reported with its column (faer's own check finds only a column without any
/// candidate row, and divides by a zero pivot). The real LU ([`FaerSparseLu`]) and Radau's
/// complex one share it.
pub(crate) struct ReusedSparseLu<T> {
    pattern: SymbolicSparseColMat<usize>,
    /// The fill-reducing column order.
    symbolic: SymbolicLu<usize>,
    numeric: SimplicialLu<usize, T>,
    row_perm: Vec<usize>,
    row_perm_inv: Vec<usize>,
    /// The last factorisation succeeded (`numeric` holds its factors).
    factored: bool,
    /// Work space for a factorisation and for a solve with one right-hand side.
    work: MemBuffer,
}

impl<T> std::fmt::Debug for ReusedSparseLu<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReusedSparseLu")
            .field("n", &self.pattern.ncols())
            .field("nnz", &self.pattern.row_idx().len())
            .field("factored", &self.factored)
            .finish_non_exhaustive()
    }
}

impl<T: ComplexField + Magnitude> ReusedSparseLu<T> {
    /// For `n x n` matrices with entries at the compressed-column pattern `(col_ptr,
    /// row_idx)`, which must be well formed (rows ascending within each column, in range);
    /// `None` when faer's ordering fails.
    pub(crate) fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Option<Self> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(pattern.as_ref(), params).ok()?;
        let work = MemBuffer::new(StackReq::any_of(&[
            simplicial::factorize_simplicial_numeric_lu_scratch::<usize, T>(n, n),
            simplicial::solve_in_place_scratch::<usize, T>(n, 1, Par::Seq),
        ]));
        Some(Self {
            pattern,
            symbolic,
            numeric: SimplicialLu::new(),
            row_perm: vec![0; n],
            row_perm_inv: vec![0; n],
            factored: false,
            work,
        })
    }

    /// The pattern's column pointers.
    pub(crate) fn col_ptr(&self) -> &[usize] {
        self.pattern.col_ptr()
    }

    /// Mark the factors unusable (a matrix refused before factorising): solves leave their
    /// right-hand side unchanged until the next successful factorisation.
    pub(crate) fn discard(&mut self) {
        self.factored = false;
    }

    /// Factorise the matrix whose values, in the pattern's order, are `values`.
    ///
    /// # Errors
    /// [`SparseLuFailure::ZeroPivot`] naming the (original) column whose pivot vanished,
    /// [`SparseLuFailure::OutOfMemory`].
    pub(crate) fn factor(&mut self, values: &[T]) -> Result<(), SparseLuFailure> {
        self.factored = false;
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let col_perm = self.symbolic.col_perm();
        let (forward, _) = col_perm.arrays();
        match simplicial::factorize_simplicial_numeric_lu(
            &mut self.row_perm,
            &mut self.row_perm_inv,
            &mut self.numeric,
            a,
            col_perm,
            MemStack::new(&mut self.work),
        ) {
            Ok(()) => {}
            Err(LuError::SymbolicSingular { index }) => {
                return Err(SparseLuFailure::ZeroPivot(forward[index]))
            }
            Err(LuError::Generic(_)) => return Err(SparseLuFailure::OutOfMemory),
        }
        // Column `j` of `U` (in the factorisation's column order) holds its pivot in row `j`.
        // Only an exactly zero (or non-finite) pivot counts: faer has divided by it, and every
        // solve would be NaN. A relative test (`n eps max |a_ij|`, the dense LUs') refused the
        // stage matrices of a stabilised 80-link chain at the first steps, whose `gamma / h M`
        // entries exceed the multipliers' by 13 decades; a small pivot is Newton's to judge.
        let u = self.numeric.u_factor_unsorted();
        for (j, &column) in forward.iter().enumerate() {
            let pivot = u
                .row_idx_of_col_raw(j)
                .iter()
                .zip(u.val_of_col(j))
                .find(|(&i, _)| i == j)
                .map_or(0.0, |(_, v)| v.magnitude());
            if !(pivot > 0.0 && pivot.is_finite()) {
                return Err(SparseLuFailure::ZeroPivot(column));
            }
        }
        self.factored = true;
        Ok(())
    }

    /// Solve `A x = b` in place with the last factorisation; `b` unchanged when the last
    /// factorisation failed (or none was made).
    pub(crate) fn solve_in_place(&mut self, b: &mut [T]) {
        if self.factored {
            let n = b.len();
            let row_perm = PermRef::new_checked(&self.row_perm, &self.row_perm_inv, n);
            self.numeric.solve_in_place_with_conj(
                row_perm,
                self.symbolic.col_perm(),
                Conj::No,
                MatMut::from_column_major_slice_mut(b, n, 1),
                Par::Seq,
                MemStack::new(&mut self.work),
            );
        }
    }
}

/// Sparse LU with partial pivoting (faer), symbolic analysis done once at construction; faer's
/// numeric factors, row permutation and work space are kept from one factorisation to the
/// next, so factorising and solving allocate nothing once the factors have their largest
/// fill.
///
/// The diagonal is always added to the pattern, so a model may leave it out.
#[derive(Debug)]
pub struct FaerSparseLu {
    matrix: PatternMatrix,
    lu: ReusedSparseLu<f64>,
    /// Per row, whether it holds a non-zero value (the zero row a failed factorisation names).
    row_filled: Vec<bool>,
}

impl FaerSparseLu {
    /// A solver for `n x n` systems with non-zeros only at `pattern` (`(row, col)` pairs) and
    /// on the diagonal.
    ///
    /// # Errors
    /// [`FactorError::OutsidePattern`] if an index is out of range, [`FactorError::Singular`]
    /// if faer's symbolic analysis fails.
    pub fn new(n: usize, pattern: &[(usize, usize)]) -> Result<Self, FactorError> {
        let mut entries: Vec<(usize, usize)> = pattern
            .iter()
            .map(|&(r, c)| (c, r))
            .chain((0..n).map(|i| (i, i)))
            .collect();
        if let Some(&(c, r)) = entries.iter().find(|&&(c, r)| r >= n || c >= n) {
            return Err(FactorError::OutsidePattern { row: r, col: c });
        }
        entries.sort_unstable();
        entries.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(c, _) in &entries {
            col_ptr[c + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = entries.iter().map(|&(_, r)| r).collect();
        let lu = ReusedSparseLu::new(n, col_ptr.clone(), row_idx.clone()).ok_or(
            FactorError::Singular {
                column: None,
                row: None,
            },
        )?;
        let nnz = row_idx.len();
        Ok(Self {
            matrix: PatternMatrix {
                n,
                col_ptr,
                row_idx,
                values: vec![0.0; nnz],
                outside: None,
            },
            lu,
            row_filled: vec![false; n],
        })
    }
}

impl LinearSolver for FaerSparseLu {
    type Matrix = PatternMatrix;

    fn dimension(&self) -> usize {
        self.matrix.n
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        &mut self.matrix
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        self.lu.discard();
        if let Some((row, col)) = self.matrix.outside {
            return Err(FactorError::OutsidePattern { row, col });
        }
        let m = &self.matrix;
        if let Some(v) = m.values.iter().position(|v| !v.is_finite()) {
            let col = m.col_ptr.partition_point(|&p| p <= v) - 1;
            return Err(FactorError::NonFinite {
                row: m.row_idx[v],
                col,
            });
        }
        match self.lu.factor(&m.values) {
            Ok(()) => Ok(()),
            // Named on the error path only: the first all-zero column when there is one (else
            // the column whose pivot vanished) and an all-zero row. A zero row or column always
            // ends in a zero pivot (its entries stay exactly zero through the elimination).
            Err(failure) => {
                let zero_column = first_column_without_pivot(&m.col_ptr, &m.values, |c| {
                    c.iter().all(|v| *v == 0.0)
                });
                let column = match failure {
                    SparseLuFailure::ZeroPivot(column) => zero_column.or(Some(column)),
                    // faer's only other failure: its factors could not grow (the process is
                    // short of memory), reported without a column as before.
                    SparseLuFailure::OutOfMemory => zero_column,
                };
                let row = first_empty_row(&mut self.row_filled, &m.row_idx, |k| m.values[k] != 0.0);
                Err(FactorError::Singular { column, row })
            }
        }
    }

    fn pattern(&self) -> Option<(&[usize], &[usize])> {
        Some((&self.matrix.col_ptr, &self.matrix.row_idx))
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        let m = &self.matrix;
        out.fill(0.0);
        for (j, wj) in w.iter().enumerate().take(m.n) {
            for k in m.col_ptr[j]..m.col_ptr[j + 1] {
                let i = m.row_idx[k];
                out[i] = out[i].max(m.values[k].abs() / wj);
            }
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        self.lu.solve_in_place(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_numerically_zero_pivot_is_named() {
        // Rows 3 and 4 of a 6 x 6 cyclic bidiagonal matrix made equal (ones in columns 3 and
        // 4, zeros elsewhere): no zero row or column, but elimination cancels one of the two pivots
        // exactly (faer alone divides by it and every solve is NaN).
        let n = 6;
        let pattern: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| [(i, i), (i, (i + 1) % n)])
            .chain([(4, 3)])
            .collect();
        let mut ls = FaerSparseLu::new(n, &pattern).expect("pattern");
        let m = ls.matrix_mut();
        for i in 0..n {
            m.set(i, i, 2.0);
            m.set(i, (i + 1) % n, 0.5);
        }
        ls.factor().expect("regular");
        let m = ls.matrix_mut();
        for (r, c) in [(3, 3), (3, 4), (4, 3), (4, 4)] {
            m.set(r, c, 1.0);
        }
        m.set(4, 5, 0.0);
        match ls.factor() {
            Err(FactorError::Singular {
                column: Some(c),
                row: None,
            }) => assert!(c == 3 || c == 4, "column {c}"),
            other => panic!("{other:?}"),
        }
        // The refused factors are not used: a solve leaves its right-hand side as it is.
        let mut b = vec![1.0; n];
        ls.solve_in_place(&mut b);
        assert_eq!(b, vec![1.0; n]);
    }

    #[test]
    fn a_non_finite_entry_is_named() {
        // Tridiagonal 5 x 5, the entry (3, 2) NaN.
        let pattern: Vec<(usize, usize)> = (0..5usize)
            .flat_map(|i| [(i, i), (i, i.saturating_sub(1)), (i, (i + 1).min(4))])
            .collect();
        let mut ls = FaerSparseLu::new(5, &pattern).expect("pattern");
        let m = ls.matrix_mut();
        for &(i, j) in &pattern {
            m.set(i, j, if i == j { 4.0 } else { 1.0 });
        }
        ls.factor().expect("regular");
        ls.matrix_mut().set(3, 2, f64::NAN);
        assert_eq!(ls.factor(), Err(FactorError::NonFinite { row: 3, col: 2 }));
    }
}
