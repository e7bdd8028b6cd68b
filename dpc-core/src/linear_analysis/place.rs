//! Multi-input pole placement by the Luenberger controller form, chain by chain.
//!
//! KNV-type (robust eigenstructure) methods cannot place a pole with multiplicity larger than
//! `rank B`; the paper places all three poles of `Abar_4 + Bbar_2 K_2` at -5 with two inputs.
//! Here the Krylov vectors `b_1, b_2, ..., A b_1, A b_2, ...` are selected in crate order
//! (Luenberger 1967; Kailath, *Linear Systems*, 1980, Sec. 6.4), giving controllability indices
//! `mu_i`. With `q_i` the row of `T^-1` belonging to the last vector of chain `i`, one has
//! `q_i A^j B = 0` for `j < mu_i - 1`, so `q_i (A + BK)^mu_i = q_i A^mu_i + q_i A^(mu_i-1) B K`.
//! Asking `q_i p_i(A + BK) = 0` for a monic `p_i` of degree `mu_i` for every chain gives
//! `L K = -P` with `L = [q_i A^(mu_i-1) B]` (triangular, invertible) and `P = [q_i p_i(A)]`;
//! the closed loop is then block diagonal in the controller coordinates with characteristic
//! polynomial `prod p_i`. Repeated poles of any multiplicity are fine.
//!
//! Before that, controllability is decided by the orthogonal staircase (the Krylov space built
//! with orthonormal bases and SVD rank decisions), which gives a typed error with the
//! dimension found.

use nalgebra::DMatrix;
use num_complex::Complex;

use super::subspace;
use super::LinearError;

type C64 = Complex<f64>;

/// Dimension of the controllable subspace of `(a, b)` and the tolerance used.
pub fn controllable_dimension(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    tol_factor: f64,
) -> Result<(usize, f64), LinearError> {
    let n = a.nrows();
    let scale = subspace::norm2(a).max(subspace::norm2(b));
    let (mut basis, d) = subspace::range(b, tol_factor, Some(scale))?;
    let mut tol = d.tol;
    let mut newest = basis.clone();
    while basis.ncols() < n && newest.ncols() > 0 {
        // Project A times the newest block onto the complement of what we have.
        let img = a * &newest;
        let img = &img - &basis * (basis.transpose() * &img);
        let (fresh, d) = subspace::range(&img, tol_factor, Some(scale))?;
        tol = d.tol;
        if fresh.ncols() == 0 {
            break;
        }
        // Re-orthogonalise against the basis once more for safety.
        let fresh = &fresh - &basis * (basis.transpose() * &fresh);
        let (fresh, _) = subspace::range(&fresh, tol_factor, Some(1.0))?;
        let mut next = DMatrix::zeros(n, basis.ncols() + fresh.ncols());
        next.view_mut((0, 0), (n, basis.ncols())).copy_from(&basis);
        next.view_mut((0, basis.ncols()), (n, fresh.ncols()))
            .copy_from(&fresh);
        basis = next;
        newest = fresh;
    }
    Ok((basis.ncols(), tol))
}

/// Split poles into real polynomials of the given degrees (conjugate pairs kept together).
fn distribute(poles: &[C64], degrees: &[usize]) -> Result<Vec<Vec<f64>>, LinearError> {
    let im_tol = |z: C64| 1e-9 * (1.0 + z.norm());
    let mut reals = Vec::new();
    let mut pairs = Vec::new();
    let mut uppers: Vec<C64> = poles
        .iter()
        .copied()
        .filter(|z| z.im > im_tol(*z))
        .collect();
    let mut lowers: Vec<C64> = poles
        .iter()
        .copied()
        .filter(|z| z.im < -im_tol(*z))
        .collect();
    for z in poles {
        if z.im.abs() <= im_tol(*z) {
            reals.push(z.re);
        }
    }
    if uppers.len() != lowers.len() {
        return Err(LinearError::BadPoles {
            reason: "complex poles must come in conjugate pairs".into(),
        });
    }
    uppers.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
    lowers.sort_by(|x, y| x.re.total_cmp(&y.re).then(y.im.total_cmp(&x.im)));
    for (u, l) in uppers.iter().zip(&lowers) {
        if (u - l.conj()).norm() > 1e-9 * (1.0 + u.norm()) {
            return Err(LinearError::BadPoles {
                reason: format!("{u} has no conjugate partner"),
            });
        }
        // (s - z)(s - conj z) = s^2 - 2 Re z s + |z|^2
        pairs.push((u.re, u.norm_sqr()));
    }
    // Fill the largest chains first with pairs, then real poles.
    let mut order: Vec<usize> = (0..degrees.len()).collect();
    order.sort_by(|&i, &j| degrees[j].cmp(&degrees[i]));
    let mut polys: Vec<Vec<f64>> = vec![vec![1.0]; degrees.len()];
    let mut left: Vec<usize> = degrees.to_vec();
    for (re, abs2) in pairs {
        let slot = order
            .iter()
            .copied()
            .filter(|&i| left[i] >= 2)
            .max_by_key(|&i| left[i].is_multiple_of(2))
            .ok_or_else(|| LinearError::BadPoles {
                reason: format!(
                    "cannot keep the conjugate pairs together on chains of lengths {degrees:?} (controllability indices); give more real poles"
                ),
            })?;
        polys[slot] = mul(&polys[slot], &[abs2, -2.0 * re, 1.0]);
        left[slot] -= 2;
    }
    let mut reals = reals.into_iter();
    for &i in &order {
        while left[i] > 0 {
            let r = reals.next().expect("pole count was checked");
            polys[i] = mul(&polys[i], &[-r, 1.0]);
            left[i] -= 1;
        }
    }
    Ok(polys)
}

