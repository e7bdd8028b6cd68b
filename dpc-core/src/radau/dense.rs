//! Dense output: the collocation polynomial of the last step.
//!
//! The Radau IIA solution on `[t_n, t_n + h]` is the cubic `u(t_n + θ h)` with `u(t_n) = y_n`
//! and `u(t_n + c_i h) = y_n + Z_i` (Hairer & Wanner, Section IV.8, "dense output"). It is
//! evaluated here in Lagrange form on the nodes `(0, c_1, c_2, c_3)`; the same polynomial,
//! extrapolated to the next step's nodes, is the starting guess of the next Newton iteration.

/// Lagrange weights `l_i(θ)` and their derivatives `l_i'(θ)` (with respect to `θ`) of the
/// nodes `c_1, c_2, c_3` in the basis on `(0, c_1, c_2, c_3)` (the weight of the node 0 is not
/// needed: its value is 0 in the increment form).
pub(crate) fn weights(c: &[f64; 3], theta: f64) -> ([f64; 3], [f64; 3]) {
    let nodes = [0.0, c[0], c[1], c[2]];
    let mut w = [0.0; 3];
    let mut dw = [0.0; 3];
    for i in 0..3 {
        let k = i + 1;
        let mut denom = 1.0;
        for (j, &nj) in nodes.iter().enumerate() {
            if j != k {
                denom *= nodes[k] - nj;
            }
        }
        let mut p = 1.0;
        let mut dp = 0.0;
        for (j, &nj) in nodes.iter().enumerate() {
            if j != k {
                dp = dp * (theta - nj) + p;
                p *= theta - nj;
            }
        }
        w[i] = p / denom;
        dw[i] = dp / denom;
    }
    (w, dw)
}

/// The collocation polynomial of one step.
#[derive(Debug, Clone)]
pub(crate) struct Collocation {
    /// Start of the step.
    pub t0: f64,
    /// Step size.
    pub h: f64,
    /// `y_n` at the start.
    pub y0: Vec<f64>,
    /// Stage increments `Z_1, Z_2, Z_3`.
    pub z: [Vec<f64>; 3],
}

impl Collocation {
    pub fn new(n: usize) -> Self {
        Self {
            t0: 0.0,
            h: 0.0,
            y0: vec![0.0; n],
            z: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
        }
    }

    /// `u(t)` into `y` and, if given, `u'(t)` into `yp`.
    pub fn eval(&self, c: &[f64; 3], t: f64, y: &mut [f64], yp: Option<&mut [f64]>) {
        let theta = (t - self.t0) / self.h;
        let (w, dw) = weights(c, theta);
        for (k, yk) in y.iter_mut().enumerate() {
            *yk = self.y0[k] + w[0] * self.z[0][k] + w[1] * self.z[1][k] + w[2] * self.z[2][k];
        }
        if let Some(yp) = yp {
            let r = 1.0 / self.h;
            for (k, v) in yp.iter_mut().enumerate() {
                *v = r * (dw[0] * self.z[0][k] + dw[1] * self.z[1][k] + dw[2] * self.z[2][k]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_interpolate_and_reproduce_cubics() {
        let c = super::super::tableau::Tableau::radau_iia_3().c;
        for (i, &ci) in c.iter().enumerate() {
            let (w, _) = weights(&c, ci);
            for (j, wj) in w.iter().enumerate() {
                let e = if i == j { 1.0 } else { 0.0 };
                assert!((wj - e).abs() < 1e-14, "{w:?}");
            }
        }
        // p(θ) = θ^3 - 2θ: sum_i l_i(θ) p(c_i) = p(θ) since p(0) = 0; derivative likewise.
        let p = |x: f64| x * x * x - 2.0 * x;
        for th in [0.0, 0.3, 0.77, 1.0, 1.6] {
            let (w, dw) = weights(&c, th);
            let v: f64 = (0..3).map(|i| w[i] * p(c[i])).sum();
            let d: f64 = (0..3).map(|i| dw[i] * p(c[i])).sum();
            assert!((v - p(th)).abs() < 1e-13, "{th}: {v}");
            assert!((d - (3.0 * th * th - 2.0)).abs() < 1e-12, "{th}: {d}");
        }
    }
}
