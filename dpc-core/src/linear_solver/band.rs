//! Banded LU with partial pivoting for iteration matrices whose entries lie near the diagonal.
//!
//! Discretised PDEs (a grid numbered row by row) and chains of components give iteration
//! matrices with every entry within `kl` below and `ku` above the diagonal. Gaussian
//! elimination with row interchanges keeps the factors inside a band: `L` within `kl` below the
//! diagonal, `U` within `kl + ku` above it (an interchange can move a row up by at most `kl`).
//! The storage is LAPACK's band layout (`dgbtrf`): column `j` holds rows `j - kl - ku ..= j + kl`
//! contiguously, `2 kl + ku + 1` entries a column, the `kl` topmost for the fill-in of the
//! interchanges; the elimination is the right-looking one of the dense back ends restricted to
//! the band. A factorisation costs about `2 n kl (kl + ku)` operations and a solve
//! `2 n (2 kl + ku)`, against `2 n^3 / 3` and `2 n^2` for the dense LU.

use super::{FactorError, LinearSolver};
use crate::sink::MatrixSink;
use core::ops::{DivAssign, Mul, SubAssign};

/// An `n x n` matrix with entries only within `kl` below and `ku` above the diagonal, in band
/// storage; a [`MatrixSink`].
///
/// A write outside the band is not stored; the first one is remembered and reported by
/// [`BandLu::factor`] as [`FactorError::OutsidePattern`] (a non-zero value only, as for the
/// sparse back end's pattern).
#[derive(Debug, Clone)]
pub struct BandMatrix {
    n: usize,
    kl: usize,
    ku: usize,
    /// Column `j`, row `i` (`j - ku <= i <= j + kl`) at `j * (kl + ku + 1) + ku + i - j`.
    values: Vec<f64>,
    outside: Option<(usize, usize)>,
}

impl BandMatrix {
    /// An `n x n` zero matrix with half-bandwidths `kl`, `ku` (taken as at most `n - 1`).
    pub(crate) fn new(n: usize, kl: usize, ku: usize) -> Self {
        let (kl, ku) = (kl.min(n.saturating_sub(1)), ku.min(n.saturating_sub(1)));
        Self {
            n,
            kl,
            ku,
            values: vec![0.0; n * (kl + ku + 1)],
            outside: None,
        }
    }

    /// The first row of column `j` inside the band and the column's entries from there to the
    /// band's last row in the matrix, contiguous.
    pub(crate) fn column(&self, j: usize) -> (usize, &[f64]) {
        let first = j.saturating_sub(self.ku);
        let last = (j + self.kl).min(self.n - 1);
        let base = j * (self.kl + self.ku + 1) + self.ku;
        (first, &self.values[base + first - j..=base + last - j])
    }

    /// The first non-zero write outside the band since the last [`MatrixSink::fill_zero`].
    pub(crate) fn outside(&self) -> Option<(usize, usize)> {
        self.outside
    }

    /// Subtract `other` (of the same size and band) entry by entry.
    pub(crate) fn subtract(&mut self, other: &Self) {
        for (a, b) in self.values.iter_mut().zip(&other.values) {
            *a -= b;
        }
    }

    /// The slot of `(row, col)`, when it lies in the band.
    #[inline]
    fn slot(&self, row: usize, col: usize) -> Option<usize> {
        if row >= self.n || col >= self.n || row + self.ku < col || row > col + self.kl {
            return None;
        }
        Some(col * (self.kl + self.ku + 1) + self.ku + row - col)
    }

    /// The entry at `(row, col)` (zero outside the band).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.slot(row, col).map_or(0.0, |k| self.values[k])
    }

    /// The lower and upper half-bandwidths `(kl, ku)`.
    pub fn half_bandwidths(&self) -> (usize, usize) {
        (self.kl, self.ku)
    }
}

