//! The preliminary feedback of the paper (Section 3.1): the law
//! `u = u0(t) + K_n (x - x0(t)) + v` and the nominal trajectories `(x0(t), u0(t))` it acts
//! about.
//!
//! * [`Nominal`]: any nominal trajectory;
//! * [`SteadyMotion`]: an equilibrium or a steady motion `x0(t) = x0 + t x0'` with constant
//!   algebraic unknowns and inputs, as the trim solver of [`crate::design`] finds it;
//! * [`ReferenceNominal`]: a nominal whose chosen states follow the reference instead;
//! * [`Prefeedback`]: the law itself, with the one chain rule `dF/dx + dF/du K_n` that both the
//!   controller (on the tracking DAE) and the closed loop (on the plant) need.
//!
//! `K_n` comes from [`crate::linear_analysis::analyze`] on a linearisation about the nominal; the whole
//! chain from a model to a law is [`crate::design`].

use crate::reference::{Reference, ReferenceError};
use crate::sink::MatrixSink;
use nalgebra::{DMatrix, DMatrixView};
use thiserror::Error;

/// Why a nominal or a preliminary feedback could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum NominalError {
    /// A vector of a steady motion has the wrong length.
    #[error("steady motion: `{what}` has {found} entries, expected {expected}")]
    Dimension {
        /// Which vector (`state`, `rate`, `algebraic`, `input`).
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A value of a steady motion is NaN or infinite.
    #[error("steady motion: `{what}` entry {index} is {value}, not a finite number")]
    NonFinite {
        /// Which vector.
        what: &'static str,
        /// Position in it.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A reference-state map entry names a state the model does not have.
    #[error("reference-state map: state index {state}, but the model has {n_states} states")]
    StateIndex {
        /// The index given.
        state: usize,
        /// Number of states.
        n_states: usize,
    },
    /// A reference-state map entry names a reference component that does not exist.
    #[error(
        "reference-state map: output index {output}, but the reference has {dimension} components"
    )]
    OutputIndex {
        /// The index given.
        output: usize,
        /// Components of the reference.
        dimension: usize,
    },
    /// The reference cannot give a derivative the map asks for.
    #[error(transparent)]
    Reference(#[from] ReferenceError),
}

/// A nominal trajectory `(x0(t), u0(t))` about which a preliminary feedback acts.
pub trait Nominal {
    /// `x0(t)` into `x0` (length = number of states).
    fn state(&self, t: f64, x0: &mut [f64]);
    /// `u0(t)` into `u0` (length = number of inputs).
    fn input(&self, t: f64, u0: &mut [f64]);
}

/// An equilibrium or a steady motion: `x0(t) = state + t * rate` with constant algebraic
/// unknowns and inputs (`rate = 0` for an equilibrium). The values are those at `t = 0`; a
/// steady motion in the nonlinear sense needs the equations not to depend on the states
/// that move (cyclic coordinates, such as the wheel's heading), which
/// [`crate::design::trim`] checks along the motion.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SteadyMotion {
    /// `x0(0)`.
    pub state: Vec<f64>,
    /// `x0'`, constant.
    pub rate: Vec<f64>,
    /// The algebraic unknowns `z0`, constant.
    pub algebraic: Vec<f64>,
    /// `u0`, constant.
    pub input: Vec<f64>,
}

impl SteadyMotion {
    /// The motion with the given values, checked against the model's dimensions
    /// `(states, algebraic unknowns, inputs)`.
    ///
    /// # Errors
    /// [`NominalError::Dimension`] for a wrong length, [`NominalError::NonFinite`] for a NaN
    /// or infinite value.
    pub fn new(
        dimensions: (usize, usize, usize),
        state: Vec<f64>,
        rate: Vec<f64>,
        algebraic: Vec<f64>,
        input: Vec<f64>,
    ) -> Result<Self, NominalError> {
        let (nx, nz, nu) = dimensions;
        for (what, v, n) in [
            ("state", &state, nx),
            ("rate", &rate, nx),
            ("algebraic", &algebraic, nz),
            ("input", &input, nu),
        ] {
            if v.len() != n {
                return Err(NominalError::Dimension {
                    what,
                    expected: n,
                    found: v.len(),
                });
            }
            if let Some((index, &value)) = v.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(NominalError::NonFinite { what, index, value });
            }
        }
        Ok(Self {
            state,
            rate,
            algebraic,
            input,
        })
    }

    /// `x0(t)` as a new vector.
    pub fn state_at(&self, t: f64) -> Vec<f64> {
        let mut x = vec![0.0; self.state.len()];
        self.state(t, &mut x);
        x
    }
}

