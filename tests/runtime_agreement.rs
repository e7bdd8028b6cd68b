//! A plant file and the compiled model of the same text agree: every `model! { ... }` of
//! `models/src/*.rs` is cut out of its source at test time and read as a plant file, and at
//! random points and random parameters its residual, all Jacobian blocks, iteration matrix,
//! outputs and output Jacobians, its position constraints' exact derivatives, its tracking DAE
//! (also after changing `W`) and its references must equal those of the generated types to
//! 1e-14 relative to the size of each evaluated block.

mod common;

use common::model_text::{invocations, template_models};
use dpc::core::model::{DaeModel, Structure};
use dpc::core::{Reference, TrackingDae};
use dpc::nalgebra::{DMatrix, DVector};
use dpc::runtime::RuntimeModel;
use dpc_models::{
    Arm1, Arm1Reference, Arm1Tracking, Arm2, Arm2Reference, Arm2Tracking, Arm6, Arm6Reference,
    Arm6Tracking, CartPendulum, CartPendulumJoint, CartPendulumJointReference,
    CartPendulumJointTracking, CartPendulumReference, CartPendulumTracking, FlexibleJoint,
    FlexibleJointMass, FlexibleJointMass3, FlexibleJointMass3Reference, FlexibleJointMass3Tracking,
    FlexibleJointMass4, FlexibleJointMass4Reference, FlexibleJointMass4Tracking,
    FlexibleJointMassReference, FlexibleJointMassTracking, FlexibleJointReference,
    FlexibleJointTracking, Pendulum, SliderCrank, SliderCrankJoint, SliderCrankJointReference,
    SliderCrankJointTracking, SliderCrankReference, SliderCrankTracking, Wheel, WheelLinear,
    WheelLinearTracking, WheelReference, WheelTracking,
};
use proptest::prelude::*;
use std::path::Path;

const TOLERANCE: f64 = 1e-14;

/// Every model of `models/src`, as `(file, name, runtime model)`.
fn repository_models() -> &'static [(String, String, RuntimeModel)] {
    static MODELS: std::sync::OnceLock<Vec<(String, String, RuntimeModel)>> =
        std::sync::OnceLock::new();
    MODELS.get_or_init(read_repository_models)
}

fn read_repository_models() -> Vec<(String, String, RuntimeModel)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/src");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    files.sort();
    let mut out = Vec::new();
    let sources: Vec<(String, String)> = files
        .iter()
        .map(|file| {
            let name = file.file_name().unwrap().to_string_lossy().to_string();
            (name, std::fs::read_to_string(file).unwrap())
        })
        .collect();
    // A template (`macro_rules!` around a model, as the arm's declaration) is read through
    // its invocations, with their arguments.
    let templates: String = sources
        .iter()
        .filter(|(_, source)| source.contains("macro_rules!"))
        .map(|(_, source)| source.as_str())
        .collect();
    for (name, source) in sources.iter().filter(|(_, s)| !s.contains("macro_rules!")) {
        let bodies = invocations(source)
            .into_iter()
            .map(|m| m.body)
            .chain(template_models(source, &templates));
        for body in bodies {
            let model = dpc::runtime::parse(name, &body).unwrap_or_else(|e| {
                panic!("a model of {name} does not read as a plant file:\n{e}")
            });
            out.push((name.clone(), model.name().to_string(), model));
        }
    }
    out
}

/// `a` and `b` agree to [`TOLERANCE`] relative to the largest finite magnitude among them.
/// Random parameters can leave a model's domain (the slider-crank's joint form takes
/// `sqrt(l^2 - (r sin th)^2)`): an entry that both evaluate to NaN agrees, one that only one
/// of them does not.
fn agree(what: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    let scale = a
        .iter()
        .chain(b)
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let both_nan = x.is_nan() && y.is_nan();
        assert!(
            both_nan
                || (x.is_finite() == y.is_finite()
                    && (x == y || (x - y).abs() <= TOLERANCE * scale)),
            "{what}[{k}]: compiled {x:e}, runtime {y:e} (scale {scale:e})"
        );
    }
}

