//! Index-3 problems of the Test Set for IVP Solvers (Mazzia, Iavernaro, Magherini, University of
//! Bari, release 2.4; Lioen & de Swart, CWI) in their index-3 form, with the Test Set's reference
//! solutions and accuracy measures: Andrews' squeezing mechanism (27 unknowns) and the car axis
//! (10 unknowns). Shared by the Radau and BDF tests and the work-precision example.
#![allow(dead_code)]
// Matrix entries are written by (row, column) index, as the formulas are.
#![allow(clippy::needless_range_loop)]

use dpc_core::stabilised::Stabilised;
use dpc_core::{ImplicitDae, MatrixSink};

/// Significant correct digits `min_i -log10(|y_i - r_i| / |r_i|)` over `components`.
pub fn scd(y: &[f64], reference: &[f64], components: &[usize]) -> f64 {
    -components
        .iter()
        .map(|&i| (y[i] - reference[i]).abs() / reference[i].abs())
        .fold(0.0f64, |m, e| {
            if e.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(e)
            }
        })
        .log10()
}

/// The Test Set's measure over tolerance jitter: the median of `digits(tol * f)` over
/// `f = 0.9, 1, 1.1`.
pub fn median_over_jitter(tol: f64, digits: impl Fn(f64) -> f64) -> f64 {
    let mut d = [0.9, 1.0, 1.1].map(|f| digits(tol * f));
    d.sort_by(f64::total_cmp);
    d[1]
}

/// [`median_over_jitter`] of the [`scd`] of `run(tol * f)` on `scored` against `reference`; a
/// failed run (its message printed) scores minus infinity.
pub fn median_scd_over_jitter(
    tol: f64,
    run: impl Fn(f64) -> Result<Vec<f64>, String>,
    reference: &[f64],
    scored: &[usize],
) -> f64 {
    median_over_jitter(tol, |t| match run(t) {
        Ok(y) => scd(&y, reference, scored),
        Err(e) => {
            println!("  tol {t:e}: {e}");
            f64::NEG_INFINITY
        }
    })
}

/// Mixed-error significant correct digits `min_i -log10(|y_i - r_i| / (atol/rtol + |r_i|))`
/// over `components` (deTestSet's `printpr`).
pub fn mescd(y: &[f64], reference: &[f64], components: &[usize], rtol: f64, atol: f64) -> f64 {
    -components
        .iter()
        .map(|&i| (y[i] - reference[i]).abs() / (atol / rtol + reference[i].abs()))
        .fold(0.0f64, |m, e| {
            if e.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(e)
            }
        })
        .log10()
}

/// The non-zero entries of `block` into `out`, its row `r` as row `first + r`.
fn write_rows<S: MatrixSink + ?Sized, const R: usize, const C: usize>(
    first: usize,
    block: &[[f64; C]; R],
    out: &mut S,
) {
    for (r, row) in block.iter().enumerate() {
        for (k, &v) in row.iter().enumerate() {
            if v != 0.0 {
                out.set(first + r, k, v);
            }
        }
    }
}

/// Andrews' squeezing mechanism, index 3 (Test Set `andrews.f`; Hairer & Wanner, *Solving ODEs
/// II*, Section VII.7): unknowns `y = (q, v, w, lambda)` with `q` the 7 angles
/// `(beta, Theta, gamma, Phi, delta, Omega, epsilon)`, `v = q'`, `w = q''` and 6 multipliers;
/// `q' = v`, `v' = w`, `0 = M(q) w - f(q, v) + G(q)^T lambda`, `0 = g(q)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Andrews;

/// Interval end of [`Andrews`].
pub const ANDREWS_T_END: f64 = 0.03;

/// Differential index per unknown: `q` 1, `v` 2, `w` and `lambda` 3 (deTestSet `ind`).
pub fn andrews_index() -> Vec<u8> {
    let mut v = vec![1u8; 7];
    v.extend([2u8; 7]);
    v.extend([3u8; 13]);
    v
}

/// Components the Test Set scores for Andrews: the positions `y1..y7`.
pub const ANDREWS_SCORED: [usize; 7] = [0, 1, 2, 3, 4, 5, 6];

/// Reference solution at `t = 0.03` (Test Set, PSIDE at `rtol = atol = 1e-14`).
#[allow(clippy::excessive_precision)]
pub const ANDREWS_REF: [f64; 27] = [
    0.1581077119629904e+2,
    -0.1575637105984298e+2,
    0.4082224013073101e-1,
    -0.5347301163226948e+0,
    0.5244099658805304e+0,
    0.5347301163226948e+0,
    0.1048080741042263e+1,
    0.1139920302151208e+4,
    -0.1424379294994111e+4,
    0.1103291221937134e+2,
    0.1929337464421385e+2,
    0.5735699284790808e+0,
    -0.1929337464421385e+2,
    0.3231791658026955e+0,
    -0.2463176316945196e+5,
    0.5185037701610329e+5,
    0.3241025686413781e+6,
    0.5667493645176213e+6,
    0.1674362929479361e+5,
    -0.5667493645176222e+6,
    0.9826520791458422e+4,
    0.1991753333731910e+3,
    -0.2975531228015052e+2,
    0.2306654119098399e+2,
    0.3145271365475927e+2,
    0.2264249232082739e+2,
    0.1161740700019673e+2,
];

