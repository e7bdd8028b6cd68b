//! Errors shared by the integrators, the controller, the analysis and the closed loop.

use core::fmt;

use crate::numeric::Readable;

/// An option or argument outside its range: which one, its value and what it must satisfy.
///
/// Displayed as `NAME = VALUE must be REQUIREMENT`, with the value in a readable form (`1e-300`,
/// not three hundred zeros).
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidOption {
    /// Field or argument name as written in the options type or the method signature.
    pub name: &'static str,
    /// The value given (a count is converted to `f64`).
    pub value: f64,
    /// What the value must satisfy, e.g. `"positive and finite"`.
    pub requirement: &'static str,
}

impl InvalidOption {
    /// The option `name` has the value `value`, which is not `requirement`.
    pub fn new(name: &'static str, value: f64, requirement: &'static str) -> Self {
        Self {
            name,
            value,
            requirement,
        }
    }

    /// `Ok(value)` when `value` is positive and finite, else the error naming `name`.
    ///
    /// # Errors
    /// [`InvalidOption`] with the requirement `"positive and finite"`.
    pub fn positive(name: &'static str, value: f64) -> Result<f64, Self> {
        if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(Self::new(name, value, "positive and finite"))
        }
    }
}

impl fmt::Display for InvalidOption {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} = {} must be {}",
            self.name,
            Readable(self.value),
            self.requirement
        )
    }
}

impl std::error::Error for InvalidOption {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_option_and_writes_the_value_readably() {
        let e = InvalidOption::positive("h", 1e-300).map(|_| ());
        assert_eq!(e, Ok(()));
        let e = InvalidOption::positive("h", -1e-300).unwrap_err();
        assert_eq!(e.to_string(), "h = -1e-300 must be positive and finite");
        let e = InvalidOption::positive("rtol", f64::NAN).unwrap_err();
        assert_eq!(e.to_string(), "rtol = NaN must be positive and finite");
    }
}
