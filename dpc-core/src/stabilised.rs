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
//! [`Stabilised`] wraps any [`ImplicitDae`], so the user writes the model once, and
//! [`Stabilised::detect`] finds its position constraints and kinematic rows from its iteration
//! matrices (or [`Stabilised::new`] takes them as given); with Radau this is the documented
//! default for DAEs of index 3 (docs/integrators.md measures both forms). It needs, at
//! every residual, `G` (the constraint rows' gradients at the positions), `dg/dt` and the
//! kinematic rows' coefficients `c_j = dF_i/dq_j'`, and for Newton's iteration matrix also the
//! constraints' curvature `d/dq (G(t, q) phi + dg/dt)` at fixed `phi` (the term `(dG/dq)^T mu`
//! is left out of the iteration matrix: it vanishes with `mu`, and simplified Newton converges
//! without it at a rate the integrator monitors). Each comes from the wrapped DAE's exact
//! derivatives when it supplies them ([`ImplicitDae::constraint_gradient`],
//! [`ImplicitDae::constraint_time_derivative`], [`ImplicitDae::constraint_curvature`]; each
//! is optional), else from differences:
//!
//! * `G` from the wrapped DAE's iteration matrix at `c = 0`, and `c_j` from it at `c = 1`
//!   (with exact gradients, `c_j` from one residual with `q'` moved: the kinematic rows are
//!   linear in `q_j'`); only the entries needed are kept (sparse, by row). `c_j` is evaluated
//!   with each iteration matrix and held by the residuals until the next one (the first
//!   residual before any matrix evaluates its own): any non-zero `c_j` gives the same
//!   solutions (`mu = 0`, `F = 0`), only the scaling of the multipliers' terms and the
//!   velocities `phi_j` read off away from them, and the integrator holds its iteration
//!   matrix through steps just the same;
//! * `dg/dt` (for a constraint that moves with time) as a central difference of the residual
//!   in `t` with a step of `cbrt(eps)` wherever `t` lies (truncation error
//!   `6e-12 |d^3 g/dt^3|`, exactly zero for a constraint without `t`);
//! * the curvature as one central difference of `G` along the motion `(1, phi)`.
//!
//! Per residual the stabilised form costs one residual of the wrapped DAE and its exact
//! derivatives, or three residuals and an iteration matrix without them (a residual before the
//! first iteration matrix: one more residual, or one more matrix, for `c_j`); per iteration
//! matrix, the wrapped DAE's iteration matrix, two residuals and the exact derivatives, or
//! four iteration matrices and a residual without them; `c_j` is read off the wrapped DAE's
//! mass matrix instead when it supplies one ([`ImplicitDae::mass_matrix`]), one residual or one
//! iteration matrix less. Its own mass matrix `dF/dy'` is the wrapped DAE's (the
//! stabilisation adds no `y'`), at the cost of the wrapped one.
//!
//! A wrapped DAE that declares its iteration matrix's pattern
//! ([`ImplicitDae::iteration_pattern`]) keeps it: the stabilised form declares the wrapped
//! pattern with the entries the stabilisation writes (per constraint `a`, the column of `mu_a`
//! in the kinematic rows of the positions its constraint involves, and the hidden row `n + a`
//! at those positions and at every unknown of their kinematic rows), read off the wrapped
//! pattern's structure, so that a large sparse model (a chain of many links) is solved with a
//! sparse or banded LU ([`FaerLu::for_dae`](crate::linear_solver::FaerLu::for_dae)) in either
//! form. Without a declared pattern the stabilised form is dense, as the wrapped one.
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
//!     // Optional: the constraint's derivatives by hand (without them, differences).
//!     fn constraint_gradient<S: MatrixSink + ?Sized>(&self, _t: f64, y: &[f64], out: &mut S) -> bool {
//!         out.set(4, 0, 2.0 * y[0]);
//!         out.set(4, 1, 2.0 * y[1]);
//!         true
//!     }
//!     fn constraint_time_derivative(&self, _t: f64, _y: &[f64], _out: &mut [f64]) -> bool {
//!         true // the constraint does not depend on t
//!     }
//!     fn constraint_curvature<S: MatrixSink + ?Sized>(
//!         &self, _t: f64, _y: &[f64], v: &[f64], out: &mut S,
//!     ) -> bool {
//!         // d/d(x, y) of 2 x v_x + 2 y v_y
//!         out.set(4, 0, 2.0 * v[0]);
//!         out.set(4, 1, 2.0 * v[1]);
//!         true
//!     }
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

use crate::sink::{Selection, Tee, Triplets};
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
    /// [`Stabilised::detect`]: the iteration matrix at the given point has a non-finite
    /// entry, so its structure cannot be read there.
    #[error("the iteration matrix is not finite at the given point: d({equation})/d({unknown}) is NaN or infinite")]
    NonFinite {
        /// The equation's name ([`ImplicitDae::equation_name`]).
        equation: String,
        /// The unknown's name ([`ImplicitDae::unknown_name`]).
        unknown: String,
    },
    /// [`Stabilised::detect`]: the given point's lengths differ from the DAE's dimension.
    #[error("the point has {y} values and {yp} derivatives, the DAE {dimension} unknowns")]
    Dimension {
        /// Length of `y`.
        y: usize,
        /// Length of `y'`.
        yp: usize,
        /// The DAE's dimension.
        dimension: usize,
    },
}

/// Work of one evaluation: the wrapped DAE's residual and the few entries of its Jacobians
/// the stabilisation reads, kept sparse (nothing here grows with the square of the dimension,
/// nor with the constraints times the positions).
struct Scratch {
    res: Vec<f64>,
    /// The residual at `t + dt` and `t - dt` (the constraints' time derivative by
    /// differences), or at `y'` moved (the kinematic coefficients `c_j`).
    res_plus: Vec<f64>,
    res_minus: Vec<f64>,
    /// `y'` moved along the position unknowns (the kinematic coefficients by a difference).
    yp_moved: Vec<f64>,
    /// `dF_g/dt` of the constraint rows, when the DAE supplies it.
    dgdt: Vec<f64>,
    /// `G` (constraint rows, position columns) and, when `G` comes from the iteration matrix
    /// at `c = 0`, `dF_i/dq_j` of the kinematic rows.
    grad: Selection,
    /// The same entries of `dF/dy'` (for `c_j`, when the DAE supplies it) or of the iteration
    /// matrix at `c = 1` (for `c_j` when neither it nor `G` is supplied).
    grad_c1: Selection,
    /// `c_j = dF_i/dq_j'` per kinematic pair.
    coef: Vec<f64>,
    /// `coef` was evaluated with the last iteration matrix and is held by the residual.
    coef_held: bool,
    /// `phi_j` per kinematic pair (the residual's copy, in pair order).
    pair_phi: Vec<f64>,
    /// The velocities `phi_j` the kinematic rows give, per unknown (zero off the positions).
    phi: Vec<f64>,
    /// The kinematic rows of `dF/dy + c dF/dy'`, every column.
    kin_c: Selection,
    /// The constraints' curvature (constraint rows, position columns), when supplied.
    curv: Selection,
    /// `y` moved along the velocities, and `G` there (forwards and backwards).
    y_moved: Vec<f64>,
    grad_plus: Selection,
    grad_minus: Selection,
    /// The non-zero entries of `G` by kinematic pair: pair `p`'s `(constraint, G_ap)` at
    /// `by_pair[by_pair_start[p]..by_pair_start[p + 1]]`, constraints ascending
    /// (`by_pair_next` the fill's cursor per pair).
    by_pair: Vec<(usize, f64)>,
    by_pair_start: Vec<usize>,
    by_pair_next: Vec<usize>,
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
    /// Per unknown of the wrapped DAE, whether it appears differentiated.
    differential: Vec<bool>,
    /// The error-control index of the algebraic unknowns and `mu` ([`Self::index`]).
    algebraic_index: u8,
    scratch: RefCell<Scratch>,
}

