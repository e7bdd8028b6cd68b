//! Three index-3 mechanisms written only here, as a user writes a constrained mechanism: the
//! Euler-Lagrange form in Cartesian coordinates of the bodies,
//!
//! ```text
//! q' = v
//! M v' = f - G(q)^T lambda
//! 0 = g(q)
//! ```
//!
//! with a constant diagonal mass matrix `M`, constant applied forces `f` (gravity, a constant
//! torque), position constraints `g` and their gradients `G = dg/dq`; unknowns `y = (q, v,
//! lambda)` of index 1, 2 and 3, with the exact iteration matrix (`dF/dy + c dF/dy'`, the
//! constraints' second derivatives contracted with `lambda` in the rows of `v'`) and the mass
//! matrix `dF/dy' = diag(I, M, 0)`:
//!
//! * [`slider_crank`]: the rigid slider crank (a crank pinned to the ground, a connecting rod,
//!   a slider on a horizontal rail), a constant torque on the crank, gravity, started turning;
//!   8 coordinates, 7 constraints, one degree of freedom (the crank angle);
//! * [`four_bar`]: the planar four-bar linkage (crank, coupler, rocker between two ground
//!   pivots), a Grashof crank-rocker whose transmission angle stays within 41-93 degrees for
//!   every crank angle (never singular), torque and gravity; 9 coordinates, 8 constraints, one
//!   degree of freedom (the input angle);
//! * [`SphericalPendulum`]: a point mass on a rigid rod in 3-D, `|x| = L`, started with an
//!   azimuthal speed that makes it precess (the polar angle stays within about 0.71-1 rad, away
//!   from the poles of the spherical angles); 3 coordinates, one constraint.
//!
//! Each is checked against an independent formulation: its minimal-coordinate ODE (crank angle,
//! input angle, polar and azimuthal angle). The planar ones are written as Lagrange's equations
//! in the form `J^T M (J s'' + J' s') = J^T f`, with the hand-derived kinematics `q(s)`, `q'`
//! and `q''` of [`Minimal::kinematics`] (the positions in closed form: the slider crank's rod
//! angle from `sin theta2 = -(L1 / L2) sin phi`, the four-bar's coupler point as the
//! intersection of two circles; velocities and accelerations from the loop closure), and the
//! spherical pendulum's as its closed-form Lagrange equations (checked against the same
//! general form in `tests/mechanisms.rs`). None of it uses `g`, `G` or the multipliers. The
//! reference at the end point is that ODE integrated by the classical Runge-Kutta method with
//! a fixed step ([`Minimal::reference`]), mapped to the Cartesian coordinates; the stored
//! values ([`SLIDER_CRANK_REF`], [`FOUR_BAR_REF`], [`SPHERICAL_REF`]) are those of 64 000 steps,
//! and 32 000 steps agree with them to 2e-12, 3e-11 and 1e-13 relative (to `max(|r|, 1e-2)`;
//! the method's error falls 16-fold per halving, so the stored values are good to about 1e-12);
//! the ignored test `references_recomputed` of `tests/mechanisms.rs` recomputes both.
#![allow(dead_code)]
// Matrix entries are written by (row, column) index, as the formulas are.
#![allow(clippy::needless_range_loop)]

use dpc_core::{ImplicitDae, MatrixSink};
use nalgebra::{DMatrix, DVector};

/// Standard gravity (m/s^2).
pub const GRAVITY: f64 = 9.81;

/// The constrained side of a mechanism: the data of its index-3 form.
pub trait Constrained {
    /// Coordinates `q`.
    fn nq(&self) -> usize;
    /// Position constraints.
    fn nc(&self) -> usize;
    /// The diagonal of the (constant) mass matrix.
    fn mass(&self, j: usize) -> f64;
    /// The (constant) applied forces into `out` (length `nq`).
    fn force(&self, out: &mut [f64]);
    /// `g(q)` into `out` (length `nc`).
    fn constraints(&self, q: &[f64], out: &mut [f64]);
    /// The non-zero entries `(a, j, dg_a/dq_j)` of `G(q)`, each once.
    fn gradient(&self, q: &[f64], entry: &mut dyn FnMut(usize, usize, f64));
    /// The entries `(j, k, sum_a w_a d^2 g_a / dq_j dq_k)` (an entry may come more than once:
    /// they add).
    fn hessian(&self, q: &[f64], w: &[f64], entry: &mut dyn FnMut(usize, usize, f64));
    /// Name of coordinate `j` (for equation and unknown names).
    fn coordinate(&self, j: usize) -> String;
}

