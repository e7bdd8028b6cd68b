//! The whole linear DPC analysis of the paper's Section 3 and the preliminary feedback of
//! Section 3.1, as one report.
//!
//! Pipeline: partial stabilisation by `W_i(s)` -> row compression `V` -> Weierstrass split of
//! `-Es + F` (`M`, `Q`, `A_1`, `N`, `nu`) -> `K_J`, `R_xi(s)` (3.8)-(3.9) -> `Q^-1 A Q`,
//! `Q^-1 B`, `Abar_4` and the verdict (Theorem 3.2) -> transmission zeros, `V*`
//! (Theorem 3.1) -> if needed `K_2`, `K_n = [0 K_2] Q^-1` and the analysis redone on
//! `(A + B K_n, B, C + D K_n, D)` -> Theorem 3.3 checks.

use nalgebra::DMatrix;
use num_complex::Complex;
use serde::Serialize;

use super::subspace::{self, RankDecision};
use super::{compress, pencil, place, serial, transfer, vstar, LinearError, LinearSystem};

type C64 = Complex<f64>;

/// When to build the preliminary feedback `K_n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PrefeedbackPolicy {
    /// When `Abar_4` is unstable, or when poles were given.
    #[default]
    Auto,
    /// Whenever there is an infinite part.
    Always,
    /// Never.
    Never,
}

/// Options of [`analyze`].
#[derive(Debug, Clone, PartialEq)]
pub struct AnalysisOptions {
    /// Per output, the numbers `w_ij >= 0` of `W_i(s) = prod_j (s + w_ij)`; `None` = no partial
    /// stabilisation (`W = I`).
    pub w: Option<Vec<Vec<f64>>>,
    /// Poles of `Abar_4 + Bbar_2 K_2` (as many as `Abar_4` has rows, conjugate pairs complete).
    /// Default: all at `-alpha`, `alpha` the largest `w_ij` if positive, else
    /// `max(1, spectral radius of Abar_4)`.
    pub poles: Option<Vec<C64>>,
    /// When to build `K_n`.
    pub prefeedback: PrefeedbackPolicy,
    /// Points at which to report the transfer matrix `H(s)` of the original system.
    pub transfer_points: Vec<C64>,
    /// Multiple of `max(rows, cols) * eps * sigma_max` below which singular values count as
    /// zero. Default 100.
    pub tol_factor: f64,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        Self {
            w: None,
            poles: None,
            prefeedback: PrefeedbackPolicy::Auto,
            transfer_points: Vec::new(),
            tol_factor: 100.0,
        }
    }
}

/// How clear-cut the numerical decisions were.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tolerances {
    /// The factor in `factor * max(rows, cols) * eps * sigma_max`.
    pub tol_factor: f64,
    /// Rank tolerance for `[B; D]`.
    pub compress_tol: f64,
    /// Smallest singular value of `[B; D]` (must be above `compress_tol`).
    pub compress_sigma_min: f64,
    /// Smallest ratio (smallest kept / largest dropped singular value) over the Wong-sequence
    /// rank decisions; `None` if no decision dropped anything nonzero.
    pub pencil_gap: Option<f64>,
    /// Largest tolerance used in the Wong-sequence decisions.
    pub pencil_tol: f64,
    /// Condition number of `Q`.
    pub cond_q: f64,
    /// Condition number of `M^-1 = [E V, F W]`.
    pub cond_m_inv: f64,
    /// Off-diagonal residual of `M E Q`, `M F Q` (relative).
    pub block_residual: f64,
    /// `||N^nu||` relative to `||N||^nu`.
    pub nilpotency_residual: f64,
    /// Smallest gap over the `V*` recursion decisions.
    pub vstar_gap: Option<f64>,
    /// An eigenvalue `z` counts as stable when `Re z < -stability_margin * (1 + |z|)`.
    pub stability_margin: f64,
}

