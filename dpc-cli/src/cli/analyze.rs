//! `dpc analyze SYSTEM.toml [--json]`: the linear DPC analysis of `dpc_core::linear`.
//!
//! Input keys: `a`, `b`, `c` (arrays of rows), optional `d` (zero if absent), optional `w`
//! (per output the numbers `w_ij >= 0` of `W_i(s) = prod_j (s + w_ij)`), optional `poles` for
//! `Abar_4 + Bbar_2 K_2` (each a real number or an `[re, im]` pair), optional `prefeedback`
//! (`"auto"`, `"always"`, `"never"`), optional `points` (where to print `H(s)`, each a real or
//! `[re, im]`). Unknown keys are errors.

use std::path::PathBuf;

use clap::Args;
use dpc::core::linear::{analyze, Analysis, AnalysisOptions, LinearSystem, Prefeedback};
use dpc::nalgebra::{Complex, DMatrix};
use serde::Deserialize;

/// Arguments of `dpc analyze`.
#[derive(Args)]
pub struct AnalyzeArgs {
    /// The system, a TOML file with keys a, b, c and optionally d, w, poles, prefeedback, points.
    pub system: PathBuf,
    /// Print the full report as JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Deserialize)]
#[serde(untagged)]
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

fn matrix(name: &str, rows: &[Vec<f64>]) -> Result<DMatrix<f64>, String> {
    let Some(first) = rows.first() else {
        return Err(format!("matrix `{name}` has no rows"));
    };
    let cols = first.len();
    if cols == 0 {
        return Err(format!("matrix `{name}` has an empty first row"));
    }
    for (i, r) in rows.iter().enumerate() {
        if r.len() != cols {
            return Err(format!(
                "matrix `{name}` is ragged: row {i} has {} entries, row 0 has {cols}",
                r.len()
            ));
        }
    }
    Ok(DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j]))
}

/// Parse the TOML text into a system and options.
fn parse(text: &str) -> Result<(LinearSystem, AnalysisOptions), String> {
    let input: Input = toml::from_str(text).map_err(|e| {
        // toml's message spans several lines; keep the promise of one error line.
        e.to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    })?;
    let a = matrix("a", &input.a)?;
    let b = matrix("b", &input.b)?;
    let c = matrix("c", &input.c)?;
    let d = match &input.d {
        Some(d) => matrix("d", d)?,
        None => DMatrix::zeros(c.nrows(), b.ncols()),
    };
    let sys = LinearSystem::new(a, b, c, d).map_err(|e| e.to_string())?;
    let prefeedback = match input.prefeedback.as_deref() {
        None | Some("auto") => Prefeedback::Auto,
        Some("always") => Prefeedback::Always,
        Some("never") => Prefeedback::Never,
        Some(other) => {
            return Err(format!(
                "prefeedback must be \"auto\", \"always\" or \"never\", found {other:?}"
            ))
        }
    };
    let opts = AnalysisOptions {
        w: input.w,
        poles: input.poles.map(|p| p.iter().map(Number::complex).collect()),
        prefeedback,
        transfer_points: input
            .points
            .map(|p| p.iter().map(Number::complex).collect())
            .unwrap_or_default(),
        ..Default::default()
    };
    Ok((sys, opts))
}

/// Run the subcommand.
pub fn run(args: &AnalyzeArgs) -> Result<(), String> {
    let text = std::fs::read_to_string(&args.system)
        .map_err(|e| format!("cannot read {}: {e}", args.system.display()))?;
    let (sys, opts) = parse(&text).map_err(|e| format!("{}: {e}", args.system.display()))?;
    let report = analyze(&sys, &opts).map_err(|e| format!("{}: {e}", args.system.display()))?;
    if args.json {
        let s = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        println!("{s}");
    } else {
        print!(
            "{}",
            text_report(&args.system.display().to_string(), &report)
        );
    }
    Ok(())
}

fn num(x: f64) -> String {
    let x = if x.abs() < 1e-10 { 0.0 } else { x };
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

fn text_report(name: &str, r: &Analysis) -> String {
    let law = &r.law;
    let mut o = String::new();
    o.push_str(&format!("Linear DPC analysis of {name}\n"));
    o.push_str(&format!(
        "  n = {} states, m = {} inputs/outputs\n",
        r.n, r.m
    ));
    match &r.w {
        Some(w) => o.push_str(&format!(
            "  partial stabilisation W_i(s) = prod (s + w): w = {w:?}\n"
        )),
        None => o.push_str("  no partial stabilisation (W = I)\n"),
    }
    o.push_str(&format!(
        "  pencil -Es + F: finite part {}, infinite part {}, index nu = {}\n",
        r.finite_dim,
        r.n - r.finite_dim,
        r.index
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
    for t in &r.transfer {
        o.push_str(&format!(
            "H(s) at s = {}: real part\n",
            cnum(&Complex::new(t.s[0], t.s[1]))
        ));
        let re = DMatrix::from_fn(r.m, r.m, |i, j| t.re[i][j]);
        let im = DMatrix::from_fn(r.m, r.m, |i, j| t.im[i][j]);
        o.push_str(&mat("    ", &re));
        o.push_str("  imaginary part\n");
        o.push_str(&mat("    ", &im));
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
        let (_, opts) = parse(
            "a = [[0.0]]\nb = [[1.0]]\nc = [[1.0]]\npoles = [-2.0]\npoints = [[0.0, 1.0], 2.0]\n",
        )
        .unwrap();
        assert_eq!(opts.poles.unwrap(), vec![Complex::new(-2.0, 0.0)]);
        assert_eq!(
            opts.transfer_points,
            vec![Complex::new(0.0, 1.0), Complex::new(2.0, 0.0)]
        );
    }

    #[test]
    fn number_formatting() {
        assert_eq!(num(-1e-14), "0");
        assert_eq!(num(2.5), "2.5");
        assert_eq!(cnum(&Complex::new(2.5, -5.21634)), "2.5 - 5.2163i");
    }
}
