//! Consistent initial values of constrained (index-2 and index-3) plants from user-given
//! states: projection onto the constraint manifold and its hidden velocity constraint, then
//! the derivatives and the multipliers.
//!
//! The plant's equations are classified from its structural patterns:
//! * *kinematic rows*: exactly one `x'` entry and no algebraic unknown, `c x'_j = f_j(t, x, u)`
//!   as written by `der(q) = v` (the state `x_j` has the velocity `phi_j(x) = x'_j - F_i / c`);
//! * *constraint rows*: no `x'` and no algebraic unknown, `g(x) = 0`. A constraint all of whose
//!   states have kinematic rows is of *position* type (index 3 with its multipliers): it has
//!   the hidden velocity constraint `g_x(x) phi(x) = 0`. Otherwise it is of *velocity* type
//!   (index 2), with no further hidden constraint on `x`.
//!
//! The algorithm (the projection steps of Brenan, Campbell & Petzold, *Numerical Solution of
//! Initial-Value Problems in DAEs*, SIAM 1996, Section 5.3, and of the consistent
//! initialisation of mechanical systems in Hairer & Wanner, *Solving ODEs II*, Section VII.1):
//! 1. *positions*: Gauss-Newton on `g(x) = 0` from the given `x`, each correction the
//!    minimum-norm solution of `G dx = -g` by a QR factorisation of `G^T` (so only the states
//!    the constraints involve move, and as little as possible);
//! 2. *velocities*: with the states of the position constraints frozen, Gauss-Newton on
//!    `g_x(x) phi(x) = 0` over the other states, again minimum-norm (for `q' = v` this is the
//!    orthogonal projection of the given velocities onto `G v = 0`); the Jacobian is exact
//!    because `g_x` depends only on frozen states;
//! 3. *derivatives and multipliers*: at the fixed `x`, Gauss-Newton (column-pivoted QR,
//!    least squares) for `(x', z)` on `F = 0` stacked with the acceleration-level constraints
//!    `G phi_x x' + kappa = 0` of position constraints and `G x' = 0` of velocity
//!    constraints. The curvature `kappa = (d/ds) g_x(x + s p) p` at `s = 0`, `p = phi(x)`, is
//!    `sum_k C_k(p) p_k` with the model's exact curvature `C(v)` of the position constraints
//!    ([`DaeModel::constraint_curvature`], which `dpc::model!` and plant files supply; its
//!    part `d^2 g/(dt dx)` is taken out, `C(p) - C(0)`, so the term is the same whether the
//!    model supplies it or not). A model that does not supply it gets a central difference of
//!    the *analytic* Jacobian along `p` (exact for quadratic constraints such as rods of fixed
//!    length, up to rounding), with the error estimated from the same difference at twice the
//!    step, Richardson-extrapolated; the estimate is reported ([`ConsistentState::curvature_error`],
//!    zero when exact). It is zero, with nothing evaluated, at rest.
//!
//! The constraints must not depend explicitly on time or on the input (the model provides no
//! `dF/dt`, and a constraint driven by the input is a prescribed motion): such a plant is
//! refused with [`ConsistentError::Unsupported`].

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

use crate::model::{DaeModel, Structure};

/// Options of [`consistent_state`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConsistentOptions {
    /// A constraint is met when `|g_i| <= tol * (1 + s_i)`, `s_i` the size of its terms
    /// (`sum_j |dg_i/dx_j| |x_j|`). Default `1e-12`.
    pub tol: f64,
    /// Gauss-Newton iterations per stage. Default 50.
    pub max_iterations: usize,
}

impl Default for ConsistentOptions {
    fn default() -> Self {
        Self {
            tol: 1e-12,
            max_iterations: 50,
        }
    }
}

