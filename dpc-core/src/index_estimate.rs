//! The index of each unknown of a DAE at a point, estimated from its iteration matrix.
//!
//! The integrators need to know which unknowns have index 2 or 3 (`Options::index` of
//! [`crate::bdf`] and [`crate::radau`]): the BDF leaves them out of its error test or scales
//! their errors, Radau scales them by the step. A DAE declared without that option fails in
//! ways that do not point at it (repeated error-test or Newton failures near the start, or
//! too many steps). [`unknown_indices`] reads the index of every unknown off the iteration
//! matrix `G(c) = dF/dy + c dF/dy'` at one point, as the integrators form it: the row of
//! `G(c)^-1` belonging to an unknown of index `m` grows like `c^(m-1)` as `c` grows (an unknown
//! whose derivative the equations determine shrinks like `1/c`; an algebraic unknown of index
//! 1 stays bounded; in a Hessenberg index-2 system the multiplier's row grows like `c`, in an
//! index-3 one the velocities' rows like `c` and the multiplier's like `c^2`). The exponent is
//! measured over decades of `c` above the scale `|dF/dy| / |dF/dy'|` of the equilibrated
//! matrices, as far as round-off allows, and taken where the last two decades agree on whole
//! numbers; where they do not, no index is reported (`Inconclusive`). `G(c)^-1` comes from a
//! singular value decomposition, so a pencil that is singular at the point (no regular DAE
//! there) is reported, not inverted.
//!
//! The reading is local: at a point where an entry that carries an unknown's coupling is zero
//! (a pendulum's rod exactly horizontal with zero tension leaves the vertical velocity free
//! there) that unknown may read one index lower; the two points near the given one, at which
//! the largest reading is taken, catch most such coincidences but not every one (the
//! horizontal pendulum still reads `v` as index 1). Estimate at a generic point of the motion.
//!
//! The bound is the index the integrators' options mean (DASSL's and IDA's convention): the
//! positions of a constrained mechanism have index 1 (they appear differentiated and their
//! rows of `G^-1` stay bounded), velocities 2, multipliers 3, as in the Test Set's problems.

use nalgebra::DMatrix;

use crate::ImplicitDae;

/// Why [`unknown_indices`] cannot estimate the index at the given point.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IndexEstimateError {
    /// `y` or `y'` does not have the DAE's dimension.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// `"y"` or `"yp"`.
        what: &'static str,
        /// The DAE's dimension.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// The iteration matrix has a NaN or infinite entry at the point.
    #[error(
        "the iteration matrix has a non-finite entry in the row of {equation}, column of {unknown}"
    )]
    NonFinite {
        /// Name of the row's equation.
        equation: String,
        /// Name of the column's unknown.
        unknown: String,
    },
    /// The rows of `G(c)^-1` did not settle on whole powers of `c` before `G(c)` became too
    /// ill-conditioned to invert (a DAE of index above 3, or one whose scales span more than
    /// round-off leaves room for): no index is reported rather than a guessed one.
    #[error(
        "the index of the unknowns at t = {t} could not be read off the iteration matrix: the \
         powers of c its inverse grows with did not settle before round-off"
    )]
    Inconclusive {
        /// The time of the point.
        t: f64,
    },
    /// `dF/dy + c dF/dy'` is singular for every `c` tried: the DAE is not regular at the point
    /// (an equation missing, or two that say the same), and no index is defined there.
    #[error(
        "the iteration matrix dF/dy + c dF/dy' is singular at t = {t} for every c tried \
         (smallest singular value {sigma_ratio:.1e} of the largest): the DAE is not regular there"
    )]
    SingularPencil {
        /// The time of the point.
        t: f64,
        /// The smallest singular value relative to the largest, at the larger `c`.
        sigma_ratio: f64,
    },
}

/// Decades of `c` above the scale `|dF/dy| / |dF/dy'|` (of the equilibrated matrices) tried.
const MAX_DECADES: usize = 14;

