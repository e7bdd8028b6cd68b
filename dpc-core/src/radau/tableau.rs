//! Coefficients of the three-stage Radau IIA method (order 5) and the transformation that
//! splits its stage system into one real and one complex system.
//!
//! The nodes are the zeros of `d^2/dx^2 (x^2 (x - 1)^3)` (Radau right points): `c = ((4 - √6)/10,
//! (4 + √6)/10, 1)`; `A` is the collocation matrix `a_ij = ∫_0^{c_i} l_j(s) ds` with `l_j` the
//! Lagrange basis on `c`; the method is stiffly accurate (`b` is the last row of `A`). See
//! Hairer & Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Section IV.5
//! (Table 5.6) and Section IV.8.
//!
//! `A^{-1}` has one real eigenvalue `gamma` and a complex pair `alpha ± i beta`. With `t_1` a
//! real eigenvector and `v = v_r + i v_i` an eigenvector of `alpha + i beta`,
//! `A^{-1} v_r = alpha v_r - beta v_i` and `A^{-1} v_i = beta v_r + alpha v_i`, so
//! `T = [t_1 v_r v_i]` gives
//!
//! ```text
//! T^{-1} A^{-1} T = Λ = [ gamma   0      0   ]
//!                       [   0   alpha   beta ]
//!                       [   0  -beta   alpha ]
//! ```
//!
//! Both are computed here from the eigen-decomposition (Schur form for the eigenvalues, the
//! null vector of the 3 x 3 matrix `A^{-1} - λ I` as the cross product of two of its rows for the
//! eigenvectors); the unit tests check `T Λ T^{-1} = A^{-1}`, the collocation conditions and the
//! closed forms of the eigenvalues.
//!
//! The embedded error estimate (Hairer & Wanner, Section IV.8, eq. (8.19)-(8.20)) uses
//! `ŷ_1 - y_1 = gamma_0 h y'_0 + sum_i e_i Z_i` with `gamma_0 = 1/gamma` and `b̂` of order 3
//! (`gamma_0 + sum b̂_i = 1`, `sum b̂_i c_i = 1/2`, `sum b̂_i c_i^2 = 1/3`), so
//! `e = (b̂ - b)^T A^{-1}`; [`Tableau::dd`] holds `gamma e`, the coefficients that multiply
//! `Z_i / h` in the right-hand side of the estimate.

use nalgebra::{Complex, Matrix3, Vector3};

/// The three-stage Radau IIA tableau and its real/complex transformation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Tableau {
    /// Nodes `c_i`.
    pub c: [f64; 3],
    /// `A^{-1}`, row-major.
    pub a_inv: [[f64; 3]; 3],
    /// `T`, row-major: `Z = (T ⊗ I) W`.
    pub t: [[f64; 3]; 3],
    /// `T^{-1}`, row-major.
    pub t_inv: [[f64; 3]; 3],
    /// Real eigenvalue of `A^{-1}`.
    pub gamma: f64,
    /// Real part of the complex eigenvalues of `A^{-1}`.
    pub alpha: f64,
    /// Imaginary part (positive) of the complex eigenvalues of `A^{-1}`.
    pub beta: f64,
    /// Error-estimate coefficients `gamma (b̂ - b)^T A^{-1}`.
    pub dd: [f64; 3],
}

/// The Radau IIA matrix `A` (Hairer & Wanner, Table IV.5.6).
pub(crate) fn radau_iia_matrix() -> Matrix3<f64> {
    let s6 = 6f64.sqrt();
    Matrix3::new(
        (88.0 - 7.0 * s6) / 360.0,
        (296.0 - 169.0 * s6) / 1800.0,
        (-2.0 + 3.0 * s6) / 225.0,
        (296.0 + 169.0 * s6) / 1800.0,
        (88.0 + 7.0 * s6) / 360.0,
        (-2.0 - 3.0 * s6) / 225.0,
        (16.0 - s6) / 36.0,
        (16.0 + s6) / 36.0,
        1.0 / 9.0,
    )
}

fn rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[(i, j)]))
}

