//! The stabilised form keeps the wrapped DAE's declared pattern
//! ([`ImplicitDae::iteration_pattern`] of [`Stabilised`]): a planar chain of `N` point masses
//! joined by rigid links in Cartesian coordinates (index 3, written here as a user would, with
//! its pattern declared), stabilised, declares a pattern that holds every entry its iteration
//! matrix writes, at random points and values of `c`, with the constraints' derivatives by
//! differences or supplied; a chain of 20 links is solved by Radau and the BDF with the sparse
//! LU ([`FaerLu::for_dae`]) and agrees with the dense LU's run.
//!
//! The timing of chains with and without the declared pattern (release mode; docs/integrators.md,
//! "The same problems in the stabilised index-2 form"):
//!
//! ```sh
//! cargo test --release -p dpc-core --test stabilised_pattern -- --ignored --nocapture --test-threads=1
//! ```

#[path = "common/matrix_check.rs"]
mod matrix_check;

use std::collections::BTreeSet;
use std::time::Instant;

use dpc_core::bdf::{self, Bdf};
use dpc_core::linear_solver::{FaerDenseLu, FaerLu, SPARSE_DENSITY};
use dpc_core::radau::{self, Radau};
use dpc_core::stabilised::Stabilised;
use dpc_core::{ImplicitDae, MatrixSink};
use matrix_check::Jitter;

/// Gravity.
const G: f64 = 9.81;

/// `links` point masses `m` hanging from the origin by massless rigid links of length `l`, in
/// the plane: per mass `k` the unknowns `(x, y, u, v, lambda)` at `5 k..5 k + 5`, with
/// `x' = u`, `y' = v`, `m u' = -lambda_k dg_k/dx_k - lambda_{k+1} dg_{k+1}/dx_k` (the same in
/// `y` with `- m g`), `0 = g_k = |p_k - p_{k-1}|^2 - l^2` (`p_{-1}` the origin).
#[derive(Clone, Copy)]
struct Chain {
    links: usize,
    m: f64,
    l: f64,
    /// Whether [`ImplicitDae::iteration_pattern`] is declared.
    pattern: bool,
    /// Whether the constraints' gradient, time derivative and curvature are supplied.
    exact: bool,
}

impl Chain {
    fn new(links: usize) -> Self {
        Self {
            links,
            m: 0.1,
            l: 0.1,
            pattern: true,
            exact: false,
        }
    }

    /// The position of mass `k` (the origin for `k = -1`, as `None`).
    fn point(y: &[f64], k: Option<usize>) -> (f64, f64) {
        k.map_or((0.0, 0.0), |k| (y[5 * k], y[5 * k + 1]))
    }

    /// Link `k`'s vector `p_k - p_{k-1}`.
    fn link(y: &[f64], k: usize) -> (f64, f64) {
        let (x0, y0) = Self::point(y, k.checked_sub(1));
        (y[5 * k] - x0, y[5 * k + 1] - y0)
    }

    /// Stretched out horizontally at rest: consistent with `lambda = 0`, `u' = 0`, `v' = -g`
    /// (gravity is orthogonal to every link).
    fn initial(&self) -> (Vec<f64>, Vec<f64>) {
        let mut y = Vec::new();
        let mut yp = Vec::new();
        for k in 0..self.links {
            y.extend([self.l * (k + 1) as f64, 0.0, 0.0, 0.0, 0.0]);
            yp.extend([0.0, 0.0, 0.0, -G, 0.0]);
        }
        (y, yp)
    }

    /// The positions of the entries `iteration_matrix` writes (`with` gives them in order).
    fn entries(&self, mut with: impl FnMut(usize, usize)) {
        for k in 0..self.links {
            let b = 5 * k;
            let next = k + 1 < self.links;
            with(b, b);
            with(b, b + 2);
            with(b + 1, b + 1);
            with(b + 1, b + 3);
            for d in 0..2 {
                let row = b + 2 + d;
                with(row, row);
                if k > 0 {
                    with(row, b - 5 + d);
                }
                with(row, b + d);
                if next {
                    with(row, b + 5 + d);
                }
                with(row, b + 4);
                if next {
                    with(row, b + 9);
                }
            }
            if k > 0 {
                with(b + 4, b - 5);
                with(b + 4, b - 4);
            }
            with(b + 4, b);
            with(b + 4, b + 1);
        }
    }
}

