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

const NONE: usize = usize::MAX;

/// Per index, its position among the selected ones (`NONE` when not selected), and the number
/// selected.
type Slots = (Vec<usize>, usize);

/// The [`Slots`] of the rows and of the columns of a `rows x cols` matrix: the layout of a
/// [`Selection`] (indices out of range or repeated are ignored; every column when
/// `selected_cols` is `None`).
fn selection_slots(
    rows: usize,
    cols: usize,
    selected_rows: &[usize],
    selected_cols: Option<&[usize]>,
) -> (Slots, Slots) {
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
    let row = slots(rows, &mut selected_rows.iter().copied());
    let col = match selected_cols {
        Some(c) => slots(cols, &mut c.iter().copied()),
        None => slots(cols, &mut (0..cols)),
    };
    (row, col)
}

/// The entries of a few rows and columns of a matrix (the constraint rows of an iteration
/// matrix, say); every other entry written is dropped (one table look-up). A block of at most
/// [`DENSE_BLOCK_MAX`] entries is held densely (reading and writing an entry costs an index);
/// a larger one sparsely: per selected row the entries written, by column, so memory and the
/// cost of clearing and reading grow with the entries written, not with the selected rows
/// times the selected columns (the constraint rows of a DAE with thousands of constraints and
/// positions).
///
/// Sparse, [`fill_zero`](MatrixSink::fill_zero) keeps the positions written (with value
/// zero), so a writer that writes the same entries at every evaluation allocates only at the
/// first, and reading an entry costs a binary search in its row.
#[derive(Debug, Clone)]
pub(crate) struct Selection {
    rows: usize,
    cols: usize,
    row_slot: Vec<usize>,
    col_slot: Vec<usize>,
    storage: BlockStorage,
}

/// The largest selected block (rows times columns) [`Selection`] holds densely (64 KB):
/// the stabilised form of small models keeps the speed of dense reads (sparse blocks cost
/// 10-18 % of the run time of Radau on one and four stabilised pendulums, 5 and 20 unknowns;
/// dense ones with the hot loops reading rows as slices, 3 %).
pub(crate) const DENSE_BLOCK_MAX: usize = 8192;

/// How a [`Selection`] holds its entries.
#[derive(Debug, Clone)]
enum BlockStorage {
    /// Every selected entry, row by row (`width` selected columns).
    Dense { width: usize, values: Vec<f64> },
    /// Per selected row, `(column slot, value)` of the positions written, by column slot.
    Sparse(Vec<Vec<(usize, f64)>>),
}

/// The entries of a row of a [`Selection`], `(column slot, value)` by column slot.
pub(crate) enum RowEntries<'a> {
    /// Every selected column of a dense block (zeros included).
    Dense(std::iter::Enumerate<std::slice::Iter<'a, f64>>),
    /// The positions written.
    Sparse(std::slice::Iter<'a, (usize, f64)>),
}

impl Iterator for RowEntries<'_> {
    type Item = (usize, f64);
    #[inline]
    fn next(&mut self) -> Option<(usize, f64)> {
        match self {
            RowEntries::Dense(it) => it.next().map(|(k, &v)| (k, v)),
            RowEntries::Sparse(it) => it.next().copied(),
        }
    }
}

impl Selection {
    /// A selection of the entries `(r, k)` of a `rows x cols` matrix with `r` in
    /// `selected_rows` and `k` in `selected_cols` (every column when `None`), all zero.
    /// Indices out of range or repeated are ignored (their entries are never captured twice).
    pub(crate) fn new(
        rows: usize,
        cols: usize,
        selected_rows: &[usize],
        selected_cols: Option<&[usize]>,
    ) -> Self {
        let ((row_slot, height), (col_slot, width)) =
            selection_slots(rows, cols, selected_rows, selected_cols);
        let storage = match height.checked_mul(width) {
            Some(size) if size <= DENSE_BLOCK_MAX => BlockStorage::Dense {
                width,
                values: vec![0.0; size],
            },
            _ => BlockStorage::Sparse(vec![Vec::new(); height]),
        };
        Self {
            rows,
            cols,
            row_slot,
            col_slot,
            storage,
        }
    }

    /// The slots `(selected row, selected column)` of `(row, col)`, `None` outside the
    /// selection.
    #[inline]
    fn slots(&self, row: usize, col: usize) -> Option<(usize, usize)> {
        let r = *self.row_slot.get(row)?;
        let c = *self.col_slot.get(col)?;
        (r != NONE && c != NONE).then_some((r, c))
    }