fn same_structure(a: &Structure, b: &Structure) {
    assert_eq!(a.name, b.name);
    for (what, x, y) in [
        ("states", &a.states, &b.states),
        ("algebraic", &a.algebraic, &b.algebraic),
        ("inputs", &a.inputs, &b.inputs),
        ("outputs", &a.outputs, &b.outputs),
        ("params", &a.params, &b.params),
        ("equations", &a.equations, &b.equations),
    ] {
        assert_eq!(x.to_vec(), y.to_vec(), "{} {what}", a.name);
    }
    assert_eq!(
        a.units.iter().collect::<Vec<_>>(),
        b.units.iter().collect::<Vec<_>>(),
        "{} units",
        a.name
    );
    assert_eq!(a.pattern_f_xdot, b.pattern_f_xdot, "{}", a.name);
    assert_eq!(a.pattern_f_x, b.pattern_f_x, "{}", a.name);
    assert_eq!(a.pattern_f_z, b.pattern_f_z, "{}", a.name);
    assert_eq!(a.pattern_f_u, b.pattern_f_u, "{}", a.name);
    assert_eq!(a.pattern_h_x, b.pattern_h_x, "{}", a.name);
}

/// A point `(t, x, x', z, u, c)` of a model with `s`'s dimensions, from `v`.
struct Point {
    t: f64,
    x: Vec<f64>,
    xdot: Vec<f64>,
    z: Vec<f64>,
    u: Vec<f64>,
    c: f64,
}

impl Point {
    fn new(s: &Structure, v: &[f64], c: f64) -> Self {
        let mut it = v.iter().copied().cycle();
        let mut take = |n: usize| (0..n).map(|_| it.next().unwrap()).collect::<Vec<_>>();
        let t = take(1)[0] * 5.0;
        Point {
            t,
            x: take(s.n_states()),
            xdot: take(s.n_states()),
            z: take(s.n_algebraic()),
            u: take(s.n_inputs()),
            c,
        }
    }
}