impl MatrixSink for BandMatrix {
    fn rows(&self) -> usize {
        self.n
    }
    fn cols(&self) -> usize {
        self.n
    }
    #[inline]
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
    #[inline]
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

/// Banded LU with partial pivoting, for iteration matrices with every entry within `kl` below
/// and `ku` above the diagonal (discretised PDEs on a grid numbered row by row, chains).
///
/// The factors stay inside a band: `L` within `kl` below the diagonal, `U` within `kl + ku`
/// above it (an interchange moves a row up by at most `kl`), in LAPACK's band layout
/// (`dgbtrf`): `2 kl + ku + 1` entries a column, the `kl` topmost for the interchanges'
/// fill-in. A factorisation costs about `2 n kl (kl + ku)` operations and a solve
/// `2 n (2 kl + ku)`, against `2 n^3 / 3` and `2 n^2` for the dense LU. The matrix, its
/// factors and the interchanges are allocated in [`BandLu::new`]; factorisations and solves
/// allocate nothing. A pivot that is exactly zero or not finite is reported as
/// [`FactorError::Singular`] (as faer's blocked dense LU does; no relative test), a
/// non-finite entry of the matrix as [`FactorError::NonFinite`].
#[derive(Debug, Clone)]
pub struct BandLu {
    matrix: BandMatrix,
    /// Column `j`, row `i` (`j - kl - ku <= i <= j + kl`) at `j * ld + kl + ku + i - j`.
    factors: Vec<f64>,
    /// `pivots[k]`: the row interchanged with row `k` at step `k`.
    pivots: Vec<usize>,
    factored: bool,
}

impl BandLu {
    /// A solver for `n x n` systems with entries only within `kl` below and `ku` above the
    /// diagonal (half-bandwidths beyond `n - 1` are taken as `n - 1`).
    pub fn new(n: usize, kl: usize, ku: usize) -> Self {
        let matrix = BandMatrix::new(n, kl, ku);
        let (kl, ku) = matrix.half_bandwidths();
        Self {
            matrix,
            factors: vec![0.0; n * (2 * kl + ku + 1)],
            pivots: vec![0; n],
            factored: false,
        }
    }

    /// A solver for the band that holds every `(row, col)` of `pattern` and the diagonal.
    ///
    /// # Errors
    /// [`FactorError::OutsidePattern`] if an index is not below `n`.
    pub fn for_pattern(n: usize, pattern: &[(usize, usize)]) -> Result<Self, FactorError> {
        let (kl, ku) = half_bandwidths(n, pattern)?;
        Ok(Self::new(n, kl, ku))
    }

    /// The lower and upper half-bandwidths `(kl, ku)`.
    pub fn half_bandwidths(&self) -> (usize, usize) {
        self.matrix.half_bandwidths()
    }
}

/// The lower and upper half-bandwidths `(kl, ku)` of `pattern` in an `n x n` matrix.
///
/// # Errors
/// [`FactorError::OutsidePattern`] if an index is not below `n`.
pub fn half_bandwidths(
    n: usize,
    pattern: &[(usize, usize)],
) -> Result<(usize, usize), FactorError> {
    let (mut kl, mut ku) = (0, 0);
    for &(row, col) in pattern {
        if row >= n || col >= n {
            return Err(FactorError::OutsidePattern { row, col });
        }
        kl = kl.max(row.saturating_sub(col));
        ku = ku.max(col.saturating_sub(row));
    }
    Ok((kl, ku))
}

impl LinearSolver for BandLu {
    type Matrix = BandMatrix;

