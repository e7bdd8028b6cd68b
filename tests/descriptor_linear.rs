//! Descriptor linearisation against independent minimal-coordinate models.
//!
//! Each constrained plant is written twice: in descriptor form (Cartesian or mixed coordinates,
//! a rod constraint, a Lagrange multiplier; index 3) and in minimal (joint) coordinates as an
//! ODE derived separately by Lagrange's equations. Their linearisations about the same
//! physical equilibrium must have the same eigenvalues and transfer function, and the Section 3
//! analysis of the manifold realisation must give the same `eig(Abar_4)`, transmission zeros,
//! verdict and (mapped to the plant's coordinates) the same `K_n`. An index-1 plant and an ODE
//! must give systems similar to [`linearize`]'s. Error cases: an inconsistent point, a singular
//! pencil, an index above 3, an input whose derivatives drive the plant.
//!
//! Consistent initial values: states given off the manifold are projected onto the rod
//! constraint and its hidden velocity constraint, and the derivatives and multiplier match those
//! of the minimal-coordinate model at the same physical state.

use dpc::core::consistent::{consistent_state, ConsistentError, ConsistentOptions};
use dpc::core::linear_analysis::descriptor::{
    linearize_descriptor, DescriptorError, DescriptorOptions, ManifoldRealisation,
};
use dpc::core::linear_analysis::transfer::transfer_matrix;
use dpc::core::linear_analysis::{analyze, eigenvalues, Analysis, AnalysisOptions, LinearSystem};
use dpc::core::linearize::{linearize, OperatingPoint};
use dpc::nalgebra::Complex;
use dpc::nalgebra::DMatrix;
use dpc_models::{SliderCrank, SliderCrankJoint, SliderCrankParams, Wheel};

type C64 = Complex<f64>;

dpc::model! {
    /// Pendulum on a cart in Cartesian coordinates: cart position `s`, bob `(xb, yb)`, a rod of
    /// length `l` from the cart to the bob, multiplier `lambda`; horizontal force `f` on the
    /// cart, viscous friction `b` on the cart. Index 3.
    pub CartPendulumCartesian {
        params { mc = 2.0, m = 0.5, l = 0.8, g = 9.81, b = 0.3 }
        states { s, xb, yb, vs, vx, vy }
        algebraic { lambda }
        inputs { f }
        equations {
            der(s) = vs;
            der(xb) = vx;
            der(yb) = vy;
            mc * der(vs) == f - b * vs + lambda * (xb - s);
            m * der(vx) == -lambda * (xb - s);
            m * der(vy) == -lambda * yb - m * g;
            0.0 == 0.5 * ((xb - s).powi(2) + yb.powi(2) - l.powi(2));
        }
        outputs { cart = s }
    }
}

dpc::model! {
    /// The same pendulum on a cart in minimal coordinates: cart position `s` and rod angle
    /// `phi` from the downward vertical (Lagrange's equations, mass matrix written implicitly).
    pub CartPendulumMinimal {
        params { mc = 2.0, m = 0.5, l = 0.8, g = 9.81, b = 0.3 }
        states { s, phi, vs, om }
        inputs { f }
        equations {
            der(s) = vs;
            der(phi) = om;
            (mc + m) * der(vs) + m * l * cos(phi) * der(om)
                == f - b * vs + m * l * sin(phi) * om.powi(2);
            cos(phi) * der(vs) + l * der(om) == -g * sin(phi);
        }
        outputs { cart = s }
    }
}

// The slider-crank in descriptor form and in the crank angle alone are the repository's
// models (`dpc_models::SliderCrank`, `dpc_models::SliderCrankJoint`).

dpc::model! {
    /// An index-1 DAE with feedthrough: the algebraic `z` depends on the input.
    pub IndexOne {
        params { a = 2.0 }
        states { x1, x2 }
        algebraic { z }
        inputs { u }
        equations {
            der(x1) = x2;
            der(x2) = -sin(x1) - z + u;
            0.0 == z - x1.powi(3) - a * x2 - 0.5 * u;
        }
        outputs { y = x1 + 0.1 * z }
    }
}

dpc::model! {
    /// Index 4: a triple integrator whose position is constrained to zero.
    pub IndexFour {
        states { x1, x2, x3 }
        algebraic { z }
        inputs { u }
        equations {
            der(x1) = x2;
            der(x2) = x3;
            der(x3) = z + u;
            0.0 == x1;
        }
        outputs { y = x2 }
    }
}