/// The DPC law of one system (3.8)-(3.10) and its structure in `z = Q^-1 x` coordinates.
#[derive(Debug, Clone, Serialize)]
pub struct DpcLaw {
    /// `nu`, the nilpotency index of `N`: the number of inner steps whose controls are
    /// dominated by an inconsistent start (the DPC controller's `DpcOptions::nu`).
    pub nu: usize,
    /// Dimension of the finite part `z_1`.
    pub finite_dim: usize,
    /// `K_J` in `x` coordinates.
    #[serde(serialize_with = "serial::mat")]
    pub k_j: DMatrix<f64>,
    /// `Kbar_J = K_J Q = [K_1 0]`.
    #[serde(serialize_with = "serial::mat")]
    pub k_j_bar: DMatrix<f64>,
    /// Coefficients `R_0, R_1, ...` of `R_xi(s)`, lowest power first.
    #[serde(serialize_with = "serial::mats")]
    pub r_xi: Vec<DMatrix<f64>>,
    /// Eigenvalues of `A_1` = transmission zeros.
    #[serde(serialize_with = "serial::cvec")]
    pub transmission_zeros: Vec<C64>,
    /// Eigenvalues of `Abar_4`.
    #[serde(serialize_with = "serial::cvec")]
    pub abar4_eigenvalues: Vec<C64>,
    /// Eigenvalues of `A + B K_J`.
    #[serde(serialize_with = "serial::cvec")]
    pub closed_loop_eigenvalues: Vec<C64>,
    /// All transmission zeros stable.
    pub minimum_phase: bool,
    /// `Abar_4` stable.
    pub abar4_stable: bool,
    /// DPC (3.10) stabilises the system: all eigenvalues of `A + B K_J` stable.
    pub dpc_stable: bool,
    /// `Q`.
    #[serde(serialize_with = "serial::mat")]
    pub q: DMatrix<f64>,
    /// `M`.
    #[serde(serialize_with = "serial::mat")]
    pub m_mat: DMatrix<f64>,
    /// `A_1`.
    #[serde(serialize_with = "serial::mat")]
    pub a1: DMatrix<f64>,
    /// `N`.
    #[serde(serialize_with = "serial::mat")]
    pub n_mat: DMatrix<f64>,
    /// `V` of the row compression.
    #[serde(serialize_with = "serial::mat")]
    pub v: DMatrix<f64>,
    /// `E`.
    #[serde(serialize_with = "serial::mat")]
    pub e: DMatrix<f64>,
    /// `F`.
    #[serde(serialize_with = "serial::mat")]
    pub f: DMatrix<f64>,
    /// `H`.
    #[serde(serialize_with = "serial::mat")]
    pub h: DMatrix<f64>,
    /// `J`.
    #[serde(serialize_with = "serial::mat")]
    pub j: DMatrix<f64>,
    /// `Q^-1 A Q`.
    #[serde(serialize_with = "serial::mat")]
    pub abar: DMatrix<f64>,
    /// `Abar_1`.
    #[serde(serialize_with = "serial::mat")]
    pub abar1: DMatrix<f64>,
    /// `Abar_2`.
    #[serde(serialize_with = "serial::mat")]
    pub abar2: DMatrix<f64>,
    /// `Abar_3`.
    #[serde(serialize_with = "serial::mat")]
    pub abar3: DMatrix<f64>,
    /// `Abar_4`.
    #[serde(serialize_with = "serial::mat")]
    pub abar4: DMatrix<f64>,
    /// `Q^-1 B`.
    #[serde(serialize_with = "serial::mat")]
    pub bbar: DMatrix<f64>,
    /// `Bbar_1`.
    #[serde(serialize_with = "serial::mat")]
    pub bbar1: DMatrix<f64>,
    /// `Bbar_2`.
    #[serde(serialize_with = "serial::mat")]
    pub bbar2: DMatrix<f64>,
    /// `C Q`.
    #[serde(serialize_with = "serial::mat")]
    pub cbar: DMatrix<f64>,
    /// Dimension of `V*`.
    pub vstar_dim: usize,
    /// Sine of the largest principal angle between `V*` and the span of `Q`'s finite part
    /// (`1` if the dimensions differ).
    pub vstar_distance: f64,
    /// Theorem 3.1 a): `max(|Abar_3 + Bbar_2 K_1|, |Cbar_1 + D K_1|)` relative to the norms.
    pub theorem_3_1_residual: f64,
    /// Theorem 3.3: `max |H_b(s) R_xi(s) - I|` (relative) at a few check points.
    pub theorem_3_3_residual: f64,
    /// Decisions.
    pub tolerances: Tolerances,
}

/// `H(s)` of the original system at one point.
#[derive(Debug, Clone, Serialize)]
pub struct TransferSample {
    /// The point `[re, im]`.
    pub s: [f64; 2],
    /// Real parts of `H(s)`, rows.
    pub re: Vec<Vec<f64>>,
    /// Imaginary parts of `H(s)`, rows.
    pub im: Vec<Vec<f64>>,
}

