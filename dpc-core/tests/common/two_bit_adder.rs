//! The two bit adding unit of the Test Set for IVP Solvers (Univ. of Bari; problem `tba`,
//! after Günther and Rentrop's MOS network models): a circuit of ten logic gates (three NOR,
//! five ANDOI, one NAND, one ORANI) and three series transistors adding two two-bit numbers and
//! a carry, `A1*2 + A0 + B1*2 + B0 + CIN = C*4 + S1*2 + S0`, with 175 node potentials `U` and
//! their charges `q`, `y = (q, U)`, 350 unknowns on `t` in `[0, 320]`:
//!
//! ```text
//! q' = f(t, U)      (the static currents into the nodes, rows 0..175)
//! 0  = q - g(U)     (the charges, rows 175..350)
//! ```
//!
//! with the constant mass matrix `diag(I, 0)`. The Test Set calls it index 1, but in this
//! form (one charge per node as an unknown) it is not index 1 throughout: `dg/dU` is singular.
//! Thirteen groups of nodes are coupled by capacitances only among themselves (the coupling
//! node of each ANDOI, NAND and ORANI gate with the bulk nodes around it, the result nodes of
//! the gates with the inputs of the gates they drive, the series transistors' nodes), so the
//! charges of a group sum to a constant, `sum q' = sum f(U) = 0` is a hidden constraint, and
//! the group's common potential is fixed by it alone: 13 directions of index 2 (Hessenberg
//! form; `W^T f_U V` regular), and 95 node potentials with a part in them, which
//! [`dpc_core::index_estimate::unknown_indices`] reads as of index 2 (tested). The
//! five inputs `V1..V4`, `CIN` are trapezoidal pulses whose slopes enter `f` through the gate
//! capacitances: `f` jumps at every multiple of 5 ([`tba_breaks`]), where the runs stop and
//! continue.
//!
//! Equations, constants, initial values and the reference values are transcribed from the Test
//! Set's problem definition (`tba.f`, as its DASSL driver holds it), written here anew as a
//! netlist: every MOS transistor (Shichman-Hodges, with four internal nodes: source, drain,
//! bulk-source and bulk-drain) adds its currents to its internal nodes and to the gate's
//! source and drain nodes, and the charge function is the Test Set's term by term. Two details
//! of the Test Set's definition are kept because its reference was computed with them: the
//! last charge of every NOR gate, `CBDBS(U(I+12) - U(I+4)) * (U(I+12) - U(I+14))` (`I+14`, not
//! `I+4`), and the linear gate couplings of nodes 18 and 98 to the series transistors, which
//! appear on one side only.
//!
//! The iteration matrix is exact: `c` on the charges' diagonal, `-df/dU` (resistors, pn
//! junctions, the drain currents' derivatives, on a branch switch those of the branch taken
//! there), the identity and `-dg/dU` (the junction capacitances and their derivatives).
//! [`TwoBitAdder::iteration_pattern`] declares its structure (about 2 % of the entries).
//!
//! The Test Set scores the three outputs `S0, S1, C` (its `y(224), y(305), y(323)`, zero-based
//! [`TBA_SCORED`]) against [`TBA_REF`]; that reference was computed by RADAU5 at
//! `rtol = atol = 1e-5` (the driver's comment), so digits beyond about 6 measure the reference
//! rather than a run (`docs/integrators.md`, two bit adding unit).
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// Number of node potentials (and of charges).
pub const NODES: usize = 175;
/// Number of unknowns, `(q, U)`.
pub const TBA_N: usize = 2 * NODES;
/// Interval end.
pub const TBA_T_END: f64 = 320.0;

/// The discontinuities of `f` in `(0, 320]` (the pulses' corners): `5, 10, ..., 320`.
pub fn tba_breaks() -> Vec<f64> {
    (1..=64).map(|i| 5.0 * f64::from(i)).collect()
}

/// The components scored: the outputs `S0`, `S1`, `C` (nodes 49, 130, 148; the Test Set's
/// `y(224)`, `y(305)`, `y(323)`).
pub const TBA_SCORED: [usize; 3] = [NODES + 48, NODES + 129, NODES + 147];

/// The Test Set's reference values of the scored components at `t = 320` (RADAU5 at
/// `rtol = atol = 1e-5`, `h0 = 4e-5`), indexed like [`TBA_SCORED`].
#[allow(clippy::excessive_precision)]
pub const TBA_REF: [f64; 3] = [
    0.2040419147264534e+0,
    0.4997238455712048e+1,
    0.2038985905095614e+0,
];