/// Why no consistent state was found.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ConsistentError {
    /// A vector has the wrong length.
    #[error("{what} has length {found}, expected {expected}")]
    Dimension {
        /// Which vector.
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// The model produced a non-finite value.
    #[error("non-finite {what} during the consistent initialisation")]
    NonFinite {
        /// Residual or Jacobian.
        what: &'static str,
    },
    /// The constraints cannot be met from the given state (contradictory, or out of reach).
    #[error("the constraints cannot be met ({stage}): {equation} keeps the residual {residual:e} (tolerance {tolerance:e}) after {iterations} Gauss-Newton steps")]
    CannotMeet {
        /// Positions, velocities, or derivatives and multipliers.
        stage: &'static str,
        /// The equation with the largest residual, as the model names it.
        equation: String,
        /// Its residual.
        residual: f64,
        /// The tolerance.
        tolerance: f64,
        /// Steps taken.
        iterations: usize,
    },
    /// The derivatives and multipliers are not determined at the projected state (dependent
    /// constraints, or a constraint that does not involve the multiplier's direction).
    #[error("the derivatives and multipliers are not determined: rank {rank} of {unknowns} (tolerance {tolerance:e})")]
    Undetermined {
        /// Numerical rank of the stacked Jacobian.
        rank: usize,
        /// Number of unknowns `n_x + n_z`.
        unknowns: usize,
        /// Rank tolerance.
        tolerance: f64,
    },
    /// The plant's structure is outside what this projection handles.
    #[error("{equation}: {reason}")]
    Unsupported {
        /// The equation, as the model names it.
        equation: String,
        /// Why.
        reason: &'static str,
    },
}

/// A consistent state and how it was reached.
#[derive(Debug, Clone, PartialEq)]
pub struct ConsistentState {
    /// The states, on the constraint manifold and its hidden velocity constraint.
    pub x: Vec<f64>,
    /// Their derivatives.
    pub xdot: Vec<f64>,
    /// The algebraic unknowns (multipliers).
    pub z: Vec<f64>,
    /// `x - x_given`, per state.
    pub moved: Vec<f64>,
    /// `max_i |moved_i|`.
    pub max_move: f64,
    /// The constraint rows of position type (index 3).
    pub position_constraints: Vec<usize>,
    /// The constraint rows of velocity type (index 2).
    pub velocity_constraints: Vec<usize>,
    /// Gauss-Newton steps of the three stages.
    pub iterations: [usize; 3],
    /// The curvature term `kappa` of the acceleration-level constraint of each position
    /// constraint (in the order of [`Self::position_constraints`]; see the module doc).
    pub curvature: Vec<f64>,
    /// Whether [`Self::curvature`] was taken from the model's exact curvature
    /// ([`DaeModel::constraint_curvature`]); `false` when it was differenced, and at rest,
    /// where it is zero with nothing evaluated.
    pub curvature_exact: bool,
    /// Estimated absolute error of the differenced curvature term `kappa` (largest entry):
    /// the Richardson estimate of the central difference's error at its step (an upper
    /// estimate for the extrapolated value used). Zero at rest and when the model supplies
    /// the curvature exactly ([`Self::curvature_exact`]; then only rounding remains).
    pub curvature_error: f64,
    /// Largest residual of `F` at the result, relative to the size of its terms.
    pub residual: f64,
}

struct Jac {
    r: Vec<f64>,
    f_xdot: DMatrix<f64>,
    f_x: DMatrix<f64>,
    f_z: DMatrix<f64>,
    f_u: DMatrix<f64>,
}