/// The minimal-coordinate side of a mechanism.
pub trait Minimal: Constrained {
    /// Minimal coordinates `s`.
    fn ns(&self) -> usize;
    /// `(q, q', q'')` from `(s, s', s'')`, derived by hand.
    fn kinematics(&self, s: &[f64], sd: &[f64], sdd: &[f64]) -> [Vec<f64>; 3];

    /// `s''` of the minimal ODE at `(s, s')`; by default [`general_acceleration`].
    fn minimal_acceleration(&self, s: &[f64], sd: &[f64]) -> Vec<f64> {
        general_acceleration(self, s, sd)
    }

    /// The minimal ODE from `(s0, s0')` over `[0, t_end]` by the classical Runge-Kutta method
    /// with `steps` steps: `(q, q')` at `t_end` (length `2 nq`).
    fn reference(&self, s0: &[f64], sd0: &[f64], t_end: f64, steps: usize) -> Vec<f64> {
        let ns = self.ns();
        let h = t_end / steps as f64;
        let f = |x: &[f64]| -> Vec<f64> {
            let a = self.minimal_acceleration(&x[..ns], &x[ns..]);
            x[ns..].iter().copied().chain(a).collect()
        };
        let add = |x: &[f64], k: &[f64], c: f64| -> Vec<f64> {
            x.iter().zip(k).map(|(a, b)| a + c * b).collect()
        };
        let mut x: Vec<f64> = s0.iter().chain(sd0).copied().collect();
        for _ in 0..steps {
            let k1 = f(&x);
            let k2 = f(&add(&x, &k1, h / 2.0));
            let k3 = f(&add(&x, &k2, h / 2.0));
            let k4 = f(&add(&x, &k3, h));
            for i in 0..x.len() {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        let [q, qd, _] = self.kinematics(&x[..ns], &x[ns..], &vec![0.0; ns]);
        q.into_iter().chain(qd).collect()
    }

    /// The consistent start of the index-3 form at `(s0, s0')`: positions and velocities from
    /// the kinematics, accelerations `q''` from the minimal ODE, and the multipliers from the
    /// acceleration level, the least-squares solution of `G^T lambda = f - M q''` (exact when
    /// the two formulations agree). `(y0, y0')`, `y = (q, v, lambda)`.
    fn initial(&self, s0: &[f64], sd0: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (nq, nc) = (self.nq(), self.nc());
        let sdd = self.minimal_acceleration(s0, sd0);
        let [q, qd, qdd] = self.kinematics(s0, sd0, &sdd);
        let g = gradient_matrix(self, &q);
        let mut f = vec![0.0; nq];
        self.force(&mut f);
        let rhs = DVector::from_fn(nq, |j, _| f[j] - self.mass(j) * qdd[j]);
        let lambda = (&g * g.transpose())
            .lu()
            .solve(&(&g * rhs))
            .expect("G has full rank");
        let y: Vec<f64> = q.iter().chain(&qd).chain(lambda.iter()).copied().collect();
        let yp: Vec<f64> = qd
            .iter()
            .chain(&qdd)
            .copied()
            .chain(std::iter::repeat_n(0.0, nc))
            .collect();
        (y, yp)
    }
}

/// `s''` from Lagrange's equations in the form `J^T M (J s'' + J' s') = J^T f` (`J = dq/ds`;
/// `q' = J s'` and `q'' = J s'' + J' s'` from [`Minimal::kinematics`]).
pub fn general_acceleration<M: Minimal + ?Sized>(m: &M, s: &[f64], sd: &[f64]) -> Vec<f64> {
    let (nq, ns) = (m.nq(), m.ns());
    let zero = vec![0.0; ns];
    let [_, _, bias] = m.kinematics(s, sd, &zero);
    let mut jac = DMatrix::zeros(nq, ns);
    for k in 0..ns {
        let mut e = vec![0.0; ns];
        e[k] = 1.0;
        let [_, col, _] = m.kinematics(s, &e, &zero);
        jac.set_column(k, &DVector::from_vec(col));
    }
    let mut f = vec![0.0; nq];
    m.force(&mut f);
    let m = DMatrix::from_diagonal(&DVector::from_fn(nq, |j, _| m.mass(j)));
    let rhs = DVector::from_vec(f) - &m * DVector::from_vec(bias);
    let a = jac.transpose() * &m * &jac;
    let sdd = a
        .lu()
        .solve(&(jac.transpose() * rhs))
        .expect("J^T M J is regular (J has full rank)");
    sdd.iter().copied().collect()
}

/// `G(q)` as a matrix (`nc x nq`).
pub fn gradient_matrix<C: Constrained + ?Sized>(c: &C, q: &[f64]) -> DMatrix<f64> {
    let mut g = DMatrix::zeros(c.nc(), c.nq());
    c.gradient(q, &mut |a, j, v| g[(a, j)] = v);
    g
}

/// Accelerations and multipliers from positions and velocities alone, the saddle-point system
/// `M a + G^T lambda = f`, `G a = -(G v)' = -sum_a (v^T H_a v) e_a` (the position constraints
/// differentiated twice): `(a, lambda)`.
pub fn saddle_point<C: Constrained + ?Sized>(c: &C, q: &[f64], v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (nq, nc) = (c.nq(), c.nc());
    let g = gradient_matrix(c, q);
    let mut k = DMatrix::zeros(nq + nc, nq + nc);
    let mut rhs = DVector::zeros(nq + nc);
    let mut f = vec![0.0; nq];
    c.force(&mut f);
    for j in 0..nq {
        k[(j, j)] = c.mass(j);
        rhs[j] = f[j];
    }
    for a in 0..nc {
        for j in 0..nq {
            k[(j, nq + a)] = g[(a, j)];
            k[(nq + a, j)] = g[(a, j)];
        }
        let mut w = vec![0.0; nc];
        w[a] = 1.0;
        let mut curvature = 0.0;
        c.hessian(q, &w, &mut |j, l, h| curvature += v[j] * h * v[l]);
        rhs[nq + a] = -curvature;
    }
    let x = k
        .lu()
        .solve(&rhs)
        .expect("the saddle-point matrix is regular");
    (
        x.rows(0, nq).iter().copied().collect(),
        x.rows(nq, nc).iter().copied().collect(),
    )
}

/// The index-3 form of a mechanism as an [`ImplicitDae`]: `y = (q, v, lambda)`, residual
/// `(q' - v, M v' - f + G^T lambda, g(q))`.
#[derive(Clone, Debug)]
pub struct IndexThree<C>(pub C);

impl<C: Constrained> IndexThree<C> {
    /// The differential index of each unknown: 1 for `q`, 2 for `v`, 3 for `lambda`.
    pub fn index(&self) -> Vec<u8> {
        let (nq, nc) = (self.0.nq(), self.0.nc());
        [vec![1; nq], vec![2; nq], vec![3; nc]].concat()
    }
}

/// Stack room for the forces (no mechanism here has more coordinates).
const MAX_Q: usize = 16;

impl<C: Constrained> ImplicitDae for IndexThree<C> {
    fn dimension(&self) -> usize {
        2 * self.0.nq() + self.0.nc()
    }
    fn residual(&self, _: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        let nq = self.0.nq();
        let mut f = [0.0; MAX_Q];
        self.0.force(&mut f[..nq]);
        for j in 0..nq {
            out[j] = yp[j] - y[nq + j];
            out[nq + j] = self.0.mass(j) * yp[nq + j] - f[j];
        }
        let lambda = &y[2 * nq..];
        let (momentum, rest) = out[nq..].split_at_mut(nq);
        self.0
            .gradient(&y[..nq], &mut |a, j, v| momentum[j] += v * lambda[a]);
        self.0.constraints(&y[..nq], rest);
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        y: &[f64],
        _: &[f64],
        c: f64,
        out: &mut S,
    ) {
        let nq = self.0.nq();
        for j in 0..nq {
            out.set(j, j, c);
            out.set(j, nq + j, -1.0);
            out.set(nq + j, nq + j, c * self.0.mass(j));
        }
        self.0
            .hessian(&y[..nq], &y[2 * nq..], &mut |j, k, h| out.add(nq + j, k, h));
        self.0.gradient(&y[..nq], &mut |a, j, v| {
            out.set(nq + j, 2 * nq + a, v);
            out.set(2 * nq + a, j, v);
        });
    }
    fn mass_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        out: &mut S,
    ) -> bool {
        let nq = self.0.nq();
        for j in 0..nq {
            out.set(j, j, 1.0);
            out.set(nq + j, nq + j, self.0.mass(j));
        }
        true
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 2 * self.0.nq()
    }
    fn equation_name(&self, i: usize) -> String {
        let nq = self.0.nq();
        if i < nq {
            format!("{}' = v_{}", self.0.coordinate(i), self.0.coordinate(i))
        } else if i < 2 * nq {
            format!("momentum of {}", self.0.coordinate(i - nq))
        } else {
            format!("constraint {}", i - 2 * nq)
        }
    }
}

/// A point of the plane: fixed, or on body `b` at distance `d` from its centre along its axis.
#[derive(Clone, Copy, Debug)]
pub enum Point {
    /// A fixed point `(x, y)`.
    Ground(f64, f64),
    /// Body `b`'s point at `d` along its axis (`d = 0` for a body without angle).
    On(usize, f64),
}

/// A joint of a planar mechanism.
#[derive(Clone, Copy, Debug)]
pub enum Joint {
    /// Two points held together (two constraints, `x` and `y`).
    Pin(Point, Point),
    /// Body `b`'s centre on the horizontal line `y = y0` (one constraint).
    Rail(usize, f64),
}

/// A planar body: a bar (centre `x, y` and angle) or a point mass (centre only).
#[derive(Clone, Copy, Debug)]
pub struct Body {
    /// Mass.
    pub mass: f64,
    /// Moment of inertia about the centre; `None` for a point mass (no angle).
    pub inertia: Option<f64>,
}

/// How a planar chain's positions follow from its one minimal coordinate.
#[derive(Clone, Copy, Debug)]
pub enum Chain {
    /// Crank of length `l1` about the origin, rod of length `l2 > l1` to a slider on `y = 0`.
    SliderCrank {
        /// Crank length.
        l1: f64,
        /// Rod length.
        l2: f64,
    },
    /// Crank `a` about the origin, coupler `b`, rocker `c` about `(d, 0)`, the coupler
    /// point above the line from the crank tip to the rocker pivot.
    FourBar {
        /// Crank length.
        a: f64,
        /// Coupler length.
        b: f64,
        /// Rocker length.
        c: f64,
        /// Distance of the ground pivots.
        d: f64,
    },
}

/// A planar mechanism of bars and point masses under gravity (`-y`) and a constant torque on
/// one body.
#[derive(Clone, Debug)]
pub struct Planar {
    /// The bodies.
    pub bodies: Vec<Body>,
    /// The joints.
    pub joints: Vec<Joint>,
    /// `(body, torque)`: the constant torque on that body's angle.
    pub torque: (usize, f64),
    /// The positions as functions of the minimal coordinate.
    pub chain: Chain,
    first: Vec<usize>,
    nq: usize,
    nc: usize,
}

impl Planar {
    /// The mechanism of `bodies` and `joints`.
    pub fn new(bodies: Vec<Body>, joints: Vec<Joint>, torque: (usize, f64), chain: Chain) -> Self {
        let mut first = Vec::new();
        let mut nq = 0;
        for b in &bodies {
            first.push(nq);
            nq += if b.inertia.is_some() { 3 } else { 2 };
        }
        let nc = joints
            .iter()
            .map(|j| match j {
                Joint::Pin(..) => 2,
                Joint::Rail(..) => 1,
            })
            .sum();
        Self {
            bodies,
            joints,
            torque,
            chain,
            first,
            nq,
            nc,
        }
    }

