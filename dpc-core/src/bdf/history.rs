//! The integrators' history: a fixed number of vectors of the problem's dimension in one
//! contiguous buffer (column `j` at `j n .. (j + 1) n`), allocated once.

/// `columns` vectors of length `n`, stored one after the other.
#[derive(Debug, Clone)]
pub(crate) struct History {
    n: usize,
    data: Vec<f64>,
}

impl History {
    /// `columns` zero vectors of length `n`.
    pub fn new(columns: usize, n: usize) -> Self {
        Self {
            n,
            data: vec![0.0; columns * n],
        }
    }

    /// Column `j`.
    #[inline]
    pub fn col(&self, j: usize) -> &[f64] {
        &self.data[j * self.n..(j + 1) * self.n]
    }

    /// Column `j`, mutable.
    #[inline]
    pub fn col_mut(&mut self, j: usize) -> &mut [f64] {
        &mut self.data[j * self.n..(j + 1) * self.n]
    }

    /// Column `j` mutable with column `k > j` shared.
    #[inline]
    pub fn pair_mut(&mut self, j: usize, k: usize) -> (&mut [f64], &[f64]) {
        debug_assert!(j < k);
        let n = self.n;
        let (lo, hi) = self.data.split_at_mut(k * n);
        (&mut lo[j * n..(j + 1) * n], &hi[..n])
    }

    /// Multiply column `j` by `s`.
    #[inline]
    pub fn scale(&mut self, j: usize, s: f64) {
        self.col_mut(j).iter_mut().for_each(|v| *v *= s);
    }
}
