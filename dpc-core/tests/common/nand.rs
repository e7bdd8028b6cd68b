//! The NAND gate of the Test Set for IVP Solvers (Univ. of Bari; problem `nand`, after Günther
//! and Rentrop's network model of a MOS NAND gate with Shichman-Hodges transistors): 14 node
//! potentials `y` on `t` in `[0, 80]`,
//!
//! ```text
//! C(y) y' = f(t, y),
//! ```
//!
//! with a capacitance matrix `C(y)` that depends on the state (four junction capacitances
//! `CBDBS(v)`), so that `dF/dy'` is not constant. `C(y)` is not singular (the Test Set calls the
//! problem an "index 0 IDE"): every unknown has index 0 and `dF/dy'` is regular at the start,
//! so the BDF's index-1 rules (`leading_matrix_singular`) do not apply. The inputs `V1`, `V2`
//! are trapezoidal pulses whose derivatives `V1'`, `V2'` enter `f`: `f` jumps at every multiple
//! of 5 ([`NAND_BREAKS`]), where the runs stop and continue (the Test Set drivers integrate
//! from breakpoint to breakpoint).
//!
//! Equations, constants, initial values and the reference solution are transcribed from the Test
//! Set's problem definition (`nand.f`, as its MEBDFI driver holds it), written here anew. As
//! there, the drain current for `V_DS < 0` of the enhancement transistors uses
//! `beta = 1.748e-4` (for `V_DS > 0`: `1.748e-3`); the reference was computed with these.
//!
//! The iteration matrix `dF/dy + c dF/dy'` is exact: `c C(y)`, the derivative of `C(y) y'`
//! through the junction capacitances, and `-df/dy` from the derivatives of the currents (on a
//! switch between two branches of the transistor model, those of the branch taken there).
//! `bench/ida_peer.c` has the same equations and matrix. The Test Set's drivers score `y5` only (the gate's output
//! node, [`NAND_SCORED`]).
#![allow(dead_code)]
// Equation rows and matrix entries are written by (row, column) index, as the model is.
#![allow(clippy::needless_range_loop)]

use dpc_core::{ImplicitDae, MatrixSink};

/// The NAND gate ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct Nand;

/// Interval end of [`Nand`].
pub const NAND_T_END: f64 = 80.0;

/// The discontinuities of `f` in `(0, 80]` (the pulses' corners): `5, 10, ..., 80`.
pub fn nand_breaks() -> [f64; 16] {
    std::array::from_fn(|i| 5.0 * (i + 1) as f64)
}

/// The components the Test Set scores (`y5`, zero-based 4).
pub const NAND_SCORED: [usize; 1] = [4];

/// Reference solution at `t = 80`, the Test Set's (PSIDE at `rtol = atol = 1e-16`, Cray
/// double precision).
#[allow(clippy::excessive_precision)]
pub const NAND_REF: [f64; 14] = [
    0.4971088699385777e+1,
    0.4999752103929311e+1,
    -0.2499998781491227e+1,
    -0.2499999999999975e+1,
    0.4970837023296724e+1,
    -0.2091214032073855e+0,
    0.4970593243278363e+1,
    -0.2500077409198803e+1,
    -0.2499998781491227e+1,
    -0.2090289583878100e+0,
    -0.2399999999966269e-3,
    -0.2091214032073855e+0,
    -0.2499999999999991e+1,
    -0.2500077409198803e+1,
];

const RGS: f64 = 4.0;
const RGD: f64 = 4.0;
const RBS: f64 = 10.0;
const RBD: f64 = 10.0;
const CGS: f64 = 0.6e-4;
const CGD: f64 = 0.6e-4;
const CBD: f64 = 2.4e-5;
const C9: f64 = 0.5e-4;
const DELTA: f64 = 0.2e-1;
const CURIS: f64 = 1e-14;
const VTH: f64 = 25.85;
const VDD: f64 = 5.0;
const VBB: f64 = -2.5;
const PHIB: f64 = 0.87;

