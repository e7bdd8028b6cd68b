//! Transfer matrices `H(s) = C (sI - A)^-1 B + D`, the polynomial `R_xi(s)` of (3.9) and the
//! check of Theorem 3.3: the DPC closed loop `(C + D K_J)(sI - A - B K_J)^-1 B + D` is
//! `R_xi(s)^-1`.

use nalgebra::DMatrix;
use num_complex::Complex;

use super::LinearSystem;

type C64 = Complex<f64>;

fn to_complex(m: &DMatrix<f64>) -> DMatrix<C64> {
    m.map(C64::from)
}

/// `C (sI - A)^-1 B + D` at `s` (LU solve, no inverse); `None` if `s` is an eigenvalue of `A`
/// to working precision.
pub fn transfer_matrix(sys: &LinearSystem, s: C64) -> Option<DMatrix<C64>> {
    let n = sys.n();
    let mut lhs = to_complex(&sys.a) * C64::from(-1.0);
    for i in 0..n {
        lhs[(i, i)] += s;
    }
    let x = if n == 0 {
        DMatrix::zeros(0, sys.m())
    } else {
        lhs.full_piv_lu().solve(&to_complex(&sys.b))?
    };
    Some(to_complex(&sys.c) * x + to_complex(&sys.d))
}

/// Evaluate the matrix polynomial `sum_k R_k s^k` (coefficients lowest power first).
pub fn polynomial_at(coefficients: &[DMatrix<f64>], s: C64) -> DMatrix<C64> {
    let (r, c) = coefficients.first().map_or((0, 0), |m| m.shape());
    let mut acc = DMatrix::<C64>::zeros(r, c);
    for k in coefficients.iter().rev() {
        acc = acc * s + to_complex(k);
    }
    acc
}

/// `max |H_b(s) R_xi(s) - I|` over the points, relative to `max(1, |H_b(s)| |R_xi(s)|)`,
/// where `H_b` is the closed loop of `sys` under `u = K_J x + v`.
pub fn theorem_3_3_residual(
    sys: &LinearSystem,
    k_j: &DMatrix<f64>,
    r_xi: &[DMatrix<f64>],
    points: &[C64],
) -> f64 {
    let Ok(closed) = sys.with_feedback(k_j) else {
        return f64::INFINITY;
    };
    let m = sys.m();
    let mut worst = 0.0f64;
    for &s in points {
        let Some(hb) = transfer_matrix(&closed, s) else {
            continue;
        };
        let r = polynomial_at(r_xi, s);
        let prod = &hb * &r;
        let scale = 1.0f64.max(
            hb.iter().map(|z| z.norm()).fold(0.0, f64::max)
                * r.iter().map(|z| z.norm()).fold(0.0, f64::max),
        );
        let res = (prod - DMatrix::<C64>::identity(m, m))
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);
        worst = worst.max(res / scale);
    }
    worst
}

/// Check points for Theorem 3.3, scaled to the system: `||A|| (1 + 0.37 i)` and friends, moved
/// off the real axis so that they avoid real poles.
pub fn check_points(scale: f64) -> Vec<C64> {
    let s = scale.max(1.0);
    vec![
        C64::new(0.31 * s, 0.77 * s),
        C64::new(-0.53 * s, 1.19 * s),
        C64::new(1.7 * s, -0.41 * s),
        C64::new(0.05, 0.93),
    ]
}