/// `reference` spread over a full state vector (zeros elsewhere), for scorers that index the
/// reference like the state.
pub fn tba_full_reference(reference: &[f64; 3]) -> Vec<f64> {
    let mut r = vec![0.0; TBA_N];
    for (k, &i) in TBA_SCORED.iter().enumerate() {
        r[i] = reference[k];
    }
    r
}

const CTIME: f64 = 1e4;
const STIFF: f64 = 5.0;
const RGS: f64 = 40.0 / (CTIME * STIFF);
const RGD: f64 = 40.0 / (CTIME * STIFF);
const RBS: f64 = 100.0 / (CTIME * STIFF);
const RBD: f64 = 100.0 / (CTIME * STIFF);
const CGS: f64 = 0.6e-4 * CTIME;
const CGD: f64 = 0.6e-4 * CTIME;
const CBD: f64 = 2.4e-5 * CTIME;
const DELTA: f64 = 0.02;
const CURIS: f64 = 1e-15 * CTIME * STIFF;
const VTH: f64 = 25.85;
const VDD: f64 = 5.0;
const VBB: f64 = -2.5;
const COUT: f64 = 2e-4 * CTIME;
const PHIB: f64 = 0.87;

/// A terminal of an element: a node potential `U[k]` (zero-based), a fixed potential, or input
/// `k` (`V1, V2, V3, V4, CIN`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum T {
    Node(usize),
    Fixed(f64),
    Input(usize),
}

const GND: T = T::Fixed(0.0);

/// Node `k` of the Test Set's one-based numbering.
fn n(k: usize) -> T {
    T::Node(k - 1)
}

/// A MOS transistor: internal nodes `j..j+4` (zero-based: source, drain, bulk-source,
/// bulk-drain), type `kind` (0 depletion, 1..3 enhancement with 1..3 units in series), gate
/// `g`, external source `s` and drain `d`.
#[derive(Debug, Clone, Copy)]
struct Mos {
    j: usize,
    kind: u8,
    g: T,
    s: T,
    d: T,
}

/// A charge term of `g(U)`: `g[row] += cap * (mul.0 - mul.1)`, `cap` a constant or the
/// junction capacitance `CBDBS(arg.0 - arg.1)`.
#[derive(Debug, Clone, Copy)]
struct Charge {
    row: usize,
    cap: Option<f64>,
    arg: (T, T),
    mul: (T, T),
}

/// The two bit adding unit ([module documentation](self)).
#[derive(Debug, Clone)]
pub struct TwoBitAdder {
    mos: Vec<Mos>,
    charges: Vec<Charge>,
}

/// The inputs `(value, slope)` at `t` (`V1, V2, V3, V4, CIN`); at a corner the left piece.
fn inputs(t: f64) -> [(f64, f64); 5] {
    [
        pulse(t, 0.0, 20.0),
        pulse(t, 10.0, 40.0),
        pulse(t, 30.0, 80.0),
        pulse(t, 70.0, 160.0),
        pulse(t, 150.0, 320.0),
    ]
}

/// The Test Set's trapezoidal pulse from 0 to 5 after `delay` (rise 5, high `period / 2 - 5`,
/// fall 5), repeated with `period`, and its slope; at a corner the left piece.
fn pulse(x: f64, delay: f64, period: f64) -> (f64, f64) {
    let (t1, t2, t3, high) = (5.0, period / 2.0 - 5.0, 5.0, 5.0);
    let time = x % period;
    if time > delay + t1 + t2 + t3 {
        (0.0, 0.0)
    } else if time > delay + t1 + t2 {
        (high / t3 * (delay + t1 + t2 + t3 - time), -high / t3)
    } else if time > delay + t1 {
        (high, 0.0)
    } else if time > delay {
        (high / t1 * (time - delay), high / t1)
    } else {
        (0.0, 0.0)
    }
}

/// `(vt0, gamma, phi, beta)` of transistor type `kind`.
fn params(kind: u8) -> (f64, f64, f64, f64) {
    match kind {
        0 => (-2.43, 0.2, 1.28, 53.5e-6 * CTIME * STIFF),
        k => (0.2, 0.035, 1.01, f64::from(4 * k) * 43.7e-6 * CTIME * STIFF),
    }
}

