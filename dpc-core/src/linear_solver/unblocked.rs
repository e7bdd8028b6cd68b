//! Unblocked dense LU with partial pivoting for small matrices, shared by the dense back ends.
//!
//! For the 5x5 to 16x16 iteration matrices of generated models the textbook right-looking
//! elimination (Golub & Van Loan, *Matrix Computations*, Algorithm 3.4.1) on a contiguous
//! column-major array beats a blocked factorisation, whose set-up and dispatch cost more than
//! the arithmetic at these sizes. Both [`super::NalgebraLu`] and [`super::FaerDenseLu`] (up to
//! [`UNBLOCKED_MAX_DIMENSION`]) factorise with [`factor`] and solve with [`solve`]: below
//! [`SPLIT_FROM`] with its steps unrolled ([`factor_columns`]), [`super::NalgebraLu`] from
//! [`SPLIT_FROM`] on with the same elimination in full-length column updates
//! ([`factor_split_fixed`], [`solve_split_fixed`]). None allocates.

/// Largest dimension for which [`super::FaerDenseLu`] uses this unblocked LU instead of
/// faer's blocked one ([`super::NalgebraLu`] always uses it).
pub const UNBLOCKED_MAX_DIMENSION: usize = 16;

/// A pivot is treated as zero when its magnitude is at most this many machine epsilons per
/// row, relative to the magnitude of the terms it was computed from: the elimination cannot
/// tell such a pivot from their round-off.
const SINGULAR_PIVOT_EPSILONS: f64 = 1.0;

/// Why a factorisation stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub(crate) enum Breakdown {
    /// A pivot vanished relative to the norm of what it was computed from (or the elimination
    /// overflowed).
    #[error("the pivot of column {column} vanishes relative to the entries it was computed from")]
    Pivot {
        /// The column whose pivot vanished.
        column: usize,
    },
    /// An entry of the matrix as given is NaN or infinite (the first in column-major order).
    #[error("entry ({row}, {column}) is not finite")]
    NonFinite {
        /// Its row.
        row: usize,
        /// Its column.
        column: usize,
    },
}

impl Breakdown {
    /// The linear solver's error, with the zero row of the matrix as given (`entry(i, j)`) for
    /// a vanished pivot.
    pub(crate) fn into_factor_error(
        self,
        n: usize,
        entry: impl Fn(usize, usize) -> f64,
    ) -> super::FactorError {
        match self {
            Self::Pivot { column } => super::FactorError::Singular {
                column: Some(column),
                row: super::zero_row(n, entry),
            },
            Self::NonFinite { row, column } => super::FactorError::NonFinite { row, col: column },
        }
    }

    /// The first non-finite entry of the `n x n` column-major matrix whose entries `entries`
    /// iterates, if any.
    pub(crate) fn non_finite<'a>(
        mut entries: impl Iterator<Item = &'a f64> + Clone,
        n: usize,
    ) -> Option<Self> {
        // One pass without early exit (it vectorises), the position only when needed.
        if !entries.clone().fold(false, |bad, v| bad | !v.is_finite()) {
            return None;
        }
        let first = entries.position(|v| !v.is_finite()).unwrap_or(0);
        Some(Self::NonFinite {
            row: first % n,
            column: first / n,
        })
    }
}

/// Factorise the `n x n` column-major matrix in `a` in place as `P A = L U`: `L` unit lower
/// triangular below the diagonal, `U` on and above it, `pivots[k]` the row interchanged with
/// row `k` at step `k` (LAPACK's `ipiv`, zero-based).
///
/// A pivot `u_kk` is numerically zero when `|u_kk| <= n eps s_k`, with
/// `s_k = |u_kk| + sum_{m<k} |l_km| |u_mk|` the norm of the terms whose sum it is
/// (`a_kk = u_kk + sum l_km u_mk` after the interchanges): the pivot is then the round-off
/// left by cancellation, as in an exactly singular matrix. The test is invariant under row and
/// column scaling, so the widely scaled iteration matrices of index-3 problems at small steps
/// (condition `O(h^-3)`, pivots of order `h^2` beside entries of order `1/h`, computed
/// without cancellation) stay regular.
///
/// # Errors
/// [`Breakdown`] when a pivot is numerically zero (exactly zero included) or an entry is
/// not finite; `a` then holds a partial factorisation.
///
/// # Panics
/// If `a` is shorter than `n * n` or `pivots` shorter than `n` (a caller's sizing bug).
#[inline(always)]
pub(crate) fn factor(a: &mut [f64], n: usize, pivots: &mut [usize]) -> Result<(), Breakdown> {
    factor_by(a, n, pivots, |col_k, right, k| {
        let multipliers = &col_k[k + 1..];
        for col in right.chunks_exact_mut(n) {
            let akj = col[k];
            if akj != 0.0 {
                for (c, l) in col[k + 1..].iter_mut().zip(multipliers) {
                    *c -= l * akj;
                }
            }
        }
    })
}

