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

    /// Multiply column `j` by `s`.
    #[inline]
    pub fn scale(&mut self, j: usize, s: f64) {
        self.col_mut(j).iter_mut().for_each(|v| *v *= s);
    }

    /// The update of the modified divided differences after an accepted step of order `K`
    /// with correction `e`: column `K + 1` becomes `e` when `next` (below the maximum order),
    /// column `K` gains `e`, then each column `j < K` gains column `j + 1`, from `K - 1` down
    /// to 0. One pass over the components, per component the same additions in the same order
    /// as one pass per column (the same values to the bit).
    pub fn accept<const K: usize>(&mut self, e: &[f64], next: bool) {
        let n = self.n;
        let e = &e[..n];
        let (head, tail) = self.data.split_at_mut((K + 1) * n);
        let (col0, mut rest) = head.split_at_mut(n);
        let col0 = &mut col0[..n];
        // Columns 1..=K.
        let cols: [&mut [f64]; K] = std::array::from_fn(|_| {
            let (c, r) = std::mem::take(&mut rest).split_at_mut(n);
            rest = r;
            c
        });
        if next {
            tail[..n].copy_from_slice(e);
        }
        for i in 0..n {
            let mut acc = cols[K - 1][i] + e[i];
            cols[K - 1][i] = acc;
            for j in (0..K - 1).rev() {
                acc += cols[j][i];
                cols[j][i] = acc;
            }
            col0[i] += acc;
        }
    }
}
