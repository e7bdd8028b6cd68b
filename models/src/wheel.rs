//! The paper's nonlinear wheel (Appendix) and its linearisation (Section 4, (4.1)).

dpc::model! {
    /// A wheel rolling on a plane, in Euler angles: lean `theta`, heading `psi`, and the
    /// rates of spin `dphi`, lean `dtheta` and heading `dpsi` (paper, Appendix). The inputs
    /// are the steering torque `u1` and the pedalling torque `u2`; the outputs to track are
    /// `theta` and `psi`. Stabilised Hirschorn step `W(s) = s + 5` on both outputs (paper,
    /// Sections 4-5).
    pub Wheel {
        params {
            /// Mass of the wheel [kg].
            m: "kg" = 1.0,
            /// Radius [m].
            r: "m" = 1.0,
            /// Radial moment of inertia [kg m^2].
            i_r: "kg m^2" = 0.5,
            /// Normal moment of inertia [kg m^2].
            i_n: "kg m^2" = 0.25,
            /// Gravity [m/s^2].
            g: "m/s^2" = 9.81,
        }
        states { theta: "rad", psi: "rad", dphi: "rad/s", dtheta: "rad/s", dpsi: "rad/s" }
        inputs {
            /// Steering torque.
            u1: "N m",
            /// Pedalling torque.
            u2: "N m",
        }
        let a1 = i_n + m * r.powi(2);
        let a2 = i_r + m * r.powi(2);
        let a3 = m * r.powi(2) + i_n - i_r;
        let a4 = 2.0 * m * r.powi(2) + i_n;
        equations {
            der(theta) = dtheta;
            der(psi) = dpsi;
            (i_r * sin(theta).powi(2) + a1 * cos(theta).powi(2)) * der(dphi)
                + a1 * cos(theta) * der(dpsi)
                == i_n * dtheta * dpsi * sin(theta)
                    + 2.0 * a3 * dphi * dtheta * cos(theta) * sin(theta)
                    + u1 * sin(theta);
            a2 * der(dtheta)
                == -a1 * dphi * dpsi * sin(theta)
                    - a3 * dphi.powi(2) * cos(theta) * sin(theta)
                    - m * g * r * cos(theta);
            a1 * cos(theta) * der(dphi) + (i_n + m * r.powi(2)) * der(dpsi)
                == a4 * dphi * dtheta * sin(theta) + u2;
        }
        outputs { theta, psi }
        references {
            theta = FRAC_PI_2 + 0.1 * sin(t),
            psi = -6.0 * t - 0.5 * (t * atan(t) - ln(1.0 + t.powi(2)) / 2.0),
        }
        tracking WheelTracking { theta: [5.0], psi: [5.0] }
    }
}

dpc::model! {
    /// The paper's linear example (4.1): the wheel linearised about
    /// `x0(t) = [pi/2, -6t, 0, 0, -6]`, in deviation coordinates. The printed model has unit
    /// input gains; the Appendix parameters give `b1 = 2`, `b2 = 0.8` (set them in the params).
    pub WheelLinear {
        params { a34 = -3.0, a41 = 6.54, a43 = 5.0, b1 = 1.0, b2 = 1.0 }
        states { theta, psi, dphi, dtheta, dpsi }
        inputs { u1, u2 }
        equations {
            der(theta) = dtheta;
            der(psi) = dpsi;
            der(dphi) = a34 * dtheta + b1 * u1;
            der(dtheta) = a41 * theta + a43 * dphi;
            der(dpsi) = b2 * u2;
        }
        outputs { y1 = theta, y2 = psi }
        tracking WheelLinearTracking { y1: [5.0], y2: [5.0] }
    }
}