/// What [`Stabilised::start`] reads: the stabilised form, its initial values, the index of
/// its unknowns and its linear solver.
pub(crate) struct StabilisedStart<D> {
    pub form: Stabilised<D>,
    pub y: Vec<f64>,
    pub yp: Vec<f64>,
    pub ls: crate::linear_solver::FaerLu,
    pub index: Vec<u8>,
}

impl<D: ImplicitDae> Stabilised<D> {
    /// Stabilise `dae`'s position constraints `rows` (equations that depend on positions
    /// only), with, per position unknown `q_j` that they involve, its kinematic row:
    /// `kinematic = [(j, row), ...]`, the row whose only derivative is `q_j'`, linear in it.
    ///
    /// Which unknowns are differential (for [`Self::index`]) is read from
    /// [`ImplicitDae::is_differential`]; [`Self::detect`] finds rows, pairs and differential
    /// unknowns by itself.
    ///
    /// # Errors
    /// [`StabilisedError`] for an index out of range or a repeated row or unknown. Without
    /// constraints the stabilised form is the DAE itself.
    pub fn new(
        dae: D,
        rows: Vec<usize>,
        kinematic: Vec<(usize, usize)>,
    ) -> Result<Self, StabilisedError> {
        let differential = (0..dae.dimension())
            .map(|i| dae.is_differential(i))
            .collect();
        let algebraic_index = if rows.is_empty() { 1 } else { 2 };
        Self::with_differential(dae, rows, kinematic, differential, algebraic_index)
    }

    /// Stabilise the position constraints of `dae` found from its structure, read at the
    /// consistent point `(t, y, y')` (or any point where the iteration matrix is finite) and at
    /// two points near it (so that an entry that happens to vanish at the given point, such as
    /// `yb(0) = 0` in the car axis' constraint, is still seen):
    ///
    /// * an unknown is *differential* when its derivative appears in some equation
    ///   (`dF/dy'` has an entry in its column), else *algebraic* (the multipliers);
    /// * a *kinematic row* of a differential unknown `q_j` is an equation whose only
    ///   derivative is `q_j'` and which has no algebraic unknown (`q_j' = v_j`, `c q_j' = ...`);
    /// * a *position constraint* is an equation without derivatives and without algebraic
    ///   unknowns all of whose unknowns have kinematic rows (`0 = g(t, q)`); a constraint on
    ///   unknowns without kinematic rows (a velocity constraint, of index 2) is left as
    ///   declared.
    ///
    /// The same classification as the closed loop applies to generated plants
    /// ([`crate::consistent::ConstraintStructure`]), here from the values of the iteration
    /// matrices at `c = 0` and `c = 2^20` (their difference is `2^20 dF/dy'`). With the result
    /// integrate with [`crate::radau::Radau`] and [`Self::index`] as its
    /// [`index`](crate::radau::Options::index): the documented default for a DAE of index 3
    /// (docs/integrators.md gives the accuracy of both forms; [`crate::radau::Radau::stabilised`]
    /// does all of it in one call, [`crate::bdf::Bdf::stabilised`] with the BDF); the DAE as
    /// declared, with the index-3 error scaling, is the alternative.
    ///
    /// ```
    /// use dpc_core::stabilised::Stabilised;
    /// use dpc_core::{ImplicitDae, MatrixSink};
    ///
    /// /// The pendulum of length 1: x' = u, y' = v, u' = -x l, v' = -y l - 1, 0 = x^2 + y^2 - 1.
    /// struct Pendulum;
    /// impl ImplicitDae for Pendulum {
    ///     fn dimension(&self) -> usize { 5 }
    ///     fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
    ///         out[0] = yp[0] - y[2];
    ///         out[1] = yp[1] - y[3];
    ///         out[2] = yp[2] + y[0] * y[4];
    ///         out[3] = yp[3] + y[1] * y[4] + 1.0;
    ///         out[4] = y[0] * y[0] + y[1] * y[1] - 1.0;
    ///     }
    ///     fn iteration_matrix<S: MatrixSink + ?Sized>(
    ///         &self, _t: f64, y: &[f64], _yp: &[f64], c: f64, out: &mut S,
    ///     ) {
    ///         for i in 0..4 { out.set(i, i, c); }
    ///         out.set(0, 2, -1.0);
    ///         out.set(1, 3, -1.0);
    ///         out.set(2, 0, y[4]);
    ///         out.set(2, 4, y[0]);
    ///         out.set(3, 1, y[4]);
    ///         out.set(3, 4, y[1]);
    ///         out.set(4, 0, 2.0 * y[0]);
    ///         out.set(4, 1, 2.0 * y[1]);
    ///     }
    /// }
    ///
    /// // Hanging at rest: x = 0 (an entry 2 x of the constraint's gradient is zero here).
    /// let (y, yp) = ([0.0, -1.0, 0.0, 0.0, 1.0], [0.0; 5]);
    /// let s = Stabilised::detect(Pendulum, 0.0, &y, &yp).unwrap();
    /// assert_eq!(s.constraint_rows(), &[4]);
    /// assert_eq!(s.kinematic_pairs(), &[(0, 0), (1, 1)]);
    /// // x, y, u, v of index 1; the multiplier l and the stabilising mu of index 2.
    /// assert_eq!(s.index(), vec![1, 1, 1, 1, 2, 2]);
    /// ```
    ///
    /// # Errors
    /// [`StabilisedError::Dimension`] for a point of the wrong length,
    /// [`StabilisedError::NonFinite`] when the iteration matrix is not finite at the given
    /// point.
    pub fn detect(dae: D, t: f64, y: &[f64], yp: &[f64]) -> Result<Self, StabilisedError> {
        let n = dae.dimension();
        if y.len() != n || yp.len() != n {
            return Err(StabilisedError::Dimension {
                y: y.len(),
                yp: yp.len(),
                dimension: n,
            });
        }
        let found = detect::structure(&dae, t, y, yp)?;
        let algebraic_index = if found.constrained { 2 } else { 1 };
        Self::with_differential(
            dae,
            found.rows,
            found.kinematic,
            found.differential,
            algebraic_index,
        )
    }