dpc::model! {
    /// The input prescribes a position: `x1 = u`, so `z = u''` (improper).
    pub Prescribed {
        states { x1, x2 }
        algebraic { z }
        inputs { u }
        equations {
            der(x1) = x2;
            der(x2) = z;
            0.0 == x1 - u;
        }
        outputs { y = x2 }
    }
}

dpc::model! {
    /// Only `z1 + z2` is determined: a singular pencil.
    pub Undetermined {
        states { x }
        algebraic { z1, z2 }
        inputs { u }
        equations {
            der(x) = -x + z1 + z2 + u;
            0.0 == z1 + z2 - x;
            0.0 == 2.0 * z1 + 2.0 * z2 - 2.0 * x;
        }
        outputs { y = x }
    }
}

/// Eigenvalue sets agree to `tol` relative to `1 + |z|` (matched greedily, so conjugate
/// pairs and repeated values are handled).
fn assert_same_spectrum(what: &str, a: &[C64], b: &[C64], tol: f64) {
    assert_eq!(a.len(), b.len(), "{what}: {a:?} vs {b:?}");
    let mut left: Vec<C64> = b.to_vec();
    for z in a {
        let (k, d) = left
            .iter()
            .enumerate()
            .map(|(k, w)| (k, (z - w).norm() / (1.0 + z.norm())))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .unwrap();
        assert!(d < tol, "{what}: {z} has no partner in {b:?} (got {a:?})");
        left.remove(k);
    }
}

fn points() -> Vec<C64> {
    vec![
        C64::new(0.3, 1.1),
        C64::new(-0.7, 2.3),
        C64::new(2.0, -0.5),
        C64::new(0.05, 7.0),
    ]
}

fn assert_same_transfer(what: &str, a: &LinearSystem, b: &LinearSystem) {
    for s in points() {
        let ha = transfer_matrix(a, s).unwrap();
        let hb = transfer_matrix(b, s).unwrap();
        let scale = 1.0 + ha.iter().map(|z| z.norm()).fold(0.0, f64::max);
        let err = (&ha - &hb).iter().map(|z| z.norm()).fold(0.0, f64::max) / scale;
        assert!(err < 1e-9, "{what}: H({s}) = {ha} vs {hb}");
    }
}

fn assert_same_analysis(what: &str, a: &Analysis, b: &Analysis) {
    assert_eq!(a.n, b.n, "{what}: state dimensions");
    assert_eq!(a.nu, b.nu, "{what}: nu of the hat system");
    assert_same_spectrum(
        &format!("{what}: eig(Abar_4)"),
        &a.abar4_eigenvalues,
        &b.abar4_eigenvalues,
        1e-7,
    );
    assert_same_spectrum(
        &format!("{what}: transmission zeros"),
        &a.transmission_zeros,
        &b.transmission_zeros,
        1e-7,
    );
    assert_same_spectrum(
        &format!("{what}: closed loop"),
        &a.closed_loop_eigenvalues,
        &b.closed_loop_eigenvalues,
        1e-7,
    );
    assert_eq!(a.dpc_stable, b.dpc_stable, "{what}: verdict");
    assert_eq!(a.minimum_phase, b.minimum_phase, "{what}: minimum phase");
    assert_eq!(
        a.dpc_stable_prefeedback, b.dpc_stable_prefeedback,
        "{what}: verdict with K_n"
    );
}

fn descriptor_point<'a>(
    x: &'a [f64],
    xdot: &'a [f64],
    z: &'a [f64],
    u: &'a [f64],
) -> OperatingPoint<'a> {
    OperatingPoint {
        t: 0.0,
        x,
        xdot,
        z,
        u,
    }
}

/// Cart pendulum: `upright` selects the inverted equilibrium; `speed` a steady motion of the
/// cart (the friction balanced by the force).
fn cart_pendulum_pair(upright: bool, speed: f64) -> (ManifoldRealisation, LinearSystem, f64) {
    let p = CartPendulumCartesianParams::default();
    let (s0, phi0) = (0.3, if upright { std::f64::consts::PI } else { 0.0 });
    let xb = s0 + p.l * phi0.sin();
    let yb = -p.l * phi0.cos();
    // m yb'' = 0 = -lambda yb - m g.
    let lambda = -p.m * p.g / yb;
    let f0 = p.b * speed;
    let x = [s0, xb, yb, speed, speed, 0.0];
    let xdot = [speed, speed, 0.0, 0.0, 0.0, 0.0];
    let (_, real) = linearize_descriptor(
        &CartPendulumCartesian::default(),
        descriptor_point(&x, &xdot, &[lambda], &[f0]),
        &DescriptorOptions::default(),
    )
    .unwrap();
    let xm = [s0, phi0, speed, 0.0];
    let xmdot = [speed, 0.0, 0.0, 0.0];
    let min = linearize(
        &CartPendulumMinimal::default(),
        descriptor_point(&xm, &xmdot, &[], &[f0]),
    )
    .unwrap();
    (real, min, phi0)
}