/// [`factor`] for a compile-time `N` with every column update over all `N` rows: the
/// multipliers are copied into a column padded with zeros on and above row `k`, so that the
/// update has a trip count known at compile time and unrolls into full-width vector operations
/// (rows `0..=k` take exact zeros). The same factors as [`factor`] up to the sign of zero
/// entries, then split for [`solve_split_fixed`] (see [`split`]). In 256-bit instructions
/// (AVX) where the processor has them (used from [`SPLIT_FROM`] on).
///
/// # Errors
/// As [`factor`].
#[inline(always)]
pub(crate) fn factor_split_fixed<const N: usize>(
    a: &mut [f64],
    pivots: &mut [usize; N],
    upper: &mut [f64],
    diag: &mut [f64; N],
) -> Result<(), Breakdown> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: `factor_split_avx` only requires AVX, which the processor was just found to
        // have.
        return unsafe { factor_split_avx::<N>(a, pivots, upper, diag) };
    }
    factor_split::<N>(a, pivots, upper, diag)
}

/// [`factor_split_fixed`] compiled with AVX enabled.
///
/// # Safety
/// The processor must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn factor_split_avx<const N: usize>(
    a: &mut [f64],
    pivots: &mut [usize; N],
    upper: &mut [f64],
    diag: &mut [f64; N],
) -> Result<(), Breakdown> {
    factor_split::<N>(a, pivots, upper, diag)
}

/// See [`factor_split_fixed`].
#[inline(always)]
fn factor_split<const N: usize>(
    a: &mut [f64],
    pivots: &mut [usize; N],
    upper: &mut [f64],
    diag: &mut [f64; N],
) -> Result<(), Breakdown> {
    let mut padded = [0.0; N];
    factor_by(a, N, pivots, |col_k, right, k| {
        for (i, m) in padded.iter_mut().enumerate() {
            *m = if i > k { col_k[i] } else { 0.0 };
        }
        for col in right.chunks_exact_mut(N) {
            let akj = col[k];
            if akj != 0.0 {
                for (c, l) in col.iter_mut().zip(&padded) {
                    *c -= l * akj;
                }
            }
        }
    })?;
    split(a, N, upper, diag);
    Ok(())
}

/// The elimination of [`factor`] with the update of the columns right of `k` left to
/// `eliminate(column k, columns k+1.., k)`, called once the pivot is in place and the
/// multipliers are scaled (below the diagonal of column `k`).
#[inline(always)]
fn factor_by(
    a: &mut [f64],
    n: usize,
    pivots: &mut [usize],
    mut eliminate: impl FnMut(&[f64], &mut [f64], usize),
) -> Result<(), Breakdown> {
    let a = &mut a[..n * n];
    let pivots = &mut pivots[..n];
    if let Some(e) = Breakdown::non_finite(a.iter(), n) {
        return Err(e);
    }
    let round_off = SINGULAR_PIVOT_EPSILONS * n as f64 * f64::EPSILON;
    for k in 0..n {
        let (left, right) = a.split_at_mut((k + 1) * n);
        let col_k = &mut left[k * n..];
        let mut pivot_row = k;
        let mut best = col_k[k].abs();
        for (i, v) in col_k.iter().enumerate().skip(k + 1) {
            if v.abs() > best {
                best = v.abs();
                pivot_row = i;
            }
        }
        pivots[k] = pivot_row;
        if pivot_row != k {
            for col in left.chunks_exact_mut(n).chain(right.chunks_exact_mut(n)) {
                col.swap(k, pivot_row);
            }
        }
        let (lower, col_k) = left.split_at_mut(k * n);
        // The terms l_km u_mk that were subtracted from the pivot's original entry.
        let subtracted: f64 = lower
            .chunks_exact(n)
            .zip(col_k.iter())
            .map(|(col_m, u_mk)| (col_m[k] * u_mk).abs())
            .sum();
        // Overflow in the elimination shows as a non-finite pivot or sum.
        let regular = best.is_finite() && best > round_off * (best + subtracted);
        if !regular {
            return Err(Breakdown::Pivot { column: k });
        }
        let d = 1.0 / col_k[k];
        for v in &mut col_k[k + 1..] {
            *v *= d;
        }
        eliminate(col_k, right, k);
    }
    Ok(())
}