    fn with_differential(
        dae: D,
        rows: Vec<usize>,
        kinematic: Vec<(usize, usize)>,
        differential: Vec<bool>,
        algebraic_index: u8,
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
        let positions: Vec<usize> = kinematic.iter().map(|&(j, _)| j).collect();
        let kin_rows: Vec<usize> = kinematic.iter().map(|&(_, i)| i).collect();
        let both: Vec<usize> = rows.iter().chain(&kin_rows).copied().collect();
        let constraint_block = || Selection::new(n, n, &rows, Some(&positions));
        let scratch = RefCell::new(Scratch {
            res: vec![0.0; n],
            res_plus: vec![0.0; n],
            res_minus: vec![0.0; n],
            yp_moved: vec![0.0; n],
            dgdt: vec![0.0; n],
            grad: Selection::new(n, n, &both, Some(&positions)),
            grad_c1: Selection::new(n, n, &both, Some(&positions)),
            coef: vec![0.0; kinematic.len()],
            coef_held: false,
            pair_phi: vec![0.0; kinematic.len()],
            phi: vec![0.0; n],
            kin_c: Selection::new(n, n, &kin_rows, None),
            curv: constraint_block(),
            y_moved: vec![0.0; n],
            grad_plus: constraint_block(),
            grad_minus: constraint_block(),
            by_pair: Vec::new(),
            by_pair_start: Vec::new(),
            by_pair_next: Vec::new(),
        });
        Ok(Self {
            dae,
            rows,
            kinematic,
            differential,
            algebraic_index,
            scratch,
        })
    }

    /// The wrapped DAE.
    pub fn inner(&self) -> &D {
        &self.dae
    }

    /// The position-constraint rows, in the order of their multipliers `mu`.
    pub fn constraint_rows(&self) -> &[usize] {
        &self.rows
    }

    /// The position unknowns with their kinematic rows, `(q_j, row)`.
    pub fn kinematic_pairs(&self) -> &[(usize, usize)] {
        &self.kinematic
    }

    /// The differentiation index of every unknown of the stabilised form as the integrator's
    /// error control needs it ([`crate::radau::Options::index`]): 1 for the wrapped DAE's
    /// differential unknowns (positions and velocities), 2 for its algebraic unknowns and the
    /// multipliers `mu` when the DAE has constraints (stabilised position constraints, or
    /// velocity constraints [`Self::detect`] found), else 1 (an index-1 DAE).
    pub fn index(&self) -> Vec<u8> {
        let z = self.algebraic_index;
        self.differential
            .iter()
            .map(|&d| if d { 1 } else { z })
            .chain(std::iter::repeat_n(z, self.rows.len()))
            .collect()
    }

    /// Number of position constraints (and of multipliers `mu`).
    pub fn n_constraints(&self) -> usize {
        self.rows.len()
    }

