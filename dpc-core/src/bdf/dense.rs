//! Dense output: the interpolating polynomial of the last step.
//!
//! In the modified-divided-difference form the polynomial through the last `k + 1` solution
//! values is `y(t) = sum_j c_j(t) phi_j`, with `c_j` products of `(t - t_n + psi_{i-1}) / psi_i`
//! (Brenan, Campbell & Petzold 1989, eq. 5.2.9; IDA's `IDAGetSolution`).

use super::history::History;

/// Evaluate the interpolant of order `kused` (at least 1) at `t`, with `tn` the end of the step.
pub(crate) fn interpolate(
    phi: &History,
    psi: &[f64],
    kused: usize,
    tn: f64,
    t: f64,
    y: &mut [f64],
    mut yp: Option<&mut [f64]>,
) {
    let kord = kused.max(1);
    let delt = t - tn;
    let mut c = 1.0;
    let mut d = 0.0;
    let mut gam = delt / psi[0];
    y.copy_from_slice(phi.col(0));
    if let Some(yp) = yp.as_deref_mut() {
        yp.fill(0.0);
    }
    for j in 1..=kord {
        d = d * gam + c / psi[j - 1];
        c *= gam;
        gam = (delt + psi[j - 1]) / psi[j];
        for (yi, p) in y.iter_mut().zip(phi.col(j)) {
            *yi += c * p;
        }
        if let Some(yp) = yp.as_deref_mut() {
            for (ypi, p) in yp.iter_mut().zip(phi.col(j)) {
                *ypi += d * p;
            }
        }
    }
}