/// Every routine of `a` (compiled) and `b` (runtime) at `p`.
fn same_values<A: DaeModel, B: DaeModel>(a: &A, b: &B, p: &Point) {
    let s = a.structure();
    let name = s.name.to_string();
    let (ne, nx, nz, nu, ny) = (
        s.n_equations(),
        s.n_states(),
        s.n_algebraic(),
        s.n_inputs(),
        s.n_outputs(),
    );
    let mut ra = vec![0.0; ne];
    let mut rb = vec![0.0; ne];
    a.residual(p.t, &p.x, &p.xdot, &p.z, &p.u, &mut ra);
    b.residual(p.t, &p.x, &p.xdot, &p.z, &p.u, &mut rb);
    agree(&format!("{name} residual"), &ra, &rb);

    let blocks = || {
        (
            DVector::<f64>::zeros(ne),
            DMatrix::<f64>::zeros(ne, nx),
            DMatrix::<f64>::zeros(ne, nx),
            DMatrix::<f64>::zeros(ne, nz),
            DMatrix::<f64>::zeros(ne, nu),
        )
    };
    let (mut r1, mut a1, mut b1, mut c1, mut d1) = blocks();
    let (mut r2, mut a2, mut b2, mut c2, mut d2) = blocks();
    a.evaluate(
        p.t,
        &p.x,
        &p.xdot,
        &p.z,
        &p.u,
        r1.as_mut_slice(),
        &mut a1,
        &mut b1,
        &mut c1,
        &mut d1,
    );
    b.evaluate(
        p.t,
        &p.x,
        &p.xdot,
        &p.z,
        &p.u,
        r2.as_mut_slice(),
        &mut a2,
        &mut b2,
        &mut c2,
        &mut d2,
    );
    agree(
        &format!("{name} evaluate residual"),
        r1.as_slice(),
        r2.as_slice(),
    );
    agree(&format!("{name} dF/dx'"), a1.as_slice(), a2.as_slice());
    agree(&format!("{name} dF/dx"), b1.as_slice(), b2.as_slice());
    agree(&format!("{name} dF/dz"), c1.as_slice(), c2.as_slice());
    agree(&format!("{name} dF/du"), d1.as_slice(), d2.as_slice());
    agree(&format!("{name} residual vs evaluate"), &rb, r2.as_slice());

    let mut m1 = DMatrix::<f64>::zeros(ne, ne);
    let mut m2 = DMatrix::<f64>::zeros(ne, ne);
    a.iteration_matrix(p.t, &p.x, &p.xdot, &p.z, &p.u, p.c, &mut m1);
    b.iteration_matrix(p.t, &p.x, &p.xdot, &p.z, &p.u, p.c, &mut m2);
    agree(
        &format!("{name} iteration matrix"),
        m1.as_slice(),
        m2.as_slice(),
    );

    // The mass matrix alone: the same in both, and `dF/dx'` as `evaluate` writes it.
    let mut k1 = DMatrix::<f64>::zeros(ne, nx);
    let mut k2 = DMatrix::<f64>::zeros(ne, nx);
    assert!(a.mass_matrix(p.t, &p.x, &p.xdot, &p.z, &p.u, &mut k1));
    assert!(b.mass_matrix(p.t, &p.x, &p.xdot, &p.z, &p.u, &mut k2));
    agree(&format!("{name} mass matrix"), k1.as_slice(), k2.as_slice());
    agree(
        &format!("{name} mass matrix against evaluate's dF/dx'"),
        k1.as_slice(),
        a1.as_slice(),
    );

    let mut y1 = vec![0.0; ny];
    let mut y2 = vec![0.0; ny];
    a.outputs(p.t, &p.x, &p.z, &p.u, &mut y1);
    b.outputs(p.t, &p.x, &p.z, &p.u, &mut y2);
    agree(&format!("{name} outputs"), &y1, &y2);

    let hs = || {
        (
            DMatrix::<f64>::zeros(ny, nx),
            DMatrix::<f64>::zeros(ny, nz),
            DMatrix::<f64>::zeros(ny, nu),
        )
    };
    let (mut hx1, mut hz1, mut hu1) = hs();
    let (mut hx2, mut hz2, mut hu2) = hs();
    a.output_jacobians(p.t, &p.x, &p.z, &p.u, &mut hx1, &mut hz1, &mut hu1);
    b.output_jacobians(p.t, &p.x, &p.z, &p.u, &mut hx2, &mut hz2, &mut hu2);
    agree(&format!("{name} dh/dx"), hx1.as_slice(), hx2.as_slice());
    agree(&format!("{name} dh/dz"), hz1.as_slice(), hz2.as_slice());
    agree(&format!("{name} dh/du"), hu1.as_slice(), hu2.as_slice());

    // The position constraints' exact derivatives: supplied by both or by neither, equal
    // (the velocities of the curvature are the point's x').
    let mut g1 = DMatrix::<f64>::zeros(ne, nx + nz);
    let mut g2 = DMatrix::<f64>::zeros(ne, nx + nz);
    let supplied = a.constraint_gradient(p.t, &p.x, &p.z, &p.u, &mut g1);
    assert_eq!(
        supplied,
        b.constraint_gradient(p.t, &p.x, &p.z, &p.u, &mut g2),
        "{name} constraint gradient supplied"
    );
    agree(
        &format!("{name} constraint gradient"),
        g1.as_slice(),
        g2.as_slice(),
    );
    let mut t1 = vec![0.0; ne];
    let mut t2 = vec![0.0; ne];
    assert_eq!(
        a.constraint_time_derivative(p.t, &p.x, &p.z, &p.u, &mut t1),
        b.constraint_time_derivative(p.t, &p.x, &p.z, &p.u, &mut t2),
        "{name} constraint time derivative supplied"
    );
    agree(&format!("{name} constraint time derivative"), &t1, &t2);
    let mut k1 = DMatrix::<f64>::zeros(ne, nx + nz);
    let mut k2 = DMatrix::<f64>::zeros(ne, nx + nz);
    assert_eq!(
        a.constraint_curvature(p.t, &p.x, &p.z, &p.u, &p.xdot, &mut k1),
        b.constraint_curvature(p.t, &p.x, &p.z, &p.u, &p.xdot, &mut k2),
        "{name} constraint curvature supplied"
    );
    agree(
        &format!("{name} constraint curvature"),
        k1.as_slice(),
        k2.as_slice(),
    );
    // The plants with position constraints supply them (their tracking DAEs do not).
    if ["CartPendulum", "SliderCrank", "Pendulum"].contains(&name.as_str()) {
        assert!(supplied, "{name} supplies its constraint derivatives");
    }
}

