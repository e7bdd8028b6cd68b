//! Simplified Newton iteration on the transformed Radau IIA stage system.
//!
//! The stage increments `Z_i = Y_i - y_n` satisfy the collocation conditions applied to `F`
//! directly,
//!
//! ```text
//! F(t_n + c_i h, y_n + Z_i, Y'_i) = 0,   Y'_i = (1/h) sum_j (A^{-1})_ij Z_j,   i = 1, 2, 3,
//! ```
//!
//! so an implicit `F` (not only `M y' = f`) is integrated as declared. One iteration evaluates
//! the three residuals, transforms them with `T^{-1}`, solves one real and one complex `n x n`
//! system with the matrices of [`super::linear`] (frozen at the step start), and maps the
//! update back with `T` (Hairer & Wanner, Section IV.8, eq. (8.5)-(8.16)).
//!
//! Convergence control follows RADAU5: the contraction rate `theta` is estimated from
//! successive update norms, the iteration is declared converged when
//! `theta/(1 - theta) |Δ| <= fnewt`, abandoned when `theta >= 0.99`, and stopped early with a
//! step-size reduction when the predicted norm after the remaining iterations,
//! `theta^(k_max - k)/(1 - theta) |Δ|`, still exceeds `fnewt`. The norm `|Δ|` is the weighted
//! RMS norm of the stage increments `ΔZ`, or, when the problem declares components of index 2
//! or 3, that of the transformed increments `ΔW = (T^{-1} ⊗ I) ΔZ` that the two linear systems
//! deliver, as RADAU5 tests ([`super::tableau`] normalises the eigenvectors as RADAU5 does, so
//! that norm is RADAU5's). On higher-index problems `|ΔW|` is several times `|ΔZ|` (`T^{-1}` has
//! entries up to 4.3): on Andrews' squeezing mechanism (index 3) the stricter test is worth 0.5
//! to 2 digits in the positions at `rtol = 1e-4`, where Newton's error otherwise dominates. On
//! smooth index-1 solutions the increments of the three stages nearly cancel in `ΔW`, and the
//! test on `ΔZ` keeps the global error proportional to the tolerance.
//!
//! An iteration that would be abandoned (slow or no contraction) while its increment is no
//! larger than the increment the round-off of the stage residuals alone causes has converged
//! as far as floating point allows and is accepted: on higher-index problems the relaxed
//! weights can put that round-off level above the Newton tolerance at every step size.

use faer::c64;

use super::linear::StageMatrices;
use super::tableau::Tableau;
use super::Stats;
use crate::linear_solver::LinearSolver;
use crate::ImplicitDae;

/// Work vectors of the stage iteration.
pub(crate) struct StageWork {
    /// Stage increments `Z_i`.
    pub z: [Vec<f64>; 3],
    /// Stage derivatives `Y'_i`.
    pub yp: [Vec<f64>; 3],
    /// Stage residuals, then transformed residuals.
    f: [Vec<f64>; 3],
    /// Stage values `y_n + Z_i`.
    ys: Vec<f64>,
    /// Right-hand side of the complex system.
    rc: Vec<c64>,
}

impl StageWork {
    pub fn new(n: usize) -> Self {
        let v = || [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        Self {
            z: v(),
            yp: v(),
            f: v(),
            ys: vec![0.0; n],
            rc: vec![c64::new(0.0, 0.0); n],
        }
    }
}

/// How one Newton solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum NewtonOutcome {
    /// Converged after `iterations` with last contraction estimate `theta`; `first_increment`
    /// is the norm of the first update in units of the Newton tolerance.
    Converged {
        iterations: usize,
        theta: f64,
        first_increment: f64,
    },
    /// Will not converge at this step size: retry with `h * factor`. `theta` is the last
    /// contraction estimate (0 when the iteration stopped before measuring one),
    /// `first_increment` the first update's norm in units of the Newton tolerance.
    Failed {
        factor: f64,
        theta: f64,
        first_increment: f64,
    },
    /// A residual was not finite in this equation: retry with half the step.
    NonFinite { equation: usize, t: f64 },
}

