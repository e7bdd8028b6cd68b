//! Fixed-size dense LU on the stack (nalgebra storage), allocation-free after construction.

use nalgebra::SMatrix;

use super::{zero_row, FactorError, LinearSolver};

/// Dense `N x N` LU with partial (row) pivoting in stack storage.
///
/// The matrix is an `SMatrix<f64, N, N>` (the sink the generated code writes into); the
/// factors overwrite a second `SMatrix` and the permutation is a `[usize; N]`. Construction,
/// factorisation and solves never touch the heap. The elimination is the textbook
/// right-looking Doolittle algorithm (Golub & Van Loan, Algorithm 3.4.1), which for the small
/// sizes of generated models beats blocked code.
#[derive(Debug, Clone)]
pub struct NalgebraLu<const N: usize> {
    matrix: SMatrix<f64, N, N>,
    lu: SMatrix<f64, N, N>,
    perm: [usize; N],
    factored: bool,
}

impl<const N: usize> NalgebraLu<N> {
    /// A solver for `N x N` systems.
    pub fn new() -> Self {
        Self {
            matrix: SMatrix::zeros(),
            lu: SMatrix::zeros(),
            perm: [0; N],
            factored: false,
        }
    }
}

impl<const N: usize> Default for NalgebraLu<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> LinearSolver for NalgebraLu<N> {
    type Matrix = SMatrix<f64, N, N>;

    fn dimension(&self) -> usize {
        N
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        &mut self.matrix
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        self.factored = false;
        self.lu = self.matrix;
        let a = &mut self.lu;
        for (i, p) in self.perm.iter_mut().enumerate() {
            *p = i;
        }
        for k in 0..N {
            let mut piv = k;
            let mut best = a[(k, k)].abs();
            for i in k + 1..N {
                let v = a[(i, k)].abs();
                if v > best {
                    best = v;
                    piv = i;
                }
            }
            if best == 0.0 || !best.is_finite() {
                let m = &self.matrix;
                return Err(FactorError::Singular {
                    column: Some(k),
                    row: zero_row(N, |i, j| m[(i, j)]),
                });
            }
            if piv != k {
                a.swap_rows(k, piv);
                self.perm.swap(k, piv);
            }
            let d = 1.0 / a[(k, k)];
            for i in k + 1..N {
                a[(i, k)] *= d;
            }
            for j in k + 1..N {
                let akj = a[(k, j)];
                if akj != 0.0 {
                    for i in k + 1..N {
                        let l = a[(i, k)];
                        a[(i, j)] -= l * akj;
                    }
                }
            }
        }
        self.factored = true;
        Ok(())
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = (0..N).fold(0.0, |m: f64, j| m.max(self.matrix[(i, j)].abs() / w[j]));
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        if !self.factored {
            return;
        }
        let b = &mut b[..N];
        let mut x = [0.0; N];
        for (xi, &p) in x.iter_mut().zip(&self.perm) {
            *xi = b[p];
        }
        let a = &self.lu;
        for j in 0..N {
            let xj = x[j];
            for i in j + 1..N {
                x[i] -= a[(i, j)] * xj;
            }
        }
        for j in (0..N).rev() {
            x[j] /= a[(j, j)];
            let xj = x[j];
            for i in 0..j {
                x[i] -= a[(i, j)] * xj;
            }
        }
        b.copy_from_slice(&x);
    }
}
