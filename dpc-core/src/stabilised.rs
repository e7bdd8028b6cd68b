//! Index reduction of a mechanical DAE by the stabilisation of Gear, Gupta and Leimkuhler
//! (GGL; "Automatic integration of Euler-Lagrange equations with constraints", J. Comput. Appl.
//! Math. 12-13, 1985).
//!
//! A DAE `F(t, y, y') = 0` of index 3 with position constraints `0 = g(t, q)` and kinematic
//! rows `c_j q_j' = phi_j(t, y)` (one per position coordinate `q_j` the constraints involve)
//! becomes, with one more unknown `mu_a` per constraint,
//!
//! ```text
//! F(t, y, y') + c_j sum_a G_aj mu_a = 0           (the kinematic rows: q' = phi - G^T mu)
//! G(t, q) phi(t, y) + dg/dt = 0                   (the hidden velocity constraints)
//! ```
//!
//! with `G = dg/dq`. Exact solutions have `mu = 0` and satisfy the position and the velocity
//! constraints; the system is of index 2 (Hessenberg form in `(q, v)` and `(lambda, mu)`), so an
//! integrator controls the error of the velocities as strictly as that of the positions, and
//! the multipliers converge at the order of index-2 components. In the index-3 form the
//! velocities' and multipliers' error weights must be relaxed by the step size (`h` and `h^2`,
//! as RADAU5 does), which leaves them far less accurate at the same tolerance.
//!
//! [`Stabilised`] wraps any [`ImplicitDae`]; it reads `G` and `c_j` from the wrapped DAE's
//! iteration matrix, so the user writes the model once: `dg/dt` (for a constraint that moves
//! with time) is a central difference of the residual in `t` with a step of `cbrt(eps)`
//! wherever `t` lies (truncation error `6e-12 |d^3 g/dt^3|`, exactly zero for a constraint
//! without `t`), and the second derivatives of the constraints that the hidden constraints'
//! row of Newton's iteration matrix needs (`(dG/dq) phi`) are one central difference of the
//! gradient along the motion. The term `(dG/dq)^T mu` is left out of
//! the iteration matrix (it vanishes with `mu`); simplified Newton converges with it, at a rate
//! the integrator monitors.
//!
//! ```
//! use dpc_core::stabilised::Stabilised;
//! use dpc_core::{ImplicitDae, MatrixSink};
//!
//! /// The pendulum of length 1 in Cartesian coordinates, index 3:
//! /// x' = u, y' = v, u' = -x l, v' = -y l - 1, 0 = x^2 + y^2 - 1.
//! struct Pendulum;
//! impl ImplicitDae for Pendulum {
//!     fn dimension(&self) -> usize { 5 }
//!     fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
//!         out[0] = yp[0] - y[2];
//!         out[1] = yp[1] - y[3];
//!         out[2] = yp[2] + y[0] * y[4];
//!         out[3] = yp[3] + y[1] * y[4] + 1.0;
//!         out[4] = y[0] * y[0] + y[1] * y[1] - 1.0;
//!     }
//!     fn iteration_matrix<S: MatrixSink + ?Sized>(
//!         &self, _t: f64, y: &[f64], _yp: &[f64], c: f64, out: &mut S,
//!     ) {
//!         for i in 0..4 { out.set(i, i, c); }
//!         out.set(0, 2, -1.0);
//!         out.set(1, 3, -1.0);
//!         out.set(2, 0, y[4]);
//!         out.set(2, 4, y[0]);
//!         out.set(3, 1, y[4]);
//!         out.set(3, 4, y[1]);
//!         out.set(4, 0, 2.0 * y[0]);
//!         out.set(4, 1, 2.0 * y[1]);
//!     }
//!     fn is_differential(&self, i: usize) -> bool { i < 4 }
//! }
//!
//! // Row 4 is the position constraint; rows 0 and 1 give x' and y'.
//! let s = Stabilised::new(Pendulum, vec![4], vec![(0, 0), (1, 1)]).unwrap();
//! assert_eq!(s.dimension(), 6);
//! // At a consistent point (hanging at rest, l = 1) with mu = 0 every residual is zero.
//! let (y, yp) = ([0.0, -1.0, 0.0, 0.0, 1.0, 0.0], [0.0; 6]);
//! let mut r = [1.0; 6];
//! s.residual(0.0, &y, &yp, &mut r);
//! assert!(r.iter().all(|v| v.abs() < 1e-15));
//! ```

