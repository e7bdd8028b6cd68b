//! The iteration matrix a fixture supplies against central differences of its residual.
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