/// The drain current (Shichman-Hodges) and its derivatives in `(vds, vgs, vbs, vgd, vbd)`
/// (on a branch switch, those of the branch taken there). `phi - vbs < 0` (outside the model's
/// domain, the Test Set's `ierr = -1`) gives a NaN, which the integrators reject.
fn ids(kind: u8, vds: f64, vgs: f64, vbs: f64, vgd: f64, vbd: f64) -> (f64, [f64; 5]) {
    let (vt0, gamma, phi, beta) = params(kind);
    if vds > 0.0 {
        let s = (phi - vbs).sqrt();
        let u = vgs - (vt0 + gamma * (s - phi.sqrt()));
        let du_dvbs = gamma / (2.0 * s);
        let (i, di_du, di_dvds) = if u <= 0.0 {
            (0.0 * s, 0.0, 0.0)
        } else if u <= vds {
            (
                -beta * u * u * (1.0 + DELTA * vds),
                -2.0 * beta * u * (1.0 + DELTA * vds),
                -beta * u * u * DELTA,
            )
        } else {
            (
                -beta * vds * (2.0 * u - vds) * (1.0 + DELTA * vds),
                -2.0 * beta * vds * (1.0 + DELTA * vds),
                -beta
                    * ((2.0 * u - 2.0 * vds) * (1.0 + DELTA * vds) + DELTA * vds * (2.0 * u - vds)),
            )
        };
        (i, [di_dvds, di_du, di_du * du_dvbs, 0.0, 0.0])
    } else if vds < 0.0 {
        let s = (phi - vbd).sqrt();
        let u = vgd - (vt0 + gamma * (s - phi.sqrt()));
        let du_dvbd = gamma / (2.0 * s);
        let (i, di_du, di_dvds) = if u <= 0.0 {
            (0.0 * s, 0.0, 0.0)
        } else if u <= -vds {
            (
                beta * u * u * (1.0 - DELTA * vds),
                2.0 * beta * u * (1.0 - DELTA * vds),
                -beta * u * u * DELTA,
            )
        } else {
            (
                -beta * vds * (2.0 * u + vds) * (1.0 - DELTA * vds),
                -2.0 * beta * vds * (1.0 - DELTA * vds),
                -beta
                    * ((2.0 * u + 2.0 * vds) * (1.0 - DELTA * vds) - DELTA * vds * (2.0 * u + vds)),
            )
        };
        (i, [di_dvds, 0.0, 0.0, di_du, di_du * du_dvbd])
    } else {
        (0.0, [0.0; 5])
    }
}

/// Current of a pn junction (bulk-source and bulk-drain alike) and its derivative.
fn ib(v: f64) -> (f64, f64) {
    if v <= 0.0 {
        let e = (v / VTH).exp();
        (-CURIS * (e - 1.0), -CURIS / VTH * e)
    } else {
        (0.0, 0.0)
    }
}

/// The voltage-dependent junction capacitance and its derivative.
fn cbdbs(v: f64) -> (f64, f64) {
    if v <= 0.0 {
        let r = 1.0 - v / PHIB;
        (CBD / r.sqrt(), CBD / (2.0 * PHIB) / (r * r.sqrt()))
    } else {
        (CBD * (1.0 + v / (2.0 * PHIB)), CBD / (2.0 * PHIB))
    }
}

/// The gate kinds of the Test Set's subroutines.
#[derive(Clone, Copy, PartialEq)]
enum Gate {
    Nor,
    Andoi,
    Nand,
    Orani,
}

impl TwoBitAdder {
    /// The netlist of the Test Set's `FCN` and `GCN`.
    pub fn new() -> Self {
        let mut s = Self {
            mos: Vec::new(),
            charges: Vec::new(),
        };
        let (v1, v2, v3, v4, cin) = (
            T::Input(0),
            T::Input(1),
            T::Input(2),
            T::Input(3),
            T::Input(4),
        );
        s.gate(Gate::Nor, 1, &[v1, v2]);
        s.gate(Gate::Andoi, 14, &[n(5), v2, v1]);
        s.gate(Gate::Nor, 32, &[n(18), cin]);
        s.gate(Gate::Andoi, 45, &[n(36), cin, n(18)]);
        s.gate(Gate::Andoi, 63, &[n(5), cin, n(18)]);
        s.gate(Gate::Nor, 81, &[v3, v4]);
        s.gate(Gate::Andoi, 94, &[n(85), v4, v3]);
        s.gate(Gate::Nand, 112, &[n(67), n(98)]);
        s.gate(Gate::Orani, 126, &[n(116), n(67), n(98)]);
        // ANDOI gate 5, whose result node 148 is also the drain of the series transistors.
        s.gate(Gate::Andoi, 144, &[n(85), n(5), n(98)]);
        // The three series transistors 148 -> 166 -> 171 -> ground.
        s.transistor(162, 3, n(98), n(166), n(148));
        s.transistor(167, 3, n(18), n(171), n(166));
        s.transistor(172, 3, cin, GND, n(171));
        s.couplings();
        s
    }