/// A trapezoidal pulse from `low` to `high` (rise `t1` after `delay`, `t2` high, fall `t3`)
/// repeated with `period`, and its derivative; at a corner the left piece.
#[allow(clippy::too_many_arguments)]
fn pulse(
    x: f64,
    low: f64,
    high: f64,
    delay: f64,
    t1: f64,
    t2: f64,
    t3: f64,
    period: f64,
) -> (f64, f64) {
    let time = x % period;
    if time > delay + t1 + t2 + t3 {
        (low, 0.0)
    } else if time > delay + t1 + t2 {
        let s = (high - low) / t3;
        (s * (delay + t1 + t2 + t3 - time) + low, -s)
    } else if time > delay + t1 {
        (high, 0.0)
    } else if time > delay {
        let s = (high - low) / t1;
        (s * (time - delay) + low, s)
    } else {
        (low, 0.0)
    }
}

/// The transistor parameters `(vt0, gamma, phi, beta)`: depletion type (`ned = 1`) or
/// enhancement type; `reverse` selects the Test Set's `beta` for `V_DS < 0`.
fn transistor(ned: u8, reverse: bool) -> (f64, f64, f64, f64) {
    if ned == 1 {
        (-2.43, 0.2, 1.28, 5.35e-4)
    } else if reverse {
        (0.2, 0.035, 1.01, 1.748e-4)
    } else {
        (0.2, 0.035, 1.01, 1.748e-3)
    }
}

/// Drain-source current of the Shichman-Hodges model.
fn ids(ned: u8, vds: f64, vgs: f64, vbs: f64, vgd: f64, vbd: f64) -> f64 {
    if vds > 0.0 {
        let (vt0, gamma, phi, beta) = transistor(ned, false);
        let vte = vt0 + gamma * ((phi - vbs).sqrt() - phi.sqrt());
        let u = vgs - vte;
        if u <= 0.0 {
            0.0
        } else if u <= vds {
            -beta * u * u * (1.0 + DELTA * vds)
        } else {
            -beta * vds * (2.0 * u - vds) * (1.0 + DELTA * vds)
        }
    } else if vds < 0.0 {
        let (vt0, gamma, phi, beta) = transistor(ned, true);
        let vte = vt0 + gamma * ((phi - vbd).sqrt() - phi.sqrt());
        let u = vgd - vte;
        if u <= 0.0 {
            0.0
        } else if u <= -vds {
            beta * u * u * (1.0 - DELTA * vds)
        } else {
            -beta * vds * (2.0 * u + vds) * (1.0 - DELTA * vds)
        }
    } else {
        0.0
    }
}

/// Current of a bulk pn junction (bulk-source and bulk-drain have the same characteristic).
fn ib(v: f64) -> f64 {
    if v <= 0.0 {
        -CURIS * ((v / VTH).exp() - 1.0)
    } else {
        0.0
    }
}

/// Voltage-dependent junction capacitance.
fn cbdbs(v: f64) -> f64 {
    if v <= 0.0 {
        CBD / (1.0 - v / PHIB).sqrt()
    } else {
        CBD * (1.0 + v / (2.0 * PHIB))
    }
}

/// `d cbdbs / dv`.
fn cbdbs_derivative(v: f64) -> f64 {
    if v <= 0.0 {
        CBD / (2.0 * PHIB) / (1.0 - v / PHIB).powf(1.5)
    } else {
        CBD / (2.0 * PHIB)
    }
}

/// `d ib / dv`.
fn ib_derivative(v: f64) -> f64 {
    if v <= 0.0 {
        -CURIS / VTH * (v / VTH).exp()
    } else {
        0.0
    }
}

