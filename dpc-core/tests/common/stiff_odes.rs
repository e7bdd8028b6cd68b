//! The stiff ODEs of the Test Set for IVP solvers (Mazzia, Magherini et al.), each written as
//! the implicit DAE `F(t, y, y') = y' - f(t, y)` with an identity mass matrix, the form a user
//! of an implicit DAE integrator gives them in (and diffsol's home ground):
//!
//! * Van der Pol (`vdpol.f`, the rescaled form with `eps = 1e-6`, 2 unknowns, `t` in `[0, 2]`),
//! * OREGO (`orego.f`, the Oregonator of Field and Noyes, 3 unknowns, `t` in `[0, 360]`),
//! * Pollution (`pollu.f`, Verwer's air pollution model, 20 unknowns, `t` in `[0, 60]`),
//! * the ring modulator (`ringmod.f`, Horneber's circuit, 15 unknowns, `t` in `[0, 1e-3]`).
//!
//! Every problem implements [`StiffOde`] (`f` and its exact Jacobian `df/dy` entry by entry)
//! and is integrated as [`Ode`]`(problem)`, whose iteration matrix is `c I - df/dy`. The
//! initial values and the reference solutions at the interval's end are the Test Set's
//! (`init`, `solut`); the Test Set scores every component of these four problems, with
//! `rtol = atol`.
#![allow(dead_code)]

use dpc_core::{ImplicitDae, MatrixSink};

/// A stiff ODE `y' = f(t, y)` of the Test Set.
pub trait StiffOde {
    /// Number of unknowns.
    const N: usize;
    /// The end of the integration interval (the start is `t = 0`).
    const T_END: f64;
    /// The unknowns' names, in order.
    const NAMES: &'static [&'static str];

    /// `f(t, y)` into `out`.
    fn f(&self, t: f64, y: &[f64], out: &mut [f64]);

    /// Every structurally non-zero entry `(row, column, df_row/dy_column)` of `df/dy` at
    /// `(t, y)`, passed to `entry` (an entry may come more than once: the values add up).
    fn jacobian(&self, t: f64, y: &[f64], entry: impl FnMut(usize, usize, f64));

    /// The Test Set's initial values `y(0)`.
    fn y0(&self) -> Vec<f64>;

    /// The Test Set's reference solution at [`T_END`](Self::T_END).
    fn reference(&self) -> Vec<f64>;
}

/// A [`StiffOde`] as the implicit DAE `F = y' - f(t, y)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ode<P>(pub P);

impl<P: StiffOde> Ode<P> {
    /// `(y(0), y'(0) = f(0, y(0)))`: consistent.
    pub fn initial(&self) -> (Vec<f64>, Vec<f64>) {
        let y = self.0.y0();
        let mut yp = vec![0.0; P::N];
        self.0.f(0.0, &y, &mut yp);
        (y, yp)
    }
}

impl<P: StiffOde> ImplicitDae for Ode<P> {
    fn dimension(&self) -> usize {
        P::N
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.0.f(t, y, out);
        for (o, p) in out.iter_mut().zip(yp) {
            *o = p - *o;
        }
    }
    /// `c I - df/dy`.
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        t: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        for i in 0..P::N {
            m.add(i, i, c);
        }
        self.0.jacobian(t, y, |r, k, v| m.add(r, k, -v));
    }
    /// The identity (an ODE).
    fn mass_matrix<S: MatrixSink + ?Sized>(&self, _: f64, _: &[f64], _: &[f64], m: &mut S) -> bool {
        for i in 0..P::N {
            m.set(i, i, 1.0);
        }
        true
    }
    fn is_differential(&self, _: usize) -> bool {
        true
    }
    fn equation_name(&self, i: usize) -> String {
        format!("d{}/dt", P::NAMES[i])
    }
    fn unknown_name(&self, i: usize) -> String {
        P::NAMES[i].to_string()
    }
}