    /// A MOS transistor with internal nodes `j..j+3` (one-based).
    fn transistor(&mut self, j: usize, kind: u8, g: T, s: T, d: T) {
        self.mos.push(Mos {
            j: j - 1,
            kind,
            g,
            s,
            d,
        });
    }

    /// `g(row) += c * (U(a) - b)` (one-based rows and nodes).
    fn linear(&mut self, row: usize, c: f64, a: T, b: T) {
        self.charges.push(Charge {
            row: row - 1,
            cap: Some(c),
            arg: (GND, GND),
            mul: (a, b),
        });
    }

    /// `g(row) += CBDBS(arg.0 - arg.1) * (mul.0 - mul.1)` (one-based).
    fn junction(&mut self, row: usize, arg: (T, T), mul: (T, T)) {
        self.charges.push(Charge {
            row: row - 1,
            cap: None,
            arg,
            mul,
        });
    }

    /// A gate starting at node `i` (one-based) with inputs `u`: its transistors (the
    /// depletion load `i..i+3` with gate and source at the result node `i+4`, then the
    /// enhancement branches) and its charge function (`DNOR`, `DANDOI`, `DNAND`, `DORANI`).
    fn gate(&mut self, kind: Gate, i: usize, u: &[T]) {
        let r = n(i + 4);
        self.transistor(i, 0, r, r, T::Fixed(VDD));
        match kind {
            Gate::Nor => {
                self.transistor(i + 5, 1, u[0], GND, r);
                self.transistor(i + 9, 1, u[1], GND, r);
            }
            Gate::Andoi => {
                self.transistor(i + 5, 1, u[0], GND, r);
                self.transistor(i + 9, 2, u[1], n(i + 13), r);
                self.transistor(i + 14, 2, u[2], GND, n(i + 13));
            }
            Gate::Nand => {
                self.transistor(i + 5, 2, u[0], n(i + 9), r);
                self.transistor(i + 10, 2, u[1], GND, n(i + 9));
            }
            Gate::Orani => {
                self.transistor(i + 5, 2, u[0], n(i + 9), r);
                self.transistor(i + 10, 2, u[1], GND, n(i + 9));
                self.transistor(i + 14, 2, u[2], GND, n(i + 9));
            }
        }
        // Charges of the load and the result node, common to the four gates.
        self.linear(i, CGS, n(i), r);
        self.linear(i + 1, CGD, n(i + 1), r);
        self.junction(i + 2, (n(i + 2), r), (n(i + 2), r));
        self.junction(i + 3, (n(i + 3), T::Fixed(VDD)), (n(i + 3), GND));
        self.linear(i + 4, CGS, r, n(i));
        self.linear(i + 4, CGD, r, n(i + 1));
        self.junction(i + 4, (n(i + 2), r), (r, n(i + 2)));
        self.junction(i + 4, (n(i + 8), r), (r, n(i + 8)));
        self.linear(i + 5, CGS, n(i + 5), GND);
        self.linear(i + 6, CGD, n(i + 6), GND);
        self.junction(i + 8, (n(i + 8), r), (n(i + 8), r));
        match kind {
            Gate::Nor | Gate::Andoi => {
                self.junction(i + 4, (n(i + 12), r), (r, n(i + 12)));
                self.junction(i + 7, (n(i + 7), GND), (n(i + 7), GND));
                self.linear(i + 9, CGS, n(i + 9), GND);
                self.linear(i + 10, CGD, n(i + 10), GND);
            }
            Gate::Nand | Gate::Orani => {
                let c = n(i + 9);
                self.junction(i + 7, (n(i + 7), c), (n(i + 7), c));
                self.junction(i + 9, (n(i + 7), c), (c, n(i + 7)));
                self.junction(i + 9, (n(i + 13), c), (c, n(i + 13)));
                self.linear(i + 10, CGS, n(i + 10), GND);
                self.linear(i + 11, CGD, n(i + 11), GND);
                self.junction(i + 12, (n(i + 12), GND), (n(i + 12), GND));
                self.junction(i + 13, (n(i + 13), c), (n(i + 13), c));
            }
        }
        match kind {
            Gate::Nor => {
                self.junction(i + 11, (n(i + 11), GND), (n(i + 11), GND));
                // The Test Set's `(U(I+12) - U(I+14))`, kept (module documentation).
                self.junction(i + 12, (n(i + 12), r), (n(i + 12), n(i + 14)));
            }
            Gate::Andoi => {
                let c = n(i + 13);
                self.junction(i + 11, (n(i + 11), c), (n(i + 11), c));
                self.junction(i + 12, (n(i + 12), r), (n(i + 12), r));
                self.junction(i + 13, (n(i + 11), c), (c, n(i + 11)));
                self.junction(i + 13, (n(i + 17), c), (c, n(i + 17)));
                self.linear(i + 14, CGS, n(i + 14), GND);
                self.linear(i + 15, CGD, n(i + 15), GND);
                self.junction(i + 16, (n(i + 16), GND), (n(i + 16), GND));
                self.junction(i + 17, (n(i + 17), c), (n(i + 17), c));
            }
            Gate::Nand => {}
            Gate::Orani => {
                let c = n(i + 9);
                self.junction(i + 9, (n(i + 17), c), (c, n(i + 17)));
                self.linear(i + 14, CGS, n(i + 14), GND);
                self.linear(i + 15, CGD, n(i + 15), GND);
                self.junction(i + 16, (n(i + 16), GND), (n(i + 16), GND));
                self.junction(i + 17, (n(i + 17), c), (n(i + 17), c));
            }
        }
    }

