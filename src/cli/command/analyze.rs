//! `dpc analyze SYSTEM.toml [--json]`: the linear DPC analysis of `dpc_core::linear_analysis`.
//!
//! Input keys: `a`, `b`, `c` (arrays of rows), optional `d` (zero if absent), optional `w`
//! (per output the numbers `w_ij >= 0` of `W_i(s) = prod_j (s + w_ij)`), optional `poles` for
//! `Abar_4 + Bbar_2 K_2` (each a real number or an `[re, im]` pair), optional `prefeedback`
//! (`"auto"`, `"always"`, `"never"`), optional `points` (where to print `H(s)`, each a real or
//! `[re, im]`). Unknown keys are errors.
//!
//! Every number is checked before the analysis: finite, and (non-zero entries) between
//! `sqrt(f64::MIN_POSITIVE)` and `sqrt(f64::MAX)` in magnitude, where products of two stay
//! representable. A point of `points` at a pole of `H` (an eigenvalue of `a` to working
//! precision) is reported as a pole: `pole` in the text, `"pole": true` (and no `re`, `im`)
//! in the JSON. Infinite numbers are written as `"inf"` in the JSON; a quantity of the
//! analysis that comes out NaN is an error naming it, never a value beside a verdict.

use std::path::PathBuf;

use clap::Args;

use crate::cli::command::sayln;
use dpc::core::linear_analysis::transfer::transfer_matrix;
use dpc::core::linear_analysis::{
    analyze, Analysis, AnalysisOptions, LinearError, LinearSystem, PrefeedbackPolicy,
};
use dpc::nalgebra::{Complex, DMatrix};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::cli::json::JsonError;
use crate::cli::scenario::{check_scalar, check_w_roots, ValueError};
use crate::cli::text::short;
use crate::cli::ScenarioError;

/// Arguments of `dpc analyze`.
#[derive(Args)]
pub struct AnalyzeArgs {
    /// The system, a TOML file with keys a, b, c and optionally d, w, poles, prefeedback, points.
    pub system: PathBuf,
    /// Print the full report as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// The most states the system may have: the analysis is dense, its work grows like
    /// n^3 and its memory like n^2, so a larger system is refused before it is read.
    #[arg(long, value_name = "N", default_value_t = 2_000)]
    pub max_states: usize,
}

/// Bytes of text per state that a system file with `n` states may need (about ten numbers
/// of 24 characters per row of `a`, `b`, `c` and a margin): a longer file is refused
/// before it is read.
const BYTES_PER_STATE: u64 = 24 * 2_000 + 1_000;

/// Why `dpc analyze` gave no report; each names the file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AnalyzeError {
    /// The system is larger than `--max-states` allows.
    #[error("{path}: {what} exceeds --max-states = {limit}; raise it deliberately (--max-states N) if the system is meant to be this large")]
    TooLarge {
        /// The file.
        path: String,
        /// What is too large (`a` has 200000 rows; the file has 4.8 GB).
        what: String,
        /// The limit in force.
        limit: usize,
    },
    /// The file could not be read.
    #[error("cannot read {path}: {message}")]
    Read {
        /// The file.
        path: String,
        /// The system's reason.
        message: String,
    },
    /// The TOML is malformed, has an unknown key or a value of the wrong type.
    #[error("{origin}: {message}")]
    Syntax {
        /// `FILE:LINE:COLUMN` where TOML gives a position.
        origin: String,
        /// What is wrong.
        message: String,
    },
    /// A matrix is not a rectangular array of rows.
    #[error("{path}: matrix `{name}` {problem}")]
    Matrix {
        /// The file.
        path: String,
        /// The matrix's key.
        name: &'static str,
        /// What is wrong with its shape.
        problem: MatrixProblem,
    },
    /// A number is out of range.
    #[error("{path}: {cause}")]
    Value {
        /// The file.
        path: String,
        /// The number, by its key.
        cause: ValueError,
    },
    /// `prefeedback` is not one of the three choices.
    #[error(
        "{path}: prefeedback must be \"auto\", \"always\" or \"never\", found \"{}\"",
        short(found)
    )]
    Prefeedback {
        /// The file.
        path: String,
        /// The value given.
        found: String,
    },
    /// The system or the analysis is not well posed.
    #[error("{path}: {cause}")]
    Linear {
        /// The file.
        path: String,
        /// What the analysis found.
        cause: LinearError,
    },
    /// A quantity of the analysis could not be computed in double precision.
    #[error("{path}: the analysis {cause}, so its verdicts cannot be trusted; are the entries of the matrices of very different scales?")]
    NotComputed {
        /// The file.
        path: String,
        /// The quantity.
        cause: JsonError,
    },
}

