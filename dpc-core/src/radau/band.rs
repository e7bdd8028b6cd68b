//! Banded complex LU for Radau's complex stage system `E_2 = J + ((alpha - i beta)/h) M` when
//! the caller's real solver is banded ([`crate::linear_solver::BandLu`]): `E_2` has the
//! structure of `E_1`, so its factors stay in the same band. The elimination is the real
//! banded one ([`crate::linear_solver::BandLu`]) in complex arithmetic, pivoting on
//! `|re| + |im|` as the dense complex LU does.

use faer::c64;

/// Complex `n x n` LU with partial pivoting inside the half-bandwidths `kl`, `ku`, storage
/// allocated once: column `j`, row `i` (`j - kl - ku <= i <= j + kl`) at
/// `j * (2 kl + ku + 1) + kl + ku + i - j`, the `kl` topmost rows of a column for the
/// interchanges' fill-in.
pub(crate) struct ComplexBandLu {
    n: usize,
    kl: usize,
    ku: usize,
    factors: Vec<c64>,
    pivots: Vec<usize>,
    factored: bool,
}

/// `|re| + |im|`, the pivot size of LAPACK's complex LU.
#[inline(always)]
fn abs1(v: c64) -> f64 {
    v.re.abs() + v.im.abs()
}

impl ComplexBandLu {
    pub fn new(n: usize, kl: usize, ku: usize) -> Self {
        Self {
            n,
            kl,
            ku,
            factors: vec![c64::new(0.0, 0.0); n * (2 * kl + ku + 1)],
            pivots: vec![0; n],
            factored: false,
        }
    }

    /// Every entry zero (the fill-in rows included), before the band is written with
    /// [`set`](Self::set).
    pub fn clear(&mut self) {
        self.factors.fill(c64::new(0.0, 0.0));
        self.factored = false;
    }

    /// The entry `(i, j)`, which must lie in the band (`j <= i + ku`, `i <= j + kl`).
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, v: c64) {
        debug_assert!(j <= i + self.ku && i <= j + self.kl && i < self.n && j < self.n);
        let ld = 2 * self.kl + self.ku + 1;
        self.factors[j * ld + self.kl + self.ku + i - j] = v;
    }

    /// Factorise in place; the first column whose pivot is zero or not finite is an error.
    pub fn factor(&mut self) -> Result<(), usize> {
        self.factored = false;
        let (n, kl, ku) = (self.n, self.kl, self.ku);
        let (ld, kv) = (2 * kl + ku + 1, kl + ku);
        let f = &mut self.factors;
        let mut reach = 0;
        for j in 0..n {
            let below = kl.min(n - 1 - j);
            let col = j * ld + kv;
            let mut p = 0;
            let mut best = abs1(f[col]);
            for i in 1..=below {
                let v = abs1(f[col + i]);
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.pivots[j] = j + p;
            if best == 0.0 || !best.is_finite() {
                return Err(j);
            }
            reach = reach.max((j + ku + p).min(n - 1));
            if p != 0 {
                for c in j..=reach {
                    let top = c * ld + kv + j - c;
                    f.swap(top, top + p);
                }
            }
            let d = c64::new(1.0, 0.0) / f[col];
            for v in &mut f[col + 1..=col + below] {
                *v *= d;
            }
            if below == 0 {
                continue;
            }
            let (left, right) = f.split_at_mut((j + 1) * ld);
            let multipliers = &left[col + 1..=col + below];
            for (k, column) in right.chunks_exact_mut(ld).take(reach - j).enumerate() {
                let top = kv + j - (j + 1 + k);
                let u = column[top];
                if u != c64::new(0.0, 0.0) {
                    for (v, l) in column[top + 1..=top + below].iter_mut().zip(multipliers) {
                        *v -= *l * u;
                    }
                }
            }
        }
        self.factored = true;
        Ok(())
    }

    /// Overwrite `b` with the solution for the last successful factorisation (left alone
    /// after a failed one).
    pub fn solve_in_place(&self, b: &mut [c64]) {
        if !self.factored {
            return;
        }
        crate::linear_solver::band::solve_band_factors(
            &self.factors,
            &self.pivots,
            self.n,
            self.kl,
            self.ku,
            b,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random complex band matrix (small diagonal: rows are interchanged) against its
    /// product: `A x = b` solved back to `x`, and a zero column reported.
    #[test]
    fn solves_a_random_band_system_and_reports_a_zero_pivot() {
        let (n, kl, ku): (usize, usize, usize) = (40, 5, 3);
        let mut state = 11u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut entries = Vec::new();
        for j in 0..n {
            for i in j.saturating_sub(ku)..=(j + kl).min(n - 1) {
                let s = if i == j { 1e-3 } else { 1.0 };
                entries.push((i, j, c64::new(s * next(), s * next())));
            }
        }
        let x: Vec<c64> = (0..n).map(|k| c64::new(1.0 + k as f64, -0.5)).collect();
        let mut b = vec![c64::new(0.0, 0.0); n];
        for &(i, j, v) in &entries {
            b[i] += v * x[j];
        }
        let mut lu = ComplexBandLu::new(n, kl, ku);
        lu.clear();
        for &(i, j, v) in &entries {
            lu.set(i, j, v);
        }
        lu.factor().expect("regular");
        assert!(lu.pivots.iter().enumerate().any(|(k, &p)| p != k));
        lu.solve_in_place(&mut b);
        for (got, want) in b.iter().zip(&x) {
            assert!(
                abs1(*got - *want) <= 1e-9 * 40.0,
                "{got:?} against {want:?}"
            );
        }
        lu.clear();
        for &(i, j, v) in entries.iter().filter(|e| e.1 != 7) {
            lu.set(i, j, v);
        }
        assert_eq!(lu.factor(), Err(7));
    }
}