    /// The capacitive couplings of the result nodes to the gates they drive, the output loads
    /// and the series transistors' charges (the end of the Test Set's `GCN`).
    fn couplings(&mut self) {
        // Result node `a` drives gates through `CGS` to `s` and `CGD` to `d`; `back` says
        // whether the driven nodes carry `-C U(a)` (the Test Set omits it for the series
        // transistors' gates, whose own charges hold `C (U - U(a))`).
        type Driven = (usize, usize, bool);
        let drives: [(usize, &[Driven]); 7] = [
            (5, &[(19, 20, true), (68, 69, true), (153, 154, true)]),
            (
                18,
                &[
                    (37, 38, true),
                    (59, 60, true),
                    (77, 78, true),
                    (167, 168, false),
                ],
            ),
            (36, &[(50, 51, true)]),
            (67, &[(117, 118, true), (136, 137, true)]),
            (85, &[(99, 100, true), (149, 150, true)]),
            (
                98,
                &[
                    (122, 123, true),
                    (140, 141, true),
                    (158, 159, true),
                    (162, 163, false),
                ],
            ),
            (116, &[(131, 132, true)]),
        ];
        for (a, driven) in drives {
            for &(s, d, back) in driven {
                self.linear(a, CGS, n(a), n(s));
                self.linear(a, CGD, n(a), n(d));
                if back {
                    self.linear(s, -CGS, n(a), GND);
                    self.linear(d, -CGD, n(a), GND);
                }
            }
        }
        self.linear(49, COUT, n(49), GND);
        self.linear(130, COUT, n(130), GND);
        self.junction(148, (n(165), n(148)), (n(148), n(165)));
        self.linear(148, COUT, n(148), GND);
        // The series transistors (internal nodes 162..175, coupling nodes 166, 171).
        self.linear(162, CGS, n(162), n(98));
        self.linear(163, CGD, n(163), n(98));
        self.junction(164, (n(164), n(166)), (n(164), n(166)));
        self.junction(165, (n(165), n(148)), (n(165), n(148)));
        self.junction(166, (n(164), n(166)), (n(166), n(164)));
        self.junction(166, (n(170), n(166)), (n(166), n(170)));
        self.linear(167, CGS, n(167), n(18));
        self.linear(168, CGD, n(168), n(18));
        self.junction(169, (n(169), n(171)), (n(169), n(171)));
        self.junction(170, (n(170), n(166)), (n(170), n(166)));
        self.junction(171, (n(169), n(171)), (n(171), n(169)));
        self.junction(171, (n(175), n(171)), (n(171), n(175)));
        self.linear(172, CGS, n(172), GND);
        self.linear(173, CGD, n(173), GND);
        self.junction(174, (n(174), GND), (n(174), GND));
        self.junction(175, (n(175), n(171)), (n(175), n(171)));
    }

