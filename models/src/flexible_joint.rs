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