/// [`factor`] for a compile-time `N` below [`SPLIT_FROM`] on an array of `N` columns: the
/// same elimination, pivots, test of a numerically zero pivot and factors (the same operations
/// in the same order, so the same numbers), with every step `k` inlined with `k` a literal, so
/// that all loop bounds are constants and the compiler unrolls the short loops that [`factor`]
/// runs through iterator set-up. The charge pump's 9 x 9 factorisation: 3 340 -> 1 300
/// instructions, its BDF run 8 % less time; from [`SPLIT_FROM`] on, the split elimination
/// takes less time (the NAND gate's 14 x 14 unrolled: 26 % fewer instructions but 1 % more
/// time, the slider crank's 24 x 24 likewise).
///
/// # Errors
/// As [`factor`].
#[inline(always)]
pub(crate) fn factor_columns<const N: usize>(
    a: &mut [[f64; N]; N],
    pivots: &mut [usize; N],
) -> Result<(), Breakdown> {
    if let Some(e) = Breakdown::non_finite(a.iter().flatten(), N) {
        return Err(e);
    }
    let round_off = SINGULAR_PIVOT_EPSILONS * N as f64 * f64::EPSILON;
    macro_rules! steps {
        ($($k:literal)*) => {
            $(if $k < N {
                elimination_step::<N>(a, pivots, $k, round_off)?;
            })*
        };
    }
    steps!(0 1 2 3 4 5 6 7 8);
    // Beyond the literal steps (not used by NalgebraLu, which splits from SPLIT_FROM on).
    for k in 9..N {
        elimination_step::<N>(a, pivots, k, round_off)?;
    }
    Ok(())
}

/// Step `k` of [`factor_columns`]: the pivot, the interchange, the test, the multipliers and
/// the update of the columns right of `k`. Index loops on purpose: with `k` a literal their
/// bounds are constants, which is what lets them unroll.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn elimination_step<const N: usize>(
    a: &mut [[f64; N]; N],
    pivots: &mut [usize; N],
    k: usize,
    round_off: f64,
) -> Result<(), Breakdown> {
    let mut pivot_row = k;
    let mut best = a[k][k].abs();
    for i in k + 1..N {
        let v = a[k][i].abs();
        if v > best {
            best = v;
            pivot_row = i;
        }
    }
    pivots[k] = pivot_row;
    if pivot_row != k {
        for col in a.iter_mut() {
            col.swap(k, pivot_row);
        }
    }
    // The terms l_km u_mk that were subtracted from the pivot's original entry.
    let mut subtracted = 0.0;
    for m in 0..k {
        subtracted += (a[m][k] * a[k][m]).abs();
    }
    let regular = best.is_finite() && best > round_off * (best + subtracted);
    if !regular {
        return Err(Breakdown::Pivot { column: k });
    }
    let (left, right) = a.split_at_mut(k + 1);
    let col_k = &mut left[k];
    let d = 1.0 / col_k[k];
    for i in k + 1..N {
        col_k[i] *= d;
    }
    for col in right.iter_mut() {
        let akj = col[k];
        if akj != 0.0 {
            for i in k + 1..N {
                col[i] -= col_k[i] * akj;
            }
        }
    }
    Ok(())
}