    /// The Test Set's initial node potentials `U0` (a steady state of the circuit at `t = 0`).
    #[allow(clippy::excessive_precision)]
    pub const U0: [f64; NODES] = [
        4.999999999996544,
        4.999999999999970,
        -2.499999999999975,
        -2.499999999999975,
        4.999999999996514,
        0.000000000000000,
        4.999999999996514,
        -2.499999999999991,
        -2.499999999999975,
        0.000000000000000,
        4.999999999996514,
        -2.499999999999991,
        -2.499999999999975,
        0.215858486765796,
        4.988182208251953,
        -2.499999999999990,
        -2.499999999999975,
        0.204040695017748,
        0.011817791748026,
        0.192222903269723,
        -2.499999999999991,
        -2.499999999999990,
        -0.228160951881239,
        0.204040695017748,
        -2.499999999999992,
        -2.499999999999990,
        -0.228160951881241,
        0.000000000000000,
        -0.228160951881239,
        -2.499999999999991,
        -2.499999999999992,
        4.999999999996547,
        4.999999999999970,
        -2.499999999999975,
        -2.499999999999975,
        4.999999999996517,
        0.000000000000000,
        4.999999999996517,
        -2.499999999999991,
        -2.499999999999975,
        0.000000000000000,
        4.999999999996517,
        -2.499999999999991,
        -2.499999999999975,
        0.215858484247529,
        4.988182208251953,
        -2.499999999999990,
        -2.499999999999975,
        0.204040692499482,
        0.011817791748035,
        0.192222900751447,
        -2.499999999999991,
        -2.499999999999990,
        -0.026041071738432,
        0.204040692499482,
        -2.499999999999992,
        -2.499999999999990,
        -0.026041071738434,
        0.000000000000000,
        -0.026041071738432,
        -2.499999999999991,
        -2.499999999999992,
        0.215858484880918,
        4.988182208251953,
        -2.499999999999990,
        -2.499999999999975,
        0.204040693132870,
        0.011817791748026,
        0.192222901384845,
        -2.499999999999991,
        -2.499999999999990,
        -0.026041071737961,
        0.204040693132870,
        -2.499999999999992,
        -2.499999999999990,
        -0.026041071737963,
        0.000000000000000,
        -0.026041071737961,
        -2.499999999999991,
        -2.499999999999992,
        4.999999999996546,
        4.999999999999970,
        -2.499999999999975,
        -2.499999999999975,
        4.999999999996516,
        0.000000000000000,
        4.999999999996516,
        -2.499999999999991,
        -2.499999999999975,
        0.000000000000000,
        4.999999999996516,
        -2.499999999999991,
        -2.499999999999975,
        0.215858481060569,
        4.988182208251953,
        -2.499999999999990,
        -2.499999999999975,
        0.204040689312522,
        0.011817791748023,
        0.192222897564498,
        -2.499999999999991,
        -2.499999999999990,
        4.734672533390068,
        0.204040689312522,
        -2.499999999999977,
        -2.499999999999990,
        4.734672533390062,
        0.000000000000000,
        4.734672533390068,
        -2.499999999999991,
        -2.499999999999977,
        4.999999999996870,
        4.999999999999972,
        -2.499999999999975,
        -2.499999999999975,
        4.999999999996843,
        -0.025968303070038,
        4.999999999996843,
        -2.499999999999992,
        -2.499999999999975,
        -0.025968303070040,
        0.000000000000000,
        -0.025968303070038,
        -2.499999999999991,
        -2.499999999999992,
        4.999999999997699,
        4.999999999999980,
        -2.499999999999975,
        -2.499999999999975,
        4.999999999997678,
        4.744923533081106,
        4.999999999997678,
        -2.499999999999977,
        -2.499999999999975,
        4.744923533081098,
        0.000000000000000,
        4.744923533081106,
        -2.499999999999991,
        -2.499999999999977,
        0.000000000000000,
        4.744923533081106,
        -2.499999999999991,
        -2.499999999999977,
        0.215858484844162,
        4.988182208251953,
        -2.499999999999990,
        -2.499999999999975,
        0.204040693096114,
        0.011817791748023,
        0.192222901348091,
        -2.499999999999991,
        -2.499999999999990,
        0.204040693096045,
        0.204040693096107,
        -2.499999999999990,
        -2.499999999999990,
        0.204040693096037,
        0.000000000000000,
        0.204040693096037,
        -2.499999999999991,
        -2.499999999999990,
        -0.026017361873565,
        0.204040693096114,
        -2.499999999999992,
        -2.499999999999990,
        -0.026017361873568,
        -0.026017590106916,
        -0.026017361873565,
        -2.499999999999992,
        -2.499999999999992,
        -0.026017590106918,
        0.000000000000000,
        -0.026017590106916,
        -2.499999999999991,
        -2.499999999999992,
    ];