/// `d(s, xb, yb, vs, vx, vy) / d(s, phi, vs, om)` at rest with angle `phi0`.
fn cart_pendulum_map(l: f64, phi0: f64) -> DMatrix<f64> {
    let (c, s) = (phi0.cos(), phi0.sin());
    DMatrix::from_row_slice(
        6,
        4,
        &[
            1.0,
            0.0,
            0.0,
            0.0, //
            1.0,
            l * c,
            0.0,
            0.0, //
            0.0,
            l * s,
            0.0,
            0.0, //
            0.0,
            0.0,
            1.0,
            0.0, //
            0.0,
            0.0,
            1.0,
            l * c, //
            0.0,
            0.0,
            0.0,
            l * s,
        ],
    )
}

fn w_options() -> AnalysisOptions {
    AnalysisOptions {
        w: Some(vec![vec![5.0]]),
        ..AnalysisOptions::default()
    }
}

fn check_cart_pendulum(upright: bool, speed: f64) {
    let what = if upright { "upright" } else { "hanging" };
    let (real, min, phi0) = cart_pendulum_pair(upright, speed);
    assert_eq!(real.index, 3, "{what}: index");
    assert_eq!(real.dof, 4, "{what}: positions and velocities of (s, phi)");
    // The rod constrains yb and vy (normal to the manifold at phi = 0 or pi), not the cart.
    assert_eq!(real.constrained_states, vec![2, 5], "{what}");
    let ortho = real.basis.transpose() * &real.basis - DMatrix::identity(4, 4);
    assert!(ortho.amax() < 1e-12, "{what}: U orthonormal");

    assert_same_spectrum(
        &format!("{what}: eig(A)"),
        &eigenvalues(&real.system.a).unwrap(),
        &eigenvalues(&min.a).unwrap(),
        1e-9,
    );
    assert_same_transfer(&format!("{what}: f -> s"), &real.system, &min);

    // The bob's horizontal position as output: e_xb^T U against [1, l cos phi0, 0, 0].
    let l = CartPendulumCartesianParams::default().l;
    let bob_real = LinearSystem::without_feedthrough(
        real.system.a.clone(),
        real.system.b.clone(),
        real.basis.rows(1, 1).into_owned(),
    )
    .unwrap();
    let bob_min = LinearSystem::without_feedthrough(
        min.a.clone(),
        min.b.clone(),
        DMatrix::from_row_slice(1, 4, &[1.0, l * phi0.cos(), 0.0, 0.0]),
    )
    .unwrap();
    assert_same_transfer(&format!("{what}: f -> xb"), &bob_real, &bob_min);

    let opts = w_options();
    let ar = analyze(&real.system, &opts).unwrap();
    let am = analyze(&min, &opts).unwrap();
    assert_same_analysis(&format!("{what}: output s"), &ar, &am);
    let abr = analyze(&bob_real, &opts).unwrap();
    let abm = analyze(&bob_min, &opts).unwrap();
    assert_same_analysis(&format!("{what}: output xb"), &abr, &abm);

    // K_n mapped to the Cartesian coordinates acts on a minimal-coordinate variation as the
    // minimal model's own K_n does (a single-input placement is unique).
    // Abar_4 is unstable for both outputs here, so K_n is built and compared.
    assert!(
        ar.k_n.is_some() && abr.k_n.is_some(),
        "{what}: no K_n to compare"
    );
    for (a_red, a_min) in [(&ar, &am), (&abr, &abm)] {
        match (&a_red.k_n, &a_min.k_n) {
            (Some(kr), Some(km)) => {
                let kx = real.gain_to_plant(kr).unwrap();
                let pulled = &kx * cart_pendulum_map(l, phi0);
                let err = (&pulled - km).amax() / (1.0 + km.amax());
                assert!(err < 1e-7, "{what}: K_n: {pulled} vs {km}");
                // Zero on the constrained directions.
                assert!((&kx * &real.normal).amax() < 1e-9 * (1.0 + kx.amax()));
            }
            (None, None) => {}
            other => panic!("{what}: K_n built for one form only: {other:?}"),
        }
    }
}