mod andrews_constants {
    pub const M1: f64 = 0.04325;
    pub const M2: f64 = 0.00365;
    pub const M3: f64 = 0.02373;
    pub const M4: f64 = 0.00706;
    pub const M5: f64 = 0.07050;
    pub const M6: f64 = 0.00706;
    pub const M7: f64 = 0.05498;
    pub const XA: f64 = -0.06934;
    pub const YA: f64 = -0.00227;
    pub const XB: f64 = -0.03635;
    pub const YB: f64 = 0.03273;
    pub const XC: f64 = 0.014;
    pub const YC: f64 = 0.072;
    pub const C0: f64 = 4530.0;
    pub const I1: f64 = 2.194e-6;
    pub const I2: f64 = 4.410e-7;
    pub const I3: f64 = 5.255e-6;
    pub const I4: f64 = 5.667e-7;
    pub const I5: f64 = 1.169e-5;
    pub const I6: f64 = 5.667e-7;
    pub const I7: f64 = 1.912e-5;
    pub const D: f64 = 0.028;
    pub const DA: f64 = 0.0115;
    pub const E: f64 = 0.02;
    pub const EA: f64 = 0.01421;
    pub const RR: f64 = 0.007;
    pub const RA: f64 = 0.00092;
    pub const L0: f64 = 0.07785;
    pub const SS: f64 = 0.035;
    pub const SA: f64 = 0.01874;
    pub const SB: f64 = 0.01043;
    pub const SC: f64 = 0.018;
    pub const SD: f64 = 0.02;
    pub const TA: f64 = 0.02308;
    pub const TB: f64 = 0.00916;
    pub const U: f64 = 0.04;
    pub const UA: f64 = 0.01228;
    pub const UB: f64 = 0.00449;
    pub const ZF: f64 = 0.02;
    pub const ZT: f64 = 0.04;
    pub const FA: f64 = 0.01421;
    pub const MOM: f64 = 0.033;
}

impl Andrews {
    /// Unknowns of index 1 in the stabilised form (the positions and velocities).
    pub const STABILISED_DIFFERENTIAL: usize = 14;

    /// The stabilised index-2 form: the position constraints `y22..y27`, each position
    /// `y1..y7` with its kinematic row.
    pub fn stabilised() -> Stabilised<Andrews> {
        Stabilised::new(
            Andrews,
            (21..27).collect(),
            (0..7).map(|j| (j, j)).collect(),
        )
        .expect("Andrews' constraint rows")
    }

    /// Consistent initial values `(y0, y0')` of the Test Set (`y'_15..27 = 0`).
    #[allow(clippy::excessive_precision)]
    pub fn initial() -> ([f64; 27], [f64; 27]) {
        let mut y = [0.0; 27];
        y[0] = -0.0617138900142764496358948458001;
        y[2] = 0.455279819163070380255912382449;
        y[3] = 0.222668390165885884674473185609;
        y[4] = 0.487364979543842550225598953530;
        y[5] = -0.222668390165885884674473185609;
        y[6] = 1.23054744454982119249735015568;
        y[14] = 14222.4439199541138705911625887;
        y[15] = -10666.8329399655854029433719415;
        y[21] = 98.5668703962410896057654982170;
        y[22] = -6.12268834425566265503114393122;
        let mut yp = [0.0; 27];
        yp[..14].copy_from_slice(&y[7..21]);
        (y, yp)
    }

    /// Mass matrix `M(q)` (symmetric).
    fn mass(q: &[f64]) -> [[f64; 7]; 7] {
        use andrews_constants::*;
        let (ct, sp, so) = (q[1].cos(), q[3].sin(), q[5].sin());
        let mut m = [[0.0; 7]; 7];
        m[0][0] = M1 * RA * RA + M2 * (RR * RR - 2.0 * DA * RR * ct + DA * DA) + I1 + I2;
        m[1][0] = M2 * (DA * DA - DA * RR * ct) + I2;
        m[0][1] = m[1][0];
        m[1][1] = M2 * DA * DA + I2;
        m[2][2] = M3 * (SA * SA + SB * SB) + I3;
        let e = E - EA;
        m[3][3] = M4 * e * e + I4;
        m[4][3] = M4 * (e * e + ZT * e * sp) + I4;
        m[3][4] = m[4][3];
        m[4][4] = M4 * (ZT * ZT + 2.0 * ZT * e * sp + e * e) + M5 * (TA * TA + TB * TB) + I4 + I5;
        let z = ZF - FA;
        m[5][5] = M6 * z * z + I6;
        m[6][5] = M6 * (z * z - U * z * so) + I6;
        m[5][6] = m[6][5];
        m[6][6] = M6 * (z * z - 2.0 * U * z * so + U * U) + M7 * (UA * UA + UB * UB) + I6 + I7;
        m
    }