fn mul(p: &[f64], q: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; p.len() + q.len() - 1];
    for (i, a) in p.iter().enumerate() {
        for (j, b) in q.iter().enumerate() {
            out[i + j] += a * b;
        }
    }
    out
}

/// `K` with `eig(a + b K) = poles` (any multiplicities).
///
/// Errors: wrong pole count or unpaired complex poles ([`LinearError::BadPoles`]), `(a, b)`
/// not controllable ([`LinearError::Uncontrollable`]).
pub fn place(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    poles: &[C64],
    tol_factor: f64,
) -> Result<DMatrix<f64>, LinearError> {
    let n = a.nrows();
    let m = b.ncols();
    if poles.len() != n {
        return Err(LinearError::BadPoles {
            reason: format!("{} poles given for a {n}x{n} matrix", poles.len()),
        });
    }
    if let Some(z) = poles
        .iter()
        .find(|z| !z.re.is_finite() || !z.im.is_finite())
    {
        return Err(LinearError::BadPoles {
            reason: format!("non-finite pole {z}"),
        });
    }
    if n == 0 {
        return Ok(DMatrix::zeros(m, 0));
    }
    let (cdim, tol) = controllable_dimension(a, b, tol_factor)?;
    if cdim < n {
        return Err(LinearError::Uncontrollable {
            controllable_dim: cdim,
            dim: n,
            tol,
        });
    }
    // Compress B to full column rank (B W_r, u = W_r v) only when it is rank deficient: with
    // full rank the chains follow the user's inputs, which keeps decoupled plants decoupled.
    let (w, sv) = subspace::svd_right(b)?;
    let dec = subspace::decide(&sv, b.shape(), tol_factor);
    let wr = if dec.rank == m {
        DMatrix::identity(m, m)
    } else {
        w.columns(0, dec.rank).into_owned()
    };
    let br = b * &wr;
    let r = br.ncols();

    // The crate order depends on the order of the inputs, and some orders give badly
    // conditioned controller forms (gains of 1e6 where 1e2 do). Try every order for up to five
    // inputs and keep the smallest gain; the identity order wins ties, so decoupled plants
    // stay decoupled.
    let mut orders: Vec<Vec<usize>> = vec![(0..r).collect()];
    if r <= 5 {
        orders = permutations(r);
    }
    let mut best: Option<(f64, DMatrix<f64>)> = None;
    let mut last_err = None;
    for order in &orders {
        let bo = DMatrix::from_fn(n, r, |i, j| br[(i, order[j])]);
        match place_in_order(a, &bo, poles) {
            Ok(ko) => {
                let mut k_r = DMatrix::zeros(r, n);
                for (j, &c) in order.iter().enumerate() {
                    k_r.set_row(c, &ko.row(j));
                }
                let size = k_r.norm();
                if best.as_ref().is_none_or(|(s, _)| size < 0.999 * s) {
                    best = Some((size, k_r));
                }
            }
            Err(e) => last_err = Some(e),
        }
    }
    match best {
        Some((_, k_r)) => Ok(&wr * k_r),
        None => Err(last_err.expect("at least one order was tried")),
    }
}