#[test]
fn cart_pendulum_hanging_matches_minimal_coordinates() {
    check_cart_pendulum(false, 0.0);
}

#[test]
fn cart_pendulum_upright_matches_minimal_coordinates() {
    let (real, _, _) = cart_pendulum_pair(true, 0.0);
    // Upright: an unstable pole from the pendulum.
    let ev = eigenvalues(&real.system.a).unwrap();
    assert!(ev.iter().any(|z| z.re > 1.0), "{ev:?}");
    check_cart_pendulum(true, 0.0);
}

#[test]
fn cart_pendulum_steady_motion_matches_minimal_coordinates() {
    check_cart_pendulum(false, 1.5);
}

#[test]
fn cart_pendulum_multipliers_on_the_manifold() {
    // Hanging at rest, the acceleration constraint linearises to -l d(yb'') = 0 (the velocity
    // terms are quadratic), and m d(yb'') = l d(lambda) - lambda d(yb) with d(yb) = 0 on the
    // manifold: d(lambda) = 0, so Z_xi and Z_u vanish.
    let (real, _, _) = cart_pendulum_pair(false, 0.0);
    assert_eq!(real.algebraic_state.shape(), (1, 4));
    assert!(
        real.algebraic_state.amax() < 1e-9,
        "{}",
        real.algebraic_state
    );
    assert!(
        real.algebraic_input.amax() < 1e-9,
        "{}",
        real.algebraic_input
    );
    // Tilted (a consistent non-symmetric point): lambda does respond.
    let p = CartPendulumCartesianParams::default();
    let phi: f64 = 0.4;
    let (xb, yb) = (p.l * phi.sin(), -p.l * phi.cos());
    // A point of a motion released at rest: zero velocity, accelerations from the minimal
    // model's equations, the multiplier from the bob's vertical equation.
    let (mc, m, l, g) = (p.mc, p.m, p.l, p.g);
    // Minimal-coordinate accelerations at rest with f = 0.
    let mm = DMatrix::from_row_slice(2, 2, &[mc + m, m * l * phi.cos(), phi.cos(), l]);
    let acc = mm
        .lu()
        .solve(&DMatrix::from_row_slice(2, 1, &[0.0, -g * phi.sin()]))
        .unwrap();
    let (sdd, phidd) = (acc[0], acc[1]);
    let xbdd = sdd + l * phi.cos() * phidd;
    let ybdd = l * phi.sin() * phidd;
    let lambda = -(m * ybdd + m * g) / yb;
    let x = [0.0, xb, yb, 0.0, 0.0, 0.0];
    let xdot = [0.0, 0.0, 0.0, sdd, xbdd, ybdd];
    let (_, real) = linearize_descriptor(
        &CartPendulumCartesian::default(),
        descriptor_point(&x, &xdot, &[lambda], &[0.0]),
        &DescriptorOptions::default(),
    )
    .unwrap();
    assert_eq!((real.index, real.dof), (3, 4));
    assert!(
        real.algebraic_input.amax() > 1e-3,
        "{}",
        real.algebraic_input
    );
}

#[test]
fn slider_crank_matches_minimal_coordinates() {
    let p = SliderCrankParams::default();
    for th0 in [1.0f64, 2.4, -0.7] {
        let what = format!("slider-crank at {th0}");
        let xs0 = p.r * th0.cos() + (p.l.powi(2) - (p.r * th0.sin()).powi(2)).sqrt();
        let lambda = -p.k * (xs0 - p.x0) / (xs0 - p.r * th0.cos());
        let tau = lambda * p.r * xs0 * th0.sin();
        let (_, real) = linearize_descriptor(
            &SliderCrank::default(),
            descriptor_point(&[th0, xs0, 0.0, 0.0], &[0.0; 4], &[lambda], &[tau]),
            &DescriptorOptions::default(),
        )
        .unwrap();
        // The minimal model's residual check: the same torque holds it at rest.
        let min = linearize(
            &SliderCrankJoint::default(),
            descriptor_point(&[th0, 0.0], &[0.0, 0.0], &[], &[tau]),
        )
        .unwrap();
        assert_eq!((real.index, real.dof), (3, 2), "{what}");
        assert_same_spectrum(
            &format!("{what}: eig(A)"),
            &eigenvalues(&real.system.a).unwrap(),
            &eigenvalues(&min.a).unwrap(),
            1e-9,
        );
        assert_same_transfer(&what, &real.system, &min);
        let opts = w_options();
        let ar = analyze(&real.system, &opts).unwrap();
        let am = analyze(&min, &opts).unwrap();
        assert_same_analysis(&what, &ar, &am);
        // The tangent direction in (th, xs) is (1, X'(th)) normalised.
        let dx = -p.r * th0.sin()
            - p.r.powi(2) * th0.sin() * th0.cos()
                / (p.l.powi(2) - (p.r * th0.sin()).powi(2)).sqrt();
        let t = nalgebra_unit(&[1.0, dx, 0.0, 0.0]);
        let proj = real.basis.transpose() * &t;
        assert!(
            (proj.norm() - 1.0).abs() < 1e-10,
            "{what}: tangent in span U"
        );
    }
}