    /// The captured entry `(row, col)` (indices of the full matrix); zero for an entry outside
    /// the selection or not written.
    #[inline]
    pub(crate) fn get(&self, row: usize, col: usize) -> f64 {
        let Some((r, c)) = self.slots(row, col) else {
            return 0.0;
        };
        match &self.storage {
            BlockStorage::Dense { width, values } => values[r * width + c],
            BlockStorage::Sparse(rows) => {
                let e = &rows[r];
                e.binary_search_by_key(&c, |&(k, _)| k)
                    .map_or(0.0, |at| e[at].1)
            }
        }
    }

    /// The entries of the `r`-th selected row, `(column slot, value)` by column slot (the
    /// position of the column in the selected list; its index when every column is
    /// selected): every selected column of a dense block, the positions written of a sparse
    /// one (zero values among them either way). Empty for `r` beyond the selected rows.
    pub(crate) fn row(&self, r: usize) -> RowEntries<'_> {
        match &self.storage {
            BlockStorage::Dense { width, values } => {
                let row = values.get(r * width..(r + 1) * width).unwrap_or(&[]);
                RowEntries::Dense(row.iter().enumerate())
            }
            BlockStorage::Sparse(rows) => {
                RowEntries::Sparse(rows.get(r).map_or(&[][..], |e| e.as_slice()).iter())
            }
        }
    }

    /// The `r`-th selected row of a dense block, every selected column by slot; `None` for a
    /// sparse block (or `r` beyond the selected rows). For the hot loops of a small block.
    #[inline]
    pub(crate) fn dense_row(&self, r: usize) -> Option<&[f64]> {
        match &self.storage {
            BlockStorage::Dense { width, values } => values.get(r * width..(r + 1) * width),
            BlockStorage::Sparse(_) => None,
        }
    }

    /// The value at `(row, col)` (inserted as zero into a sparse block when not yet written);
    /// `None` outside the selection.
    #[inline]
    fn entry(&mut self, row: usize, col: usize) -> Option<&mut f64> {
        let (r, c) = self.slots(row, col)?;
        match &mut self.storage {
            BlockStorage::Dense { width, values } => Some(&mut values[r * *width + c]),
            BlockStorage::Sparse(rows) => Some(sparse_entry(&mut rows[r], c)),
        }
    }
}

/// The value at column slot `c` of a sparse row (`(column slot, value)` by slot), inserted as
/// zero when not yet written; out of line, so that a dense block's writes stay small enough to
/// inline into the writer.
#[inline(never)]
fn sparse_entry(row: &mut Vec<(usize, f64)>, c: usize) -> &mut f64 {
    let at = match row.binary_search_by_key(&c, |&(k, _)| k) {
        Ok(at) => at,
        Err(at) => {
            row.insert(at, (c, 0.0));
            at
        }
    };
    &mut row[at].1
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
        if let Some(v) = self.entry(row, col) {
            *v = value;
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if let Some(v) = self.entry(row, col) {
            *v += value;
        }
    }
    fn fill_zero(&mut self) {
        match &mut self.storage {
            BlockStorage::Dense { values, .. } => values.fill(0.0),
            BlockStorage::Sparse(rows) => {
                for e in rows {
                    for (_, v) in e.iter_mut() {
                        *v = 0.0;
                    }
                }
            }
        }
    }
}

/// The entries written to a matrix, kept sparse: every write is recorded as it comes and
/// [`Triplets::entries`] replays them per position (a [`set`](MatrixSink::set) overwrites,
/// an [`add`](MatrixSink::add) accumulates, from zero), so the values are those a zeroed
/// dense destination would hold, to the bit.
///
/// For reading a Jacobian's structure and values where the dimension is too large for a
/// dense `n x n` matrix: memory and time grow with the number of writes, not with the
/// matrix's size. Writes outside the `rows x cols` matrix are dropped.
#[derive(Debug, Clone, Default)]
pub struct Triplets {
    rows: usize,
    cols: usize,
    /// `(row, col, value, overwrite)` in the order written.
    writes: Vec<(usize, usize, f64, bool)>,
}

impl Triplets {
    /// An empty (all-zero) `rows x cols` matrix.
    pub fn new(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            writes: Vec::new(),
        }
    }

    /// The positions written and their values, sorted by row and then column, one per
    /// position (a position written with zero is listed with zero).
    pub fn entries(&self) -> Vec<(usize, usize, f64)> {
        let mut writes = self.writes.clone();
        // Stable: the writes to one position stay in the order they were made.
        writes.sort_by_key(|&(r, c, _, _)| (r, c));
        let mut out: Vec<(usize, usize, f64)> = Vec::with_capacity(writes.len());
        for (r, c, v, overwrite) in writes {
            match out.last_mut() {
                Some(last) if (last.0, last.1) == (r, c) => {
                    if overwrite {
                        last.2 = v;
                    } else {
                        last.2 += v;
                    }
                }
                // The first write to a position starts from zero (`0.0 + v` as a dense
                // destination adds, for the sign of a zero).
                _ => out.push((r, c, if overwrite { v } else { 0.0 + v })),
            }
        }
        out
    }

    /// The number of writes recorded (an upper bound of the positions written).
    pub fn writes(&self) -> usize {
        self.writes.len()
    }
}