    /// `(x, y)` of `p` at `q`.
    fn position(&self, q: &[f64], p: Point) -> [f64; 2] {
        match p {
            Point::Ground(x, y) => [x, y],
            Point::On(b, d) => {
                let k = self.first[b];
                if self.bodies[b].inertia.is_some() {
                    let (s, c) = q[k + 2].sin_cos();
                    [q[k] + d * c, q[k + 1] + d * s]
                } else {
                    [q[k], q[k + 1]]
                }
            }
        }
    }

    /// `(j, dx/dq_j, dy/dq_j)` of `p`, each non-zero coordinate once, times `sign`.
    fn point_gradient(&self, q: &[f64], p: Point, sign: f64, out: &mut dyn FnMut(usize, f64, f64)) {
        if let Point::On(b, d) = p {
            let k = self.first[b];
            out(k, sign, 0.0);
            out(k + 1, 0.0, sign);
            if self.bodies[b].inertia.is_some() {
                let (s, c) = q[k + 2].sin_cos();
                out(k + 2, -sign * d * s, sign * d * c);
            }
        }
    }

    /// `(j, d^2x/dq_j^2, d^2y/dq_j^2)` of `p` (only an angle's), times `sign`.
    fn point_hessian(&self, q: &[f64], p: Point, sign: f64) -> Option<(usize, f64, f64)> {
        match p {
            Point::On(b, d) if self.bodies[b].inertia.is_some() => {
                let k = self.first[b] + 2;
                let (s, c) = q[k].sin_cos();
                Some((k, -sign * d * c, -sign * d * s))
            }
            _ => None,
        }
    }
}

impl Constrained for Planar {
    fn nq(&self) -> usize {
        self.nq
    }
    fn nc(&self) -> usize {
        self.nc
    }
    fn mass(&self, j: usize) -> f64 {
        let b = self.first.iter().rposition(|&k| k <= j).unwrap_or(0);
        match (j - self.first[b], self.bodies[b].inertia) {
            (2, Some(inertia)) => inertia,
            _ => self.bodies[b].mass,
        }
    }
    fn force(&self, out: &mut [f64]) {
        out.fill(0.0);
        for (b, body) in self.bodies.iter().enumerate() {
            out[self.first[b] + 1] = -body.mass * GRAVITY;
        }
        out[self.first[self.torque.0] + 2] = self.torque.1;
    }
    fn constraints(&self, q: &[f64], out: &mut [f64]) {
        let mut row = 0;
        for joint in &self.joints {
            match *joint {
                Joint::Pin(p, r) => {
                    let (a, b) = (self.position(q, p), self.position(q, r));
                    out[row] = a[0] - b[0];
                    out[row + 1] = a[1] - b[1];
                    row += 2;
                }
                Joint::Rail(b, y0) => {
                    out[row] = q[self.first[b] + 1] - y0;
                    row += 1;
                }
            }
        }
    }
    fn gradient(&self, q: &[f64], entry: &mut dyn FnMut(usize, usize, f64)) {
        let mut row = 0;
        for joint in &self.joints {
            match *joint {
                Joint::Pin(p, r) => {
                    // The two points are on different bodies (or one on the ground): no
                    // coordinate comes twice.
                    for (point, sign) in [(p, 1.0), (r, -1.0)] {
                        self.point_gradient(q, point, sign, &mut |j, dx, dy| {
                            if dx != 0.0 {
                                entry(row, j, dx);
                            }
                            if dy != 0.0 {
                                entry(row + 1, j, dy);
                            }
                        });
                    }
                    row += 2;
                }
                Joint::Rail(b, _) => {
                    entry(row, self.first[b] + 1, 1.0);
                    row += 1;
                }
            }
        }
    }
    fn hessian(&self, q: &[f64], w: &[f64], entry: &mut dyn FnMut(usize, usize, f64)) {
        let mut row = 0;
        for joint in &self.joints {
            match *joint {
                Joint::Pin(p, r) => {
                    for (point, sign) in [(p, 1.0), (r, -1.0)] {
                        if let Some((k, hx, hy)) = self.point_hessian(q, point, sign) {
                            entry(k, k, w[row] * hx + w[row + 1] * hy);
                        }
                    }
                    row += 2;
                }
                Joint::Rail(..) => row += 1,
            }
        }
    }
    fn coordinate(&self, j: usize) -> String {
        let b = self.first.iter().rposition(|&k| k <= j).unwrap_or(0);
        let name = ["x", "y", "theta"][j - self.first[b]];
        format!("{name}{}", b + 1)
    }
}

/// Position, velocity and acceleration of a point in the plane.
#[derive(Clone, Copy, Debug)]
struct Kin {
    p: [f64; 2],
    v: [f64; 2],
    a: [f64; 2],
}

impl Kin {
    const ORIGIN: Kin = Kin {
        p: [0.0; 2],
        v: [0.0; 2],
        a: [0.0; 2],
    };
    fn at(x: f64, y: f64) -> Kin {
        Kin {
            p: [x, y],
            ..Kin::ORIGIN
        }
    }
    /// This point moved by `d` along the direction of angle `(th, thd, thdd)`.
    fn along(self, d: f64, (th, thd, thdd): (f64, f64, f64)) -> Kin {
        let (s, c) = th.sin_cos();
        Kin {
            p: [self.p[0] + d * c, self.p[1] + d * s],
            v: [self.v[0] - d * thd * s, self.v[1] + d * thd * c],
            a: [
                self.a[0] - d * (thdd * s + thd * thd * c),
                self.a[1] + d * (thdd * c - thd * thd * s),
            ],
        }
    }
}

/// Appends a bar's `(x, y, theta)` (or a point mass's `(x, y)`) to `(q, q', q'')`.
fn push(out: &mut [Vec<f64>; 3], centre: Kin, angle: Option<(f64, f64, f64)>) {
    for (k, v) in [centre.p, centre.v, centre.a].into_iter().enumerate() {
        out[k].extend_from_slice(&v);
    }
    if let Some((th, thd, thdd)) = angle {
        out[0].push(th);
        out[1].push(thd);
        out[2].push(thdd);
    }
}

impl Minimal for Planar {
    fn ns(&self) -> usize {
        1
    }
    fn kinematics(&self, s: &[f64], sd: &[f64], sdd: &[f64]) -> [Vec<f64>; 3] {
        let crank = (s[0], sd[0], sdd[0]);
        let mut out = [Vec::new(), Vec::new(), Vec::new()];
        match self.chain {
            Chain::SliderCrank { l1, l2 } => {
                // sin theta2 = -r sin phi (the slider on y = 0), cos theta2 > 0, differentiated
                // twice.
                let r = l1 / l2;
                let (sp, cp) = s[0].sin_cos();
                let (w, al) = (sd[0], sdd[0]);
                let s2 = -r * sp;
                let c2 = (1.0 - s2 * s2).sqrt();
                let th2 = s2.atan2(c2);
                let w2 = -r * cp * w / c2;
                let al2 = (r * sp * w * w - r * cp * al + s2 * w2 * w2) / c2;
                let rod = (th2, w2, al2);
                let tip = Kin::ORIGIN.along(l1, crank);
                push(&mut out, Kin::ORIGIN.along(l1 / 2.0, crank), Some(crank));
                push(&mut out, tip.along(l2 / 2.0, rod), Some(rod));
                push(&mut out, tip.along(l2, rod), None);
            }
            Chain::FourBar { a, b, c, d } => {
                // The coupler point: the intersection of the circles of radius b about the
                // crank tip and c about the rocker pivot, above the line between them.
                let tip = Kin::ORIGIN.along(a, crank);
                let (dx, dy) = (d - tip.p[0], -tip.p[1]);
                let dist = dx.hypot(dy);
                let along = (b * b - c * c + dist * dist) / (2.0 * dist);
                let across = (b * b - along * along).sqrt();
                let px = tip.p[0] + (along * dx - across * dy) / dist;
                let py = tip.p[1] + (along * dy + across * dx) / dist;
                let th2 = (py - tip.p[1]).atan2(px - tip.p[0]);
                let th3 = py.atan2(px - d);
                // Loop closure a e1 + b e2 = D + c e3 differentiated once and twice: a 2 x 2
                // system [b e2perp, -c e3perp] (w2, w3) = rhs.
                let (s2, c2) = th2.sin_cos();
                let (s3, c3) = th3.sin_cos();
                let (a11, a12, a21, a22) = (-b * s2, c * s3, b * c2, -c * c3);
                let det = a11 * a22 - a12 * a21;
                let solve = |r: [f64; 2]| {
                    [
                        (r[0] * a22 - a12 * r[1]) / det,
                        (a11 * r[1] - a21 * r[0]) / det,
                    ]
                };
                let [w2, w3] = solve([-tip.v[0], -tip.v[1]]);
                let [al2, al3] = solve([
                    -tip.a[0] + b * w2 * w2 * c2 - c * w3 * w3 * c3,
                    -tip.a[1] + b * w2 * w2 * s2 - c * w3 * w3 * s3,
                ]);
                let coupler = (th2, w2, al2);
                let rocker = (th3, w3, al3);
                push(&mut out, Kin::ORIGIN.along(a / 2.0, crank), Some(crank));
                push(&mut out, tip.along(b / 2.0, coupler), Some(coupler));
                push(
                    &mut out,
                    Kin::at(d, 0.0).along(c / 2.0, rocker),
                    Some(rocker),
                );
            }
        }
        out
    }
}

/// A uniform bar of mass `m` and length `l`.
fn bar(m: f64, l: f64) -> Body {
    Body {
        mass: m,
        inertia: Some(m * l * l / 12.0),
    }
}

/// The slider crank: crank 0.2 m, 1 kg; rod 0.5 m, 2 kg; slider 1.5 kg; torque 0.5 N m on the
/// crank.
pub fn slider_crank() -> Planar {
    let (l1, l2) = (0.2, 0.5);
    Planar::new(
        vec![
            bar(1.0, l1),
            bar(2.0, l2),
            Body {
                mass: 1.5,
                inertia: None,
            },
        ],
        vec![
            Joint::Pin(Point::On(0, -l1 / 2.0), Point::Ground(0.0, 0.0)),
            Joint::Pin(Point::On(0, l1 / 2.0), Point::On(1, -l2 / 2.0)),
            Joint::Pin(Point::On(1, l2 / 2.0), Point::On(2, 0.0)),
            Joint::Rail(2, 0.0),
        ],
        (0, 0.5),
        Chain::SliderCrank { l1, l2 },
    )
}

/// The slider crank's start: crank angle and speed (rad, rad/s).
pub const SLIDER_CRANK_START: (f64, f64) = (0.3, 5.0);
/// The slider crank's end time (s).
pub const SLIDER_CRANK_T_END: f64 = 2.0;
/// The slider crank's `(q, q')` at the end (module documentation): the crank has swung back
/// (gravity on the rod outweighs the torque).
pub const SLIDER_CRANK_REF: [f64; 16] = [
    -0.010946644135912967,
    -0.09939904920149731,
    -1.680482576438564,
    0.20749683579160955,
    -0.09939904920149731,
    0.40889557814218475,
    0.436886959855045,
    0.0,
    -0.6987118413175517,
    0.07694791793175938,
    -7.02936141673905,
    -1.364080704546227,
    0.07694791793175938,
    -0.3354456441659198,
    -1.330737726457351,
    0.0,
];

/// The four-bar linkage: crank 0.2 m, 0.4 kg; coupler 0.6 m, 1.2 kg; rocker 0.5 m, 1 kg;
/// ground pivots 0.6 m apart; torque 0.5 N m on the crank.
pub fn four_bar() -> Planar {
    let (a, b, c, d) = (0.2, 0.6, 0.5, 0.6);
    Planar::new(
        vec![bar(0.4, a), bar(1.2, b), bar(1.0, c)],
        vec![
            Joint::Pin(Point::On(0, -a / 2.0), Point::Ground(0.0, 0.0)),
            Joint::Pin(Point::On(0, a / 2.0), Point::On(1, -b / 2.0)),
            Joint::Pin(Point::On(1, b / 2.0), Point::On(2, c / 2.0)),
            Joint::Pin(Point::On(2, -c / 2.0), Point::Ground(d, 0.0)),
        ],
        (0, 0.5),
        Chain::FourBar { a, b, c, d },
    )
}

/// The four-bar's start: input angle and speed (rad, rad/s).
pub const FOUR_BAR_START: (f64, f64) = (0.5, 8.0);
/// The four-bar's end time (s).
pub const FOUR_BAR_T_END: f64 = 2.0;
/// The four-bar's `(q, q')` at the end (module documentation): the crank has turned 5.6 times.
pub const FOUR_BAR_REF: [f64; 18] = [
    -0.0805539111154906,
    -0.05925426064003872,
    35.19173078310236,
    0.03449678049110905,
    0.10895321043304668,
    0.8605568763691163,
    0.4150506916065996,
    0.1682074710730854,
    2.4035652716001707,
    2.5328633583150295,
    -3.443331291784364,
    42.74567484187876,
    1.8871765233916173,
    -4.153283904447578,
    13.97399979899584,
    -0.6456868349234128,
    -0.7099526126632137,
    3.838633508988818,
];

/// The spherical pendulum: a point mass `m` on a rod of length `l`, `x = (x, y, z)`, gravity
/// along `-z`, the constraint `(|x|^2 - l^2) / 2 = 0`.
#[derive(Clone, Copy, Debug)]
pub struct SphericalPendulum {
    /// Mass.
    pub m: f64,
    /// Rod length.
    pub l: f64,
}

/// The spherical pendulum of 1 kg on 1 m.
pub const SPHERICAL: SphericalPendulum = SphericalPendulum { m: 1.0, l: 1.0 };
/// Its start: polar angle from the downward vertical, azimuth, and their rates.
pub const SPHERICAL_START: ([f64; 2], [f64; 2]) = ([1.0, 0.0], [0.0, 3.0]);
/// Its end time (s).
pub const SPHERICAL_T_END: f64 = 3.0;
/// Its `(x, x')` at the end (module documentation).
pub const SPHERICAL_REF: [f64; 6] = [
    0.4688661551830708,
    -0.6253277390231948,
    -0.6238026509497886,
    2.4701583516356234,
    1.2360920304365346,
    0.6175206434611397,
];

impl SphericalPendulum {
    /// Lagrange's equations of `L = m l^2 (theta'^2 + sin^2 theta phi'^2) / 2 + m g l cos
    /// theta`: `theta'' = sin theta cos theta phi'^2 - (g / l) sin theta`, `phi'' = -2 cot
    /// theta theta' phi'`.
    pub fn lagrange(&self, s: &[f64], sd: &[f64]) -> [f64; 2] {
        let (st, ct) = s[0].sin_cos();
        [
            st * ct * sd[1] * sd[1] - GRAVITY / self.l * st,
            -2.0 * ct / st * sd[0] * sd[1],
        ]
    }
}

impl Constrained for SphericalPendulum {
    fn nq(&self) -> usize {
        3
    }
    fn nc(&self) -> usize {
        1
    }
    fn mass(&self, _: usize) -> f64 {
        self.m
    }
    fn force(&self, out: &mut [f64]) {
        out.copy_from_slice(&[0.0, 0.0, -self.m * GRAVITY]);
    }
    fn constraints(&self, q: &[f64], out: &mut [f64]) {
        out[0] = 0.5 * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] - self.l * self.l);
    }
    fn gradient(&self, q: &[f64], entry: &mut dyn FnMut(usize, usize, f64)) {
        for j in 0..3 {
            entry(0, j, q[j]);
        }
    }
    fn hessian(&self, _: &[f64], w: &[f64], entry: &mut dyn FnMut(usize, usize, f64)) {
        for j in 0..3 {
            entry(j, j, w[0]);
        }
    }
    fn coordinate(&self, j: usize) -> String {
        ["x", "y", "z"][j].into()
    }
}

