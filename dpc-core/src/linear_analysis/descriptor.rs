//! Linearisation of descriptor plants (constrained mechanics, index up to 3) and their
//! state-space realisation on the constraint manifold, for the Section 3 analysis.
//!
//! About a consistent point `(t, x, x', z, u)` of `F(t, x', x, z, u) = 0`, `y = h(t, x, z, u)`
//! (an equilibrium, or a steady motion with the given `x'`), the variations `w = (dx, dz)`
//! satisfy the linear descriptor system
//!
//! ```text
//! E w' = A w + B u,   y = C w + D u,
//! E = [F_x' 0],  A = -[F_x F_z],  B = -F_u,  C = [h_x h_z],  D = h_u,
//! ```
//!
//! from the generated Jacobians (no finite differences). Its realisation on the constraint
//! manifold is computed with orthogonal decompositions only:
//!
//! 0. balancing: `D_r (sE - A) D_c` with diagonal power-of-two scalings that equilibrate the
//!    rows and columns of `|E| + |A|`, so that rank decisions are not relative to the largest of
//!    coefficients that span orders of magnitude; the bases below are mapped back by `D_c`;
//! 1. the Weierstrass split of the regular pencil `sE - A` by the Wong sequences
//!    ([`super::pencil::split`]; Berger, Ilchmann & Trenn, "The quasi-Kronecker form for matrix
//!    pencils", SIAM J. Matrix Anal. Appl. 33, 2012): orthonormal bases (of the balanced
//!    pencil) `V` of the finite and `W` of the infinite deflating subspace, each step an SVD
//!    with a rank decision relative to `||E||` or `||A||`; the number of steps of the infinite
//!    sequence is the index `nu` (the nilpotency index of `N`), and a pencil whose two limits do
//!    not span `R^n` is singular.
//!    This is the deflation of the pencil onto its finite part that Varga's descriptor-system
//!    algorithms perform by orthogonal staircase reductions (A. Varga, *Solving Fault Diagnosis
//!    Problems*, Springer 2017, Section 10.1; Kunkel & Mehrmann, *Differential-Algebraic
//!    Equations*, EMS 2006, Sections 2.1 and 3.1 for the regular-pencil theory).
//! 2. With `M = [E V, A W]^-1` (applied by solving with `[E V, A W]`, an LU with full
//!    pivoting whose condition number is reported), the slow part `zeta' = A_1 zeta + B_1 u`
//!    and the fast part `N eta' = eta + B_2 u`, where
//!    `[B_1; B_2] = M B` and `w = V zeta + W eta`. The fast part is `eta = -B_2 u` exactly when
//!    `N B_2 = 0`; otherwise the plant responds to derivatives of `u` (an improper transfer
//!    function, e.g. a position prescribed by the input) and no `LinearSystem` describes it.
//! 3. The differential part `V_x` of `V` (its first `n_x` rows) has full column rank for a
//!    regular pencil (a slow direction with `dx = 0` would lie in `ker E`); its thin QR
//!    factorisation `V_x = U R` gives the reduced state `xi = R zeta` with `dx = U xi`, `U`
//!    orthonormal. Then
//!
//! ```text
//! xi' = R A_1 R^-1 xi + R B_1 u,   y = C V R^-1 xi + (D - C W B_2) u,
//! dz  = V_z R^-1 xi - W_z B_2 u,
//! ```
//!
//! with `R^-1` applied by triangular solves. The state dimension is `dim V`, the plant's
//! degrees of freedom (positions and velocities on the constraint manifold, twice the
//! mechanical degrees of freedom for a mechanical plant).
//!
//! # Gains on the reduced state
//! `U` spans the tangent space, in the plant's own coordinates `x`, of the manifold on which the
//! linearised plant moves (positions and velocities consistent with the constraints and their
//! hidden derivatives). For a consistent variation `dx` the reduced state is `xi = U^T dx`.
//! A gain `K_r` on `xi` (for example `K_n` of [`super::analyze`] on [`ManifoldRealisation::system`])
//! is the plant gain `K_x = K_r U^T` ([`ManifoldRealisation::gain_to_plant`]): `K_x dx = K_r xi`
//! for every consistent `dx`, so the linear closed loop is the same. Any `K` with `K U = K_r`
//! acts identically on consistent variations; `K_r U^T` is the one that is zero on the
//! constrained (normal) directions, the columns of [`ManifoldRealisation::normal`]. The mapping
//! does not depend on the choice of basis: with another orthonormal basis `U Q` of the tangent
//! space the reduced system is similar by `Q`, its `K_r` becomes `K_r Q`, and `K_r Q (U Q)^T =
//! K_r U^T`.
//!
//! For an ODE or an index-1 plant the realisation is similar to [`crate::linearize::linearize`]'s
//! (same eigenvalues and transfer function), with `U` an orthonormal basis of all of `R^{n_x}`.