/// Parameters `i` of both set to `values[i]` (values near the defaults, so that the models
/// stay in their domain).
fn with_params<A: DaeModel, B: DaeModel>(a: &A, b: &B, scales: &[f64]) -> (A, B) {
    let mut pa = a.params().clone();
    let mut pb = b.params().clone();
    for i in 0..a.structure().n_params() {
        let v = A::parameter(&pa, i).unwrap() * scales[i % scales.len()];
        assert!(A::set_parameter(&mut pa, i, v));
        assert!(B::set_parameter(&mut pb, i, v));
    }
    (A::from_params(pa), B::from_params(pb))
}

fn check_plant<P: DaeModel + Default>(model: &RuntimeModel, v: &[f64], c: f64, scales: &[f64]) {
    let compiled = P::default();
    let runtime = model.plant();
    same_structure(compiled.structure(), runtime.structure());
    let (compiled, runtime) = with_params(&compiled, &runtime, scales);
    same_values(&compiled, &runtime, &Point::new(compiled.structure(), v, c));
}

fn check_tracking<T: TrackingDae + Default>(
    model: &RuntimeModel,
    v: &[f64],
    c: f64,
    scales: &[f64],
) {
    let compiled = T::default();
    let runtime = model.tracking().expect("the file has a tracking section");
    same_structure(compiled.structure(), runtime.structure());
    assert_eq!(compiled.relative_degrees(), runtime.relative_degrees());
    assert_eq!(compiled.plant_algebraic(), runtime.plant_algebraic());
    let (mut compiled, mut runtime) = with_params(&compiled, &runtime, scales);
    let m = compiled.structure().n_outputs();
    for i in 0..=m {
        assert_eq!(
            compiled.default_w_coefficients(i),
            runtime.default_w_coefficients(i)
        );
        assert_eq!(compiled.w_coefficients(i), runtime.w_coefficients(i));
    }
    let point = Point::new(compiled.structure(), v, c);
    same_values(&compiled, &runtime, &point);
    // Other roots of W, read from the values by both.
    for i in 0..m {
        let degree = compiled.default_w_coefficients(i).len() - 1;
        let roots: Vec<f64> = (0..degree)
            .map(|k| 0.5 + v[k % v.len()].abs() * 4.0)
            .collect();
        compiled.set_w_roots(i, &roots).unwrap();
        runtime.set_w_roots(i, &roots).unwrap();
        assert_eq!(compiled.w_coefficients(i), runtime.w_coefficients(i));
    }
    same_values(&compiled, &runtime, &point);
}

fn check_reference<R: Reference + Default>(model: &RuntimeModel, t: f64) {
    let compiled = R::default();
    let runtime = model
        .reference()
        .expect("the file has a references section");
    assert_eq!(compiled.dimension(), runtime.dimension());
    assert_eq!(compiled.max_order(), runtime.max_order());
    let n = (compiled.max_order() + 1) * compiled.dimension();
    let mut a = vec![0.0; n];
    let mut b = vec![0.0; n];
    compiled
        .derivatives(t, compiled.max_order(), &mut a)
        .unwrap();
    runtime.derivatives(t, runtime.max_order(), &mut b).unwrap();
    agree("references", &a, &b);
}

