//! The planar pendulum in Cartesian coordinates: a constrained plant of index 3.

dpc::model! {
    /// A point mass `m` on a massless rod of length `l`, in Cartesian coordinates `(x, y)`
    /// with velocities `(vx, vy)` and the Lagrange multiplier `lambda` (rod force per unit
    /// length). A horizontal force `f` acts on the mass; the output is the angle from the
    /// downward vertical. The position constraint makes the DAE index 3.
    pub Pendulum {
        params { m = 1.0, l = 1.0, g = 9.81 }
        states { x, y, vx, vy }
        algebraic { lambda }
        inputs { f }
        equations {
            der(x) = vx;
            der(y) = vy;
            m * der(vx) == -lambda * x + f;
            m * der(vy) == -lambda * y - m * g;
            0.0 == x.powi(2) + y.powi(2) - l.powi(2);
        }
        outputs { angle = atan2(x, -y) }
    }
}