/// Null vector of a rank-2 3 x 3 matrix: the largest cross product of two of its rows (bilinear,
/// so it also serves complex matrices).
fn null_vector<T>(m: [[T; 3]; 3], norm: impl Fn(&[T; 3]) -> f64) -> [T; 3]
where
    T: Copy + core::ops::Mul<Output = T> + core::ops::Sub<Output = T>,
{
    let cross = |a: [T; 3], b: [T; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let candidates = [cross(m[0], m[1]), cross(m[0], m[2]), cross(m[1], m[2])];
    let mut best = candidates[0];
    for c in candidates {
        if norm(&c) > norm(&best) {
            best = c;
        }
    }
    best
}

impl Tableau {
    /// The three-stage Radau IIA method.
    ///
    /// # Panics
    /// Never for the constant data used here (the unit tests exercise this path); the checks
    /// guard against a broken linear-algebra dependency, not against user input.
    pub fn radau_iia_3() -> Self {
        let s6 = 6f64.sqrt();
        let c = [(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0];
        let a = radau_iia_matrix();
        let a_inv = a
            .col_piv_qr()
            .try_inverse()
            .expect("the Radau IIA matrix is non-singular");
        let eig = a_inv.complex_eigenvalues();
        let (mut gamma, mut lam) = (0.0, Complex::new(0.0, 0.0));
        for e in eig.iter() {
            if e.im.abs() < 1e-12 * e.norm() {
                gamma = e.re;
            } else if e.im > 0.0 {
                lam = *e;
            }
        }
        assert!(gamma > 0.0 && lam.im > 0.0, "eigenvalues of A^-1: {eig}");

        // Real eigenvector, unit length.
        let shifted = rows(&(a_inv - Matrix3::identity() * gamma));
        let t1 = Vector3::from(null_vector(shifted, |v| {
            v.iter().map(|x| x * x).sum::<f64>().sqrt()
        }))
        .normalize();
        // Complex eigenvector of alpha + i beta, scaled so that its last component is 1.
        let ac = rows(&a_inv).map(|r| r.map(|x| Complex::new(x, 0.0)));
        let mut m = ac;
        for (i, row) in m.iter_mut().enumerate() {
            row[i] -= lam;
        }
        let v = null_vector(m, |v| v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt());
        let v = v.map(|x| x / v[2]);
        let t = Matrix3::new(
            t1[0], v[0].re, v[0].im, t1[1], v[1].re, v[1].im, t1[2], v[2].re, v[2].im,
        );
        let t_inv = t
            .col_piv_qr()
            .try_inverse()
            .expect("eigenvectors of distinct eigenvalues are independent");

        // Embedded formula of order 3: Vandermonde system for b̂.
        let vdm = Matrix3::new(
            1.0,
            1.0,
            1.0,
            c[0],
            c[1],
            c[2],
            c[0] * c[0],
            c[1] * c[1],
            1.0,
        );
        let gamma0 = 1.0 / gamma;
        let bhat = vdm
            .col_piv_qr()
            .solve(&Vector3::new(1.0 - gamma0, 0.5, 1.0 / 3.0))
            .expect("distinct nodes");
        let b = a.row(2).transpose();
        let e = a_inv.transpose() * (bhat - b);
        Self {
            c,
            a_inv: rows(&a_inv),
            t: rows(&t),
            t_inv: rows(&t_inv),
            gamma,
            alpha: lam.re,
            beta: lam.im,
            dd: [gamma * e[0], gamma * e[1], gamma * e[2]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat(m: &[[f64; 3]; 3]) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| m[i][j])
    }

    #[test]
    fn collocation_conditions_hold() {
        // sum_j a_ij c_j^(k-1) = c_i^k / k for k = 1, 2, 3 (order conditions C(3)).
        let tab = Tableau::radau_iia_3();
        let a = radau_iia_matrix();
        for i in 0..3 {
            for k in 1..=3 {
                let lhs: f64 = (0..3).map(|j| a[(i, j)] * tab.c[j].powi(k - 1)).sum();
                let rhs = tab.c[i].powi(k) / f64::from(k);
                assert!((lhs - rhs).abs() < 1e-15, "i {i} k {k}: {lhs} vs {rhs}");
            }
        }
        // Stiff accuracy: the weights are the last row, and they integrate degree 4 exactly.
        let b = a.row(2);
        for k in 1..=5 {
            let q: f64 = (0..3).map(|j| b[j] * tab.c[j].powi(k - 1)).sum();
            assert!((q - 1.0 / f64::from(k)).abs() < 1e-15, "k {k}: {q}");
        }
    }

    #[test]
    fn transformation_diagonalises_a_inverse() {
        let tab = Tableau::radau_iia_3();
        let lam = Matrix3::new(
            tab.gamma, 0.0, 0.0, 0.0, tab.alpha, tab.beta, 0.0, -tab.beta, tab.alpha,
        );
        let back = mat(&tab.t) * lam * mat(&tab.t_inv);
        let a_inv = mat(&tab.a_inv);
        assert!(
            (back - a_inv).norm() < 1e-12 * a_inv.norm(),
            "{back} vs {a_inv}"
        );
        assert!((mat(&tab.t) * mat(&tab.t_inv) - Matrix3::identity()).norm() < 1e-14);
        assert!((a_inv * radau_iia_matrix() - Matrix3::identity()).norm() < 1e-13);
    }

    #[test]
    fn eigenvalues_match_closed_form() {
        // Eigenvalues of A in closed form (cube roots of 81 and 9; they are the reciprocals of
        // the roots of the characteristic polynomial of A^-1), inverted.
        let (c81, c9) = (81f64.cbrt(), 9f64.cbrt());
        let u1 = (6.0 + c81 - c9) / 30.0;
        let al = (12.0 - c81 + c9) / 60.0;
        let be = (c81 + c9) * 3f64.sqrt() / 60.0;
        let cno = al * al + be * be;
        let tab = Tableau::radau_iia_3();
        assert!((tab.gamma - 1.0 / u1).abs() < 1e-13, "{}", tab.gamma);
        assert!((tab.alpha - al / cno).abs() < 1e-13, "{}", tab.alpha);
        assert!((tab.beta - be / cno).abs() < 1e-13, "{}", tab.beta);
    }

    #[test]
    fn error_coefficients_match_published_values() {
        // Hairer & Wanner, Section IV.8: gamma e = (-(13 + 7√6)/3, (-13 + 7√6)/3, -1/3).
        let tab = Tableau::radau_iia_3();
        let s6 = 6f64.sqrt();
        let expected = [
            -(13.0 + 7.0 * s6) / 3.0,
            (-13.0 + 7.0 * s6) / 3.0,
            -1.0 / 3.0,
        ];
        for (d, e) in tab.dd.iter().zip(expected) {
            assert!((d - e).abs() < 1e-12 * e.abs().max(1.0), "{d} vs {e}");
        }
    }
}