impl Nominal for SteadyMotion {
    fn state(&self, t: f64, x0: &mut [f64]) {
        for ((x, s), r) in x0.iter_mut().zip(&self.state).zip(&self.rate) {
            *x = s + t * r;
        }
    }

    fn input(&self, _t: f64, u0: &mut [f64]) {
        u0.copy_from_slice(&self.input);
    }
}

/// Which state component of a [`ReferenceNominal`] follows which derivative of the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReferenceState {
    /// Index of the state in `x`.
    pub state: usize,
    /// Index of the reference component (output).
    pub output: usize,
    /// Derivative order: `x0_state(t) = xi_output^(order)(t)`.
    pub order: usize,
}

/// A preliminary feedback taken *about the reference* instead of about the nominal motion it
/// was designed on: `x0(t)` is the base nominal with the listed states replaced by the
/// reference and its derivatives (for the wheel: `theta`, `psi` by `theta_ref`, `psi_ref`, and
/// `dtheta`, `dpsi` by their derivatives), while `u0(t)` stays the base nominal's.
///
/// For a linear plant the choice does not matter (DPC absorbs any affine offset of the
/// feedback into `v`). For a nonlinear plant whose reference drifts away from the nominal,
/// the feedback about the nominal pulls the plant back to the nominal between samples, which
/// the held `v` can only correct at the next sample; about the reference it pulls towards
/// the path instead.
///
/// If the reference fails at some `t`, the replaced components are NaN, so that the failure
/// surfaces as a non-finite control instead of a plausible wrong one.
pub struct ReferenceNominal<N: Nominal, R: Reference> {
    base: N,
    reference: R,
    map: Vec<ReferenceState>,
    order: usize,
    /// Reference derivatives `(order + 1) * dimension`, allocated once.
    scratch: std::sync::Mutex<Vec<f64>>,
}

impl<N: Nominal, R: Reference> ReferenceNominal<N, R> {
    /// `base` with the states in `map` following `reference`.
    ///
    /// # Errors
    /// [`NominalError::StateIndex`] / [`NominalError::OutputIndex`] when a map entry names a
    /// state beyond `n_states` or an output beyond the reference's dimension;
    /// [`NominalError::Reference`] when an order exceeds what the reference provides.
    pub fn new(
        base: N,
        reference: R,
        n_states: usize,
        map: Vec<ReferenceState>,
    ) -> Result<Self, NominalError> {
        let m = reference.dimension();
        for e in &map {
            if e.state >= n_states {
                return Err(NominalError::StateIndex {
                    state: e.state,
                    n_states,
                });
            }
            if e.output >= m {
                return Err(NominalError::OutputIndex {
                    output: e.output,
                    dimension: m,
                });
            }
        }
        let order = map.iter().map(|e| e.order).max().unwrap_or(0);
        if order > reference.max_order() {
            return Err(NominalError::Reference(ReferenceError::OrderTooHigh {
                name: "reference of the preliminary feedback".into(),
                max: reference.max_order(),
                requested: order,
            }));
        }
        Ok(Self {
            base,
            reference,
            map,
            order,
            scratch: std::sync::Mutex::new(vec![0.0; (order + 1) * m]),
        })
    }
}

impl<N: Nominal, R: Reference> Nominal for ReferenceNominal<N, R> {
    fn state(&self, t: f64, x0: &mut [f64]) {
        self.base.state(t, x0);
        let m = self.reference.dimension();
        // A poisoned lock only means another thread panicked mid-write of plain numbers.
        let mut d = self
            .scratch
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let ok = self.reference.derivatives(t, self.order, &mut d).is_ok();
        for e in &self.map {
            x0[e.state] = if ok {
                d[e.order * m + e.output]
            } else {
                f64::NAN
            };
        }
    }

    fn input(&self, t: f64, u0: &mut [f64]) {
        self.base.input(t, u0);
    }
}