use nalgebra::DMatrix;
use thiserror::Error;

use super::subspace::{self, RankDecision};
use super::{pencil, LinearError, LinearSystem};
use crate::linearize::{Jacobians, OperatingPoint, PointError};
use crate::model::{DaeModel, Structure};

/// Options of [`linearize_descriptor`] and [`realise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DescriptorOptions {
    /// Multiple of `max(rows, cols) * eps * norm` below which singular values count as zero in
    /// the pencil split (as [`super::AnalysisOptions::tol_factor`]). Default 100.
    pub tol_factor: f64,
    /// Equation `i` is consistent when `|F_i| <= consistency_tol * (1 + s_i)`, with
    /// `s_i = sum_j |dF_i/dv_j| |v_j|` over all arguments `v = (x', x, z, u)`: the size of the
    /// terms that cancel in `F_i`. Default `1e-8`.
    pub consistency_tol: f64,
    /// Relative tolerance for the structural zeros `N B_2 = 0` and `W_x B_2 = 0`, relative to
    /// `max(1, ||N||) ||M B||` and `||M B||`. Default `1e-8` (they are computed through `M`,
    /// so they carry its condition number times `eps`).
    pub structural_tol: f64,
    /// Highest index accepted. Default 3.
    pub max_index: usize,
}

impl Default for DescriptorOptions {
    fn default() -> Self {
        Self {
            tol_factor: 100.0,
            consistency_tol: 1e-8,
            structural_tol: 1e-8,
            max_index: 3,
        }
    }
}

