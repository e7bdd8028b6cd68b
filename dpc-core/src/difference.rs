//! The iteration matrix of a hand-written [`ImplicitDae`] by difference quotients of its
//! residual, for a model that has no Jacobian (IDA's default when no `IDASetJacFn` is given).
//!
//! A DAE ported by hand from another code often comes with `F(t, y, y')` alone. Its
//! [`iteration_matrix`](ImplicitDae::iteration_matrix) can then be one line:
//!
//! ```
//! use dpc_core::difference::DifferenceQuotients;
//! use dpc_core::{ImplicitDae, MatrixSink};
//!
//! /// Robertson's reaction in the form `y1 + y2 + y3 = 1`, without a Jacobian.
//! struct Robertson {
//!     differences: DifferenceQuotients,
//! }
//!
//! impl ImplicitDae for Robertson {
//!     fn dimension(&self) -> usize {
//!         3
//!     }
//!     fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
//!         out[0] = yp[0] + 0.04 * y[0] - 1e4 * y[1] * y[2];
//!         out[1] = yp[1] - 0.04 * y[0] + 1e4 * y[1] * y[2] + 3e7 * y[1] * y[1];
//!         out[2] = y[0] + y[1] + y[2] - 1.0;
//!     }
//!     fn iteration_matrix<S: MatrixSink + ?Sized>(
//!         &self,
//!         t: f64,
//!         y: &[f64],
//!         yp: &[f64],
//!         c: f64,
//!         out: &mut S,
//!     ) {
//!         self.differences.iteration_matrix(self, t, y, yp, c, out);
//!     }
//! }
//!
//! // Robertson's y2 is of order 1e-5: the increments' floor from the integrator's atol, as IDA.
//! let atol = [1e-6, 1e-10, 1e-6];
//! let differences = DifferenceQuotients::with_absolute_tolerance(&atol).expect("positive");
//! let dae = Robertson { differences };
//! let mut m = nalgebra::DMatrix::zeros(3, 3);
//! dae.iteration_matrix(0.0, &[1.0, 0.0, 0.0], &[-0.04, 0.04, 0.0], 10.0, &mut m);
//! assert!((m[(0, 0)] - (10.0 + 0.04)).abs() < 1e-6);
//! assert!((m[(2, 1)] - 1.0).abs() < 1e-5); // y1 + y2 + y3 - 1 loses digits to the 1
//! ```
//!
//! # The increment
//!
//! Column `j` of `dF/dy + c dF/dy'` is the directional derivative of `F` along `y_j` with
//! `y'_j` moving `c` times as fast, so one residual at `(y + inc_j e_j, y' + c inc_j e_j)`
//! gives the whole column: `(F(y + inc_j e_j, y' + c inc_j e_j) - F(y, y')) / inc_j`, an error
//! of `O(inc_j |F''|)` (truncation) plus `O(eps |F| / inc_j)` (round-off of the residuals'
//! difference). The two balance at `inc_j ~ sqrt(eps)` times the unknown's scale, which
//! leaves about half the digits of the residual in each entry: plenty for Newton's iteration,
//! which converges with a matrix that is a few per cent off (Brenan, Campbell & Petzold 1989,
//! 5.2.2; IDA's `idaLsDenseDQJac` uses the same order).
//!
//! The scale of unknown `j` is `max(|y_j|, typ_j)`: a relative increment where `y_j` is away
//! from zero, and `typ_j`, a typical magnitude of the unknown
//! ([`with_typical_magnitude`](DifferenceQuotients::with_typical_magnitude) for every unknown,
//! [`with_typical`](DifferenceQuotients::with_typical) one per unknown, as the `typx` of Dennis &
//! Schnabel; no default), for an unknown at or through zero. IDA uses `max(sqrt(eps) max(|y_j|, |h y'_j|),
//! 1 / w_j)` with `w_j` its error weight (`1 / w_j = rtol |y_j| + atol_j`) and `h` the step;
//! the integrators pass neither to the model, so:
//!
//! * `typ_j` stands for `1 / w_j`. A magnitude 1 suits unknowns of order 1 (voltages, angles,
//!   positions in metres). An unknown that is small next to 1, or a residual that is very
//!   curved in it, needs it smaller: Robertson's `y2` (of order `1e-5`, `3e7 y2^2` in its
//!   residual) with magnitude 1 perturbs `y2` by `1.5e-8`, an error of `0.45` in an entry of
//!   `1e4` that the iteration matrix's near-singular direction at large steps (`c ~ 1e-10`)
//!   turns into a Newton contraction near 1: 38 444 steps for 452 with the exact matrix at
//!   `rtol = 1e-4`, and no correct digit. [`with_absolute_tolerance`](DifferenceQuotients::with_absolute_tolerance)
//!   sets IDA's floor from the `atol` given to the integrator;
//!   [`with_typical`](DifferenceQuotients::with_typical) sets the magnitudes directly;
//! * there is no `|h y'_j|` term. `|y'_j| / c` would stand for it (`c ~ alpha / h` in the BDF
//!   and Radau), but the increment would then change with `c`, and the library reads `dF/dy'`
//!   as the difference of two matrices at one point and two values of `c` (Radau at `c = 0`
//!   and `c = 1` when the DAE has no [`mass_matrix`](ImplicitDae::mass_matrix), consistent
//!   initialisation, [`Stabilised`](crate::stabilised::Stabilised)). With the same increment at
//!   every `c` a row without `y'` (an algebraic equation) has the same quotient in both, so
//!   their difference is exactly zero there; with increments that differ it would carry
//!   `sqrt(eps) |dF/dy|` of noise, which Radau multiplies by `gamma / h`. What the term guards
//!   against, `y'_j + c inc_j` rounding away the perturbation of `y'_j`, costs a relative
//!   `eps |y'_j| / (c inc_j) = sqrt(eps) (|y'_j| / c) / max(|y_j|, typ_j)` of the `c dF/dy'`
//!   part: the change of `y_j` over a step relative to its scale, times `sqrt(eps)`, small in
//!   any step an accurate integration takes.
//!
//! The increment has the sign of `y'_j` (IDA: of `h y'_j`), so the perturbed point lies on
//! the side the solution moves to, which the next steps evaluate anyway; the other side may be
//! outside the residual's domain when the solution leaves a boundary (a `sqrt(y)` as `y` rises
//! from 0). It is rounded to `(y_j + inc_j) - y_j` so the step divided by is the step taken.
//!
//! [`central`](DifferenceQuotients::central) differences, `(F(+) - F(-)) / (2 inc_j)` with
//! `inc_j = eps^(1/3)` times the scale, leave about two thirds of the residual's digits
//! (truncation `O(inc^2 F''')`) at twice the residuals: for models whose matrix must be
//! close, e.g. when the DAE is differenced again (index reduction by
//! [`Stabilised`](crate::stabilised::Stabilised) differences the matrix at `c = 0`).
//!
//! # Cost and column grouping
//!
//! Forward differences cost one residual per column group plus one at `(y, y')`; central
//! differences two per group. Without a pattern every column is its own group: `n + 1`
//! residuals per matrix, as IDA's dense difference quotients. When the DAE declares
//! [`iteration_pattern`](ImplicitDae::iteration_pattern), columns that share no row are
//! perturbed together (Curtis, Powell & Reid 1974): one residual then yields every column of
//! the group, each row read off by the one column of the group it belongs to. The groups are
//! a greedy colouring of the columns' conflict graph, formed on the first call (the better of
//! the natural and the largest-degree-first order); a sparse matrix then costs as many residuals
//! as it has groups, about the largest number of non-zeros in a row. The pattern must hold
//! every entry that can be non-zero: an entry missing from it is read into another column
//! of its group. A pattern with an entry out of range is ignored (every column its own
//! group; [`prepare`](DifferenceQuotients::prepare) says how many groups are in use).
//!
//! # Non-finite residuals
//!
//! A residual that is not finite at a perturbed point makes the entries of its rows in the
//! perturbed columns non-finite (they are written, never skipped or replaced): the integrators'
//! linear solvers refuse such a matrix ([`FactorError::NonFinite`](crate::linear_solver::FactorError::NonFinite)).
//! The BDF retries the step smaller, with a matrix formed at the new predicted point, which is
//! usually enough (a [`BdfError::NonFiniteMatrix`](crate::bdf::BdfError::NonFiniteMatrix)
//! naming the entry's equation and unknown when it is not). Radau forms its matrix at the
//! step's start, which a smaller step does not move: it stops at once with
//! [`RadauError::NonFiniteMatrix`](crate::radau::RadauError::NonFiniteMatrix).
//!
//! # The mass matrix
//!
//! There is no difference quotient of [`mass_matrix`](ImplicitDae::mass_matrix) alone: a DAE
//! that leaves it at its default is asked by Radau for `iteration_matrix` at `c = 0` and
//! `c = 1`, which this type serves (`dF/dy'` as their difference). A DAE that knows `dF/dy'`
//! exactly (often a constant or a few entries) may form `dF/dy` here at `c = 0` and add
//! `c dF/dy'` itself: the entries are added with [`MatrixSink::add`], so the two parts may
//! come in either order.
//!
//! # Work vectors and threads
//!
//! `iteration_matrix` takes `&self`; the residual vectors and the perturbed point live in a
//! [`Mutex`] inside the value, sized on the first call, so later calls allocate nothing. A DAE
//! holding a `DifferenceQuotients` stays `Send` and `Sync` (the integrators require neither; a
//! caller may share a DAE between threads). A call that finds the vectors in use by another
//! thread (or by a residual that forms a matrix itself) does not wait: it works in vectors of
//! its own, allocated for that call. Use one `DifferenceQuotients` per DAE: its column groups
//! are those of the first DAE it is called with (a DAE of another dimension is served, with
//! every column its own group and vectors allocated per call).