    /// Forces `f(q, v)`.
    fn forces(q: &[f64], v: &[f64]) -> [f64; 7] {
        use andrews_constants::*;
        let (sg, cg) = (q[2].sin(), q[2].cos());
        let xd = SD * cg + SC * sg + XB;
        let yd = SD * sg - SC * cg + YB;
        let lg = ((xd - XC).powi(2) + (yd - YC).powi(2)).sqrt();
        let force = -C0 * (lg - L0) / lg;
        let (fx, fy) = (force * (xd - XC), force * (yd - YC));
        let e = E - EA;
        let z = ZF - FA;
        [
            MOM - M2 * DA * RR * v[1] * (v[1] + 2.0 * v[0]) * q[1].sin(),
            M2 * DA * RR * v[0] * v[0] * q[1].sin(),
            fx * (SC * cg - SD * sg) + fy * (SD * cg + SC * sg),
            M4 * ZT * e * v[4] * v[4] * q[3].cos(),
            -M4 * ZT * e * v[3] * (v[3] + 2.0 * v[4]) * q[3].cos(),
            -M6 * U * z * v[6] * v[6] * q[5].cos(),
            M6 * U * z * v[5] * (v[5] + 2.0 * v[6]) * q[5].cos(),
        ]
    }

    /// Constraints `g(q)`.
    fn constraints(q: &[f64]) -> [f64; 6] {
        use andrews_constants::*;
        let (b, t, g, p, d, o, ep) = (q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
        let cx = RR * b.cos() - D * (b + t).cos();
        let cy = RR * b.sin() - D * (b + t).sin();
        [
            cx - SS * g.sin() - XB,
            cy + SS * g.cos() - YB,
            cx - E * (p + d).sin() - ZT * d.cos() - XA,
            cy + E * (p + d).cos() - ZT * d.sin() - YA,
            cx - ZF * (o + ep).cos() - U * ep.sin() - XA,
            cy - ZF * (o + ep).sin() + U * ep.cos() - YA,
        ]
    }

    /// Constraint Jacobian `G(q) = dg/dq`.
    fn constraint_jacobian(q: &[f64]) -> [[f64; 7]; 6] {
        use andrews_constants::*;
        let (b, t, g, p, d, o, ep) = (q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
        let mut m = [[0.0; 7]; 6];
        for r in [0, 2, 4] {
            m[r][0] = -RR * b.sin() + D * (b + t).sin();
            m[r][1] = D * (b + t).sin();
            m[r + 1][0] = RR * b.cos() - D * (b + t).cos();
            m[r + 1][1] = -D * (b + t).cos();
        }
        m[0][2] = -SS * g.cos();
        m[1][2] = -SS * g.sin();
        m[2][3] = -E * (p + d).cos();
        m[2][4] = -E * (p + d).cos() + ZT * d.sin();
        m[3][3] = -E * (p + d).sin();
        m[3][4] = -E * (p + d).sin() - ZT * d.cos();
        m[4][5] = ZF * (o + ep).sin();
        m[4][6] = ZF * (o + ep).sin() - U * ep.cos();
        m[5][5] = -ZF * (o + ep).cos();
        m[5][6] = -ZF * (o + ep).cos() - U * ep.sin();
        m
    }

    /// The constraints' curvature along `v`: `d/dq_k sum_j G_rj(q) v_j` (the constraints do not
    /// depend on `t`), differentiated by hand from [`Self::constraint_jacobian`].
    fn constraint_curvature(q: &[f64], v: &[f64]) -> [[f64; 7]; 6] {
        use andrews_constants::*;
        let (b, t, g, p, d, o, ep) = (q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
        let (sb, cb, sbt, cbt) = (b.sin(), b.cos(), (b + t).sin(), (b + t).cos());
        let v01 = v[0] + v[1];
        // d/d(beta, Theta) of the crank's terms G_r0 v0 + G_r1 v1, shared by the x rows (even)
        // and the y rows (odd).
        let x_beta = -RR * cb * v[0] + D * cbt * v01;
        let x_theta = D * cbt * v01;
        let y_beta = -RR * sb * v[0] + D * sbt * v01;
        let y_theta = D * sbt * v01;
        let mut m = [[0.0; 7]; 6];
        for r in [0, 2, 4] {
            m[r][0] = x_beta;
            m[r][1] = x_theta;
            m[r + 1][0] = y_beta;
            m[r + 1][1] = y_theta;
        }
        m[0][2] = SS * g.sin() * v[2];
        m[1][2] = -SS * g.cos() * v[2];
        let (spd, cpd, v34) = ((p + d).sin(), (p + d).cos(), v[3] + v[4]);
        m[2][3] = E * spd * v34;
        m[2][4] = E * spd * v34 + ZT * d.cos() * v[4];
        m[3][3] = -E * cpd * v34;
        m[3][4] = -E * cpd * v34 + ZT * d.sin() * v[4];
        let (soe, coe, v56) = ((o + ep).sin(), (o + ep).cos(), v[5] + v[6]);
        m[4][5] = ZF * coe * v56;
        m[4][6] = ZF * coe * v56 + U * ep.sin() * v[6];
        m[5][5] = ZF * soe * v56;
        m[5][6] = ZF * soe * v56 - U * ep.cos() * v[6];
        m
    }

    /// `M(q) w - f(q, v) + G(q)^T lambda`.
    fn dynamics(y: &[f64]) -> [f64; 7] {
        let (q, v, w, la) = (&y[0..7], &y[7..14], &y[14..21], &y[21..27]);
        let m = Self::mass(q);
        let f = Self::forces(q, v);
        let g = Self::constraint_jacobian(q);
        let mut out = [0.0; 7];
        for i in 0..7 {
            out[i] = (0..7).map(|j| m[i][j] * w[j]).sum::<f64>() - f[i]
                + (0..6).map(|r| g[r][i] * la[r]).sum::<f64>();
        }
        out
    }

    /// The derivatives of [`Self::dynamics`], `M(q) w - f(q, v) + G(q)^T lambda`, in `q` and in
    /// `v` (row `i`, column `j`), differentiated by hand: `d(M w)/dq` from the three angles `M`
    /// depends on, `-df/dq` and `-df/dv` of the forces (the spring's through `gamma` by the
    /// chain rule), and `d(G^T lambda)/dq = sum_r lambda_r d^2 g_r / dq dq`.
    fn dynamics_derivatives(y: &[f64]) -> ([[f64; 7]; 7], [[f64; 7]; 7]) {
        use andrews_constants::*;
        let (q, v, w, la) = (&y[0..7], &y[7..14], &y[14..21], &y[21..27]);
        let (b, t, g, p, d, o, ep) = (q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
        let (s1, c1) = t.sin_cos();
        let (s3, c3) = p.sin_cos();
        let (s5, c5) = o.sin_cos();
        let (sb, cb) = b.sin_cos();
        let (sbt, cbt) = (b + t).sin_cos();
        let (sg, cg) = g.sin_cos();
        let (spd, cpd) = (p + d).sin_cos();
        let (sd, cd) = d.sin_cos();
        let (soe, coe) = (o + ep).sin_cos();
        let (sep, cep) = ep.sin_cos();
        let e = E - EA;
        let z = ZF - FA;
        let (c2, c4, c6) = (M2 * DA * RR, M4 * ZT * e, M6 * U * z);
        let mut dq = [[0.0; 7]; 7];
        let mut dv = [[0.0; 7]; 7];
        // d(M w)/dq: M00 and M01 = M10 through cos(theta), M34, M44 through sin(phi), M56, M66
        // through sin(Omega).
        dq[0][1] += 2.0 * c2 * s1 * w[0] + c2 * s1 * w[1];
        dq[1][1] += c2 * s1 * w[0];
        dq[3][3] += c4 * c3 * w[4];
        dq[4][3] += c4 * c3 * w[3] + 2.0 * c4 * c3 * w[4];
        dq[5][5] -= c6 * c5 * w[6];
        dq[6][5] -= c6 * c5 * w[5] + 2.0 * c6 * c5 * w[6];
        // -df/dq and -df/dv.
        dq[0][1] += c2 * v[1] * (v[1] + 2.0 * v[0]) * c1;
        dv[0][0] += 2.0 * c2 * v[1] * s1;
        dv[0][1] += 2.0 * c2 * (v[1] + v[0]) * s1;
        dq[1][1] -= c2 * v[0] * v[0] * c1;
        dv[1][0] -= 2.0 * c2 * v[0] * s1;
        dq[3][3] += c4 * v[4] * v[4] * s3;
        dv[3][4] -= 2.0 * c4 * v[4] * c3;
        dq[4][3] -= c4 * v[3] * (v[3] + 2.0 * v[4]) * s3;
        dv[4][3] += 2.0 * c4 * (v[3] + v[4]) * c3;
        dv[4][4] += 2.0 * c4 * v[3] * c3;
        dq[5][5] -= c6 * v[6] * v[6] * s5;
        dv[5][6] += 2.0 * c6 * v[6] * c5;
        dq[6][5] += c6 * v[5] * (v[5] + 2.0 * v[6]) * s5;
        dv[6][5] -= 2.0 * c6 * (v[5] + v[6]) * c5;
        dv[6][6] -= 2.0 * c6 * v[5] * c5;
        // The spring: f2 = force(l) (dx a + dy b) with (a, b) = d(xd, yd)/dgamma.
        let (dx, dy) = (SD * cg + SC * sg + XB - XC, SD * sg - SC * cg + YB - YC);
        let (a, bb) = (SC * cg - SD * sg, SD * cg + SC * sg);
        let (da_, db_) = (-SC * sg - SD * cg, -SD * sg + SC * cg);
        let lg = (dx * dx + dy * dy).sqrt();
        let s = dx * a + dy * bb;
        let force = -C0 * (lg - L0) / lg;
        let dforce = -C0 * L0 * (s / lg) / (lg * lg);
        let ds = a * a + bb * bb + dx * da_ + dy * db_;
        dq[2][2] -= dforce * s + force * ds;
        // d(G^T lambda)/dq: the Hessians of the constraints, contracted with lambda.
        let (lx, ly) = (la[0] + la[2] + la[4], la[1] + la[3] + la[5]);
        dq[0][0] += lx * (-RR * cb + D * cbt) + ly * (-RR * sb + D * sbt);
        let h01 = D * (lx * cbt + ly * sbt);
        dq[0][1] += h01;
        dq[1][0] += h01;
        dq[1][1] += h01;
        dq[2][2] += SS * (la[0] * sg - la[1] * cg);
        let h34 = E * (la[2] * spd - la[3] * cpd);
        dq[3][3] += h34;
        dq[3][4] += h34;
        dq[4][3] += h34;
        dq[4][4] += h34 + ZT * (la[2] * cd + la[3] * sd);
        let h56 = ZF * (la[4] * coe + la[5] * soe);
        dq[5][5] += h56;
        dq[5][6] += h56;
        dq[6][5] += h56;
        dq[6][6] += h56 + U * (la[4] * sep - la[5] * cep);
        (dq, dv)
    }

    /// Rows `0..21` of the iteration matrix, the same in every formulation: `c I` and `-I` of
    /// the kinematic rows `q' = v`, `v' = w`; `M(q)`, `G(q)^T` and the derivatives in `q` and
    /// `v` ([`Self::dynamics_derivatives`]) of the dynamic rows.
    fn kinematic_and_dynamic_rows<S: MatrixSink + ?Sized>(y: &[f64], c: f64, m: &mut S) {
        for i in 0..14 {
            m.set(i, i, c);
            m.set(i, i + 7, -1.0);
        }
        let q = &y[0..7];
        let mass = Self::mass(q);
        let g = Self::constraint_jacobian(q);
        for i in 0..7 {
            for j in 0..7 {
                if mass[i][j] != 0.0 {
                    m.set(14 + i, 14 + j, mass[i][j]);
                }
            }
            for r in 0..6 {
                if g[r][i] != 0.0 {
                    m.set(14 + i, 21 + r, g[r][i]);
                }
            }
        }
        let (dq, dv) = Self::dynamics_derivatives(y);
        for i in 0..7 {
            for j in 0..7 {
                if dq[i][j] != 0.0 {
                    m.set(14 + i, j, dq[i][j]);
                }
                if dv[i][j] != 0.0 {
                    m.set(14 + i, 7 + j, dv[i][j]);
                }
            }
        }
    }
}

impl ImplicitDae for Andrews {
    fn dimension(&self) -> usize {
        27
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        for i in 0..14 {
            out[i] = yp[i] - y[i + 7];
        }
        out[14..21].copy_from_slice(&Self::dynamics(y));
        out[21..27].copy_from_slice(&Self::constraints(&y[0..7]));
    }
    /// Exact, written by hand as the `model!` macro would generate it: besides `c I`, `M(q)`
    /// and `G(q)`, the seven dynamic rows' derivatives in `q` and `v`
    /// ([`Self::dynamics_derivatives`]).
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        Self::kinematic_and_dynamic_rows(y, c, m);
        write_rows(21, &Self::constraint_jacobian(&y[0..7]), m);
    }
    /// The identity on the positions and velocities (`q' = v`, `v' = w`; the dynamic and
    /// constraint rows have no derivatives).
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..14 {
            m.set(i, i, 1.0);
        }
        true
    }
    /// The constraint rows `y22..y27` of the iteration matrix, written by hand.
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, _: f64, y: &[f64], out: &mut S) -> bool {
        write_rows(21, &Self::constraint_jacobian(&y[0..7]), out);
        true
    }
    /// Andrews' constraints do not depend on `t`.
    fn constraint_time_derivative(&self, _: f64, _: &[f64], _: &mut [f64]) -> bool {
        true
    }
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        v: &[f64],
        out: &mut S,
    ) -> bool {
        write_rows(21, &Self::constraint_curvature(&y[0..7], &v[0..7]), out);
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 14
    }
    fn unknown_name(&self, i: usize) -> String {
        format!("y{}", i + 1)
    }
}