impl ImplicitDae for Chain {
    fn dimension(&self) -> usize {
        5 * self.links
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for k in 0..self.links {
            let b = 5 * k;
            let (dx, dy) = Self::link(y, k);
            let (nx, ny, next_lambda) = if k + 1 < self.links {
                let (nx, ny) = Self::link(y, k + 1);
                (nx, ny, y[b + 9])
            } else {
                (0.0, 0.0, 0.0)
            };
            let lambda = y[b + 4];
            out[b] = yp[b] - y[b + 2];
            out[b + 1] = yp[b + 1] - y[b + 3];
            out[b + 2] = self.m * yp[b + 2] + 2.0 * lambda * dx - 2.0 * next_lambda * nx;
            out[b + 3] =
                self.m * yp[b + 3] + self.m * G + 2.0 * lambda * dy - 2.0 * next_lambda * ny;
            out[b + 4] = dx * dx + dy * dy - self.l * self.l;
        }
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        out: &mut S,
    ) {
        for k in 0..self.links {
            let b = 5 * k;
            let next = k + 1 < self.links;
            let d = Self::link(y, k);
            let n = if next {
                Self::link(y, k + 1)
            } else {
                (0.0, 0.0)
            };
            let (lambda, next_lambda) = (y[b + 4], if next { y[b + 9] } else { 0.0 });
            out.set(b, b, c);
            out.set(b, b + 2, -1.0);
            out.set(b + 1, b + 1, c);
            out.set(b + 1, b + 3, -1.0);
            for (e, (dd, nd)) in [(d.0, n.0), (d.1, n.1)].into_iter().enumerate() {
                let row = b + 2 + e;
                out.set(row, row, c * self.m);
                if k > 0 {
                    out.set(row, b - 5 + e, -2.0 * lambda);
                }
                out.set(row, b + e, 2.0 * lambda + 2.0 * next_lambda);
                if next {
                    out.set(row, b + 5 + e, -2.0 * next_lambda);
                }
                out.set(row, b + 4, 2.0 * dd);
                if next {
                    out.set(row, b + 9, -2.0 * nd);
                }
            }
            if k > 0 {
                out.set(b + 4, b - 5, -2.0 * d.0);
                out.set(b + 4, b - 4, -2.0 * d.1);
            }
            out.set(b + 4, b, 2.0 * d.0);
            out.set(b + 4, b + 1, 2.0 * d.1);
        }
    }
    fn is_differential(&self, i: usize) -> bool {
        i % 5 != 4
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        if !self.pattern {
            return None;
        }
        let mut p = Vec::new();
        self.entries(|i, j| p.push((i, j)));
        Some(p)
    }
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, _: f64, y: &[f64], out: &mut S) -> bool {
        if !self.exact {
            return false;
        }
        for k in 0..self.links {
            let b = 5 * k;
            let (dx, dy) = Self::link(y, k);
            if k > 0 {
                out.set(b + 4, b - 5, -2.0 * dx);
                out.set(b + 4, b - 4, -2.0 * dy);
            }
            out.set(b + 4, b, 2.0 * dx);
            out.set(b + 4, b + 1, 2.0 * dy);
        }
        true
    }
    fn constraint_time_derivative(&self, _: f64, _: &[f64], _: &mut [f64]) -> bool {
        self.exact
    }
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        v: &[f64],
        out: &mut S,
    ) -> bool {
        if !self.exact {
            return false;
        }
        // d/dp of 2 (p_k - p_{k-1}) . (v_k - v_{k-1}).
        for k in 0..self.links {
            let b = 5 * k;
            let (wx, wy) = Self::link(v, k);
            if k > 0 {
                out.set(b + 4, b - 5, -2.0 * wx);
                out.set(b + 4, b - 4, -2.0 * wy);
            }
            out.set(b + 4, b, 2.0 * wx);
            out.set(b + 4, b + 1, 2.0 * wy);
        }
        true
    }
    fn equation_name(&self, i: usize) -> String {
        let k = i / 5;
        match i % 5 {
            4 => format!("length of link {k}"),
            e => format!("equation {e} of mass {k}"),
        }
    }
}

/// Every position written with a non-zero value, including positions out of range.
struct Recorder {
    n: usize,
    written: BTreeSet<(usize, usize)>,
}

impl MatrixSink for Recorder {
    fn rows(&self) -> usize {
        self.n
    }
    fn cols(&self) -> usize {
        self.n
    }
    fn set(&mut self, row: usize, col: usize, value: f64) {
        if value != 0.0 {
            self.written.insert((row, col));
        }
    }
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self.set(row, col, value);
    }
    fn fill_zero(&mut self) {}
}