use std::sync::{Mutex, OnceLock, TryLockError};

use crate::error::InvalidOption;
use crate::sink::MatrixSink;
use crate::ImplicitDae;

/// The difference formula of [`DifferenceQuotients`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Formula {
    /// `(F(y + inc) - F(y)) / inc`, `inc = sqrt(eps)` times the scale: one residual per column
    /// group (and one at the point), about half the residual's digits.
    Forward,
    /// `(F(y + inc) - F(y - inc)) / (2 inc)`, `inc = eps^(1/3)` times the scale: two residuals
    /// per column group, about two thirds of the residual's digits.
    Central,
}

/// What [`DifferenceQuotients::prepare`] found for a DAE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Prepared {
    /// Columns perturbed together in one residual: the number of groups.
    pub groups: usize,
    /// Residual evaluations per [`iteration_matrix`](DifferenceQuotients::iteration_matrix)
    /// call: `groups + 1` forward, `2 groups` central.
    pub residuals_per_matrix: usize,
    /// Whether the DAE's [`iteration_pattern`](ImplicitDae::iteration_pattern) is in use (it
    /// declares one, it is in range and grouping is not turned off).
    pub pattern: bool,
}

/// The iteration matrix `dF/dy + c dF/dy'` of an [`ImplicitDae`] by difference quotients of
/// its residual; see the [module documentation](self) for the increment, the cost and the
/// column grouping.
pub struct DifferenceQuotients {
    formula: Formula,
    /// Typical magnitude of each unknown (`None`: `uniform` for every unknown).
    typical: Option<Vec<f64>>,
    /// The typical magnitude of every unknown when `typical` is `None`.
    uniform: f64,
    /// Group columns by the DAE's pattern when it declares one.
    grouping: bool,
    /// The columns' rows and groups, formed on the first call.
    layout: OnceLock<Layout>,
    /// Residuals and the perturbed point, sized on the first call.
    work: Mutex<Work>,
}