    fn dimension(&self) -> usize {
        self.matrix.n
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        &mut self.matrix
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        self.factored = false;
        let m = &self.matrix;
        if let Some((row, col)) = m.outside {
            return Err(FactorError::OutsidePattern { row, col });
        }
        let (n, kl, ku) = (m.n, m.kl, m.ku);
        let (lda, ld, kv) = (kl + ku + 1, 2 * kl + ku + 1, kl + ku);
        // One pass without early exit (it vectorises), the position only when needed.
        if m.values.iter().fold(false, |bad, v| bad | !v.is_finite()) {
            let first = m.values.iter().position(|v| !v.is_finite()).unwrap_or(0);
            // Slot `ku + row - col` of column `col` (only slots inside the matrix are written).
            let (col, slot) = (first / lda, first % lda);
            return Err(FactorError::NonFinite {
                row: (col + slot).saturating_sub(ku),
                col,
            });
        }
        // The matrix below the fill-in rows of every column.
        for (f, a) in self
            .factors
            .chunks_exact_mut(ld)
            .zip(m.values.chunks_exact(lda))
        {
            f[..kl].fill(0.0);
            f[kl..].copy_from_slice(a);
        }
        let f = &mut self.factors;
        // The last column that the interchanges so far reach.
        let mut reach = 0;
        for j in 0..n {
            let below = kl.min(n - 1 - j);
            let col = j * ld + kv;
            let mut p = 0;
            let mut best = f[col].abs();
            for i in 1..=below {
                let v = f[col + i].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.pivots[j] = j + p;
            if best == 0.0 || !best.is_finite() {
                return Err(self.singular(j));
            }
            reach = reach.max((j + ku + p).min(n - 1));
            if p != 0 {
                // Rows j and j + p in columns j..=reach: entry (i, c) at c * ld + kv + i - c,
                // so column c's two entries are `ld - 1` apart per column to the right.
                for c in j..=reach {
                    let top = c * ld + kv + j - c;
                    f.swap(top, top + p);
                }
            }
            let d = 1.0 / f[col];
            for v in &mut f[col + 1..=col + below] {
                *v *= d;
            }
            if below == 0 {
                continue;
            }
            // Columns j+1..=reach: rows j+1..=j+below less the multipliers times row j.
            let (left, right) = f.split_at_mut((j + 1) * ld);
            let multipliers = &left[col + 1..=col + below];
            for (k, column) in right.chunks_exact_mut(ld).take(reach - j).enumerate() {
                let c = j + 1 + k;
                let top = kv + j - c;
                let u = column[top];
                if u != 0.0 {
                    for (v, l) in column[top + 1..=top + below].iter_mut().zip(multipliers) {
                        *v -= l * u;
                    }
                }
            }
        }
        self.factored = true;
        Ok(())
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        if !self.factored {
            return;
        }
        let (n, kl, ku) = (self.matrix.n, self.matrix.kl, self.matrix.ku);
        solve_band_factors(&self.factors, &self.pivots, n, kl, ku, b);
    }

    fn band(&self) -> Option<(usize, usize)> {
        Some(self.half_bandwidths())
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        let m = &self.matrix;
        let lda = m.kl + m.ku + 1;
        out.fill(0.0);
        for (j, (column, wj)) in m.values.chunks_exact(lda).zip(w).enumerate() {
            let first = j.saturating_sub(m.ku);
            let last = (j + m.kl).min(m.n - 1);
            for i in first..=last {
                let v = column[m.ku + i - j].abs() / wj;
                out[i] = out[i].max(v);
            }
        }
    }
}

/// Overwrite `b[..n]` with the solution of the system whose band factors `f` (LAPACK's layout,
/// `2 kl + ku + 1` entries a column, `kl + ku` above the diagonal) and row interchanges
/// `pivots` a banded elimination left: `L` with the interchanges in the order of the
/// factorisation, then `U` (upper bandwidth `kl + ku`). Real ([`BandLu`]) and complex (Radau's
/// stage system) alike; columns whose right-hand entry is zero are skipped.
pub(crate) fn solve_band_factors<T>(
    f: &[T],
    pivots: &[usize],
    n: usize,
    kl: usize,
    ku: usize,
    b: &mut [T],
) where
    T: Copy + Default + PartialEq + SubAssign + DivAssign + Mul<Output = T>,
{
    let (ld, kv) = (2 * kl + ku + 1, kl + ku);
    let b = &mut b[..n];
    let zero = T::default();
    for j in 0..n {
        let p = pivots[j];
        if p != j {
            b.swap(j, p);
        }
        let below = kl.min(n - 1 - j);
        let bj = b[j];
        if bj != zero && below > 0 {
            let col = j * ld + kv;
            for (bi, &l) in b[j + 1..=j + below]
                .iter_mut()
                .zip(&f[col + 1..=col + below])
            {
                *bi -= l * bj;
            }
        }
    }
    for j in (0..n).rev() {
        let col = j * ld + kv;
        b[j] /= f[col];
        let above = kv.min(j);
        let bj = b[j];
        if bj != zero && above > 0 {
            for (bi, &u) in b[j - above..j].iter_mut().zip(&f[col - above..col]) {
                *bi -= u * bj;
            }
        }
    }
}

impl BandLu {
    /// The typed error for a vanished (or overflowed) pivot in `column`, naming a zero row of
    /// the matrix when it has one.
    fn singular(&self, column: usize) -> FactorError {
        let m = &self.matrix;
        let row = (0..m.n).find(|&i| {
            let first = i.saturating_sub(m.kl);
            let last = (i + m.ku).min(m.n - 1);
            (first..=last).all(|j| m.get(i, j) == 0.0)
        });
        FactorError::Singular {
            column: Some(column),
            row,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear_solver::FaerDenseLu;

    /// Deterministic numbers in `[-1, 1)` (SplitMix64).
    struct Random(u64);
    impl Random {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 52) as f64 * 2.0 - 1.0
        }
    }