/// The Test Set's Van der Pol problem (`vdpol.f`): `y1' = y2`,
/// `y2' = ((1 - y1^2) y2 - y1) / eps` with `eps = 1e-6` (the rescaled form: a relaxation
/// oscillation of period about 0.8 in `t`, with near-jumps of `y2` of size `1/eps` time scales),
/// `y(0) = (2, 0)`, to `t = 2`.
#[derive(Debug, Clone, Copy, Default)]
pub struct VanDerPol;

/// The stiffness parameter of [`VanDerPol`].
pub const VDPOL_EPS: f64 = 1e-6;

impl StiffOde for VanDerPol {
    const N: usize = 2;
    const T_END: f64 = 2.0;
    const NAMES: &'static [&'static str] = &["y1", "y2"];

    fn f(&self, _: f64, y: &[f64], out: &mut [f64]) {
        out[0] = y[1];
        out[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / VDPOL_EPS;
    }
    fn jacobian(&self, _: f64, y: &[f64], mut entry: impl FnMut(usize, usize, f64)) {
        entry(0, 1, 1.0);
        entry(1, 0, (-2.0 * y[0] * y[1] - 1.0) / VDPOL_EPS);
        entry(1, 1, (1.0 - y[0] * y[0]) / VDPOL_EPS);
    }
    fn y0(&self) -> Vec<f64> {
        vec![2.0, 0.0]
    }
    /// `solut` of `vdpol.f` (RADAU in extended precision, `rtol = atol = 1.1e-18`).
    #[allow(clippy::excessive_precision)]
    fn reference(&self) -> Vec<f64> {
        vec![0.1706167732170483e1, -0.8928097010247975]
    }
}

/// The Test Set's OREGO problem (`orego.f`): the Oregonator, the Field-Noyes model of the
/// Belousov-Zhabotinskii reaction, `y(0) = (1, 2, 3)`, to `t = 360` (a periodic solution whose
/// components sweep several orders of magnitude):
///
/// ```text
/// y1' = s (y2 + y1 (1 - q y1 - y2)),   s = 77.27, q = 8.375e-6
/// y2' = (y3 - (1 + y1) y2) / s
/// y3' = w (y1 - y3),                   w = 0.161
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct Orego;

const OREGO_S: f64 = 77.27;
const OREGO_Q: f64 = 8.375e-6;
const OREGO_W: f64 = 0.161;

impl StiffOde for Orego {
    const N: usize = 3;
    const T_END: f64 = 360.0;
    const NAMES: &'static [&'static str] = &["HBrO2", "Br-", "Ce(IV)"];

    fn f(&self, _: f64, y: &[f64], out: &mut [f64]) {
        out[0] = OREGO_S * (y[1] + y[0] * (1.0 - OREGO_Q * y[0] - y[1]));
        out[1] = (y[2] - (1.0 + y[0]) * y[1]) / OREGO_S;
        out[2] = OREGO_W * (y[0] - y[2]);
    }
    fn jacobian(&self, _: f64, y: &[f64], mut entry: impl FnMut(usize, usize, f64)) {
        entry(0, 0, OREGO_S * (1.0 - 2.0 * OREGO_Q * y[0] - y[1]));
        entry(0, 1, OREGO_S * (1.0 - y[0]));
        entry(1, 0, -y[1] / OREGO_S);
        entry(1, 1, -(1.0 + y[0]) / OREGO_S);
        entry(1, 2, 1.0 / OREGO_S);
        entry(2, 0, OREGO_W);
        entry(2, 2, -OREGO_W);
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 2.0, 3.0]
    }
    /// `solut` of `orego.f`.
    #[allow(clippy::excessive_precision)]
    fn reference(&self) -> Vec<f64> {
        vec![
            0.1000814870318523e1,
            0.1228178521549917e4,
            0.1320554942846706e3,
        ]
    }
}

/// The Test Set's Pollution problem (`pollu.f`; Verwer 1994, the chemistry of an air pollution
/// model at the Dutch National Institute of Public Health, RIVM): 20 species, 25 reactions of
/// mass-action kinetics with rate constants from `0.82e-3` to `0.444e12`, to `t = 60`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Pollution;