/// The full report.
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    /// States.
    pub n: usize,
    /// Inputs = outputs.
    pub m: usize,
    /// `nu`, the nilpotency index of `N` of the partially stabilised system.
    pub nu: usize,
    /// `n_f`.
    pub finite_dim: usize,
    /// `W_i` roots used (`w_ij`).
    pub w: Option<Vec<Vec<f64>>>,
    /// Output matrix of the partially stabilised system.
    #[serde(serialize_with = "serial::mat")]
    pub c_hat: DMatrix<f64>,
    /// Feedthrough of the partially stabilised system.
    #[serde(serialize_with = "serial::mat")]
    pub d_hat: DMatrix<f64>,
    /// Transmission zeros of the partially stabilised system.
    #[serde(serialize_with = "serial::cvec")]
    pub transmission_zeros: Vec<C64>,
    /// Eigenvalues of `Abar_4`.
    #[serde(serialize_with = "serial::cvec")]
    pub abar4_eigenvalues: Vec<C64>,
    /// Whether plain DPC is stable.
    pub dpc_stable: bool,
    /// Zeros stable.
    pub minimum_phase: bool,
    /// `K_J`.
    #[serde(serialize_with = "serial::mat")]
    pub k_j: DMatrix<f64>,
    /// `R_xi` coefficients, lowest power first.
    #[serde(serialize_with = "serial::mats")]
    pub r_xi: Vec<DMatrix<f64>>,
    /// Eigenvalues of `A + B K_J`.
    #[serde(serialize_with = "serial::cvec")]
    pub closed_loop_eigenvalues: Vec<C64>,
    /// Everything of the DPC law of the partially stabilised system.
    pub law: DpcLaw,
    /// `H(s)` of the original system at the requested points.
    pub transfer: Vec<TransferSample>,
    /// Poles used for `Abar_4 + Bbar_2 K_2`.
    #[serde(
        serialize_with = "serial::opt_cvec",
        skip_serializing_if = "Option::is_none"
    )]
    pub poles: Option<Vec<C64>>,
    /// `K_2`.
    #[serde(
        serialize_with = "serial::opt_mat",
        skip_serializing_if = "Option::is_none"
    )]
    pub k_2: Option<DMatrix<f64>>,
    /// `K_n = [0 K_2] Q^-1`.
    #[serde(
        serialize_with = "serial::opt_mat",
        skip_serializing_if = "Option::is_none"
    )]
    pub k_n: Option<DMatrix<f64>>,
    /// `K_J'` of the pre-fed-back system.
    #[serde(
        serialize_with = "serial::opt_mat",
        skip_serializing_if = "Option::is_none"
    )]
    pub k_j_prefeedback: Option<DMatrix<f64>>,
    /// `R_xi` of the pre-fed-back system.
    #[serde(
        serialize_with = "serial::opt_mats",
        skip_serializing_if = "Option::is_none"
    )]
    pub r_xi_prefeedback: Option<Vec<DMatrix<f64>>>,
    /// Eigenvalues of `A + B (K_n + K_J')`.
    #[serde(
        serialize_with = "serial::opt_cvec",
        skip_serializing_if = "Option::is_none"
    )]
    pub closed_loop_eigenvalues_prefeedback: Option<Vec<C64>>,
    /// Whether DPC after the preliminary feedback is stable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dpc_stable_prefeedback: Option<bool>,
    /// The whole DPC law of the pre-fed-back system.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub law_prefeedback: Option<DpcLaw>,
    /// Why `K_n` could not be built in `Auto` mode (e.g. `(Abar_4, Bbar_2)` uncontrollable).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prefeedback_error: Option<String>,
}

/// Default relative stability margin.
pub const STABILITY_MARGIN: f64 = 1e-8;

fn is_stable(z: &C64) -> bool {
    z.re < -STABILITY_MARGIN * (1.0 + z.norm())
}

fn min_gap(ds: &[RankDecision]) -> Option<f64> {
    ds.iter().filter_map(|d| d.gap()).reduce(f64::min)
}

