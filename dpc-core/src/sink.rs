//! Destinations for Jacobian entries.
//!
//! Generated code never builds a matrix itself: it writes each structurally non-zero entry
//! into a [`MatrixSink`] chosen by the caller. One emitted routine therefore serves the
//! fixed-size nalgebra back end (stack storage, no heap), faer dense matrices for large models
//! and sparse value arrays laid out by a known pattern.
//!
//! Sinks are *not* cleared by the writer: structurally zero entries are never written, so the
//! caller zeroes the destination once (or relies on a sparse layout that has no zero slots).

use faer::reborrow::ReborrowMut;
use nalgebra::{Dim, Matrix, StorageMut};

/// A matrix that receives entries `(row, col, value)`.
pub trait MatrixSink {
    /// Number of rows of the destination.
    fn rows(&self) -> usize;
    /// Number of columns of the destination.
    fn cols(&self) -> usize;
    /// Store `value` at `(row, col)`, overwriting what was there.
    fn set(&mut self, row: usize, col: usize, value: f64);
    /// Add `value` to the entry at `(row, col)`.
    fn add(&mut self, row: usize, col: usize, value: f64);
    /// Set every entry to zero.
    fn fill_zero(&mut self);
}

impl<R: Dim, C: Dim, S: StorageMut<f64, R, C>> MatrixSink for Matrix<f64, R, C, S> {
    fn rows(&self) -> usize {
        self.nrows()
    }
    fn cols(&self) -> usize {
        self.ncols()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        self[(row, col)] = value;
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self[(row, col)] += value;
    }
    fn fill_zero(&mut self) {
        // A contiguous column-major matrix (an owned `SMatrix` or `DMatrix`, the integrators'
        // iteration matrices, zeroed before every evaluation) as one `fill` of its slice:
        // nalgebra's `fill` walks the entries with a strided iterator, about nine
        // instructions per entry (4.6 % of Andrews' stabilised form on the BDF at 1e-4).
        let (rows, cols) = self.shape();
        if self.strides() == (1, rows) {
            let len = rows * cols;
            // SAFETY: with row stride 1 and column stride `rows` the storage holds the
            // `rows * cols` entries one after the other from `as_mut_ptr`, and `self` is
            // borrowed mutably for the slice's lifetime.
            unsafe { std::slice::from_raw_parts_mut(self.as_mut_ptr(), len) }.fill(0.0);
        } else {
            self.fill(0.0);
        }
    }
}

impl MatrixSink for faer::MatMut<'_, f64> {
    fn rows(&self) -> usize {
        self.nrows()
    }
    fn cols(&self) -> usize {
        self.ncols()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        *self.rb_mut().get_mut(row, col) = value;
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        *self.rb_mut().get_mut(row, col) += value;
    }
    fn fill_zero(&mut self) {
        self.fill(0.0);
    }
}

impl MatrixSink for faer::Mat<f64> {
    fn rows(&self) -> usize {
        self.nrows()
    }
    fn cols(&self) -> usize {
        self.ncols()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        *self.get_mut(row, col) = value;
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        *self.get_mut(row, col) += value;
    }
    fn fill_zero(&mut self) {
        self.fill(0.0);
    }
}

/// The entries of a few rows and columns of a matrix, captured into a compact dense block;
/// every other entry written is dropped.
///
/// For a caller that needs a handful of entries of a Jacobian whose writer produces all of
/// them (the constraint rows of an iteration matrix, say): the cost of clearing and reading
/// grows with the number of selected entries, not with the matrix's size. Writes to unselected
/// entries cost one table look-up.
#[derive(Debug, Clone)]
pub struct Selection {
    rows: usize,
    cols: usize,
    /// Per row of the full matrix, its row in `values` (`NONE` when not selected).
    row_slot: Vec<usize>,
    /// Per column of the full matrix, its column in `values` (`NONE` when not selected).
    col_slot: Vec<usize>,
    /// Number of selected columns (the stride of `values`).
    width: usize,
    /// The selected entries, row by row.
    values: Vec<f64>,
}

const NONE: usize = usize::MAX;

impl Selection {
    /// A selection of the entries `(r, k)` of a `rows x cols` matrix with `r` in
    /// `selected_rows` and `k` in `selected_cols` (every column when `None`), all zero.
    /// Indices out of range or repeated are ignored (their entries are never captured twice).
    pub fn new(
        rows: usize,
        cols: usize,
        selected_rows: &[usize],
        selected_cols: Option<&[usize]>,
    ) -> Self {
        let slots = |n: usize, selected: &mut dyn Iterator<Item = usize>| {
            let mut slot = vec![NONE; n];
            let mut next = 0;
            for i in selected {
                if i < n && slot[i] == NONE {
                    slot[i] = next;
                    next += 1;
                }
            }
            (slot, next)
        };
        let (row_slot, height) = slots(rows, &mut selected_rows.iter().copied());
        let (col_slot, width) = match selected_cols {
            Some(c) => slots(cols, &mut c.iter().copied()),
            None => slots(cols, &mut (0..cols)),
        };
        Self {
            rows,
            cols,
            row_slot,
            col_slot,
            width,
            values: vec![0.0; height * width],
        }
    }

