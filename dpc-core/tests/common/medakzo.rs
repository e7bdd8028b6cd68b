//! The Test Set's Medical Akzo Nobel problem (`medakzo.f`; Mazzia, Magherini et al., the Test
//! Set for IVP solvers), written anew from its mathematical definition: the penetration of
//! radio-labelled antibodies into tumour tissue, a reaction-diffusion PDE in one space variable
//! brought by the method of lines to an ODE of 400 unknowns, integrated here as the implicit
//! DAE `F(t, y, y') = y' - f(t, y)` with an identity mass matrix.
//!
//! On the grid `zeta_j = j dzeta`, `j = 1..N`, `N = 200`, `dzeta = 1/N`, the unknowns are
//! interleaved, `y = (u_1, v_1, u_2, v_2, ..., u_N, v_N)` (0-based: `u_j` at `2 (j - 1)`, `v_j`
//! right after it), so that the Jacobian is a band with half-bandwidths 2 (the Test Set's
//! `mljac = mujac = 2`). With `k = 100`, `c = 4`,
//!
//! ```text
//! u_j' = beta_j (u_{j-1} - 2 u_j + u_{j+1}) / dzeta^2
//!        + alpha_j (u_{j+1} - u_{j-1}) / (2 dzeta) - k u_j v_j,
//! v_j' = -k u_j v_j,
//! alpha_j = 2 (zeta_j - 1)^3 / c^2,   beta_j = (zeta_j - 1)^4 / c^2,
//! ```
//!
//! with the boundary input `u_0 = phi(t)`, `phi = 2` for `t <= 5` and `0` after (the injection
//! stops at `t = 5`). At `zeta_N = 1` both coefficients vanish and `u_N' = -k u_N v_N`: no
//! `u_{N+1}` enters (the Test Set's last rows). The initial values are `u = 0`, `v = 1`; the
//! interval is `[0, 20]`.
//!
//! The boundary input jumps at `t = 5`: `y` is continuous there, `y'` jumps in `u_1'` alone
//! (by about `-4.9e3`). The Test Set declares that point (`ndisc = 1`, `t = (0, 5, 20)` in its
//! problem routine, as the MESA transcription of it in its numerics test suite shows) and its
//! drivers integrate the two pieces one after the other, each a call of the solver of its own.
//! The peer table does the same in each of the three codes: it stops at
//! [`MEDAKZO_T_SWITCH`] and restarts there from `(y(5), f(5+, y(5)))`
//! ([`Medakzo::slope_after_switch`]; dpc's `reinit`, IDA's `IDAReInit`, a new diffsol state),
//! the statistics of both pieces added. Continuing across the jump without a restart (the
//! history before it then predicts the old slope) costs the BDF error-test failures until a
//! step of about `Delta y' h` within the tolerance is found, `h` below `1e-16` at
//! `rtol = atol = 1e-12`, where it fails; integrating straight through is measured in
//! `tests/medakzo.rs` (ignored) beside the restart.
//!
//! The reference at `t = 20` ([`MEDAKZO_REF`]) is the Test Set's `solut` (PSIDE at
//! `rtol = atol = 1e-10` on a Cray C90, as its comment says), read from two independent
//! transcriptions that agree digit for digit: the DASSL driver `tests/medakzo.f` of John
//! Ernsthausen's DASSL repository (its `SOLUT`) and the final values of the `AkzoNobel`
//! problem in ReaK's integrator unit tests. dpc's Radau and BDF at `rtol = atol = 1e-12`
//! reach 9.76 and 10.15 of its digits in the measure below and 9.99 of each other's
//! (`tests/medakzo.rs`, `reference_agrees_with_tight_runs`): the reference is good to about
//! `1e-10`, far beyond the table's `1e-8`.
//!
//! Scoring ([`medakzo_scd`]): all 400 components with the mixed error
//! `|y_i - r_i| / (1 + |r_i|)`, the Test Set's `mescd` at `rtol = atol`. The relative error of
//! the Test Set's plain `scd` means nothing here: half the reference values are below `1e-20`
//! (the `v_j` left of the front are about `1e-143`, some of them negative, rounding noise of
//! PSIDE's run; the `u_j` right of it fall to `1e-164` and `0`), so the relative error of any
//! run is astronomically large there. Since every reference value is at most 1, the mixed
//! error is the absolute error (within a factor 2), the quantity the integrators control at
//! `atol = rtol` for values below 1 (the `u_j` are at most `3.7e-4`), and the measure the DASSL
//! driver above prints (`SCD of norm(Y-Exact, infty)`, the absolute error over all 400).
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// Grid points.
pub const MEDAKZO_N: usize = 200;
/// Unknowns: `(u_j, v_j)` per grid point.
pub const MEDAKZO_DIM: usize = 2 * MEDAKZO_N;
/// Half-bandwidths of the iteration matrix (upper and lower).
pub const MEDAKZO_HALF_BANDWIDTH: usize = 2;
/// End of the interval.
pub const MEDAKZO_T_END: f64 = 20.0;
/// The time the boundary input switches off (`phi = 2` up to and including it, 0 after).
pub const MEDAKZO_T_SWITCH: f64 = 5.0;
/// Reaction rate `k`.
const K: f64 = 100.0;
/// The constant `c` of the coefficients.
const C: f64 = 4.0;
/// `dzeta = 1/N`.
const DZ: f64 = 1.0 / MEDAKZO_N as f64;