/// The chain's stabilised form, its constraints given as `Stabilised::new` takes them.
fn stabilise(chain: Chain) -> Stabilised<Chain> {
    let rows = (0..chain.links).map(|k| 5 * k + 4).collect();
    let kinematic = (0..chain.links)
        .flat_map(|k| [(5 * k, 5 * k), (5 * k + 1, 5 * k + 1)])
        .collect();
    Stabilised::new(chain, rows, kinematic).unwrap()
}

#[test]
fn the_pattern_holds_every_entry_written() {
    let mut jitter = Jitter::new(7);
    for exact in [false, true] {
        let chain = Chain {
            exact,
            ..Chain::new(6)
        };
        let s = stabilise(chain);
        let m = s.dimension();
        let wrapped: BTreeSet<_> = chain.iteration_pattern().unwrap().into_iter().collect();
        let pattern = s.iteration_pattern().unwrap();
        // Sorted by row and column, without repeats, in range.
        assert!(pattern.windows(2).all(|w| w[0] < w[1]), "{pattern:?}");
        assert!(pattern.iter().all(|&(i, j)| i < m && j < m));
        // The wrapped pattern is kept whole; the stabilisation adds, and far fewer than dense.
        let set: BTreeSet<_> = pattern.iter().copied().collect();
        assert!(wrapped.is_subset(&set));
        assert!(pattern.len() < m * m / 4, "{} of {}", pattern.len(), m * m);
        let mut written = BTreeSet::new();
        for _ in 0..5 {
            // Anywhere: off the constraints, with non-zero multipliers, mu and derivatives.
            let y: Vec<f64> = (0..m).map(|_| jitter.next()).collect();
            let yp: Vec<f64> = (0..m).map(|_| jitter.next()).collect();
            let t = jitter.next();
            for c in [0.0, 1.0, 3.7, 1e3 * (1.5 + jitter.next())] {
                let mut rec = Recorder {
                    n: m,
                    written: BTreeSet::new(),
                };
                s.iteration_matrix(t, &y, &yp, c, &mut rec);
                let outside: Vec<_> = rec.written.difference(&set).collect();
                assert!(outside.is_empty(), "exact {exact}, c {c}: {outside:?}");
                written.extend(rec.written);
            }
        }
        // And it is tight: every entry the stabilisation adds is written at some point.
        let unwritten: Vec<_> = set
            .difference(&wrapped)
            .filter(|e| !written.contains(e))
            .collect();
        assert!(unwritten.is_empty(), "exact {exact}: {unwritten:?}");
    }
    // The entries added: per constraint of link `k` and per position it involves (those of
    // masses `k - 1` and `k`, two for the first link), its `mu` in the position's kinematic
    // row and its hidden row at the position and at its velocity.
    let chain = Chain::new(6);
    let added = stabilise(chain).iteration_pattern().unwrap().len()
        - chain.iteration_pattern().unwrap().len();
    assert_eq!(added, 3 * 2 + 5 * (3 * 4));
}

#[test]
fn without_a_declared_pattern_the_form_is_dense() {
    let chain = Chain {
        pattern: false,
        ..Chain::new(3)
    };
    assert!(stabilise(chain).iteration_pattern().is_none());
    assert!(!FaerLu::for_dae(&stabilise(chain)).is_sparse());
    // Without constraints the pattern is the wrapped one, sorted.
    let s = Stabilised::new(Chain::new(3), vec![], vec![]).unwrap();
    let mut p = Chain::new(3).iteration_pattern().unwrap();
    p.sort_unstable();
    assert_eq!(s.iteration_pattern(), Some(p));
}

/// The integrator on the stabilised chain at `tol` to `t_end`, with the linear solver `ls`
/// (`None`: the one `Radau::stabilised` or `Bdf::stabilised` picks): the final state and the
/// steps.
fn run(chain: Chain, bdf: bool, (tol, t_end): (f64, f64), ls: Option<FaerLu>) -> (Vec<f64>, usize) {
    let (y0, yp0) = chain.initial();
    let mut out = vec![0.0; chain.dimension() + chain.links];
    let steps = if bdf {
        let opts = bdf::Options::with_tolerances(tol, tol);
        let mut b = match ls {
            None => Bdf::stabilised(chain, opts, 0.0, &y0, &yp0).unwrap(),
            Some(ls) => {
                let s = Stabilised::detect(chain, 0.0, &y0, &yp0).unwrap();
                let (y, yp) = s.extend(&y0, &yp0);
                let index = s.index();
                Bdf::new(s, ls, bdf::Options { index, ..opts }, 0.0, &y, &yp).unwrap()
            }
        };
        b.solve_to(t_end, &mut out, None).unwrap();
        b.stats().steps
    } else {
        let opts = radau::Options::with_tolerances(tol, tol);
        let mut r = match ls {
            None => Radau::stabilised(chain, opts, 0.0, &y0, &yp0).unwrap(),
            Some(ls) => {
                let s = Stabilised::detect(chain, 0.0, &y0, &yp0).unwrap();
                let (y, yp) = s.extend(&y0, &yp0);
                let index = s.index();
                Radau::new(s, ls, radau::Options { index, ..opts }, 0.0, &y, &yp).unwrap()
            }
        };
        r.solve_to(t_end, &mut out, None).unwrap();
        r.stats().steps
    };
    (out, steps)
}

