//! The analytic Jacobians generated for the plants in `dpc-models` agree with central
//! differences of the generated residual at random points (relative error < 1e-6), and the
//! generated routines agree with each other (iteration matrix, fixed-size conveniences).

use dpc::core::model::DaeModel;
use dpc::nalgebra::DMatrix;
use dpc_models::{Pendulum, Wheel, WheelLinear};
use proptest::prelude::*;

/// A point `(t, x, x', z, u)` of model `M`, stored flat in that order.
struct Point<'a> {
    t: f64,
    x: &'a [f64],
    xdot: &'a [f64],
    z: &'a [f64],
    u: &'a [f64],
}

/// Start of each block (`x'`, `x`, `z`, `u`) in the flat vector, and its length.
fn blocks<M: DaeModel>() -> [(usize, usize); 4] {
    let (nx, nz, nu) = (M::N_STATES, M::N_ALGEBRAIC, M::N_INPUTS);
    [
        (1 + nx, nx),
        (1, nx),
        (1 + 2 * nx, nz),
        (1 + 2 * nx + nz, nu),
    ]
}

fn point<M: DaeModel>(v: &[f64]) -> Point<'_> {
    let [(xd, nx), (x, _), (z, nz), (u, nu)] = blocks::<M>();
    Point {
        t: v[0],
        x: &v[x..x + nx],
        xdot: &v[xd..xd + nx],
        z: &v[z..z + nz],
        u: &v[u..u + nu],
    }
}

fn dims<M: DaeModel>() -> usize {
    1 + 2 * M::N_STATES + M::N_ALGEBRAIC + M::N_INPUTS
}