    /// A random `n x n` matrix with half-bandwidths `kl`, `ku`, its diagonal scaled by
    /// `diagonal` (small: the elimination must interchange rows), as `(row, col, value)`.
    fn random_band(
        n: usize,
        kl: usize,
        ku: usize,
        diagonal: f64,
        seed: u64,
    ) -> Vec<(usize, usize, f64)> {
        let mut r = Random(seed);
        let mut entries = Vec::new();
        for j in 0..n {
            for i in j.saturating_sub(ku)..=(j + kl).min(n - 1) {
                let v = r.next();
                entries.push((i, j, if i == j { diagonal * v } else { v }));
            }
        }
        entries
    }

    /// The band solver's and the dense LU's solutions of the same system, the band solution's
    /// backward error `max_i |b - A x|_i / max_i (|A| |x| + |b|)_i`, and whether the band
    /// solver interchanged rows.
    fn both(
        n: usize,
        kl: usize,
        ku: usize,
        diagonal: f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<f64>, f64, bool) {
        let entries = random_band(n, kl, ku, diagonal, seed);
        let mut band = BandLu::new(n, kl, ku);
        let mut dense = FaerDenseLu::new(n);
        band.matrix_mut().fill_zero();
        dense.matrix_mut().fill_zero();
        for &(i, j, v) in &entries {
            band.matrix_mut().set(i, j, v);
            dense.matrix_mut().set(i, j, v);
        }
        band.factor().expect("regular band matrix");
        dense.factor().expect("regular dense matrix");
        let mut r = Random(seed ^ 0xABCD);
        let b: Vec<f64> = (0..n).map(|_| r.next()).collect();
        let (mut x_band, mut x_dense) = (b.clone(), b.clone());
        band.solve_in_place(&mut x_band);
        dense.solve_in_place(&mut x_dense);
        let (mut residual, mut size) = (b.clone(), b.iter().map(|v| v.abs()).collect::<Vec<_>>());
        for &(i, j, v) in &entries {
            residual[i] -= v * x_band[j];
            size[i] += (v * x_band[j]).abs();
        }
        let worst = residual.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        let backward = worst / size.iter().fold(0.0f64, |m, s| m.max(*s));
        let pivoted = band.pivots.iter().enumerate().any(|(k, &p)| p != k);
        (x_band, x_dense, backward, pivoted)
    }

    #[test]
    fn agrees_with_the_dense_lu_on_random_band_matrices() {
        let mut pivoted_somewhere = false;
        let (mut seed, mut compared) = (1, 0);
        for &(n, kl, ku) in &[
            (1, 0, 0),
            (5, 1, 1),
            (12, 2, 3),
            (12, 3, 2),
            (30, 0, 4),
            (30, 4, 0),
            (40, 7, 7),
            (64, 10, 10),
            (100, 20, 5),
            (20, 25, 25),
        ] {
            for diagonal in [10.0, 1.0, 1e-3] {
                seed += 1;
                let (x_band, x_dense, backward, pivoted) = both(n, kl, ku, diagonal, seed);
                pivoted_somewhere |= pivoted;
                // Backward stable: the residual a few roundings of the terms.
                assert!(
                    backward <= 64.0 * f64::EPSILON,
                    "n {n}, kl {kl}, ku {ku}, diagonal {diagonal}: backward error {backward:e}"
                );
                // The dense LU's solution where the random matrix is well conditioned (a
                // solution below 1e4 for a right-hand side below 1; the triangular bands with
                // a small diagonal reach 1e22).
                let scale = x_dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if scale > 1e4 {
                    continue;
                }
                compared += 1;
                for (a, b) in x_band.iter().zip(&x_dense) {
                    assert!(
                        (a - b).abs() <= 1e-10 * scale,
                        "n {n}, kl {kl}, ku {ku}, diagonal {diagonal}: {a} against {b}"
                    );
                }
            }
        }
        assert!(compared >= 20, "{compared} of 30 cases compared");
        assert!(pivoted_somewhere, "no case interchanged rows");
    }