/// The formulations of Andrews' mechanism (Hairer & Wanner, *Solving ODEs II*, Section VII.7;
/// the Test Set's problem description): the same 27 unknowns `y = (q, v, w, lambda)` and the
/// same rows `1..21`; rows `22..27` are the position constraints `g(q) = 0` (index 3), the
/// velocity constraints `G(q) v = 0` (index 2) or the acceleration constraints
/// `G(q) w + g_qq(q)(v, v) = 0` (index 1). The index-3 start ([`Andrews::initial`]) is
/// consistent for each: it satisfies `g = 0`, has `v = 0` and `G(q) w = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AndrewsForm {
    /// The position constraints: [`Andrews`].
    Index3,
    /// The velocity constraints `G(q) v = 0`.
    Index2,
    /// The acceleration constraints `G(q) w + g_qq(q)(v, v) = 0`.
    Index1,
}

impl AndrewsForm {
    /// The three formulations, index 3 first.
    pub const ALL: [Self; 3] = [Self::Index3, Self::Index2, Self::Index1];

    /// The differential index of the formulation.
    pub fn dae_index(self) -> u8 {
        match self {
            Self::Index3 => 3,
            Self::Index2 => 2,
            Self::Index1 => 1,
        }
    }

    /// Index per unknown, as Hairer & Wanner's codes count it (RADAU5's `nind1, nind2, nind3`):
    /// index 3: `q` 1, `v` 2, `w` and `lambda` 3 ([`andrews_index`]); index 2: `q` and `v` 1,
    /// `w` and `lambda` 2; index 1: all 27 of index 1.
    pub fn index(self) -> Vec<u8> {
        match self {
            Self::Index3 => andrews_index(),
            Self::Index2 => {
                let mut v = vec![1u8; 14];
                v.extend([2u8; 13]);
                v
            }
            Self::Index1 => vec![1u8; 27],
        }
    }

