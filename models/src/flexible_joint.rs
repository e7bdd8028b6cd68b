//! A single-link robot arm with a flexible joint: relative degree 4, the kind of plant DPC
//! was introduced for (Jankowski & Van Brussel 1992).

dpc::model! {
    /// A link of inertia `i_link` driven through a torsional spring of stiffness `k` by a
    /// motor of inertia `j_motor`; gravity acts on the link's centre of mass at distance
    /// `l`. The motor torque `u` is the input, the link angle `q_link` the output, which the
    /// input reaches only after four differentiations. The tracking DAE applies two
    /// stabilised Hirschorn steps, `W(s) = (s + 2)(s + 3)`.
    pub FlexibleJoint {
        params { i_link = 1.0, j_motor = 0.5, k = 40.0, m = 1.0, l = 0.5, g = 9.81 }
        states { q_link: "rad", w_link: "rad/s", q_motor: "rad", w_motor: "rad/s" }
        inputs { u: "N m" }
        equations {
            der(q_link) = w_link;
            der(w_link) = (-m * g * l * sin(q_link) - k * (q_link - q_motor)) / i_link;
            der(q_motor) = w_motor;
            der(w_motor) = (k * (q_link - q_motor) + u) / j_motor;
        }
        outputs { q_link }
        references { q_link = 0.5 * sin(2.0 * t) }
        tracking FlexibleJointTracking { q_link: [2.0, 3.0] }
    }
}

dpc::model! {
    /// [`FlexibleJoint`] in mass-matrix form: the link's and the motor's equations are
    /// implicit, `I der(w) == ...`, with the link's inertia about the joint written as its
    /// inertia about its centre of mass plus `m l^2` (so the defaults give the same plant as
    /// `FlexibleJoint`). Two stabilised Hirschorn steps, `W(s) = (s + 2)(s + 3)`, need only
    /// the plant's unknown `der(w_link)`.
    pub FlexibleJointMass {
        params { i_com = 0.75, j_motor = 0.5, k = 40.0, m = 1.0, l = 0.5, g = 9.81 }
        states { q_link: "rad", w_link: "rad/s", q_motor: "rad", w_motor: "rad/s" }
        inputs { u: "N m" }
        equations {
            der(q_link) = w_link;
            (i_com + m * l.powi(2)) * der(w_link) == -m * g * l * sin(q_link) - k * (q_link - q_motor);
            der(q_motor) = w_motor;
            j_motor * der(w_motor) == k * (q_link - q_motor) + u;
        }
        outputs { q_link }
        references { q_link = 0.5 * sin(2.0 * t) }
        tracking FlexibleJointMassTracking { q_link: [2.0, 3.0] }
    }
}

dpc::model! {
    /// [`FlexibleJointMass`] with three stabilised Hirschorn steps,
    /// `W(s) = (s + 2)(s + 3)(s + 4)`: the third derivative of `q_link` is `der2(w_link)`, which
    /// the time derivative of the implicit link equation determines; both join the tracking
    /// DAE (one equation, one algebraic unknown), and the mass is never inverted.
    pub FlexibleJointMass3 {
        params { i_com = 0.75, j_motor = 0.5, k = 40.0, m = 1.0, l = 0.5, g = 9.81 }
        states { q_link: "rad", w_link: "rad/s", q_motor: "rad", w_motor: "rad/s" }
        inputs { u: "N m" }
        equations {
            der(q_link) = w_link;
            (i_com + m * l.powi(2)) * der(w_link) == -m * g * l * sin(q_link) - k * (q_link - q_motor);
            der(q_motor) = w_motor;
            j_motor * der(w_motor) == k * (q_link - q_motor) + u;
        }
        outputs { q_link }
        references { q_link = 0.5 * sin(2.0 * t) }
        tracking FlexibleJointMass3Tracking { q_link: [2.0, 3.0, 4.0] }
    }
}

dpc::model! {
    /// [`FlexibleJointMass`] with four stabilised Hirschorn steps, as many as its relative
    /// degree, `W(s) = (s + 2)(s + 3)(s + 4)(s + 5)`: the first and second time derivatives of
    /// the implicit link equation determine `der2(w_link)` and `der3(w_link)`, the tracking
    /// DAE has index 1.
    pub FlexibleJointMass4 {
        params { i_com = 0.75, j_motor = 0.5, k = 40.0, m = 1.0, l = 0.5, g = 9.81 }
        states { q_link: "rad", w_link: "rad/s", q_motor: "rad", w_motor: "rad/s" }
        inputs { u: "N m" }
        equations {
            der(q_link) = w_link;
            (i_com + m * l.powi(2)) * der(w_link) == -m * g * l * sin(q_link) - k * (q_link - q_motor);
            der(q_motor) = w_motor;
            j_motor * der(w_motor) == k * (q_link - q_motor) + u;
        }
        outputs { q_link }
        references { q_link = 0.5 * sin(2.0 * t) }
        tracking FlexibleJointMass4Tracking { q_link: [2.0, 3.0, 4.0, 5.0] }
    }
}
