// The planar n-link flexible-joint arm, declared once for every number of links:
// `flexible_joint_arm!(DOC, Name, NameTracking, N)` declares the plant `Name` with `N` links
// (and `NameParams`, `NameTracking`, `NameReference`), two stabilised Hirschorn steps per
// joint, `W(s) = (s + 4)^2`. Included by `models/src/arm.rs` (Arm1, Arm2, Arm6) and by the
// compile-time examples and the benchmark (`examples/arm_compile/common.rs`); the tests, the
// expansion benchmark (`dpc-codegen/benches/arms.rs`) and the routine-splitting test read it
// as text, instantiated by `template_models` of `tests/common/model_text.rs`. The arguments
// are token trees, so the macro receives them as written.

macro_rules! flexible_joint_arm {
    ($doc:tt, $name:ident, $tracking:ident, $n:tt) => {
        dpc::model! {
            #[doc = $doc]
            pub $name {
                consts { N = $n }
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
                tracking $tracking { q: [4.0, 4.0] }
            }
        }
    };
}