/// Inputs of one stage solve.
pub(crate) struct StageProblem<'a> {
    pub t: f64,
    pub h: f64,
    pub y: &'a [f64],
    /// Weights of the convergence norm (index-scaled).
    pub w: &'a [f64],
    pub max_iterations: usize,
    pub fnewt: f64,
    /// Test the transformed increments `ΔW` (higher-index problems) instead of `ΔZ`.
    pub transformed_norm: bool,
    /// The least carried `FACCON` the first update is judged with
    /// ([`crate::newton::MIN_CARRIED_RATE`] on a DAE with unknowns of index 2 or 3, else 0:
    /// RADAU5's test).
    pub min_carried: f64,
}

/// Weighted RMS norm over the three stages.
fn stage_norm(dz: &[Vec<f64>; 3], w: &[f64]) -> f64 {
    let n = w.len();
    let mut s = 0.0;
    for d in dz {
        for (a, b) in d.iter().zip(w) {
            s += (a * b) * (a * b);
        }
    }
    (s / (3 * n).max(1) as f64).sqrt()
}

/// Weighted RMS norm of the transformed increment `ΔW`: the real part `dw` and the complex
/// pair `dc` (real and imaginary parts are the second and third stage components).
fn transformed_norm(dw: &[f64], dc: &[c64], w: &[f64]) -> f64 {
    let n = w.len();
    let mut s = 0.0;
    for ((a, c), b) in dw.iter().zip(dc).zip(w) {
        s += (a * b) * (a * b) + (c.re * b) * (c.re * b) + (c.im * b) * (c.im * b);
    }
    (s / (3 * n).max(1) as f64).sqrt()
}

/// Stage derivatives `Y'_i = (1/h) sum_j (A^{-1})_ij Z_j`.
pub(crate) fn stage_derivatives(tab: &Tableau, h: f64, z: &[Vec<f64>; 3], yp: &mut [Vec<f64>; 3]) {
    let r = 1.0 / h;
    let n = z[0].len();
    // Cut to one length so that the loop compiles without bounds checks.
    let (z0, z1, z2) = (&z[0][..n], &z[1][..n], &z[2][..n]);
    for (i, ypi) in yp.iter_mut().enumerate() {
        let a = tab.a_inv[i];
        for (k, v) in ypi[..n].iter_mut().enumerate() {
            *v = r * (a[0] * z0[k] + a[1] * z1[k] + a[2] * z2[k]);
        }
    }
}