#[test]
fn a_long_chain_is_solved_with_the_sparse_lu() {
    let chain = Chain::new(20);
    let (y0, yp0) = chain.initial();
    let s = Stabilised::detect(chain, 0.0, &y0, &yp0).unwrap();
    // detect finds the rows `stabilise` gives, so the pattern is the same.
    assert_eq!(s.iteration_pattern(), stabilise(chain).iteration_pattern());
    let m = s.dimension();
    let nnz = s.iteration_pattern().unwrap().len();
    assert!(
        (nnz as f64) < SPARSE_DENSITY * (m * m) as f64,
        "{nnz} of {m}^2"
    );
    assert!(FaerLu::for_dae(&s).is_sparse());
    let (tol, t_end) = (1e-6, 0.3);
    for bdf in [false, true] {
        let (sparse, steps) = run(chain, bdf, (tol, t_end), Some(FaerLu::for_dae(&s)));
        // `Radau::stabilised` (`Bdf::stabilised`) picks the same solver: the same run to the
        // bit.
        let (picked, picked_steps) = run(chain, bdf, (tol, t_end), None);
        assert_eq!(picked_steps, steps);
        assert!(picked
            .iter()
            .zip(&sparse)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let dense_ls = FaerLu::Dense(FaerDenseLu::new(m));
        let (dense, dense_steps) = run(chain, bdf, (tol, t_end), Some(dense_ls));
        // Only the LU's round-off differs: the positions agree far within the tolerance.
        let worst = (0..chain.links)
            .flat_map(|k| [5 * k, 5 * k + 1])
            .map(|j| (sparse[j] - dense[j]).abs())
            .fold(0.0, f64::max);
        let scale = (0..chain.links)
            .flat_map(|k| [5 * k, 5 * k + 1])
            .map(|j| dense[j].abs())
            .fold(0.0, f64::max);
        println!(
            "bdf {bdf}: {steps} steps (dense {dense_steps}); positions differ by {worst:.1e} \
             ({:.1e} of the largest)",
            worst / scale
        );
        assert!(worst < tol, "bdf {bdf}: {worst}");
        if !bdf {
            // Radau keeps J, M and the complex stage matrix in the pattern too: the dense
            // run's steps, the positions within round-off.
            assert_eq!(steps, dense_steps);
            assert!(worst < 1e-12 * scale, "{worst} of {scale}");
        }
        // The chain fell and kept its links.
        assert!(sparse[1] < -1e-3);
        for k in 0..chain.links {
            let (dx, dy) = Chain::link(&sparse, k);
            assert!((dx.hypot(dy) - chain.l).abs() < 1e-6, "bdf {bdf}: link {k}");
        }
    }
}

/// Radau and the BDF on stabilised chains of 20, 40 and 80 links at `1e-6` to `t = 0.3`, with
/// the pattern declared (the sparse LU) and without (dense): median wall times of 5 runs,
/// set-up included.
#[test]
#[ignore = "timing run: release mode"]
fn chain_times_with_and_without_the_pattern() {
    for bdf in [false, true] {
        for links in [20, 40, 80] {
            let mut row = Vec::new();
            for pattern in [true, false] {
                let chain = Chain {
                    pattern,
                    ..Chain::new(links)
                };
                let mut times = Vec::new();
                let mut steps = 0;
                for _ in 0..5 {
                    let start = Instant::now();
                    steps = run(chain, bdf, (1e-6, 0.3), None).1;
                    times.push(start.elapsed().as_secs_f64() * 1e3);
                }
                times.sort_by(f64::total_cmp);
                row.push((times[2], steps));
            }
            println!(
                "{} chain {links} links ({} unknowns): with the pattern {:.1} ms ({} steps), \
                 without {:.1} ms ({} steps)",
                if bdf { "BDF" } else { "Radau" },
                6 * links,
                row[0].0,
                row[0].1,
                row[1].0,
                row[1].1
            );
        }
    }
}