fn evaluate<M: DaeModel>(
    model: &M,
    t: f64,
    x: &[f64],
    xdot: &[f64],
    z: &[f64],
    u: &[f64],
) -> Result<Jac, ConsistentError> {
    let s = model.structure();
    let (ne, nx, nz, nu) = (s.n_equations(), s.n_states(), s.n_algebraic(), s.n_inputs());
    let mut j = Jac {
        r: vec![0.0; ne],
        f_xdot: DMatrix::zeros(ne, nx),
        f_x: DMatrix::zeros(ne, nx),
        f_z: DMatrix::zeros(ne, nz),
        f_u: DMatrix::zeros(ne, nu),
    };
    model.evaluate(
        t,
        x,
        xdot,
        z,
        u,
        &mut j.r,
        &mut j.f_xdot,
        &mut j.f_x,
        &mut j.f_z,
        &mut j.f_u,
    );
    if j.r.iter().any(|v| !v.is_finite()) {
        return Err(ConsistentError::NonFinite { what: "residual" });
    }
    for (what, m) in [("dF/dx'", &j.f_xdot), ("dF/dx", &j.f_x), ("dF/dz", &j.f_z)] {
        if m.iter().any(|v| !v.is_finite()) {
            return Err(ConsistentError::NonFinite { what });
        }
    }
    Ok(j)
}

/// The constraint structure of a plant, read from its structural patterns (see the module
/// documentation): which rows are kinematic, which are constraints of position type (index 3
/// with their multipliers) or of velocity type (index 2), and the differentiation index of each
/// unknown that follows from it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConstraintStructure {
    /// Per state, its kinematic row `c x'_j = f_j(t, x, u)`, if it has one.
    pub kinematic: Vec<Option<usize>>,
    /// Constraint rows all of whose states have kinematic rows (position type).
    pub position_constraints: Vec<usize>,
    /// The other constraint rows (velocity type).
    pub velocity_constraints: Vec<usize>,
    /// The states the position constraints involve, ascending.
    pub position_states: Vec<usize>,
    /// The states the kinematic rows of the position states involve, other than the position
    /// states themselves (the velocities of the constrained positions), ascending.
    pub velocity_states: Vec<usize>,
    /// Rows without `x'` and algebraic unknowns that depend on the input: prescribed motions
    /// (or, in a tracking DAE, the output rows), not counted as constraints.
    pub prescribed: Vec<usize>,
    /// Number of states.
    pub n_states: usize,
    /// Number of algebraic unknowns.
    pub n_algebraic: usize,
}

impl ConstraintStructure {
    /// Classify the rows of `model`.
    pub fn of<M: DaeModel>(model: &M) -> Self {
        Self::from_structure(model.structure())
    }

    /// Classify the rows of a model with the structure `s` (what [`Self::of`] reads of it).
    pub fn from_structure(s: &Structure) -> Self {
        let (ne, nx) = (s.n_equations(), s.n_states());
        // Per row, the columns of a pattern's entries in the pattern's order: one pass over
        // the entries (a scan of the whole pattern per row was quadratic in the dimension).
        let by_row = |p: &[(usize, usize)]| -> Vec<Vec<usize>> {
            let mut rows = vec![Vec::new(); ne];
            for &(r, c) in p {
                if let Some(row) = rows.get_mut(r) {
                    row.push(c);
                }
            }
            rows
        };
        let (f_xdot, f_z, f_u, f_x) = (
            by_row(&s.pattern_f_xdot),
            by_row(&s.pattern_f_z),
            by_row(&s.pattern_f_u),
            by_row(&s.pattern_f_x),
        );
        let mut kinematic: Vec<Option<usize>> = vec![None; nx]; // state -> row
        let mut constraints = Vec::new();
        let mut prescribed = Vec::new();
        for i in 0..ne {
            let (xd, zc) = (&f_xdot[i], &f_z[i]);
            if zc.is_empty() && xd.len() == 1 && kinematic[xd[0]].is_none() {
                kinematic[xd[0]] = Some(i);
            }
            if xd.is_empty() && zc.is_empty() {
                if f_u[i].is_empty() {
                    constraints.push(i);
                } else {
                    prescribed.push(i);
                }
            }
        }
        let states_of = |i: usize| f_x[i].iter().copied();
        let (position, velocity): (Vec<usize>, Vec<usize>) = constraints
            .iter()
            .partition(|&&i| states_of(i).all(|j| kinematic[j].is_some()));
        let mut pos_states: Vec<usize> = position.iter().flat_map(|&i| states_of(i)).collect();
        pos_states.sort_unstable();
        pos_states.dedup();
        let mut is_position = vec![false; nx];
        for &j in &pos_states {
            is_position[j] = true;
        }
        let mut vel_states: Vec<usize> = pos_states
            .iter()
            .filter_map(|&j| kinematic[j])
            .flat_map(states_of)
            .filter(|&j| !is_position.get(j).copied().unwrap_or(false))
            .collect();
        vel_states.sort_unstable();
        vel_states.dedup();
        Self {
            kinematic,
            position_constraints: position,
            velocity_constraints: velocity,
            position_states: pos_states,
            velocity_states: vel_states,
            prescribed,
            n_states: nx,
            n_algebraic: s.n_algebraic(),
        }
    }