/// Overwrite `b` with the solution of `A x = b` from a factorisation by [`factor`].
///
/// # Panics
/// If `lu`, `pivots` or `b` are shorter than `n * n`, `n`, `n`.
#[inline(always)]
pub(crate) fn solve(lu: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    let lu = &lu[..n * n];
    let b = &mut b[..n];
    for (k, &p) in pivots[..n].iter().enumerate() {
        if p != k {
            b.swap(k, p);
        }
    }
    // Columns by offset (not `chunks_exact`, whose count is an integer division by the
    // run-time `n`, a noticeable part of a 5x5 solve).
    for j in 0..n {
        let col = &lu[j * n..j * n + n];
        let bj = b[j];
        if bj != 0.0 {
            for (bi, l) in b[j + 1..].iter_mut().zip(&col[j + 1..]) {
                *bi -= l * bj;
            }
        }
    }
    for j in (0..n).rev() {
        let col = &lu[j * n..j * n + n];
        b[j] /= col[j];
        let bj = b[j];
        if bj != 0.0 {
            for (bi, u) in b[..j].iter_mut().zip(&col[..j]) {
                *bi -= u * bj;
            }
        }
    }
}

/// The dimension from which [`super::NalgebraLu`] factorises with [`factor_split_fixed`] and
/// solves with [`solve_split_fixed`]. Below it the full-length updates cost more than the
/// loops they replace (the wheel's closed loop, 5 x 5 and 7 x 7 systems, 1.1 % more
/// instructions; per BDF corrector solve, HIRES and the transistor amplifier (8 x 8) 5.5 %
/// more, the charge pump (9 x 9) 6 % more); at 10 x 10 they are even (the car axis, 1.4 %
/// fewer), and from there they cost less (the NAND gate's 14 x 14: solves 5.7 M -> 3.1 M
/// instructions, factorisations 4.7 M -> 3.6 M, the run 9.5 % fewer).
pub(crate) const SPLIT_FROM: usize = 10;

/// [`solve`] from the factors split by [`split`]: `lower` holds `L` below the diagonal and
/// zeros on and above it, `upper` holds `U` above the diagonal and zeros on and below it,
/// `diag` the diagonal of `U`. Every column update then runs from (or to) the block of four
/// rows that holds the triangle's first (last) entry of the column, adding exact zeros in the
/// rest of that block; for the first 32 columns the column index is a literal, so these bounds
/// are constants and the compiler unrolls the updates into full-width vector operations: no
/// loop set-up, no remainder per column. The same result as [`solve`] up to the sign of zero
/// entries when `b` is finite; in 256-bit instructions (AVX) where the processor has them
/// (used from [`SPLIT_FROM`] on). Skipping the blocks of zeros (each update ran over all `N`
/// rows before) took the slider crank's BDF runs (24 x 24) 20-25 % less time, the NAND gate's
/// (14 x 14) and the stabilised car axis' 15-20 % less.
#[inline(always)]
pub(crate) fn solve_split_fixed<const N: usize>(
    lower: &[f64],
    upper: &[f64],
    diag: &[f64; N],
    pivots: &[usize; N],
    b: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: `solve_split_avx` only requires AVX, which the processor was just found to
        // have.
        unsafe { solve_split_avx::<N>(lower, upper, diag, pivots, b) };
        return;
    }
    solve_split::<N>(lower, upper, diag, pivots, b)
}

/// [`solve_split_fixed`] compiled with AVX enabled.
///
/// # Safety
/// The processor must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn solve_split_avx<const N: usize>(
    lower: &[f64],
    upper: &[f64],
    diag: &[f64; N],
    pivots: &[usize; N],
    b: &mut [f64],
) {
    solve_split::<N>(lower, upper, diag, pivots, b)
}