/// Which rows each column writes and which columns are perturbed together.
#[derive(Debug, Clone)]
struct Layout {
    n: usize,
    /// The pattern by columns (compressed: rows of column `j` are
    /// `rows[col_start[j]..col_start[j + 1]]`), or `None`: every row, written when non-zero.
    pattern: Option<(Vec<usize>, Vec<usize>)>,
    /// Columns of group `g`: `members[group_start[g]..group_start[g + 1]]`.
    group_start: Vec<usize>,
    members: Vec<usize>,
}

/// The vectors of one evaluation.
#[derive(Debug, Default)]
struct Work {
    /// `F` at `(y, y')` (forward) or at the point perturbed down (central).
    base: Vec<f64>,
    /// `F` at the point perturbed up.
    up: Vec<f64>,
    y: Vec<f64>,
    yp: Vec<f64>,
    /// The increment of each unknown (as rounded; central: the whole span `2 inc`).
    inc: Vec<f64>,
}

impl Work {
    fn size(&mut self, n: usize) {
        if self.y.len() != n {
            for v in [
                &mut self.base,
                &mut self.up,
                &mut self.y,
                &mut self.yp,
                &mut self.inc,
            ] {
                v.clear();
                v.resize(n, 0.0);
            }
        }
    }
}

impl Clone for DifferenceQuotients {
    /// The options and the column groups; work vectors of its own.
    fn clone(&self) -> Self {
        let layout = OnceLock::new();
        if let Some(l) = self.layout.get() {
            let _ = layout.set(l.clone());
        }
        Self {
            formula: self.formula,
            typical: self.typical.clone(),
            uniform: self.uniform,
            grouping: self.grouping,
            layout,
            work: Mutex::new(Work::default()),
        }
    }
}

