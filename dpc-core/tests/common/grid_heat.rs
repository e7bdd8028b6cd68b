//! A 2-D heat equation on a growing grid, hand-written as a user ports it (no mass matrix), for
//! the tests of large sparse DAEs: `tests/ida_banded.rs` (band against sparse LU on growing
//! grids) and `tests/sparse_setup.rs` (set-up paths without dense matrices).
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// `u_t = u_xx + u_yy` on the unit square, `u = 0` on the edges, central differences on an
/// `m x m` grid: the interior values differential, the edges algebraic (`0 = u`), unknowns
/// numbered `i + m j`. Exact banded iteration matrix, its pattern declared, no mass matrix.
pub struct GridHeat(pub usize);

impl GridHeat {
    pub fn edge(&self, k: usize) -> bool {
        let m = self.0;
        let (i, j) = (k % m, k / m);
        i == 0 || j == 0 || i == m - 1 || j == m - 1
    }
    pub fn coeff(&self) -> f64 {
        ((self.0 - 1) * (self.0 - 1)) as f64
    }
    /// Consistent initial values: `16 x (1 - x) y (1 - y)` inside, 0 on the edges.
    pub fn initial(&self) -> (Vec<f64>, Vec<f64>) {
        let m = self.0;
        let n = m * m;
        let dx = 1.0 / (m - 1) as f64;
        let y: Vec<f64> = (0..n)
            .map(|k| {
                let (x, z) = ((k % m) as f64 * dx, (k / m) as f64 * dx);
                if self.edge(k) {
                    0.0
                } else {
                    16.0 * x * (1.0 - x) * z * (1.0 - z)
                }
            })
            .collect();
        let mut r = vec![0.0; n];
        self.residual(0.0, &y, &vec![0.0; n], &mut r);
        let yp = (0..n)
            .map(|k| if self.edge(k) { 0.0 } else { -r[k] })
            .collect();
        (y, yp)
    }
}

impl ImplicitDae for GridHeat {
    fn dimension(&self) -> usize {
        self.0 * self.0
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let m = self.0;
        for k in 0..m * m {
            out[k] = if self.edge(k) {
                y[k]
            } else {
                yp[k] - self.coeff() * (y[k - 1] + y[k + 1] + y[k - m] + y[k + m] - 4.0 * y[k])
            };
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let m = self.0;
        for k in 0..m * m {
            if self.edge(k) {
                out.set(k, k, 1.0);
            } else {
                out.set(k, k, c + 4.0 * self.coeff());
                for q in [k - m, k - 1, k + 1, k + m] {
                    out.set(k, q, -self.coeff());
                }
            }
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        !self.edge(i)
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let m = self.0;
        let mut p = Vec::new();
        for k in 0..m * m {
            if self.edge(k) {
                p.push((k, k));
            } else {
                for q in [k - m, k - 1, k, k + 1, k + m] {
                    p.push((k, q));
                }
            }
        }
        Some(p)
    }
}