/// The 25 rate constants `k1..k25` of [`Pollution`].
const POLLU_K: [f64; 25] = [
    0.35, 0.266e2, 0.123e5, 0.86e-3, 0.82e-3, 0.15e5, 0.13e-3, 0.24e5, 0.165e5, 0.9e4, 0.22e-1,
    0.12e5, 0.188e1, 0.163e5, 0.48e7, 0.35e-3, 0.175e-1, 0.1e9, 0.444e12, 0.124e4, 0.21e1, 0.578e1,
    0.474e-1, 0.178e4, 0.312e1,
];

/// The reactions of [`Pollution`]: reaction `r` has rate `k_r` times the product of its
/// reactants' concentrations (one or two species, 0-based; `None` for none), and its
/// stoichiometry: the species it consumes and those it produces (a species listed twice
/// changes by two).
struct Reaction {
    reactants: (usize, Option<usize>),
    produces: &'static [usize],
}

/// `pollu.f`'s reactions, 0-based species: `r1 = k1 y1`, `r2 = k2 y2 y4`, ... (the Test Set's
/// `r(i)`), each with the species whose `f` it enters with a plus sign; every reaction enters
/// its reactants' rows with a minus sign.
const POLLU_REACTIONS: [Reaction; 25] = [
    Reaction {
        reactants: (0, None),
        produces: &[1, 2],
    },
    Reaction {
        reactants: (1, Some(3)),
        produces: &[0],
    },
    Reaction {
        reactants: (4, Some(1)),
        produces: &[0, 5],
    },
    Reaction {
        reactants: (6, None),
        produces: &[4, 4, 7],
    },
    Reaction {
        reactants: (6, None),
        produces: &[7],
    },
    Reaction {
        reactants: (6, Some(5)),
        produces: &[4, 7],
    },
    Reaction {
        reactants: (8, None),
        produces: &[4, 7, 9],
    },
    Reaction {
        reactants: (8, Some(5)),
        produces: &[10],
    },
    Reaction {
        reactants: (10, Some(1)),
        produces: &[0, 9, 11],
    },
    Reaction {
        reactants: (10, Some(0)),
        produces: &[12],
    },
    Reaction {
        reactants: (12, None),
        produces: &[0, 10],
    },
    Reaction {
        reactants: (9, Some(1)),
        produces: &[0, 13],
    },
    Reaction {
        reactants: (13, None),
        produces: &[4, 6],
    },
    Reaction {
        reactants: (0, Some(5)),
        produces: &[14],
    },
    Reaction {
        reactants: (2, None),
        produces: &[3],
    },
    Reaction {
        reactants: (3, None),
        produces: &[15],
    },
    Reaction {
        reactants: (3, None),
        produces: &[2],
    },
    Reaction {
        reactants: (15, None),
        produces: &[5, 5],
    },
    Reaction {
        reactants: (15, None),
        produces: &[2],
    },
    Reaction {
        reactants: (16, Some(5)),
        produces: &[4, 17],
    },
    Reaction {
        reactants: (18, None),
        produces: &[1],
    },
    Reaction {
        reactants: (18, None),
        produces: &[0, 2],
    },
    Reaction {
        reactants: (0, Some(3)),
        produces: &[18],
    },
    Reaction {
        reactants: (18, Some(0)),
        produces: &[19],
    },
    Reaction {
        reactants: (19, None),
        produces: &[0, 18],
    },
];

impl Pollution {
    /// The reactions' rates `r1..r25` at `y`.
    fn rates(y: &[f64]) -> [f64; 25] {
        let mut r = [0.0; 25];
        for (i, (reaction, k)) in POLLU_REACTIONS.iter().zip(POLLU_K).enumerate() {
            let (a, b) = reaction.reactants;
            r[i] = k * y[a] * b.map_or(1.0, |b| y[b]);
        }
        r
    }
}

