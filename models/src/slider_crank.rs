//! A slider-crank, written twice: with the slider position and the rod constraint and its
//! multiplier (a descriptor plant of index 3), and in the crank angle alone as an ODE. The
//! output is the crank angle, driven by a torque against a slider held by a spring.

dpc::model! {
    /// A crank of inertia `j` (angle `th`, damping `bt`, torque `tau`) drives, through a
    /// massless rod of length `l` from the crank pin at radius `r`, a slider of mass `ms`
    /// (position `xs`) on a spring of stiffness `k` to `x0` with damping `c`. The rod is the
    /// constraint `(xs - r cos(th))^2 + (r sin(th))^2 = l^2` with the multiplier `lambda`:
    /// index 3.
    pub SliderCrank {
        params { j = 0.05, ms = 2.0, r = 0.3, l = 1.0, k = 50.0, x0 = 1.0, c = 0.5, bt = 0.1 }
        states { th: "rad", xs: "m", om: "rad/s", vs: "m/s" }
        algebraic { lambda }
        inputs { tau: "N m" }
        equations {
            der(th) = om;
            der(xs) = vs;
            j * der(om) == tau - bt * om - lambda * r * xs * sin(th);
            ms * der(vs) == -k * (xs - x0) - c * vs - lambda * (xs - r * cos(th));
            0.0 == 0.5 * ((xs - r * cos(th)).powi(2) + (r * sin(th)).powi(2) - l.powi(2));
        }
        outputs { angle: "rad" = th }
        references { angle = 1.0 + 0.3 * (1.0 - cos(t)) }
        tracking SliderCrankTracking { angle: [4.0] }
    }
}

dpc::model! {
    /// The same slider-crank in the crank angle alone: the slider position `xs = X(th)` from
    /// the closed-form geometry, Lagrange's equation with `X'` and `X''` written out.
    pub SliderCrankJoint {
        params { j = 0.05, ms = 2.0, r = 0.3, l = 1.0, k = 50.0, x0 = 1.0, c = 0.5, bt = 0.1 }
        states { th: "rad", om: "rad/s" }
        inputs { tau: "N m" }
        let sn = sin(th);
        let cs = cos(th);
        let q = sqrt(l.powi(2) - (r * sn).powi(2));
        let xs = r * cs + q;
        let dx = -r * sn - r.powi(2) * sn * cs / q;
        let ddx = -r * cs - r.powi(2) * (cs.powi(2) - sn.powi(2)) / q
            - r.powi(4) * sn.powi(2) * cs.powi(2) / q.powi(3);
        equations {
            der(th) = om;
            (j + ms * dx.powi(2)) * der(om)
                == tau - bt * om - c * dx.powi(2) * om - k * (xs - x0) * dx
                    - ms * dx * ddx * om.powi(2);
        }
        outputs { angle: "rad" = th }
        references { angle = 1.0 + 0.3 * (1.0 - cos(t)) }
        tracking SliderCrankJointTracking { angle: [4.0] }
    }
}