    #[test]
    fn interchanges_rows_when_the_diagonal_vanishes() {
        // [[0, 1], [2, 3]] x = [1, 8]: x = (2.5, 1); the first pivot is row 1.
        let mut lu = BandLu::new(2, 1, 1);
        lu.matrix_mut().set(0, 1, 1.0);
        lu.matrix_mut().set(1, 0, 2.0);
        lu.matrix_mut().set(1, 1, 3.0);
        lu.factor().expect("regular");
        assert_eq!(lu.pivots[0], 1);
        let mut b = [1.0, 8.0];
        lu.solve_in_place(&mut b);
        assert_eq!(b, [2.5, 1.0]);
    }

    #[test]
    fn a_singular_matrix_is_reported_with_its_zero_row() {
        let mut lu = BandLu::new(4, 1, 1);
        for k in 0..4 {
            if k != 2 {
                lu.matrix_mut().set(k, k, 1.0);
            }
        }
        // Row 2 and column 2 are empty.
        assert_eq!(
            lu.factor(),
            Err(FactorError::Singular {
                column: Some(2),
                row: Some(2)
            })
        );
        // Solving after a failed factorisation leaves b alone.
        let mut b = [1.0; 4];
        lu.solve_in_place(&mut b);
        assert_eq!(b, [1.0; 4]);
    }

    #[test]
    fn a_non_finite_entry_is_reported_at_its_position() {
        let mut lu = BandLu::new(3, 1, 1);
        for k in 0..3 {
            lu.matrix_mut().set(k, k, 1.0);
        }
        for (bad, (i, j)) in [(f64::NAN, (2, 1)), (f64::INFINITY, (0, 1))] {
            lu.matrix_mut().set(i, j, bad);
            assert_eq!(lu.factor(), Err(FactorError::NonFinite { row: i, col: j }));
            lu.matrix_mut().set(i, j, 0.0);
        }
    }

    #[test]
    fn a_write_outside_the_band_is_reported() {
        let mut lu = BandLu::new(5, 1, 2);
        lu.matrix_mut().fill_zero();
        for k in 0..5 {
            lu.matrix_mut().set(k, k, 1.0);
        }
        // A zero outside the band is no entry; a non-zero one is an error.
        lu.matrix_mut().set(4, 0, 0.0);
        assert!(lu.factor().is_ok());
        lu.matrix_mut().add(0, 3, 1.0);
        assert_eq!(
            lu.factor(),
            Err(FactorError::OutsidePattern { row: 0, col: 3 })
        );
        lu.matrix_mut().fill_zero();
        for k in 0..5 {
            lu.matrix_mut().set(k, k, 2.0);
        }
        assert!(lu.factor().is_ok());
    }

    #[test]
    fn half_bandwidths_of_a_pattern() {
        let p = [(0, 0), (3, 1), (1, 4), (2, 2)];
        assert_eq!(half_bandwidths(5, &p), Ok((2, 3)));
        assert_eq!(
            half_bandwidths(3, &p),
            Err(FactorError::OutsidePattern { row: 3, col: 1 })
        );
        let lu = BandLu::for_pattern(5, &p).expect("in range");
        assert_eq!(lu.half_bandwidths(), (2, 3));
    }

    #[test]
    fn scaled_row_norms_read_the_band() {
        let mut lu = BandLu::new(3, 1, 1);
        lu.matrix_mut().set(0, 0, 2.0);
        lu.matrix_mut().set(0, 1, -6.0);
        lu.matrix_mut().set(1, 0, 1.0);
        lu.matrix_mut().set(2, 2, 4.0);
        let mut out = [0.0; 3];
        lu.scaled_row_norms(&[1.0, 2.0, 4.0], &mut out);
        assert_eq!(out, [3.0, 1.0, 1.0]);
    }
}