/// What is wrong with the shape of a matrix.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum MatrixProblem {
    /// `[]`.
    #[error("has no rows")]
    NoRows,
    /// `[[]]`.
    #[error("has an empty first row")]
    EmptyRow,
    /// Rows of different lengths.
    #[error("is ragged: row {row} has {found} entries, row 0 has {expected}")]
    Ragged {
        /// The row.
        row: usize,
        /// Its length.
        found: usize,
        /// The length of row 0.
        expected: usize,
    },
}

#[derive(Deserialize)]
#[serde(untagged, expecting = "a real number or an [re, im] pair")]
enum Number {
    Real(f64),
    Pair([f64; 2]),
}

impl Number {
    fn complex(&self) -> Complex<f64> {
        match *self {
            Number::Real(r) => Complex::new(r, 0.0),
            Number::Pair([re, im]) => Complex::new(re, im),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    a: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    c: Vec<Vec<f64>>,
    d: Option<Vec<Vec<f64>>>,
    w: Option<Vec<Vec<f64>>>,
    poles: Option<Vec<Number>>,
    prefeedback: Option<String>,
    points: Option<Vec<Number>>,
}

/// Why the input could not be turned into a system (the file is added by the caller).
enum ParseError {
    Syntax(ScenarioError),
    Matrix(&'static str, MatrixProblem),
    Value(ValueError),
    Prefeedback(String),
    Linear(LinearError),
}

impl ParseError {
    fn with_path(self, path: &str) -> AnalyzeError {
        let path = path.to_string();
        match self {
            ParseError::Syntax(ScenarioError::Invalid { origin, message }) => {
                AnalyzeError::Syntax { origin, message }
            }
            ParseError::Syntax(other) => AnalyzeError::Syntax {
                origin: path,
                message: other.to_string(),
            },
            ParseError::Matrix(name, problem) => AnalyzeError::Matrix {
                path,
                name,
                problem,
            },
            ParseError::Value(cause) => AnalyzeError::Value { path, cause },
            ParseError::Prefeedback(found) => AnalyzeError::Prefeedback { path, found },
            ParseError::Linear(cause) => AnalyzeError::Linear { path, cause },
        }
    }
}

/// A matrix from rows; every entry finite and, unless zero, between
/// `sqrt(f64::MIN_POSITIVE)` and `sqrt(f64::MAX)` in magnitude.
fn matrix(name: &'static str, rows: &[Vec<f64>]) -> Result<DMatrix<f64>, ParseError> {
    let Some(first) = rows.first() else {
        return Err(ParseError::Matrix(name, MatrixProblem::NoRows));
    };
    let cols = first.len();
    if cols == 0 {
        return Err(ParseError::Matrix(name, MatrixProblem::EmptyRow));
    }
    for (i, r) in rows.iter().enumerate() {
        if r.len() != cols {
            return Err(ParseError::Matrix(
                name,
                MatrixProblem::Ragged {
                    row: i,
                    found: r.len(),
                    expected: cols,
                },
            ));
        }
    }
    let smallest = f64::MIN_POSITIVE.sqrt();
    for (i, r) in rows.iter().enumerate() {
        for (j, &v) in r.iter().enumerate() {
            let key = format!("{name}[{i}][{j}]");
            check_scalar(&key, v).map_err(ParseError::Value)?;
            if v != 0.0 && v.abs() < smallest {
                return Err(ParseError::Value(ValueError::TooSmall {
                    key,
                    value: v,
                    limit: smallest,
                }));
            }
        }
    }
    Ok(DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j]))
}

/// Finite numbers within range, by key (`poles[1]`), as complex numbers.
fn complex_list(key: &str, numbers: &[Number]) -> Result<Vec<Complex<f64>>, ParseError> {
    numbers
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let z = n.complex();
            let key = format!("{key}[{i}]");
            check_scalar(&key, z.re).map_err(ParseError::Value)?;
            check_scalar(&key, z.im).map_err(ParseError::Value)?;
            Ok(z)
        })
        .collect()
}

