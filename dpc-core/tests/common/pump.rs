//! The charge pump of the Test Set for IVP Solvers (Univ. of Bari; problem `pump`, after
//! Günther, Denk and Feldmann's charge-oriented MOS model): an index-2 DAE of 9 unknowns on
//! `t` in `[0, 1.2e-6]`, the charges `y1..y5` (gate, two source and two drain charges), the
//! voltages `U1 = y6`, `U2 = y7`, `U3 = y8` and the current `I = y9` of the voltage source,
//!
//! ```text
//! y1'       = -y9                      0 = y6 - vin(t)
//! y2' + y3' = 0                        0 = qgate(y6, y6 - y7, y6 - y8) - y1
//! y4' + y5' = 0                        0 = C_S y7 - y2
//!                                      0 = qsrc(...) - y3
//!                                      0 = C_D y8 - y4
//!                                      0 = qdrain(...) - y5
//! ```
//!
//! a constant singular mass matrix `M` (rows 1 to 3). `y9` is the index-2 unknown (it is
//! `-d/dt qgate(vin(t), ...)`), the others have index 1, as the Test Set's driver declares
//! ([`PUMP_INDEX`]). The input `vin` is a trapezoidal pulse of period 120 ns whose corners
//! ([`pump_breaks`]) the runs stop at (the Test Set drivers integrate from corner to corner).
//!
//! Equations, constants, initial values, the tolerances ([`pump_atol`]) and the reference
//! solution are transcribed from the Test Set's problem definition (`pump.f`, as its MEBDFI
//! driver holds it), written here anew, with the rows 4 to 9 negated (the same solution). The
//! Test Set scores `y1` only: `y2..y8` are zero at the end and `y9` (index 2) is skipped
//! ([`PUMP_SCORED`]). The iteration matrix is exact: the charges' derivatives are derived
//! piecewise below. `bench/ida_peer.c` has the same equations.
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// The charge pump ([module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct Pump;

/// Interval end of [`Pump`].
pub const PUMP_T_END: f64 = 1200e-9;

/// The index of each unknown: `y9` has index 2.
pub const PUMP_INDEX: [u8; 9] = [1, 1, 1, 1, 1, 1, 1, 1, 2];

/// The components the Test Set scores (`y1`, zero-based 0).
pub const PUMP_SCORED: [usize; 1] = [0];

/// Reference solution at `t = 1.2e-6`, the Test Set's (PSIDE at `tol = 2e-8`); `y9` (not
/// scored) is the current on the last falling edge of `vin`.
#[allow(clippy::excessive_precision)]
pub const PUMP_REF: [f64; 9] = [
    0.1262800429876759e-12,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.1522565920949845e-03,
];

/// The corners of `vin` in `(0, 1.2e-6]`: `50, 60, 110, 120` ns in each period of 120 ns, as
/// the Test Set's driver computes them.
pub fn pump_breaks() -> [f64; 40] {
    let first = [50e-9, 60e-9, 110e-9];
    let mut t = [0.0; 40];
    for i in 1..40 {
        let base = (i / 4) as f64 * 120e-9;
        t[i - 1] = if i % 4 == 0 {
            base
        } else {
            first[i % 4 - 1] + base
        };
    }
    t[39] = PUMP_T_END;
    t
}

/// The Test Set driver's absolute tolerances at `rtol = tol`: `1e-6 tol` for the charges
/// `y1..y5`, `tol` for the voltages; `y9` gets `tol` (the driver sets 1000 to take it out of the
/// error test; here the index-2 exclusion does that).
pub fn pump_atol(tol: f64) -> Vec<f64> {
    (0..9)
        .map(|i| if i < 5 { 1e-6 * tol } else { tol })
        .collect()
}

const CAPD: f64 = 0.40e-12;
const CAPS: f64 = 1.60e-12;
const VT0: f64 = 0.20;
const GAMMA: f64 = 0.350e-1;
const PHI: f64 = 1.010;
const COX: f64 = 4.0e-12;

/// The input voltage: a pulse of 20 V, period 120 ns (rise 50 to 60 ns, fall 110 to 120 ns).
pub fn vin(t: f64) -> f64 {
    const VHIGH: f64 = 20.0;
    let d = t % 120e-9;
    if d < 50e-9 {
        0.0
    } else if d < 60e-9 {
        (d - 50e-9) * 0.10e9 * VHIGH
    } else if d < 110e-9 {
        VHIGH
    } else {
        (120e-9 - d) * 0.10e9 * VHIGH
    }
}

/// Which charge of the transistor.
#[derive(Clone, Copy, PartialEq)]
enum Charge {
    Gate,
    /// Source and drain charges have the same formula.
    SourceOrDrain,
}