impl StiffOde for Pollution {
    const N: usize = 20;
    const T_END: f64 = 60.0;
    const NAMES: &'static [&'static str] = &[
        "NO2", "NO", "O3P", "O3", "HO2", "OH", "HCHO", "CO", "ALD", "MEO2", "C2O3", "CO2", "PAN",
        "CH3O", "HNO3", "O1D", "SO2", "SO4", "NO3", "N2O5",
    ];

    fn f(&self, _: f64, y: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (reaction, r) in POLLU_REACTIONS.iter().zip(Self::rates(y)) {
            let (a, b) = reaction.reactants;
            out[a] -= r;
            if let Some(b) = b {
                out[b] -= r;
            }
            for &p in reaction.produces {
                out[p] += r;
            }
        }
    }
    fn jacobian(&self, _: f64, y: &[f64], mut entry: impl FnMut(usize, usize, f64)) {
        for (reaction, k) in POLLU_REACTIONS.iter().zip(POLLU_K) {
            let (a, b) = reaction.reactants;
            // d r / d y_a (k y_b, or k alone) and d r / d y_b (k y_a).
            let first = (a, k * b.map_or(1.0, |b| y[b]));
            for (col, d) in std::iter::once(first).chain(b.map(|b| (b, k * y[a]))) {
                entry(a, col, -d);
                if let Some(b) = b {
                    entry(b, col, -d);
                }
                for &p in reaction.produces {
                    entry(p, col, d);
                }
            }
        }
    }
    /// `init` of `pollu.f`: NO 0.2, O3 0.04, HCHO 0.1, CO 0.3, ALD 0.01, SO2 0.007, the rest 0.
    fn y0(&self) -> Vec<f64> {
        let mut y = vec![0.0; 20];
        y[1] = 0.2;
        y[3] = 0.04;
        y[6] = 0.1;
        y[7] = 0.3;
        y[8] = 0.01;
        y[16] = 0.007;
        y
    }
    /// `solut` of `pollu.f` (RADAU5 in extended precision, `rtol = atol = 1.1e-18`).
    #[allow(clippy::excessive_precision)]
    fn reference(&self) -> Vec<f64> {
        vec![
            0.5646255480022769e-01,
            0.1342484130422339e+00,
            0.4139734331099427e-08,
            0.5523140207484359e-02,
            0.2018977262302196e-06,
            0.1464541863493966e-06,
            0.7784249118997964e-01,
            0.3245075353396018e+00,
            0.7494013383880406e-02,
            0.1622293157301561e-07,
            0.1135863833257075e-07,
            0.2230505975721359e-02,
            0.2087162882798630e-03,
            0.1396921016840158e-04,
            0.8964884856898295e-02,
            0.4352846369330103e-17,
            0.6899219696263405e-02,
            0.1007803037365946e-03,
            0.1772146513969984e-05,
            0.5682943292316392e-04,
        ]
    }
}

/// The Test Set's ring modulator (`ringmod.f`, the ODE form; Horneber 1976, Kampowsky, Rentrop
/// and Schmidt 1992): a diode ring mixing a 1 kHz signal `Uin1 = 0.5 sin(2e3 pi t)` with a
/// 10 kHz carrier `Uin2 = 2 sin(2e4 pi t)`, 15 unknowns (the Test Set's numbering: the node
/// voltages `y1..y7`, the inductor currents `y8..y15`), from rest to `t = 1e-3`. Each diode
/// conducts `q(U) = gamma (e^(delta U) - 1)`; the parasitic capacitance `Cs = 2e-12` makes
/// it very stiff and the carrier makes it oscillate fast.
#[derive(Debug, Clone, Copy, Default)]
pub struct RingModulator;

// The Test Set's parameters.
const RM_C: f64 = 1.6e-8;
const RM_CS: f64 = 2e-12;
const RM_CP: f64 = 1e-8;
const RM_R: f64 = 25e3;
const RM_RP: f64 = 50.0;
const RM_LH: f64 = 4.45;
const RM_LS1: f64 = 2e-3;
const RM_LS2: f64 = 5e-4;
const RM_LS3: f64 = 5e-4;
const RM_RG1: f64 = 36.3;
const RM_RG2: f64 = 17.3;
const RM_RG3: f64 = 17.3;
const RM_RI: f64 = 50.0;
const RM_RC: f64 = 600.0;
const RM_GAMMA: f64 = 40.67286402e-9;
const RM_DELTA: f64 = 17.7493332;