/// See [`solve_split_fixed`].
///
/// # Panics
/// If `lower` or `upper` are shorter than `N * N` or `b` shorter than `N`.
#[inline(always)]
fn solve_split<const N: usize>(
    lower: &[f64],
    upper: &[f64],
    diag: &[f64; N],
    pivots: &[usize; N],
    b: &mut [f64],
) {
    let b = &mut b[..N];
    let (lower, upper) = (&lower[..N * N], &upper[..N * N]);
    for (k, &p) in pivots.iter().enumerate() {
        if p != k {
            b.swap(k, p);
        }
    }
    // Column `j` of `lower` is zero above row `j + 1` and column `j` of `upper` from row `j`
    // on: each update starts (or ends) at the block of four rows that holds its first (last)
    // entry, a bound that is a constant when `j` is a literal (the columns below).
    let forward = |b: &mut [f64], j: usize| {
        let col = &lower[j * N..(j + 1) * N];
        let bj = b[j];
        let start = (j + 1) / 4 * 4;
        for (bi, l) in b[start..].iter_mut().zip(&col[start..]) {
            *bi -= l * bj;
        }
    };
    let backward = |b: &mut [f64], j: usize| {
        let col = &upper[j * N..(j + 1) * N];
        b[j] /= diag[j];
        let bj = b[j];
        let end = (j.div_ceil(4) * 4).min(N);
        for (bi, u) in b[..end].iter_mut().zip(&col[..end]) {
            *bi -= u * bj;
        }
    };
    macro_rules! columns {
        ($step:ident, $($j:literal)*) => {
            $(if $j < N {
                $step(b, $j);
            })*
        };
    }
    columns!(forward, 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31);
    for j in 32..N {
        forward(b, j);
    }
    for j in (32..N).rev() {
        backward(b, j);
    }
    columns!(backward, 31 30 29 28 27 26 25 24 23 22 21 20 19 18 17 16 15 14 13 12 11 10 9 8 7 6 5 4 3 2 1 0);
}

/// Split a factorisation by [`factor`] in `lu` (`n x n`, column-major) into the strictly lower
/// part, left in `lu`, the strictly upper part, written to `upper`, and the diagonal, written
/// to `diag` (the layout of [`solve_split_fixed`]).
pub(crate) fn split(lu: &mut [f64], n: usize, upper: &mut [f64], diag: &mut [f64]) {
    for (j, (col, up)) in lu[..n * n]
        .chunks_exact_mut(n)
        .zip(upper[..n * n].chunks_exact_mut(n))
        .enumerate()
    {
        up[..j].copy_from_slice(&col[..j]);
        up[j..].fill(0.0);
        diag[j] = col[j];
        col[..=j].fill(0.0);
    }
}

/// [`factor`] with `n` turned into a constant for each size up to
/// [`UNBLOCKED_MAX_DIMENSION`], so that a run-time dimension gets the same unrolled loops as a
/// compile-time one (for `n = 5` the generic loops spent about 600 instructions per solve in
/// loop set-up; see `docs/performance.md`).
pub(crate) fn factor_dispatched(
    a: &mut [f64],
    n: usize,
    pivots: &mut [usize],
) -> Result<(), Breakdown> {
    macro_rules! sizes {
        ($($c:literal)*; $($k:literal)*) => {
            match n {
                $($c => factor_slice::<$c>(a, pivots),)*
                $($k => factor(a, $k, pivots),)*
                _ => factor(a, n, pivots),
            }
        };
    }
    // Below SPLIT_FROM the unrolled elimination of the fixed-size solver, above it the loops.
    sizes!(1 2 3 4 5 6 7 8 9; 10 11 12 13 14 15 16)
}

/// [`factor_columns`] on the first `N * N` entries of a column-major slice.
///
/// # Panics
/// If `a` is shorter than `N * N` or `pivots` shorter than `N` (a caller's sizing bug).
#[inline(always)]
fn factor_slice<const N: usize>(a: &mut [f64], pivots: &mut [usize]) -> Result<(), Breakdown> {
    let (columns, _) = a[..N * N].as_chunks_mut::<N>();
    let columns: &mut [[f64; N]; N] = columns.try_into().expect("N columns of N entries");
    let pivots: &mut [usize; N] = (&mut pivots[..N]).try_into().expect("N pivots");
    factor_columns(columns, pivots)
}