/// `G(c)` is inverted only while its smallest singular value is at least this fraction of its
/// largest (the inverse's rows then carry several correct digits; an index-3 pencil's
/// condition number grows like `c^3`, so this bounds the decades an index-3 DAE can be read
/// over).
const MIN_SINGULAR_RATIO: f64 = 1e-12;

/// Two consecutive powers of a row agree, and lie on a whole number, to within this.
const SETTLED: f64 = 0.1;

/// Scale the rows and columns of `F_y` and `F_y'` alike by powers of two (exact) so that the
/// largest entry of `|F_y| + |F_y'|` in every row and column is near 1: the scaling does not
/// change the power of `c` any row of `G(c)^-1` grows with, but it keeps `G(c)` as well
/// conditioned as the DAE allows, so more decades of `c` can be read before round-off.
fn equilibrate(dfdy: &mut DMatrix<f64>, dfdyp: &mut DMatrix<f64>) {
    let n = dfdy.nrows();
    let power_of_two = |m: f64| {
        if m > 0.0 && m.is_finite() {
            2f64.powi(-(m.log2().round() as i32))
        } else {
            1.0
        }
    };
    for _ in 0..3 {
        // Rows, then columns: the transposes make one loop serve both.
        for transpose in [false, true] {
            if transpose {
                dfdy.transpose_mut();
                dfdyp.transpose_mut();
            }
            for i in 0..n {
                let m = (0..n)
                    .map(|j| dfdy[(i, j)].abs() + dfdyp[(i, j)].abs())
                    .fold(0.0, f64::max);
                let f = power_of_two(m);
                dfdy.row_mut(i).scale_mut(f);
                dfdyp.row_mut(i).scale_mut(f);
            }
            if transpose {
                dfdy.transpose_mut();
                dfdyp.transpose_mut();
            }
        }
    }
}