impl std::fmt::Debug for DifferenceQuotients {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DifferenceQuotients")
            .field("formula", &self.formula)
            .field("typical", &self.typical)
            .field("uniform", &self.uniform)
            .field("grouping", &self.grouping)
            .field("groups", &self.layout.get().map(Layout::groups))
            .finish_non_exhaustive()
    }
}

impl DifferenceQuotients {
    /// Forward differences with the typical magnitude `magnitude` for every unknown, columns
    /// grouped by the DAE's [`iteration_pattern`](ImplicitDae::iteration_pattern) when it
    /// declares one. For unknowns of that order (or larger); an unknown much smaller than it
    /// (Robertson's `y2`, of order `1e-5`, with `magnitude = 1`) gets increments too large for
    /// its rows: give the integrator's absolute tolerances instead
    /// ([`with_absolute_tolerance`](Self::with_absolute_tolerance)) or one magnitude per
    /// unknown ([`with_typical`](Self::with_typical)). There is no default: no one magnitude
    /// suits every model.
    ///
    /// # Errors
    /// [`InvalidOption`] named `typical` when `magnitude` is not positive and finite.
    pub fn with_typical_magnitude(magnitude: f64) -> Result<Self, InvalidOption> {
        if !(magnitude.is_finite() && magnitude > 0.0) {
            return Err(InvalidOption::new(
                "typical",
                magnitude,
                "positive and finite",
            ));
        }
        Ok(Self {
            formula: Formula::Forward,
            typical: None,
            uniform: magnitude,
            grouping: true,
            layout: OnceLock::new(),
            work: Mutex::new(Work::default()),
        })
    }

    /// Central differences instead of forward ones (twice the residuals, more digits).
    #[must_use]
    pub fn central(mut self) -> Self {
        self.formula = Formula::Central;
        self
    }

    /// The difference formula.
    pub fn formula(&self) -> Formula {
        self.formula
    }

    /// Every column its own group even when the DAE declares a pattern (IDA's dense
    /// difference quotients; entries are still written only where the pattern has them).
    #[must_use]
    pub fn ungrouped(mut self) -> Self {
        self.grouping = false;
        self
    }