    /// The unknowns of index 1 (those of larger index follow them).
    pub fn differential(self) -> usize {
        match self {
            Self::Index3 => 7,
            Self::Index2 => 14,
            Self::Index1 => 27,
        }
    }

    /// The curvature terms `g_qq(q)(v, v)` of the acceleration constraints: row `r` is
    /// `sum_k C_rk v_k` with `C` = [`Andrews::constraint_curvature`]`(q, v)` (the second time
    /// derivative of `g` along `q' = v`, `v' = w` is `G(q) w + C(q, v) v`).
    fn curvature_terms(q: &[f64], v: &[f64]) -> [f64; 6] {
        let c = Andrews::constraint_curvature(q, v);
        c.map(|row| (0..7).map(|k| row[k] * v[k]).sum())
    }

    /// The derivatives of [`Self::curvature_terms`] in `q` (row `r`, column `k`), by hand from
    /// the terms written out: `-RR cos(b) v0^2 + D cos(b + t) (v0 + v1)^2 + SS sin(g) v2^2`
    /// (row 1) and so on; in `v` they are `2 C(q, v)` (the constraints' Hessians are symmetric).
    fn curvature_terms_dq(q: &[f64], v: &[f64]) -> [[f64; 7]; 6] {
        use andrews_constants::*;
        let (b, t, g, p, d, o, ep) = (q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
        let (sb, cb) = b.sin_cos();
        let (sbt, cbt) = (b + t).sin_cos();
        let (sg, cg) = g.sin_cos();
        let (spd, cpd) = (p + d).sin_cos();
        let (sd, cd) = d.sin_cos();
        let (soe, coe) = (o + ep).sin_cos();
        let (sep, cep) = ep.sin_cos();
        let v0 = v[0] * v[0];
        let v01 = (v[0] + v[1]) * (v[0] + v[1]);
        let v2 = v[2] * v[2];
        let v34 = (v[3] + v[4]) * (v[3] + v[4]);
        let v4 = v[4] * v[4];
        let v56 = (v[5] + v[6]) * (v[5] + v[6]);
        let v6 = v[6] * v[6];
        let mut m = [[0.0; 7]; 6];
        // The crank's terms, -RR cos(b) v0^2 + D cos(b + t) v01^2 in the x rows (even) and
        // -RR sin(b) v0^2 + D sin(b + t) v01^2 in the y rows (odd).
        for r in [0, 2, 4] {
            m[r][0] = RR * sb * v0 - D * sbt * v01;
            m[r][1] = -D * sbt * v01;
            m[r + 1][0] = -RR * cb * v0 + D * cbt * v01;
            m[r + 1][1] = D * cbt * v01;
        }
        // SS sin(g) v2^2, -SS cos(g) v2^2.
        m[0][2] = SS * cg * v2;
        m[1][2] = SS * sg * v2;
        // E sin(p + d) v34^2 + ZT cos(d) v4^2, -E cos(p + d) v34^2 + ZT sin(d) v4^2.
        m[2][3] = E * cpd * v34;
        m[2][4] = E * cpd * v34 - ZT * sd * v4;
        m[3][3] = E * spd * v34;
        m[3][4] = E * spd * v34 + ZT * cd * v4;
        // ZF cos(o + ep) v56^2 + U sin(ep) v6^2, ZF sin(o + ep) v56^2 - U cos(ep) v6^2.
        m[4][5] = -ZF * soe * v56;
        m[4][6] = -ZF * soe * v56 + U * cep * v6;
        m[5][5] = ZF * coe * v56;
        m[5][6] = ZF * coe * v56 + U * sep * v6;
        m
    }
}

impl ImplicitDae for AndrewsForm {
    fn dimension(&self) -> usize {
        27
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        Andrews.residual(t, y, yp, out);
        let (q, v, w) = (&y[0..7], &y[7..14], &y[14..21]);
        let g = Andrews::constraint_jacobian(q);
        match self {
            Self::Index3 => {}
            Self::Index2 => {
                for r in 0..6 {
                    out[21 + r] = (0..7).map(|j| g[r][j] * v[j]).sum();
                }
            }
            Self::Index1 => {
                let h = Self::curvature_terms(q, v);
                for r in 0..6 {
                    out[21 + r] = (0..7).map(|j| g[r][j] * w[j]).sum::<f64>() + h[r];
                }
            }
        }
    }
    /// Exact: rows `1..21` as [`Andrews`]; rows `22..27` of the index-2 form `C(q, v)` in `q`
    /// and `G(q)` in `v`, of the index-1 form `C(q, w)` plus the curvature terms' derivative in
    /// `q`, `2 C(q, v)` in `v` and `G(q)` in `w`.
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (q, v, w) = (&y[0..7], &y[7..14], &y[14..21]);
        match self {
            Self::Index3 => Andrews.iteration_matrix(t, y, yp, c, m),
            Self::Index2 => {
                Andrews::kinematic_and_dynamic_rows(y, c, m);
                let g = Andrews::constraint_jacobian(q);
                let cv = Andrews::constraint_curvature(q, v);
                for r in 0..6 {
                    for j in 0..7 {
                        if cv[r][j] != 0.0 {
                            m.set(21 + r, j, cv[r][j]);
                        }
                        if g[r][j] != 0.0 {
                            m.set(21 + r, 7 + j, g[r][j]);
                        }
                    }
                }
            }
            Self::Index1 => {
                Andrews::kinematic_and_dynamic_rows(y, c, m);
                let g = Andrews::constraint_jacobian(q);
                let cv = Andrews::constraint_curvature(q, v);
                let cw = Andrews::constraint_curvature(q, w);
                let hq = Self::curvature_terms_dq(q, v);
                for r in 0..6 {
                    for j in 0..7 {
                        let dq = cw[r][j] + hq[r][j];
                        if dq != 0.0 {
                            m.set(21 + r, j, dq);
                        }
                        if cv[r][j] != 0.0 {
                            m.set(21 + r, 7 + j, 2.0 * cv[r][j]);
                        }
                        if g[r][j] != 0.0 {
                            m.set(21 + r, 14 + j, g[r][j]);
                        }
                    }
                }
            }
        }
    }
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        m: &mut S,
    ) -> bool {
        Andrews.mass_matrix(t, y, yp, m)
    }
    /// The position constraints of the index-3 form; the other forms have none (their rows
    /// `22..27` depend on `v` and `w`).
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, t: f64, y: &[f64], out: &mut S) -> bool {
        *self == Self::Index3 && Andrews.constraint_gradient(t, y, out)
    }
    fn constraint_time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) -> bool {
        *self == Self::Index3 && Andrews.constraint_time_derivative(t, y, out)
    }
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        v: &[f64],
        out: &mut S,
    ) -> bool {
        *self == Self::Index3 && Andrews.constraint_curvature(t, y, v, out)
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 14
    }
    fn unknown_name(&self, i: usize) -> String {
        format!("y{}", i + 1)
    }
}