/// Why a descriptor plant could not be linearised or realised.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DescriptorError {
    /// A point vector has the wrong length.
    #[error("{what} has length {found}, expected {expected}")]
    Dimension {
        /// Which vector or matrix.
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// The model produced a non-finite value at the point.
    #[error("non-finite {what} at the linearisation point")]
    NonFinite {
        /// Residual or which Jacobian.
        what: &'static str,
    },
    /// The point does not satisfy the plant's equations.
    #[error("the point is not consistent: {equation} has residual {residual:e}, above the tolerance {tolerance:e} (relative to the size {scale:e} of its terms)")]
    Inconsistent {
        /// The equation with the largest relative residual, as the model names it.
        equation: String,
        /// Its residual.
        residual: f64,
        /// The absolute tolerance it was held to.
        tolerance: f64,
        /// The size of its terms that the tolerance is relative to.
        scale: f64,
    },
    /// The pencil `sE - A` is singular: the linearised plant has no unique solution (too few
    /// or dependent equations, or a constraint that does not determine its multiplier).
    #[error("singular pencil sE - A: the finite deflating subspace has dimension {finite_dim}, the infinite one {infinite_dim}, together less than the {n} unknowns (tolerance factor {tol_factor})")]
    SingularPencil {
        /// Dimension of the finite deflating subspace found.
        finite_dim: usize,
        /// Dimension of the infinite deflating subspace found.
        infinite_dim: usize,
        /// Number of unknowns `n_x + n_z`.
        n: usize,
        /// Rank tolerance factor used.
        tol_factor: f64,
    },
    /// The index exceeds what is supported.
    #[error("the plant has index {index} at the point, above the supported {max}")]
    IndexTooHigh {
        /// Index found (nilpotency index of `N`).
        index: usize,
        /// Highest index accepted.
        max: usize,
    },
    /// The constrained components respond to derivatives of the input (`N B_2 != 0`).
    #[error("the input's derivatives drive the constrained components (|N B_2| = {coupling:e} > {tolerance:e}): the transfer function is improper and has no state-space realisation")]
    ImproperInput {
        /// `||N B_2||`.
        coupling: f64,
        /// Tolerance it was compared with.
        tolerance: f64,
    },
    /// The input moves a differential state instantaneously (`W_x B_2 != 0`).
    #[error("the input moves state {state} instantaneously (|W_x B_2| = {coupling:e} > {tolerance:e}): the differential state does not determine the reduced state")]
    StateFeedthrough {
        /// The state most affected.
        state: String,
        /// `||W_x B_2||`.
        coupling: f64,
        /// Tolerance it was compared with.
        tolerance: f64,
    },
    /// A linear-algebra step failed (an SVD did not converge, or the reduced system is not
    /// square).
    #[error(transparent)]
    Linear(#[from] LinearError),
}

/// The linear descriptor system `E w' = A w + B u, y = C w + D u` in `w = (dx, dz)`.
#[derive(Debug, Clone, PartialEq)]
pub struct DescriptorSystem {
    /// `E = [F_x' 0]`, `n x n` with `n = n_x + n_z`.
    pub e: DMatrix<f64>,
    /// `A = -[F_x F_z]`.
    pub a: DMatrix<f64>,
    /// `B = -F_u`.
    pub b: DMatrix<f64>,
    /// `C = [h_x h_z]`.
    pub c: DMatrix<f64>,
    /// `D = h_u`.
    pub d: DMatrix<f64>,
    /// Number of differential unknowns `n_x` (the first entries of `w`).
    pub n_states: usize,
}

/// The state-space realisation of a descriptor system on its constraint manifold.
#[derive(Debug, Clone)]
pub struct ManifoldRealisation {
    /// `xi' = A_r xi + B_r u, y = C_r xi + D_r u` with `dx = U xi`: the system
    /// [`super::analyze`] takes.
    pub system: LinearSystem,
    /// `U` (`n_x x dof`, orthonormal columns): the tangent space of the constraint manifold in
    /// the plant's state coordinates; `dx = U xi`, `xi = U^T dx` for consistent `dx`.
    pub basis: DMatrix<f64>,
    /// `Z_xi` (`n_z x dof`): the algebraic unknowns (multipliers) on the manifold,
    /// `dz = Z_xi xi + Z_u u`.
    pub algebraic_state: DMatrix<f64>,
    /// `Z_u` (`n_z x m`), see [`algebraic_state`](Self::algebraic_state).
    pub algebraic_input: DMatrix<f64>,
    /// Orthonormal basis (`n_x x (n_x - dof)`) of the constrained directions of `x`, the
    /// orthogonal complement of [`basis`](Self::basis).
    pub normal: DMatrix<f64>,
    /// Per state, `|row i of normal|^2` in `[0, 1]`: the part of the unit vector of state `i`
    /// that is normal to the manifold (0 for a state the constraints do not restrict).
    pub normal_share: Vec<f64>,
    /// The states with `normal_share > 1e-10`: the constrained components.
    pub constrained_states: Vec<usize>,
    /// Degrees of freedom: the dimension of the manifold (`dim V` of the pencil).
    pub dof: usize,
    /// Index of the pencil (`nu`, 0 for an ODE).
    pub index: usize,
    /// Dimensions of the infinite Wong sequence `W_0, W_1, ..., W_nu`.
    pub infinite_chain: Vec<usize>,
    /// Diagnostics of the numerical decisions.
    pub diagnostics: RealisationDiagnostics,
}

/// How clear-cut the decisions of [`realise`] were.
#[derive(Debug, Clone, PartialEq)]
pub struct RealisationDiagnostics {
    /// Smallest ratio (smallest kept / largest dropped singular value) over the Wong-sequence
    /// rank decisions, if any dropped a nonzero value.
    pub pencil_gap: Option<f64>,
    /// Condition number of `[V W]`.
    pub cond_q: f64,
    /// Condition number of `[E V, A W]`.
    pub cond_m_inv: f64,
    /// Off-diagonal residual of the block form (relative).
    pub block_residual: f64,
    /// Condition number of `V_x` (of `R`).
    pub cond_basis: f64,
    /// `||N B_2||`, zero for a proper plant.
    pub improper_coupling: f64,
    /// `||W_x B_2||`, zero when the input does not move the state instantaneously.
    pub state_feedthrough: f64,
}

impl ManifoldRealisation {
    /// The plant-coordinate gain `K_x = K_r U^T` (`m x n_x`) of a gain `K_r` (`m x dof`) on
    /// the reduced state: `K_x dx = K_r xi` for every consistent variation `dx = U xi`, and
    /// `K_x` is zero on the constrained directions. See the module documentation.
    ///
    /// # Errors
    /// [`DescriptorError::Dimension`] when `K_r` does not have `dof` columns.
    pub fn gain_to_plant(&self, k_r: &DMatrix<f64>) -> Result<DMatrix<f64>, DescriptorError> {
        if k_r.ncols() != self.dof {
            return Err(DescriptorError::Dimension {
                what: "columns of the reduced gain",
                expected: self.dof,
                found: k_r.ncols(),
            });
        }
        Ok(k_r * self.basis.transpose())
    }

    /// The reduced state `xi = U^T dx` of a state variation `dx` (`n_x` entries).
    ///
    /// # Errors
    /// [`DescriptorError::Dimension`] for a wrong length.
    pub fn reduce(&self, dx: &[f64]) -> Result<nalgebra::DVector<f64>, DescriptorError> {
        if dx.len() != self.basis.nrows() {
            return Err(DescriptorError::Dimension {
                what: "state variation",
                expected: self.basis.nrows(),
                found: dx.len(),
            });
        }
        Ok(self.basis.transpose() * nalgebra::DVector::from_column_slice(dx))
    }
}

impl From<PointError> for DescriptorError {
    fn from(e: PointError) -> Self {
        match e {
            PointError::Dimension {
                what,
                expected,
                found,
            } => Self::Dimension {
                what,
                expected,
                found,
            },
            PointError::NonFinite { what } => Self::NonFinite { what },
        }
    }
}

/// The linear descriptor system of `model` about `point` and the residual there.
///
/// # Errors
/// [`DescriptorError::Dimension`] for wrong lengths, [`DescriptorError::NonFinite`] for a
/// non-finite residual or Jacobian, [`DescriptorError::Inconsistent`] when the point does not
/// satisfy `F = 0` within [`DescriptorOptions::consistency_tol`].
pub fn descriptor_system<M: DaeModel>(
    model: &M,
    point: OperatingPoint<'_>,
    opts: &DescriptorOptions,
) -> Result<DescriptorSystem, DescriptorError> {
    let jacobians = Jacobians::at(model, point)?;
    descriptor_from_jacobians(model.structure(), point, jacobians, opts)
}

/// [`descriptor_system`] from the Jacobians at `point` of a model with the structure
/// `structure`: compiled once in this crate, not once per model in every crate that uses it.
fn descriptor_from_jacobians(
    structure: &Structure,
    point: OperatingPoint<'_>,
    jacobians: Jacobians,
    opts: &DescriptorOptions,
) -> Result<DescriptorSystem, DescriptorError> {
    let (nx, nz, ny, ne) = (
        structure.n_states(),
        structure.n_algebraic(),
        structure.n_outputs(),
        structure.n_equations(),
    );
    let Jacobians {
        residual: r,
        f_xdot,
        f_x,
        f_z,
        f_u,
        h_x,
        h_z,
        h_u,
    } = jacobians;
    if r.iter().any(|v| !v.is_finite()) {
        return Err(DescriptorError::NonFinite { what: "residual" });
    }

    // Consistency, per equation, relative to the terms that cancel in it.
    let mut worst: Option<(usize, f64, f64)> = None;
    for (i, &ri) in r.iter().enumerate() {
        let term = |m: &DMatrix<f64>, v: &[f64]| -> f64 {
            v.iter()
                .enumerate()
                .map(|(j, vj)| m[(i, j)].abs() * vj.abs())
                .sum()
        };
        let scale = term(&f_xdot, point.xdot)
            + term(&f_x, point.x)
            + term(&f_z, point.z)
            + term(&f_u, point.u);
        let ratio = ri.abs() / (1.0 + scale);
        if ratio > opts.consistency_tol && worst.is_none_or(|(_, w, _)| ratio > w) {
            worst = Some((i, ratio, scale));
        }
    }
    if let Some((i, _, scale)) = worst {
        return Err(DescriptorError::Inconsistent {
            equation: structure.equation_name(i),
            residual: r[i],
            tolerance: opts.consistency_tol * (1.0 + scale),
            scale,
        });
    }

    let n = nx + nz;
    let mut e = DMatrix::zeros(ne, n);
    e.columns_mut(0, nx).copy_from(&f_xdot);
    let mut a = DMatrix::zeros(ne, n);
    a.columns_mut(0, nx).copy_from(&(-&f_x));
    a.columns_mut(nx, nz).copy_from(&(-&f_z));
    let mut c = DMatrix::zeros(ny, n);
    c.columns_mut(0, nx).copy_from(&h_x);
    c.columns_mut(nx, nz).copy_from(&h_z);
    Ok(DescriptorSystem {
        e,
        a,
        b: -f_u,
        c,
        d: h_u,
        n_states: nx,
    })
}

/// Linearise a descriptor plant about a consistent point and realise it on its constraint
/// manifold: [`descriptor_system`] then [`realise`].
///
/// State names in errors are those of `model`.
///
/// # Errors
/// Those of [`descriptor_system`] and [`realise`].
pub fn linearize_descriptor<M: DaeModel>(
    model: &M,
    point: OperatingPoint<'_>,
    opts: &DescriptorOptions,
) -> Result<(DescriptorSystem, ManifoldRealisation), DescriptorError> {
    let desc = descriptor_system(model, point, opts)?;
    let structure = model.structure();
    let real = realise(&desc, opts, |i| structure.unknown_name(i))?;
    Ok((desc, real))
}

/// Realise `E w' = A w + B u, y = C w + D u` on its constraint manifold (see the module
/// documentation for the algorithm). `state_name(i)` names state `i` in errors.
///
/// ```
/// use dpc_core::linear_analysis::descriptor::{realise, DescriptorOptions, DescriptorSystem};
/// use dpc_core::linear_analysis::eigenvalues;
/// use nalgebra::DMatrix;
/// // A unit mass on a line x = 0 held by the multiplier lambda, with a horizontal force u and
/// // a spring k = 4: w = (x, y, vx, vy, lambda); x' = vx, y' = vy, vx' = -4 x + u,
/// // vy' = lambda, 0 = y (index 3). On the manifold: x'' = -4 x + u.
/// let mut e = DMatrix::zeros(5, 5);
/// let mut a = DMatrix::zeros(5, 5);
/// for i in 0..4 {
///     e[(i, i)] = 1.0;
/// }
/// a[(0, 2)] = 1.0;
/// a[(1, 3)] = 1.0;
/// a[(2, 0)] = -4.0;
/// a[(3, 4)] = 1.0;
/// a[(4, 1)] = 1.0;
/// let mut b = DMatrix::zeros(5, 1);
/// b[(2, 0)] = 1.0;
/// let mut c = DMatrix::zeros(1, 5);
/// c[(0, 0)] = 1.0;
/// let sys = DescriptorSystem { e, a, b, c, d: DMatrix::zeros(1, 1), n_states: 4 };
/// let real = realise(&sys, &DescriptorOptions::default(), |i| format!("w{i}")).unwrap();
/// assert_eq!((real.index, real.dof), (3, 2));
/// assert_eq!(real.constrained_states, vec![1, 3]); // y and vy
/// let ev = eigenvalues(&real.system.a).unwrap();
/// assert!(ev.iter().all(|z| z.re.abs() < 1e-12 && (z.im.abs() - 2.0).abs() < 1e-12));
/// ```
///
/// # Errors
/// [`DescriptorError::Dimension`] when the matrices do not fit together,
/// [`DescriptorError::SingularPencil`], [`DescriptorError::IndexTooHigh`],
/// [`DescriptorError::ImproperInput`], [`DescriptorError::StateFeedthrough`], and
/// [`DescriptorError::Linear`] when a decomposition fails or the reduced system is not square.
pub fn realise(
    sys: &DescriptorSystem,
    opts: &DescriptorOptions,
    state_name: impl Fn(usize) -> String,
) -> Result<ManifoldRealisation, DescriptorError> {
    realise_named(sys, opts, &state_name)
}

/// [`realise`] with the names behind a reference, so that its decompositions are compiled once
/// in this crate, not once per closure in every crate that calls it.
fn realise_named(
    sys: &DescriptorSystem,
    opts: &DescriptorOptions,
    state_name: &dyn Fn(usize) -> String,
) -> Result<ManifoldRealisation, DescriptorError> {
    let n = sys.e.ncols();
    let nx = sys.n_states;
    let m = sys.b.ncols();
    for (what, found, expected) in [
        ("rows of E", sys.e.nrows(), n),
        ("rows of A", sys.a.nrows(), n),
        ("columns of A", sys.a.ncols(), n),
        ("rows of B", sys.b.nrows(), n),
        ("columns of C", sys.c.ncols(), n),
        ("rows of D", sys.d.nrows(), sys.c.nrows()),
        ("columns of D", sys.d.ncols(), m),
    ] {
        if found != expected {
            return Err(DescriptorError::Dimension {
                what,
                expected,
                found,
            });
        }
    }
    if nx > n {
        return Err(DescriptorError::Dimension {
            what: "number of states",
            expected: n,
            found: nx,
        });
    }

    // Rank decisions are made on the balanced pencil D_r (sE - A) D_c: entries of a plant
    // span orders of magnitude (masses, stiffnesses, lengths), and a decision relative to
    // the largest one would drop the smallest physical coefficients.
    let (dr, dc) = balance(&sys.e, &sys.a);
    let es = DMatrix::from_fn(n, n, |i, j| dr[i] * sys.e[(i, j)] * dc[j]);
    let as_ = DMatrix::from_fn(n, n, |i, j| dr[i] * sys.a[(i, j)] * dc[j]);
    let bs = DMatrix::from_fn(n, m, |i, j| dr[i] * sys.b[(i, j)]);
    let scale_e = subspace::norm2(&es);
    let scale_a = subspace::norm2(&as_);
    let sp = match pencil::split(&es, &as_, opts.tol_factor, scale_e, scale_a) {
        Ok(sp) => sp,
        Err(LinearError::SingularPencil {
            finite_dim,
            infinite_dim,
            n,
            ..
        }) => {
            return Err(DescriptorError::SingularPencil {
                finite_dim,
                infinite_dim,
                n,
                tol_factor: opts.tol_factor,
            })
        }
        Err(e) => return Err(e.into()),
    };
    if sp.index > opts.max_index {
        return Err(DescriptorError::IndexTooHigh {
            index: sp.index,
            max: opts.max_index,
        });
    }
    let nf = sp.finite_dim;
    let ni = n - nf;
    let singular = || DescriptorError::SingularPencil {
        finite_dim: nf,
        infinite_dim: ni,
        n,
        tol_factor: opts.tol_factor,
    };
    // Bases of the deflating subspaces in the unscaled unknowns w = D_c w_s.
    let v = DMatrix::from_fn(n, nf, |i, j| dc[i] * sp.q[(i, j)]);
    let w = DMatrix::from_fn(n, ni, |i, j| dc[i] * sp.q[(i, nf + j)]);

    // [B_1; B_2] = M B, by solving with M^-1 = [E V, A W].
    let mb = subspace::solve(&sp.m_inv, &bs).ok_or_else(singular)?;
    let b1 = mb.rows(0, nf).into_owned();
    let b2 = mb.rows(nf, ni).into_owned();
    let nb2 = &sp.n_mat * &b2;
    let improper_coupling = subspace::norm2(&nb2);
    // Relative to the size of the whole of M B: B_2 itself may be zero up to rounding.
    let mb_norm = subspace::norm2(&mb).max(f64::MIN_POSITIVE);
    let improper_tol = opts.structural_tol * subspace::norm2(&sp.n_mat).max(1.0) * mb_norm;
    if improper_coupling > improper_tol {
        return Err(DescriptorError::ImproperInput {
            coupling: improper_coupling,
            tolerance: improper_tol,
        });
    }
    // The fast part is eta = -B_2 u.
    let w_b2 = &w * &b2;
    let wx_b2 = w_b2.rows(0, nx).into_owned();
    let state_feedthrough = subspace::norm2(&wx_b2);
    let feed_tol = opts.structural_tol * mb_norm;
    if state_feedthrough > feed_tol {
        let worst = (0..nx)
            .max_by(|&i, &j| wx_b2.row(i).amax().total_cmp(&wx_b2.row(j).amax()))
            .unwrap_or(0);
        return Err(DescriptorError::StateFeedthrough {
            state: state_name(worst),
            coupling: state_feedthrough,
            tolerance: feed_tol,
        });
    }

    if nf > nx {
        // More slow directions than states: V_x cannot have full column rank.
        return Err(singular());
    }
    // V_x = U R (thin QR); xi = R zeta, dx = U xi.
    let v_x = v.rows(0, nx).into_owned();
    let v_z = v.rows(nx, n - nx).into_owned();
    let (u, r) = if nf == 0 {
        (DMatrix::zeros(nx, 0), DMatrix::zeros(0, 0))
    } else {
        let qr = v_x.clone().qr();
        (qr.q(), qr.r())
    };
    let cond_basis = subspace::cond(&r);
    let cond_limit = 1.0 / (opts.tol_factor * (n.max(1) as f64) * f64::EPSILON);
    if !(cond_basis.is_finite() && cond_basis < cond_limit) {
        // For a regular pencil V_x has full column rank; a rank-deficient R means the split
        // itself was not trustworthy.
        return Err(singular());
    }
    // X R^-1 by solving R^T Y = X^T.
    let right_div = |x: &DMatrix<f64>| -> Result<DMatrix<f64>, DescriptorError> {
        if nf == 0 {
            return Ok(DMatrix::zeros(x.nrows(), 0));
        }
        r.tr_solve_upper_triangular(&x.transpose())
            .map(|y| y.transpose())
            .ok_or_else(singular)
    };
    let a_r = right_div(&(&r * &sp.a1))?;
    let b_r = &r * &b1;
    let c_r = right_div(&(&sys.c * &v))?;
    let d_r = &sys.d - &sys.c * &w_b2;
    let algebraic_state = right_div(&v_z)?;
    let algebraic_input = -w_b2.rows(nx, n - nx).into_owned();
    let system = LinearSystem::new(a_r, b_r, c_r, d_r)?;

    let normal = subspace::complement(&u)?;
    let normal_share: Vec<f64> = (0..nx).map(|i| normal.row(i).norm_squared()).collect();
    let constrained_states = normal_share
        .iter()
        .enumerate()
        .filter(|(_, &s)| s > 1e-10)
        .map(|(i, _)| i)
        .collect();

    let min_gap = |ds: &[RankDecision]| ds.iter().filter_map(|d| d.gap()).reduce(f64::min);
    let diagnostics = RealisationDiagnostics {
        pencil_gap: min_gap(&sp.decisions),
        cond_q: sp.cond_q,
        cond_m_inv: sp.cond_m_inv,
        block_residual: sp.block_residual,
        cond_basis,
        improper_coupling,
        state_feedthrough,
    };
    Ok(ManifoldRealisation {
        system,
        basis: u,
        algebraic_state,
        algebraic_input,
        normal,
        normal_share,
        constrained_states,
        dof: nf,
        index: sp.index,
        infinite_chain: sp.infinite_chain,
        diagnostics,
    })
}

/// Row and column scalings by powers of two (exact in floating point) that bring the largest
/// entry of every row and column of `|E| + |A|` near 1: a few sweeps of alternating row and
/// column equilibration (as in the balancing that precedes descriptor-system reductions,
/// Varga 2017, Section 10.1.1; Ward, "Balancing the generalized eigenvalue problem", 1981).
fn balance(e: &DMatrix<f64>, a: &DMatrix<f64>) -> (Vec<f64>, Vec<f64>) {
    let (r, c) = e.shape();
    let g = DMatrix::from_fn(r, c, |i, j| e[(i, j)].abs() + a[(i, j)].abs());
    let mut dr = vec![1.0; r];
    let mut dc = vec![1.0; c];
    let pow2 = |v: f64| -> f64 {
        if v > 0.0 && v.is_finite() {
            2f64.powi(-(v.log2().round() as i32))
        } else {
            1.0
        }
    };
    for _ in 0..4 {
        for (i, d) in dr.iter_mut().enumerate() {
            let mx = (0..c).map(|j| g[(i, j)] * dc[j]).fold(0.0, f64::max);
            *d = pow2(mx);
        }
        for (j, d) in dc.iter_mut().enumerate() {
            let mx = (0..r).map(|i| g[(i, j)] * dr[i]).fold(0.0, f64::max);
            *d = pow2(mx);
        }
    }
    (dr, dc)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two masses joined rigidly, `x1 = x2`, the first on a spring and driven by `u`:
    /// `m1 v1' = -k x1 + lambda + u`, `m2 v2' = -lambda`, `0 = x2 - x1` (index 3). On the
    /// manifold it is one mass `m1 + m2` on the spring.
    fn rigid_pair(m1: f64, m2: f64, k: f64) -> DescriptorSystem {
        // w = (x1, x2, v1, v2, lambda).
        let mut e = DMatrix::zeros(5, 5);
        let mut a = DMatrix::zeros(5, 5);
        e[(0, 0)] = 1.0;
        a[(0, 2)] = 1.0;
        e[(1, 1)] = 1.0;
        a[(1, 3)] = 1.0;
        e[(2, 2)] = m1;
        a[(2, 0)] = -k;
        a[(2, 4)] = 1.0;
        e[(3, 3)] = m2;
        a[(3, 4)] = -1.0;
        a[(4, 0)] = -1.0;
        a[(4, 1)] = 1.0;
        let mut b = DMatrix::zeros(5, 1);
        b[(2, 0)] = 1.0;
        let mut c = DMatrix::zeros(1, 5);
        c[(0, 1)] = 1.0;
        DescriptorSystem {
            e,
            a,
            b,
            c,
            d: DMatrix::zeros(1, 1),
            n_states: 4,
        }
    }

    #[test]
    fn rigid_pair_is_one_mass_on_a_spring() {
        let (m1, m2, k) = (1.0, 3.0, 16.0);
        let real = realise(&rigid_pair(m1, m2, k), &DescriptorOptions::default(), |i| {
            format!("x{i}")
        })
        .unwrap();
        assert_eq!((real.index, real.dof), (3, 2));
        assert_eq!(real.constrained_states, vec![0, 1, 2, 3]);
        let ev = super::super::eigenvalues(&real.system.a).unwrap();
        let omega = (k / (m1 + m2)).sqrt();
        assert!(ev.iter().all(|z| z.re.abs() < 1e-12));
        assert!(
            ev.iter().all(|z| (z.im.abs() - omega).abs() < 1e-12),
            "{ev:?}"
        );
        // H(s) = 1 / ((m1 + m2) s^2 + k).
        let s = num_complex::Complex::new(0.4, 1.3);
        let h = super::super::transfer::transfer_matrix(&real.system, s).unwrap()[(0, 0)];
        let expected = 1.0 / (s * s * (m1 + m2) + k);
        assert!(
            (h - expected).norm() < 1e-12 * expected.norm(),
            "{h} vs {expected}"
        );
        // lambda = -m2 x'' = -m2 (u - k x) / (m1 + m2) on the manifold.
        let zu = real.algebraic_input[(0, 0)];
        assert!((zu + m2 / (m1 + m2)).abs() < 1e-12, "{zu}");
        // A reduced gain acts on consistent variations through U and is zero on the normal
        // directions (x1 - x2, v1 - v2): equal shares on x1 and x2, on v1 and v2.
        let k_r = DMatrix::from_row_slice(1, 2, &[1.0, 0.5]);
        let kx = real.gain_to_plant(&k_r).unwrap();
        assert!((&kx * &real.basis - &k_r).amax() < 1e-12);
        assert!((kx[(0, 0)] - kx[(0, 1)]).abs() < 1e-12, "{kx}");
        assert!((kx[(0, 2)] - kx[(0, 3)]).abs() < 1e-12, "{kx}");
        assert!(real.gain_to_plant(&DMatrix::zeros(1, 3)).is_err());
    }
}