    /// The Test Set's `(y0, y0')`: `y0 = (g(U0), U0)`, `y0' = 0` (`f(0, y0)` is not exactly
    /// zero: its largest entry is printed by the tests; the integrators start from it as
    /// given, as the Test Set's drivers do).
    pub fn initial(&self) -> (Vec<f64>, Vec<f64>) {
        let mut y = vec![0.0; TBA_N];
        let g = self.charge(&Self::U0);
        y[..NODES].copy_from_slice(&g);
        y[NODES..].copy_from_slice(&Self::U0);
        (y, vec![0.0; TBA_N])
    }

    /// The charges `g(U)`.
    pub fn charge(&self, u: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; NODES];
        let v = |x: T| match x {
            T::Node(k) => u[k],
            T::Fixed(c) => c,
            T::Input(_) => unreachable_input(),
        };
        for c in &self.charges {
            let cap = c.cap.unwrap_or_else(|| cbdbs(v(c.arg.0) - v(c.arg.1)).0);
            g[c.row] += cap * (v(c.mul.0) - v(c.mul.1));
        }
        g
    }

    /// The currents `f(t, U)`.
    pub fn current(&self, t: f64, u: &[f64]) -> Vec<f64> {
        let mut f = vec![0.0; NODES];
        self.currents(t, u, &mut f, &mut |_, _, _| {});
        f
    }

    /// `f(t, U)` into `f` and each partial derivative `(row, node, df_row/dU_node)` to `df`
    /// (several calls for one entry add up; zero derivatives are reported too, so that the
    /// calls cover the structure).
    fn currents(&self, t: f64, u: &[f64], f: &mut [f64], df: &mut impl FnMut(usize, usize, f64)) {
        let inp = inputs(t);
        let v = |x: T| match x {
            T::Node(k) => u[k],
            T::Fixed(c) => c,
            T::Input(k) => inp[k].0,
        };
        // d(value)/d(terminal) as derivative entries of row `row`.
        let mut d = |row: usize, x: T, value: f64| {
            if let T::Node(k) = x {
                df(row, k, value);
            }
        };
        for m in &self.mos {
            let j = m.j;
            let (src, drn, bs, bd) = (T::Node(j), T::Node(j + 1), T::Node(j + 2), T::Node(j + 3));
            let args = [(drn, src), (m.g, src), (bs, m.s), (m.g, drn), (bd, m.d)];
            let a: [f64; 5] = std::array::from_fn(|k| v(args[k].0) - v(args[k].1));
            let (i, gi) = ids(m.kind, a[0], a[1], a[2], a[3], a[4]);
            let slope = match m.g {
                T::Input(k) => inp[k].1,
                _ => 0.0,
            };
            // Source and drain of the channel: resistor to the external terminal, the drain
            // current leaving the source and entering the drain.
            f[j] += CGS * slope - (u[j] - v(m.s)) / RGS - i;
            f[j + 1] += CGD * slope - (u[j + 1] - v(m.d)) / RGD + i;
            d(j, src, -1.0 / RGS);
            d(j, m.s, 1.0 / RGS);
            d(j + 1, drn, -1.0 / RGD);
            d(j + 1, m.d, 1.0 / RGD);
            for k in 0..5 {
                d(j, args[k].0, -gi[k]);
                d(j, args[k].1, gi[k]);
                d(j + 1, args[k].0, gi[k]);
                d(j + 1, args[k].1, -gi[k]);
            }
            // Bulk nodes: resistor to VBB, junction to the external source / drain.
            let (ibs, dibs) = ib(a[2]);
            let (ibd, dibd) = ib(a[4]);
            f[j + 2] += -(u[j + 2] - VBB) / RBS + ibs;
            f[j + 3] += -(u[j + 3] - VBB) / RBD + ibd;
            d(j + 2, bs, -1.0 / RBS + dibs);
            d(j + 2, m.s, -dibs);
            d(j + 3, bd, -1.0 / RBD + dibd);
            d(j + 3, m.d, -dibd);
            // The external source and drain nodes receive the opposite currents.
            if let T::Node(s) = m.s {
                f[s] += -(u[s] - u[j]) / RGS - ibs;
                d(s, m.s, 1.0 / -RGS + dibs);
                d(s, src, 1.0 / RGS);
                d(s, bs, -dibs);
            }
            if let T::Node(dn) = m.d {
                f[dn] += -(u[dn] - u[j + 1]) / RGD - ibd;
                d(dn, m.d, 1.0 / -RGD + dibd);
                d(dn, drn, 1.0 / RGD);
                d(dn, bd, -dibd);
            }
        }
    }

    /// `g(U)` into `g` and each partial derivative `(row, node, dg_row/dU_node)` to `dg`.
    fn charges_with(&self, u: &[f64], g: &mut [f64], dg: &mut impl FnMut(usize, usize, f64)) {
        let v = |x: T| match x {
            T::Node(k) => u[k],
            T::Fixed(c) => c,
            T::Input(_) => unreachable_input(),
        };
        let mut d = |row: usize, x: T, value: f64| {
            if let T::Node(k) = x {
                dg(row, k, value);
            }
        };
        for c in &self.charges {
            let w = v(c.mul.0) - v(c.mul.1);
            let cap = match c.cap {
                Some(cap) => cap,
                None => {
                    let (cap, dcap) = cbdbs(v(c.arg.0) - v(c.arg.1));
                    d(c.row, c.arg.0, dcap * w);
                    d(c.row, c.arg.1, -dcap * w);
                    cap
                }
            };
            g[c.row] += cap * w;
            d(c.row, c.mul.0, cap);
            d(c.row, c.mul.1, -cap);
        }
    }
}

