//! SUNDIALS IDA's banded example `idaHeat2D_bnd` written anew from its mathematical definition:
//! the heat equation `u_t = u_xx + u_yy` on the unit square with `u = 0` on the edges, central
//! differences on an `M x M` grid (`M = 10`, `dx = 1/(M-1)`), the 64 interior values
//! differential and the 36 boundary values algebraic (`0 = u`), 100 unknowns numbered
//! `i + M j` (`i` along `x`), index 1. The residual of an interior point is
//!
//! ```text
//! u'_ij - (u_{i-1,j} + u_{i+1,j} + u_{i,j-1} + u_{i,j+1} - 4 u_ij) / dx^2
//! ```
//!
//! and of a boundary point `u_ij`. The iteration matrix is banded with half-bandwidths `M` (the
//! example's `mu = ml = M`); it is exact here, and [`Heat2d::iteration_pattern`] declares its
//! 356 entries.
//!
//! Initial values as the example's: `u = 16 x (1 - x) y (1 - y)` inside, `0` on the edges
//! (already consistent: the example starts its boundary at 0.1 to show `IDACalcIC`), `u'` the
//! interior residual's right-hand side, `0` on the edges.
//!
//! The example prints the max norm at `t = 0.01, 0.02, 0.04, ..., 10.24` with `rtol = 0`,
//! `atol = 1e-3`. From `t = 0.64` on the solution is below `1e-20` (the slowest mode decays as
//! `exp(-19.5 t)`), so relative digits there measure nothing but the absolute tolerance; the
//! table stops at [`HEAT_T_END`] `= 0.16`, the example's fifth output (max norm 0.045), and
//! scores the 64 interior values. The reference is exact: the semi-discrete system is linear
//! with the discrete sine modes as eigenvectors, so [`heat_exact`] sums the 64 modes of the
//! initial values (a discrete sine transform), each decayed by its eigenvalue, rounding error
//! only.
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// Grid points per direction.
pub const HEAT_M: usize = 10;
/// Unknowns.
pub const HEAT_N: usize = HEAT_M * HEAT_M;
/// Half-bandwidths of the iteration matrix (upper and lower).
pub const HEAT_HALF_BANDWIDTH: usize = HEAT_M;
/// End of the scored interval (the example's fifth output time).
pub const HEAT_T_END: f64 = 0.16;
/// `1 / dx^2`.
const COEFF: f64 = ((HEAT_M - 1) * (HEAT_M - 1)) as f64;

/// The 2-D heat equation of `idaHeat2D_bnd` ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct Heat2d;

/// Whether unknown `k` lies on the boundary.
fn on_boundary(k: usize) -> bool {
    let (i, j) = (k % HEAT_M, k / HEAT_M);
    i == 0 || j == 0 || i == HEAT_M - 1 || j == HEAT_M - 1
}

/// The scored components: the 64 interior points.
pub fn heat_scored() -> Vec<usize> {
    (0..HEAT_N).filter(|&k| !on_boundary(k)).collect()
}

impl Heat2d {
    /// `(u(0), u'(0))`, consistent ([module documentation](self)).
    pub fn initial() -> (Vec<f64>, Vec<f64>) {
        let h = 1.0 / (HEAT_M - 1) as f64;
        let mut u = vec![0.0; HEAT_N];
        for (k, v) in u.iter_mut().enumerate() {
            if !on_boundary(k) {
                let (x, y) = ((k % HEAT_M) as f64 * h, (k / HEAT_M) as f64 * h);
                *v = 16.0 * x * (1.0 - x) * y * (1.0 - y);
            }
        }
        let mut up = vec![0.0; HEAT_N];
        for (k, v) in up.iter_mut().enumerate() {
            if !on_boundary(k) {
                *v = COEFF * laplace(&u, k);
            }
        }
        (u, up)
    }
}

/// `u_{i-1,j} + u_{i+1,j} + u_{i,j-1} + u_{i,j+1} - 4 u_ij` at interior point `k`.
fn laplace(u: &[f64], k: usize) -> f64 {
    u[k - 1] + u[k + 1] + u[k - HEAT_M] + u[k + HEAT_M] - 4.0 * u[k]
}

/// The exact solution of the semi-discrete system at `t` from [`Heat2d::initial`]: with
/// `N = M - 1`, the interior values are `sum_{p,q} a_pq sin(p pi i/N) sin(q pi j/N)
/// exp(-lambda_pq t)`, `lambda_pq = 4 (sin^2(p pi/2N) + sin^2(q pi/2N)) / dx^2`, `a_pq` the
/// discrete sine transform of `u(0)` (`(2/N)^2 sum_ij u_ij(0) sin(p pi i/N) sin(q pi j/N)`);
/// the boundary values are 0.
pub fn heat_exact(t: f64) -> Vec<f64> {
    let nn = HEAT_M - 1;
    let (u0, _) = Heat2d::initial();
    let s = |p: usize, i: usize| (std::f64::consts::PI * (p * i) as f64 / nn as f64).sin();
    let lambda = |p: usize| {
        let v = (std::f64::consts::PI * p as f64 / (2 * nn) as f64).sin();
        4.0 * COEFF * v * v
    };
    let norm = (2.0 / nn as f64) * (2.0 / nn as f64);
    let mut u = vec![0.0; HEAT_N];
    for q in 1..nn {
        for p in 1..nn {
            let mut a = 0.0;
            for j in 1..nn {
                for i in 1..nn {
                    a += u0[i + HEAT_M * j] * s(p, i) * s(q, j);
                }
            }
            let a = norm * a * (-(lambda(p) + lambda(q)) * t).exp();
            for j in 1..nn {
                for i in 1..nn {
                    u[i + HEAT_M * j] += a * s(p, i) * s(q, j);
                }
            }
        }
    }
    u
}

impl ImplicitDae for Heat2d {
    fn dimension(&self) -> usize {
        HEAT_N
    }

    fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for (k, r) in out.iter_mut().enumerate() {
            *r = if on_boundary(k) {
                y[k]
            } else {
                yp[k] - COEFF * laplace(y, k)
            };
        }
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _t: f64,
        _y: &[f64],
        _yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        for k in 0..HEAT_N {
            if on_boundary(k) {
                out.set(k, k, 1.0);
            } else {
                out.set(k, k, c + 4.0 * COEFF);
                for m in [k - HEAT_M, k - 1, k + 1, k + HEAT_M] {
                    out.set(k, m, -COEFF);
                }
            }
        }
    }

    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for k in (0..HEAT_N).filter(|&k| !on_boundary(k)) {
            m.set(k, k, 1.0);
        }
        true
    }

    fn is_differential(&self, i: usize) -> bool {
        !on_boundary(i)
    }

    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let mut p = Vec::new();
        for k in 0..HEAT_N {
            if on_boundary(k) {
                p.push((k, k));
            } else {
                for m in [k - HEAT_M, k - 1, k, k + 1, k + HEAT_M] {
                    p.push((k, m));
                }
            }
        }
        Some(p)
    }
}
