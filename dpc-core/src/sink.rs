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
        self.fill(0.0);
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

/// A sink that places each entry at a given offset from the origin of another sink.
///
/// Used to assemble block matrices (for example `[dF/dx  dF/dz]`) from routines that each
/// write one block in their own local coordinates.
pub struct Offset<'a, S: MatrixSink + ?Sized> {
    inner: &'a mut S,
    row: usize,
    col: usize,
    rows: usize,
    cols: usize,
}

impl<'a, S: MatrixSink + ?Sized> Offset<'a, S> {
    /// The `rows x cols` block of `inner` whose top-left entry is `(row, col)`.
    ///
    /// # Panics
    /// If the block does not fit inside `inner` (a programming error of the caller, not
    /// something a model can cause).
    pub fn new(inner: &'a mut S, row: usize, col: usize, rows: usize, cols: usize) -> Self {
        assert!(
            row + rows <= inner.rows() && col + cols <= inner.cols(),
            "block {rows}x{cols} at ({row},{col}) does not fit a {}x{} sink",
            inner.rows(),
            inner.cols()
        );
        Self {
            inner,
            row,
            col,
            rows,
            cols,
        }
    }
}

impl<S: MatrixSink + ?Sized> MatrixSink for Offset<'_, S> {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        self.inner.set(self.row + row, self.col + col, value);
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self.inner.add(self.row + row, self.col + col, value);
    }
    fn fill_zero(&mut self) {
        for j in 0..self.cols {
            for i in 0..self.rows {
                self.inner.set(self.row + i, self.col + j, 0.0);
            }
        }
    }
}

/// A sink that discards everything, for callers that want only some of the blocks a
/// generated routine produces.
#[derive(Debug, Clone, Copy, Default)]
pub struct Discard {
    /// Reported row count.
    pub rows: usize,
    /// Reported column count.
    pub cols: usize,
}

impl MatrixSink for Discard {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    #[inline]
    fn set(&mut self, _: usize, _: usize, _: f64) {}
    #[inline]
    fn add(&mut self, _: usize, _: usize, _: f64) {}
    fn fill_zero(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    #[test]
    fn offset_writes_into_block() {
        let mut m = SMatrix::<f64, 3, 4>::zeros();
        {
            let mut blk = Offset::new(&mut m, 1, 2, 2, 2);
            blk.set(0, 0, 1.0);
            blk.add(1, 1, 2.0);
            blk.add(1, 1, 0.5);
        }
        assert_eq!(m[(1, 2)], 1.0);
        assert_eq!(m[(2, 3)], 2.5);
        assert_eq!(m.iter().filter(|v| **v != 0.0).count(), 2);
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
}