fn nalgebra_unit(v: &[f64]) -> dpc::nalgebra::DVector<f64> {
    let v = dpc::nalgebra::DVector::from_column_slice(v);
    let n = v.norm();
    v / n
}

/// For index-1 and ODE plants the manifold realisation is similar to `linearize`'s result.
fn assert_similar_to_linearize<M: dpc::core::DaeModel>(
    model: &M,
    point: OperatingPoint<'_>,
    index: usize,
) {
    let (_, real) = linearize_descriptor(model, point, &DescriptorOptions::default()).unwrap();
    let old = linearize(model, point).unwrap();
    assert_eq!(real.index, index);
    assert_eq!(real.dof, old.n());
    assert!(real.constrained_states.is_empty());
    assert_same_spectrum(
        "eig(A)",
        &eigenvalues(&real.system.a).unwrap(),
        &eigenvalues(&old.a).unwrap(),
        1e-9,
    );
    assert_same_transfer("index <= 1", &real.system, &old);
    // The similarity is U itself: A_r = U^T A U etc.
    let u = &real.basis;
    let scale = 1.0 + old.a.amax();
    assert!((&real.system.a - u.transpose() * &old.a * u).amax() < 1e-9 * scale);
    assert!((&real.system.b - u.transpose() * &old.b).amax() < 1e-9 * (1.0 + old.b.amax()));
    assert!((&real.system.c - &old.c * u).amax() < 1e-9 * (1.0 + old.c.amax()));
    assert!((&real.system.d - &old.d).amax() < 1e-9 * (1.0 + old.d.amax()));
}

#[test]
fn index_one_and_ode_plants_agree_with_linearize() {
    // Index 1 with feedthrough, away from equilibrium.
    let p = IndexOneParams::default();
    let (x1, x2, u) = (0.3, 0.2, 0.1);
    let z = x1 * x1 * x1 + p.a * x2 + 0.5 * u;
    let x = [x1, x2];
    let xdot = [x2, -x1.sin() - z + u];
    assert_similar_to_linearize(
        &IndexOne::default(),
        descriptor_point(&x, &xdot, &[z], &[u]),
        1,
    );
    // The wheel (an ODE with an implicit mass matrix) on the paper's nominal motion.
    let x0 = [std::f64::consts::FRAC_PI_2, -12.0, 0.0, 0.0, -6.0];
    let xdot0 = [0.0, -6.0, 0.0, 0.0, 0.0];
    assert_similar_to_linearize(
        &Wheel::default(),
        OperatingPoint {
            t: 2.0,
            x: &x0,
            xdot: &xdot0,
            z: &[],
            u: &[0.0, 0.0],
        },
        0,
    );
}

#[test]
fn inconsistent_point_is_reported_with_its_equation() {
    let err = linearize_descriptor(
        &CartPendulumCartesian::default(),
        descriptor_point(
            &[0.0, 0.0, -0.7, 0.0, 0.0, 0.0],
            &[0.0; 6],
            &[0.5 * 9.81 / 0.7],
            &[0.0],
        ),
        &DescriptorOptions::default(),
    )
    .unwrap_err();
    match &err {
        DescriptorError::Inconsistent { equation, .. } => {
            assert!(equation.starts_with("equation 6"), "{equation}");
        }
        other => panic!("expected Inconsistent, got {other:?}"),
    }
    assert!(!err.to_string().contains("Some("), "{err}");
}

