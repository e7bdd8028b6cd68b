//! Dense LU with partial pivoting (faer), workspace allocated once.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Mat, MatMut, Par};

use super::{zero_row, FactorError, LinearSolver};

/// Dense `n x n` LU with partial pivoting on a faer [`Mat`], for large models.
///
/// The matrix, its factors, the row permutation and faer's scratch memory are allocated in
/// [`FaerDenseLu::new`]; factorisations and solves reuse them.
pub struct FaerDenseLu {
    matrix: Mat<f64>,
    lu: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    mem: MemBuffer,
    factored: bool,
}

impl FaerDenseLu {
    /// A solver for `n x n` systems.
    pub fn new(n: usize) -> Self {
        let par = Par::Seq;
        let req = factor::lu_in_place_scratch::<usize, f64>(n, n, par, Default::default())
            .or(solve::solve_in_place_scratch::<usize, f64>(n, 1, par));
        Self {
            matrix: Mat::zeros(n, n),
            lu: Mat::zeros(n, n),
            perm: vec![0; n],
            perm_inv: vec![0; n],
            mem: MemBuffer::new(req),
            factored: false,
        }
    }
}

impl LinearSolver for FaerDenseLu {
    type Matrix = Mat<f64>;

    fn dimension(&self) -> usize {
        self.matrix.nrows()
    }

    fn matrix_mut(&mut self) -> &mut Self::Matrix {
        &mut self.matrix
    }

    fn factor(&mut self) -> Result<(), FactorError> {
        let n = self.matrix.nrows();
        self.lu.copy_from(&self.matrix);
        factor::lu_in_place(
            self.lu.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        let lu = &self.lu;
        if let Some(k) = (0..n).find(|&k| lu[(k, k)] == 0.0 || !lu[(k, k)].is_finite()) {
            self.factored = false;
            let m = &self.matrix;
            return Err(FactorError::Singular {
                column: Some(k),
                row: zero_row(n, |i, j| m[(i, j)]),
            });
        }
        self.factored = true;
        Ok(())
    }

    fn scaled_row_norms(&self, w: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (j, wj) in w.iter().enumerate() {
            for (i, o) in out.iter_mut().enumerate() {
                *o = o.max(self.matrix[(i, j)].abs() / wj);
            }
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) {
        if !self.factored {
            return;
        }
        let n = b.len();
        // SAFETY-free construction: the permutation arrays were produced by faer's factorisation.
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, n);
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        solve::solve_in_place(
            self.lu.as_ref(),
            self.lu.as_ref(),
            perm,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
    }
}

impl core::fmt::Debug for FaerDenseLu {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FaerDenseLu")
            .field("n", &self.matrix.nrows())
            .field("factored", &self.factored)
            .finish_non_exhaustive()
    }
}