    /// The typical magnitude of each unknown, the smallest scale its increment is taken
    /// relative to (see the module documentation); one per unknown.
    ///
    /// Forward differences, columns grouped as in
    /// [`with_typical_magnitude`](Self::with_typical_magnitude).
    ///
    /// # Errors
    /// [`InvalidOption`] named `typical` when a magnitude is not positive and finite.
    pub fn with_typical(typical: Vec<f64>) -> Result<Self, InvalidOption> {
        if let Some(&bad) = typical.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(InvalidOption::new("typical", bad, "positive and finite"));
        }
        let mut dq = Self::with_typical_magnitude(1.0)?;
        dq.typical = Some(typical);
        Ok(dq)
    }

    /// IDA's floor of the increment: the absolute tolerances `atol` given to the integrator
    /// (one per unknown). Forward differences then perturb `y_j` by at least `atol_j`, as
    /// IDA's `1 / w_j = rtol |y_j| + atol_j` does where `y_j` is small: the typical magnitude
    /// of unknown `j` is `atol_j / sqrt(eps)` (central differences: at least
    /// `eps^(-1/6) atol_j`, about `400 atol_j`). For a problem ported from IDA with its
    /// tolerances, and for unknowns that are small next to 1 (Robertson's `y2`, of order
    /// `1e-5`, resolved to `atol = 1e-14`).
    ///
    /// # Errors
    /// [`InvalidOption`] named `atol` when a tolerance is not positive and finite.
    pub fn with_absolute_tolerance(atol: &[f64]) -> Result<Self, InvalidOption> {
        if let Some(&bad) = atol.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(InvalidOption::new("atol", bad, "positive and finite"));
        }
        let root = f64::EPSILON.sqrt();
        Self::with_typical(atol.iter().map(|a| a / root).collect())
    }

    /// Form the column groups for `dae` now (the first
    /// [`iteration_matrix`](Self::iteration_matrix) call does it otherwise) and say what they
    /// cost.
    ///
    /// # Errors
    /// [`InvalidOption`] named `typical` when typical magnitudes were given and their number
    /// is not the DAE's dimension (an unknown without one would use 1), or named `dimension`
    /// when the groups were formed for a DAE of another dimension.
    pub fn prepare<D: ImplicitDae + ?Sized>(&self, dae: &D) -> Result<Prepared, InvalidOption> {
        let n = dae.dimension();
        if let Some(typ) = &self.typical {
            if typ.len() != n {
                return Err(InvalidOption::new(
                    "typical",
                    typ.len() as f64,
                    "one magnitude per unknown of the DAE",
                ));
            }
        }
        let layout = self.layout(dae);
        if layout.n != n {
            return Err(InvalidOption::new(
                "dimension",
                n as f64,
                "the dimension of the DAE the column groups were formed for",
            ));
        }
        let groups = layout.groups();
        Ok(Prepared {
            groups,
            residuals_per_matrix: match self.formula {
                Formula::Forward => groups + 1,
                Formula::Central => 2 * groups,
            },
            pattern: layout.pattern.is_some(),
        })
    }

    fn layout<D: ImplicitDae + ?Sized>(&self, dae: &D) -> &Layout {
        self.layout.get_or_init(|| {
            let n = dae.dimension();
            let pattern = if self.grouping {
                dae.iteration_pattern()
            } else {
                None
            };
            Layout::new(n, pattern.as_deref(), self.grouping)
        })
    }

    /// Add `dF/dy + c dF/dy'` of `dae` at `(t, y, y')` into `out` by difference quotients of
    /// [`ImplicitDae::residual`]: every entry when the DAE declares no pattern (written when
    /// not zero), the pattern's entries when it does. `out` is zeroed by the caller, as in
    /// [`ImplicitDae::iteration_matrix`], from which this is meant to be called.
    pub fn iteration_matrix<D: ImplicitDae + ?Sized, S: MatrixSink + ?Sized>(
        &self,
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        self.evaluate(dae, t, y, yp, c, None, out);
    }

    /// The residual `F(t, y, y')` into `residual` and the matrix as
    /// [`iteration_matrix`](Self::iteration_matrix), for
    /// [`ImplicitDae::residual_and_iteration_matrix`]: forward differences need that residual
    /// anyway, so the pair costs one residual less than the two calls.
    #[allow(clippy::too_many_arguments)] // the trait method's arguments and the DAE
    pub fn residual_and_iteration_matrix<D: ImplicitDae + ?Sized, S: MatrixSink + ?Sized>(
        &self,
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: &mut [f64],
        out: &mut S,
    ) {
        self.evaluate(dae, t, y, yp, c, Some(residual), out);
    }

    #[allow(clippy::too_many_arguments)]
    fn evaluate<D: ImplicitDae + ?Sized, S: MatrixSink + ?Sized>(
        &self,
        dae: &D,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        residual: Option<&mut [f64]>,
        out: &mut S,
    ) {
        let n = dae.dimension();
        let shared = self.layout(dae);
        // A DAE other than the one the groups were formed for: every column its own group.
        let own_layout;
        let layout = if shared.n == n {
            shared
        } else {
            own_layout = Layout::new(n, None, false);
            &own_layout
        };
        let mut own_work;
        let mut guard;
        let work: &mut Work = match self.work.try_lock() {
            Ok(g) => {
                guard = g;
                &mut guard
            }
            // A panic in an earlier call's residual: every vector is rewritten before use.
            Err(TryLockError::Poisoned(p)) => {
                guard = p.into_inner();
                &mut guard
            }
            // In use by another thread or by this call's own residual: vectors of its own.
            Err(TryLockError::WouldBlock) => {
                own_work = Work::default();
                &mut own_work
            }
        };
        work.size(n);
        let typical = self.typical.as_deref().unwrap_or(&[]);
        self.increments(typical, y, yp, &mut work.inc);
        work.y.copy_from_slice(y);
        work.yp.copy_from_slice(yp);
        let forward = self.formula == Formula::Forward;
        match residual {
            Some(r) => {
                dae.residual(t, y, yp, r);
                if forward {
                    work.base.copy_from_slice(r);
                }
            }
            None if forward => dae.residual(t, y, yp, &mut work.base),
            None => {}
        }
        let Work {
            base,
            up,
            y: yw,
            yp: ypw,
            inc,
        } = work;
        for g in 0..layout.groups() {
            let members = layout.group(g);
            if forward {
                for &j in members {
                    let h = (y[j] + inc[j]) - y[j];
                    inc[j] = h;
                    yw[j] = y[j] + h;
                    ypw[j] = yp[j] + c * h;
                }
                dae.residual(t, yw, ypw, up);
            } else {
                for &j in members {
                    let h = inc[j];
                    yw[j] = y[j] + h;
                    ypw[j] = yp[j] + c * h;
                }
                dae.residual(t, yw, ypw, up);
                for &j in members {
                    let h = inc[j];
                    yw[j] = y[j] - h;
                    ypw[j] = yp[j] - c * h;
                    // The span as rounded: `(y + h) - (y - h)`.
                    inc[j] = (y[j] + h) - yw[j];
                }
                dae.residual(t, yw, ypw, base);
            }
            for &j in members {
                yw[j] = y[j];
                ypw[j] = yp[j];
                let inv = 1.0 / inc[j];
                match layout.rows(j) {
                    Some(rows) => {
                        for &i in rows {
                            out.add(i, j, (up[i] - base[i]) * inv);
                        }
                    }
                    None => {
                        for i in 0..n {
                            let d = (up[i] - base[i]) * inv;
                            // NaN is written: a non-finite residual must reach the matrix.
                            if d != 0.0 {
                                out.add(i, j, d);
                            }
                        }
                    }
                }
            }
        }
    }

    /// The increment of each unknown, signed and not yet rounded (module documentation).
    fn increments(&self, typical: &[f64], y: &[f64], yp: &[f64], inc: &mut [f64]) {
        let factor = match self.formula {
            Formula::Forward => f64::EPSILON.sqrt(),
            Formula::Central => f64::EPSILON.cbrt(),
        };
        for j in 0..inc.len() {
            let typ = typical.get(j).copied().unwrap_or(self.uniform);
            let h = factor * y[j].abs().max(typ);
            inc[j] = if yp[j] < 0.0 { -h } else { h };
        }
    }
}