/// The Medical Akzo Nobel problem ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct Medakzo;

/// The boundary input `phi(t)`.
pub fn medakzo_phi(t: f64) -> f64 {
    if t <= MEDAKZO_T_SWITCH {
        2.0
    } else {
        0.0
    }
}

/// `(a, b, d)` of grid point `j` (1-based): the coefficients of `u_{j-1}`, `u_j` and `u_{j+1}`
/// in the transport part of `u_j'`, `beta / dzeta^2 -+ alpha / (2 dzeta)` and
/// `-2 beta / dzeta^2`.
fn stencil(j: usize) -> (f64, f64, f64) {
    let s = j as f64 * DZ - 1.0;
    let alpha = 2.0 * s * s * s / (C * C);
    let beta = s * s * s * s / (C * C);
    let diffusion = beta / (DZ * DZ);
    let convection = alpha / (2.0 * DZ);
    (
        diffusion - convection,
        -2.0 * diffusion,
        diffusion + convection,
    )
}

/// `f` with the boundary value `u_0 = phi` into `out`.
fn f_with_input(phi: f64, y: &[f64], out: &mut [f64]) {
    let n = MEDAKZO_N;
    for j in 1..=n {
        let (iu, iv) = (2 * (j - 1), 2 * (j - 1) + 1);
        let reaction = -K * y[iu] * y[iv];
        let transport = if j == n {
            // zeta = 1: alpha = beta = 0.
            0.0
        } else {
            let left = if j == 1 { phi } else { y[iu - 2] };
            let (a, b, d) = stencil(j);
            a * left + b * y[iu] + d * y[iu + 2]
        };
        out[iu] = transport + reaction;
        out[iv] = reaction;
    }
}

impl Medakzo {
    /// `(y(0), y'(0) = f(0, y(0)))`: `u = 0`, `v = 1`, consistent.
    pub fn initial() -> (Vec<f64>, Vec<f64>) {
        let y: Vec<f64> = (0..MEDAKZO_DIM)
            .map(|i| if i.is_multiple_of(2) { 0.0 } else { 1.0 })
            .collect();
        let mut yp = vec![0.0; MEDAKZO_DIM];
        Medakzo.f(0.0, &y, &mut yp);
        (y, yp)
    }

    /// `f(t, y)` into `out`.
    pub fn f(&self, t: f64, y: &[f64], out: &mut [f64]) {
        f_with_input(medakzo_phi(t), y, out);
    }

    /// `f(5+, y)`: the slope after the input switched off, the `y'` of the restart at
    /// [`MEDAKZO_T_SWITCH`].
    pub fn slope_after_switch(y: &[f64]) -> Vec<f64> {
        let mut yp = vec![0.0; MEDAKZO_DIM];
        f_with_input(0.0, y, &mut yp);
        yp
    }

