//! Radau with a sparse real solver ([`FaerSparseLu`]) keeps `J`, `M` and the complex stage
//! matrix in the solver's pattern (`dpc_core::linear_solver::LinearSolver::pattern`): on a
//! sparse index-1 DAE with a known solution it takes the dense LU's steps and agrees with its
//! run to round-off, and an entry the model writes outside its declared pattern is reported
//! as [`RadauError::OutsidePattern`].

use dpc_core::linear_solver::{FaerDenseLu, FaerSparseLu};
use dpc_core::radau::{Options, Radau, RadauError};
use dpc_core::{ImplicitDae, MatrixSink};

/// `blocks` oscillators `x_i' = v_i`, `v_i' = -w_i^2 x_i` (`w_i = 1 + i/4`) with an algebraic
/// `z_i = x_i + x_{i+1}` (cyclic, so the pattern is not banded), unknowns `(x, v, z)` of block
/// `i` at `3 i..3 i + 3`: `x_i = cos(w_i t)`, `v_i = -w_i sin(w_i t)`.
#[derive(Clone, Copy)]
struct Oscillators {
    blocks: usize,
    /// Whether the declared pattern leaves out the last `z`'s dependence on `x_0`.
    short_pattern: bool,
}

impl Oscillators {
    fn w(i: usize) -> f64 {
        1.0 + i as f64 / 4.0
    }
    fn next(&self, i: usize) -> usize {
        (i + 1) % self.blocks
    }
    fn exact(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        let (mut y, mut yp) = (Vec::new(), Vec::new());
        for i in 0..self.blocks {
            let (w, wn) = (Self::w(i), Self::w(self.next(i)));
            y.extend([
                (w * t).cos(),
                -w * (w * t).sin(),
                (w * t).cos() + (wn * t).cos(),
            ]);
            yp.extend([
                -w * (w * t).sin(),
                -w * w * (w * t).cos(),
                -w * (w * t).sin() - wn * (wn * t).sin(),
            ]);
        }
        (y, yp)
    }
}

impl ImplicitDae for Oscillators {
    fn dimension(&self) -> usize {
        3 * self.blocks
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for i in 0..self.blocks {
            let (b, w) = (3 * i, Self::w(i));
            out[b] = yp[b] - y[b + 1];
            out[b + 1] = yp[b + 1] + w * w * y[b];
            out[b + 2] = y[b + 2] - y[b] - y[3 * self.next(i)];
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        for i in 0..self.blocks {
            let (b, w) = (3 * i, Self::w(i));
            m.add(b, b, c);
            m.add(b, b + 1, -1.0);
            m.add(b + 1, b + 1, c);
            m.add(b + 1, b, w * w);
            m.add(b + 2, b + 2, 1.0);
            m.add(b + 2, b, -1.0);
            m.add(b + 2, 3 * self.next(i), -1.0);
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        i % 3 != 2
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let mut p = Vec::new();
        for i in 0..self.blocks {
            let b = 3 * i;
            p.extend([
                (b, b),
                (b, b + 1),
                (b + 1, b + 1),
                (b + 1, b),
                (b + 2, b + 2),
            ]);
            p.push((b + 2, b));
            if !(self.short_pattern && i + 1 == self.blocks) {
                p.push((b + 2, 3 * self.next(i)));
            }
        }
        Some(p)
    }
}

/// The sparse and the dense LU on 12 oscillators (36 unknowns) to `t = 2` at `1e-8`: the
/// same steps, iterations and factorisations, the states within `1e-12` (relative to the largest) of each other, both within
/// `1e-5` of the exact solution.
#[test]
fn the_sparse_solver_takes_the_dense_steps() {
    let model = Oscillators {
        blocks: 12,
        short_pattern: false,
    };
    let n = model.dimension();
    let (y0, yp0) = model.exact(0.0);
    let opts = Options::with_tolerances(1e-8, 1e-8);
    let sparse_ls = FaerSparseLu::new(n, &model.iteration_pattern().unwrap()).unwrap();
    let mut sparse = Radau::new(model, sparse_ls, opts.clone(), 0.0, &y0, &yp0).unwrap();
    let mut dense = Radau::new(model, FaerDenseLu::new(n), opts, 0.0, &y0, &yp0).unwrap();
    let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
    for k in 1..=4 {
        let t = 0.5 * f64::from(k);
        sparse.solve_to(t, &mut a, None).unwrap();
        dense.solve_to(t, &mut b, None).unwrap();
        let scale = b.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
        let apart = a
            .iter()
            .zip(&b)
            .fold(0.0, |m: f64, (x, y)| m.max((x - y).abs()))
            / scale;
        let (exact, _) = model.exact(t);
        let error = a
            .iter()
            .zip(&exact)
            .fold(0.0, |m: f64, (x, y)| m.max((x - y).abs()));
        println!("t = {t}: sparse and dense {apart:.1e} apart, error {error:.1e}");
        assert!(apart < 1e-12, "t = {t}: {apart}");
        assert!(error < 1e-5, "t = {t}: {error}");
    }
    assert_eq!(sparse.stats(), dense.stats());
}

/// A model that writes `dz/dx_0` of the last block outside the pattern it declares: the
/// first step reports the entry by name, nothing is dropped.
#[test]
fn an_entry_outside_the_declared_pattern_is_an_error() {
    let model = Oscillators {
        blocks: 4,
        short_pattern: true,
    };
    let n = model.dimension();
    let (y0, yp0) = model.exact(0.0);
    let ls = FaerSparseLu::new(n, &model.iteration_pattern().unwrap()).unwrap();
    let mut r = Radau::new(
        model,
        ls,
        Options::with_tolerances(1e-6, 1e-6),
        0.0,
        &y0,
        &yp0,
    )
    .unwrap();
    let mut out = vec![0.0; n];
    match r.solve_to(1.0, &mut out, None) {
        Err(RadauError::OutsidePattern { equation, unknown }) => {
            assert_eq!(equation, model.equation_name(n - 1));
            assert_eq!(unknown, model.unknown_name(0));
        }
        other => panic!("{other:?}"),
    }
}