impl Layout {
    /// The rows of each column and the column groups for `n` unknowns: the pattern's when
    /// given and in range, grouped when `grouping`; else every column alone and dense.
    fn new(n: usize, pattern: Option<&[(usize, usize)]>, grouping: bool) -> Self {
        let pattern = pattern.filter(|p| p.iter().all(|&(i, j)| i < n && j < n));
        let Some(pattern) = pattern else {
            return Self {
                n,
                pattern: None,
                group_start: (0..=n).collect(),
                members: (0..n).collect(),
            };
        };
        let (col_start, rows) = compress(n, pattern.iter().map(|&(i, j)| (j, i)));
        let (group_start, members) = if grouping {
            let (row_start, cols) = compress(n, pattern.iter().copied());
            let natural: Vec<usize> = (0..n).collect();
            let by_natural = colour(&natural, &col_start, &rows, &row_start, &cols);
            let degree = degrees(&col_start, &rows, &row_start, &cols);
            let mut largest_first = natural;
            // Stable: equal degrees keep the natural order.
            largest_first.sort_by_key(|&j| std::cmp::Reverse(degree[j]));
            let by_degree = colour(&largest_first, &col_start, &rows, &row_start, &cols);
            let best = if by_degree.0 < by_natural.0 {
                by_degree
            } else {
                by_natural
            };
            groups_of(n, best)
        } else {
            ((0..=n).collect(), (0..n).collect())
        };
        Self {
            n,
            pattern: Some((col_start, rows)),
            group_start,
            members,
        }
    }