/// Iterate from the starting guess in `work.z`; `faccon` carries RADAU5's `FACCON` between steps.
// The Kronecker products with T and T^-1 index the three stage vectors at the same component.
#[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
pub(crate) fn solve<D: ImplicitDae, L: LinearSolver>(
    dae: &D,
    sm: &mut StageMatrices<L>,
    tab: &Tableau,
    stats: &mut Stats,
    p: &StageProblem<'_>,
    work: &mut StageWork,
    dz: &mut [Vec<f64>; 3],
    faccon: &mut f64,
) -> NewtonOutcome {
    let n = p.y.len();
    let nit = p.max_iterations;
    *faccon = faccon.max(f64::EPSILON).powf(0.8);
    let mut theta: f64 = 0.0;
    let mut dyno_old = 0.0;
    let mut thq_old = 0.0;
    let mut newt = 0;
    let mut first_increment = 0.0;
    loop {
        if newt >= nit {
            return NewtonOutcome::Failed {
                factor: 0.5,
                theta,
                first_increment,
            };
        }
        // Residuals at the stages.
        stage_derivatives(tab, p.h, &work.z, &mut work.yp);
        for i in 0..3 {
            for ((s, y), z) in work.ys.iter_mut().zip(p.y).zip(&work.z[i]) {
                *s = y + z;
            }
            let ti = p.t + tab.c[i] * p.h;
            dae.residual(ti, &work.ys, &work.yp[i], &mut work.f[i]);
            stats.residual_evaluations += 1;
            if let Some(e) = work.f[i].iter().position(|v| !v.is_finite()) {
                return NewtonOutcome::NonFinite { equation: e, t: ti };
            }
        }
        // Transformed residuals R = (T^{-1} ⊗ I) F, and the two solves for -ΔW.
        let ti = tab.t_inv;
        {
            let (f0, f1, f2) = (&work.f[0][..n], &work.f[1][..n], &work.f[2][..n]);
            let (dw, rc) = (&mut dz[0][..n], &mut work.rc[..n]);
            for k in 0..n {
                let (f0, f1, f2) = (f0[k], f1[k], f2[k]);
                dw[k] = -(ti[0][0] * f0 + ti[0][1] * f1 + ti[0][2] * f2);
                let r1 = ti[1][0] * f0 + ti[1][1] * f1 + ti[1][2] * f2;
                let r2 = ti[2][0] * f0 + ti[2][1] * f1 + ti[2][2] * f2;
                rc[k] = c64::new(-r1, -r2);
            }
        }
        sm.solve_real(&mut dz[0]);
        sm.solve_complex(&mut work.rc);
        stats.newton_iterations += 1;
        let dyno_w = if p.transformed_norm {
            transformed_norm(&dz[0], &work.rc, p.w)
        } else {
            0.0
        };
        // ΔZ = (T ⊗ I) ΔW, written over dz.
        let t = tab.t;
        {
            let [d0, d1, d2] = dz;
            let (d0, d1, d2, rc) = (&mut d0[..n], &mut d1[..n], &mut d2[..n], &work.rc[..n]);
            for k in 0..n {
                let (w0, w1, w2) = (d0[k], rc[k].re, rc[k].im);
                d0[k] = t[0][0] * w0 + t[0][1] * w1 + t[0][2] * w2;
                d1[k] = t[1][0] * w0 + t[1][1] * w1 + t[1][2] * w2;
                d2[k] = t[2][0] * w0 + t[2][1] * w1 + t[2][2] * w2;
            }
        }
        let dyno = if p.transformed_norm {
            dyno_w
        } else {
            stage_norm(dz, p.w)
        };
        newt += 1;
        if !dyno.is_finite() {
            return NewtonOutcome::Failed {
                factor: 0.5,
                theta,
                first_increment,
            };
        }
        if newt == 1 {
            first_increment = dyno / p.fnewt;
        }
        if newt > 1 && newt < nit {
            let thq = dyno / dyno_old;
            theta = if newt == 2 {
                thq
            } else {
                (thq * thq_old).sqrt()
            };
            thq_old = thq;
            if theta < 0.99 {
                *faccon = theta / (1.0 - theta);
                let remaining = (nit - 1 - newt) as i32;
                let dyth = *faccon * dyno * theta.powi(remaining) / p.fnewt;
                if dyth >= 1.0 {
                    if at_roundoff(sm, tab, p, work, dyno) {
                        return converged_at_roundoff(
                            tab,
                            p,
                            work,
                            dz,
                            (newt, theta, first_increment),
                        );
                    }
                    let qnewt = dyth.clamp(1e-4, 20.0);
                    let factor = 0.8 * qnewt.powf(-1.0 / (4.0 + f64::from(remaining)));
                    return NewtonOutcome::Failed {
                        factor,
                        theta,
                        first_increment,
                    };
                }
            } else {
                if at_roundoff(sm, tab, p, work, dyno) {
                    return converged_at_roundoff(tab, p, work, dz, (newt, theta, first_increment));
                }
                return NewtonOutcome::Failed {
                    factor: divergence_factor(theta),
                    theta,
                    first_increment,
                };
            }
        }
        dyno_old = dyno.max(f64::EPSILON);
        for (zi, di) in work.z.iter_mut().zip(dz.iter()) {
            for (a, b) in zi.iter_mut().zip(di) {
                *a += b;
            }
        }
        let carried = if newt == 1 {
            faccon.max(p.min_carried)
        } else {
            *faccon
        };
        if carried * dyno <= p.fnewt {
            stage_derivatives(tab, p.h, &work.z, &mut work.yp);
            return NewtonOutcome::Converged {
                iterations: newt,
                theta,
                first_increment,
            };
        }
    }
}