    /// Everything an integrator on the stabilised form of `dae` starts from, read at the
    /// consistent point `(t, y, y')` of `dae`: the form ([`Self::detect`]), its initial values
    /// ([`Self::extend`]), its index per unknown ([`Self::index`]) and the linear solver
    /// [`FaerLu::for_dae`](crate::linear_solver::FaerLu::for_dae) picks for it. What
    /// [`Radau::stabilised`](crate::radau::Radau::stabilised) and
    /// [`Bdf::stabilised`](crate::bdf::Bdf::stabilised) do before their `new`.
    ///
    /// # Errors
    /// [`Self::detect`]'s.
    pub(crate) fn start(
        dae: D,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<StabilisedStart<D>, StabilisedError> {
        let form = Self::detect(dae, t, y, yp)?;
        let (y, yp) = form.extend(y, yp);
        let ls = crate::linear_solver::FaerLu::for_dae(&form);
        let index = form.index();
        Ok(StabilisedStart {
            form,
            y,
            yp,
            ls,
            index,
        })
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

    /// `G` into `sc.grad`: the DAE's exact gradients when it supplies them (returns `true`),
    /// else its iteration matrix at `c = 0` (which also leaves `dF_i/dq_j` of the kinematic
    /// rows there).
    fn gradient(&self, t: f64, y: &[f64], yp: &[f64], sc: &mut Scratch) -> bool {
        sc.grad.fill_zero();
        if self.dae.constraint_gradient(t, y, &mut sc.grad) {
            return true;
        }
        sc.grad.fill_zero();
        self.dae.iteration_matrix(t, y, yp, 0.0, &mut sc.grad);
        false
    }

    /// `c_j = dF_i/dq_j'` of the kinematic rows into `sc.coef`: from the DAE's `dF/dy'` when it
    /// supplies one ([`ImplicitDae::mass_matrix`]), else from the iteration matrix at
    /// `c = 1` less the one at `c = 0` already in `sc.grad` (`exact_gradient` false), or, when
    /// `G` was supplied and the iteration matrix not evaluated, from one residual at `y'`
    /// moved along every position (each kinematic row has only its own `q_j'`, linearly;
    /// `sc.res` holds the residual at `(t, y, y')`).
    fn coefficients(&self, t: f64, y: &[f64], yp: &[f64], exact_gradient: bool, sc: &mut Scratch) {
        sc.grad_c1.fill_zero();
        if self.dae.mass_matrix(t, y, yp, &mut sc.grad_c1) {
            for (c, &(j, i)) in sc.coef.iter_mut().zip(&self.kinematic) {
                *c = sc.grad_c1.get(i, j);
            }
            return;
        }
        if exact_gradient {
            sc.yp_moved.copy_from_slice(yp);
            for &(j, _) in &self.kinematic {
                sc.yp_moved[j] += 1.0 + yp[j].abs();
            }
            self.dae.residual(t, y, &sc.yp_moved, &mut sc.res_plus);
            for (c, &(j, i)) in sc.coef.iter_mut().zip(&self.kinematic) {
                *c = (sc.res_plus[i] - sc.res[i]) / (sc.yp_moved[j] - yp[j]);
            }
        } else {
            sc.grad_c1.fill_zero();
            self.dae.iteration_matrix(t, y, yp, 1.0, &mut sc.grad_c1);
            for (c, &(j, i)) in sc.coef.iter_mut().zip(&self.kinematic) {
                *c = sc.grad_c1.get(i, j) - sc.grad.get(i, j);
            }
        }
    }

    /// The velocities `phi_j = q_j' - F_i / c_j` the kinematic rows give (`F_i = c_j (q_j' -
    /// phi_j)`) into `sc.phi`, with `sc.res` and `sc.coef` evaluated: (largest `|q_j|`, largest
    /// `|phi_j|`).
    fn velocities(&self, y: &[f64], yp: &[f64], sc: &mut Scratch) -> (f64, f64) {
        let (mut q_max, mut phi_max) = (0.0f64, 0.0f64);
        for (&(j, i), &c) in self.kinematic.iter().zip(&sc.coef) {
            let phi = yp[j] - sc.res[i] / c;
            sc.phi[j] = phi;
            q_max = q_max.max(y[j].abs());
            phi_max = phi_max.max(phi.abs());
        }
        (q_max, phi_max)
    }

    /// The hidden constraints' dependence through `G` and `dg/dt`: `d/dq_k (G(t, q) phi + dg/dt)`
    /// at fixed `phi` is `sum_j d^2 g/dq_j dq_k phi_j + d^2 g/dt dq_k`, added into the rows
    /// `n + a` of `out`. The DAE's exact curvature when supplied; else the derivative of the
    /// gradient `G_k` along `(1, phi)` (the Hessian is symmetric), one central difference of
    /// `G` (exact gradients, or the iteration matrix at `c = 0`) along the motion. Without the
    /// term simplified Newton converges slowly (for the pendulum it is `2 (x', y')`, as large
    /// as the rest of the row). `sc.res`, `sc.coef` must be evaluated at `(t, y, y')`.
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        exact_gradient: bool,
        sc: &mut Scratch,
        out: &mut S,
    ) {
        let n = self.dae.dimension();
        let (q_max, phi_max) = self.velocities(y, yp, sc);
        sc.curv.fill_zero();
        if self.dae.constraint_curvature(t, y, &sc.phi, &mut sc.curv) {
            // Constraint `a`'s row is the `a`-th selected row, pair `p`'s position its column
            // slot `p` (rows and unknowns are distinct, checked in `new`).
            for a in 0..self.rows.len() {
                for (p, d) in sc.curv.row(a) {
                    if d != 0.0 && d.is_finite() {
                        out.add(n + a, self.kinematic[p].0, d);
                    }
                }
            }
            return;
        }
        // A step of cbrt(eps) relative to the positions and to time.
        let mut eps = f64::EPSILON.cbrt() * t.abs().max(1.0);
        if phi_max > 0.0 {
            eps = eps.min(f64::EPSILON.cbrt() * (1.0 + q_max) / phi_max);
        }
        for (sign, plus) in [(1.0, true), (-1.0, false)] {
            sc.y_moved.copy_from_slice(y);
            for &(j, _) in &self.kinematic {
                sc.y_moved[j] += sign * eps * sc.phi[j];
            }
            let m = if plus {
                &mut sc.grad_plus
            } else {
                &mut sc.grad_minus
            };
            m.fill_zero();
            let t_moved = t + sign * eps;
            if !(exact_gradient && self.dae.constraint_gradient(t_moved, &sc.y_moved, m)) {
                m.fill_zero();
                self.dae.iteration_matrix(t_moved, &sc.y_moved, yp, 0.0, m);
            }
        }
        for a in 0..self.rows.len() {
            let dense = (sc.grad_plus.dense_row(a), sc.grad_minus.dense_row(a));
            if let (Some(plus), Some(minus)) = dense {
                // Small blocks, held densely: every pair in order.
                for ((&(k, _), &gp), &gm) in self.kinematic.iter().zip(plus).zip(minus) {
                    let d = (gp - gm) / (2.0 * eps);
                    if d != 0.0 && d.is_finite() {
                        out.add(n + a, k, d);
                    }
                }
                continue;
            }
            crate::dae::merge_sorted(
                sc.grad_plus.row(a),
                sc.grad_minus.row(a),
                |e| e,
                |p, plus, minus| {
                    let d = (plus - minus) / (2.0 * eps);
                    if d != 0.0 && d.is_finite() {
                        out.add(n + a, self.kinematic[p].0, d);
                    }
                },
            );
        }
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
        let (y, yp, mu) = (&y[..n], &yp[..n], &y[n..]);
        let sc = &mut *self.scratch.borrow_mut();
        // The wrapped DAE's residual straight into its rows (the multipliers' terms are added
        // below).
        self.dae.residual(t, y, yp, &mut out[..n]);
        let exact = self.gradient(t, y, yp, sc);
        // `c_j` as of the last iteration matrix (see the module documentation); only before
        // the first one evaluated here.
        if !sc.coef_held {
            sc.res.copy_from_slice(&out[..n]);
            self.coefficients(t, y, yp, exact, sc);
        }
        out[n..].fill(0.0);
        // Only the constraint rows of `dgdt` are read: only they need zeroing.
        for &g in &self.rows {
            sc.dgdt[g] = 0.0;
        }
        if self.dae.constraint_time_derivative(t, y, &mut sc.dgdt) {
            for (a, &g) in self.rows.iter().enumerate() {
                out[n + a] = sc.dgdt[g];
            }
        } else {
            // A constraint that depends on time (a prescribed motion of the support, for
            // example) has the hidden constraint G phi + dg/dt = 0; dg/dt by a central
            // difference (zero exactly for a constraint without t). Its truncation error,
            // dt^2 |d3g/dt3| / 6, does not depend on where the time origin lies, so neither
            // does the step: it only stays far above the ulp of t, and the difference is
            // divided by the distance of the two times as rounded.
            let dt = f64::EPSILON.cbrt().max(f64::EPSILON.sqrt() * t.abs());
            let (t_plus, t_minus) = (t + dt, t - dt);
            self.dae.residual(t_plus, y, yp, &mut sc.res_plus);
            self.dae.residual(t_minus, y, yp, &mut sc.res_minus);
            for (a, &g) in self.rows.iter().enumerate() {
                let d = sc.res_plus[g] - sc.res_minus[g];
                if d != 0.0 {
                    out[n + a] = d / (t_plus - t_minus);
                }
            }
        }
        // q_j' - F_i / c_j is the velocity phi_j the kinematic row gives (F_i = c_j (q_j' -
        // phi_j)), once per pair; then per constraint its hidden row and its multiplier's terms
        // in the kinematic rows (plain loops: this runs at every residual).
        for ((v, &(j, i)), &cj) in sc.pair_phi.iter_mut().zip(&self.kinematic).zip(&sc.coef) {
            *v = yp[j] - out[i] / cj;
        }
        // `G` in `sc.grad`: constraint `a`'s row is its `a`-th selected row, position `q_j`
        // of pair `p` its column slot `p` (rows and unknowns are distinct, checked in `new`);
        // its entries by pair, as a dense row would be read.
        let (wrapped, hidden_rows) = out.split_at_mut(n);
        for (a, (&m, hidden)) in mu.iter().zip(hidden_rows).enumerate() {
            if let Some(g_row) = sc.grad.dense_row(a) {
                // A small block, held densely: its row read without look-ups.
                let pairs = g_row.iter().zip(&self.kinematic).zip(&sc.pair_phi);
                for (((&gj, &(_, i)), &v), &cj) in pairs.zip(&sc.coef) {
                    if gj != 0.0 {
                        *hidden += gj * v;
                        wrapped[i] += cj * gj * m;
                    }
                }
                continue;
            }
            for (p, gj) in sc.grad.row(a) {
                if gj != 0.0 {
                    *hidden += gj * sc.pair_phi[p];
                    wrapped[self.kinematic[p].1] += sc.coef[p] * gj * m;
                }
            }
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
        let (y, yp) = (&y[..n], &yp[..n]);
        let sc = &mut *self.scratch.borrow_mut();
        self.dae.residual(t, y, yp, &mut sc.res);
        let exact = self.gradient(t, y, yp, sc);
        // The wrapped DAE's rows straight into `out`, keeping the kinematic rows.
        sc.kin_c.fill_zero();
        self.dae
            .iteration_matrix(t, y, yp, c, &mut Tee(&mut *out, &mut sc.kin_c));
        if exact || c == 0.0 {
            self.coefficients(t, y, yp, exact, sc);
        } else {
            // c_j from the matrices at c and at 0.
            for (cj, &(j, i)) in sc.coef.iter_mut().zip(&self.kinematic) {
                *cj = (sc.kin_c.get(i, j) - sc.grad.get(i, j)) / c;
            }
        }
        // The non-zero entries of `G` by pair, constraints ascending: the order in which a
        // dense `G` is read pair by pair, so that `out` receives the same additions in the same
        // order.
        let pairs = self.kinematic.len();
        sc.by_pair_start.clear();
        sc.by_pair_start.resize(pairs + 1, 0);
        for a in 0..self.rows.len() {
            for (p, gj) in sc.grad.row(a) {
                if gj != 0.0 {
                    sc.by_pair_start[p + 1] += 1;
                }
            }
        }
        for p in 0..pairs {
            sc.by_pair_start[p + 1] += sc.by_pair_start[p];
        }
        sc.by_pair_next.clear();
        sc.by_pair_next
            .extend_from_slice(&sc.by_pair_start[..pairs]);
        sc.by_pair.clear();
        sc.by_pair.resize(sc.by_pair_start[pairs], (0, 0.0));
        for a in 0..self.rows.len() {
            for (p, gj) in sc.grad.row(a) {
                if gj != 0.0 {
                    sc.by_pair[sc.by_pair_next[p]] = (a, gj);
                    sc.by_pair_next[p] += 1;
                }
            }
        }
        // `kin_c` selects the kinematic rows, all columns: pair `p`'s row is its `p`-th
        // selected row (rows are distinct, checked in `new`), its column slots the columns.
        for (p, (&(j, i), &cj)) in self.kinematic.iter().zip(&sc.coef).enumerate() {
            for &(a, gj) in &sc.by_pair[sc.by_pair_start[p]..sc.by_pair_start[p + 1]] {
                out.add(i, n + a, cj * gj);
                // d/dy + c d/dy' of G_aj (q_j' - F_i / c_j) at fixed G and c_j.
                out.add(n + a, j, gj * c);
                for (k, v) in sc.kin_c.row(p) {
                    if v != 0.0 {
                        out.add(n + a, k, -gj * v / cj);
                    }
                }
            }
        }
        self.constraint_curvature(t, y, yp, exact, sc, out);
        sc.coef_held = true;
    }

    /// The wrapped DAE's `dF/dy'` ([`ImplicitDae::mass_matrix`]) in its rows and columns, when
    /// it supplies one (`false` otherwise): the stabilisation adds nothing to `dF/dy'`. The
    /// multipliers' terms `c_j G_aj mu_a` have no `y'`, and the hidden constraints read the
    /// velocities `phi_j = q_j' - F_i / c_j`, which do not depend on `y'` since a kinematic row
    /// is `F_i = c_j (q_j' - phi_j)` (its `dF_i/dy'` is `c_j` at `q_j'` alone): in
    /// [`iteration_matrix`](ImplicitDae::iteration_matrix) the hidden rows' `c`-terms, `c G_aj`
    /// at `q_j` and `-c G_aj dF_i/dy'_k / c_j` along the kinematic row, cancel. Costs the
    /// wrapped DAE's mass matrix only (no residual, no constraint derivatives).
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        out: &mut S,
    ) -> bool {
        let n = self.dae.dimension();
        self.dae.mass_matrix(t, &y[..n], &yp[..n], out)
    }

    /// The structural pattern of the stabilised iteration matrix when the wrapped DAE declares
    /// one (`None`, dense, when it does not), sorted by row and column, without repeats, so
    /// that [`FaerLu::for_dae`](crate::linear_solver::FaerLu::for_dae) (and any other reader of
    /// the pattern, such as the column groups of [`crate::difference`]) keeps a large sparse
    /// model sparse once it is stabilised.
    ///
    /// The wrapped pattern `P` with, per position constraint `a` (row `g`) and per position
    /// `q_j` with a kinematic row `i` and `(g, j)` in `P` (`G_aj` structurally non-zero):
    /// `(i, n + a)` (the multiplier's term `c_j G_aj mu_a`), `(n + a, j)` (the hidden
    /// constraint's `c G_aj` at `q_j`, and its curvature, whose columns are `G`'s: a second
    /// derivative of `g` is zero wherever its first is identically) and `(n + a, k)` for
    /// every `(i, k)` in `P` (the hidden constraint reads `phi_j = q_j' - F_i / c_j`). Nothing
    /// else is written: the multipliers `mu` have no entry in the hidden rows. It is the
    /// pattern of the iteration matrix, which leaves out `(dG/dq)^T mu` (see the
    /// [module documentation](self)): the residual's derivative has that term's entries too
    /// (kinematic row `i` at the other positions of the constraints on `q_j`) wherever
    /// `mu != 0`, outside this pattern.
    ///
    /// This holds when the wrapped DAE's own derivatives stay within `P`: its iteration
    /// matrix (which gives `G` at `c = 0`, the kinematic rows and, by differences, the
    /// curvature), and [`ImplicitDae::constraint_gradient`] and
    /// [`ImplicitDae::constraint_curvature`] when it supplies them (they are parts of the
    /// iteration matrix's constraint rows at `c = 0` and their derivatives, so a correct
    /// pattern covers them). Entries of `P` beyond the wrapped DAE's dimension are passed on
    /// as given and add nothing. Set-up work: it allocates, in proportion to the entries.
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let mut pattern = self.dae.iteration_pattern()?;
        pattern.sort_unstable();
        pattern.dedup();
        if self.rows.is_empty() {
            return Some(pattern);
        }
        let n = self.dae.dimension();
        // Row `r`'s entries of the sorted wrapped pattern (empty beyond its rows).
        let row = |p: &[(usize, usize)], r: usize| -> (usize, usize) {
            let first = p.partition_point(|e| e.0 < r);
            (first, first + p[first..].partition_point(|e| e.0 == r))
        };
        // Per unknown, its kinematic row when it is a position.
        let mut kinematic_row = vec![None; n];
        for &(j, i) in &self.kinematic {
            kinematic_row[j] = Some(i);
        }
        let mut added = Vec::new();
        for (a, &g) in self.rows.iter().enumerate() {
            let (first, last) = row(&pattern, g);
            for &(_, j) in &pattern[first..last] {
                let Some(i) = kinematic_row.get(j).copied().flatten() else {
                    continue;
                };
                added.push((i, n + a));
                added.push((n + a, j));
                let (k_first, k_last) = row(&pattern, i);
                added.extend(
                    pattern[k_first..k_last]
                        .iter()
                        .filter(|&&(_, k)| k < n)
                        .map(|&(_, k)| (n + a, k)),
                );
            }
        }
        pattern.extend(added);
        pattern.sort_unstable();
        pattern.dedup();
        Some(pattern)
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

/// The share of what the tolerances allow a constraint's residual at which the diagnosis of a
/// failure before the first step names it ([`start_near_tolerance`]; the start check,
/// [`start_violation`], refuses at the whole). The Test Set's slider crank (initial values
/// consistent to the nine digits given) meets a velocity constraint to `1.19e-8`, 0.99 of what
/// `rtol = atol = 1e-10` allow: both integrators fail at `t = 0` there and run at `1e-9`.
pub(crate) const NEAR_TOLERANCE_SHARE: f64 = 0.1;

/// A constraint the initial values miss by more than the tolerances allow: [`start_violation`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ConstraintViolation {
    /// The constraint's name (the DAE's [`ImplicitDae::equation_name`], or "the hidden
    /// velocity constraint of ..." for the derivative of a position constraint).
    pub equation: String,
    /// Its residual at the start.
    pub residual: f64,
    /// What moving every unknown by its tolerance can change it by (see [`start_violation`]).
    pub bound: f64,
}

/// The constraint the start `(t, y, y')` of `dae` misses worst, when it misses one by more than
/// the tolerances allow; `None` when every constraint holds within them, or when the DAE's
/// structure cannot be read at the start (a non-finite iteration matrix: the integrators report
/// that themselves).
///
/// The constraints are the rows [`Stabilised::detect`] classifies (equations without
/// derivatives and without algebraic unknowns, which restrict the differential unknowns
/// themselves), and, of every position constraint `0 = g(t, q)`, its hidden velocity
/// constraint `G(t, q) phi(t, y) + dg/dt = 0` (the residual of [`Stabilised`]'s row; `phi` the
/// velocities the kinematic rows give). An integrator started off such a constraint jumps onto
/// it within its first step, with no error: the solution it returns is not the one of the
/// values given. A constraint row `h` with residual `r` is missed when `|r|` exceeds both
/// `sum_j |dh/dy_j| tol_j`, with `tol_j = tolerance(j)` (the integrator's `rtol_j |y_j| +
/// atol_j`: by Hölder's inequality, no change of the unknowns within their tolerances can
/// remove a larger residual), and [`crate::index_estimate::INCONSISTENT_FACTOR`] times its
/// round-off bound `10 eps sum_j |dh/dy_j| max_k |y_k|`. The worst is the largest ratio of
/// residual to bound. Costs the structure's sampled matrices (six iteration matrices)
/// and the stabilised form's residual and iteration matrix, each read as the entries written
/// (memory and time grow with the non-zeros, not with `n^2`, so DAEs of any size are
/// checked): for set-up, not for a step.
pub(crate) fn start_violation<D: ImplicitDae>(
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
    tolerance: impl Fn(usize) -> f64,
) -> Option<ConstraintViolation> {
    worst_constraint(dae, (t, y, yp), tolerance, |tolerated, roundoff| {
        let bound = tolerated.max(roundoff);
        (bound, bound)
    })
}

/// The constraint of [`start_violation`] whose residual at the start is the largest share of
/// what the tolerances allow it (`sum_j |dh/dy_j| tol_j`), when that share is at least
/// [`NEAR_TOLERANCE_SHARE`]; the violation's `bound` is the whole. A start that meets a
/// constraint only so closely passes the start check, but its first step must also put the
/// unknowns on the constraint, which takes that share of their tolerances at every step size:
/// the likely cause of a failure before the first step. Round-off does not excuse it here (a
/// residual at the round-off of large terms that fills the tolerances asks for looser ones).
/// For the integrators' error paths; the costs of [`start_violation`].
/// Read at an integration's recorded `start` with its tolerances (`rtol_j |y_j| + atol_j` at
/// the start's values).
pub(crate) fn start_near_tolerance<D: ImplicitDae>(
    dae: &D,
    start: &crate::index_estimate::StartPoint,
    rtol: &crate::bdf::Tolerance,
    atol: &crate::bdf::Tolerance,
) -> Option<ConstraintViolation> {
    let (t, y, yp) = start.point();
    let tolerance = |j: usize| rtol.get(j) * y[j].abs() + atol.get(j);
    worst_constraint(dae, (t, y, yp), tolerance, |tolerated, _| {
        (NEAR_TOLERANCE_SHARE * tolerated, tolerated)
    })
}

/// The constraint (rows and hidden velocity constraints, as [`start_violation`] reads them)
/// with the largest ratio of residual to bound among those whose residual exceeds its limit,
/// where `limit(tolerated, roundoff)` gives `(limit, bound)` from what the tolerances allow
/// (`sum_j |dh/dy_j| tol_j`) and 1 000 times the round-off bound.
fn worst_constraint<D: ImplicitDae>(
    dae: &D,
    (t, y, yp): (f64, &[f64], &[f64]),
    tolerance: impl Fn(usize) -> f64,
    limit: impl Fn(f64, f64) -> (f64, f64),
) -> Option<ConstraintViolation> {
    let n = dae.dimension();
    let found = detect::structure(dae, t, y, yp).ok()?;
    if !found.constrained {
        return None;
    }
    let y_max = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst: Option<(f64, ConstraintViolation)> = None;
    // The rows `rows` of a DAE of dimension `m` at `(ys, yps)`: residual and `dF/dy` there,
    // the latter as the entries written (a dense row per constraint would cost `rows x m`).
    let mut check = |dae: &dyn Fn(&mut [f64], &mut Triplets),
                     m: usize,
                     rows: &[usize],
                     name: &dyn Fn(usize) -> String| {
        let mut res = vec![0.0; m];
        let mut grad = Triplets::new(m, m);
        dae(&mut res, &mut grad);
        let entries = grad.entries();
        for &i in rows {
            // The row's entries, by column (the order a dense row is summed in).
            let first = entries.partition_point(|e| e.0 < i);
            let row = entries[first..].iter().take_while(|e| e.0 == i);
            let (mut tolerated, mut size) = (0.0, 0.0);
            for &(_, j, g) in row.filter(|e| e.1 < n) {
                tolerated += g.abs() * tolerance(j);
                size += g.abs();
            }
            let roundoff =
                crate::index_estimate::INCONSISTENT_FACTOR * 10.0 * f64::EPSILON * size * y_max;
            let (limit, bound) = limit(tolerated, roundoff);
            let r = res[i];
            if !r.is_finite() || r.abs() <= limit || bound <= 0.0 {
                continue;
            }
            let ratio = r.abs() / bound;
            if worst.as_ref().is_none_or(|(w, _)| ratio > *w) {
                worst = Some((
                    ratio,
                    ConstraintViolation {
                        equation: name(i),
                        residual: r,
                        bound,
                    },
                ));
            }
        }
    };
    let rows: Vec<usize> = found
        .rows
        .iter()
        .chain(&found.velocity_rows)
        .copied()
        .collect();
    check(
        &|res, grad| {
            dae.residual(t, y, yp, res);
            dae.iteration_matrix(t, y, yp, 0.0, grad);
        },
        n,
        &rows,
        &|i| dae.equation_name(i),
    );
    if !found.rows.is_empty() {
        let s =
            Stabilised::with_differential(dae, found.rows, found.kinematic, found.differential, 2)
                .ok()?;
        let (ys, yps) = s.extend(y, yp);
        let m = s.dimension();
        let hidden: Vec<usize> = (n..m).collect();
        check(
            &|res, grad| {
                s.residual(t, &ys, &yps, res);
                s.iteration_matrix(t, &ys, &yps, 0.0, grad);
            },
            m,
            &hidden,
            &|i| s.equation_name(i),
        );
    }
    worst.map(|(_, v)| v)
}

/// The structure [`Stabilised::detect`] reads from sampled iteration matrices, classified by
/// the one classification of constraint structures ([`ConstraintStructure`]).
mod detect {
    use std::borrow::Cow;

