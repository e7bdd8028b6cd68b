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

/// A number as a person would write it in a message: plain decimals between `1e-4` and
/// `1e9`, scientific notation outside (never hundreds of zeros), `inf`, `-inf` and `NaN` by
/// name.
///
/// ```
/// use dpc_core::numeric::Readable;
///
/// assert_eq!(Readable(0.05).to_string(), "0.05");
/// assert_eq!(Readable(1e-300).to_string(), "1e-300");
/// assert_eq!(Readable(-2e300).to_string(), "-2e300");
/// assert_eq!(Readable(f64::INFINITY).to_string(), "inf");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Readable(pub f64);

impl std::fmt::Display for Readable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x.is_nan() {
            f.write_str("NaN")
        } else if x.is_infinite() {
            f.write_str(if x > 0.0 { "inf" } else { "-inf" })
        } else if x == 0.0 || (1e-4..1e9).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// A time in a message, to the precision that matters: sample times `k h` carry the
/// rounding of their sum (`1.8900000000000001`), so decimals are cut at ten places and
/// trailing zeros dropped (`1.89`); outside `1e-4 ..= 1e9` and for non-finite values it is
/// [`Readable`].
///
/// ```
/// use dpc_core::numeric::Time;
///
/// assert_eq!(Time(1.8900000000000001).to_string(), "1.89");
/// assert_eq!(Time(9.200000000000001).to_string(), "9.2");
/// assert_eq!(Time(20.0).to_string(), "20");
/// assert_eq!(Time(0.0).to_string(), "0");
/// assert_eq!(Time(5.6e-16).to_string(), "5.6e-16");
/// assert_eq!(Time(7.108268666266728e-17).to_string(), "7.108e-17");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Time(pub f64);

impl std::fmt::Display for Time {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 {
            return f.write_str("0");
        }
        if !x.is_finite() {
            return Readable(x).fmt(f);
        }
        if !(1e-4..1e9).contains(&x.abs()) {
            // Four significant digits say where a time so far from 1 is.
            let text = format!("{x:.3e}");
            let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            return write!(f, "{mantissa}e{exponent}");
        }
        let text = format!("{x:.10}");
        let text = text.trim_end_matches('0').trim_end_matches('.');
        f.write_str(text)
    }
}

/// Unknowns with their differentiation index, as an error message lists them: the first
/// [`IndexedUnknowns::SHOWN`] by name (`` `y[3]` of index 2 ``), then how many more there are
/// (the error's field holds them all). A circuit's error named all 95 of its floating node
/// potentials in one line.
///
/// ```
/// use dpc_core::numeric::IndexedUnknowns;
///
/// let two = [("x".to_string(), 2), ("lambda".to_string(), 3)];
/// assert_eq!(IndexedUnknowns(&two).to_string(), "`x` of index 2, `lambda` of index 3");
/// let many: Vec<(String, u8)> = (0..12).map(|i| (format!("y[{i}]"), 2)).collect();
/// assert!(IndexedUnknowns(&many).to_string().ends_with("`y[7]` of index 2 and 4 more"));
/// ```
#[derive(Debug, Clone, Copy)]
pub struct IndexedUnknowns<'a>(pub &'a [(String, u8)]);

impl IndexedUnknowns<'_> {
    /// How many unknowns are named before the count of the rest.
    pub const SHOWN: usize = 8;
}

impl std::fmt::Display for IndexedUnknowns<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, (name, index)) in self.0.iter().take(Self::SHOWN).enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "`{name}` of index {index}")?;
        }
        match self.0.len().saturating_sub(Self::SHOWN) {
            0 => Ok(()),
            more => write!(f, " and {more} more"),
        }
    }
}

/// Visit two points near `(t, y, y')`, each coordinate and `t` moved by up to 10 % of
/// `1 + |value|` by a fixed deterministic sequence (xorshift64*): where a structure is read off
/// a model, entries that vanish at the given point by coincidence (a pendulum hanging straight
/// down, a road at its zero crossing) are seen at one of these, and the result never depends
/// on a seed the user does not see. `visit` returns whether the point was usable (the model
/// finite there); an unusable one is replaced by one moved ten times less, up to four times,
/// then skipped.
pub(crate) fn visit_nearby_points(
    t: f64,
    y: &[f64],
    yp: &[f64],
    mut visit: impl FnMut(f64, &[f64], &[f64]) -> bool,
) {
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut unit = || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        let bits = state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        bits as f64 / (1u64 << 52) as f64 - 1.0
    };
    let (mut y_moved, mut yp_moved) = (vec![0.0; y.len()], vec![0.0; yp.len()]);
    for _ in 0..2 {
        let mut scale = 0.1;
        for _ in 0..4 {
            let mut moved = |v: f64| v + scale * (1.0 + v.abs()) * unit();
            for (m, &v) in y_moved.iter_mut().zip(y).chain(yp_moved.iter_mut().zip(yp)) {
                *m = moved(v);
            }
            let t_moved = moved(t);
            if visit(t_moved, &y_moved, &yp_moved) {
                break;
            }
            scale *= 0.1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{max_or_nan, Readable};

    #[test]
    fn readable_numbers_at_every_magnitude() {
        assert_eq!(Readable(0.0).to_string(), "0");
        assert_eq!(Readable(-2.5).to_string(), "-2.5");
        assert_eq!(Readable(1e-5).to_string(), "1e-5");
        assert_eq!(Readable(1e308).to_string(), "1e308");
        assert_eq!(Readable(f64::NAN).to_string(), "NaN");
    }

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
