//! The square linear system `x' = Ax + Bu, y = Cx + Du` (paper, (3.1)) and its partial
//! stabilisation `yhat_i = W_i(d/dt) y_i` (paper, Section 2, (2.1b)).

use nalgebra::DMatrix;
use serde::Serialize;

use super::{serial, LinearError};

/// A square linear system `x' = Ax + Bu, y = Cx + Du` with `n` states and `m` inputs/outputs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearSystem {
    /// State matrix, `n x n`.
    #[serde(serialize_with = "serial::mat")]
    pub a: DMatrix<f64>,
    /// Input matrix, `n x m`.
    #[serde(serialize_with = "serial::mat")]
    pub b: DMatrix<f64>,
    /// Output matrix, `m x n`.
    #[serde(serialize_with = "serial::mat")]
    pub c: DMatrix<f64>,
    /// Feedthrough, `m x m`.
    #[serde(serialize_with = "serial::mat")]
    pub d: DMatrix<f64>,
}

impl LinearSystem {
    /// Check shapes (square `A`, `m` inputs = `m` outputs) and finiteness.
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
    ) -> Result<Self, LinearError> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(LinearError::DimensionMismatch {
                what: format!("A is {}x{}, not square", a.nrows(), a.ncols()),
            });
        }
        if b.nrows() != n {
            return Err(LinearError::DimensionMismatch {
                what: format!("B has {} rows but A is {n}x{n}", b.nrows()),
            });
        }
        if c.ncols() != n {
            return Err(LinearError::DimensionMismatch {
                what: format!("C has {} columns but A is {n}x{n}", c.ncols()),
            });
        }
        let m = b.ncols();
        if m == 0 {
            return Err(LinearError::DimensionMismatch {
                what: "B has no columns: the system has no inputs".into(),
            });
        }
        if c.nrows() != m {
            return Err(LinearError::NonSquare {
                inputs: m,
                outputs: c.nrows(),
            });
        }
        if d.shape() != (m, m) {
            return Err(LinearError::DimensionMismatch {
                what: format!(
                    "D is {}x{} but C has {} rows and B {} columns",
                    d.nrows(),
                    d.ncols(),
                    c.nrows(),
                    m
                ),
            });
        }
        for (name, mat) in [("A", &a), ("B", &b), ("C", &c), ("D", &d)] {
            check_finite(name, mat)?;
        }
        Ok(Self { a, b, c, d })
    }

    /// `D = 0` convenience constructor.
    pub fn without_feedthrough(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
    ) -> Result<Self, LinearError> {
        let d = DMatrix::zeros(c.nrows(), b.ncols());
        Self::new(a, b, c, d)
    }

    /// Number of states.
    pub fn n(&self) -> usize {
        self.a.nrows()
    }

    /// Number of inputs (= outputs).
    pub fn m(&self) -> usize {
        self.b.ncols()
    }

    /// The partially stabilised system: output `i` becomes `W_i(d/dt) y_i` with
    /// `W_i(s) = prod_j (s + w[i][j])` (an empty list means `W_i = 1`; a zero entry means a plain
    /// differentiation).
    ///
    /// `W_i(d/dt) y_i` must be a function of `x` and `u` only, so `deg W_i` may not exceed the
    /// relative degree of output `i`: with `y_i^(k) = c_i A^k x + sum_j c_i A^(k-1-j) B u^(j) + d_i
    /// u^(k)`, every coefficient of a derivative `u^(j)`, `j >= 1`, must vanish (checked relative
    /// to the norms involved). Roots with negative `w` (unstable factors) are rejected.
    pub fn stabilise(&self, w: &[Vec<f64>]) -> Result<Self, LinearError> {
        let m = self.m();
        if w.len() != m {
            return Err(LinearError::DimensionMismatch {
                what: format!("W has {} entries but the system has {m} outputs", w.len()),
            });
        }
        let scale = 1.0 + super::subspace::norm2(&self.a);
        let mut c_hat = DMatrix::zeros(m, self.n());
        let mut d_hat = DMatrix::zeros(m, m);
        for (i, roots) in w.iter().enumerate() {
            for &r in roots {
                if !r.is_finite() {
                    return Err(LinearError::BadW {
                        output: i,
                        reason: format!("non-finite entry {r}"),
                    });
                }
                if r < 0.0 {
                    return Err(LinearError::BadW {
                        output: i,
                        reason: format!(
                            "entry {r} gives the factor (s {r:+}) with a root in the right half plane; entries must be >= 0 (0 = plain differentiation)"
                        ),
                    });
                }
            }
            // Coefficients of W_i(s), lowest power first, monic.
            let mut coef = vec![1.0];
            for &r in roots {
                let mut next = vec![0.0; coef.len() + 1];
                for (k, &ck) in coef.iter().enumerate() {
                    next[k] += r * ck;
                    next[k + 1] += ck;
                }
                coef = next;
            }
            let k = roots.len();
            let ci = self.c.row(i).into_owned();
            let di = self.d.row(i).into_owned();
            // Rows c_i A^l for l = 0..=k and the Markov-like terms c_i A^l B.
            let mut powers = Vec::with_capacity(k + 1);
            let mut row = ci.clone();
            for _ in 0..=k {
                powers.push(row.clone());
                row = &row * &self.a;
            }
            let mut chat = ci.clone() * 0.0;
            for (l, p) in powers.iter().enumerate() {
                chat += p * coef[l];
            }
            // Coefficient of u^(j): sum_{l > j} w_l c_i A^(l-1-j) B + w_j d_i.
            let mut dhat = di.clone() * coef[0];
            for j in 0..=k {
                let mut cj = &di * coef[j];
                for l in (j + 1)..=k {
                    cj += (&powers[l - 1 - j] * &self.b) * coef[l];
                }
                if j == 0 {
                    dhat = cj;
                } else {
                    let size = cj.amax();
                    let reference = (1.0 + self.b.amax() + di.amax())
                        * coef.iter().fold(0.0f64, |a, c| a.max(c.abs()))
                        * scale.powi(k as i32)
                        * 1e3
                        * f64::EPSILON;
                    if size > reference {
                        return Err(LinearError::BadW {
                            output: i,
                            reason: format!(
                                "degree {k} exceeds the relative degree of output {i}: the derivative u^({j}) appears with coefficient of size {size:.3e}"
                            ),
                        });
                    }
                }
            }
            c_hat.set_row(i, &chat);
            d_hat.set_row(i, &dhat);
        }
        Self::new(self.a.clone(), self.b.clone(), c_hat, d_hat)
    }

    /// The system after the preliminary feedback `u = K x + v`:
    /// `(A + BK, B, C + DK, D)`.
    pub fn with_feedback(&self, k: &DMatrix<f64>) -> Result<Self, LinearError> {
        if k.shape() != (self.m(), self.n()) {
            return Err(LinearError::DimensionMismatch {
                what: format!(
                    "feedback is {}x{} but the system needs {}x{}",
                    k.nrows(),
                    k.ncols(),
                    self.m(),
                    self.n()
                ),
            });
        }
        Self::new(
            &self.a + &self.b * k,
            self.b.clone(),
            &self.c + &self.d * k,
            self.d.clone(),
        )
    }
}

fn check_finite(name: &'static str, m: &DMatrix<f64>) -> Result<(), LinearError> {
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            let v = m[(i, j)];
            if !v.is_finite() {
                return Err(LinearError::NonFinite {
                    matrix: name,
                    row: i,
                    col: j,
                    value: v,
                });
            }
        }
    }
    Ok(())
}
