//! Shared checks for generated models: analytic Jacobians against central differences.

#![allow(dead_code)]

pub mod model_text;

use dpc::core::model::{DaeModel, Structure};
use dpc::nalgebra::DMatrix;

/// A point `(t, x, x', z, u)` of model `M`, stored flat in that order.
struct Point<'a> {
    t: f64,
    x: &'a [f64],
    xdot: &'a [f64],
    z: &'a [f64],
    u: &'a [f64],
}

/// Start of each block (`x'`, `x`, `z`, `u`) in the flat vector, and its length.
fn blocks(s: &Structure) -> [(usize, usize); 4] {
    let (nx, nz, nu) = (s.n_states(), s.n_algebraic(), s.n_inputs());
    [
        (1 + nx, nx),
        (1, nx),
        (1 + 2 * nx, nz),
        (1 + 2 * nx + nz, nu),
    ]
}

fn point<'a>(s: &Structure, v: &'a [f64]) -> Point<'a> {
    let [(xd, nx), (x, _), (z, nz), (u, nu)] = blocks(s);
    Point {
        t: v[0],
        x: &v[x..x + nx],
        xdot: &v[xd..xd + nx],
        z: &v[z..z + nz],
        u: &v[u..u + nu],
    }
}

pub fn dims<M: DaeModel + Default>() -> usize {
    let model = M::default();
    let s = model.structure();
    1 + 2 * s.n_states() + s.n_algebraic() + s.n_inputs()
}

/// Central difference of the residual with respect to block `which` of the flat point.
fn central_block<M: DaeModel>(model: &M, v: &[f64], which: usize) -> DMatrix<f64> {
    let s = model.structure();
    let ne = s.n_equations();
    let (start, n) = blocks(s)[which];
    let mut jac = DMatrix::zeros(ne, n);
    let (mut plus, mut minus) = (vec![0.0; ne], vec![0.0; ne]);
    let mut w = v.to_vec();
    for j in 0..n {
        let h = 1e-5 * (1.0 + v[start + j].abs());
        w[start + j] = v[start + j] + h;
        let p = point(s, &w);
        model.residual(p.t, p.x, p.xdot, p.z, p.u, &mut plus);
        w[start + j] = v[start + j] - h;
        let p = point(s, &w);
        model.residual(p.t, p.x, p.xdot, p.z, p.u, &mut minus);
        w[start + j] = v[start + j];
        for i in 0..ne {
            jac[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    jac
}

/// Entry-wise agreement relative to the scale of each row of the whole Jacobian
/// (`row_scale[i] = 1 + max_j |dF_i/d(x', x, z, u)_j|`): a difference quotient of row `i`
/// cannot resolve entries much below that row's largest sensitivity.
fn assert_close(name: &str, analytic: &DMatrix<f64>, fd: &DMatrix<f64>, row_scale: &[f64]) {
    for i in 0..analytic.nrows() {
        for j in 0..analytic.ncols() {
            let err = (analytic[(i, j)] - fd[(i, j)]).abs() / row_scale[i];
            assert!(
                err < 1e-6,
                "{name}[{i},{j}]: relative error {err:e}\nanalytic = {analytic}\nfinite differences = {fd}"
            );
        }
    }
}

pub fn check_model<M: DaeModel + Default>(v: &[f64]) {
    let model = M::default();
    let s = model.structure();
    let p = point(s, v);
    let (ne, nx, nz, nu) = (s.n_equations(), s.n_states(), s.n_algebraic(), s.n_inputs());
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

    let row_scale: Vec<f64> = (0..ne)
        .map(|i| {
            [&f_xdot, &f_x, &f_z, &f_u]
                .iter()
                .map(|b| if b.ncols() == 0 { 0.0 } else { b.row(i).amax() })
                .fold(1.0_f64, |acc, v| acc.max(1.0 + v))
        })
        .collect();
    let blocks = [
        ("dF/dx'", &f_xdot),
        ("dF/dx", &f_x),
        ("dF/dz", &f_z),
        ("dF/du", &f_u),
    ];
    for (which, (name, analytic)) in blocks.into_iter().enumerate() {
        assert_close(name, analytic, &central_block(&model, v, which), &row_scale);
    }

    // Structural patterns cover every non-zero entry.
    let patterns = [
        &s.pattern_f_xdot,
        &s.pattern_f_x,
        &s.pattern_f_z,
        &s.pattern_f_u,
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
    let ny = s.n_outputs();
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
    let out_scale: Vec<f64> = (0..ny).map(|i| 1.0 + h_x.row(i).amax()).collect();
    assert_close("dh/dx", &h_x, &fd, &out_scale);
}