/// The compiled counterpart of every model; a model added to `models/src` without a case
/// here fails the test.
fn check(name: &str, model: &RuntimeModel, v: &[f64], c: f64, scales: &[f64]) {
    match name {
        "Wheel" => {
            check_plant::<Wheel>(model, v, c, scales);
            check_tracking::<WheelTracking>(model, v, c, scales);
            check_reference::<WheelReference>(model, v[0] * 10.0);
        }
        "WheelLinear" => {
            check_plant::<WheelLinear>(model, v, c, scales);
            check_tracking::<WheelLinearTracking>(model, v, c, scales);
            assert!(model.reference().is_none());
        }
        "Pendulum" => {
            check_plant::<Pendulum>(model, v, c, scales);
            assert!(model.tracking().is_none() && model.reference().is_none());
        }
        "FlexibleJoint" => {
            check_plant::<FlexibleJoint>(model, v, c, scales);
            check_tracking::<FlexibleJointTracking>(model, v, c, scales);
            check_reference::<FlexibleJointReference>(model, v[0] * 10.0);
        }
        "FlexibleJointMass" => {
            check_plant::<FlexibleJointMass>(model, v, c, scales);
            check_tracking::<FlexibleJointMassTracking>(model, v, c, scales);
            check_reference::<FlexibleJointMassReference>(model, v[0] * 10.0);
        }
        "FlexibleJointMass3" => {
            check_plant::<FlexibleJointMass3>(model, v, c, scales);
            check_tracking::<FlexibleJointMass3Tracking>(model, v, c, scales);
            check_reference::<FlexibleJointMass3Reference>(model, v[0] * 10.0);
        }
        "FlexibleJointMass4" => {
            check_plant::<FlexibleJointMass4>(model, v, c, scales);
            check_tracking::<FlexibleJointMass4Tracking>(model, v, c, scales);
            check_reference::<FlexibleJointMass4Reference>(model, v[0] * 10.0);
        }
        "CartPendulum" => {
            check_plant::<CartPendulum>(model, v, c, scales);
            check_tracking::<CartPendulumTracking>(model, v, c, scales);
            check_reference::<CartPendulumReference>(model, v[0] * 10.0);
        }
        "CartPendulumJoint" => {
            check_plant::<CartPendulumJoint>(model, v, c, scales);
            check_tracking::<CartPendulumJointTracking>(model, v, c, scales);
            check_reference::<CartPendulumJointReference>(model, v[0] * 10.0);
        }
        "SliderCrank" => {
            check_plant::<SliderCrank>(model, v, c, scales);
            check_tracking::<SliderCrankTracking>(model, v, c, scales);
            check_reference::<SliderCrankReference>(model, v[0] * 10.0);
        }
        "SliderCrankJoint" => {
            check_plant::<SliderCrankJoint>(model, v, c, scales);
            check_tracking::<SliderCrankJointTracking>(model, v, c, scales);
            check_reference::<SliderCrankJointReference>(model, v[0] * 10.0);
        }
        "Arm1" => {
            check_plant::<Arm1>(model, v, c, scales);
            check_tracking::<Arm1Tracking>(model, v, c, scales);
            check_reference::<Arm1Reference>(model, v[0] * 10.0);
        }
        "Arm2" => {
            check_plant::<Arm2>(model, v, c, scales);
            check_tracking::<Arm2Tracking>(model, v, c, scales);
            check_reference::<Arm2Reference>(model, v[0] * 10.0);
        }
        "Arm6" => {
            check_plant::<Arm6>(model, v, c, scales);
            check_tracking::<Arm6Tracking>(model, v, c, scales);
            check_reference::<Arm6Reference>(model, v[0] * 10.0);
        }
        other => panic!("model `{other}` of models/src has no compiled counterpart in this test"),
    }
}