/// The index of every unknown of `dae` at `(t, y, y')`, in the sense of the integrators'
/// `Options::index`: 1 for an unknown whose derivative is determined by the equations or an
/// algebraic unknown of index 1, 2 or 3 (or higher) for the others. See the module
/// documentation for the method. The index is read at the point and at two points near it
/// (see `Stabilised::detect`), and the largest is taken: an entry that vanishes at the point by
/// coincidence does not hide an index.
///
/// Costs two evaluations of the iteration matrix and singular value decompositions of a dense
/// `n x n` matrix per decade of `c` at each of the three points (`n^2` memory, `n^3` time):
/// meant for set-up and diagnostics of DAEs of up to a few hundred unknowns, not for every
/// step (the integrators' failure diagnosis stops at `DIAGNOSIS_MAX` = 500 unknowns).
///
/// ```
/// use dpc::core::index_estimate::unknown_indices;
/// use dpc::core::{ImplicitDae, MatrixSink};
///
/// /// The Cartesian pendulum `x' = u, y' = v, u' = -lambda x, v' = -lambda y - 1,
/// /// 0 = x^2 + y^2 - 1`.
/// struct Pendulum;
/// impl ImplicitDae for Pendulum {
///     fn dimension(&self) -> usize {
///         5
///     }
///     fn residual(&self, _t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
///         out[0] = yp[0] - y[2];
///         out[1] = yp[1] - y[3];
///         out[2] = yp[2] + y[4] * y[0];
///         out[3] = yp[3] + y[4] * y[1] + 1.0;
///         out[4] = y[0] * y[0] + y[1] * y[1] - 1.0;
///     }
///     fn iteration_matrix<S: MatrixSink + ?Sized>(
///         &self,
///         _t: f64,
///         y: &[f64],
///         _yp: &[f64],
///         c: f64,
///         m: &mut S,
///     ) {
///         for i in 0..4 {
///             m.set(i, i, c);
///         }
///         m.set(0, 2, -1.0);
///         m.set(1, 3, -1.0);
///         m.set(2, 0, y[4]);
///         m.set(2, 4, y[0]);
///         m.set(3, 1, y[4]);
///         m.set(3, 4, y[1]);
///         m.set(4, 0, 2.0 * y[0]);
///         m.set(4, 1, 2.0 * y[1]);
///     }
/// }
///
/// // At rest at the angle 0.6 from the vertical, with the consistent multiplier and
/// // accelerations.
/// let (s, c) = 0.6f64.sin_cos();
/// let lambda = c;
/// let y = [s, -c, 0.0, 0.0, lambda];
/// let yp = [0.0, 0.0, -lambda * s, lambda * c - 1.0, 0.0];
/// assert_eq!(unknown_indices(&Pendulum, 0.0, &y, &yp).unwrap(), [1, 1, 2, 2, 3]);
/// ```
///
/// # Errors
/// [`IndexEstimateError::DimensionMismatch`] for `y` or `y'` of the wrong length,
/// [`IndexEstimateError::NonFinite`] for a NaN or infinite matrix entry,
/// [`IndexEstimateError::SingularPencil`] when the DAE is not regular at the point,
/// [`IndexEstimateError::Inconclusive`] when the powers do not settle at the point or near it.
pub fn unknown_indices<D: ImplicitDae + ?Sized>(
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
) -> Result<Vec<u8>, IndexEstimateError> {
    let n = dae.dimension();
    for (what, found) in [("y", y.len()), ("yp", yp.len())] {
        if found != n {
            return Err(IndexEstimateError::DimensionMismatch {
                what,
                expected: n,
                found,
            });
        }
    }
    // The point's own reading, unless it is inconclusive (an entry that is small there by
    // coincidence delays the leading power beyond round-off): then the points near it decide.
    let mut indices = match indices_at(dae, t, y, yp) {
        Ok(indices) => Some(indices),
        Err(IndexEstimateError::Inconclusive { .. }) => None,
        Err(e) => return Err(e),
    };
    // Entries that vanish at the point by coincidence (the pendulum's horizontal velocity is
    // free where it hangs straight down) hide an unknown's index there: the largest over the
    // point and two points near it, as `Stabilised::detect` reads its structure.
    crate::numeric::visit_nearby_points(t, y, yp, |t_moved, y_moved, yp_moved| {
        match indices_at(dae, t_moved, y_moved, yp_moved) {
            Ok(near) => {
                match &mut indices {
                    Some(indices) => {
                        for (m, k) in indices.iter_mut().zip(near) {
                            *m = (*m).max(k);
                        }
                    }
                    None => indices = Some(near),
                }
                true
            }
            Err(_) => false,
        }
    });
    indices.ok_or(IndexEstimateError::Inconclusive { t })
}

/// The unknowns [`unknown_indices`] finds of index 2 or higher at `(t, y, y')`, by name
/// ([`ImplicitDae::unknown_name`]) with their index; empty when every unknown has index 1 or
/// the estimate is not available there (an error of [`unknown_indices`]). When a step fails on
/// a DAE declared with every unknown of index 1, the integrators read the estimate at the
/// failure point and at the integration's start: unknowns of higher index at both are named
/// as the likely cause (`BdfError::UndeclaredIndex`, `RadauError::UndeclaredIndex`), a higher
/// reading at the failure point only is a nearly singular point of the DAE
/// (`BdfError::SingularPoint`, `RadauError::SingularPoint`).
pub fn higher_index_unknowns<D: ImplicitDae + ?Sized>(
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
) -> Vec<(String, u8)> {
    unknown_indices(dae, t, y, yp)
        .map(|estimate| {
            estimate
                .iter()
                .enumerate()
                .filter(|&(_, &m)| m > 1)
                .map(|(i, &m)| (dae.unknown_name(i), m))
                .collect()
        })
        .unwrap_or_default()
}

/// The point an integration started from (at `new` or `reinit`), kept so that a failure can
/// be compared with it ([`diagnose_failure`]): allocated once with the integrator, copied at
/// a restart, read only on an error path.
#[derive(Debug, Clone)]
pub(crate) struct StartPoint {
    t: f64,
    y: Vec<f64>,
    yp: Vec<f64>,
}