/// Central difference of the residual with respect to block `which` of the flat point.
fn central_block<M: DaeModel>(model: &M, v: &[f64], which: usize) -> DMatrix<f64> {
    let (start, n) = blocks::<M>()[which];
    let mut jac = DMatrix::zeros(M::N_EQUATIONS, n);
    let (mut plus, mut minus) = (vec![0.0; M::N_EQUATIONS], vec![0.0; M::N_EQUATIONS]);
    let mut w = v.to_vec();
    for j in 0..n {
        let h = 1e-5 * (1.0 + v[start + j].abs());
        w[start + j] = v[start + j] + h;
        let p = point::<M>(&w);
        model.residual(p.t, p.x, p.xdot, p.z, p.u, &mut plus);
        w[start + j] = v[start + j] - h;
        let p = point::<M>(&w);
        model.residual(p.t, p.x, p.xdot, p.z, p.u, &mut minus);
        w[start + j] = v[start + j];
        for i in 0..M::N_EQUATIONS {
            jac[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    jac
}

fn assert_close(name: &str, analytic: &DMatrix<f64>, fd: &DMatrix<f64>) {
    let scale = 1.0 + fd.amax();
    let err = (analytic - fd).amax() / scale;
    assert!(
        err < 1e-6,
        "{name}: relative error {err:e}\nanalytic = {analytic}\nfinite differences = {fd}"
    );
}

fn check_model<M: DaeModel + Default>(v: &[f64]) {
    let model = M::default();
    let p = point::<M>(v);
    let (ne, nx, nz, nu) = (M::N_EQUATIONS, M::N_STATES, M::N_ALGEBRAIC, M::N_INPUTS);
    let mut r = vec![0.0; ne];
    let mut f_xdot = DMatrix::zeros(ne, nx);
    let mut f_x = DMatrix::zeros(ne, nx);
    let mut f_z = DMatrix::zeros(ne, nz);
    let mut f_u = DMatrix::zeros(ne, nu);
    model.evaluate(
        p.t,
        p.x,
        p.xdot,
        p.z,
        p.u,
        &mut r,
        &mut f_xdot,
        &mut f_x,
        &mut f_z,
        &mut f_u,
    );
    let mut r_alone = vec![0.0; ne];
    model.residual(p.t, p.x, p.xdot, p.z, p.u, &mut r_alone);
    assert_eq!(r, r_alone, "evaluate and residual agree");

    let blocks = [
        ("dF/dx'", &f_xdot),
        ("dF/dx", &f_x),
        ("dF/dz", &f_z),
        ("dF/du", &f_u),
    ];
    for (which, (name, analytic)) in blocks.into_iter().enumerate() {
        assert_close(name, analytic, &central_block(&model, v, which));
    }

    // Structural patterns cover every non-zero entry.
    let patterns = [
        M::PATTERN_F_XDOT,
        M::PATTERN_F_X,
        M::PATTERN_F_Z,
        M::PATTERN_F_U,
    ];
    for ((name, m), pat) in blocks.iter().zip(patterns) {
        for i in 0..m.nrows() {
            for j in 0..m.ncols() {
                if m[(i, j)] != 0.0 {
                    assert!(
                        pat.contains(&(i, j)),
                        "{name}[{i},{j}] non-zero outside the pattern"
                    );
                }
            }
        }
    }

    // The iteration matrix is [dF/dx + c dF/dx' | dF/dz].
    let c = 0.37;
    let mut g = DMatrix::zeros(ne, ne);
    model.iteration_matrix(p.t, p.x, p.xdot, p.z, p.u, c, &mut g);
    let mut expected = DMatrix::zeros(ne, ne);
    expected.columns_mut(0, nx).copy_from(&(&f_x + &f_xdot * c));
    expected.columns_mut(nx, nz).copy_from(&f_z);
    assert!((g - expected).amax() <= 1e-12 * (1.0 + f_x.amax() + f_xdot.amax()));

    // Output Jacobian against central differences in x.
    let ny = M::N_OUTPUTS;
    let mut h_x = DMatrix::zeros(ny, nx);
    let mut h_z = DMatrix::zeros(ny, nz);
    let mut h_u = DMatrix::zeros(ny, nu);
    model.output_jacobians(p.t, p.x, p.z, p.u, &mut h_x, &mut h_z, &mut h_u);
    let mut fd = DMatrix::zeros(ny, nx);
    let (mut yp, mut ym) = (vec![0.0; ny], vec![0.0; ny]);
    for j in 0..nx {
        let h = 1e-5 * (1.0 + p.x[j].abs());
        let mut x = p.x.to_vec();
        x[j] += h;
        model.outputs(p.t, &x, p.z, p.u, &mut yp);
        x[j] -= 2.0 * h;
        model.outputs(p.t, &x, p.z, p.u, &mut ym);
        for i in 0..ny {
            fd[(i, j)] = (yp[i] - ym[i]) / (2.0 * h);
        }
    }
    assert_close("dh/dx", &h_x, &fd);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn wheel_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<Wheel>())) {
        check_model::<Wheel>(&v);
    }

    #[test]
    fn wheel_linear_jacobians_match_central_differences(v in prop::collection::vec(-3.0..3.0f64, dims::<WheelLinear>())) {
        check_model::<WheelLinear>(&v);
    }

    #[test]
    fn pendulum_jacobians_match_central_differences(v in prop::collection::vec(0.2..3.0f64, dims::<Pendulum>())) {
        check_model::<Pendulum>(&v);
    }
}

#[test]
fn wheel_linearisation_reproduces_the_paper() {
    // About x0 = [pi/2, -6t, 0, 0, -6] with u = 0: A of (4.1), B with the Appendix gains.
    let wheel = Wheel::default();
    let x = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];
    let j = wheel.jacobians_fixed(
        0.0,
        &x.into(),
        &Default::default(),
        &Default::default(),
        &Default::default(),
    );
    // x' = -(dF/dx')^-1 dF/dx x - (dF/dx')^-1 dF/du u.
    let m = j.f_xdot.lu();
    let a = m.solve(&(-j.f_x)).unwrap();
    let b = m.solve(&(-j.f_u)).unwrap();
    let a_paper = dpc::nalgebra::SMatrix::<f64, 5, 5>::from_row_slice(&[
        0.0, 0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, 1.0, //
        0.0, 0.0, 0.0, -3.0, 0.0, //
        6.54, 0.0, 5.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    assert!((a - a_paper).amax() < 1e-12, "A = {a}");
    let b_appendix = dpc::nalgebra::SMatrix::<f64, 5, 2>::from_row_slice(&[
        0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.8,
    ]);
    assert!((b - b_appendix).amax() < 1e-12, "B = {b}");
}