/// All permutations of `0..r`, the identity first.
fn permutations(r: usize) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new()];
    for _ in 0..r {
        let mut next = Vec::new();
        for p in &out {
            for c in 0..r {
                if !p.contains(&c) {
                    let mut q = p.clone();
                    q.push(c);
                    next.push(q);
                }
            }
        }
        out = next;
    }
    out
}

/// Luenberger placement with the inputs in the given order; `br` has full column rank and
/// `(a, br)` is controllable.
fn place_in_order(
    a: &DMatrix<f64>,
    br: &DMatrix<f64>,
    poles: &[C64],
) -> Result<DMatrix<f64>, LinearError> {
    let n = a.nrows();
    let r = br.ncols();
    // Crate-order selection of Krylov vectors.
    let scale = subspace::norm2(a).max(1e-300);
    let mut chains: Vec<Vec<nalgebra::DVector<f64>>> = vec![Vec::new(); r];
    let mut alive = vec![true; r];
    let mut current: Vec<nalgebra::DVector<f64>> =
        (0..r).map(|i| br.column(i).into_owned()).collect();
    let mut ortho: Vec<nalgebra::DVector<f64>> = Vec::new();
    // Far above eps: a barely independent Krylov vector makes T, and so K, ill-conditioned.
    let indep_tol = 1e-8;
    while ortho.len() < n && alive.iter().any(|&x| x) {
        for i in 0..r {
            if !alive[i] || ortho.len() == n {
                continue;
            }
            let v = current[i].clone();
            let vn = v.norm();
            let mut res = v.clone();
            for _ in 0..2 {
                for o in &ortho {
                    let c = o.dot(&res);
                    res -= o * c;
                }
            }
            if vn == 0.0 || res.norm() <= indep_tol * vn {
                alive[i] = false;
                continue;
            }
            ortho.push(&res / res.norm());
            // Normalise the chain vector; scaling a chain does not change the construction.
            let vs = v / vn;
            current[i] = a * &vs / scale;
            chains[i].push(vs);
        }
    }
    if ortho.len() < n {
        return Err(LinearError::Uncontrollable {
            controllable_dim: ortho.len(),
            dim: n,
            tol: indep_tol,
        });
    }
    let used: Vec<usize> = (0..r).filter(|&i| !chains[i].is_empty()).collect();
    let degrees: Vec<usize> = used.iter().map(|&i| chains[i].len()).collect();
    let mut t = DMatrix::zeros(n, n);
    let mut col = 0;
    let mut last_col = Vec::new();
    for &i in &used {
        for v in &chains[i] {
            t.set_column(col, v);
            col += 1;
        }
        last_col.push(col - 1);
    }
    let polys = distribute(poles, &degrees)?;

    // q_i = e_last^T T^-1, by solving T^T q^T = e.
    let mut e = DMatrix::zeros(n, used.len());
    for (k, &c) in last_col.iter().enumerate() {
        e[(c, k)] = 1.0;
    }
    let qs = subspace::solve(&t.transpose(), &e).ok_or(LinearError::Uncontrollable {
        controllable_dim: ortho.len(),
        dim: n,
        tol: indep_tol,
    })?;
    let k_used = used.len();
    let mut l = DMatrix::zeros(k_used, r);
    let mut p = DMatrix::zeros(k_used, n);
    for (k, poly) in polys.iter().enumerate() {
        let q = qs.column(k).transpose();
        // Accumulate q p(A) and pick up q A^(mu-1) B on the way.
        let mut row = q.clone();
        let mut acc = q.clone() * 0.0;
        for (deg, coef) in poly.iter().enumerate() {
            acc += &row * *coef;
            if deg + 1 == degrees[k] {
                l.set_row(k, &(&row * br));
            }
            if deg < degrees[k] {
                row = &row * a;
            }
        }
        p.set_row(k, &acc);
    }
    // L has one row per used chain; unused compressed inputs get zero gain.
    let lu = l.columns(0, r).into_owned();
    let used_cols: Vec<usize> = used.clone();
    let l_sq = DMatrix::from_fn(k_used, k_used, |i, j| lu[(i, used_cols[j])]);
    let k_sq = subspace::solve(&l_sq, &(-p)).ok_or(LinearError::Uncontrollable {
        controllable_dim: ortho.len(),
        dim: n,
        tol: indep_tol,
    })?;
    let mut k_r = DMatrix::zeros(r, n);
    for (j, &c) in used_cols.iter().enumerate() {
        k_r.set_row(c, &k_sq.row(j));
    }
    Ok(k_r)
}