    /// Every structurally non-zero entry `(row, column, df_row/dy_column)` of `df/dy` at `y`
    /// (each once; `f` depends on `t` only through the boundary value, not on `y`).
    pub fn jacobian(&self, y: &[f64], mut entry: impl FnMut(usize, usize, f64)) {
        let n = MEDAKZO_N;
        for j in 1..=n {
            let (iu, iv) = (2 * (j - 1), 2 * (j - 1) + 1);
            let (u, v) = (y[iu], y[iv]);
            if j < n {
                let (a, b, d) = stencil(j);
                if j > 1 {
                    entry(iu, iu - 2, a);
                }
                entry(iu, iu, b - K * v);
                entry(iu, iu + 2, d);
            } else {
                entry(iu, iu, -K * v);
            }
            entry(iu, iv, -K * u);
            entry(iv, iu, -K * v);
            entry(iv, iv, -K * u);
        }
    }

    /// The structure of `df/dy` (which holds the diagonal): the pattern of the iteration
    /// matrix, 1 197 entries in the band of half-bandwidths 2.
    pub fn pattern() -> Vec<(usize, usize)> {
        let y = vec![0.0; MEDAKZO_DIM];
        let mut p = Vec::with_capacity(6 * MEDAKZO_N);
        Medakzo.jacobian(&y, |r, c, _| p.push((r, c)));
        p
    }
}

impl ImplicitDae for Medakzo {
    fn dimension(&self) -> usize {
        MEDAKZO_DIM
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.f(t, y, out);
        for (o, p) in out.iter_mut().zip(yp) {
            *o = p - *o;
        }
    }

    /// `c I - df/dy`, exact.
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _t: f64,
        y: &[f64],
        _yp: &[f64],
        c: f64,
        out: &mut S,
    ) {
        self.jacobian(y, |r, k, v| {
            out.set(r, k, if r == k { c - v } else { -v });
        });
    }

    /// The identity (an ODE).
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..MEDAKZO_DIM {
            m.set(i, i, 1.0);
        }
        true
    }

    fn is_differential(&self, _: usize) -> bool {
        true
    }

    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        Some(Self::pattern())
    }

    fn equation_name(&self, i: usize) -> String {
        format!("d{}/dt", self.unknown_name(i))
    }

    fn unknown_name(&self, i: usize) -> String {
        let which = if i.is_multiple_of(2) { "u" } else { "v" };
        format!("{which}{}", i / 2 + 1)
    }
}

/// The digits of `y` at `t = 20` against [`MEDAKZO_REF`]: `-log10` of the largest mixed
/// error `|y_i - r_i| / (1 + |r_i|)` over all 400 components ([module documentation](self));
/// NaN when a component is NaN: the Test Set's `mescd` at `rtol = atol`
/// ([`crate::testset_index3::mescd`], which every user of this fixture also includes).
pub fn medakzo_scd(y: &[f64]) -> f64 {
    let all: Vec<usize> = (0..MEDAKZO_DIM).collect();
    crate::testset_index3::mescd(y, &MEDAKZO_REF, &all, 1.0, 1.0)
}