/// The four diode voltages `U_k = sum (sign, unknown) - s_k Uin2` of [`RingModulator`]: the
/// unknowns (0-based) with their signs, and the sign `s_k` of `Uin2` (`ud1 = y3 - y5 - y7 -
/// Uin2`, `ud2 = -y4 + y6 - y7 - Uin2`, `ud3 = y4 + y5 + y7 + Uin2`, `ud4 = -y3 - y6 + y7 +
/// Uin2`).
const RM_DIODES: [([(usize, f64); 3], f64); 4] = [
    ([(2, 1.0), (4, -1.0), (6, -1.0)], -1.0),
    ([(3, -1.0), (5, 1.0), (6, -1.0)], -1.0),
    ([(3, 1.0), (4, 1.0), (6, 1.0)], 1.0),
    ([(2, -1.0), (5, -1.0), (6, 1.0)], 1.0),
];

/// How the diode currents `q1..q4` enter `f3..f7` of [`RingModulator`] (rows 2..6, before the
/// division by the row's capacitance): `f3 ~ -q1 + q4`, `f4 ~ q2 - q3`, `f5 ~ q1 - q3`,
/// `f6 ~ -q2 + q4`, `f7 ~ q1 + q2 - q3 - q4`.
const RM_DIODE_ROWS: [[f64; 4]; 5] = [
    [-1.0, 0.0, 0.0, 1.0],
    [0.0, 1.0, -1.0, 0.0],
    [1.0, 0.0, -1.0, 0.0],
    [0.0, -1.0, 0.0, 1.0],
    [1.0, 1.0, -1.0, -1.0],
];

impl RingModulator {
    /// The inputs `(Uin1, Uin2)` at `t`.
    fn inputs(t: f64) -> (f64, f64) {
        let pi = std::f64::consts::PI;
        (0.5 * (2e3 * pi * t).sin(), 2.0 * (2e4 * pi * t).sin())
    }

    /// The diode voltages `U_k` at `(t, y)`.
    fn diode_voltages(t: f64, y: &[f64]) -> [f64; 4] {
        let (_, uin2) = Self::inputs(t);
        RM_DIODES.map(|(terms, s)| terms.iter().map(|&(j, a)| a * y[j]).sum::<f64>() + s * uin2)
    }

    /// The capacitance of rows 2..6 (`y3..y7`).
    fn row_capacitance(row: usize) -> f64 {
        if row == 6 {
            RM_CP
        } else {
            RM_CS
        }
    }
}

