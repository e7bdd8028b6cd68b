//! Parameter sweeps: every combination of `--set key=v1,v2,...` values run in parallel, one
//! summary table and a plot of the late tracking error against the first numeric parameter.

use std::io::Write;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::plot::{sweep_figure, SweepSeries};
use crate::registry::Registry;
use crate::report::{write_run, Summary};
use crate::scenario::{parse_value, split_assignment, value_text, Overrides, Scenario};
use crate::ScenarioError;

/// One swept key and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Dotted scenario key.
    pub key: String,
    /// Values, in the order given.
    pub values: Vec<toml::Value>,
}

impl Axis {
    /// Parse `key=v1,v2,...`; commas inside brackets or quotes belong to a value.
    ///
    /// # Errors
    /// [`ScenarioError::Override`] for a missing `=`, an empty key or an empty value.
    pub fn parse(text: &str) -> Result<Self, ScenarioError> {
        let (key, values) = split_assignment(text)?;
        let mut out = Vec::new();
        let (mut depth, mut quoted, mut start) = (0_i32, false, 0);
        let bytes = values.as_bytes();
        for (i, &b) in bytes.iter().enumerate() {
            match b {
                b'"' => quoted = !quoted,
                b'[' | b'{' if !quoted => depth += 1,
                b']' | b'}' if !quoted => depth -= 1,
                b',' if !quoted && depth == 0 => {
                    out.push(&values[start..i]);
                    start = i + 1;
                }
                _ => {}
            }
        }
        out.push(&values[start..]);
        if out.iter().any(|v| v.trim().is_empty()) {
            return Err(ScenarioError::Override(format!(
                "`{text}` has an empty value; expected key=v1,v2,..."
            )));
        }
        Ok(Self {
            key: key.to_string(),
            values: out.into_iter().map(|v| parse_value(v.trim())).collect(),
        })
    }

    fn numeric(&self) -> Option<Vec<f64>> {
        self.values
            .iter()
            .map(|v| match v {
                toml::Value::Float(f) => Some(*f),
                toml::Value::Integer(i) => Some(*i as f64),
                _ => None,
            })
            .collect()
    }
}

/// Every combination of the axes' values (the last axis varies fastest).
pub fn combinations(axes: &[Axis]) -> Vec<Overrides> {
    let mut out = vec![Overrides::default()];
    for axis in axes {
        let mut next = Vec::with_capacity(out.len() * axis.values.len());
        for base in &out {
            for v in &axis.values {
                let mut o = base.clone();
                o.0.push((axis.key.clone(), v.clone()));
                next.push(o);
            }
        }
        out = next;
    }
    out
}

/// The outcome of one combination.
#[derive(Debug, Clone)]
pub struct SweepRow {
    /// The overrides of this run.
    pub overrides: Overrides,
    /// Its summary, or why it could not run.
    pub outcome: Result<Summary, String>,
}