    /// Refuse a plant with a prescribed motion, whose consistent values depend on the input's
    /// derivatives.
    ///
    /// # Errors
    /// [`ConsistentError::Unsupported`] naming the first such row.
    pub fn check_supported<M: DaeModel>(&self, model: &M) -> Result<(), ConsistentError> {
        self.check_supported_in(model.structure())
    }

    /// [`Self::check_supported`] for a model with the structure `s`.
    fn check_supported_in(&self, s: &Structure) -> Result<(), ConsistentError> {
        match self.prescribed.first() {
            Some(&i) => Err(ConsistentError::Unsupported {
                equation: s.equation_name(i),
                reason: "a constraint that depends on the input prescribes a motion; consistent values depend on the input's derivatives",
            }),
            None => Ok(()),
        }
    }

    /// Whether the plant has constraint rows (and so is of index 2 or 3, not an ODE or an
    /// index-1 DAE).
    pub fn is_constrained(&self) -> bool {
        !(self.position_constraints.is_empty() && self.velocity_constraints.is_empty())
    }

    /// The constraint rows, ascending.
    pub fn constraint_rows(&self) -> Vec<usize> {
        let mut c: Vec<usize> = self
            .position_constraints
            .iter()
            .chain(&self.velocity_constraints)
            .copied()
            .collect();
        c.sort_unstable();
        c
    }

    /// Per unknown of the plant stabilised by the hidden velocity constraints (the unknowns
    /// `(x, z)` followed by one multiplier `mu` per position constraint, as the closed loop
    /// integrates it; see [`crate::simulate`]), its differentiation index as the integrator's
    /// error control needs it ([`crate::radau::Options::index`]): 1 for the states, 2 for the
    /// algebraic unknowns and the `mu` of a constrained plant.
    pub fn stabilised_index(&self) -> Vec<u8> {
        let z = if self.is_constrained() { 2 } else { 1 };
        let mut index = vec![1u8; self.n_states];
        index.extend(std::iter::repeat_n(
            z,
            self.n_algebraic + self.position_constraints.len(),
        ));
        index
    }
}

/// Minimum-norm solution of the underdetermined `g dx = rhs` (`g` with full row rank) by a
/// QR factorisation of `g^T`; `None` when `g` is rank deficient.
fn min_norm(g: &DMatrix<f64>, rhs: &DVector<f64>) -> Option<DVector<f64>> {
    if g.nrows() == 0 {
        return Some(DVector::zeros(g.ncols()));
    }
    if g.nrows() > g.ncols() {
        return None;
    }
    let qr = g.transpose().qr();
    let r = qr.r();
    let rmax = r.diagonal().amax();
    let tol = 100.0 * (g.ncols() as f64) * f64::EPSILON * rmax;
    if rmax == 0.0 || r.diagonal().iter().any(|d| d.abs() <= tol) {
        return None;
    }
    let y = r.tr_solve_upper_triangular(rhs)?;
    Some(qr.q() * y)
}