    /// The captured entry `(row, col)` (indices of the full matrix); zero for an entry outside
    /// the selection.
    #[inline]
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.slot(row, col).map_or(0.0, |s| self.values[s])
    }

    /// The captured entries row by row: selected row `r` and column `k` (their positions in
    /// the lists given to [`Selection::new`], repeats and indices out of range dropped) at
    /// `r * width + k`, with `width` the number of selected columns. For a caller that reads
    /// the same entries at every evaluation without the look-ups of [`Selection::get`].
    #[inline]
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    #[inline]
    fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let r = *self.row_slot.get(row)?;
        let c = *self.col_slot.get(col)?;
        (r != NONE && c != NONE).then(|| r * self.width + c)
    }
}

impl MatrixSink for Selection {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        if let Some(s) = self.slot(row, col) {
            self.values[s] = value;
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if let Some(s) = self.slot(row, col) {
            self.values[s] += value;
        }
    }
    fn fill_zero(&mut self) {
        self.values.fill(0.0);
    }
}

/// Two sinks written at once: every entry goes to both (a destination and a [`Selection`]
/// that keeps a few of its entries for the caller, for example).
pub struct Tee<'a, A: ?Sized, B: ?Sized>(pub &'a mut A, pub &'a mut B);

impl<A: MatrixSink + ?Sized, B: MatrixSink + ?Sized> MatrixSink for Tee<'_, A, B> {
    fn rows(&self) -> usize {
        self.0.rows()
    }
    fn cols(&self) -> usize {
        self.0.cols()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        self.0.set(row, col, value);
        self.1.set(row, col, value);
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self.0.add(row, col, value);
        self.1.add(row, col, value);
    }
    fn fill_zero(&mut self) {
        self.0.fill_zero();
        self.1.fill_zero();
    }
}

/// A sink that adds `factor` times every entry written to another sink: [`set`](MatrixSink::set)
/// and [`add`](MatrixSink::add) both become `add(factor * value)`.
///
/// For moving an iteration matrix `dF/dy + c dF/dy'` to another `c` with the mass matrix
/// alone: the mass matrix written through `Scaled { sink, factor: c_new - c }` (each
/// structural entry written once, as [`ImplicitDae::mass_matrix`](crate::ImplicitDae::mass_matrix)
/// writes it). [`fill_zero`](MatrixSink::fill_zero) does nothing: the destination's entries are
/// what is being added to.
pub struct Scaled<'a, S: ?Sized> {
    /// The destination.
    pub sink: &'a mut S,
    /// The factor of every entry written.
    pub factor: f64,
}

impl<S: MatrixSink + ?Sized> MatrixSink for Scaled<'_, S> {
    fn rows(&self) -> usize {
        self.sink.rows()
    }
    fn cols(&self) -> usize {
        self.sink.cols()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        self.sink.add(row, col, self.factor * value);
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self.sink.add(row, col, self.factor * value);
    }
    fn fill_zero(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    #[test]
    fn scaled_adds_the_multiple_of_every_entry_written() {
        let mut m = SMatrix::<f64, 2, 2>::new(1.0, 2.0, 3.0, 4.0);
        let mut s = Scaled {
            sink: &mut m,
            factor: -0.5,
        };
        s.set(0, 1, 4.0);
        s.add(1, 0, 2.0);
        s.add(1, 0, 2.0);
        s.fill_zero();
        assert_eq!((s.rows(), s.cols()), (2, 2));
        assert_eq!(m, SMatrix::<f64, 2, 2>::new(1.0, 0.0, 1.0, 4.0));
    }

    #[test]
    fn faer_sink_matches_nalgebra_sink() {
        let mut a = faer::Mat::<f64>::zeros(2, 2);
        let mut b = SMatrix::<f64, 2, 2>::zeros();
        for s in [&mut a as &mut dyn MatrixSink, &mut b as &mut dyn MatrixSink] {
            s.set(0, 1, 3.0);
            s.add(1, 0, -1.0);
        }
        assert_eq!(a[(0, 1)], b[(0, 1)]);
        assert_eq!(a[(1, 0)], b[(1, 0)]);
    }

    #[test]
    fn selection_keeps_only_its_entries() {
        let mut s = Selection::new(4, 5, &[3, 1, 9], Some(&[0, 4, 4]));
        assert_eq!((s.rows(), s.cols()), (4, 5));
        for r in 0..4 {
            for k in 0..5 {
                s.set(r, k, (10 * r + k) as f64);
            }
        }
        s.add(1, 4, 0.5);
        s.add(2, 4, 0.5);
        for r in 0..4 {
            for k in 0..5 {
                let kept = [1, 3].contains(&r) && [0, 4].contains(&k);
                let want = if kept { (10 * r + k) as f64 } else { 0.0 };
                let want = if (r, k) == (1, 4) { want + 0.5 } else { want };
                assert_eq!(s.get(r, k), want, "({r}, {k})");
            }
        }
        assert_eq!(s.get(7, 0), 0.0);
        s.fill_zero();
        assert_eq!(s.get(3, 4), 0.0);
        // Every column when none are named.
        let mut all = Selection::new(3, 3, &[2], None);
        let mut m = SMatrix::<f64, 3, 3>::zeros();
        let mut tee = Tee(&mut m, &mut all);
        tee.set(2, 1, 4.0);
        tee.add(0, 1, 1.0);
        assert_eq!((all.get(2, 1), all.get(0, 1)), (4.0, 0.0));
        assert_eq!((m[(2, 1)], m[(0, 1)]), (4.0, 1.0));
    }
}