/// The drain current and its derivatives in `(vds, vgs, vbs, vgd, vbd)` (on a branch switch,
/// those of the branch [`ids`] takes there).
fn ids_gradient(ned: u8, vds: f64, vgs: f64, vbs: f64, vgd: f64, vbd: f64) -> [f64; 5] {
    if vds > 0.0 {
        let (vt0, gamma, phi, beta) = transistor(ned, false);
        let s = (phi - vbs).sqrt();
        let u = vgs - (vt0 + gamma * (s - phi.sqrt()));
        // du/dvbs = -dvte/dvbs.
        let du_dvbs = gamma / (2.0 * s);
        let (di_du, di_dvds) = if u <= 0.0 {
            (0.0, 0.0)
        } else if u <= vds {
            (-2.0 * beta * u * (1.0 + DELTA * vds), -beta * u * u * DELTA)
        } else {
            (
                -2.0 * beta * vds * (1.0 + DELTA * vds),
                -beta
                    * ((2.0 * u - 2.0 * vds) * (1.0 + DELTA * vds) + DELTA * vds * (2.0 * u - vds)),
            )
        };
        [di_dvds, di_du, di_du * du_dvbs, 0.0, 0.0]
    } else if vds < 0.0 {
        let (vt0, gamma, phi, beta) = transistor(ned, true);
        let s = (phi - vbd).sqrt();
        let u = vgd - (vt0 + gamma * (s - phi.sqrt()));
        let du_dvbd = gamma / (2.0 * s);
        let (di_du, di_dvds) = if u <= 0.0 {
            (0.0, 0.0)
        } else if u <= -vds {
            (2.0 * beta * u * (1.0 - DELTA * vds), -beta * u * u * DELTA)
        } else {
            (
                -2.0 * beta * vds * (1.0 - DELTA * vds),
                -beta
                    * ((2.0 * u + 2.0 * vds) * (1.0 - DELTA * vds) - DELTA * vds * (2.0 * u + vds)),
            )
        };
        [di_dvds, 0.0, 0.0, di_du, di_du * du_dvbd]
    } else {
        [0.0; 5]
    }
}

/// Adds `g` times the stamp of a two-terminal element between nodes `a` and `b` (`None`: a
/// fixed potential) to `m`: `+g` on the diagonal entries, `-g` on the coupling ones.
fn stamp<S: MatrixSink + ?Sized>(m: &mut S, a: usize, b: Option<usize>, g: f64) {
    m.add(a, a, g);
    if let Some(b) = b {
        m.add(a, b, -g);
        m.add(b, a, -g);
        m.add(b, b, g);
    }
}

impl Nand {
    /// The Test Set's `y0` and `y0' = 0` (consistent: `f(0, y0)` is below `1e-14`).
    pub fn initial() -> ([f64; 14], [f64; 14]) {
        let y = [
            5.0, 5.0, VBB, VBB, 5.0, 3.62385, 5.0, VBB, VBB, 3.62385, 0.0, 3.62385, VBB, VBB,
        ];
        (y, [0.0; 14])
    }

    /// The capacitance matrix `C(y)` (dense).
    pub fn capacitance(y: &[f64]) -> [[f64; 14]; 14] {
        let mut c = [[0.0; 14]; 14];
        let c35 = cbdbs(y[2] - y[4]);
        let c4 = cbdbs(y[3] - VDD);
        let c95 = cbdbs(y[8] - y[4]);
        let c810 = cbdbs(y[7] - y[9]);
        let c1410 = cbdbs(y[13] - y[9]);
        c[0][0] = CGS;
        c[0][4] = -CGS;
        c[1][1] = CGD;
        c[1][4] = -CGD;
        c[2][2] = c35;
        c[2][4] = -c35;
        c[3][3] = c4;
        c[4][0] = -CGS;
        c[4][1] = -CGD;
        c[4][2] = -c35;
        c[4][4] = CGS + CGD + c35 + c95 + C9;
        c[4][8] = -c95;
        c[5][5] = CGS;
        c[6][6] = CGD;
        c[7][7] = c810;
        c[7][9] = -c810;
        c[8][4] = -c95;
        c[8][8] = c95;
        c[9][7] = -c810;
        c[9][9] = c810 + c1410 + C9;
        c[9][13] = -c1410;
        c[10][10] = CGS;
        c[11][11] = CGD;
        c[12][12] = cbdbs(y[12]);
        c[13][9] = -c1410;
        c[13][13] = c1410;
        c
    }