/// The consistent state nearest (in the sense of minimum-norm Gauss-Newton corrections) to
/// `x_given`, with its derivatives and multipliers, at time `t` and input `u`. See the module
/// documentation for the algorithm.
///
/// # Errors
/// [`ConsistentError`]: wrong lengths, non-finite values, constraints that cannot be met,
/// undetermined multipliers, or an unsupported structure.
pub fn consistent_state<M: DaeModel>(
    model: &M,
    t: f64,
    x_given: &[f64],
    u: &[f64],
    opts: &ConsistentOptions,
) -> Result<ConsistentState, ConsistentError> {
    let eval =
        |t: f64, x: &[f64], xdot: &[f64], z: &[f64], u: &[f64]| evaluate(model, t, x, xdot, z, u);
    let s = model.structure();
    let (ne, nx, nz) = (s.n_equations(), s.n_states(), s.n_algebraic());
    let curvature = |t: f64, x: &[f64], z: &[f64], u: &[f64], v: &[f64]| {
        let mut c = DMatrix::zeros(ne, nx + nz);
        model
            .constraint_curvature(t, x, z, u, v, &mut c)
            .then_some(c)
    };
    solve(s, &eval, &curvature, t, x_given, u, opts)
}

/// A model's residual with every Jacobian block at a point `(t, x, x', z, u)`, behind a
/// reference to a closure: the iteration of [`consistent_state`] is compiled once in this
/// crate instead of once per model in every crate that uses it (only [`evaluate`] is).
type Evaluate<'a> = &'a dyn Fn(f64, &[f64], &[f64], &[f64], &[f64]) -> Result<Jac, ConsistentError>;

/// A model's exact constraint curvature `C(v)` at `(t, x, z, u)` along `v` (equations x
/// unknowns, [`DaeModel::constraint_curvature`]), `None` when the model does not supply it.
type Curvature<'a> = &'a dyn Fn(f64, &[f64], &[f64], &[f64], &[f64]) -> Option<DMatrix<f64>>;