/// The DPC law (3.8)-(3.10) of one (partially stabilised) system, without preliminary feedback.
pub fn dpc_law(sys: &LinearSystem, tol_factor: f64) -> Result<DpcLaw, LinearError> {
    let (n, m) = (sys.n(), sys.m());
    let rc = compress::compress(sys, tol_factor)?;
    // E = [V_1 V_2][I; 0] and F = [V_1 V_2][A; C] with orthonormal rows [V_1 V_2].
    let mut ac = DMatrix::zeros(n + m, n);
    ac.view_mut((0, 0), (n, n)).copy_from(&sys.a);
    ac.view_mut((n, 0), (m, n)).copy_from(&sys.c);
    let sp = pencil::split(&rc.e, &rc.f, tol_factor, 1.0, subspace::norm2(&ac))?;
    let nf = sp.finite_dim;
    let ni = n - nf;
    let q = &sp.q;
    let q1 = q.columns(0, nf).into_owned();
    let q2 = q.columns(nf, ni).into_owned();

    // K_J Q = [H Q_1 A_1 - J Q_1, 0]; K_J = Kbar Q^-1 by solving Q^T K_J^T = Kbar^T.
    let k1 = &rc.h * &q1 * &sp.a1 - &rc.j * &q1;
    let mut k_j_bar = DMatrix::zeros(m, n);
    k_j_bar.view_mut((0, 0), (m, nf)).copy_from(&k1);
    let singular_q = || LinearError::SingularPencil {
        finite_dim: nf,
        infinite_dim: ni,
        n,
        sigma_min: 0.0,
        tol: 0.0,
    };
    let k_j = subspace::solve(&q.transpose(), &k_j_bar.transpose())
        .ok_or_else(singular_q)?
        .transpose();

    // R_xi(s) = V_4 - (H Q_1 G_1 - (sH - J) Q_2 sum (sN)^i G_2), G = M V_2 = [G_1; G_2].
    let g = subspace::solve(&sp.m_inv, &rc.v2).ok_or_else(singular_q)?;
    let g1 = g.rows(0, nf).into_owned();
    let g2 = g.rows(nf, ni).into_owned();
    let hq2 = &rc.h * &q2;
    let jq2 = &rc.j * &q2;
    let mut r_xi = vec![&rc.v4 - &rc.h * &q1 * &g1 - &jq2 * &g2];
    let mut npow_g2 = g2.clone(); // N^(k-1) G_2
    for _ in 1..=sp.index {
        let next = &sp.n_mat * &npow_g2; // N^k G_2
        r_xi.push(&hq2 * &npow_g2 - &jq2 * &next);
        npow_g2 = next;
    }

    // z coordinates.
    let aq = &sys.a * q;
    let abar = subspace::solve(q, &aq).ok_or_else(singular_q)?;
    let bbar = subspace::solve(q, &sys.b).ok_or_else(singular_q)?;
    let cbar = &sys.c * q;
    let abar1 = abar.view((0, 0), (nf, nf)).into_owned();
    let abar2 = abar.view((0, nf), (nf, ni)).into_owned();
    let abar3 = abar.view((nf, 0), (ni, nf)).into_owned();
    let abar4 = abar.view((nf, nf), (ni, ni)).into_owned();
    let bbar1 = bbar.rows(0, nf).into_owned();
    let bbar2 = bbar.rows(nf, ni).into_owned();

    let transmission_zeros = subspace::eigenvalues(&sp.a1)?;
    let abar4_eigenvalues = subspace::eigenvalues(&abar4)?;
    let closed_loop_eigenvalues = subspace::eigenvalues(&(&sys.a + &sys.b * &k_j))?;
    let minimum_phase = transmission_zeros.iter().all(is_stable);
    let abar4_stable = abar4_eigenvalues.iter().all(is_stable);
    let dpc_stable = closed_loop_eigenvalues.iter().all(is_stable);

    // Theorem 3.1 a).
    let scale_a = 1.0 + subspace::norm2(&abar) + subspace::norm2(&bbar) * subspace::norm2(&k1);
    let scale_c = 1.0 + subspace::norm2(&cbar) + subspace::norm2(&sys.d) * subspace::norm2(&k1);
    let r_a = (&abar3 + &bbar2 * &k1).amax() / scale_a;
    let r_c = (cbar.columns(0, nf) + &sys.d * &k1).amax() / scale_c;
    let theorem_3_1_residual = r_a.max(r_c);

    // Theorem 3.1 c).
    let vs = vstar::vstar(sys, tol_factor)?;
    let vstar_distance = if vs.basis.ncols() != nf {
        1.0
    } else {
        let (q1o, _) = subspace::range(&q1, tol_factor, Some(1.0))?;
        subspace::subspace_distance(&vs.basis, &q1o)
            .max(subspace::subspace_distance(&q1o, &vs.basis))
    };

    let points = transfer::check_points(subspace::norm2(&sys.a));
    let theorem_3_3_residual = transfer::theorem_3_3_residual(sys, &k_j, &r_xi, &points);

    let mut v = DMatrix::zeros(n + m, n + m);
    v.view_mut((0, 0), (n, n)).copy_from(&rc.v1);
    v.view_mut((0, n), (n, m)).copy_from(&rc.v2);
    v.view_mut((n, 0), (m, n)).copy_from(&rc.v3);
    v.view_mut((n, n), (m, m)).copy_from(&rc.v4);

    let tolerances = Tolerances {
        tol_factor,
        compress_tol: rc.decision.tol,
        compress_sigma_min: rc.decision.smallest_kept.unwrap_or(0.0),
        pencil_gap: min_gap(&sp.decisions),
        pencil_tol: sp.decisions.iter().map(|d| d.tol).fold(0.0, f64::max),
        cond_q: sp.cond_q,
        cond_m_inv: sp.cond_m_inv,
        block_residual: sp.block_residual,
        nilpotency_residual: sp.nilpotency_residual,
        vstar_gap: min_gap(&vs.decisions),
        stability_margin: STABILITY_MARGIN,
    };

    Ok(DpcLaw {
        nu: sp.index,
        finite_dim: nf,
        k_j,
        k_j_bar,
        r_xi,
        transmission_zeros,
        abar4_eigenvalues,
        closed_loop_eigenvalues,
        minimum_phase,
        abar4_stable,
        dpc_stable,
        q: sp.q.clone(),
        m_mat: sp.m.clone(),
        a1: sp.a1.clone(),
        n_mat: sp.n_mat.clone(),
        v,
        e: rc.e,
        f: rc.f,
        h: rc.h,
        j: rc.j,
        abar,
        abar1,
        abar2,
        abar3,
        abar4,
        bbar,
        bbar1,
        bbar2,
        cbar,
        vstar_dim: vs.basis.ncols(),
        vstar_distance,
        theorem_3_1_residual,
        theorem_3_3_residual,
        tolerances,
    })
}