/// A preliminary feedback `u = u0(t) + K_n (x - x0(t)) + v` (paper, Section 3.1), applied in
/// deviation coordinates about a nominal trajectory.
pub struct Prefeedback {
    /// `K_n` (`inputs x states`), from [`crate::linear_analysis::analyze`] on the linearisation.
    pub k_n: DMatrix<f64>,
    /// The nominal trajectory.
    pub nominal: Box<dyn Nominal + Send + Sync>,
}

/// The law `u = u0 + K (x - x0) + v`, with `K` given row by row: `inputs` yields each
/// input's slot with its `u0`. The one place the law's arithmetic is written: each input's
/// sum is formed in a local, `v_i` first, then the states in order.
pub(crate) fn feedback_law<'u, R: Iterator<Item = f64>>(
    rows: impl Iterator<Item = R>,
    x: &[f64],
    v: &[f64],
    x0: &[f64],
    inputs: impl Iterator<Item = (&'u mut f64, f64)>,
) {
    for (((ui, u0i), k), vi) in inputs.zip(rows).zip(v) {
        let mut s = *vi;
        for (kij, (xj, x0j)) in k.zip(x.iter().zip(x0)) {
            s += kij * (xj - x0j);
        }
        *ui = u0i + s;
    }
}

impl Prefeedback {
    /// `u = u0(t) + K_n (x - x0(t)) + v`, using the scratch buffers `x0` and `u0`.
    pub fn input(&self, t: f64, x: &[f64], v: &[f64], x0: &mut [f64], u: &mut [f64]) {
        self.nominal.state(t, x0);
        self.nominal.input(t, u);
        // `u` holds `u0(t)`.
        let inputs = u.iter_mut().map(|ui| {
            let u0i = *ui;
            (ui, u0i)
        });
        feedback_law(self.gain_by_rows(), x, v, x0, inputs);
    }

    /// [`input`](Self::input) with the nominal `x0(t)`, `u0(t)` already evaluated (once per
    /// time, where several iterates share it): `u = u0 + K_n (x - x0) + v`.
    pub fn input_about(&self, x: &[f64], v: &[f64], x0: &[f64], u0: &[f64], u: &mut [f64]) {
        let inputs = u.iter_mut().zip(u0.iter().copied());
        feedback_law(self.gain_by_rows(), x, v, x0, inputs);
    }

    /// `K_n`'s rows as iterators over their entries.
    fn gain_by_rows(&self) -> impl Iterator<Item = impl Iterator<Item = f64> + '_> + '_ {
        let k = &self.k_n;
        (0..k.nrows()).map(move |i| (0..k.ncols()).map(move |j| k[(i, j)]))
    }

    /// `K_n` row by row in one contiguous buffer (`inputs x states`), for a caller that
    /// applies the law at every Newton iteration ([`feedback_law`] over its chunks).
    pub(crate) fn gain_rows(&self) -> Vec<f64> {
        self.gain_by_rows().flatten().collect()
    }

    /// The iteration matrix `[F_x + c F_x' + F_u K_n | F_z]` of a DAE whose input `u` is
    /// given by this law (so `du/dx = K_n`), into the zeroed sink `out`; entries that are
    /// exactly zero are not written. `f_u` holds the columns of the input the law drives, `f_z`
    /// those of every algebraic unknown, written from column `n_states` on. The controller
    /// passes the tracking DAE's blocks (where `u` is a part of `Z`, so `f_u` is a view into
    /// `f_z`), the closed loop the plant's.
    pub fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        c: f64,
        f_x: &DMatrix<f64>,
        f_xdot: &DMatrix<f64>,
        f_u: DMatrixView<'_, f64>,
        f_z: DMatrixView<'_, f64>,
        out: &mut S,
    ) {
        let (ne, nx) = f_x.shape();
        for j in 0..nx {
            for i in 0..ne {
                let mut v = f_x[(i, j)] + c * f_xdot[(i, j)];
                for k in 0..self.k_n.nrows() {
                    v += f_u[(i, k)] * self.k_n[(k, j)];
                }
                if v != 0.0 {
                    out.set(i, j, v);
                }
            }
        }
        for j in 0..f_z.ncols() {
            for i in 0..ne {
                let v = f_z[(i, j)];
                if v != 0.0 {
                    out.set(i, nx + j, v);
                }
            }
        }
    }
}

