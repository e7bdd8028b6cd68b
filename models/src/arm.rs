//! The planar n-link robot arm with flexible joints (Spong's model): per joint, a link angle
//! `q[i]` (relative to the previous link, measured from the downward vertical for the first)
//! driven through a torsional spring of stiffness `ks[i]` by a motor at angle `th[i]`,
//!
//! ```text
//! M(q) q'' + C(q, q') q' + g(q) + K (q - th) = 0,      J th'' + K (th - q) = u,
//! ```
//!
//! with the link angles as outputs, each of relative degree 4. The equations of the links are
//! written once for every `N` with the DSL's indexed families, in the form of d'Alembert's
//! principle: per joint `i`, the sum over the links `c >= i` of `m_c (dp_c/dq_i) . p_c''`
//! (`p_c` the centre of mass of link `c`) plus `I_c phi_c''` (`phi_c` the absolute angle) plus
//! the gravity and spring torques, which is `M(q) q'' + C(q, q') q' + g(q)` without the mass
//! matrix or the Coriolis terms being written out. The mass matrix stays implicit: the
//! macro never inverts it.
//!
//! The motors and springs are those of [`crate::FlexibleJoint`] (`j_motor = 0.5`, `ks = 40`);
//! [`Arm1`] is that model with the link inertia split into its centre-of-mass part and
//! `m r^2`; [`Arm2`] and [`Arm6`] are the plants of `scenarios/arm2.toml` and
//! `scenarios/arm6.toml`. All three apply two stabilised Hirschorn steps per joint,
//! `W(s) = (s + 4)^2`; `docs/arms.md` measures the same declaration for other `N` and steps.

dpc::model! {
    /// The one-link arm: [`crate::FlexibleJoint`] in the arm's parameters.
    pub Arm1 {
        consts { N = 1 }
        params {
            /// Link masses.
            m[N] = 1.0,
            /// Link lengths (joint to joint).
            l[N] = 0.5,
            /// Distances from each joint to its link's centre of mass.
            r[N] = 0.25,
            /// Link inertias about their centres of mass.
            i_link[N] = 0.02,
            /// Motor inertias.
            j_motor[N] = 0.5,
            /// Joint stiffnesses.
            ks[N] = 40.0,
            /// Gravity.
            g = 9.81
        }
        states { q[N]: "rad", w[N]: "rad/s", th[N]: "rad", wm[N]: "rad/s" }
        inputs { u[N]: "N m" }
        // Absolute angle, angular velocity and angular acceleration of each link.
        let phi[a in 0..N] = sum(0..=a, |j| q[j]);
        let om[a in 0..N] = sum(0..=a, |j| w[j]);
        let al[a in 0..N] = sum(0..=a, |j| der(w[j]));
        // The acceleration of the end of a unit link at angle phi[b].
        let ex[b in 0..N] = cos(phi[b]) * al[b] - sin(phi[b]) * om[b].powi(2);
        let ey[b in 0..N] = sin(phi[b]) * al[b] + cos(phi[b]) * om[b].powi(2);
        // The acceleration of the centre of mass of link c.
        let ax[c in 0..N] = sum(0..c, |b| l[b] * ex[b]) + r[c] * ex[c];
        let ay[c in 0..N] = sum(0..c, |b| l[b] * ey[b]) + r[c] * ey[c];
        // The derivative of the centre of mass of link c by q[i] (for i <= c).
        let jx[c in 0..N][i in 0..N] = sum(i..c, |a| l[a] * cos(phi[a])) + r[c] * cos(phi[c]);
        let jy[c in 0..N][i in 0..N] = sum(i..c, |a| l[a] * sin(phi[a])) + r[c] * sin(phi[c]);
        equations {
            for i in 0..N {
                der(q[i]) = w[i];
                sum(i..N, |c| m[c] * (jx[c][i] * ax[c] + jy[c][i] * (ay[c] + g)) + i_link[c] * al[c])
                    + ks[i] * (q[i] - th[i]) == 0.0;
                der(th[i]) = wm[i];
                der(wm[i]) = (ks[i] * (q[i] - th[i]) + u[i]) / j_motor[i];
            }
        }
        outputs { q }
        references { q[i in 0..N] = 0.3 * sin(0.8 * t + 0.5 * i) }
        tracking Arm1Tracking { q: [4.0, 4.0] }
    }
}