use std::cell::RefCell;

use nalgebra::DMatrix;

use crate::{ImplicitDae, MatrixSink};

/// A malformed description of the constraints of [`Stabilised::new`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StabilisedError {
    /// A row or unknown index is not below the DAE's dimension.
    #[error("{what} {index} is out of range: the DAE has {dimension} equations and unknowns")]
    OutOfRange {
        /// What the index designates ("constraint row", "kinematic row", "position unknown").
        what: &'static str,
        /// The index given.
        index: usize,
        /// The DAE's dimension.
        dimension: usize,
    },
    /// A row or unknown is named twice, or a constraint row is also a kinematic row.
    #[error("{what} {index} is given twice")]
    Repeated {
        /// What the index designates.
        what: &'static str,
        /// The index given twice.
        index: usize,
    },
}

/// Work of one evaluation: the wrapped DAE's residual and its Jacobians.
struct Scratch {
    res: Vec<f64>,
    /// The residual at `t + dt` and `t - dt`, for the constraints' time derivative.
    res_plus: Vec<f64>,
    res_minus: Vec<f64>,
    /// `dF/dy`.
    f_y: DMatrix<f64>,
    /// `dF/dy'`.
    f_yp: DMatrix<f64>,
    /// `dF/dy + c dF/dy'`.
    f_c: DMatrix<f64>,
    /// `y` moved along the velocities, and `dF/dy` there (forwards and backwards).
    y_moved: Vec<f64>,
    f_y_plus: DMatrix<f64>,
    f_y_minus: DMatrix<f64>,
}

/// The GGL-stabilised index-2 form of an index-3 DAE (see the [module documentation](self)).
///
/// Unknowns and equations: those of the wrapped DAE, then one multiplier `mu_a` and one
/// hidden velocity constraint per position constraint, in the order given.
pub struct Stabilised<D> {
    dae: D,
    /// The position-constraint rows.
    rows: Vec<usize>,
    /// `(q_j, row)`: the position unknowns with their kinematic rows.
    kinematic: Vec<(usize, usize)>,
    scratch: RefCell<Scratch>,
}

impl<D: ImplicitDae> Stabilised<D> {
    /// Stabilise `dae`'s position constraints `rows` (equations that depend on positions
    /// only), with, per position unknown `q_j` that they involve, its kinematic row:
    /// `kinematic = [(j, row), ...]`, the row whose only derivative is `q_j'`.
    ///
    /// # Errors
    /// [`StabilisedError`] for an index out of range or a repeated row or unknown. Without
    /// constraints the stabilised form is the DAE itself.
    pub fn new(
        dae: D,
        rows: Vec<usize>,
        kinematic: Vec<(usize, usize)>,
    ) -> Result<Self, StabilisedError> {
        let n = dae.dimension();
        let mut seen_rows = vec![false; n];
        let mut seen_unknowns = vec![false; n];
        let listed = rows.iter().map(|&r| ("constraint row", r, true)).chain(
            kinematic
                .iter()
                .flat_map(|&(j, r)| [("position unknown", j, false), ("kinematic row", r, true)]),
        );
        for (what, index, is_row) in listed {
            if index >= n {
                return Err(StabilisedError::OutOfRange {
                    what,
                    index,
                    dimension: n,
                });
            }
            let seen = if is_row {
                &mut seen_rows
            } else {
                &mut seen_unknowns
            };
            if std::mem::replace(&mut seen[index], true) {
                return Err(StabilisedError::Repeated { what, index });
            }
        }
        let scratch = RefCell::new(Scratch {
            res: vec![0.0; n],
            res_plus: vec![0.0; n],
            res_minus: vec![0.0; n],
            f_y: DMatrix::zeros(n, n),
            f_yp: DMatrix::zeros(n, n),
            f_c: DMatrix::zeros(n, n),
            y_moved: vec![0.0; n],
            f_y_plus: DMatrix::zeros(n, n),
            f_y_minus: DMatrix::zeros(n, n),
        });
        Ok(Self {
            dae,
            rows,
            kinematic,
            scratch,
        })
    }