impl StartPoint {
    /// The start `(t, y, y')`.
    pub(crate) fn new(t: f64, y: &[f64], yp: &[f64]) -> Self {
        Self {
            t,
            y: y.to_vec(),
            yp: yp.to_vec(),
        }
    }

    /// The start time.
    pub(crate) fn t(&self) -> f64 {
        self.t
    }

    /// The start `(t, y, y')`.
    pub(crate) fn point(&self) -> (f64, &[f64], &[f64]) {
        (self.t, &self.y, &self.yp)
    }

    /// A new start of the same dimension, without allocating.
    pub(crate) fn set(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        self.t = t;
        self.y.copy_from_slice(y);
        self.yp.copy_from_slice(yp);
    }
}

/// How far above its round-off bound an equation's residual at the start must lie for
/// [`inconsistent_start`] to name it: three decades, so that no rounding of the user's
/// arithmetic (the bound allows ten roundings of every term at the largest magnitude) is taken
/// for an inconsistency.
pub(crate) const INCONSISTENT_FACTOR: f64 = 1e3;

/// An equation the start does not satisfy: [`inconsistent_start`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Inconsistency {
    /// The equation's index.
    pub equation: usize,
    /// Its residual `F_i(t0, y0, y0')`.
    pub residual: f64,
    /// Its round-off bound `10 eps (sum_j |dF_i/dy_j| max_k |y_k| + sum_j |dF_i/dy'_j| max_k
    /// |y'_k|)`.
    pub bound: f64,
}

/// The equation with the largest residual at `start` among those more than
/// [`INCONSISTENT_FACTOR`] times above their round-off bound: initial values that do not
/// satisfy the DAE (a position off its constraint, say), which an integrator that fails before
/// its first step names as the cause. The bound takes every unknown at the largest magnitude
/// among the unknowns (and every derivative at the largest among the derivatives): a value
/// that should vanish but was computed as a difference of large terms (the slider crank's
/// slider speed, `1.1e-16`) carries their rounding, not its own (its bound from its own size
/// was `2.5e-31`, and it was named instead of the velocity that was off by `1e-2`). `None`
/// when no residual is so far above its bound, or when a residual or an iteration matrix at
/// the start is not finite (another error names that). Costs a residual and two iteration
/// matrices, read as the entries the DAE writes (memory and time grow with the non-zeros, not
/// with `n^2`, so DAEs of any size are checked); meant for error paths only.
pub(crate) fn inconsistent_start<D: ImplicitDae + ?Sized>(
    dae: &D,
    start: &StartPoint,
) -> Option<Inconsistency> {
    let (t, y, yp) = (start.t, &start.y[..], &start.yp[..]);
    let n = dae.dimension();
    let mut res = vec![0.0; n];
    dae.residual(t, y, yp, &mut res);
    if res.iter().any(|r| !r.is_finite()) {
        return None;
    }
    let j0 = crate::dae::sparse_iteration_matrix(dae, t, y, yp, 0.0).ok()?;
    let j1 = crate::dae::sparse_iteration_matrix(dae, t, y, yp, 1.0).ok()?;
    // Per row `sum_j |dF_i/dy_j|` and `sum_j |dF_i/dy'_j|`, summed over the columns in order
    // (the entries not written add nothing).
    let (mut row_dy, mut row_dyp) = (vec![0.0; n], vec![0.0; n]);
    crate::dae::merge_sorted(
        &j0,
        &j1,
        |e| ((e.0, e.1), e.2),
        |(i, _), a, b| {
            row_dy[i] += a.abs();
            row_dyp[i] += (b - a).abs();
        },
    );
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let (y_max, yp_max) = (largest(y), largest(yp));
    let mut worst: Option<Inconsistency> = None;
    for (i, &r) in res.iter().enumerate() {
        let (dy, dyp) = (row_dy[i], row_dyp[i]);
        let bound = 10.0 * f64::EPSILON * (dy * y_max + dyp * yp_max);
        if r == 0.0 || r.abs() <= INCONSISTENT_FACTOR * bound {
            continue;
        }
        if worst.as_ref().is_none_or(|w| r.abs() > w.residual.abs()) {
            worst = Some(Inconsistency {
                equation: i,
                residual: r,
                bound,
            });
        }
    }
    worst
}