/// The step reduction after Newton diverged with contraction estimate `theta >= 0.99`: the
/// step at which the contraction would be about a half if it grows in proportion to `h` (a
/// simplified Newton iteration's contraction is `h` times the change of the Jacobian over the
/// iterates, until stiff components saturate it), between a tenth and RADAU5's half. A mild
/// divergence keeps RADAU5's halving; a strong one (a fast transient switched on by a corner
/// of an input, where the contraction falls from 7 at the carried step to below 1 only at a
/// hundredth of it) takes two or three reductions instead of eight halvings.
fn divergence_factor(theta: f64) -> f64 {
    if theta.is_finite() {
        (0.5 / theta).clamp(0.1, 0.5)
    } else {
        0.1
    }
}

/// Newton's increment `dyno` is no larger than the increment that the round-off of the stage
/// residuals alone causes, in the norm of the convergence test, so further iterations cannot
/// reduce it. This happens on higher-index problems, whose weights are relaxed by `h`: a
/// multiplier `mu` that enforces a position constraint `g = 0` through `q' = ... - h G^T mu`
/// moves by `round-off(g) / (h |G|^2)` in every iteration, which its weight `h / atol'` turns
/// into an increment independent of `h`; a tight Newton tolerance may not admit it, and no
/// smaller step helps (Andrews' squeezing mechanism in the stabilised form at `rtol = 1e-10`).
///
/// The round-off bound of [`StageMatrices::residual_roundoff`] at the last stage stands for
/// every stage's; it is transformed and solved as the residuals are (`|T^{-1}|` for `T^{-1}`).
#[allow(clippy::needless_range_loop)]
fn at_roundoff<L: LinearSolver>(
    sm: &mut StageMatrices<L>,
    tab: &Tableau,
    p: &StageProblem<'_>,
    work: &mut StageWork,
    dyno: f64,
) -> bool {
    let n = p.y.len();
    for ((s, y), z) in work.ys.iter_mut().zip(p.y).zip(&work.z[2]) {
        *s = y + z;
    }
    let [r, dw, _] = &mut work.f;
    sm.residual_roundoff(&work.ys, &work.yp[2], r);
    let floor = if p.transformed_norm {
        let s = tab
            .t_inv
            .map(|row| row.iter().map(|v| v.abs()).sum::<f64>());
        for k in 0..n {
            dw[k] = s[0] * r[k];
            work.rc[k] = c64::new(s[1] * r[k], s[2] * r[k]);
        }
        sm.solve_real(dw);
        sm.solve_complex(&mut work.rc);
        transformed_norm(dw, &work.rc, p.w)
    } else {
        sm.solve_real(r);
        super::wrms(r, p.w)
    };
    dyno <= floor
}

/// Accept the iterate whose increment `dz` is at the round-off level (see [`at_roundoff`]).
fn converged_at_roundoff(
    tab: &Tableau,
    p: &StageProblem<'_>,
    work: &mut StageWork,
    dz: &[Vec<f64>; 3],
    (iterations, theta, first_increment): (usize, f64, f64),
) -> NewtonOutcome {
    for (zi, di) in work.z.iter_mut().zip(dz.iter()) {
        for (a, b) in zi.iter_mut().zip(di) {
            *a += b;
        }
    }
    stage_derivatives(tab, p.h, &work.z, &mut work.yp);
    NewtonOutcome::Converged {
        iterations,
        theta,
        first_increment,
    }
}

#[cfg(test)]
mod tests {
    use super::divergence_factor;

    #[test]
    fn divergence_reduces_to_the_step_of_half_the_contraction() {
        // Mild divergence keeps RADAU5's halving; strong divergence reduces to 0.5 / theta,
        // at most to a tenth; a contraction that is not a number takes the tenth.
        assert_eq!(divergence_factor(0.99), 0.5);
        assert!((divergence_factor(2.5) - 0.2).abs() < 1e-15);
        assert_eq!(divergence_factor(50.0), 0.1);
        assert_eq!(divergence_factor(f64::NAN), 0.1);
    }
}