/// Run the whole analysis: partial stabilisation, DPC law, verdict, and (as asked by
/// `opts.prefeedback`) the preliminary feedback and the analysis of the pre-fed-back system.
pub fn analyze(sys: &LinearSystem, opts: &AnalysisOptions) -> Result<Analysis, LinearError> {
    analyze_as_given(sys, opts).map_err(|cause| match w_out_of_scale(sys, opts) {
        // Only a numerical failure can be blamed on W's scale; a malformed system or option
        // is reported as it is.
        Some((output, root, scale)) if cause.is_numerical() => LinearError::WOutOfScale {
            output,
            root,
            scale,
            cause: Box::new(cause),
        },
        _ => cause,
    })
}

/// Ratio of the largest root of `W` to the plant's scale beyond which a failed analysis is
/// blamed on `W`'s scale.
const W_SCALE_RATIO: f64 = 1e3;

/// The output with the largest root of `W`, that root and the plant's scale, when the root
/// exceeds the scale by more than [`W_SCALE_RATIO`].
fn w_out_of_scale(sys: &LinearSystem, opts: &AnalysisOptions) -> Option<(usize, f64, f64)> {
    let norm = sys.a.norm();
    let scale = if norm > 0.0 { norm } else { 1.0 };
    let (output, root) = opts
        .w
        .as_ref()?
        .iter()
        .enumerate()
        .flat_map(|(i, roots)| roots.iter().map(move |r| (i, r.abs())))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (root > W_SCALE_RATIO * scale).then_some((output, root, scale))
}