#[test]
fn singular_pencil_index_above_three_and_improper_input_are_typed_errors() {
    let opts = DescriptorOptions::default();
    let err = linearize_descriptor(
        &Undetermined::default(),
        descriptor_point(&[0.0], &[0.0], &[0.0, 0.0], &[0.0]),
        &opts,
    )
    .unwrap_err();
    assert!(
        matches!(err, DescriptorError::SingularPencil { n: 3, .. }),
        "{err:?}"
    );
    let err = linearize_descriptor(
        &IndexFour::default(),
        descriptor_point(&[0.0; 3], &[0.0; 3], &[0.0], &[0.0]),
        &opts,
    )
    .unwrap_err();
    assert_eq!(err, DescriptorError::IndexTooHigh { index: 4, max: 3 });
    // The same plant passes with a higher limit: all of it is constrained (no freedom left).
    let (_, real) = linearize_descriptor(
        &IndexFour::default(),
        descriptor_point(&[0.0; 3], &[0.0; 3], &[0.0], &[0.0]),
        &DescriptorOptions {
            max_index: 4,
            ..opts
        },
    )
    .unwrap();
    assert_eq!((real.index, real.dof), (4, 0));
    let err = linearize_descriptor(
        &Prescribed::default(),
        descriptor_point(&[0.0; 2], &[0.0; 2], &[0.0], &[0.0]),
        &opts,
    )
    .unwrap_err();
    assert!(
        matches!(err, DescriptorError::ImproperInput { .. }),
        "{err:?}"
    );
    // The pendulum on a cart with a limit of 2.
    let p = CartPendulumCartesianParams::default();
    let err = linearize_descriptor(
        &CartPendulumCartesian::default(),
        descriptor_point(
            &[0.0, 0.0, -p.l, 0.0, 0.0, 0.0],
            &[0.0; 6],
            &[p.m * p.g / p.l],
            &[0.0],
        ),
        &DescriptorOptions {
            max_index: 2,
            ..opts
        },
    )
    .unwrap_err();
    assert_eq!(err, DescriptorError::IndexTooHigh { index: 3, max: 2 });
    // Wrong lengths.
    let err = linearize_descriptor(
        &CartPendulumCartesian::default(),
        descriptor_point(&[0.0; 5], &[0.0; 6], &[0.0], &[0.0]),
        &opts,
    )
    .unwrap_err();
    assert!(matches!(
        err,
        DescriptorError::Dimension {
            what: "x",
            expected: 6,
            found: 5
        }
    ));
}

dpc::model! {
    /// A point held on a circle of imaginary radius: the constraint cannot be met.
    pub Unreachable {
        states { x, y, vx, vy }
        algebraic { lam }
        equations {
            der(x) = vx;
            der(y) = vy;
            der(vx) == -2.0 * lam * x;
            der(vy) == -2.0 * lam * y;
            0.0 == x.powi(2) + y.powi(2) + 1.0;
        }
        outputs { y }
    }
}

/// Minimal-coordinate accelerations `(s'', phi'')` of the cart pendulum.
fn cart_pendulum_accelerations(phi: f64, vs: f64, om: f64, f: f64) -> (f64, f64) {
    let p = CartPendulumCartesianParams::default();
    let mm = DMatrix::from_row_slice(2, 2, &[p.mc + p.m, p.m * p.l * phi.cos(), phi.cos(), p.l]);
    let rhs = DMatrix::from_row_slice(
        2,
        1,
        &[
            f - p.b * vs + p.m * p.l * phi.sin() * om * om,
            -p.g * phi.sin(),
        ],
    );
    let acc = mm.lu().solve(&rhs).unwrap();
    (acc[0], acc[1])
}