/// The most unknowns [`diagnose_failure`] reads the index of: its estimate decomposes dense
/// `n x n` matrices some forty times (about a second at this size in release mode, 2 MB
/// each); a larger DAE's failure is reported without the diagnosis.
pub(crate) const DIAGNOSIS_MAX: usize = 500;

/// What [`diagnose_failure`] finds for a step failure of a DAE declared with every unknown
/// of index at most 1.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum FailureDiagnosis {
    /// Nothing to add: the failure point reads every unknown as of index 1, or the estimate
    /// is not available there or at the start.
    None,
    /// Unknowns of index 2 or 3 at the failure point that read so at the start too (with
    /// their index at the failure point): a model of higher index than declared.
    Undeclared(Vec<(String, u8)>),
    /// Unknowns that read index 2 or 3 at the failure point while the start read every
    /// unknown as of index 1: the DAE nearly loses regularity there (a near-singular
    /// algebraic part reads like a higher index over the decades of `c` the estimate
    /// samples).
    OnlyHere {
        /// Time of the start the estimate was compared with.
        t_start: f64,
        /// The unknowns read of index 2 or 3 at the failure point, with their index.
        unknowns: Vec<(String, u8)>,
    },
}

/// The cause to add to a step failure at `(t, y, y')` of `dae`, declared with every unknown
/// of index at most 1, that started at `start`: the estimate of [`unknown_indices`] at the
/// failure point, confirmed at the start. A DAE of undeclared higher index reads so all along
/// its solution (the index estimate's unknowns are the same at both points); a DAE of index 1
/// whose algebraic part becomes nearly singular where it fails (a capacitance or mass that
/// nearly vanishes, an impasse point) reads index 2 there only, and declaring that index
/// would not help: that case is told apart ([`FailureDiagnosis::OnlyHere`]) rather than
/// reported as an undeclared index. Costs the estimate at both points (singular value
/// decompositions of dense `n x n` matrices, some forty of them); meant for the integrators'
/// error paths only, and made for DAEs of at most [`DIAGNOSIS_MAX`] unknowns: above, the
/// answer is [`FailureDiagnosis::None`] (the integrator's error is reported without a cause
/// added, never with a wrong one).
pub(crate) fn diagnose_failure<D: ImplicitDae + ?Sized>(
    dae: &D,
    start: &StartPoint,
    (t, y, yp): (f64, &[f64], &[f64]),
) -> FailureDiagnosis {
    if dae.dimension() > DIAGNOSIS_MAX {
        return FailureDiagnosis::None;
    }
    let Ok(here) = unknown_indices(dae, t, y, yp) else {
        return FailureDiagnosis::None;
    };
    if here.iter().all(|&m| m <= 1) {
        return FailureDiagnosis::None;
    }
    let named = |keep: &dyn Fn(usize) -> bool| -> Vec<(String, u8)> {
        (0..here.len())
            .filter(|&i| here[i] > 1 && keep(i))
            .map(|i| (dae.unknown_name(i), here[i]))
            .collect()
    };
    let at_start = if (start.t, &start.y[..], &start.yp[..]) == (t, y, yp) {
        Ok(here.clone())
    } else {
        unknown_indices(dae, start.t, &start.y, &start.yp)
    };
    match at_start {
        // No reading at the start: no confirmation, and no diagnosis rather than a doubtful one.
        Err(_) => FailureDiagnosis::None,
        Ok(s) if s.iter().all(|&m| m <= 1) => FailureDiagnosis::OnlyHere {
            t_start: start.t,
            unknowns: named(&|_| true),
        },
        Ok(s) => {
            let confirmed = named(&|i| s[i] > 1);
            if confirmed.is_empty() {
                // Higher-index unknowns at both points, but different ones: the start's
                // reading does not confirm these.
                FailureDiagnosis::None
            } else {
                FailureDiagnosis::Undeclared(confirmed)
            }
        }
    }
}