/// [`consistent_state`] for the model with structure `s` evaluated by `eval`.
fn solve(
    s: &Structure,
    eval: Evaluate<'_>,
    exact_curvature: Curvature<'_>,
    t: f64,
    x_given: &[f64],
    u: &[f64],
    opts: &ConsistentOptions,
) -> Result<ConsistentState, ConsistentError> {
    let (ne, nx, nz, nu) = (s.n_equations(), s.n_states(), s.n_algebraic(), s.n_inputs());
    for (what, v, n) in [("x", x_given, nx), ("u", u, nu)] {
        if v.len() != n {
            return Err(ConsistentError::Dimension {
                what,
                expected: n,
                found: v.len(),
            });
        }
    }
    let structure = ConstraintStructure::from_structure(s);
    structure.check_supported_in(s)?;
    let ConstraintStructure {
        kinematic,
        position_constraints: position,
        velocity_constraints: velocity,
        position_states: pos_states,
        ..
    } = structure;
    let constraints: Vec<usize> = {
        let mut c: Vec<usize> = position.iter().chain(&velocity).copied().collect();
        c.sort_unstable();
        c
    };

    let mut x = x_given.to_vec();
    let mut xdot = vec![0.0; nx];
    let mut z = vec![0.0; nz];
    let mut iterations = [0usize; 3];

    // Relative residual of rows `rows` of `j` at `x`.
    let rel = |j: &Jac, rows: &[usize], x: &[f64]| -> (f64, usize) {
        let mut worst = (0.0, rows.first().copied().unwrap_or(0));
        for &i in rows {
            let scale: f64 = (0..nx).map(|k| j.f_x[(i, k)].abs() * x[k].abs()).sum();
            let v = j.r[i].abs() / (1.0 + scale);
            if v > worst.0 || v.is_nan() {
                worst = (v, i);
            }
        }
        worst
    };
    let cannot =
        |stage: &'static str, j: &Jac, i: usize, iters: usize| ConsistentError::CannotMeet {
            stage,
            equation: s.equation_name(i),
            residual: j.r[i],
            tolerance: opts.tol,
            iterations: iters,
        };

    // 1. Positions: g(x) = 0 over all states, minimum norm.
    let all_states: Vec<usize> = (0..nx).collect();
    let mut it = 0;
    loop {
        let j = eval(t, &x, &xdot, &z, u)?;
        let (worst, wi) = rel(&j, &constraints, &x);
        if worst <= opts.tol {
            break;
        }
        if it == opts.max_iterations {
            return Err(cannot("positions", &j, wi, it));
        }
        let g = DMatrix::from_fn(constraints.len(), nx, |a, k| j.f_x[(constraints[a], k)]);
        let rhs = DVector::from_fn(constraints.len(), |a, _| -j.r[constraints[a]]);
        let dx = min_norm(&g, &rhs).ok_or_else(|| cannot("positions", &j, wi, it))?;
        for k in &all_states {
            x[*k] += dx[*k];
        }
        it += 1;
    }
    iterations[0] = it;

    // Velocities phi_j(x) of the kinematic states, and their Jacobian rows.
    let velocities = |j: &Jac, xdot: &[f64]| -> (DVector<f64>, DMatrix<f64>) {
        let mut p = DVector::zeros(nx);
        let mut p_x = DMatrix::zeros(nx, nx);
        for (k, row) in kinematic.iter().enumerate() {
            if let Some(i) = *row {
                let c = j.f_xdot[(i, k)];
                p[k] = xdot[k] - j.r[i] / c;
                for l in 0..nx {
                    p_x[(k, l)] = -j.f_x[(i, l)] / c;
                }
            }
        }
        (p, p_x)
    };
    let j = eval(t, &x, &xdot, &z, u)?;
    for (k, row) in kinematic.iter().enumerate() {
        if let Some(i) = *row {
            if j.f_xdot[(i, k)] == 0.0 {
                return Err(ConsistentError::Unsupported {
                    equation: s.equation_name(i),
                    reason: "the derivative's coefficient vanishes at the given state",
                });
            }
        }
    }

    // 2. Velocities: g_x(x) phi(x) = 0 over the states the position constraints do not involve.
    let free: Vec<usize> = (0..nx).filter(|k| !pos_states.contains(k)).collect();
    let mut it = 0;
    loop {
        let j = eval(t, &x, &xdot, &z, u)?;
        let (p, p_x) = velocities(&j, &xdot);
        let g = DMatrix::from_fn(position.len(), nx, |a, k| j.f_x[(position[a], k)]);
        let h = &g * &p;
        let mut worst = (0.0, 0usize);
        for (a, &i) in position.iter().enumerate() {
            let scale: f64 = (0..nx).map(|k| (g[(a, k)] * p[k]).abs()).sum();
            let v = h[a].abs() / (1.0 + scale);
            if v > worst.0 || v.is_nan() {
                worst = (v, i);
            }
        }
        if worst.0 <= opts.tol {
            break;
        }
        let fail = |it| ConsistentError::CannotMeet {
            stage: "velocities",
            equation: format!("the derivative of {}", s.equation_name(worst.1)),
            residual: worst.0,
            tolerance: opts.tol,
            iterations: it,
        };
        if it == opts.max_iterations {
            return Err(fail(it));
        }
        let jac_full = &g * &p_x;
        let jac = DMatrix::from_fn(position.len(), free.len(), |a, b| jac_full[(a, free[b])]);
        let d = min_norm(&jac, &(-h)).ok_or_else(|| fail(it))?;
        for (b, &k) in free.iter().enumerate() {
            x[k] += d[b];
        }
        it += 1;
    }
    iterations[1] = it;

    // 3. Derivatives and multipliers at fixed x.
    let n = nx + nz;
    let (kappa, curvature_error, curvature_exact) = {
        let j = eval(t, &x, &xdot, &z, u)?;
        let (p, _) = velocities(&j, &xdot);
        curvature(eval, exact_curvature, t, &x, &xdot, &z, u, &position, &p)?
    };
    let mut it = 0;
    loop {
        let j = eval(t, &x, &xdot, &z, u)?;
        let (_, p_x) = velocities(&j, &xdot);
        let rows = ne + position.len() + velocity.len();
        let mut jac = DMatrix::zeros(rows, n);
        let mut res = DVector::zeros(rows);
        jac.view_mut((0, 0), (ne, nx)).copy_from(&j.f_xdot);
        jac.view_mut((0, nx), (ne, nz)).copy_from(&j.f_z);
        for i in 0..ne {
            res[i] = j.r[i];
        }
        for (a, &i) in position.iter().enumerate() {
            let g = j.f_x.row(i);
            let row = g * &p_x;
            let xd = DVector::from_column_slice(&xdot);
            jac.view_mut((ne + a, 0), (1, nx)).copy_from(&row);
            res[ne + a] = (row * xd)[0] + kappa[a];
        }
        for (b, &i) in velocity.iter().enumerate() {
            let g = j.f_x.row(i);
            let xd = DVector::from_column_slice(&xdot);
            jac.view_mut((ne + position.len() + b, 0), (1, nx))
                .copy_from(&g);
            res[ne + position.len() + b] = (g * xd)[0];
        }
        // Residuals relative to the size of the terms that cancel in them (values included:
        // near a fast motion the terms, and their rounding errors, are large).
        let (worst, wi) = {
            let mut worst = (0.0_f64, 0usize);
            for r in 0..rows {
                let terms: f64 = (0..n)
                    .map(|k| {
                        let v = if k < nx { xdot[k] } else { z[k - nx] };
                        (jac[(r, k)] * v).abs()
                    })
                    .sum();
                let known = if r < ne {
                    (0..nx).map(|k| (j.f_x[(r, k)] * x[k]).abs()).sum::<f64>()
                } else if r < ne + position.len() {
                    kappa[r - ne].abs()
                } else {
                    0.0
                };
                let v = res[r].abs() / (1.0 + terms + known);
                if v > worst.0 || v.is_nan() {
                    worst = (v, r);
                }
            }
            worst
        };
        if worst <= opts.tol && it > 0 {
            break;
        }
        if it == opts.max_iterations {
            let equation = if wi < ne {
                s.equation_name(wi)
            } else if wi < ne + position.len() {
                format!(
                    "the second time derivative of {}",
                    s.equation_name(position[wi - ne])
                )
            } else {
                format!(
                    "the time derivative of {}",
                    s.equation_name(velocity[wi - ne - position.len()])
                )
            };
            return Err(ConsistentError::CannotMeet {
                stage: "derivatives and multipliers",
                equation,
                residual: res[wi],
                tolerance: opts.tol,
                iterations: it,
            });
        }
        let qr = jac.clone().col_piv_qr();
        let rd = qr.r().diagonal();
        let tol = 100.0 * (rows as f64) * f64::EPSILON * rd.amax();
        let rank = rd.iter().filter(|v| v.abs() > tol).count();
        if rank < n {
            return Err(ConsistentError::Undetermined {
                rank,
                unknowns: n,
                tolerance: tol,
            });
        }
        // Least squares through the (consistent, overdetermined) stacked system:
        // R P^T d = (Q^T r)[..n].
        let qtr = qr.q().transpose() * (-&res);
        let r = qr.r();
        let rn = r.view((0, 0), (n, n)).into_owned();
        let mut y = rn
            .solve_upper_triangular(&qtr.rows(0, n).into_owned())
            .ok_or(ConsistentError::Undetermined {
                rank,
                unknowns: n,
                tolerance: tol,
            })?;
        qr.p().inv_permute_rows(&mut y);
        for k in 0..nx {
            xdot[k] += y[k];
        }
        for k in 0..nz {
            z[k] += y[nx + k];
        }
        it += 1;
    }
    iterations[2] = it;

    let j = eval(t, &x, &xdot, &z, u)?;
    let residual = (0..ne)
        .map(|i| {
            let scale: f64 = (0..nx)
                .map(|k| j.f_x[(i, k)].abs() * x[k].abs() + j.f_xdot[(i, k)].abs() * xdot[k].abs())
                .sum::<f64>()
                + (0..nz)
                    .map(|k| j.f_z[(i, k)].abs() * z[k].abs())
                    .sum::<f64>();
            j.r[i].abs() / (1.0 + scale)
        })
        .fold(0.0, f64::max);
    let moved: Vec<f64> = x.iter().zip(x_given).map(|(a, b)| a - b).collect();
    let max_move = moved.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    Ok(ConsistentState {
        x,
        xdot,
        z,
        moved,
        max_move,
        position_constraints: position,
        velocity_constraints: velocity,
        iterations,
        curvature: kappa,
        curvature_exact,
        curvature_error,
        residual,
    })
}