/// Parse the TOML text into a system, options and the points where `H(s)` is asked for.
fn parse(
    origin: &str,
    text: &str,
) -> Result<(LinearSystem, AnalysisOptions, Vec<Complex<f64>>), ParseError> {
    let input: Input = toml::from_str(text)
        .map_err(|e| ParseError::Syntax(crate::cli::toml_error(origin, text, &e)))?;
    let a = matrix("a", &input.a)?;
    let b = matrix("b", &input.b)?;
    let c = matrix("c", &input.c)?;
    let d = match &input.d {
        Some(d) => matrix("d", d)?,
        None => DMatrix::zeros(c.nrows(), b.ncols()),
    };
    let sys = LinearSystem::new(a, b, c, d).map_err(ParseError::Linear)?;
    let prefeedback = match input.prefeedback.as_deref() {
        None | Some("auto") => PrefeedbackPolicy::Auto,
        Some("always") => PrefeedbackPolicy::Always,
        Some("never") => PrefeedbackPolicy::Never,
        Some(other) => return Err(ParseError::Prefeedback(other.to_string())),
    };
    for (i, roots) in input.w.iter().flatten().enumerate() {
        check_w_roots(&format!("w[{i}]"), roots).map_err(ParseError::Value)?;
    }
    let poles = match &input.poles {
        Some(p) => Some(complex_list("poles", p)?),
        None => None,
    };
    let points = match &input.points {
        Some(p) => complex_list("points", p)?,
        None => Vec::new(),
    };
    let opts = AnalysisOptions {
        w: input.w,
        poles,
        prefeedback,
        ..Default::default()
    };
    Ok((sys, opts, points))
}

/// `H(s)` of the system at a requested point, or the pole it sits on.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
enum TransferPoint {
    /// `H(s)`.
    Value {
        /// The point `[re, im]`.
        s: [f64; 2],
        /// Real parts of `H(s)`, rows.
        re: Vec<Vec<f64>>,
        /// Imaginary parts of `H(s)`, rows.
        im: Vec<Vec<f64>>,
    },
    /// `s` is an eigenvalue of `a` to working precision: `H` has a pole there.
    Pole {
        /// The point `[re, im]`.
        s: [f64; 2],
        /// Always `true`.
        pole: bool,
    },
}

fn transfer_at(sys: &LinearSystem, s: Complex<f64>) -> TransferPoint {
    let rows = |m: DMatrix<f64>| -> Vec<Vec<f64>> {
        m.row_iter().map(|r| r.iter().copied().collect()).collect()
    };
    match transfer_matrix(sys, s) {
        Some(h) if h.iter().all(|z| z.re.is_finite() && z.im.is_finite()) => TransferPoint::Value {
            s: [s.re, s.im],
            re: rows(h.map(|z| z.re)),
            im: rows(h.map(|z| z.im)),
        },
        _ => TransferPoint::Pole {
            s: [s.re, s.im],
            pole: true,
        },
    }
}

/// Run the subcommand.
///
/// # Errors
/// [`AnalyzeError`] naming the file and, for a value, its key.
pub fn run(args: &AnalyzeArgs) -> Result<(), AnalyzeError> {
    let path = args.system.display().to_string();
    // A file far longer than a system of --max-states states can be is refused unread.
    let limit_bytes = (args.max_states as u64).saturating_mul(BYTES_PER_STATE);
    if let Ok(meta) = std::fs::metadata(&args.system) {
        if meta.len() > limit_bytes {
            return Err(AnalyzeError::TooLarge {
                path,
                what: format!(
                    "the file has {} bytes, more than a system of that many states needs ({limit_bytes}); it",
                    meta.len()
                ),
                limit: args.max_states,
            });
        }
    }
    let text = std::fs::read_to_string(&args.system).map_err(|e| AnalyzeError::Read {
        path: path.clone(),
        message: e.to_string(),
    })?;
    let (sys, opts, points) = parse(&path, &text).map_err(|e| e.with_path(&path))?;
    if sys.n() > args.max_states {
        return Err(AnalyzeError::TooLarge {
            path,
            what: format!("`a` has {} states, which", sys.n()),
            limit: args.max_states,
        });
    }
    let report = analyze(&sys, &opts).map_err(|cause| AnalyzeError::Linear {
        path: path.clone(),
        cause,
    })?;
    let transfer: Vec<TransferPoint> = points.iter().map(|&s| transfer_at(&sys, s)).collect();
    let not_computed = |cause| AnalyzeError::NotComputed {
        path: path.clone(),
        cause,
    };
    // Checked before anything is printed: no verdict beside a NaN.
    let json = crate::cli::json::to_string_pretty(&report).map_err(not_computed)?;
    let transfer_json = crate::cli::json::to_string_pretty(&transfer).map_err(not_computed)?;
    if args.json {
        // Both texts are JSON with infinities as "inf"; join them as values.
        let mut value: serde_json::Value = serde_json::from_str(&json)
            .map_err(|e| not_computed(JsonError::Other(e.to_string())))?;
        value["transfer"] = serde_json::from_str(&transfer_json)
            .map_err(|e| not_computed(JsonError::Other(e.to_string())))?;
        let s = serde_json::to_string_pretty(&value)
            .map_err(|e| not_computed(JsonError::Other(e.to_string())))?;
        sayln!("{s}");
    } else {
        crate::cli::command::say(format_args!("{}", text_report(&path, &report, &transfer)));
    }
    Ok(())
}