/// [`unknown_indices`] at the one point `(t, y, y')`.
fn indices_at<D: ImplicitDae + ?Sized>(
    dae: &D,
    t: f64,
    y: &[f64],
    yp: &[f64],
) -> Result<Vec<u8>, IndexEstimateError> {
    let n = dae.dimension();
    let matrix = |c: f64| {
        crate::dae::dense_iteration_matrix(dae, t, y, yp, c).map_err(|(i, j)| {
            IndexEstimateError::NonFinite {
                equation: dae.equation_name(i),
                unknown: dae.unknown_name(j),
            }
        })
    };
    // G(c) = dF/dy + c dF/dy' is linear in c: its two parts from c = 0 and c = 1.
    let mut dfdy = matrix(0.0)?;
    let mut dfdyp = matrix(1.0)? - &dfdy;
    equilibrate(&mut dfdy, &mut dfdyp);
    let (ny, nyp) = (dfdy.norm(), dfdyp.norm());
    let scale = if ny > 0.0 && nyp > 0.0 { ny / nyp } else { 1.0 };
    // Row norms of G(c)^-1 for c = scale x 10, 100, ... while G(c) stays far from singular
    // (or MAX_DECADES); kept: the norms at the last c, the powers between the last two and
    // between the two before, the most asymptotic ones the arithmetic allows.
    let mut last_norms: Option<Vec<f64>> = None;
    let mut last_powers: Option<Vec<f64>> = None;
    let mut earlier_powers: Option<Vec<f64>> = None;
    let mut worst_ratio = f64::NAN;
    let mut c = scale;
    for _ in 0..MAX_DECADES {
        c *= 10.0;
        let g = &dfdy + &dfdyp * c;
        let svd = g.svd(true, true);
        let (smax, smin) = (svd.singular_values.max(), svd.singular_values.min());
        let ratio = if smax > 0.0 { smin / smax } else { 0.0 };
        // G^-1 = V S^-1 U^T from the decomposition, only while every singular value is well
        // above round-off.
        let inverse = match svd.pseudo_inverse(0.0) {
            Ok(inverse) if ratio > MIN_SINGULAR_RATIO => inverse,
            _ => {
                worst_ratio = ratio;
                break;
            }
        };
        let norms: Vec<f64> = (0..n).map(|i| inverse.row(i).amax()).collect();
        if let Some(before) = &last_norms {
            let powers: Vec<f64> = norms
                .iter()
                .zip(before)
                .map(|(&b, &a)| (b / a).log10())
                .collect();
            earlier_powers = last_powers.replace(powers);
        }
        last_norms = Some(norms);
    }
    let (Some(last), Some(earlier)) = (last_powers, earlier_powers) else {
        // Fewer than three values of c at which G(c) could be inverted.
        return Err(IndexEstimateError::SingularPencil {
            t,
            sigma_ratio: worst_ratio,
        });
    };
    let mut indices = Vec::with_capacity(n);
    for (&p, &q) in last.iter().zip(&earlier) {
        if (p - q).abs() > SETTLED || (p - p.round()).abs() > SETTLED {
            return Err(IndexEstimateError::Inconclusive { t });
        }
        // The power of c the row grows with: -1 (a derivative the equations determine), 0
        // (an algebraic unknown of index 1), 1, 2, ...; the index is the power + 1, at least 1.
        indices.push((p.round() + 1.0).clamp(1.0, f64::from(u8::MAX)) as u8);
    }
    Ok(indices)
}