/// The charges do not depend on the inputs.
fn unreachable_input() -> f64 {
    f64::NAN
}

impl Default for TwoBitAdder {
    fn default() -> Self {
        Self::new()
    }
}

impl ImplicitDae for TwoBitAdder {
    fn dimension(&self) -> usize {
        TBA_N
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let u = &y[NODES..];
        let (top, bottom) = out.split_at_mut(NODES);
        top.fill(0.0);
        self.currents(t, u, top, &mut |_, _, _| {});
        for i in 0..NODES {
            top[i] = yp[i] - top[i];
        }
        bottom.fill(0.0);
        self.charges_with(u, bottom, &mut |_, _, _| {});
        for i in 0..NODES {
            bottom[i] = y[i] - bottom[i];
        }
    }

    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        _yp: &[f64],
        c: f64,
        m: &mut S,
    ) {
        let u = &y[NODES..];
        let mut scratch = [0.0; NODES];
        for i in 0..NODES {
            m.add(i, i, c);
            m.add(NODES + i, i, 1.0);
        }
        self.currents(t, u, &mut scratch, &mut |r, k, v| m.add(r, NODES + k, -v));
        self.charges_with(u, &mut scratch, &mut |r, k, v| {
            m.add(NODES + r, NODES + k, -v)
        });
    }

    /// The constant `diag(I, 0)`: the charges' derivatives in the current rows.
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..NODES {
            m.add(i, i, 1.0);
        }
        true
    }

    fn is_differential(&self, i: usize) -> bool {
        i < NODES
    }

    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        let mut p: Vec<(usize, usize)> =
            (0..NODES).flat_map(|i| [(i, i), (NODES + i, i)]).collect();
        let (y, _) = self.initial();
        let u = &y[NODES..];
        let mut scratch = [0.0; NODES];
        self.currents(0.0, u, &mut scratch, &mut |r, k, _| p.push((r, NODES + k)));
        self.charges_with(u, &mut scratch, &mut |r, k, _| {
            p.push((NODES + r, NODES + k))
        });
        p.sort_unstable();
        p.dedup();
        Some(p)
    }
}