impl Minimal for SphericalPendulum {
    fn ns(&self) -> usize {
        2
    }
    /// `x = l (sin theta cos phi, sin theta sin phi, -cos theta)` differentiated twice.
    fn kinematics(&self, s: &[f64], sd: &[f64], sdd: &[f64]) -> [Vec<f64>; 3] {
        let l = self.l;
        let (st, ct) = s[0].sin_cos();
        let (sp, cp) = s[1].sin_cos();
        let (td, pd, tdd, pdd) = (sd[0], sd[1], sdd[0], sdd[1]);
        let q = vec![l * st * cp, l * st * sp, -l * ct];
        let qd = vec![
            l * (ct * cp * td - st * sp * pd),
            l * (ct * sp * td + st * cp * pd),
            l * st * td,
        ];
        let qdd = vec![
            l * (-st * cp * td * td - 2.0 * ct * sp * td * pd - st * cp * pd * pd + ct * cp * tdd
                - st * sp * pdd),
            l * (-st * sp * td * td + 2.0 * ct * cp * td * pd - st * sp * pd * pd
                + ct * sp * tdd
                + st * cp * pdd),
            l * (ct * td * td + st * tdd),
        ];
        [q, qd, qdd]
    }
    fn minimal_acceleration(&self, s: &[f64], sd: &[f64]) -> Vec<f64> {
        self.lagrange(s, sd).to_vec()
    }
}