/// The chain rule `dG/dX + dG/du K_n` on the iteration matrix of a DAE whose input `u` is
/// one of its unknowns (the tracking DAE, where the plant's inputs are its last algebraic
/// unknowns) and is replaced by the law's correction `v`: since `du/dX = K_n` and `du/dv = I`,
/// the matrix in `[X; Z; v]` is the model's own matrix in `[X; Z; u]` with `(dG/du) K_n` added
/// to the state columns.
///
/// The model writes its matrix through [`capture`](Self::capture), which records the entries
/// of the `u` columns as they pass; [`apply`](Self::apply) then adds the products, only in the
/// rows where `u` appears structurally. Each structural entry of the result is written every
/// time (zeros included), so the destination's other entries can be zeroed once.
#[derive(Debug, Clone)]
pub struct FeedbackChain {
    /// First column of `u` in the matrix.
    u_start: usize,
    n_u: usize,
    n_x: usize,
    /// `dG/du` as captured, `rows x n_u` row-major by matrix row.
    f_u: Vec<f64>,
    /// `K_n`, row-major.
    k_n: Vec<f64>,
    /// `(row, state column, whether the model's own matrix has the entry)`.
    terms: Vec<(usize, usize, bool)>,
}

impl FeedbackChain {
    /// The chain rule for `law` on a matrix of `rows` rows whose columns are the `n_x` states,
    /// then the algebraic unknowns with `u` last, from `u_start` on; `pattern_u` holds the
    /// structural `(row, k)` of `dG/du_k`, `pattern_model` the model's own structural entries.
    pub fn new(
        law: &Prefeedback,
        rows: usize,
        u_start: usize,
        pattern_u: impl IntoIterator<Item = (usize, usize)>,
        pattern_model: &[(usize, usize)],
    ) -> Self {
        let (n_u, n_x) = law.k_n.shape();
        let mut u_rows: Vec<usize> = pattern_u.into_iter().map(|(i, _)| i).collect();
        u_rows.sort_unstable();
        u_rows.dedup();
        let terms = u_rows
            .iter()
            .flat_map(|&i| (0..n_x).map(move |j| (i, j)))
            .map(|(i, j)| (i, j, pattern_model.contains(&(i, j))))
            .collect();
        Self {
            u_start,
            n_u,
            n_x,
            f_u: vec![0.0; rows * n_u],
            k_n: (0..n_u)
                .flat_map(|k| (0..n_x).map(move |j| (k, j)))
                .map(|(k, j)| law.k_n[(k, j)])
                .collect(),
            terms,
        }
    }

    /// A sink for the model's matrix that forwards every entry to `out` and records those of
    /// the `u` columns.
    pub fn capture<'a, S: MatrixSink + ?Sized>(&'a mut self, out: &'a mut S) -> Capture<'a, S> {
        Capture {
            inner: out,
            u_start: self.u_start,
            n_u: self.n_u,
            f_u: &mut self.f_u,
        }
    }

    /// Add `(dG/du) K_n` (as captured) to the state columns of `out`, in the rows where `u`
    /// appears: added to the model's own entries, set where the model has none.
    pub fn apply<S: MatrixSink + ?Sized>(&self, out: &mut S) {
        for &(i, j, structural) in &self.terms {
            let f_u = &self.f_u[i * self.n_u..(i + 1) * self.n_u];
            let v: f64 = f_u
                .iter()
                .enumerate()
                .map(|(k, d)| d * self.k_n[k * self.n_x + j])
                .sum();
            if structural {
                out.add(i, j, v);
            } else {
                out.set(i, j, v);
            }
        }
    }

    /// The positions `(row, state column)` the chain rule writes.
    pub fn positions(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.terms.iter().map(|&(i, j, _)| (i, j))
    }
}

/// The sink of [`FeedbackChain::capture`].
pub struct Capture<'a, S: MatrixSink + ?Sized> {
    inner: &'a mut S,
    u_start: usize,
    n_u: usize,
    f_u: &'a mut [f64],
}

