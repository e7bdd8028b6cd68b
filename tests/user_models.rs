//! Models declared the way a user crate would, depending only on `dpc`: mechanical and
//! chemical DAEs that are not in `dpc-models`, using every supported function. Their
//! generated Jacobians must agree with central differences of their residuals.

mod common;

use common::{check_model, dims};
use dpc::core::model::{DaeModel, UnknownKind};
use proptest::prelude::*;

dpc::model! {
    /// Robertson's chemical kinetics as an index-1 DAE (Hairer & Wanner, IV.10).
    pub Robertson {
        params { k1 = 0.04, k2 = 3e7, k3 = 1e4 }
        states { y1, y2 }
        algebraic { y3 }
        equations {
            der(y1) = -k1 * y1 + k3 * y2 * y3;
            der(y2) = k1 * y1 - k3 * y2 * y3 - k2 * y2.powi(2);
            0.0 == y1 + y2 + y3 - 1.0;
        }
        outputs { y3 }
    }
}

dpc::model! {
    /// A non-isothermal CSTR with Arrhenius kinetics; the coolant temperature is the input.
    pub Cstr {
        params { q = 100.0, v = 100.0, c_in = 1.0, t_in = 350.0, k0 = 7.2e10, e_r = 8750.0,
                 dh = -5e4, rho = 1000.0, cp = 0.239, ua = 5e4 }
        states { ca, temp }
        inputs { t_cool }
        let rate = k0 * exp(-e_r / temp) * ca;
        equations {
            der(ca) = q / v * (c_in - ca) - rate;
            rho * cp * der(temp) == rho * cp * q / v * (t_in - temp) - dh * rate
                + ua / v * (t_cool - temp);
        }
        outputs { temp }
    }
}

dpc::model! {
    /// A double pendulum in joint angles, with its mass matrix written implicitly.
    pub DoublePendulum {
        params { m1 = 1.0, m2 = 0.7, l1 = 1.0, l2 = 0.8, g = 9.81 }
        states { a1, a2, w1, w2 }
        inputs { tau1, tau2 }
        let c = cos(a1 - a2);
        let s = sin(a1 - a2);
        equations {
            der(a1) = w1;
            der(a2) = w2;
            (m1 + m2) * l1 * der(w1) + m2 * l2 * c * der(w2)
                == -m2 * l2 * w2.powi(2) * s - (m1 + m2) * g * sin(a1) + tau1 / l1;
            l2 * der(w2) + l1 * c * der(w1) == l1 * w1.powi(2) * s - g * a2.sin() + tau2 / (m2 * l2);
        }
        outputs { tip_x = l1 * sin(a1) + l2 * sin(a2), tip_y = -l1 * cos(a1) - l2 * cos(a2) }
    }
}

dpc::model! {
    /// Not a physical plant: exercises every function of the DSL in both call forms.
    pub Functions {
        params { a = 0.3 }
        states { x, y }
        algebraic { z }
        inputs { u }
        equations {
            der(x) = sqrt(x.powi(2) + 1.0) + exp(-y) * ln(2.0 + x.sin().powi(2)) + tan(a * x)
                + asin(a * y.tanh()) + x.cos().acos() * 0.1 + atan(u) + x.sinh() - cosh(y) / 3.0;
            der(y) = atan2(y, 1.5 + x.abs()) + x.hypot(y) + (1.0 + y.powi(2)).powf(a + u)
                - z + std::f64::consts::PI * t + E;
            // On the sampled range (0.1, 0.9) the order of each min/max's operands is fixed:
            // the second operand wins in the free forms, the receiver in the method forms.
            0.0 == z - y.powf(2.0) - abs(x) * z.tanh() - 3.0 + 0.1 * (x + 2.0).signum() * y
                + signum(u - 2.0) * x + 0.2 * max(x, y + 2.0) * (x + 1.0).max(y * y)
                - min(x * z, y - 1.0) * (z - 2.0).min(u * x);
        }
        outputs { r = hypot(x, y) }
    }
}