/// The Test Set's reference solution at `t = 20` (`solut` of `medakzo.f`), in its order
/// `(u_1, v_1, u_2, v_2, ...)`.
#[allow(clippy::excessive_precision)]
pub const MEDAKZO_REF: [f64; MEDAKZO_DIM] = [
    0.5113983840919909e-5,
    0.1925112884312553e-143,
    0.1027858770570419e-4,
    0.1890518289312031e-142,
    0.1549349862635799e-4,
    0.1774199325357386e-142,
    0.2075835344757462e-4,
    0.5897341137981092e-143,
    0.2607273610116854e-4,
    0.1093527900908030e-143,
    0.3143617475695002e-4,
    0.1188834841626416e-144,
    0.3684813884509626e-4,
    0.9968323236025642e-147,
    0.4230803594492533e-4,
    -0.2801994001528093e-146,
    0.4781520853483223e-4,
    -0.7337417669341249e-147,
    0.5336893059800053e-4,
    -0.1209033101530330e-147,
    0.5896840407836044e-4,
    -0.1430357497530360e-148,
    0.6461275518112516e-4,
    -0.1063952641824646e-149,
    0.7030103051210320e-4,
    0.7939969136126717e-152,
    0.7603219304985662e-4,
    0.1568246940545520e-150,
    0.8180511794465543e-4,
    0.4074950357924872e-150,
    0.8761858813806752e-4,
    0.5592746648679992e-150,
    0.9347128979692480e-4,
    -0.5510388943414421e-151,
    0.9936180755532036e-4,
    -0.2724738349250769e-149,
    0.1052886195582220e-3,
    -0.9327772452398718e-149,
    0.1112500923002360e-3,
    -0.2182885200987554e-148,
    0.1172444752530255e-3,
    -0.4041450806475518e-148,
    0.1232698952748828e-3,
    -0.5608157478395261e-148,
    0.1293243507959787e-3,
    -0.2639662630908699e-148,
    0.1354057057728661e-3,
    0.1801866277537073e-147,
    0.1415116834059119e-3,
    0.8464449882759417e-147,
    0.1476398596134615e-3,
    0.2245234937355967e-146,
    0.1537876562567258e-3,
    0.3359213489153582e-146,
    0.1599523341096154e-3,
    -0.3085721171916412e-146,
    0.1661309855680449e-3,
    -0.4465322607423735e-145,
    0.1723205270935920e-3,
    -0.1970925996866384e-144,
    0.1785176913868402e-3,
    -0.6070953121563027e-144,
    0.1847190192862588e-3,
    -0.1412011918930335e-143,
    0.1909208513890961e-3,
    -0.2378861987352203e-143,
    0.1971193193914910e-3,
    -0.2380432473186974e-143,
    0.2033103371458565e-3,
    -0.6522557638254663e-145,
    0.2094895914345677e-3,
    0.1784305601809064e-143,
    0.2156525324601176e-3,
    -0.1007474781780816e-142,
    0.2217943640531935e-3,
    -0.5281511349479423e-142,
    0.2279100336016016e-3,
    -0.1117525482975987e-141,
    0.2339942217046434e-3,
    -0.1127916494884468e-141,
    0.2400413315594459e-3,
    -0.1633306916231411e-142,
    0.2460454780878912e-3,
    0.2708874035585891e-143,
    0.2520004768152150e-3,
    -0.2501941069702609e-142,
    0.2578998325140575e-3,
    -0.2642308070750020e-141,
    0.2637367276308081e-3,
    -0.3684887530751217e-139,
    0.2695040105145025e-3,
    -0.3647274179805887e-138,
    0.2751941834723564e-3,
    -0.1255641406397419e-137,
    0.2807993906802854e-3,
    -0.1694257216823904e-138,
    0.2863114059815211e-3,
    -0.1785516142939602e-136,
    0.2917216206117258e-3,
    -0.3935939757647002e-135,
    0.2970210308948898e-3,
    -0.2514765666933440e-134,
    0.3022002259608294e-3,
    -0.7200873856605984e-134,
    0.3072493755423352e-3,
    -0.7539683247227422e-134,
    0.3121582179180383e-3,
    0.3738577086039426e-135,
    0.3169160480759169e-3,
    -0.2493582962172335e-131,
    0.3215117061821543e-3,
    0.3039632438293726e-130,
    0.3259335664508512e-3,
    0.5321044068586611e-128,
    0.3301695265219917e-3,
    -0.1918129324351378e-126,
    0.3342069974681551e-3,
    -0.1336929159252586e-124,
    0.3380328945648600e-3,
    0.9521748754010357e-123,
    0.3416336289752354e-3,
    0.1001197393324181e-120,
    0.3449951005170561e-3,
    0.2703860993866771e-119,
    0.3481026916991771e-3,
    0.4365133580297076e-119,
    0.3509412632351946e-3,
    0.4898111237855383e-115,
    0.3534951512648823e-3,
    0.1621439381962246e-112,
    0.3557481665387581e-3,
    0.3003220203772183e-110,
    0.3576835958481664e-3,
    0.5931668289615909e-108,
    0.3592842060126915e-3,
    0.2235590472383775e-105,
    0.3605322507686931e-3,
    0.1025457293602057e-102,
    0.3614094809374544e-3,
    0.3496613568296336e-100,
    0.3618971582890092e-3,
    0.4767073568395508e-98,
    0.3619760735583436e-3,
    -0.2410784286794997e-95,
    0.3616265691144918e-3,
    -0.9188398110576038e-93,
    0.3608285668302233e-3,
    0.1146623087995081e-89,
    0.3595616017506735e-3,
    0.1649638439865233e-86,
    0.3578048622135169e-3,
    0.1215140240350217e-83,
    0.3555372371311931e-3,
    0.7134490346394154e-81,
    0.3527373712073181e-3,
    0.4502515392738464e-78,
    0.3493837289247301e-3,
    0.7138395988310312e-75,
    0.3454546682115489e-3,
    0.9941693919247076e-71,
    0.3409285247640208e-3,
    0.2012859826753015e-66,
    0.3357837080804970e-3,
    0.3598261520662423e-62,
    0.3299988103392750e-3,
    0.5466580008990664e-58,
    0.3235527293336597e-3,
    0.6945384844951550e-54,
    0.3164248067597393e-3,
    0.7275415527806026e-50,
    0.3085949832350532e-3,
    0.6193143746524996e-46,
    0.3000439715082906e-3,
    0.4219255556214135e-42,
    0.2907534493998412e-3,
    0.2263678154715720e-38,
    0.2807062740884081e-3,
    0.9401607967545219e-35,
    0.2698867194275612e-3,
    0.2968231730793053e-31,
    0.2582807380350103e-3,
    0.6987463944434805e-28,
    0.2458762499428408e-3,
    0.1201641789884051e-24,
    0.2326634596245027e-3,
    0.1477169946829840e-21,
    0.2186352032185982e-3,
    0.1268462422099779e-18,
    0.2037873277440060e-3,
    0.7425015664001834e-16,
    0.1881191040379240e-3,
    0.2886826929895103e-13,
    0.1716336750388461e-3,
    0.7252477041900172e-11,
    0.1543385408702044e-3,
    0.1143390654212691e-8,
    0.1362460820444338e-3,
    0.1096625145716966e-6,
    0.1173741304462833e-3,
    0.6190822732534586e-5,
    0.9774701310627047e-4,
    0.1986273404756002e-3,
    0.7740788649977313e-4,
    0.3489773624098464e-2,
    0.5657119003189305e-4,
    0.3234526094359604e-1,
    0.3643334879766658e-4,
    0.1548747348410801e0,
    0.2003152841880950e-4,
    0.4026980529594953e0,
    0.9608297851720770e-5,
    0.6649744834198490e0,
    0.4215537698495267e-5,
    0.8409284546320647e0,
    0.1753504402754791e-5,
    0.9314946676956936e0,
    0.7048158429518009e-6,
    0.9720896201631835e0,
    0.2760943506466737e-6,
    0.9890204872799944e0,
    0.1057554501281432e-6,
    0.9957930123519514e0,
    0.3965142250779033e-7,
    0.9984246531478463e0,
    0.1455273204279008e-7,
    0.9994229325942358e0,
    0.5226348147846279e-8,
    0.9997932125999319e0,
    0.1835610545325733e-8,
    0.9999275409325039e0,
    0.6301078589385454e-9,
    0.9999751869380269e0,
    0.2112538351365564e-9,
    0.9999917015131560e0,
    0.6912550453447044e-10,
    0.9999972914302640e0,
    0.2205932132514696e-10,
    0.9999991378543379e0,
    0.6860095639285670e-11,
    0.9999997325855174e0,
    0.2077324462852526e-11,
    0.9999999192384585e0,
    0.6120038908594393e-12,
    0.9999999762710279e0,
    0.1752695518797070e-12,
    0.9999999932230490e0,
    0.4875001992978682e-13,
    0.9999999981203191e0,
    0.1315706848908981e-13,
    0.9999999994941428e0,
    0.3442274192104633e-14,
    0.9999999998680372e0,
    0.8721783456154470e-15,
    0.9999999999666630e0,
    0.2137938962858872e-15,
    0.9999999999918528e0,
    0.5064735930780995e-16,
    0.9999999999980759e0,
    0.1158284928109727e-16,
    0.9999999999995613e0,
    0.2554350586347124e-17,
    0.9999999999999036e0,
    0.5425563935887811e-18,
    0.9999999999999796e0,
    0.1108623976460997e-18,
    0.9999999999999958e0,
    0.2176490922739810e-19,
    0.9999999999999992e0,
    0.4100180074816888e-20,
    0.9999999999999998e0,
    0.7401919443964595e-21,
    0.1000000000000000e1,
    0.1278745657114596e-21,
    0.1000000000000000e1,
    0.2111087049605767e-22,
    0.1000000000000000e1,
    0.3325632734364699e-23,
    0.1000000000000000e1,
    0.4991515592566292e-24,
    0.1000000000000000e1,
    0.7126950428617158e-25,
    0.1000000000000000e1,
    0.9664740804131475e-26,
    0.1000000000000000e1,
    0.1242716896959521e-26,
    0.1000000000000000e1,
    0.1512543532243458e-27,
    0.1000000000000000e1,
    0.1739533019752215e-28,
    0.1000000000000000e1,
    0.1886942537979667e-29,
    0.1000000000000000e1,
    0.1926965705022792e-30,
    0.1000000000000000e1,
    0.1849021812823421e-31,
    0.1000000000000000e1,
    0.1663798767415642e-32,
    0.1000000000000000e1,
    0.1401076830818626e-33,
    0.1000000000000000e1,
    0.1101818149402153e-34,
    0.1000000000000000e1,
    0.8074224739509168e-36,
    0.1000000000000000e1,
    0.5501249196662931e-37,
    0.1000000000000000e1,
    0.3476859813132770e-38,
    0.1000000000000000e1,
    0.2033489290876775e-39,
    0.1000000000000000e1,
    0.1097880013869247e-40,
    0.1000000000000000e1,
    0.5457825200381417e-42,
    0.1000000000000000e1,
    0.2491675366427318e-43,
    0.1000000000000000e1,
    0.1041801880291617e-44,
    0.1000000000000000e1,
    0.3978066491064419e-46,
    0.1000000000000000e1,
    0.1383174699098532e-47,
    0.1000000000000000e1,
    0.4365911791079500e-49,
    0.1000000000000000e1,
    0.1247057764661705e-50,
    0.1000000000000000e1,
    0.3212728839963712e-52,
    0.1000000000000000e1,
    0.7439366703571565e-54,
    0.1000000000000000e1,
    0.1542770387822259e-55,
    0.1000000000000000e1,
    0.2854454245592573e-57,
    0.1000000000000000e1,
    0.4693220411250150e-59,
    0.1000000000000000e1,
    0.6828458274546624e-61,
    0.1000000000000000e1,
    0.8752952529541412e-63,
    0.1000000000000000e1,
    0.9838541433761416e-65,
    0.1000000000000000e1,
    0.9649177728609193e-67,
    0.1000000000000000e1,
    0.8213596936190817e-69,
    0.1000000000000000e1,
    0.6033986647865674e-71,
    0.1000000000000000e1,
    0.3802531117966294e-73,
    0.1000000000000000e1,
    0.2042261117698575e-75,
    0.1000000000000000e1,
    0.9282595096128614e-78,
    0.1000000000000000e1,
    0.3543587864454877e-80,
    0.1000000000000000e1,
    0.1126779423370979e-82,
    0.1000000000000000e1,
    0.2957534367766753e-85,
    0.1000000000000000e1,
    0.6344600529877694e-88,
    0.1000000000000000e1,
    0.1100279075462365e-90,
    0.1000000000000000e1,
    0.1523845293461783e-93,
    0.1000000000000000e1,
    0.1662696161555950e-96,
    0.1000000000000000e1,
    0.1407578290673998e-99,
    0.1000000000000000e1,
    0.9086150803567186e-103,
    0.1000000000000000e1,
    0.4384339596163745e-106,
    0.1000000000000000e1,
    0.1545482064392824e-109,
    0.1000000000000000e1,
    0.3874172613928345e-113,
    0.1000000000000000e1,
    0.6689452219441953e-117,
    0.1000000000000000e1,
    0.7655680935317283e-121,
    0.1000000000000000e1,
    0.5538543899545850e-125,
    0.1000000000000000e1,
    0.2386173886563501e-129,
    0.1000000000000000e1,
    0.5664887497790931e-134,
    0.1000000000000000e1,
    0.6671124967149171e-139,
    0.1000000000000000e1,
    0.3351973480286951e-144,
    0.1000000000000000e1,
    0.5684315818559200e-150,
    0.1000000000000000e1,
    0.2142121793294590e-156,
    0.1000000000000000e1,
    0.6727117900187205e-164,
    0.1000000000000000e1,
    0.0,
    0.1000000000000000e1,
];
