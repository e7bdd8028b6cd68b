//! Serde helpers: matrices as arrays of rows, complex numbers as `[re, im]` pairs.

use nalgebra::DMatrix;
use num_complex::Complex;
use serde::ser::{SerializeSeq, Serializer};

/// A matrix as an array of rows.
pub fn mat<S: Serializer>(m: &DMatrix<f64>, s: S) -> Result<S::Ok, S::Error> {
    let mut seq = s.serialize_seq(Some(m.nrows()))?;
    for i in 0..m.nrows() {
        let row: Vec<f64> = m.row(i).iter().copied().collect();
        seq.serialize_element(&row)?;
    }
    seq.end()
}

/// An optional matrix.
pub fn opt_mat<S: Serializer>(m: &Option<DMatrix<f64>>, s: S) -> Result<S::Ok, S::Error> {
    match m {
        Some(m) => mat(m, s),
        None => s.serialize_none(),
    }
}

/// A list of matrices.
pub fn mats<S: Serializer>(ms: &[DMatrix<f64>], s: S) -> Result<S::Ok, S::Error> {
    let rows: Vec<Vec<Vec<f64>>> = ms.iter().map(to_rows).collect();
    serde::Serialize::serialize(&rows, s)
}

/// An optional list of matrices.
pub fn opt_mats<S: Serializer>(ms: &Option<Vec<DMatrix<f64>>>, s: S) -> Result<S::Ok, S::Error> {
    match ms {
        Some(ms) => mats(ms, s),
        None => s.serialize_none(),
    }
}

/// Complex numbers as `[re, im]` pairs.
pub fn cvec<S: Serializer>(v: &[Complex<f64>], s: S) -> Result<S::Ok, S::Error> {
    let pairs: Vec<[f64; 2]> = v.iter().map(|z| [z.re, z.im]).collect();
    serde::Serialize::serialize(&pairs, s)
}

/// Optional complex vector.
pub fn opt_cvec<S: Serializer>(v: &Option<Vec<Complex<f64>>>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => cvec(v, s),
        None => s.serialize_none(),
    }
}

/// Rows of a matrix.
pub fn to_rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}