#[test]
fn every_repository_model_is_covered() {
    let names: Vec<&str> = repository_models().iter().map(|m| m.1.as_str()).collect();
    assert_eq!(names.len(), 14, "{names:?}");
    // The listings are the generated ones.
    for (_, name, model) in repository_models() {
        let want = match name.as_str() {
            "Wheel" => WheelTracking::LISTING,
            "WheelLinear" => WheelLinearTracking::LISTING,
            "Pendulum" => Pendulum::LISTING,
            "FlexibleJoint" => FlexibleJointTracking::LISTING,
            "FlexibleJointMass" => FlexibleJointMassTracking::LISTING,
            "FlexibleJointMass3" => FlexibleJointMass3Tracking::LISTING,
            "FlexibleJointMass4" => FlexibleJointMass4Tracking::LISTING,
            "CartPendulum" => CartPendulumTracking::LISTING,
            "CartPendulumJoint" => CartPendulumJointTracking::LISTING,
            "SliderCrank" => SliderCrankTracking::LISTING,
            "SliderCrankJoint" => SliderCrankJointTracking::LISTING,
            "Arm1" => Arm1Tracking::LISTING,
            "Arm2" => Arm2Tracking::LISTING,
            "Arm6" => Arm6Tracking::LISTING,
            other => panic!("{other}"),
        };
        assert_eq!(model.listing(), want, "{name}");
        let degrees = match name.as_str() {
            "Wheel" => Wheel::RELATIVE_DEGREES,
            "WheelLinear" => WheelLinear::RELATIVE_DEGREES,
            "Pendulum" => Pendulum::RELATIVE_DEGREES,
            "FlexibleJoint" => FlexibleJoint::RELATIVE_DEGREES,
            "FlexibleJointMass" => FlexibleJointMass::RELATIVE_DEGREES,
            "FlexibleJointMass3" => FlexibleJointMass3::RELATIVE_DEGREES,
            "FlexibleJointMass4" => FlexibleJointMass4::RELATIVE_DEGREES,
            "CartPendulum" => CartPendulum::RELATIVE_DEGREES,
            "CartPendulumJoint" => CartPendulumJoint::RELATIVE_DEGREES,
            "SliderCrank" => SliderCrank::RELATIVE_DEGREES,
            "SliderCrankJoint" => SliderCrankJoint::RELATIVE_DEGREES,
            "Arm1" => Arm1::RELATIVE_DEGREES,
            "Arm2" => Arm2::RELATIVE_DEGREES,
            "Arm6" => Arm6::RELATIVE_DEGREES,
            other => panic!("{other}"),
        };
        assert_eq!(model.relative_degrees(), degrees, "{name}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn runtime_models_agree_with_compiled_ones(
        v in prop::collection::vec(-1.5f64..1.5, 48),
        c in 0.1f64..100.0,
        scales in prop::collection::vec(0.5f64..2.0, 8),
    ) {
        for (_, name, model) in repository_models() {
            check(name, model, &v, c, &scales);
        }
    }
}

/// The repository's plant file `scenarios/wheel.dpc` holds the compiled `Wheel`'s text (up to
/// layout and plain comments), so the closed-loop agreement of the two in
/// `dpc-cli/tests/plant_files.rs` compares the same model.
#[test]
fn the_wheel_plant_file_is_the_compiled_wheels_text() {
    use std::str::FromStr;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = std::fs::read_to_string(root.join("scenarios/wheel.dpc")).unwrap();
    let source = std::fs::read_to_string(root.join("models/src/wheel.rs")).unwrap();
    let wheel = invocations(&source)
        .into_iter()
        .find(|m| m.body.contains("pub Wheel {"))
        .expect("Wheel in models/src/wheel.rs");
    let tokens = |text: &str| {
        proc_macro2::TokenStream::from_str(text)
            .unwrap()
            .to_string()
    };
    assert_eq!(tokens(&file), tokens(&wheel.body));
}