    use super::StabilisedError;
    use crate::consistent::ConstraintStructure;
    use crate::dae::Entries;
    use crate::model::{Names, Structure, Units};
    use crate::ImplicitDae;

    /// Positions `(row, column)` of a matrix, sorted.
    type Positions = Vec<(usize, usize)>;

    /// `c` of the second iteration matrix: `M(c) - M(0) = c dF/dy'` stays non-zero where
    /// `dF/dy'` is, even beside a large `dF/dy` (a power of two, so `c dF/dy'` is exact).
    const C: f64 = 1_048_576.0;

    /// The rows, pairs and differential unknowns [`Stabilised::detect`](super::Stabilised::detect) found.
    pub(super) struct Found {
        pub(super) rows: Vec<usize>,
        pub(super) kinematic: Vec<(usize, usize)>,
        pub(super) differential: Vec<bool>,
        /// The constraints on unknowns without kinematic rows (velocity type, index 2).
        pub(super) velocity_rows: Vec<usize>,
        /// Whether the DAE has constraints of either type.
        pub(super) constrained: bool,
    }

    /// The iteration matrices at `c = 0` and `c = C` at one point as their sorted entries
    /// (`crate::dae::sparse_iteration_matrix`), or the first non-finite entry `(row, column)`.
    fn matrices<D: ImplicitDae>(
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<(Entries, Entries), (usize, usize)> {
        Ok((
            crate::dae::sparse_iteration_matrix(dae, t, y, yp, 0.0)?,
            crate::dae::sparse_iteration_matrix(dae, t, y, yp, C)?,
        ))
    }

    /// Entries of `dF/dy` and `dF/dy'` that are non-zero at `(t, y, y')` or at one of two
    /// points near it (moved by up to 10 % of `1 + |value|` in every coordinate and in time;
    /// a point where the matrix is not finite is moved less, four times, then skipped), as
    /// positions `(row, column)` sorted by row and column: memory and time grow with the
    /// entries the DAE writes, not with `n^2`.
    fn sampled_pattern<D: ImplicitDae>(
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<(Positions, Positions), StabilisedError> {
        let (mut f_y, mut f_yp) = (Vec::new(), Vec::new());
        let mut mark = |m0: &[(usize, usize, f64)], m1: &[(usize, usize, f64)]| {
            crate::dae::merge_sorted(
                m0,
                m1,
                |e| ((e.0, e.1), e.2),
                |(i, j), a, b| {
                    if a != 0.0 {
                        f_y.push((i, j));
                    }
                    if b != a {
                        f_yp.push((i, j));
                    }
                },
            );
        };
        let (m0, m1) = matrices(dae, t, y, yp).map_err(|(i, j)| StabilisedError::NonFinite {
            equation: dae.equation_name(i),
            unknown: dae.unknown_name(j),
        })?;
        mark(&m0, &m1);
        crate::numeric::visit_nearby_points(t, y, yp, |t_moved, y_moved, yp_moved| {
            matrices(dae, t_moved, y_moved, yp_moved)
                .map(|(m0, m1)| mark(&m0, &m1))
                .is_ok()
        });
        for m in [&mut f_y, &mut f_yp] {
            m.sort_unstable();
            m.dedup();
        }
        Ok((f_y, f_yp))
    }

    /// Classify `dae`'s rows from its sampled pattern (see [`Stabilised::detect`](super::Stabilised::detect)).
    pub(super) fn structure<D: ImplicitDae>(
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Found, StabilisedError> {
        let n = dae.dimension();
        let (f_y, f_yp) = sampled_pattern(dae, t, y, yp)?;
        let mut differential = vec![false; n];
        for &(_, j) in &f_yp {
            differential[j] = true;
        }
        // The unknowns as a model's states (the differential ones) and algebraic unknowns, in
        // the DAE's order within each group; per unknown its position in its group.
        let (states, algebraic): (Vec<usize>, Vec<usize>) = (0..n).partition(|&j| differential[j]);
        let mut slot = vec![0; n];
        for group in [&states, &algebraic] {
            for (k, &j) in group.iter().enumerate() {
                slot[j] = k;
            }
        }
        // The entries `(row, position in the group)` of the columns of one group, by row and
        // position (the positions ascend with the columns within a group).
        let pattern = |m: &[(usize, usize)], in_group: bool| -> Cow<'static, [(usize, usize)]> {
            Cow::Owned(
                m.iter()
                    .filter(|&&(_, j)| differential[j] == in_group)
                    .map(|&(i, j)| (i, slot[j]))
                    .collect(),
            )
        };
        let names = |v: &[usize]| Names::Owned(v.iter().map(|&j| dae.unknown_name(j)).collect());
        let structure = Structure {
            name: Cow::Borrowed("the DAE"),
            states: names(&states),
            algebraic: names(&algebraic),
            inputs: Names::Static(&[]),
            outputs: Names::Static(&[]),
            params: Names::Static(&[]),
            equations: Names::Owned((0..n).map(|i| dae.equation_name(i)).collect()),
            units: Units::Static(&[]),
            pattern_f_xdot: pattern(&f_yp, true),
            pattern_f_x: pattern(&f_y, true),
            pattern_f_z: pattern(&f_y, false),
            pattern_f_u: Cow::Borrowed(&[]),
            pattern_h_x: Cow::Borrowed(&[]),
        };
        let classified = ConstraintStructure::from_structure(&structure);
        let kinematic = classified
            .position_states
            .iter()
            .filter_map(|&s| classified.kinematic[s].map(|row| (states[s], row)))
            .collect();
        Ok(Found {
            constrained: classified.is_constrained(),
            rows: classified.position_constraints,
            velocity_rows: classified.velocity_constraints,
            kinematic,
            differential,
        })
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

    /// [`Moving`] with a kinematic coefficient that varies with the position:
    /// `(2 + y0^2) (y0' - y1) = 0`.
    struct MovingVarying;
    impl ImplicitDae for MovingVarying {
        fn dimension(&self) -> usize {
            3
        }
        fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            Moving.residual(t, y, yp, out);
            out[0] = (2.0 + y[0] * y[0]) * (yp[0] - y[1]);
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            y: &[f64],
            yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            Moving.iteration_matrix(t, y, yp, c, out);
            let k = 2.0 + y[0] * y[0];
            out.set(0, 0, 2.0 * y[0] * (yp[0] - y[1]) + k * c);
            out.set(0, 1, -k);
        }
    }

    /// `y0' = y0 + y1`, `0 = y0 - 1`: a constraint on a differential unknown without a
    /// kinematic row (the row of `y0'` has the algebraic `y1`), of index 2.
    struct VelocityType;
    impl ImplicitDae for VelocityType {
        fn dimension(&self) -> usize {
            2
        }
        fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = yp[0] - y[0] - y[1];
            out[1] = y[0] - 1.0;
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _t: f64,
            _y: &[f64],
            _yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            out.set(0, 0, c - 1.0);
            out.set(0, 1, -1.0);
            out.set(1, 0, 1.0);
        }
    }

    /// `rtol |y_j| + atol` with `rtol = atol = 1e-6` at `y`.
    fn tolerance(y: &[f64]) -> impl Fn(usize) -> f64 + '_ {
        |j| 1e-6 * y[j].abs() + 1e-6
    }