    /// The wrapped DAE.
    pub fn inner(&self) -> &D {
        &self.dae
    }

    /// Number of position constraints (and of multipliers `mu`).
    pub fn n_constraints(&self) -> usize {
        self.rows.len()
    }

    /// The stabilised unknowns `(y, mu = 0)` and derivatives `(y', 0)` from a consistent
    /// point of the wrapped DAE.
    pub fn extend(&self, y: &[f64], yp: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let p = self.rows.len();
        let mut ys = y.to_vec();
        ys.extend(std::iter::repeat_n(0.0, p));
        let mut yps = yp.to_vec();
        yps.extend(std::iter::repeat_n(0.0, p));
        (ys, yps)
    }

    /// `dF/dy` and `dF/dy'` of the wrapped DAE at `(t, y, y')`, from its iteration matrix at
    /// `c = 0` and `c = 1`.
    fn jacobians(&self, t: f64, y: &[f64], yp: &[f64], sc: &mut Scratch) {
        sc.f_y.fill(0.0);
        self.dae.iteration_matrix(t, y, yp, 0.0, &mut sc.f_y);
        sc.f_yp.fill(0.0);
        self.dae.iteration_matrix(t, y, yp, 1.0, &mut sc.f_yp);
        sc.f_yp -= &sc.f_y;
    }

    /// The hidden constraints' dependence through `G` and `dg/dt`: `d/dq_k (G(t, q) phi + dg/dt)`
    /// at fixed `phi` is `sum_j d^2 g/dq_j dq_k phi_j + d^2 g/dt dq_k`, the derivative of the
    /// gradient `G_k` along `(1, phi)` (the Hessian is symmetric), taken as one central
    /// difference of `dF/dy` along the motion. Without it, simplified Newton converges slowly
    /// (for the pendulum the term is `2 (x', y')`, as large as the rest of the row).
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        sc: &mut Scratch,
        out: &mut S,
    ) {
        let n = self.dae.dimension();
        self.dae.residual(t, &y[..n], &yp[..n], &mut sc.res);
        let (mut q_max, mut phi_max) = (0.0f64, 0.0f64);
        for &(j, i) in &self.kinematic {
            q_max = q_max.max(y[j].abs());
            phi_max = phi_max.max((yp[j] - sc.res[i] / sc.f_yp[(i, j)]).abs());
        }
        // A step of cbrt(eps) relative to the positions and to time.
        let mut eps = f64::EPSILON.cbrt() * t.abs().max(1.0);
        if phi_max > 0.0 {
            eps = eps.min(f64::EPSILON.cbrt() * (1.0 + q_max) / phi_max);
        }
        for (sign, plus) in [(1.0, true), (-1.0, false)] {
            sc.y_moved.copy_from_slice(&y[..n]);
            for &(j, i) in &self.kinematic {
                let phi = yp[j] - sc.res[i] / sc.f_yp[(i, j)];
                sc.y_moved[j] += sign * eps * phi;
            }
            let m = if plus {
                &mut sc.f_y_plus
            } else {
                &mut sc.f_y_minus
            };
            m.fill(0.0);
            self.dae
                .iteration_matrix(t + sign * eps, &sc.y_moved, &yp[..n], 0.0, m);
        }
        for (a, &g) in self.rows.iter().enumerate() {
            for &(k, _) in &self.kinematic {
                let d = (sc.f_y_plus[(g, k)] - sc.f_y_minus[(g, k)]) / (2.0 * eps);
                if d != 0.0 && d.is_finite() {
                    out.add(n + a, k, d);
                }
            }
        }
    }

    /// The stabilisation's terms: per constraint `a` (row `g`) and position unknown `j` (with
    /// kinematic row `i`) where `G_aj = dF_g/dy_j` is not zero, `(a, i, j, G_aj, c_j)` with
    /// `c_j = dF_i/dy_j'`.
    fn terms<'s>(
        &'s self,
        sc: &'s Scratch,
    ) -> impl Iterator<Item = (usize, usize, usize, f64, f64)> + 's {
        self.rows.iter().enumerate().flat_map(move |(a, &g)| {
            self.kinematic.iter().filter_map(move |&(j, i)| {
                let gj = sc.f_y[(g, j)];
                (gj != 0.0).then(|| (a, i, j, gj, sc.f_yp[(i, j)]))
            })
        })
    }
}

