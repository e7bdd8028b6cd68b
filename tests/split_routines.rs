//! Routines long enough for the macro to split them into parts (`dpc-codegen/src/emit/routine.rs`,
//! above 2 000 operations) compute what the run-time evaluator of the same text computes: the
//! model below couples every state with every other through `sin` and `cos`, so its Jacobian
//! routines have several thousand operations, more than any model of `models/src`, whose
//! routines stay in one piece. Residual, iteration matrix (alone and with the residual) and
//! all Jacobian blocks of the plant and of its tracking DAE agree to 1e-14 relative to the
//! size of each block.

mod common;

use common::model_text::invocations;
use dpc::core::model::DaeModel;
use dpc::nalgebra::DMatrix;
use std::path::Path;

dpc::model! {
    /// Fourteen states coupled pairwise.
    pub Coupled {
        consts { N = 14 }
        params { k[N] = 1.5, g = 0.3 }
        states { x[N], v[N] }
        inputs { u[N] }
        let s[i in 0..N] = sum(0..N, |j| k[j] * sin(x[j] - x[i]) * cos(v[j] + g * x[i]));
        equations {
            for i in 0..N {
                der(x[i]) = v[i];
                der(v[i]) = s[i] - g * v[i] + u[i];
            }
        }
        outputs { x }
        tracking CoupledTracking { x: [2.0, 3.0] }
    }
}

/// Every value the routines write at one point, block by block.
fn values<M: DaeModel>(model: &M, c: f64) -> Vec<Vec<f64>> {
    let s = model.structure();
    let (nx, nz, nu, ne) = (s.n_states(), s.n_algebraic(), s.n_inputs(), s.n_equations());
    let x: Vec<f64> = (0..nx).map(|k| 0.3 * (k as f64).sin() + 0.1).collect();
    let xdot: Vec<f64> = (0..nx).map(|k| 0.2 * (k as f64).cos()).collect();
    let z: Vec<f64> = (0..nz).map(|k| 0.05 * k as f64).collect();
    let u: Vec<f64> = (0..nu).map(|k| 0.4 - 0.03 * k as f64).collect();
    let t = 0.7;
    let mut residual = vec![0.0; ne];
    model.residual(t, &x, &xdot, &z, &u, &mut residual);
    let mut iteration = DMatrix::zeros(ne, ne);
    model.iteration_matrix(t, &x, &xdot, &z, &u, c, &mut iteration);
    let mut fused_residual = vec![0.0; ne];
    let mut fused = DMatrix::zeros(ne, ne);
    model.residual_and_iteration_matrix(t, &x, &xdot, &z, &u, c, &mut fused_residual, &mut fused);
    let mut evaluated_residual = vec![0.0; ne];
    let (mut f_xdot, mut f_x) = (DMatrix::zeros(ne, nx), DMatrix::zeros(ne, nx));
    let (mut f_z, mut f_u) = (DMatrix::zeros(ne, nz), DMatrix::zeros(ne, nu));
    model.evaluate(
        t,
        &x,
        &xdot,
        &z,
        &u,
        &mut evaluated_residual,
        &mut f_xdot,
        &mut f_x,
        &mut f_z,
        &mut f_u,
    );
    vec![
        residual,
        iteration.as_slice().to_vec(),
        fused_residual,
        fused.as_slice().to_vec(),
        evaluated_residual,
        f_xdot.as_slice().to_vec(),
        f_x.as_slice().to_vec(),
        f_z.as_slice().to_vec(),
        f_u.as_slice().to_vec(),
    ]
}

fn agree(what: &str, compiled: &[Vec<f64>], runtime: &[Vec<f64>]) {
    assert_eq!(compiled.len(), runtime.len());
    for (b, (a, r)) in compiled.iter().zip(runtime).enumerate() {
        assert_eq!(a.len(), r.len(), "{what}, block {b}");
        let scale = a
            .iter()
            .chain(r)
            .fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()));
        for (k, (x, y)) in a.iter().zip(r).enumerate() {
            assert!(
                (x - y).abs() <= 1e-14 * scale,
                "{what}, block {b}, entry {k}: compiled {x:e}, runtime {y:e}"
            );
        }
    }
}

#[test]
fn split_routines_agree_with_the_runtime_evaluator() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/split_routines.rs");
    let source = std::fs::read_to_string(path).expect("this file");
    let text = &invocations(&source)[0].body;
    let runtime = dpc::runtime::parse("split_routines.rs", text).expect("the model reads");
    for c in [0.0, 1.0, 37.5] {
        agree(
            "plant",
            &values(&Coupled::default(), c),
            &values(&runtime.plant(), c),
        );
        agree(
            "tracking DAE",
            &values(&CoupledTracking::default(), c),
            &values(&runtime.tracking().expect("tracking"), c),
        );
    }
}
