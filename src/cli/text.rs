//! How values are quoted back to the user in messages: numbers readable at any magnitude
//! ([`Num`]), long lists and long texts as a short excerpt ([`excerpt`], [`short`]).
//!
//! ```
//! use dpc::cli::text::{excerpt, short, Num};
//!
//! assert_eq!(Num(0.05).to_string(), "0.05");
//! assert_eq!(Num(1e-300).to_string(), "1e-300");
//! assert_eq!(Num(5e13).to_string(), "5e13");
//! assert_eq!(Num(f64::INFINITY).to_string(), "inf");
//! let long: Vec<f64> = (0..200_000).map(f64::from).collect();
//! assert_eq!(excerpt(&long), "[0, 1, 2, 3, ... (200000 entries)]");
//! assert_eq!(excerpt(&[1.5, 2.0]), "[1.5, 2]");
//! assert_eq!(short(&"x".repeat(500)).len(), 80 + "... (500 characters)".len());
//! ```

/// A number as a person would write it: plain decimals between `1e-4` and `1e9`, scientific
/// notation outside (never hundreds of zeros), `inf`, `-inf` and `NaN` by name. The one
/// formatter of numbers in messages, shared with the closed loop's divergence causes.
pub use dpc::core::numeric::Readable as Num;

/// How many entries of a list a message quotes.
const EXCERPT_ENTRIES: usize = 4;

/// How many characters of a text a message quotes.
const EXCERPT_CHARS: usize = 80;

/// A list of numbers as `[a, b, c]`, or its first few entries and its length when it is
/// longer than a message should quote.
pub fn excerpt(values: &[f64]) -> String {
    let shown: Vec<String> = values
        .iter()
        .take(EXCERPT_ENTRIES)
        .map(|v| Num(*v).to_string())
        .collect();
    if values.len() > EXCERPT_ENTRIES {
        format!("[{}, ... ({} entries)]", shown.join(", "), values.len())
    } else {
        format!("[{}]", shown.join(", "))
    }
}

/// A text cut to its first characters, with its length, when it is longer than a message
/// should quote.
pub fn short(text: &str) -> String {
    let count = text.chars().count();
    if count <= EXCERPT_CHARS {
        text.to_string()
    } else {
        let head: String = text.chars().take(EXCERPT_CHARS).collect();
        format!("{head}... ({count} characters)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_readable_at_every_magnitude() {
        assert_eq!(Num(0.0).to_string(), "0");
        assert_eq!(Num(-2.5).to_string(), "-2.5");
        assert_eq!(Num(1e-3).to_string(), "0.001");
        assert_eq!(Num(1e-5).to_string(), "1e-5");
        assert_eq!(Num(1e308).to_string(), "1e308");
        assert_eq!(Num(f64::NEG_INFINITY).to_string(), "-inf");
        assert_eq!(Num(f64::NAN).to_string(), "NaN");
        assert!(Num(f64::MIN_POSITIVE).to_string().len() < 30);
    }

    #[test]
    fn excerpts_are_short() {
        assert_eq!(excerpt(&[]), "[]");
        assert_eq!(excerpt(&[1.0, 2.0, 3.0, 4.0]), "[1, 2, 3, 4]");
        assert_eq!(
            excerpt(&[1.0, 2.0, 3.0, 4.0, 5.0]),
            "[1, 2, 3, 4, ... (5 entries)]"
        );
        assert_eq!(short("abc"), "abc");
        let cut = short(&"é".repeat(100));
        assert!(cut.starts_with(&"é".repeat(80)), "{cut}");
        assert!(cut.ends_with("... (100 characters)"), "{cut}");
    }
}
