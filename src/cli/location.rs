//! Where a key of a scenario file was written: `FILE:LINE:COLUMN` for error messages.
//!
//! Errors about a scenario's values name the key as the user wrote it (`x0`, `w.theta`,
//! `design.poles[1]`); [`Source::locate`] turns such a key into the position of its value in
//! the file, or says that the value came from `--set` (or from a default, when the key is
//! absent).

use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

use toml::de::{DeTable, DeValue};

/// The text a scenario was read from, and the keys `--set` replaced in it.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// The file.
    pub path: PathBuf,
    /// Its text.
    pub text: Arc<str>,
    /// The keys set on the command line, as written after `--set`.
    pub overridden: Vec<String>,
}

/// One step of a key path: a table key or an array index.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// `design.poles[1]` -> `design`, `poles`, `1`. Keys may be quoted by backticks in messages;
/// those are not part of the key.
fn steps(key: &str) -> Vec<Step<'_>> {
    let key = key.split(['`', ' ']).next().unwrap_or_default();
    let mut out = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if !name.is_empty() {
            out.push(Step::Key(name));
        }
        while let Some(close) = rest.find(']') {
            match rest[1..close].parse() {
                Ok(i) => out.push(Step::Index(i)),
                Err(_) => return out,
            }
            rest = &rest[close + 1..];
        }
    }
    out
}

/// The byte range of the value at `key` (or of its deepest existing ancestor that is not the
/// whole document), with whether the whole key was found.
fn span_of(text: &str, key: &str) -> Option<(Range<usize>, bool)> {
    let doc = DeTable::parse(text).ok()?;
    let path = steps(key);
    let mut best: Option<Range<usize>> = None;
    let mut table: Option<&DeTable<'_>> = Some(doc.get_ref());
    let mut value: Option<&DeValue<'_>> = None;
    for (depth, step) in path.iter().enumerate() {
        let next = match (step, table, value) {
            (Step::Key(k), Some(t), _) => t
                .iter()
                .find(|(name, _)| name.get_ref().as_ref() == *k)
                .map(|(_, v)| v),
            (Step::Index(i), _, Some(DeValue::Array(items))) => items.get(*i),
            _ => None,
        };
        let Some(next) = next else {
            return best.map(|b| (b, false));
        };
        best = Some(next.span());
        value = Some(next.get_ref());
        table = match next.get_ref() {
            DeValue::Table(t) => Some(t),
            _ => None,
        };
        if depth + 1 == path.len() {
            return best.map(|b| (b, true));
        }
    }
    best.map(|b| (b, false))
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

impl Source {
    /// Where `key`'s value came from: `FILE:LINE:COLUMN` of the value in the file,
    /// `FILE (--set KEY)` when the command line set it, `FILE:LINE:COLUMN` of the closest
    /// enclosing table when only part of the key is written, or `FILE` when none of it is
    /// (the value is a default).
    pub fn locate(&self, key: &str) -> String {
        let file = self.path.display();
        let set = self.overridden.iter().find(|o| {
            key == o.as_str()
                || key.starts_with(&format!("{o}."))
                || key.starts_with(&format!("{o}["))
        });
        if let Some(o) = set {
            return format!("{file} (--set {o})");
        }
        match span_of(&self.text, key) {
            Some((span, _)) => {
                let (line, column) = line_column(&self.text, span.start);
                format!("{file}:{line}:{column}")
            }
            None => file.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn source(text: &str, overridden: &[&str]) -> Source {
        Source {
            path: "s.toml".into(),
            text: text.into(),
            overridden: overridden.iter().map(|s| s.to_string()).collect(),
        }
    }

    #[test]
    fn keys_are_found_where_they_are_written() {
        let text = "model = \"wheel\"\nx0 = [1.0, 2.0,\n  3.0]\n\n[design]\npoles = [-5.0, [-1.0, 2.0]]\nnominal = { state = [0.0] }\n[w]\ntheta = [5.0]\n";
        let s = source(text, &[]);
        assert_eq!(s.locate("x0"), "s.toml:2:6");
        assert_eq!(s.locate("x0[2]"), "s.toml:3:3");
        assert_eq!(s.locate("design.poles[1]"), "s.toml:6:16");
        assert_eq!(s.locate("design.nominal.state"), "s.toml:7:21");
        assert_eq!(s.locate("w.theta"), "s.toml:9:9");
        // Absent below a written table: the table; absent at the top: the file alone.
        assert_eq!(s.locate("design.about"), "s.toml:5:1");
        assert_eq!(s.locate("limits.samples"), "s.toml");
    }

    #[test]
    fn overridden_keys_name_the_command_line() {
        let s = source("h = 0.05\n[plant]\nrtol = 1e-6\n", &["plant"]);
        assert_eq!(s.locate("plant.rtol"), "s.toml (--set plant)");
        assert_eq!(s.locate("h"), "s.toml:1:5");
    }

    #[test]
    fn columns_count_characters() {
        assert_eq!(line_column("a = \"é\"\nb = 1", 11), (2, 3));
        assert_eq!(line_column("ab", 99), (1, 3));
    }
}