fn num(x: f64) -> String {
    let x = if x.abs() < 1e-10 { 0.0 } else { x };
    if !x.is_finite() {
        return crate::cli::text::Num(x).to_string();
    }
    if x.abs() >= 1e9 {
        // Four decimals of the mantissa, never hundreds of digits.
        let s = format!("{x:.4e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}e{exponent}");
    }
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn cnum(z: &Complex<f64>) -> String {
    // Imaginary parts that do not show at the printed precision are left out.
    if num(z.im.abs()) == "0" {
        num(z.re)
    } else if z.im > 0.0 {
        format!("{} + {}i", num(z.re), num(z.im))
    } else {
        format!("{} - {}i", num(z.re), num(-z.im))
    }
}

fn clist(v: &[Complex<f64>]) -> String {
    if v.is_empty() {
        return "(none)".into();
    }
    v.iter().map(cnum).collect::<Vec<_>>().join(", ")
}

fn mat(indent: &str, m: &DMatrix<f64>) -> String {
    let cells: Vec<Vec<String>> = (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| num(m[(i, j)])).collect())
        .collect();
    let width = cells.iter().flatten().map(String::len).max().unwrap_or(1);
    let mut out = String::new();
    for row in cells {
        let line: Vec<String> = row.iter().map(|c| format!("{c:>width$}")).collect();
        out.push_str(&format!("{indent}[ {} ]\n", line.join("  ")));
    }
    out
}

fn poly(indent: &str, coefs: &[DMatrix<f64>]) -> String {
    let mut out = String::new();
    for (k, r) in coefs.iter().enumerate() {
        out.push_str(&format!("{indent}R_{k} (coefficient of s^{k}):\n"));
        out.push_str(&mat(&format!("{indent}  "), r));
    }
    out
}

fn verdict(stable: bool) -> &'static str {
    if stable {
        "STABLE"
    } else {
        "UNSTABLE"
    }
}