/// The car axis, index 3 (Test Set `caraxis.F`; Hairer & Wanner): unknowns
/// `(xl, yl, xr, yr, ul, vl, ur, vr, lambda1, lambda2)`, mass-matrix form
/// `diag(1, 1, 1, 1, k, k, k, k, 0, 0) y' = phi(t, y)` with `k = M eps^2 / 2`.
#[derive(Debug, Clone, Copy)]
pub struct CarAxis {
    /// `eps` (Test Set: `1e-2`).
    pub eps: f64,
    /// Mass `M` (10).
    pub m: f64,
    /// Axis length `L` (1).
    pub l: f64,
    /// Spring rest length `L0` (1/2).
    pub l0: f64,
    /// Bump amplitude `r` (0.1).
    pub r: f64,
    /// Bump frequency `omega` (10).
    pub w: f64,
    /// Gravity `g` (1).
    pub g: f64,
}

impl Default for CarAxis {
    fn default() -> Self {
        Self {
            eps: 1e-2,
            m: 10.0,
            l: 1.0,
            l0: 0.5,
            r: 0.1,
            w: 10.0,
            g: 1.0,
        }
    }
}

/// Interval end of [`CarAxis`].
pub const CAR_AXIS_T_END: f64 = 3.0;

/// Differential index per unknown (deTestSet `nind = c(4, 4, 2)`).
pub const CAR_AXIS_INDEX: [u8; 10] = [1, 1, 1, 1, 2, 2, 2, 2, 3, 3];