/// Run every combination of `axes` on the scenario at `path`, writing per-run results under
/// `out/runs/`, the table `out/summary.csv` and the plot `out/sweep.{svg,png}`.
///
/// Combinations that are invalid (for example `delta >= h`) are recorded as errors in the
/// table; a scenario file that cannot be read at all is an error of the sweep.
///
/// # Errors
/// [`ScenarioError`] when the scenario file is malformed or outputs cannot be written.
pub fn sweep(
    registry: &Registry,
    path: &Path,
    axes: &[Axis],
    out: &Path,
    progress: bool,
) -> Result<Vec<SweepRow>, ScenarioError> {
    Scenario::load(path, &Overrides::default())?;
    let combos = combinations(axes);
    let runs_dir = out.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(|e| ScenarioError::Write {
        path: runs_dir.display().to_string(),
        message: e.to_string(),
    })?;
    let bar = if progress {
        ProgressBar::new(combos.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let rows: Vec<SweepRow> = combos
        .into_par_iter()
        .map(|overrides| {
            let label = overrides.label();
            let outcome = Scenario::load(path, &overrides)
                .and_then(|s| registry.run(&s, &label))
                .and_then(|r| write_run(&runs_dir.join(dir_name(&label)), &r))
                .map_err(|e| e.to_string());
            bar.inc(1);
            SweepRow { overrides, outcome }
        })
        .collect();
    bar.finish_and_clear();
    write_table(&out.join("summary.csv"), axes, &rows)?;
    let (parameter, series) = plot_series(axes, &rows);
    sweep_figure(&out.join("sweep"), &parameter, &series)?;
    Ok(rows)
}

/// A directory name for a run label (no path separators or quotes).
fn dir_name(label: &str) -> PathBuf {
    let clean: String = label
        .chars()
        .map(|c| match c {
            '/' | '\\' | '"' | '\'' | ' ' | ':' | '*' | '?' | '<' | '>' | '|' => '_',
            c => c,
        })
        .collect();
    PathBuf::from(if clean.is_empty() {
        "main".into()
    } else {
        clean
    })
}

fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

fn write_table(path: &Path, axes: &[Axis], rows: &[SweepRow]) -> Result<(), ScenarioError> {
    let err = |e: std::io::Error| ScenarioError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let outputs: Vec<String> = rows
        .iter()
        .find_map(|r| r.outcome.as_ref().ok())
        .map(|s| s.max_abs_error.keys().cloned().collect())
        .unwrap_or_default();
    let mut header: Vec<String> = axes.iter().map(|a| a.key.clone()).collect();
    header.extend(["status".into(), "t_diverged".into()]);
    header.extend(outputs.iter().map(|o| format!("max_abs_error_{o}")));
    header.extend(outputs.iter().map(|o| format!("final_error_{o}")));
    header.extend(
        [
            "samples",
            "newton_iterations",
            "retries",
            "failed_samples",
            "wall_time_s",
            "message",
        ]
        .map(String::from),
    );
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(err)?);
    writeln!(f, "{}", header.join(",")).map_err(err)?;
    for row in rows {
        let mut fields: Vec<String> = row
            .overrides
            .0
            .iter()
            .map(|(_, v)| csv_field(&value_text(v)))
            .collect();
        match &row.outcome {
            Ok(s) => {
                fields.push(if s.diverged { "diverged" } else { "ok" }.into());
                fields.push(s.t_diverged.map_or(String::new(), |t| format!("{t}")));
                for o in &outputs {
                    fields.push(format!(
                        "{:e}",
                        s.max_abs_error.get(o).copied().unwrap_or(f64::NAN)
                    ));
                }
                for o in &outputs {
                    fields.push(format!(
                        "{:e}",
                        s.final_error.get(o).copied().unwrap_or(f64::NAN)
                    ));
                }
                fields.extend([
                    s.samples.to_string(),
                    s.newton_iterations.to_string(),
                    s.retries.to_string(),
                    s.failed_samples.to_string(),
                    format!("{:.4}", s.wall_time_s),
                    csv_field(s.divergence_cause.as_deref().unwrap_or("")),
                ]);
            }
            Err(message) => {
                fields.push("error".into());
                fields.extend(std::iter::repeat_n(
                    String::new(),
                    1 + 2 * outputs.len() + 5,
                ));
                fields.push(csv_field(message));
            }
        }
        writeln!(f, "{}", fields.join(",")).map_err(err)?;
    }
    f.flush().map_err(err)
}

/// The x axis is the first axis with numeric values (else the run index); one series per
/// combination of the other axes.
fn plot_series(axes: &[Axis], rows: &[SweepRow]) -> (String, Vec<SweepSeries>) {
    let x_axis = axes.iter().position(|a| a.numeric().is_some());
    let parameter = x_axis.map_or("run".to_string(), |i| axes[i].key.clone());
    let mut series: Vec<SweepSeries> = Vec::new();
    for (index, row) in rows.iter().enumerate() {
        let (x, name) = match x_axis {
            Some(i) => {
                let x = axes[i].numeric().map_or(f64::NAN, |v| {
                    let pos = axes[i]
                        .values
                        .iter()
                        .position(|v| Some(v) == row.overrides.0.get(i).map(|p| &p.1));
                    pos.map_or(f64::NAN, |p| v[p])
                });
                let others: Vec<String> = row
                    .overrides
                    .0
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != i)
                    .map(|(_, (k, v))| format!("{k}={}", value_text(v)))
                    .collect();
                (
                    x,
                    if others.is_empty() {
                        "all".into()
                    } else {
                        others.join(", ")
                    },
                )
            }
            None => (index as f64, "runs".to_string()),
        };
        let y = match &row.outcome {
            Ok(s) if !s.diverged => Some(s.worst_late_error()),
            _ => None,
        };
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push((x, y)),
            None => series.push(SweepSeries {
                name,
                points: vec![(x, y)],
            }),
        }
    }
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    (parameter, series)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_split_values_outside_brackets() {
        let a = Axis::parse("x0=[1.0, 2.0],[3.0, 4.0]").unwrap();
        assert_eq!(a.key, "x0");
        assert_eq!(a.values.len(), 2);
        let a = Axis::parse("h = 0.01, 0.05,0.1").unwrap();
        assert_eq!(a.numeric().unwrap(), vec![0.01, 0.05, 0.1]);
        let a = Axis::parse("hold=input,correction").unwrap();
        assert!(a.numeric().is_none());
        assert!(Axis::parse("h=0.1,,0.2").is_err());
        assert!(Axis::parse("h").is_err());
    }

    #[test]
    fn combinations_are_the_cartesian_product() {
        let axes = [
            Axis::parse("h=0.01,0.05,0.1").unwrap(),
            Axis::parse("prefeedback=true,false").unwrap(),
        ];
        let c = combinations(&axes);
        assert_eq!(c.len(), 6);
        assert_eq!(c[0].label(), "h=0.01,prefeedback=true");
        assert_eq!(c[5].label(), "h=0.1,prefeedback=false");
        assert_eq!(combinations(&[]).len(), 1);
    }

    #[test]
    fn directory_names_have_no_separators() {
        assert_eq!(dir_name("a/b=\"c d\""), PathBuf::from("a_b=_c_d_"));
        assert_eq!(dir_name(""), PathBuf::from("main"));
    }
}