    fn groups(&self) -> usize {
        self.group_start.len() - 1
    }

    fn group(&self, g: usize) -> &[usize] {
        &self.members[self.group_start[g]..self.group_start[g + 1]]
    }

    fn rows(&self, j: usize) -> Option<&[usize]> {
        self.pattern
            .as_ref()
            .map(|(start, rows)| &rows[start[j]..start[j + 1]])
    }
}

/// `(key, value)` pairs with keys below `n` as compressed lists: the values of key `k` are
/// `values[start[k]..start[k + 1]]`, sorted and without repeats.
fn compress(
    n: usize,
    pairs: impl Iterator<Item = (usize, usize)> + Clone,
) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; n + 1];
    for (k, _) in pairs.clone() {
        start[k + 1] += 1;
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut values = vec![0usize; start[n]];
    let mut next = start.clone();
    for (k, v) in pairs {
        values[next[k]] = v;
        next[k] += 1;
    }
    // Sort and drop repeats within each key, then close the gaps.
    let mut write = 0;
    let mut new_start = vec![0usize; n + 1];
    for k in 0..n {
        let list = &mut values[start[k]..start[k + 1]];
        list.sort_unstable();
        let mut last = None;
        for idx in start[k]..start[k + 1] {
            let v = values[idx];
            if last != Some(v) {
                values[write] = v;
                write += 1;
                last = Some(v);
            }
        }
        new_start[k + 1] = write;
    }
    values.truncate(write);
    (new_start, values)
}

/// The number of other columns each column shares a row with.
fn degrees(col_start: &[usize], rows: &[usize], row_start: &[usize], cols: &[usize]) -> Vec<usize> {
    let n = col_start.len() - 1;
    let mut seen = vec![usize::MAX; n];
    (0..n)
        .map(|j| {
            let mut d = 0;
            for &i in &rows[col_start[j]..col_start[j + 1]] {
                for &k in &cols[row_start[i]..row_start[i + 1]] {
                    if k != j && seen[k] != j {
                        seen[k] = j;
                        d += 1;
                    }
                }
            }
            d
        })
        .collect()
}

/// Greedy colouring in `order`: each column takes the smallest group that holds no column
/// sharing a row with it. The number of groups and each column's group.
fn colour(
    order: &[usize],
    col_start: &[usize],
    rows: &[usize],
    row_start: &[usize],
    cols: &[usize],
) -> (usize, Vec<usize>) {
    let n = col_start.len() - 1;
    let mut group = vec![usize::MAX; n];
    // `taken[g] == j`: group `g` holds a neighbour of column `j`.
    let mut taken = vec![usize::MAX; n + 1];
    let mut count = 0;
    for &j in order {
        for &i in &rows[col_start[j]..col_start[j + 1]] {
            for &k in &cols[row_start[i]..row_start[i + 1]] {
                if group[k] != usize::MAX {
                    taken[group[k]] = j;
                }
            }
        }
        let g = (0..).find(|&g| taken[g] != j).unwrap_or(0);
        group[j] = g;
        count = count.max(g + 1);
    }
    (count, group)
}