#[test]
fn declared_dimensions_names_and_kinds() {
    assert_eq!(Robertson::N_STATES, 2);
    assert_eq!(Robertson::N_ALGEBRAIC, 1);
    let robertson = Robertson::default();
    let kinds: Vec<UnknownKind> = (0..3)
        .map(|i| robertson.structure().unknown_kind(i))
        .collect();
    assert_eq!(
        kinds,
        [
            UnknownKind::Differential,
            UnknownKind::Differential,
            UnknownKind::Algebraic
        ]
    );
    assert_eq!(robertson.params.k2, 3e7);
    assert_eq!(Cstr::default().structure().inputs, ["t_cool"]);
    assert_eq!(
        DoublePendulum::default().structure().outputs,
        ["tip_x", "tip_y"]
    );
    assert_eq!(DoublePendulum::RELATIVE_DEGREES, &[Some(2), Some(2)]);
    assert_eq!(Cstr::RELATIVE_DEGREES, &[Some(1)]);
    // Robertson's residual at the consistent initial state.
    let mut r = [0.0; 3];
    Robertson::default().residual(0.0, &[1.0, 0.0], &[-0.04, 0.04], &[0.0], &[], &mut r);
    assert_eq!(r, [0.0, 0.0, 0.0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn robertson_jacobians(v in prop::collection::vec(0.0..1.0f64, dims::<Robertson>())) {
        check_model::<Robertson>(&v);
    }

    #[test]
    fn cstr_jacobians(v in prop::collection::vec(0.5..1.0f64, dims::<Cstr>())) {
        // Scale to the physical range: temperatures about 300-400 K.
        let mut v = v;
        v[2] *= 400.0;
        v[4] *= 400.0;
        v[5] *= 400.0;
        check_model::<Cstr>(&v);
    }

    #[test]
    fn double_pendulum_jacobians(v in prop::collection::vec(-3.0..3.0f64, dims::<DoublePendulum>())) {
        check_model::<DoublePendulum>(&v);
    }

    #[test]
    fn all_functions_jacobians(v in prop::collection::vec(0.1..0.9f64, dims::<Functions>())) {
        check_model::<Functions>(&v);
    }
}

dpc::model! {
    /// Coulomb friction on a mass, the sign taken with `signum`: `m v' = u - mu g signum(v)`.
    pub Coulomb {
        params { m = 2.0, mu = 0.3, g = 9.81 }
        states { x, v }
        inputs { u }
        equations {
            der(x) = v;
            m * der(v) == u - mu * m * g * v.signum();
        }
    }
}

#[test]
fn signum_is_the_sign_with_derivative_zero_compiled_and_read_from_a_file() {
    let text = r#"
        pub Coulomb {
            params { m = 2.0, mu = 0.3, g = 9.81 }
            states { x, v }
            inputs { u }
            equations {
                der(x) = v;
                m * der(v) == u - mu * m * g * signum(v);
            }
        }
    "#;
    let file = dpc::runtime::parse("coulomb.dpc", text).unwrap();
    let plant = file.plant();
    let compiled = Coulomb::default();
    for v in [-1.5, -1e-300, 0.0, -0.0, 2.0] {
        let (x, xdot, u) = ([0.1, v], [v, 0.4], [1.0]);
        let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
        compiled.residual(0.0, &x, &xdot, &[], &u, &mut a);
        plant.residual(0.0, &x, &xdot, &[], &u, &mut b);
        let expected = 2.0 * 0.4 - (1.0 - 0.3 * 2.0 * 9.81 * f64::signum(v));
        assert_eq!(a[1], expected, "v = {v}");
        assert_eq!(b[1], expected, "v = {v}");
        // d/dv of the friction term is 0: the entry is the mass matrix's `c m` alone.
        let mut m = dpc::nalgebra::DMatrix::<f64>::zeros(2, 2);
        compiled.iteration_matrix(0.0, &x, &xdot, &[], &u, 5.0, &mut m);
        assert_eq!(m[(1, 1)], 10.0);
        let mut m = dpc::nalgebra::DMatrix::<f64>::zeros(2, 2);
        plant.iteration_matrix(0.0, &x, &xdot, &[], &u, 5.0, &mut m);
        assert_eq!(m[(1, 1)], 10.0);
    }
}

dpc::model! {
    /// A mass pushed by a saturated proportional actuator, with viscous damping:
    /// `m v' = max(-umax, min(umax, u - k x)) - damping v`.
    pub Saturation {
        params { m = 2.0, umax = 1.5, k = 2.0, damping = 0.5 }
        states { x, v }
        inputs { u }
        equations {
            der(x) = v;
            m * der(v) == max(-umax, min(umax, u - k * x)) - damping * v;
        }
    }
}

/// The same plant as a plant file, with the method forms.
fn saturation_file(umax: f64) -> String {
    format!(
        r#"
        pub Saturation {{
            params {{ m = 2.0, umax = {umax:?}, k = 2.0, damping = 0.5 }}
            states {{ x, v }}
            inputs {{ u }}
            equations {{
                der(x) = v;
                m * der(v) == (u - k * x).min(umax).max(-umax) - damping * v;
            }}
        }}
    "#
    )
}

#[test]
fn min_and_max_saturate_exactly_compiled_and_read_from_a_file() {
    let eps = 2f64.powi(-20);
    // (umax, v, v', actuator demand u - k x, the weight of the unsaturated branch in the
    // derivative: 1 inside, 0 saturated, 1/2 on a corner)
    type Case<'a> = (f64, f64, f64, &'a [(f64, f64)]);
    let cases: [Case<'_>; 2] = [
        (
            1.5,
            0.25,
            0.5,
            &[
                (-3.0, 0.0),
                (-1.5 - eps, 0.0),
                (-1.5, 0.5),
                (-1.5 + eps, 1.0),
                (0.0, 1.0),
                (1.5 - eps, 1.0),
                (1.5, 0.5),
                (1.5 + eps, 0.0),
                (3.0, 0.0),
            ],
        ),
        // Very different magnitudes: `0.5 (a + b - |a - b|)` would make min(1e20, 1) zero.
        // v = v' = 0, so the residual is exactly minus the actuator force.
        (
            1e20,
            0.0,
            0.0,
            &[
                (1.0, 1.0),
                (-1.0, 1.0),
                (1e30, 0.0),
                (-1e30, 0.0),
                (1e20, 0.5),
            ],
        ),
    ];
    let (m, k, damping, c) = (2.0, 2.0, 0.5, 5.0);
    for (umax, v, vdot, points) in cases {
        let file = dpc::runtime::parse("saturation.dpc", &saturation_file(umax)).unwrap();
        let plant = file.plant();
        let mut compiled = Saturation::default();
        compiled.params.umax = umax;
        for &(demand, weight) in points {
            // x = 1/4: the demand u - k x is u - 1/2, exactly
            let (x, xdot, u) = ([0.25, v], [v, vdot], [demand + 0.5]);
            assert_eq!(u[0] - k * x[0], demand, "demand {demand} is exact");
            let force = demand.min(umax).max(-umax);
            let expected = m * vdot - force + damping * v;
            let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
            compiled.residual(0.0, &x, &xdot, &[], &u, &mut a);
            plant.residual(0.0, &x, &xdot, &[], &u, &mut b);
            assert_eq!(a[1], expected, "umax = {umax}, demand = {demand}");
            assert_eq!(b[1], expected, "umax = {umax}, demand = {demand}");
            // dF/dx = k * weight, dF/dv + c dF/dv' = damping + c m
            let mut ma = dpc::nalgebra::DMatrix::<f64>::zeros(2, 2);
            compiled.iteration_matrix(0.0, &x, &xdot, &[], &u, c, &mut ma);
            let mut mb = dpc::nalgebra::DMatrix::<f64>::zeros(2, 2);
            plant.iteration_matrix(0.0, &x, &xdot, &[], &u, c, &mut mb);
            for mat in [ma, mb] {
                assert_eq!(mat[(1, 0)], k * weight, "umax = {umax}, demand = {demand}");
                assert_eq!(
                    mat[(1, 1)],
                    damping + c * m,
                    "umax = {umax}, demand = {demand}"
                );
            }
        }
    }
}