impl<D: ImplicitDae> ImplicitDae for Stabilised<D> {
    fn dimension(&self) -> usize {
        self.dae.dimension() + self.rows.len()
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        if self.rows.is_empty() {
            return self.dae.residual(t, y, yp, out);
        }
        let n = self.dae.dimension();
        let sc = &mut *self.scratch.borrow_mut();
        self.dae.residual(t, &y[..n], &yp[..n], &mut sc.res);
        self.jacobians(t, &y[..n], &yp[..n], sc);
        out[..n].copy_from_slice(&sc.res);
        out[n..].fill(0.0);
        // A constraint that depends on time (a prescribed motion of the support, for
        // example) has the hidden constraint G phi + dg/dt = 0; dg/dt by a central difference
        // (zero exactly for a constraint without t). Its truncation error, dt^2 |d3g/dt3| / 6,
        // does not depend on where the time origin lies, so neither does the step: it only
        // stays far above the ulp of t, and the difference is divided by the distance of the
        // two times as rounded.
        let dt = f64::EPSILON.cbrt().max(f64::EPSILON.sqrt() * t.abs());
        let (t_plus, t_minus) = (t + dt, t - dt);
        self.dae
            .residual(t_plus, &y[..n], &yp[..n], &mut sc.res_plus);
        self.dae
            .residual(t_minus, &y[..n], &yp[..n], &mut sc.res_minus);
        for (a, &g) in self.rows.iter().enumerate() {
            let d = sc.res_plus[g] - sc.res_minus[g];
            if d != 0.0 {
                out[n + a] = d / (t_plus - t_minus);
            }
        }
        let mu = &y[n..];
        for (a, i, j, gj, cj) in self.terms(sc) {
            // q_j' - F_i / c_j is the velocity phi_j the kinematic row gives (F_i = c_j (q_j' - phi_j)).
            out[n + a] += gj * (yp[j] - sc.res[i] / cj);
            out[i] += cj * gj * mu[a];
        }
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        if self.rows.is_empty() {
            return self.dae.iteration_matrix(t, y, yp, c, out);
        }
        let n = self.dae.dimension();
        let sc = &mut *self.scratch.borrow_mut();
        self.jacobians(t, &y[..n], &yp[..n], sc);
        let Scratch { f_y, f_yp, f_c, .. } = &mut *sc;
        for (d, (a, b)) in f_c.iter_mut().zip(f_y.iter().zip(f_yp.iter())) {
            *d = a + c * b;
        }
        for k in 0..n {
            for r in 0..n {
                let v = sc.f_c[(r, k)];
                if v != 0.0 {
                    out.set(r, k, v);
                }
            }
        }
        let Scratch { f_c, .. } = &*sc;
        for (a, i, j, gj, cj) in self.terms(sc) {
            out.add(i, n + a, cj * gj);
            // d/dy + c d/dy' of G_aj (q_j' - F_i / c_j) at fixed G and c_j.
            out.add(n + a, j, gj * c);
            for k in 0..n {
                let v = f_c[(i, k)];
                if v != 0.0 {
                    out.add(n + a, k, -gj * v / cj);
                }
            }
        }
        self.constraint_curvature(t, y, yp, sc, out);
    }

    fn is_differential(&self, i: usize) -> bool {
        i < self.dae.dimension() && self.dae.is_differential(i)
    }

    fn equation_name(&self, i: usize) -> String {
        let n = self.dae.dimension();
        if i < n {
            self.dae.equation_name(i)
        } else {
            format!(
                "the hidden velocity constraint of {}",
                self.dae.equation_name(self.rows[i - n])
            )
        }
    }