    /// The right-hand side `f(t, y)` (the currents into the nodes).
    pub fn f(t: f64, y: &[f64]) -> [f64; 14] {
        let (v1, v1d) = pulse(t, 0.0, 5.0, 5.0, 5.0, 5.0, 5.0, 20.0);
        let (v2, v2d) = pulse(t, 0.0, 5.0, 15.0, 5.0, 15.0, 5.0, 40.0);
        let i1 = ids(
            1,
            y[1] - y[0],
            y[4] - y[0],
            y[2] - y[4],
            y[4] - y[1],
            y[3] - VDD,
        );
        let i2 = ids(
            2,
            y[6] - y[5],
            v1 - y[5],
            y[7] - y[9],
            v1 - y[6],
            y[8] - y[4],
        );
        let i3 = ids(
            2,
            y[11] - y[10],
            v2 - y[10],
            y[12],
            v2 - y[11],
            y[13] - y[9],
        );
        [
            -(y[0] - y[4]) / RGS - i1,
            -(y[1] - VDD) / RGD + i1,
            -(y[2] - VBB) / RBS + ib(y[2] - y[4]),
            -(y[3] - VBB) / RBD + ib(y[3] - VDD),
            -(y[4] - y[0]) / RGS - ib(y[2] - y[4]) - (y[4] - y[6]) / RGD - ib(y[8] - y[4]),
            CGS * v1d - (y[5] - y[9]) / RGS - i2,
            CGD * v1d - (y[6] - y[4]) / RGD + i2,
            -(y[7] - VBB) / RBS + ib(y[7] - y[9]),
            -(y[8] - VBB) / RBD + ib(y[8] - y[4]),
            -(y[9] - y[5]) / RGS - ib(y[7] - y[9]) - (y[9] - y[11]) / RGD - ib(y[13] - y[9]),
            CGS * v2d - y[10] / RGS - i3,
            CGD * v2d - (y[11] - y[9]) / RGD + i3,
            -(y[12] - VBB) / RBS + ib(y[12]),
            -(y[13] - VBB) / RBD + ib(y[13] - y[9]),
        ]
    }

    /// The capacitors of the network: `(a, b, C)`, a capacitance `C` between nodes `a` and `b`
    /// (`None`: a fixed potential). `C(y)` is their sum of stamps (`+C` at `(a, a)`, `(b, b)`,
    /// `-C` at `(a, b)`, `(b, a)`); a test checks it against [`capacitance`](Self::capacitance).
    pub fn capacitors(y: &[f64]) -> [(usize, Option<usize>, f64); 14] {
        [
            (0, Some(4), CGS),
            (1, Some(4), CGD),
            (2, Some(4), cbdbs(y[2] - y[4])),
            (3, None, cbdbs(y[3] - VDD)),
            (8, Some(4), cbdbs(y[8] - y[4])),
            (4, None, C9),
            (5, None, CGS),
            (6, None, CGD),
            (7, Some(9), cbdbs(y[7] - y[9])),
            (13, Some(9), cbdbs(y[13] - y[9])),
            (9, None, C9),
            (10, None, CGS),
            (11, None, CGD),
            (12, None, cbdbs(y[12])),
        ]
    }

    /// `C(y) y' - f(t, y)`, `C(y) y'` from the capacitors' stamps.
    fn residual_array(t: f64, y: &[f64], yp: &[f64]) -> [f64; 14] {
        let f = Self::f(t, y);
        let mut r: [f64; 14] = std::array::from_fn(|i| -f[i]);
        for (a, b, cap) in Self::capacitors(y) {
            let q = cap * (yp[a] - b.map_or(0.0, |b| yp[b]));
            r[a] += q;
            if let Some(b) = b {
                r[b] -= q;
            }
        }
        r
    }
}