dpc::model! {
    /// The two-link arm of `scenarios/arm2.toml`.
    pub Arm2 {
        consts { N = 2 }
        params {
            /// Link masses.
            m[N] = 1.0,
            /// Link lengths (joint to joint).
            l[N] = 0.5,
            /// Distances from each joint to its link's centre of mass.
            r[N] = 0.25,
            /// Link inertias about their centres of mass.
            i_link[N] = 0.02,
            /// Motor inertias.
            j_motor[N] = 0.5,
            /// Joint stiffnesses.
            ks[N] = 40.0,
            /// Gravity.
            g = 9.81
        }
        states { q[N]: "rad", w[N]: "rad/s", th[N]: "rad", wm[N]: "rad/s" }
        inputs { u[N]: "N m" }
        // Absolute angle, angular velocity and angular acceleration of each link.
        let phi[a in 0..N] = sum(0..=a, |j| q[j]);
        let om[a in 0..N] = sum(0..=a, |j| w[j]);
        let al[a in 0..N] = sum(0..=a, |j| der(w[j]));
        // The acceleration of the end of a unit link at angle phi[b].
        let ex[b in 0..N] = cos(phi[b]) * al[b] - sin(phi[b]) * om[b].powi(2);
        let ey[b in 0..N] = sin(phi[b]) * al[b] + cos(phi[b]) * om[b].powi(2);
        // The acceleration of the centre of mass of link c.
        let ax[c in 0..N] = sum(0..c, |b| l[b] * ex[b]) + r[c] * ex[c];
        let ay[c in 0..N] = sum(0..c, |b| l[b] * ey[b]) + r[c] * ey[c];
        // The derivative of the centre of mass of link c by q[i] (for i <= c).
        let jx[c in 0..N][i in 0..N] = sum(i..c, |a| l[a] * cos(phi[a])) + r[c] * cos(phi[c]);
        let jy[c in 0..N][i in 0..N] = sum(i..c, |a| l[a] * sin(phi[a])) + r[c] * sin(phi[c]);
        equations {
            for i in 0..N {
                der(q[i]) = w[i];
                sum(i..N, |c| m[c] * (jx[c][i] * ax[c] + jy[c][i] * (ay[c] + g)) + i_link[c] * al[c])
                    + ks[i] * (q[i] - th[i]) == 0.0;
                der(th[i]) = wm[i];
                der(wm[i]) = (ks[i] * (q[i] - th[i]) + u[i]) / j_motor[i];
            }
        }
        outputs { q }
        references { q[i in 0..N] = 0.3 * sin(0.8 * t + 0.5 * i) }
        tracking Arm2Tracking { q: [4.0, 4.0] }
    }
}

dpc::model! {
    /// The six-link arm of `scenarios/arm6.toml`.
    pub Arm6 {
        consts { N = 6 }
        params {
            /// Link masses.
            m[N] = 1.0,
            /// Link lengths (joint to joint).
            l[N] = 0.5,
            /// Distances from each joint to its link's centre of mass.
            r[N] = 0.25,
            /// Link inertias about their centres of mass.
            i_link[N] = 0.02,
            /// Motor inertias.
            j_motor[N] = 0.5,
            /// Joint stiffnesses.
            ks[N] = 40.0,
            /// Gravity.
            g = 9.81
        }
        states { q[N]: "rad", w[N]: "rad/s", th[N]: "rad", wm[N]: "rad/s" }
        inputs { u[N]: "N m" }
        // Absolute angle, angular velocity and angular acceleration of each link.
        let phi[a in 0..N] = sum(0..=a, |j| q[j]);
        let om[a in 0..N] = sum(0..=a, |j| w[j]);
        let al[a in 0..N] = sum(0..=a, |j| der(w[j]));
        // The acceleration of the end of a unit link at angle phi[b].
        let ex[b in 0..N] = cos(phi[b]) * al[b] - sin(phi[b]) * om[b].powi(2);
        let ey[b in 0..N] = sin(phi[b]) * al[b] + cos(phi[b]) * om[b].powi(2);
        // The acceleration of the centre of mass of link c.
        let ax[c in 0..N] = sum(0..c, |b| l[b] * ex[b]) + r[c] * ex[c];
        let ay[c in 0..N] = sum(0..c, |b| l[b] * ey[b]) + r[c] * ey[c];
        // The derivative of the centre of mass of link c by q[i] (for i <= c).
        let jx[c in 0..N][i in 0..N] = sum(i..c, |a| l[a] * cos(phi[a])) + r[c] * cos(phi[c]);
        let jy[c in 0..N][i in 0..N] = sum(i..c, |a| l[a] * sin(phi[a])) + r[c] * sin(phi[c]);
        equations {
            for i in 0..N {
                der(q[i]) = w[i];
                sum(i..N, |c| m[c] * (jx[c][i] * ax[c] + jy[c][i] * (ay[c] + g)) + i_link[c] * al[c])
                    + ks[i] * (q[i] - th[i]) == 0.0;
                der(th[i]) = wm[i];
                der(wm[i]) = (ks[i] * (q[i] - th[i]) + u[i]) / j_motor[i];
            }
        }
        outputs { q }
        references { q[i in 0..N] = 0.3 * sin(0.8 * t + 0.5 * i) }
        tracking Arm6Tracking { q: [4.0, 4.0] }
    }
}