/// [`solve`] with `n` turned into a constant, as [`factor_dispatched`].
pub(crate) fn solve_dispatched(lu: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    macro_rules! sizes {
        ($($k:literal)*) => {
            match n {
                $($k => solve(lu, $k, pivots, b),)*
                _ => solve(lu, n, pivots, b),
            }
        };
    }
    sizes!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Column-major `n x n` matrix from a row-major literal.
    fn column_major(rows: &[&[f64]]) -> Vec<f64> {
        let n = rows.len();
        (0..n * n).map(|k| rows[k % n][k / n]).collect()
    }

    fn multiply(a: &[f64], n: usize, x: &[f64]) -> Vec<f64> {
        (0..n)
            .map(|i| (0..n).map(|j| a[i + j * n] * x[j]).sum())
            .collect()
    }

    /// A 12 x 12 random matrix with a zero entry (an update the elimination skips) and a
    /// sparse column.
    fn random_12() -> Vec<f64> {
        let n = 12;
        let mut state = 1u64;
        let mut a: Vec<f64> = (0..n * n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        a[3 * n + 1] = 0.0;
        for i in 0..n - 2 {
            a[7 * n + i] = 0.0;
        }
        a
    }

    #[test]
    fn the_split_factors_and_solve_equal_the_generic_ones() {
        // 12 x 12 with interchanges (AVX from N = 8 where available). The full-length updates
        // add exact zeros outside the triangles: the same numbers, up to the sign of zeros.
        const N: usize = 12;
        let a = random_12();
        let mut lu = a.clone();
        let mut pivots = [0; N];
        factor(&mut lu, N, &mut pivots).expect("regular");
        assert!(pivots.iter().enumerate().any(|(k, &p)| p != k));
        let (mut lower, mut upper, mut diag, mut split_pivots) =
            (a.clone(), vec![0.0; N * N], [0.0; N], [0; N]);
        factor_split_fixed::<N>(&mut lower, &mut split_pivots, &mut upper, &mut diag)
            .expect("regular");
        assert_eq!(pivots, split_pivots);
        for j in 0..N {
            for i in 0..N {
                let (want, got) = match i.cmp(&j) {
                    std::cmp::Ordering::Greater => (lu[j * N + i], lower[j * N + i]),
                    std::cmp::Ordering::Less => (lu[j * N + i], upper[j * N + i]),
                    std::cmp::Ordering::Equal => (lu[j * N + i], diag[j]),
                };
                assert!(want == got, "({i}, {j}): {want} vs {got}");
                if i != j {
                    // The other triangle holds zeros.
                    let other = if i > j {
                        upper[j * N + i]
                    } else {
                        lower[j * N + i]
                    };
                    assert_eq!(other, 0.0);
                }
            }
        }
        let b: Vec<f64> = (0..N).map(|i| (0.7 * i as f64).sin()).collect();
        let (mut generic, mut split) = (b.clone(), b.clone());
        solve(&lu, N, &pivots, &mut generic);
        solve_split_fixed::<N>(&lower, &upper, &diag, &pivots, &mut split);
        for (g, s) in generic.iter().zip(&split) {
            assert!(g == s, "{g} vs {s}");
        }
        let residual = multiply(&a, N, &split);
        for (r, want) in residual.iter().zip(&b) {
            assert!((r - want).abs() < 1e-12, "{r} vs {want}");
        }
    }

    /// The split solve against the generic one from the same factors, on an `N x N` random
    /// matrix: equal numbers (the skipped blocks hold exact zeros).
    fn split_solve_equals_generic<const N: usize>() {
        let mut state = N as u64;
        let a: Vec<f64> = (0..N * N)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let (mut lu, mut pivots) = (a.clone(), [0; N]);
        factor(&mut lu, N, &mut pivots).expect("regular");
        let (mut lower, mut upper, mut diag) = (lu.clone(), vec![0.0; N * N], [0.0; N]);
        split(&mut lower, N, &mut upper, &mut diag);
        let b: Vec<f64> = (0..N).map(|i| (0.7 * i as f64).sin()).collect();
        let (mut generic, mut split) = (b.clone(), b.clone());
        solve(&lu, N, &pivots, &mut generic);
        solve_split_fixed::<N>(&lower, &upper, &diag, &pivots, &mut split);
        for (g, s) in generic.iter().zip(&split) {
            assert!(g == s, "N = {N}: {g} vs {s}");
        }
    }

    #[test]
    fn the_split_solve_equals_the_generic_one_in_and_beyond_its_literal_columns() {
        split_solve_equals_generic::<10>();
        split_solve_equals_generic::<13>();
        split_solve_equals_generic::<31>();
        split_solve_equals_generic::<32>();
        split_solve_equals_generic::<33>();
        split_solve_equals_generic::<41>();
    }

    #[test]
    fn the_split_factorisation_reports_what_the_generic_one_does() {
        // A non-finite entry names its column; a singular matrix the column of the vanishing
        // pivot, as `factor` does.
        const N: usize = 12;
        let (mut upper, mut diag, mut pivots) = (vec![0.0; N * N], [0.0; N], [0; N]);
        let mut a = random_12();
        a[5 * N + 2] = f64::NAN;
        let got = factor_split_fixed::<N>(&mut a, &mut pivots, &mut upper, &mut diag);
        assert_eq!(got, Err(Breakdown::NonFinite { row: 2, column: 5 }));
        let mut a = random_12();
        // Column 9 = column 2 + column 4: rank 11.
        for i in 0..N {
            a[9 * N + i] = a[2 * N + i] + a[4 * N + i];
        }
        let mut generic = a.clone();
        let mut generic_pivots = [0; N];
        let want = factor(&mut generic, N, &mut generic_pivots);
        let got = factor_split_fixed::<N>(&mut a, &mut pivots, &mut upper, &mut diag);
        assert!(want.is_err());
        assert_eq!(got, want);
    }

    /// `factor_slice::<N>` against `factor` on the leading `N x N` block of `random_12()`:
    /// the same factors and pivots bit for bit, and the same error on a singular matrix.
    fn unrolled_equals_generic<const N: usize>() {
        let full = random_12();
        let a: Vec<f64> = (0..N * N).map(|k| full[(k / N) * 12 + k % N]).collect();
        let (mut want, mut got) = (a.clone(), a.clone());
        let (mut want_pivots, mut got_pivots) = ([0; N], [0; N]);
        let want_result = factor(&mut want, N, &mut want_pivots);
        let got_result = factor_slice::<N>(&mut got, &mut got_pivots);
        assert_eq!(got_result, want_result, "N = {N}");
        assert_eq!(got_pivots, want_pivots, "N = {N}");
        assert!(
            got.iter()
                .zip(&want)
                .all(|(g, w)| g.to_bits() == w.to_bits()),
            "N = {N}"
        );
        if N > 2 {
            // The last column a copy of the first: the vanishing pivot's column, as `factor`.
            let mut singular = a.clone();
            for i in 0..N {
                singular[(N - 1) * N + i] = a[i];
            }
            let mut generic = singular.clone();
            let want = factor(&mut generic, N, &mut want_pivots);
            assert!(want.is_err(), "N = {N}");
            assert_eq!(factor_slice::<N>(&mut singular, &mut got_pivots), want);
        }
    }

    #[test]
    fn the_unrolled_factorisation_equals_the_generic_one() {
        // Every size it serves (through `factor_dispatched` and NalgebraLu), and one beyond
        // its literal steps.
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
        let mut a = random_12()[..81].to_vec();
        a[4 * 9 + 7] = f64::INFINITY;
        assert_eq!(
            factor_slice::<9>(&mut a, &mut [0; 9]),
            Err(Breakdown::NonFinite { row: 7, column: 4 })
        );
    }

    #[test]
    fn solves_a_system_that_needs_pivoting() {
        let a = column_major(&[
            &[0.0, 2.0, 1.0, 0.0],
            &[1.0, 0.0, 0.0, 3.0],
            &[4.0, 1.0, -1.0, 0.0],
            &[0.0, 0.0, 5.0, 1.0],
        ]);
        let x = [1.0, -2.0, 0.5, 3.0];
        let mut b = multiply(&a, 4, &x);
        let mut lu = a.clone();
        let mut pivots = [0; 4];
        factor(&mut lu, 4, &mut pivots).expect("regular");
        solve(&lu, 4, &pivots, &mut b);
        for (got, want) in b.iter().zip(x) {
            assert!((got - want).abs() <= 1e-14 * 5.0, "{b:?}");
        }
    }

    #[test]
    fn agrees_with_faer_on_random_matrices_up_to_the_limit() {
        use faer::prelude::Solve;
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for n in 1..=UNBLOCKED_MAX_DIMENSION {
            let a: Vec<f64> = (0..n * n).map(|_| next()).collect();
            let b: Vec<f64> = (0..n).map(|_| next()).collect();
            let mut lu = a.clone();
            let mut pivots = vec![0; n];
            factor(&mut lu, n, &mut pivots).expect("random matrices are regular");
            let mut x = b.clone();
            solve(&lu, n, &pivots, &mut x);
            let fa = faer::Mat::from_fn(n, n, |i, j| a[i + j * n]);
            let fb = faer::Mat::from_fn(n, 1, |i, _| b[i]);
            let reference = fa.partial_piv_lu().solve(&fb);
            let scale = x.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            for i in 0..n {
                assert!(
                    (x[i] - reference[(i, 0)]).abs() <= 1e-10 * scale,
                    "n = {n}: {} vs {}",
                    x[i],
                    reference[(i, 0)]
                );
            }
        }
    }

    #[test]
    fn a_pivot_left_by_cancellation_is_singular() {
        // Rank 2: the last pivot is round-off of the entries it was computed from (or zero).
        let mut a = column_major(&[&[1.0, 2.0, 3.0], &[4.0, 5.0, 6.0], &[7.0, 8.0, 9.0]]);
        let mut pivots = [0; 3];
        assert_eq!(
            factor(&mut a, 3, &mut pivots),
            Err(Breakdown::Pivot { column: 2 })
        );
        let mut zero_column = column_major(&[&[1.0, 0.0], &[2.0, 0.0]]);
        assert_eq!(
            factor(&mut zero_column, 2, &mut pivots),
            Err(Breakdown::Pivot { column: 1 })
        );
    }

    #[test]
    fn a_widely_scaled_regular_matrix_is_regular() {
        // Condition 1e17 by scaling alone, and an index-3-like matrix at a step of 1e-7
        // (entries 1/h beside a last pivot of order h^2, condition 1e21): both factorise, and
        // the solution satisfies the system to round-off of its terms (backward stable).
        let h = 1e-7;
        for rows in [
            vec![vec![1e10, 0.0], vec![0.0, 1e-7]],
            vec![
                vec![1.0 / h, -1.0, 0.0],
                vec![0.0, 1.0 / h, 0.6],
                vec![0.6, 0.0, 0.0],
            ],
        ] {
            let n = rows.len();
            let rows: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            let a = column_major(&rows);
            let mut lu = a.clone();
            let mut pivots = [0; 3];
            factor(&mut lu, n, &mut pivots).expect("regular");
            let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
            let mut x = b.clone();
            solve(&lu, n, &pivots, &mut x);
            let ax = multiply(&a, n, &x);
            for i in 0..n {
                let terms: f64 = (0..n).map(|j| (a[i + j * n] * x[j]).abs()).sum();
                assert!(
                    (ax[i] - b[i]).abs() <= 1e-14 * (terms + b[i].abs()),
                    "row {i}: {} vs {}",
                    ax[i],
                    b[i]
                );
            }
        }
    }

    #[test]
    fn a_non_finite_entry_is_reported_at_its_column() {
        let mut a = column_major(&[&[1.0, 0.0], &[0.0, f64::NAN]]);
        let mut pivots = [0; 2];
        assert_eq!(
            factor(&mut a, 2, &mut pivots),
            Err(Breakdown::NonFinite { row: 1, column: 1 })
        );
    }

    #[test]
    fn a_well_scaled_small_pivot_is_regular() {
        // A pivot of 1e-12 against entries of size 1 is far above round-off: regular.
        let a = column_major(&[&[1e-12, 1.0], &[1.0, 1.0]]);
        let mut lu = a.clone();
        let mut pivots = [0; 2];
        factor(&mut lu, 2, &mut pivots).expect("regular");
        let mut b = multiply(&a, 2, &[2.0, 3.0]);
        solve(&lu, 2, &pivots, &mut b);
        assert!(
            (b[0] - 2.0).abs() < 1e-12 && (b[1] - 3.0).abs() < 1e-12,
            "{b:?}"
        );
    }
}
