//! A pendulum hanging from a cart (an overhead crane with a rigid rope), written twice: in
//! Cartesian coordinates with a rod constraint and its Lagrange multiplier (a descriptor plant
//! of index 3), and in minimal (joint) coordinates as an ODE. The output is the cart position;
//! air drag on the load makes the zero dynamics (the load swinging under a cart held on its
//! path) stable, so the plant is minimum phase.

dpc::model! {
    /// A cart of mass `mc` (position `s`, viscous friction `b`, horizontal force `f`) carries a
    /// massless rod of length `l` with a load of mass `m` at `(xb, yb)`, `yb` measured upwards
    /// from the cart's pivot, and linear air drag `c` on the load. The rod is the constraint
    /// `(xb - s)^2 + yb^2 = l^2` with the multiplier `lambda` (rod tension per unit length):
    /// index 3. The load hanging at rest below the cart is an equilibrium for `f = 0`.
    pub CartPendulum {
        params { mc = 1.0, m = 0.5, l = 0.5, g = 9.81, b = 0.1, c = 0.2 }
        states { s: "m", xb: "m", yb: "m", vs: "m/s", vx: "m/s", vy: "m/s" }
        algebraic { lambda }
        inputs { f: "N" }
        equations {
            der(s) = vs;
            der(xb) = vx;
            der(yb) = vy;
            mc * der(vs) == f - b * vs + lambda * (xb - s);
            m * der(vx) == -lambda * (xb - s) - c * vx;
            m * der(vy) == -lambda * yb - c * vy - m * g;
            0.0 == 0.5 * ((xb - s).powi(2) + yb.powi(2) - l.powi(2));
        }
        outputs { cart: "m" = s }
        references { cart = 0.5 * (1.0 - cos(t)) }
        tracking CartPendulumTracking { cart: [2.0] }
    }
}

dpc::model! {
    /// The same crane in the cart position `s` and the rope angle `phi` from the downward
    /// vertical (Lagrange's equations; the load is at `(s + l sin(phi), -l cos(phi))`, the drag
    /// enters as generalised forces).
    pub CartPendulumJoint {
        params { mc = 1.0, m = 0.5, l = 0.5, g = 9.81, b = 0.1, c = 0.2 }
        states { s: "m", phi: "rad", vs: "m/s", om: "rad/s" }
        inputs { f: "N" }
        equations {
            der(s) = vs;
            der(phi) = om;
            (mc + m) * der(vs) + m * l * cos(phi) * der(om)
                == f - b * vs + m * l * sin(phi) * om.powi(2) - c * (vs + l * cos(phi) * om);
            m * l * cos(phi) * der(vs) + m * l.powi(2) * der(om)
                == -m * g * l * sin(phi) - c * l * (cos(phi) * vs + l * om);
        }
        outputs { cart: "m" = s }
        references { cart = 0.5 * (1.0 - cos(t)) }
        tracking CartPendulumJointTracking { cart: [2.0] }
    }
}
