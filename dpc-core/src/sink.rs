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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

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