/// The charge `q(vgb, vgs, vgd)` and its gradient in `(vgb, vgs, vgd)`.
fn charge(kind: Charge, vgb: f64, vgs: f64, vgd: f64) -> (f64, [f64; 3]) {
    // The model is symmetric in source and drain: ugs is the larger of vgs, vgd.
    let swapped = vgs - vgd <= 0.0;
    let (ugs, ugd) = if swapped { (vgd, vgs) } else { (vgs, vgd) };
    let ugb = vgb;
    let ubs = ugs - ugb;
    let vfb = VT0 - GAMMA * PHI.sqrt() - PHI;
    let s = (PHI - ubs).sqrt();
    let vte = VT0 + GAMMA * (s - PHI.sqrt());
    // d vte / d(ugb, ugs, ugd).
    let dv = GAMMA / (2.0 * s);
    let dvte = [dv, -dv, 0.0];
    // (q, dq/d(ugb, ugs, ugd)).
    let (q, g) = if ugb <= vfb {
        match kind {
            Charge::Gate => (COX * (ugb - vfb), [COX, 0.0, 0.0]),
            Charge::SourceOrDrain => (0.0, [0.0; 3]),
        }
    } else if ugs <= vte {
        match kind {
            Charge::Gate => {
                let r = (GAMMA * GAMMA / 4.0 + ugb - vfb).sqrt();
                (
                    COX * GAMMA * (r - GAMMA / 2.0),
                    [COX * GAMMA / (2.0 * r), 0.0, 0.0],
                )
            }
            Charge::SourceOrDrain => (0.0, [0.0; 3]),
        }
    } else {
        let ugst = ugs - vte;
        let dugst = [-dvte[0], 1.0 - dvte[1], 0.0];
        // The gate charge switches the drain term on at ugd > vte, the others at ugd >= vte.
        let on = match kind {
            Charge::Gate => ugd > vte,
            Charge::SourceOrDrain => ugd >= vte,
        };
        let (ugdt, dugdt) = if on {
            (ugd - vte, [-dvte[0], -dvte[1], 1.0])
        } else {
            (0.0, [0.0; 3])
        };
        let sum = ugdt + ugst;
        let h = sum - ugdt * ugst / sum;
        let dh_dst = 1.0 - ugdt * ugdt / (sum * sum);
        let dh_ddt = 1.0 - ugst * ugst / (sum * sum);
        let dh: [f64; 3] = std::array::from_fn(|k| dh_dst * dugst[k] + dh_ddt * dugdt[k]);
        match kind {
            Charge::Gate => {
                // gamma sqrt(phi - ubs), ubs = ugs - ugb.
                let ds = [1.0 / (2.0 * s), -1.0 / (2.0 * s), 0.0];
                let q = COX * (2.0 / 3.0 * h + GAMMA * s);
                (
                    q,
                    std::array::from_fn(|k| COX * (2.0 / 3.0 * dh[k] + GAMMA * ds[k])),
                )
            }
            Charge::SourceOrDrain => {
                let q = -COX / 3.0 * h;
                (q, std::array::from_fn(|k| -COX / 3.0 * dh[k]))
            }
        }
    };
    let g = if swapped { [g[0], g[2], g[1]] } else { g };
    (q, g)
}

/// The charge at the unknowns `y` (`vgb = y6`, `vgs = y6 - y7`, `vgd = y6 - y8`) and its
/// derivatives in `(y6, y7, y8)`.
fn charge_of(kind: Charge, y: &[f64]) -> (f64, [f64; 3]) {
    let (q, g) = charge(kind, y[5], y[5] - y[6], y[5] - y[7]);
    (q, [g[0] + g[1] + g[2], -g[1], -g[2]])
}

impl Pump {
    /// The Test Set's consistent start: the charges of zero voltages, `y' = 0`.
    pub fn initial() -> ([f64; 9], [f64; 9]) {
        let z = [0.0; 9];
        let mut y = z;
        y[0] = charge_of(Charge::Gate, &z).0;
        y[2] = charge_of(Charge::SourceOrDrain, &z).0;
        y[4] = charge_of(Charge::SourceOrDrain, &z).0;
        (y, z)
    }
}

impl ImplicitDae for Pump {
    fn dimension(&self) -> usize {
        9
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let qg = charge_of(Charge::Gate, y).0;
        let qs = charge_of(Charge::SourceOrDrain, y).0;
        out[0] = yp[0] + y[8];
        out[1] = yp[1] + yp[2];
        out[2] = yp[3] + yp[4];
        out[3] = y[5] - vin(t);
        out[4] = qg - y[0];
        out[5] = CAPS * y[6] - y[1];
        out[6] = qs - y[2];
        out[7] = CAPD * y[7] - y[3];
        out[8] = qs - y[4];
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let (_, dg) = charge_of(Charge::Gate, y);
        let (_, ds) = charge_of(Charge::SourceOrDrain, y);
        m.set(0, 0, c);
        m.set(0, 8, 1.0);
        m.set(1, 1, c);
        m.set(1, 2, c);
        m.set(2, 3, c);
        m.set(2, 4, c);
        m.set(3, 5, 1.0);
        m.set(4, 0, -1.0);
        m.set(5, 1, -1.0);
        m.set(5, 6, CAPS);
        m.set(6, 2, -1.0);
        m.set(7, 3, -1.0);
        m.set(7, 7, CAPD);
        m.set(8, 4, -1.0);
        for k in 0..3 {
            for (row, d) in [(4, dg[k]), (6, ds[k]), (8, ds[k])] {
                if d != 0.0 {
                    m.add(row, 5 + k, d);
                }
            }
        }
    }
    /// The constant `M`: `y1'`, `y2' + y3'`, `y4' + y5'` in the first three rows.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        m.set(0, 0, 1.0);
        m.set(1, 1, 1.0);
        m.set(1, 2, 1.0);
        m.set(2, 3, 1.0);
        m.set(2, 4, 1.0);
        true
    }
}