impl ImplicitDae for Nand {
    fn dimension(&self) -> usize {
        14
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&Self::residual_array(t, y, yp));
    }
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, y: &[f64], _: &[f64], m: &mut S) -> bool {
        for (a, b, cap) in Self::capacitors(y) {
            stamp(m, a, b, cap);
        }
        true
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        c: f64,
        m: &mut S,
    ) {
        // c C(y).
        for (a, b, cap) in Self::capacitors(y) {
            stamp(m, a, b, c * cap);
        }
        // d(C(y) y')/dy: each junction capacitance cbdbs(y_a - y_b) adds cbdbs (y_a' - y_b') to
        // row a and takes it from row b.
        let yb = |b: Option<usize>| b.map_or(0.0, |b| y[b]);
        let ypb = |b: Option<usize>| b.map_or(0.0, |b| yp[b]);
        for (a, b, offset) in [
            (2, Some(4), 0.0),
            (3, None, VDD),
            (8, Some(4), 0.0),
            (7, Some(9), 0.0),
            (13, Some(9), 0.0),
            (12, None, 0.0),
        ] {
            let v = y[a] - yb(b) - offset;
            stamp(m, a, b, cbdbs_derivative(v) * (yp[a] - ypb(b)));
        }
        // -df/dy: resistors (current (y_a - y_b)/R leaves node a) ...
        for (a, b, r) in [
            (0, Some(4), RGS),
            (1, None, RGD),
            (2, None, RBS),
            (3, None, RBD),
            (4, Some(6), RGD),
            (5, Some(9), RGS),
            (7, None, RBS),
            (8, None, RBD),
            (9, Some(11), RGD),
            (10, None, RGS),
            (12, None, RBS),
            (13, None, RBD),
        ] {
            stamp(m, a, b, 1.0 / r);
        }
        // ... the bulk diodes (current ib(y_a - y_b) enters node a) ...
        for (a, b, offset) in [
            (2, Some(4), 0.0),
            (3, None, VDD),
            (8, Some(4), 0.0),
            (7, Some(9), 0.0),
            (13, Some(9), 0.0),
            (12, None, 0.0),
        ] {
            stamp(m, a, b, -ib_derivative(y[a] - yb(b) - offset));
        }
        // ... and the transistors: current ids leaves the source row and enters the drain
        // row; each argument is a difference of two unknowns (`None`: an input or a supply).
        let (v1, _) = pulse(t, 0.0, 5.0, 5.0, 5.0, 5.0, 5.0, 20.0);
        let (v2, _) = pulse(t, 0.0, 5.0, 15.0, 5.0, 15.0, 5.0, 40.0);
        type Arg = (Option<usize>, Option<usize>, f64);
        let transistors: [(u8, usize, usize, [Arg; 5]); 3] = [
            (
                1,
                0,
                1,
                [
                    (Some(1), Some(0), 0.0),
                    (Some(4), Some(0), 0.0),
                    (Some(2), Some(4), 0.0),
                    (Some(4), Some(1), 0.0),
                    (Some(3), None, -VDD),
                ],
            ),
            (
                2,
                5,
                6,
                [
                    (Some(6), Some(5), 0.0),
                    (None, Some(5), v1),
                    (Some(7), Some(9), 0.0),
                    (None, Some(6), v1),
                    (Some(8), Some(4), 0.0),
                ],
            ),
            (
                2,
                10,
                11,
                [
                    (Some(11), Some(10), 0.0),
                    (None, Some(10), v2),
                    (Some(12), None, 0.0),
                    (None, Some(11), v2),
                    (Some(13), Some(9), 0.0),
                ],
            ),
        ];
        for (ned, source, drain, args) in transistors {
            let v: [f64; 5] = std::array::from_fn(|k| {
                let (p, n, offset) = args[k];
                p.map_or(0.0, |p| y[p]) - n.map_or(0.0, |n| y[n]) + offset
            });
            let g = ids_gradient(ned, v[0], v[1], v[2], v[3], v[4]);
            for (k, (p, n, _)) in args.into_iter().enumerate() {
                for (j, sign) in [(p, 1.0), (n, -1.0)] {
                    if let (Some(j), true) = (j, g[k] != 0.0) {
                        m.add(source, j, sign * g[k]);
                        m.add(drain, j, -sign * g[k]);
                    }
                }
            }
        }
    }
}
