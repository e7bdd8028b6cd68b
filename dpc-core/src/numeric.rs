//! Floating-point helpers shared by the controller, the closed loop and the reports.

/// The largest of `values`, or NaN if any of them is NaN (`0` for none).
///
/// `f64::max` returns the other argument when one is NaN, so a plain fold forgets a NaN met
/// before the last value; a convergence test or an error summary built on it could then
/// pass over a non-finite residual or error.
pub fn max_or_nan(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut m = 0.0_f64;
    for v in values {
        if v.is_nan() {
            return f64::NAN;
        }
        m = m.max(v);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::max_or_nan;

    #[test]
    fn a_nan_anywhere_wins() {
        assert_eq!(max_or_nan([1.0, 3.0, 2.0]), 3.0);
        assert_eq!(max_or_nan([]), 0.0);
        assert!(max_or_nan([1.0, f64::NAN, 2.0]).is_nan());
        assert!(max_or_nan([f64::NAN, 2.0]).is_nan());
        assert!(max_or_nan([2.0, f64::NAN]).is_nan());
        assert_eq!(max_or_nan([1.0, f64::INFINITY]), f64::INFINITY);
    }
}