    fn unknown_name(&self, i: usize) -> String {
        let n = self.dae.dimension();
        if i < n {
            self.dae.unknown_name(i)
        } else {
            format!(
                "the stabilising multiplier of {}",
                self.dae.equation_name(self.rows[i - n])
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y0' = y1, y1' = -y2 y0, 0 = y0 - sin t` (a prescribed motion): index 3.
    struct Moving;
    impl ImplicitDae for Moving {
        fn dimension(&self) -> usize {
            3
        }
        fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = 2.0 * (yp[0] - y[1]);
            out[1] = yp[1] + y[2] * y[0];
            out[2] = y[0] - t.sin();
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _t: f64,
            y: &[f64],
            _yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            out.set(0, 0, 2.0 * c);
            out.set(0, 1, -2.0);
            out.set(1, 1, c);
            out.set(1, 0, y[2]);
            out.set(1, 2, y[0]);
            out.set(2, 0, 1.0);
        }
    }

    #[test]
    fn malformed_constraints_are_refused() {
        let e = |rows: Vec<usize>, kin: Vec<(usize, usize)>| {
            Stabilised::new(Moving, rows, kin)
                .err()
                .map(|e| e.to_string())
        };
        assert_eq!(
            e(vec![3], vec![(0, 0)]),
            Some("constraint row 3 is out of range: the DAE has 3 equations and unknowns".into())
        );
        assert_eq!(
            e(vec![2], vec![(0, 0), (0, 1)]),
            Some("position unknown 0 is given twice".into())
        );
        assert_eq!(
            e(vec![2], vec![(0, 2)]),
            Some("kinematic row 2 is given twice".into())
        );
        assert!(e(vec![2], vec![(0, 0)]).is_none());
    }

    #[test]
    fn moving_constraint_far_from_the_time_origin() {
        // dg/dt of the prescribed motion y0 = sin t is as accurate at t = 100 as near 0: the
        // difference step does not grow with |t| (with a step of cbrt(eps) |t| the hidden
        // constraint was off by 5e-8 here, the truncation error dt^2 |cos t| / 6).
        let s = Stabilised::new(Moving, vec![2], vec![(0, 0)]).unwrap();
        for t in [0.3f64, 3.0, 100.0] {
            let y = [t.sin(), t.cos(), 1.0, 0.0];
            let yp = [t.cos(), -t.sin(), 0.0, 0.0];
            let mut r = [1.0; 4];
            s.residual(t, &y, &yp, &mut r);
            assert!(r[3].abs() < 1e-9, "t {t}: {r:?}");
        }
    }

    #[test]
    fn moving_constraint_and_scaled_kinematic_row() {
        // On the exact solution y0 = sin t, y1 = cos t, y2 = 1 (mu = 0) every residual of the
        // stabilised form vanishes: the hidden constraint is y1 - cos t = 0 (G phi + dg/dt
        // with the kinematic row's coefficient 2 divided out).
        let s = Stabilised::new(Moving, vec![2], vec![(0, 0)]).unwrap();
        let t: f64 = 0.7;
        let y = [t.sin(), t.cos(), 1.0, 0.0];
        let yp = [t.cos(), -t.sin(), 0.0, 0.0];
        let mut r = [1.0; 4];
        s.residual(t, &y, &yp, &mut r);
        assert!(r.iter().all(|v| v.abs() < 1e-9), "{r:?}");
        // Off the solution, the hidden constraint measures the velocity error.
        let y_off = [t.sin(), t.cos() + 1e-3, 1.0, 0.0];
        s.residual(t, &y_off, &yp, &mut r);
        assert!((r[3] - 1e-3).abs() < 1e-9, "{r:?}");
        // The iteration matrix against central differences of the residual, at mu = 0 (where
        // the left-out term (dG/dq)^T mu vanishes): d/dy + c d/dy'.
        let c = 3.0;
        let mut m = DMatrix::zeros(4, 4);
        s.iteration_matrix(t, &y_off, &yp, c, &mut m);
        let h = 1e-6;
        for k in 0..4 {
            let (mut yk, mut ypk) = (y_off, yp);
            yk[k] += h;
            ypk[k] += c * h;
            let mut plus = [0.0; 4];
            s.residual(t, &yk, &ypk, &mut plus);
            yk[k] -= 2.0 * h;
            ypk[k] -= 2.0 * c * h;
            let mut minus = [0.0; 4];
            s.residual(t, &yk, &ypk, &mut minus);
            for i in 0..4 {
                let fd = (plus[i] - minus[i]) / (2.0 * h);
                assert!(
                    (m[(i, k)] - fd).abs() < 1e-6,
                    "({i}, {k}): {} vs {fd}",
                    m[(i, k)]
                );
            }
        }
    }
}