#[test]
fn cart_pendulum_consistent_state_from_given_positions() {
    let p = CartPendulumCartesianParams::default();
    let given = [0.1, 0.5, -0.6, 0.2, 1.0, 0.3];
    let f = 0.7;
    let cs = consistent_state(
        &CartPendulumCartesian::default(),
        0.0,
        &given,
        &[f],
        &ConsistentOptions::default(),
    )
    .unwrap();
    assert_eq!(cs.position_constraints, vec![6]);
    assert!(cs.velocity_constraints.is_empty());
    let [s, xb, yb, vs, vx, vy] = [0, 1, 2, 3, 4, 5].map(|i| cs.x[i]);
    let (dx, dy) = (xb - s, yb);
    assert!((dx * dx + dy * dy - p.l * p.l).abs() < 1e-12, "rod");
    assert!(
        ((vx - vs) * dx + vy * dy).abs() < 1e-12,
        "hidden velocity constraint"
    );
    // Moved: the given distance was 0.72, not 0.8.
    assert!(cs.max_move > 0.01 && cs.max_move < 0.2, "{:?}", cs.moved);
    let moved: Vec<f64> = cs.x.iter().zip(&given).map(|(a, b)| a - b).collect();
    assert_eq!(moved, cs.moved);
    // The velocity correction is minimum-norm: along G^T = (-(xb - s), xb - s, yb).
    let dv = [cs.moved[3], cs.moved[4], cs.moved[5]];
    let gt = [-dx, dx, dy];
    let along = (dv[0] * gt[0] + dv[1] * gt[1] + dv[2] * gt[2]) / (dx * dx * 2.0 + dy * dy);
    for k in 0..3 {
        assert!(
            (dv[k] - along * gt[k]).abs() < 1e-12,
            "{dv:?} not along {gt:?}"
        );
    }
    assert!(
        along.abs() > 1e-3,
        "the given velocities were not consistent"
    );
    // The minimal model at the same physical state.
    let phi = dx.atan2(-dy);
    let om = ((vx - vs) * phi.cos() + vy * phi.sin()) / p.l;
    let (sdd, phidd) = cart_pendulum_accelerations(phi, vs, om, f);
    let xbdd = sdd + p.l * (phi.cos() * phidd - phi.sin() * om * om);
    let ybdd = p.l * (phi.sin() * phidd + phi.cos() * om * om);
    let lambda = -(p.m * ybdd + p.m * p.g) / yb;
    let expected = [vs, vx, vy, sdd, xbdd, ybdd];
    for (k, (a, b)) in cs.xdot.iter().zip(expected).enumerate() {
        assert!(
            (a - b).abs() < 1e-9 * (1.0 + b.abs()),
            "x'[{k}] = {a} vs {b}"
        );
    }
    assert!(
        (cs.z[0] - lambda).abs() < 1e-9 * (1.0 + lambda.abs()),
        "{} vs {lambda}",
        cs.z[0]
    );
    assert!(cs.residual < 1e-12, "{}", cs.residual);
    // The rod is quadratic: the curvature difference is exact up to rounding.
    assert!(cs.curvature_error < 1e-8, "{}", cs.curvature_error);
    // A consistent state is left where it is.
    let again = consistent_state(
        &CartPendulumCartesian::default(),
        0.0,
        &cs.x,
        &[f],
        &ConsistentOptions::default(),
    )
    .unwrap();
    assert!(again.max_move < 1e-12, "{:?}", again.moved);
}

#[test]
fn slider_crank_consistent_state_matches_minimal_model() {
    let p = SliderCrankParams::default();
    let (th, om, tau) = (0.8, 2.5, 0.4);
    // Given: the crank angle and rate right, the slider off the rod's reach and at rest.
    let given = [th, 1.4, om, 0.0];
    let cs = consistent_state(
        &SliderCrank::default(),
        0.0,
        &given,
        &[tau],
        &ConsistentOptions::default(),
    )
    .unwrap();
    let [th1, xs, om1, vs] = [0, 1, 2, 3].map(|i| cs.x[i]);
    let g = (xs - p.r * th1.cos()).powi(2) + (p.r * th1.sin()).powi(2) - p.l * p.l;
    assert!(g.abs() < 1e-12, "rod: {g}");
    // Minimum-norm projection moves the crank too; compare at the projected (th1, om1).
    let q = (p.l * p.l - (p.r * th1.sin()).powi(2)).sqrt();
    assert!((xs - (p.r * th1.cos() + q)).abs() < 1e-12);
    let x1 = -p.r * th1.sin() - p.r * p.r * th1.sin() * th1.cos() / q;
    assert!((vs - x1 * om1).abs() < 1e-12, "hidden velocity constraint");
    // Crank acceleration from the minimal model's residual at the projected state.
    let min = SliderCrankJoint::default();
    let mut r0 = [0.0; 2];
    let mut r1 = [0.0; 2];
    use dpc::core::DaeModel;
    min.residual(0.0, &[th1, om1], &[om1, 0.0], &[], &[tau], &mut r0);
    min.residual(0.0, &[th1, om1], &[om1, 1.0], &[], &[tau], &mut r1);
    let thdd = -r0[1] / (r1[1] - r0[1]);
    assert!(
        (cs.xdot[2] - thdd).abs() < 1e-7 * (1.0 + thdd.abs()),
        "{} vs {thdd}",
        cs.xdot[2]
    );
    let lambda = (tau - p.bt * om1 - p.j * thdd) / (p.r * xs * th1.sin());
    assert!(
        (cs.z[0] - lambda).abs() < 1e-7 * (1.0 + lambda.abs()),
        "{} vs {lambda}",
        cs.z[0]
    );
    // The macro supplies the rod's curvature exactly: no difference, no error estimate
    // (tests/constraint_derivatives.rs compares it with the difference of a plant without it).
    assert!(cs.curvature_exact && cs.curvature_error == 0.0, "{cs:?}");
}