fn text_report(name: &str, r: &Analysis, transfer: &[TransferPoint]) -> String {
    let law = &r.law;
    let mut o = String::new();
    o.push_str(&format!("Linear DPC analysis of {name}\n"));
    o.push_str(&format!(
        "  n = {} states, m = {} inputs/outputs\n",
        r.n, r.m
    ));
    match &r.w {
        Some(w) => o.push_str(&format!(
            "  partial stabilisation W_i(s) = prod (s + w): w = [{}]\n",
            w.iter()
                .map(|roots| format!(
                    "[{}]",
                    roots.iter().map(|v| num(*v)).collect::<Vec<_>>().join(", ")
                ))
                .collect::<Vec<_>>()
                .join(", ")
        )),
        None => o.push_str("  no partial stabilisation (W = I)\n"),
    }
    o.push_str(&format!(
        "  pencil -Es + F: finite part {}, infinite part {}, nilpotency index nu = {}\n",
        r.finite_dim,
        r.n - r.finite_dim,
        r.nu
    ));
    o.push_str(&format!(
        "  transmission zeros (eig A_1): {}{}\n",
        clist(&r.transmission_zeros),
        if r.minimum_phase {
            ""
        } else {
            "  (NOT minimum phase)"
        }
    ));
    o.push_str(&format!(
        "  eig(Abar_4): {}  ({})\n",
        clist(&r.abar4_eigenvalues),
        if law.abar4_stable {
            "stable"
        } else {
            "unstable"
        }
    ));
    o.push_str(&format!(
        "  eig(A + B K_J): {}\n",
        clist(&r.closed_loop_eigenvalues)
    ));
    o.push_str(&format!("  verdict: DPC is {}\n", verdict(r.dpc_stable)));
    o.push_str("  K_J =\n");
    o.push_str(&mat("    ", &r.k_j));
    o.push_str("  R_xi(s) = sum R_k s^k:\n");
    o.push_str(&poly("    ", &r.r_xi));
    if let (Some(k_n), Some(poles)) = (&r.k_n, &r.poles) {
        o.push_str(&format!(
            "Preliminary feedback u = K_n x + v (poles of Abar_4 + Bbar_2 K_2: {})\n",
            clist(poles)
        ));
        o.push_str("  K_n = [0 K_2] Q^-1 =\n");
        o.push_str(&mat("    ", k_n));
        if let Some(cl) = &r.closed_loop_eigenvalues_prefeedback {
            o.push_str(&format!("  eig(A + B (K_n + K_J')): {}\n", clist(cl)));
        }
        if let Some(rx) = &r.r_xi_prefeedback {
            o.push_str("  R_xi(s) after the preliminary feedback:\n");
            o.push_str(&poly("    ", rx));
        }
        if let Some(s) = r.dpc_stable_prefeedback {
            o.push_str(&format!(
                "  verdict: DPC with preliminary feedback is {}\n",
                verdict(s)
            ));
        }
    }
    if let Some(e) = &r.prefeedback_error {
        o.push_str(&format!("No preliminary feedback could be built: {e}\n"));
    }
    for t in transfer {
        match t {
            TransferPoint::Value { s, re, im } => {
                o.push_str(&format!(
                    "H(s) at s = {}: real part\n",
                    cnum(&Complex::new(s[0], s[1]))
                ));
                o.push_str(&mat("    ", &DMatrix::from_fn(r.m, r.m, |i, j| re[i][j])));
                o.push_str("  imaginary part\n");
                o.push_str(&mat("    ", &DMatrix::from_fn(r.m, r.m, |i, j| im[i][j])));
            }
            TransferPoint::Pole { s, .. } => o.push_str(&format!(
                "H(s) at s = {}: pole (s is an eigenvalue of A to working precision)\n",
                cnum(&Complex::new(s[0], s[1]))
            )),
        }
    }
    let tol = &law.tolerances;
    o.push_str("Checks\n");
    o.push_str(&format!(
        "  Theorem 3.1 a) residual {:.1e}; V* dimension {} vs finite part {} (distance {:.1e})\n",
        law.theorem_3_1_residual, law.vstar_dim, law.finite_dim, law.vstar_distance
    ));
    o.push_str(&format!(
        "  Theorem 3.3 residual |H_b R_xi - I| {:.1e}\n",
        law.theorem_3_3_residual
    ));
    o.push_str(&format!(
        "  rank decisions: factor {}, [B; D] sigma_min {:.3e} > tol {:.1e}; pencil tol {:.1e}, gap {}; cond Q {:.2e}, cond M^-1 {:.2e}\n",
        tol.tol_factor,
        tol.compress_sigma_min,
        tol.compress_tol,
        tol.pencil_tol,
        tol.pencil_gap.map_or("none".into(), |g| format!("{g:.1e}")),
        tol.cond_q,
        tol.cond_m_inv
    ));
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poles_accept_reals_and_pairs() {
        let Ok((_, opts, points)) = parse(
            "s.toml",
            "a = [[0.0]]\nb = [[1.0]]\nc = [[1.0]]\npoles = [-2.0]\npoints = [[0.0, 1.0], 2.0]\n",
        ) else {
            panic!("parses")
        };
        assert_eq!(opts.poles.unwrap(), vec![Complex::new(-2.0, 0.0)]);
        assert_eq!(points, vec![Complex::new(0.0, 1.0), Complex::new(2.0, 0.0)]);
    }

    #[test]
    fn number_formatting() {
        assert_eq!(num(-1e-14), "0");
        assert_eq!(num(2.5), "2.5");
        assert_eq!(cnum(&Complex::new(2.5, -5.21634)), "2.5 - 5.2163i");
        assert_eq!(num(8.46e299), "8.46e299");
        assert_eq!(num(-1e300), "-1e300");
        assert_eq!(num(f64::INFINITY), "inf");
    }
}