impl MatrixSink for Triplets {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        if row < self.rows && col < self.cols {
            self.writes.push((row, col, value, true));
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if row < self.rows && col < self.cols {
            self.writes.push((row, col, value, false));
        }
    }
    fn fill_zero(&mut self) {
        self.writes.clear();
    }
}

/// Two sinks written at once: every entry goes to both (a destination and a sink that keeps a
/// few of its entries for the caller, for example).
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
    fn a_large_selection_is_held_sparsely_with_the_entries_of_a_dense_one() {
        // A small block is held densely, a large one sparsely: the selected entries of what
        // was written either way.
        for cols in [5, DENSE_BLOCK_MAX] {
            let (rows, selected) = ([3, 1, 9, 1], [0, 4, 4, 2]);
            let all: Vec<usize> = (0..cols).collect();
            let selected_cols = if cols == 5 { &selected[..] } else { &all[..] };
            let mut full = nalgebra::DMatrix::<f64>::zeros(4, cols);
            let mut sparse = Selection::new(4, cols, &rows, Some(selected_cols));
            let held_dense = matches!(sparse.storage, BlockStorage::Dense { .. });
            assert_eq!(held_dense, cols == 5);
            for s in [
                &mut full as &mut dyn MatrixSink,
                &mut sparse as &mut dyn MatrixSink,
            ] {
                for r in (0..4).rev() {
                    for k in 0..5 {
                        s.add(r, k, (10 * r + k) as f64);
                    }
                }
                s.set(1, 4, 0.5);
                s.add(3, 2, 0.25);
            }
            sparse.set(9, 0, 1.0);
            assert_eq!((sparse.rows(), sparse.cols()), (4, cols));
            for r in 0..6 {
                for k in 0..6 {
                    let kept = [1, 3].contains(&r) && k < cols && selected_cols.contains(&k);
                    let want = if kept { full[(r, k)] } else { 0.0 };
                    assert_eq!(sparse.get(r, k).to_bits(), want.to_bits(), "({r}, {k})");
                }
            }
            let non_zero = |r| {
                sparse
                    .row(r)
                    .filter(|e| e.1 != 0.0)
                    .collect::<Vec<(usize, f64)>>()
            };
            if cols == 5 {
                // Row 3 is the first selected, its columns 0, 4, 2 in the slots 0, 1, 2.
                assert_eq!(non_zero(0), [(0, 30.0), (1, 34.0), (2, 32.25)]);
                assert_eq!(non_zero(1), [(0, 10.0), (1, 0.5), (2, 12.0)]);
            } else {
                let row3 = [(0, 30.0), (1, 31.0), (2, 32.25), (3, 33.0), (4, 34.0)];
                assert_eq!(non_zero(0), row3);
                assert_eq!(sparse.row(1).count(), 5);
            }
            assert_eq!(sparse.row(2).count(), 0);
            sparse.fill_zero();
            assert!(sparse.row(1).all(|e| e.1 == 0.0));
            assert_eq!(sparse.get(1, 4), 0.0);
        }
    }

    #[test]
    fn triplets_hold_what_a_dense_matrix_holds() {
        let mut t = Triplets::new(3, 4);
        let mut d = nalgebra::DMatrix::<f64>::zeros(3, 4);
        for s in [&mut t as &mut dyn MatrixSink, &mut d as &mut dyn MatrixSink] {
            s.add(2, 1, 0.1);
            s.set(0, 3, 5.0);
            s.add(2, 1, 0.2);
            s.add(0, 3, -1.5);
            s.set(1, 0, 7.0);
            s.set(1, 0, 0.0);
            s.add(2, 1, 0.3);
            s.set(2, 2, f64::NAN);
            s.set(2, 2, 1.0);
            // Outside the matrix: dropped by the sparse sink (the dense one would panic).
        }
        t.set(3, 0, 1.0);
        t.add(0, 4, 1.0);
        assert_eq!((t.rows(), t.cols(), t.writes()), (3, 4, 9));
        let entries = t.entries();
        assert_eq!(
            entries.iter().map(|e| (e.0, e.1)).collect::<Vec<_>>(),
            [(0, 3), (1, 0), (2, 1), (2, 2)]
        );
        for (r, c, v) in entries {
            assert_eq!(v.to_bits(), d[(r, c)].to_bits(), "({r}, {c})");
        }
        t.fill_zero();
        assert!(t.entries().is_empty());
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