#[test]
fn unreachable_constraint_is_a_typed_error() {
    let err = consistent_state(
        &Unreachable::default(),
        0.0,
        &[0.3, 0.2, 0.0, 0.0],
        &[],
        &ConsistentOptions::default(),
    )
    .unwrap_err();
    match &err {
        ConsistentError::CannotMeet {
            stage, equation, ..
        } => {
            assert_eq!(*stage, "positions");
            assert!(equation.starts_with("equation 4"), "{equation}");
        }
        other => panic!("expected CannotMeet, got {other:?}"),
    }
    let err = consistent_state(
        &CartPendulumCartesian::default(),
        0.0,
        &[0.0; 5],
        &[0.0],
        &ConsistentOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err, ConsistentError::Dimension { what: "x", .. }));
    let err = consistent_state(
        &Prescribed::default(),
        0.0,
        &[0.0; 2],
        &[0.0],
        &ConsistentOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(err, ConsistentError::Unsupported { .. }),
        "{err:?}"
    );
}

#[test]
fn cart_pendulum_badly_scaled_matches_minimal_coordinates() {
    use dpc::core::DaeModel;
    // A heavy cart, a light bob on a long rod, in units that spread the Jacobian entries over
    // several orders of magnitude: the rank decisions must still find index 3 and 4 states.
    for (mc, m, l) in [(1000.0, 0.01, 20.0), (0.05, 40.0, 0.02)] {
        let g = 9.81;
        let b = 0.3;
        let cart =
            CartPendulumCartesian::from_params(CartPendulumCartesianParams { mc, m, l, g, b });
        let minimal =
            CartPendulumMinimal::from_params(CartPendulumMinimalParams { mc, m, l, g, b });
        let lambda = m * g / l;
        let (_, real) = linearize_descriptor(
            &cart,
            descriptor_point(&[0.0, 0.0, -l, 0.0, 0.0, 0.0], &[0.0; 6], &[lambda], &[0.0]),
            &DescriptorOptions::default(),
        )
        .unwrap();
        let min = linearize(
            &minimal,
            descriptor_point(&[0.0; 4], &[0.0; 4], &[], &[0.0]),
        )
        .unwrap();
        let what = format!("mc = {mc}, m = {m}, l = {l}");
        assert_eq!((real.index, real.dof), (3, 4), "{what}");
        assert_same_spectrum(
            &what,
            &eigenvalues(&real.system.a).unwrap(),
            &eigenvalues(&min.a).unwrap(),
            1e-8,
        );
        assert_same_transfer(&what, &real.system, &min);
    }
}

/// `design` takes the descriptor path for a plant that is not of index 1 at the nominal, and
/// reports the pencil's failures as typed errors at the nominal's time.
#[test]
fn design_of_descriptor_plants_reports_pencil_errors() {
    use dpc::core::design::{design, DesignError, DesignOptions};
    use dpc::core::prefeedback::SteadyMotion;
    let opts = DesignOptions {
        horizon: 1.0,
        ..DesignOptions::default()
    };
    let rest = |nx: usize, nz: usize| SteadyMotion {
        state: vec![0.0; nx],
        rate: vec![0.0; nx],
        algebraic: vec![0.0; nz],
        input: vec![0.0],
    };
    let err = design(&IndexFour::default(), &rest(3, 1), &opts).unwrap_err();
    assert!(
        matches!(
            err,
            DesignError::Descriptor {
                source: DescriptorError::IndexTooHigh { index: 4, max: 3 },
                ..
            }
        ),
        "{err:?}"
    );
    let err = design(&Undetermined::default(), &rest(1, 2), &opts).unwrap_err();
    assert!(
        matches!(
            err,
            DesignError::Descriptor {
                source: DescriptorError::SingularPencil { .. },
                ..
            }
        ),
        "{err:?}"
    );
    // A nominal off the rod: the descriptor linearisation names the constraint.
    let p = CartPendulumCartesianParams::default();
    let off = SteadyMotion {
        state: vec![0.0, 0.0, -1.1 * p.l, 0.0, 0.0, 0.0],
        rate: vec![0.0; 6],
        algebraic: vec![p.m * p.g / (1.1 * p.l)],
        input: vec![0.0],
    };
    let err = design(&CartPendulumCartesian::default(), &off, &opts).unwrap_err();
    assert!(
        matches!(
            &err,
            DesignError::Descriptor {
                source: DescriptorError::Inconsistent { .. },
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("l.powi(2)"), "{err}");
}
