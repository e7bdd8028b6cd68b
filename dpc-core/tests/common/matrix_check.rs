//! The iteration matrix a fixture supplies against central differences of its residual, and
//! its mass matrix against its iteration matrices at two values of `c`.
#![allow(dead_code)]

use dpc_core::ImplicitDae;
use nalgebra::DMatrix;

/// The largest difference between `dae`'s iteration matrix `dF/dy + c dF/dy'` at
/// `(t, y, yp)` and a central difference quotient of its residual (in `y` and `y'` together,
/// `y'` moving `c` times as far), relative to the largest entry of its row. The step in `y_j`
/// is `rel * max(|y_j|, floor)`.
pub fn matrix_error<D: ImplicitDae>(
    dae: &D,
    (t, y, yp): (f64, &[f64], &[f64]),
    c: f64,
    (rel, floor): (f64, f64),
) -> f64 {
    let n = dae.dimension();
    let mut m = DMatrix::zeros(n, n);
    dae.iteration_matrix(t, y, yp, c, &mut m);
    let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
    let mut dq = DMatrix::zeros(n, n);
    for j in 0..n {
        let h = rel * y[j].abs().max(floor);
        let (mut y1, mut p1, mut y2, mut p2) = (y.to_vec(), yp.to_vec(), y.to_vec(), yp.to_vec());
        y1[j] += h;
        p1[j] += c * h;
        y2[j] -= h;
        p2[j] -= c * h;
        dae.residual(t, &y1, &p1, &mut up);
        dae.residual(t, &y2, &p2, &mut down);
        for i in 0..n {
            dq[(i, j)] = (up[i] - down[i]) / (2.0 * h);
        }
    }
    let mut worst = 0.0f64;
    for i in 0..n {
        let scale = (0..n).map(|j| dq[(i, j)].abs()).fold(0.0, f64::max);
        for j in 0..n {
            worst = worst.max((m[(i, j)] - dq[(i, j)]).abs() / scale);
        }
    }
    worst
}

/// The largest difference between `dae`'s iteration matrix at `c` and the one at `c = 0` plus
/// `c` times its mass matrix ([`ImplicitDae::mass_matrix`]), at `(t, y, yp)`, relative to the
/// largest entry of the row among `J(0)` and `c M` (an all-zero row must match exactly).
///
/// # Errors
/// A message when the DAE supplies no mass matrix, when an entry of one of the matrices is not
/// finite, or when the mass matrix has an entry outside the DAE's
/// [`iteration_pattern`](ImplicitDae::iteration_pattern).
pub fn mass_matrix_error<D: ImplicitDae>(
    dae: &D,
    (t, y, yp): (f64, &[f64], &[f64]),
    c: f64,
) -> Result<f64, String> {
    let n = dae.dimension();
    let (mut j0, mut jc, mut mass) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
    );
    dae.iteration_matrix(t, y, yp, 0.0, &mut j0);
    dae.iteration_matrix(t, y, yp, c, &mut jc);
    if !dae.mass_matrix(t, y, yp, &mut mass) {
        return Err("no mass matrix supplied".into());
    }
    for (name, m) in [("J(0)", &j0), ("J(c)", &jc), ("M", &mass)] {
        if let Some(k) = m.iter().position(|v| !v.is_finite()) {
            return Err(format!("{name} not finite at ({}, {})", k % n, k / n));
        }
    }
    if let Some(pattern) = dae.iteration_pattern() {
        let mut inside = DMatrix::from_element(n, n, false);
        for (i, j) in pattern {
            inside[(i, j)] = true;
        }
        for i in 0..n {
            for j in 0..n {
                if mass[(i, j)] != 0.0 && !inside[(i, j)] {
                    return Err(format!("M has ({i}, {j}) outside the iteration pattern"));
                }
            }
        }
    }
    let mut worst = 0.0f64;
    for i in 0..n {
        let scale = (0..n)
            .map(|j| j0[(i, j)].abs().max((c * mass[(i, j)]).abs()))
            .fold(0.0, f64::max);
        for j in 0..n {
            let d = (jc[(i, j)] - j0[(i, j)] - c * mass[(i, j)]).abs();
            if d != 0.0 {
                worst = worst.max(d / scale);
            }
        }
    }
    Ok(worst)
}

/// Deterministic pseudo-random numbers in `[-1, 1)` (SplitMix64), for moving a point.
pub struct Jitter(u64);

impl Jitter {
    /// The sequence of `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// The next number.
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// `(t, y, y')` moved by a small pseudo-random amount: every `y_i` and `y'_i` by up to
/// `1e-3 (|v| + 1e-3)` either way, `t` forward by up to `1e-3 (1 + |t|)` (never before the
/// start of an interval).
pub fn perturbed(t: f64, y: &[f64], yp: &[f64], seed: u64) -> (f64, Vec<f64>, Vec<f64>) {
    let mut r = Jitter::new(seed);
    let mut move_all = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .map(|&x| x + 1e-3 * (x.abs() + 1e-3) * r.next())
            .collect()
    };
    let (y, yp) = (move_all(y), move_all(yp));
    let t = t + 1e-3 * (1.0 + t.abs()) * 0.5 * (1.0 + r.next());
    (t, y, yp)
}

/// The seed of [`check_mass_matrix`]'s moved point.
pub const MASS_SEED: u64 = 20_261_204;

/// Relative bound of [`check_mass_matrix`]: a few rounding errors of the row's largest term
/// (`J(c)` adds `c M` to `J(0)` in one or a few roundings).
pub const MASS_TOL: f64 = 64.0 * f64::EPSILON;

/// Checks `J(c) = J(0) + c M` ([`mass_matrix_error`]) below [`MASS_TOL`] for `c = 1` and
/// `c = 1e3`, at `(t, y, yp)` and at the point moved by [`perturbed`] (fixed seed); panics
/// naming `name`, the point and `c` otherwise. Returns the largest error seen.
pub fn check_mass_matrix<D: ImplicitDae>(
    name: &str,
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
) -> f64 {
    check_mass_matrix_within(name, dae, (t, y, yp), |_| MASS_TOL)
}

/// [`check_mass_matrix`] with the bound `bound(c)` at `c`.
pub fn check_mass_matrix_within<D: ImplicitDae>(
    name: &str,
    dae: &D,
    (t, y, yp): (f64, &[f64], &[f64]),
    bound: impl Fn(f64) -> f64,
) -> f64 {
    let (tp, y_moved, yp_moved) = perturbed(t, y, yp, MASS_SEED);
    let mut worst = 0.0f64;
    for (point, p) in [
        ("initial", (t, y, yp)),
        ("perturbed", (tp, &y_moved[..], &yp_moved[..])),
    ] {
        for c in [1.0, 1e3] {
            let e = mass_matrix_error(dae, p, c)
                .unwrap_or_else(|m| panic!("{name}, {point} point, c = {c}: {m}"));
            assert!(
                e <= bound(c),
                "{name}, {point} point, c = {c}: J(c) - J(0) - c M is {e:e} of its row"
            );
            worst = worst.max(e);
        }
    }
    worst
}