impl StiffOde for RingModulator {
    const N: usize = 15;
    const T_END: f64 = 1e-3;
    const NAMES: &'static [&'static str] = &[
        "y1", "y2", "y3", "y4", "y5", "y6", "y7", "y8", "y9", "y10", "y11", "y12", "y13", "y14",
        "y15",
    ];

    fn f(&self, t: f64, y: &[f64], out: &mut [f64]) {
        let (uin1, _) = Self::inputs(t);
        let q = Self::diode_voltages(t, y).map(|u| RM_GAMMA * ((RM_DELTA * u).exp() - 1.0));
        out[0] = (y[7] - 0.5 * y[9] + 0.5 * y[10] + y[13] - y[0] / RM_R) / RM_C;
        out[1] = (y[8] - 0.5 * y[11] + 0.5 * y[12] + y[14] - y[1] / RM_R) / RM_C;
        // The linear parts of rows 2..6: y10, -y11, y12, -y13, -y7 / Rp.
        let linear = [y[9], -y[10], y[11], -y[12], -y[6] / RM_RP];
        for (k, (row, lin)) in RM_DIODE_ROWS.iter().zip(linear).enumerate() {
            let currents: f64 = row.iter().zip(&q).map(|(a, q)| a * q).sum();
            out[2 + k] = (lin + currents) / Self::row_capacitance(2 + k);
        }
        out[7] = -y[0] / RM_LH;
        out[8] = -y[1] / RM_LH;
        out[9] = (0.5 * y[0] - y[2] - RM_RG2 * y[9]) / RM_LS2;
        out[10] = (-0.5 * y[0] + y[3] - RM_RG3 * y[10]) / RM_LS3;
        out[11] = (0.5 * y[1] - y[4] - RM_RG2 * y[11]) / RM_LS2;
        out[12] = (-0.5 * y[1] + y[5] - RM_RG3 * y[12]) / RM_LS3;
        out[13] = (-y[0] + uin1 - (RM_RI + RM_RG1) * y[13]) / RM_LS1;
        out[14] = (-y[1] - (RM_RC + RM_RG1) * y[14]) / RM_LS1;
    }
    fn jacobian(&self, t: f64, y: &[f64], mut e: impl FnMut(usize, usize, f64)) {
        // Rows 0, 1.
        for (row, (a, b, c, d, own)) in [(7, 9, 10, 13, 0), (8, 11, 12, 14, 1)]
            .into_iter()
            .enumerate()
        {
            e(row, a, 1.0 / RM_C);
            e(row, b, -0.5 / RM_C);
            e(row, c, 0.5 / RM_C);
            e(row, d, 1.0 / RM_C);
            e(row, own, -1.0 / (RM_R * RM_C));
        }
        // Rows 2..6: linear parts and the diodes, dq_k/dU_k = gamma delta e^(delta U_k).
        let linear = [
            (9, 1.0),
            (10, -1.0),
            (11, 1.0),
            (12, -1.0),
            (6, -1.0 / RM_RP),
        ];
        let dq = Self::diode_voltages(t, y).map(|u| RM_GAMMA * RM_DELTA * (RM_DELTA * u).exp());
        for (k, (row, (col, a))) in RM_DIODE_ROWS.iter().zip(linear).enumerate() {
            let cap = Self::row_capacitance(2 + k);
            e(2 + k, col, a / cap);
            for ((coef, (terms, _)), g) in row.iter().zip(&RM_DIODES).zip(dq) {
                if *coef != 0.0 {
                    for &(j, s) in terms {
                        e(2 + k, j, coef * g * s / cap);
                    }
                }
            }
        }
        e(7, 0, -1.0 / RM_LH);
        e(8, 1, -1.0 / RM_LH);
        for (row, (node, branch, ls, rg, sign)) in [
            (9, (2, 0, RM_LS2, RM_RG2, 1.0)),
            (10, (3, 0, RM_LS3, RM_RG3, -1.0)),
            (11, (4, 1, RM_LS2, RM_RG2, 1.0)),
            (12, (5, 1, RM_LS3, RM_RG3, -1.0)),
        ] {
            e(row, branch, 0.5 * sign / ls);
            e(row, node, -sign / ls);
            e(row, row, -rg / ls);
        }
        e(13, 0, -1.0 / RM_LS1);
        e(13, 13, -(RM_RI + RM_RG1) / RM_LS1);
        e(14, 1, -1.0 / RM_LS1);
        e(14, 14, -(RM_RC + RM_RG1) / RM_LS1);
    }
    /// `init` of `ringmod.f`: all zero.
    fn y0(&self) -> Vec<f64> {
        vec![0.0; 15]
    }
    /// `solut` of `ringmod.f` (RADAU at `rtol = atol = 1e-12`).
    #[allow(clippy::excessive_precision)]
    fn reference(&self) -> Vec<f64> {
        vec![
            -0.2339057358486745e-01,
            -0.7367485485540825e-02,
            0.2582956709291169e+00,
            -0.4064465721283450e+00,
            -0.4039455665149794e+00,
            0.2607966765422943e+00,
            0.1106761861269975e+00,
            0.2939904342435596e-06,
            -0.2840029933642329e-07,
            0.7267198267264553e-03,
            0.7929487196960840e-03,
            -0.7255283495698965e-03,
            -0.7941401968526521e-03,
            0.7088495416976114e-04,
            0.2390059075236570e-04,
        ]
    }
}