/// Compressed member lists from each column's group.
fn groups_of(n: usize, (count, group): (usize, Vec<usize>)) -> (Vec<usize>, Vec<usize>) {
    compress(count, (0..n).map(|j| (group[j], j)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tridiagonal system: three groups whatever `n`.
    struct Tridiagonal(usize);

    impl ImplicitDae for Tridiagonal {
        fn dimension(&self) -> usize {
            self.0
        }
        fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
            let n = self.0;
            for i in 0..n {
                let left = if i > 0 { y[i - 1] } else { 0.0 };
                let right = if i + 1 < n { y[i + 1] } else { 0.0 };
                out[i] = yp[i] + y[i] * y[i] - left * right.sin();
            }
        }
        fn iteration_matrix<S: MatrixSink + ?Sized>(
            &self,
            _: f64,
            _: &[f64],
            _: &[f64],
            _: f64,
            _: &mut S,
        ) {
        }
        fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
            let n = self.0;
            Some(
                (0..n)
                    .flat_map(|i| [i.saturating_sub(1), i, (i + 1).min(n - 1)].map(|j| (i, j)))
                    .collect(),
            )
        }
    }

    #[test]
    fn a_tridiagonal_pattern_takes_three_groups_and_dense_ones_match() {
        let dae = Tridiagonal(12);
        let grouped = DifferenceQuotients::with_typical_magnitude(1.0).expect("positive");
        let p = grouped.prepare(&dae).expect("prepared");
        assert_eq!((p.groups, p.residuals_per_matrix, p.pattern), (3, 4, true));
        let plain = DifferenceQuotients::with_typical_magnitude(1.0)
            .expect("positive")
            .ungrouped();
        assert_eq!(plain.prepare(&dae).expect("prepared").groups, 12);
        let y: Vec<f64> = (0..12).map(|i| 0.3 + 0.1 * i as f64).collect();
        let yp: Vec<f64> = (0..12).map(|i| (-1.0f64).powi(i) * 0.5).collect();
        let (mut a, mut b) = (
            nalgebra::DMatrix::zeros(12, 12),
            nalgebra::DMatrix::zeros(12, 12),
        );
        grouped.iteration_matrix(&dae, 0.0, &y, &yp, 7.0, &mut a);
        plain.iteration_matrix(&dae, 0.0, &y, &yp, 7.0, &mut b);
        assert_eq!(a, b);
        assert!((a[(3, 3)] - (7.0 + 2.0 * y[3])).abs() < 1e-6);
    }

    #[test]
    fn an_out_of_range_pattern_is_ignored_and_typical_magnitudes_are_checked() {
        struct Bad;
        impl ImplicitDae for Bad {
            fn dimension(&self) -> usize {
                2
            }
            fn residual(&self, _: f64, y: &[f64], _: &[f64], out: &mut [f64]) {
                out.copy_from_slice(y);
            }
            fn iteration_matrix<S: MatrixSink + ?Sized>(
                &self,
                _: f64,
                _: &[f64],
                _: &[f64],
                _: f64,
                _: &mut S,
            ) {
            }
            fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
                Some(vec![(0, 0), (1, 5)])
            }
        }
        let p = DifferenceQuotients::with_typical_magnitude(1.0)
            .expect("positive")
            .prepare(&Bad)
            .expect("prepared");
        assert_eq!((p.groups, p.pattern), (2, false));
        assert!(DifferenceQuotients::with_typical(vec![1.0, 0.0]).is_err());
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = DifferenceQuotients::with_typical_magnitude(bad).map(|_| ());
            assert_eq!(e.map_err(|e| e.name), Err("typical"), "{bad}");
            let e = DifferenceQuotients::with_absolute_tolerance(&[1e-6, bad]).map(|_| ());
            assert_eq!(e.map_err(|e| e.name), Err("atol"), "{bad}");
        }
        let three = DifferenceQuotients::with_typical(vec![1.0; 3]).expect("valid");
        assert_eq!(three.prepare(&Bad).map_err(|e| e.name), Err("typical"));
    }

    #[test]
    fn the_increment_takes_the_sign_of_y_prime_and_not_c() {
        let dq = DifferenceQuotients::with_typical(vec![1.0, 1.0, 1e-6]).expect("valid");
        let mut inc = [0.0; 3];
        dq.increments(
            &[1.0, 1.0, 1e-6],
            &[2.0, 0.0, 0.0],
            &[0.0, -50.0, 1e-3],
            &mut inc,
        );
        let s = f64::EPSILON.sqrt();
        assert_eq!(inc, [2.0 * s, -s, 1e-6 * s]);
    }
}