/// Reference solution at `t = 3` (deTestSet `reference("caraxis")`).
#[allow(clippy::excessive_precision)]
pub const CAR_AXIS_REF: [f64; 10] = [
    0.493455784275402809122e-1,
    0.496989460230171153861,
    0.104174252488542151681e+1,
    0.373911027265361256927,
    -0.770583684040972357970e-1,
    0.744686658723778553466e-2,
    0.175568157537232222276e-1,
    0.770341043779251976443,
    -0.473688659084893324729e-2,
    -0.110468033125734368808e-2,
];

impl CarAxis {
    /// Unknowns of index 1 in the stabilised form (the positions and velocities).
    pub const STABILISED_DIFFERENTIAL: usize = 8;

    /// The stabilised index-2 form: the constraints `y9`, `y10`, each position `y1..y4` with
    /// its kinematic row.
    pub fn stabilised(self) -> Stabilised<CarAxis> {
        Stabilised::new(self, vec![8, 9], (0..4).map(|j| (j, j)).collect())
            .expect("the car axis' constraint rows")
    }

    fn k(&self) -> f64 {
        self.m * self.eps * self.eps / 2.0
    }
    fn road(&self, t: f64) -> (f64, f64) {
        let yb = self.r * (self.w * t).sin();
        ((self.l * self.l - yb * yb).sqrt(), yb)
    }
    /// The road's time derivative `(xb', yb')` at `t`.
    fn road_rate(&self, t: f64) -> (f64, f64) {
        let (xb, yb) = self.road(t);
        let ybp = self.r * self.w * (self.w * t).cos();
        (-yb * ybp / xb, ybp)
    }
    /// Test Set initial values `(y0, y0')`.
    pub fn initial(&self) -> ([f64; 10], [f64; 10]) {
        (
            [0.0, 0.5, 1.0, 0.5, -0.5, 0.0, -0.5, 0.0, 0.0, 0.0],
            [-0.5, 0.0, -0.5, 0.0, 0.0, -self.g, 0.0, -self.g, 0.0, 0.0],
        )
    }
}