    #[test]
    fn start_violation_reads_the_constraint_its_derivative_and_the_tolerance() {
        // `Moving` at t = 0.3 on its solution: y0 = sin t, y1 = y0' = cos t, and y2 from
        // y1' = -y2 y0 with y1' = -sin t, so y2 = 1.
        let t = 0.3f64;
        let y = [t.sin(), t.cos(), 1.0];
        let yp = [t.cos(), -t.sin(), 0.0];
        assert_eq!(start_violation(&Moving, t, &y, &yp, tolerance(&y)), None);
        // The position off its (time-dependent) constraint by 1e-3.
        let mut off = y;
        off[0] += 1e-3;
        let v = start_violation(&Moving, t, &off, &yp, tolerance(&off)).unwrap();
        assert_eq!(v.equation, "equation 2");
        assert!((v.residual - 1e-3).abs() < 1e-12, "{}", v.residual);
        assert!((v.bound - tolerance(&off)(0)).abs() < 1e-15, "{}", v.bound);
        // The velocity (and y0' with it) off the hidden constraint `y1 - cos t = 0` by 1e-3:
        // the derivative of the moving constraint, `dg/dt = -cos t`, is taken into account.
        let (mut off, mut off_p) = (y, yp);
        off[1] += 1e-3;
        off_p[0] += 1e-3;
        let v = start_violation(&Moving, t, &off, &off_p, tolerance(&off)).unwrap();
        assert_eq!(v.equation, "the hidden velocity constraint of equation 2");
        assert!((v.residual - 1e-3).abs() < 1e-9, "{}", v.residual);
        // By a tenth of the tolerance it passes; by ten times it is named.
        for (by, missed) in [(1e-7, false), (1e-5, true)] {
            let (mut off, mut off_p) = (y, yp);
            off[1] += by;
            off_p[0] += by;
            let v = start_violation(&Moving, t, &off, &off_p, tolerance(&off));
            assert_eq!(v.is_some(), missed, "{by}: {v:?}");
        }
        // Near the tolerance: a half of it is named, a fortieth is not; the bound is all the
        // tolerances allow.
        for (by, named) in [(5e-8, false), (1e-6, true)] {
            let (mut off, mut off_p) = (y, yp);
            off[1] += by;
            off_p[0] += by;
            let start = crate::index_estimate::StartPoint::new(t, &off, &off_p);
            let tol = crate::bdf::Tolerance::Scalar(1e-6);
            let v = start_near_tolerance(&Moving, &start, &tol, &tol);
            assert_eq!(v.is_some(), named, "{by}: {v:?}");
            if let Some(v) = v {
                let share = v.residual.abs() / v.bound;
                assert!((share - by / tolerance(&off)(1)).abs() < 1e-4, "{v:?}");
            }
        }
        // A constraint of velocity type is checked itself, without a derivative.
        let (y, yp) = ([1.0 + 1e-3, 0.0], [1.0 + 1e-3, 0.0]);
        let v = start_violation(&VelocityType, 0.0, &y, &yp, tolerance(&y)).unwrap();
        assert_eq!(v.equation, "equation 1");
        let (y, yp) = ([1.0, 0.0], [5.0, 0.0]);
        assert_eq!(
            start_violation(&VelocityType, 0.0, &y, &yp, tolerance(&y)),
            None
        );
        // No structure to read (a non-finite iteration matrix): no verdict.
        assert_eq!(
            start_violation(&NotFinite, 0.0, &[1.0, 1.0], &[1.0, 0.0], |_| 1e-6),
            None
        );
    }