fn analyze_as_given(sys: &LinearSystem, opts: &AnalysisOptions) -> Result<Analysis, LinearError> {
    let hat = match &opts.w {
        Some(w) => sys.stabilise(w)?,
        None => sys.clone(),
    };
    let law = dpc_law(&hat, opts.tol_factor)?;
    let ni = sys.n() - law.finite_dim;

    let mut transfer = Vec::new();
    for &s in &opts.transfer_points {
        if let Some(h) = transfer::transfer_matrix(sys, s) {
            transfer.push(TransferSample {
                s: [s.re, s.im],
                re: serial::to_rows(&h.map(|z| z.re)),
                im: serial::to_rows(&h.map(|z| z.im)),
            });
        }
    }

    let build = ni > 0
        && match opts.prefeedback {
            PrefeedbackPolicy::Never => false,
            PrefeedbackPolicy::Always => true,
            PrefeedbackPolicy::Auto => !law.abar4_stable || opts.poles.is_some(),
        };

    let mut out = Analysis {
        n: sys.n(),
        m: sys.m(),
        nu: law.nu,
        finite_dim: law.finite_dim,
        w: opts.w.clone(),
        c_hat: hat.c.clone(),
        d_hat: hat.d.clone(),
        transmission_zeros: law.transmission_zeros.clone(),
        abar4_eigenvalues: law.abar4_eigenvalues.clone(),
        dpc_stable: law.dpc_stable,
        minimum_phase: law.minimum_phase,
        k_j: law.k_j.clone(),
        r_xi: law.r_xi.clone(),
        closed_loop_eigenvalues: law.closed_loop_eigenvalues.clone(),
        transfer,
        poles: None,
        k_2: None,
        k_n: None,
        k_j_prefeedback: None,
        r_xi_prefeedback: None,
        closed_loop_eigenvalues_prefeedback: None,
        dpc_stable_prefeedback: None,
        law_prefeedback: None,
        prefeedback_error: None,
        law,
    };
    if !build {
        if ni == 0 && opts.poles.as_ref().is_some_and(|p| !p.is_empty()) {
            // Poles asked for where there is nothing to place: silently ignoring them would
            // let the caller believe a K_n was designed.
            return Err(LinearError::BadPoles {
                reason: format!(
                    "{} pole(s) given, but with this W the pencil has no infinite part, so there is no preliminary feedback to place them with (Abar_4 has dimension {}); give no poles",
                    opts.poles.as_ref().map_or(0, Vec::len),
                    out.law.abar4.nrows()
                ),
            });
        }
        return Ok(out);
    }

    let poles = match &opts.poles {
        Some(p) => p.clone(),
        None => default_poles(&out.law, opts.w.as_deref()),
    };
    let explicit = opts.poles.is_some() || opts.prefeedback == PrefeedbackPolicy::Always;
    let k2 = match place::place(&out.law.abar4, &out.law.bbar2, &poles, opts.tol_factor) {
        Ok(k2) => k2,
        // Asked for explicitly: the caller gets the typed error. In `Auto` mode the verdict
        // is still worth having, with the reason why no K_n could be built.
        Err(e) if !explicit => {
            out.prefeedback_error = Some(e.to_string());
            return Ok(out);
        }
        Err(e) => return Err(e),
    };
    let k_n = prefeedback_gain(&out.law.q, &k2, out.law.finite_dim)?;
    let fed = hat.with_feedback(&k_n)?;
    let law2 = dpc_law(&fed, opts.tol_factor)?;
    let total = &k_n + &law2.k_j;
    let cl = subspace::eigenvalues(&(&sys.a + &sys.b * &total))?;
    out.dpc_stable_prefeedback = Some(cl.iter().all(is_stable));
    out.closed_loop_eigenvalues_prefeedback = Some(cl);
    out.k_j_prefeedback = Some(law2.k_j.clone());
    out.r_xi_prefeedback = Some(law2.r_xi.clone());
    out.poles = Some(poles);
    out.k_2 = Some(k2);
    out.k_n = Some(k_n);
    out.law_prefeedback = Some(law2);
    Ok(out)
}

/// `K_n = [0 K_2] Q^-1`, by solving `Q^T K_n^T = [0 K_2]^T`.
pub fn prefeedback_gain(
    q: &DMatrix<f64>,
    k2: &DMatrix<f64>,
    finite_dim: usize,
) -> Result<DMatrix<f64>, LinearError> {
    let n = q.nrows();
    let m = k2.nrows();
    let mut kbar = DMatrix::zeros(m, n);
    kbar.view_mut((0, finite_dim), (m, n - finite_dim))
        .copy_from(k2);
    let kt =
        subspace::solve(&q.transpose(), &kbar.transpose()).ok_or(LinearError::SingularPencil {
            finite_dim,
            infinite_dim: n - finite_dim,
            n,
            sigma_min: 0.0,
            tol: 0.0,
        })?;
    Ok(kt.transpose())
}

/// All poles at `-alpha`: `alpha` the largest `w_ij` if positive (the paper uses the root of
/// `W` itself, -5), else `max(1, spectral radius of Abar_4)`.
pub fn default_poles(law: &DpcLaw, w: Option<&[Vec<f64>]>) -> Vec<C64> {
    let from_w = w
        .map(|w| w.iter().flatten().copied().fold(0.0, f64::max))
        .unwrap_or(0.0);
    let alpha = if from_w > 0.0 {
        from_w
    } else {
        law.abar4_eigenvalues
            .iter()
            .map(|z| z.norm())
            .fold(1.0, f64::max)
    };
    vec![C64::new(-alpha, 0.0); law.abar4.nrows()]
}