/// `kappa_a = d/ds [g_x(x + s p) p]_a` at `s = 0` for the position constraints, from the
/// model's exact curvature if it supplies it (error estimate zero), else by a central
/// difference of the analytic Jacobian with the Richardson estimate of its error from the
/// difference at twice the step; and whether it is exact.
#[allow(clippy::too_many_arguments)]
fn curvature(
    eval: Evaluate<'_>,
    exact: Curvature<'_>,
    t: f64,
    x: &[f64],
    xdot: &[f64],
    z: &[f64],
    u: &[f64],
    rows: &[usize],
    p: &DVector<f64>,
) -> Result<(Vec<f64>, f64, bool), ConsistentError> {
    let pn = p.amax();
    if rows.is_empty() || pn == 0.0 {
        return Ok((vec![0.0; rows.len()], 0.0, false));
    }
    // C(p) - C(0): the second derivatives in x along p, without the part d^2 g/(dt dx) that
    // a time-dependent constraint adds (which the difference below does not see either).
    if let Some(c_p) = exact(t, x, z, u, p.as_slice()) {
        let c_0 = exact(t, x, z, u, &vec![0.0; p.len()])
            .unwrap_or_else(|| DMatrix::zeros(c_p.nrows(), c_p.ncols()));
        let k: Vec<f64> = rows
            .iter()
            .map(|&i| {
                (0..p.len())
                    .map(|k| (c_p[(i, k)] - c_0[(i, k)]) * p[k])
                    .sum::<f64>()
            })
            .collect();
        if k.iter().any(|v| !v.is_finite()) {
            return Err(ConsistentError::NonFinite {
                what: "constraint curvature",
            });
        }
        return Ok((k, 0.0, true));
    }
    let xn = x.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let h = f64::EPSILON.cbrt() * xn / pn;
    let diff = |h: f64| -> Result<Vec<f64>, ConsistentError> {
        let shift = |sign: f64| -> Vec<f64> {
            x.iter()
                .zip(p.iter())
                .map(|(a, b)| a + sign * h * b)
                .collect()
        };
        let jp = eval(t, &shift(1.0), xdot, z, u)?;
        let jm = eval(t, &shift(-1.0), xdot, z, u)?;
        Ok(rows
            .iter()
            .map(|&i| {
                let gp = jp.f_x.row(i) * p;
                let gm = jm.f_x.row(i) * p;
                (gp[0] - gm[0]) / (2.0 * h)
            })
            .collect())
    };
    let k1 = diff(h)?;
    let k2 = diff(2.0 * h)?;
    let err = k1
        .iter()
        .zip(&k2)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs() / 3.0));
    // Richardson extrapolation removes the O(h^2) term.
    let k: Vec<f64> = k1.iter().zip(&k2).map(|(a, b)| a + (a - b) / 3.0).collect();
    Ok((k, err, false))
}