impl ImplicitDae for CarAxis {
    fn dimension(&self) -> usize {
        10
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let (xl, yl, xr, yr) = (y[0], y[1], y[2], y[3]);
        let (l1, l2) = (y[8], y[9]);
        let (xb, yb) = self.road(t);
        let ll = (xl * xl + yl * yl).sqrt();
        let lr = ((xr - xb).powi(2) + (yr - yb).powi(2)).sqrt();
        let k = self.k();
        for i in 0..4 {
            out[i] = yp[i] - y[i + 4];
        }
        out[4] = k * yp[4] - ((self.l0 - ll) * xl / ll + l1 * xb + 2.0 * l2 * (xl - xr));
        out[5] =
            k * yp[5] - ((self.l0 - ll) * yl / ll + l1 * yb + 2.0 * l2 * (yl - yr) - k * self.g);
        out[6] = k * yp[6] - ((self.l0 - lr) * (xr - xb) / lr - 2.0 * l2 * (xl - xr));
        out[7] = k * yp[7] - ((self.l0 - lr) * (yr - yb) / lr - 2.0 * l2 * (yl - yr) - k * self.g);
        out[8] = xb * xl + yb * yl;
        out[9] = (xl - xr).powi(2) + (yl - yr).powi(2) - self.l * self.l;
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (xl, yl, xr, yr) = (y[0], y[1], y[2], y[3]);
        let l2 = y[9];
        let (xb, yb) = self.road(t);
        let k = self.k();
        let l0 = self.l0;
        for i in 0..4 {
            m.set(i, i, c);
            m.set(i, i + 4, -1.0);
            m.set(i + 4, i + 4, k * c);
        }
        let ll3 = (xl * xl + yl * yl).powf(1.5);
        let (dx, dy) = (xr - xb, yr - yb);
        let lr3 = (dx * dx + dy * dy).powf(1.5);
        // d/d(x, y) of (L0 - |p|) p / |p| = L0 p/|p| - p.
        m.set(4, 0, -(l0 * yl * yl / ll3 - 1.0) - 2.0 * l2);
        m.set(4, 1, l0 * xl * yl / ll3);
        m.set(4, 2, 2.0 * l2);
        m.set(4, 8, -xb);
        m.set(4, 9, -2.0 * (xl - xr));
        m.set(5, 0, l0 * xl * yl / ll3);
        m.set(5, 1, -(l0 * xl * xl / ll3 - 1.0) - 2.0 * l2);
        m.set(5, 3, 2.0 * l2);
        m.set(5, 8, -yb);
        m.set(5, 9, -2.0 * (yl - yr));
        m.set(6, 2, -(l0 * dy * dy / lr3 - 1.0) - 2.0 * l2);
        m.set(6, 3, l0 * dx * dy / lr3);
        m.set(6, 0, 2.0 * l2);
        m.set(6, 9, 2.0 * (xl - xr));
        m.set(7, 2, l0 * dx * dy / lr3);
        m.set(7, 3, -(l0 * dx * dx / lr3 - 1.0) - 2.0 * l2);
        m.set(7, 1, 2.0 * l2);
        m.set(7, 9, 2.0 * (yl - yr));
        self.constraint_gradient(t, y, m);
    }
    /// `diag(1, 1, 1, 1, k, k, k, k, 0, 0)`.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        let k = self.k();
        for i in 0..4 {
            m.set(i, i, 1.0);
            m.set(i + 4, i + 4, k);
        }
        true
    }
    /// The constraint rows `y9`, `y10` of the iteration matrix.
    fn constraint_gradient<S: MatrixSink + ?Sized>(&self, t: f64, y: &[f64], m: &mut S) -> bool {
        let (xb, yb) = self.road(t);
        let (dx, dy) = (y[0] - y[2], y[1] - y[3]);
        m.set(8, 0, xb);
        m.set(8, 1, yb);
        m.set(9, 0, 2.0 * dx);
        m.set(9, 2, -2.0 * dx);
        m.set(9, 1, 2.0 * dy);
        m.set(9, 3, -2.0 * dy);
        true
    }
    /// The first constraint moves with the road: `d/dt (xb xl + yb yl) = xb' xl + yb' yl`.
    fn constraint_time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) -> bool {
        let (xbp, ybp) = self.road_rate(t);
        out[8] = xbp * y[0] + ybp * y[1];
        true
    }
    /// `d/dq (G v + dg/dt)`: `(xb', yb', 0, 0)` for the first constraint (its gradient does not
    /// depend on `q`), `2 (v_l - v_r)` with the signs of `G` for the axis' length.
    fn constraint_curvature<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        _: &[f64],
        v: &[f64],
        m: &mut S,
    ) -> bool {
        let (xbp, ybp) = self.road_rate(t);
        let (dvx, dvy) = (v[0] - v[2], v[1] - v[3]);
        m.set(8, 0, xbp);
        m.set(8, 1, ybp);
        m.set(9, 0, 2.0 * dvx);
        m.set(9, 2, -2.0 * dvx);
        m.set(9, 1, 2.0 * dvy);
        m.set(9, 3, -2.0 * dvy);
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 8
    }
    fn unknown_name(&self, i: usize) -> String {
        [
            "xl", "yl", "xr", "yr", "ul", "vl", "ur", "vr", "lambda1", "lambda2",
        ][i]
            .to_string()
    }
}