    /// A DAE whose iteration matrix has `d(equation 1)/d(y[0]) = NaN` everywhere.
    struct NotFinite;
    impl ImplicitDae for NotFinite {
        fn dimension(&self) -> usize {
            2
        }
        fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            out[0] = yp[0] - y[1];
            out[1] = y[0].sqrt() - y[1];
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _t: f64,
            _y: &[f64],
            _yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            out.set(0, 0, c);
            out.set(0, 1, -1.0);
            out.set(1, 0, f64::NAN);
            out.set(1, 1, -1.0);
        }
    }

    #[test]
    fn detect_reports_a_matrix_it_cannot_read() {
        let e = Stabilised::detect(NotFinite, 0.0, &[0.0, 0.0], &[0.0, 0.0]).err();
        assert_eq!(
            e,
            Some(StabilisedError::NonFinite {
                equation: "equation 1".into(),
                unknown: "y[0]".into(),
            })
        );
        assert_eq!(
            e.map(|e| e.to_string()).unwrap_or_default(),
            "the iteration matrix is not finite at the given point: d(equation 1)/d(y[0]) is NaN or infinite"
        );
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
    fn held_kinematic_coefficients_keep_exact_solutions_exact() {
        // The residual holds `c_j` from the last iteration matrix, here evaluated far from
        // the points below (c = 2 + 3^2 = 11 against 2 + sin^2 t): on the exact solution
        // every residual still vanishes (F = 0, mu = 0, so phi_j = q_j' for any c_j).
        let s = Stabilised::new(MovingVarying, vec![2], vec![(0, 0)]).unwrap();
        let mut m = nalgebra::DMatrix::zeros(4, 4);
        s.iteration_matrix(0.0, &[3.0, 0.0, 1.0, 0.0], &[0.0; 4], 5.0, &mut m);
        for t in [0.3f64, 0.7, 2.0] {
            let y = [t.sin(), t.cos(), 1.0, 0.0];
            let yp = [t.cos(), -t.sin(), 0.0, 0.0];
            let mut r = [1.0; 4];
            s.residual(t, &y, &yp, &mut r);
            assert!(r.iter().all(|v| v.abs() < 1e-9), "t {t}: {r:?}");
        }
    }

    /// [`Moving`] with its constraint's derivatives supplied: `G = (1, 0, 0)`, `dg/dt =
    /// -cos t`, no curvature (`G` is constant and `dg/dt` does not depend on `y`).
    struct MovingExact;
    impl ImplicitDae for MovingExact {
        fn dimension(&self) -> usize {
            3
        }
        fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            Moving.residual(t, y, yp, out);
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            t: f64,
            y: &[f64],
            yp: &[f64],
            c: f64,
            out: &mut S,
        ) {
            Moving.iteration_matrix(t, y, yp, c, out);
        }
        fn constraint_gradient<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            _: &[f64],
            out: &mut S,
        ) -> bool {
            out.set(2, 0, 1.0);
            true
        }
        fn constraint_time_derivative(&self, t: f64, _: &[f64], out: &mut [f64]) -> bool {
            out[2] = -t.cos();
            true
        }
        fn constraint_curvature<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            _: &[f64],
            _: &[f64],
            _: &mut S,
        ) -> bool {
            true
        }
    }

    #[test]
    fn moving_constraint_and_scaled_kinematic_row() {
        moving_constraint_and_scaled_kinematic_row_of(Moving, 1e-9);
        // Exact derivatives: dg/dt without a difference's truncation error.
        moving_constraint_and_scaled_kinematic_row_of(MovingExact, 1e-15);
    }

    fn moving_constraint_and_scaled_kinematic_row_of<D: ImplicitDae>(dae: D, tol: f64) {
        // On the exact solution y0 = sin t, y1 = cos t, y2 = 1 (mu = 0) every residual of the
        // stabilised form vanishes: the hidden constraint is y1 - cos t = 0 (G phi + dg/dt
        // with the kinematic row's coefficient 2 divided out).
        let s = Stabilised::new(dae, vec![2], vec![(0, 0)]).unwrap();
        let t: f64 = 0.7;
        let y = [t.sin(), t.cos(), 1.0, 0.0];
        let yp = [t.cos(), -t.sin(), 0.0, 0.0];
        let mut r = [1.0; 4];
        s.residual(t, &y, &yp, &mut r);
        assert!(r.iter().all(|v| v.abs() < tol), "{r:?}");
        // Off the solution, the hidden constraint measures the velocity error.
        let y_off = [t.sin(), t.cos() + 1e-3, 1.0, 0.0];
        s.residual(t, &y_off, &yp, &mut r);
        assert!((r[3] - 1e-3).abs() < 1e-9, "{r:?}");
        // The iteration matrix against central differences of the residual, at mu = 0 (where
        // the left-out term (dG/dq)^T mu vanishes): d/dy + c d/dy'.
        for c in [3.0, 0.0] {
            let mut m = nalgebra::DMatrix::zeros(4, 4);
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
                        "c {c}: ({i}, {k}): {} vs {fd}",
                        m[(i, k)]
                    );
                }
            }
        }
    }
}