impl<S: MatrixSink + ?Sized> MatrixSink for Capture<'_, S> {
    fn rows(&self) -> usize {
        self.inner.rows()
    }
    fn cols(&self) -> usize {
        self.inner.cols()
    }
    #[inline]
    fn set(&mut self, row: usize, col: usize, value: f64) {
        self.inner.set(row, col, value);
        if col >= self.u_start {
            self.f_u[row * self.n_u + col - self.u_start] = value;
        }
    }
    #[inline]
    fn add(&mut self, row: usize, col: usize, value: f64) {
        self.inner.add(row, col, value);
        if col >= self.u_start {
            self.f_u[row * self.n_u + col - self.u_start] += value;
        }
    }
    fn fill_zero(&mut self) {
        self.inner.fill_zero();
        self.f_u.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::{Components, Polynomial, Sinusoid};

    struct Steady;
    impl Nominal for Steady {
        fn state(&self, t: f64, x0: &mut [f64]) {
            x0.copy_from_slice(&[1.0, -6.0 * t, 0.0, 0.0, -6.0]);
        }
        fn input(&self, _t: f64, u0: &mut [f64]) {
            u0.copy_from_slice(&[0.5, 0.25]);
        }
    }

    fn reference() -> Components {
        Components::new(
            2,
            vec![
                Box::new(Sinusoid {
                    offset: 1.0,
                    amplitude: 0.1,
                    omega: 1.0,
                    phase: 0.0,
                }),
                Box::new(Polynomial(vec![0.0, -7.0])),
            ],
        )
        .unwrap()
    }

    #[test]
    fn reference_nominal_replaces_the_mapped_states_only() {
        let map = vec![
            ReferenceState {
                state: 0,
                output: 0,
                order: 0,
            },
            ReferenceState {
                state: 3,
                output: 0,
                order: 1,
            },
            ReferenceState {
                state: 1,
                output: 1,
                order: 0,
            },
            ReferenceState {
                state: 4,
                output: 1,
                order: 1,
            },
        ];
        let n = ReferenceNominal::new(Steady, reference(), 5, map).unwrap();
        let t = 0.7_f64;
        let mut x0 = [0.0; 5];
        n.state(t, &mut x0);
        let want = [1.0 + 0.1 * t.sin(), -7.0 * t, 0.0, 0.1 * t.cos(), -7.0];
        for (a, b) in x0.iter().zip(&want) {
            assert!((a - b).abs() < 1e-15, "{x0:?} vs {want:?}");
        }
        let mut u0 = [0.0; 2];
        n.input(t, &mut u0);
        assert_eq!(u0, [0.5, 0.25]);
    }

    #[test]
    fn reference_nominal_checks_its_map() {
        let bad_state = vec![ReferenceState {
            state: 5,
            output: 0,
            order: 0,
        }];
        assert!(matches!(
            ReferenceNominal::new(Steady, reference(), 5, bad_state),
            Err(NominalError::StateIndex { .. } | NominalError::OutputIndex { .. })
        ));
        let bad_output = vec![ReferenceState {
            state: 0,
            output: 2,
            order: 0,
        }];
        assert!(matches!(
            ReferenceNominal::new(Steady, reference(), 5, bad_output),
            Err(NominalError::StateIndex { .. } | NominalError::OutputIndex { .. })
        ));
        struct Shallow;
        impl Reference for Shallow {
            fn dimension(&self) -> usize {
                1
            }
            fn max_order(&self) -> usize {
                0
            }
            fn derivatives(
                &self,
                _t: f64,
                _order: usize,
                out: &mut [f64],
            ) -> Result<(), ReferenceError> {
                out.fill(1.0);
                Ok(())
            }
        }
        let too_deep = vec![ReferenceState {
            state: 0,
            output: 0,
            order: 1,
        }];
        assert!(matches!(
            ReferenceNominal::new(Steady, Shallow, 5, too_deep),
            Err(NominalError::Reference(ReferenceError::OrderTooHigh { .. }))
        ));
    }

    #[test]
    fn a_steady_motion_moves_along_its_rate_and_checks_its_values() {
        let m = SteadyMotion::new(
            (2, 1, 1),
            vec![1.0, 2.0],
            vec![0.0, -3.0],
            vec![4.0],
            vec![0.5],
        )
        .unwrap();
        assert_eq!(m.state_at(2.0), vec![1.0, -4.0]);
        let mut u = [0.0];
        m.input(7.0, &mut u);
        assert_eq!(u, [0.5]);
        assert!(matches!(
            SteadyMotion::new((2, 1, 1), vec![1.0], vec![0.0, 0.0], vec![0.0], vec![0.0]),
            Err(NominalError::Dimension {
                what: "state",
                expected: 2,
                found: 1
            })
        ));
        assert!(matches!(
            SteadyMotion::new((1, 0, 1), vec![1.0], vec![f64::NAN], vec![], vec![0.0]),
            Err(NominalError::NonFinite {
                what: "rate",
                index: 0,
                ..
            })
        ));
    }

    #[test]
    fn the_captured_chain_rule_agrees_with_the_blockwise_one() {
        // Two states, one plant algebraic unknown, one input: columns [x0, x1, z, u].
        let law = Prefeedback {
            k_n: DMatrix::from_row_slice(1, 2, &[-2.0, -3.0]),
            nominal: Box::new(Steady),
        };
        let f_x = DMatrix::from_row_slice(3, 2, &[0.0, -1.0, 1.0, 0.0, 0.0, 0.0]);
        let f_xdot = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let f_z = DMatrix::from_row_slice(3, 2, &[0.0, 0.0, 0.0, -1.0, 1.0, 4.0]);
        let c = 0.5;
        let mut want = DMatrix::zeros(3, 4);
        law.iteration_matrix(
            c,
            &f_x,
            &f_xdot,
            f_z.columns(1, 1),
            f_z.columns(0, 2),
            &mut want,
        );
        // The model's own matrix [F_x + c F_x' | F_z | F_u], written entry by entry.
        let model: Vec<(usize, usize, f64)> = vec![
            (0, 0, c),
            (0, 1, -1.0),
            (1, 0, 1.0),
            (1, 3, -1.0),
            (2, 2, 1.0),
            (2, 3, 4.0),
        ];
        let pattern: Vec<(usize, usize)> = model.iter().map(|&(i, j, _)| (i, j)).collect();
        let mut chain = FeedbackChain::new(&law, 3, 3, [(1, 0), (2, 0)], &pattern);
        let mut got = DMatrix::zeros(3, 4);
        // Stale values where the chain rule writes without a model entry must be overwritten.
        got[(2, 1)] = 99.0;
        {
            let mut sink = chain.capture(&mut got);
            for &(i, j, v) in &model {
                sink.set(i, j, v);
            }
        }
        chain.apply(&mut got);
        assert_eq!(got, want);
        assert_eq!(
            chain.positions().collect::<Vec<_>>(),
            vec![(1, 0), (1, 1), (2, 0), (2, 1)]
        );
    }

    #[test]
    fn the_input_about_a_given_nominal_is_the_input() {
        let law = Prefeedback {
            k_n: DMatrix::from_row_slice(
                2,
                5,
                &[1.0, 2.0, 3.0, 4.0, 5.0, -1.0, 0.5, 0.0, 2.0, 1.0],
            ),
            nominal: Box::new(Steady),
        };
        let (x, v, t) = ([1.1, -2.0, 0.3, 0.1, -5.5], [0.2, -0.1], 0.4);
        let (mut x0, mut u) = ([0.0; 5], [0.0; 2]);
        law.input(t, &x, &v, &mut x0, &mut u);
        let mut u0 = [0.0; 2];
        law.nominal.input(t, &mut u0);
        let mut again = [0.0; 2];
        law.input_about(&x, &v, &x0, &u0, &mut again);
        assert_eq!(u, again);
    }

    #[test]
    fn the_chain_rule_adds_f_u_k_n_to_the_state_columns() {
        let law = Prefeedback {
            k_n: DMatrix::from_row_slice(1, 2, &[-2.0, -3.0]),
            nominal: Box::new(Steady),
        };
        let f_x = DMatrix::from_row_slice(2, 2, &[0.0, -1.0, 1.0, 0.0]);
        let f_xdot = DMatrix::identity(2, 2);
        let f_z = DMatrix::from_row_slice(2, 1, &[0.0, -1.0]);
        let mut out = DMatrix::zeros(2, 3);
        law.iteration_matrix(
            0.5,
            &f_x,
            &f_xdot,
            f_z.columns(0, 1),
            f_z.columns(0, 1),
            &mut out,
        );
        let want = DMatrix::from_row_slice(2, 3, &[0.5, -1.0, 0.0, 3.0, 3.5, -1.0]);
        assert_eq!(out, want);
    }
}
