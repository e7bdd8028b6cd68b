//! Parameter sweeps: every combination of `--set key=v1,v2,...` values run in parallel, one
//! summary table and a plot of the late tracking error against the first numeric parameter.

use std::io::Write;
use std::path::Path;

use rayon::prelude::*;

use crate::cli::output::{unique_names, Staging};
use crate::cli::plot::{sweep_figure, SweepSeries};
use crate::cli::registry::Registry;
use crate::cli::report::{write_run, Digest};
use crate::cli::scenario::{
    parse_value, split_assignment, value_text, OverrideError, Overrides, Scenario,
};
use crate::cli::ScenarioError;

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
            return Err(ScenarioError::Override(OverrideError::EmptyValue {
                item: text.to_string(),
            }));
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

/// The number of combinations of the axes' values, `None` when it does not fit a `usize`.
pub fn combination_count(axes: &[Axis]) -> Option<usize> {
    axes.iter()
        .try_fold(1_usize, |n, axis| n.checked_mul(axis.values.len()))
}

/// Combination number `index` of the axes' values (the last axis varies fastest), made
/// when asked for: a sweep never holds its combinations in memory.
pub fn combination(axes: &[Axis], mut index: usize) -> Overrides {
    let mut picked = vec![0; axes.len()];
    for (slot, axis) in picked.iter_mut().zip(axes).rev() {
        let n = axis.values.len().max(1);
        *slot = index % n;
        index /= n;
    }
    Overrides(
        axes.iter()
            .zip(picked)
            .map(|(axis, i)| (axis.key.clone(), axis.values[i].clone()))
            .collect(),
    )
}

/// Every combination of the axes' values (the last axis varies fastest), one at a time.
pub fn combinations(axes: &[Axis]) -> impl Iterator<Item = Overrides> + '_ {
    (0..combination_count(axes).unwrap_or(usize::MAX)).map(move |i| combination(axes, i))
}

/// The outcome of one combination.
#[derive(Debug, Clone)]
pub struct SweepRow {
    /// The combination's index ([`combination`]).
    pub index: usize,
    /// The overrides of this run.
    pub overrides: Overrides,
    /// The directory of its results under `runs/`.
    pub directory: String,
    /// What the sweep keeps of its summary, or why it could not run.
    pub outcome: Result<Digest, ScenarioError>,
}

/// Run every combination of `axes` on the scenario at `path`, writing per-run results under
/// `out/runs/`, the table `out/summary.csv` and the plot `out/sweep.{svg,png}`. Everything
/// is written beside `out` first and moved into place at the end ([`Staging`]), so earlier
/// results in `out` are replaced as a whole or not at all.
///
/// Combinations that are invalid (for example `delta >= h`) are recorded as errors in the
/// table; a scenario file that cannot be read at all is an error of the sweep, and so is a
/// sweep in which every run failed (the earlier results then stay).
///
/// # Errors
/// [`ScenarioError`] when the scenario file is malformed, the sweep has more than
/// `max_runs` combinations, every run failed or outputs cannot be written.
pub fn sweep(
    registry: &Registry,
    path: &Path,
    axes: &[Axis],
    out: &Path,
    max_runs: usize,
    progress: bool,
    shard: Shard,
) -> Result<Vec<SweepRow>, ScenarioError> {
    let base = Scenario::load(path, &Overrides::default())?;
    let title = match &base.title {
        Some(t) => format!("{t}: sweep"),
        None => format!("sweep of {}", path.display()),
    };
    let count = combination_count(axes)
        .filter(|n| *n <= max_runs)
        .ok_or_else(|| ScenarioError::TooManyRuns {
            sizes: axes.iter().map(|a| a.values.len()).collect(),
            limit: max_runs,
        })?;
    let staging = Staging::new(out, "summary.csv")?;
    let not_written = |cause| staging.not_written(cause);
    let runs_dir = staging.subdirectory("runs")?;
    // Names over every combination, so that each shard names its runs as a single run would.
    let names = unique_names((0..count).map(|i| combination(axes, i).label()));
    let indices: Vec<usize> = (0..count).filter(|i| shard.contains(*i)).collect();
    let bar = crate::cli::progress::bar(indices.len() as u64, "{pos}/{len} runs", progress);
    let rows: Vec<SweepRow> = indices
        .into_par_iter()
        .map(|index| {
            let overrides = combination(axes, index);
            let label = overrides.label();
            let directory = names[index].clone();
            let outcome = Scenario::load(path, &overrides)
                .and_then(|s| registry.run(&s, &label))
                .and_then(|r| write_run(&runs_dir.join(&directory), &r))
                .map(|summary| summary.digest());
            bar.inc(1);
            SweepRow {
                index,
                overrides,
                directory,
                outcome,
            }
        })
        .collect();
    bar.finish_and_clear();
    if let Some(first) = rows.iter().find_map(|r| r.outcome.as_ref().err()) {
        if rows.iter().all(|r| r.outcome.is_err()) {
            return Err(ScenarioError::SweepFailed {
                runs: rows.len(),
                target: staging.target().display().to_string(),
                previous: staging.had_previous(),
                first: Box::new(first.clone()),
            });
        }
    }
    let manifest = Manifest::new(path, &title, axes, shard, count, &rows);
    write_results(staging.path(), &manifest, axes, &rows).map_err(not_written)?;
    staging.commit()?;
    Ok(rows)
}

/// `summary.csv`, `sweep.{svg,png}` and the manifest `sweep.json` of `rows` into `dir`.
fn write_results(
    dir: &Path,
    manifest: &Manifest,
    axes: &[Axis],
    rows: &[SweepRow],
) -> Result<(), ScenarioError> {
    write_table(&dir.join("summary.csv"), axes, rows)?;
    let (parameter, series) = plot_series(axes, rows);
    sweep_figure(&dir.join("sweep"), &manifest.title, &parameter, &series)?;
    let path = dir.join(MANIFEST);
    let text =
        crate::cli::json::to_string_pretty(manifest).map_err(|cause| ScenarioError::NotFinite {
            path: path.display().to_string(),
            cause,
        })?;
    std::fs::write(&path, text + "\n").map_err(|e| write_error(&path, &e))
}

/// The file in a sweep's output that says which sweep and which part of it the results are.
pub const MANIFEST: &str = "sweep.json";

/// Part `part` of `count` of a sweep (`--shard K/N`): the combinations whose index is
/// `part - 1` modulo `count`. The split depends only on the combinations, so a batch system's
/// job array (Slurm's `--array=1-N`, a Kubernetes indexed job) runs the parts on as many
/// machines, and [`merge`] joins them into the results of a single run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// Which part, from 1.
    pub part: usize,
    /// Of how many.
    pub count: usize,
}

impl Shard {
    /// The whole sweep: part 1 of 1.
    pub const WHOLE: Shard = Shard { part: 1, count: 1 };

    /// Parse `K/N` with `1 <= K <= N`.
    ///
    /// # Errors
    /// [`ScenarioError::Shard`] quoting the text.
    pub fn parse(text: &str) -> Result<Self, ScenarioError> {
        let bad = || ScenarioError::Shard {
            text: crate::cli::text::short(text),
        };
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let part: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if part == 0 || part > count {
            return Err(bad());
        }
        Ok(Self { part, count })
    }

    /// Whether combination `index` belongs to this part.
    pub fn contains(self, index: usize) -> bool {
        index % self.count == self.part - 1
    }
}

/// What a sweep's output holds, for [`merge`]: the sweep (scenario, title, axes as written,
/// number of combinations), the part, and per combination run its index with its digest or
/// its error.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Manifest {
    scenario: String,
    title: String,
    axes: Vec<(String, Vec<String>)>,
    combinations: usize,
    shard: Shard,
    rows: Vec<ManifestRow>,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct ManifestRow {
    index: usize,
    directory: String,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    digest: Option<Digest>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    error: Option<String>,
}

impl Manifest {
    fn new(
        scenario: &Path,
        title: &str,
        axes: &[Axis],
        shard: Shard,
        combinations: usize,
        rows: &[SweepRow],
    ) -> Self {
        Self {
            scenario: scenario.file_name().map_or_else(
                || scenario.display().to_string(),
                |n| n.to_string_lossy().into(),
            ),
            title: title.to_string(),
            axes: axes
                .iter()
                .map(|a| (a.key.clone(), a.values.iter().map(value_text).collect()))
                .collect(),
            combinations,
            shard,
            rows: rows
                .iter()
                .map(|r| ManifestRow {
                    index: r.index,
                    directory: r.directory.clone(),
                    digest: r.outcome.as_ref().ok().cloned(),
                    error: r.outcome.as_ref().err().map(ToString::to_string),
                })
                .collect(),
        }
    }
}

/// Why the parts of a sweep cannot be merged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MergeError {
    /// No directory was given.
    #[error("nothing to merge: give the output directories of the sweep's parts")]
    Nothing,
    /// A directory has no readable manifest.
    #[error("{path}: {message} (not the output of `dpc sweep`?)")]
    Manifest {
        /// The manifest's path.
        path: String,
        /// What is wrong with it.
        message: String,
    },
    /// A part belongs to another sweep than the first.
    #[error("{path} is part of another sweep than {first}: its {what} differs")]
    Mismatch {
        /// The directory that differs.
        path: String,
        /// The first directory.
        first: String,
        /// What differs (`scenario`, `axes`, `number of parts`).
        what: &'static str,
    },
    /// Two directories hold the same part.
    #[error("part {part} of {count} is given twice: {first} and {second}")]
    Duplicate {
        /// The part.
        part: usize,
        /// Of how many.
        count: usize,
        /// The first directory holding it.
        first: String,
        /// The second.
        second: String,
    },
    /// Parts are missing.
    #[error("{} of {count} {} missing", match missing.as_slice() { [one] => format!("part {one}"), _ => format!("parts {}", missing.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")) }, if missing.len() == 1 { "is" } else { "are" })]
    Missing {
        /// The missing parts.
        missing: Vec<usize>,
        /// Of how many.
        count: usize,
    },
}

/// Join the outputs of the parts of a sweep (`dpc sweep ... --shard K/N`, one directory each)
/// into `out`: the runs, `summary.csv`, the figure and the manifest of a single run of the whole
/// sweep. The parts are checked to be the parts of one sweep, each exactly once; they are
/// left as they are, and `out` is written like a sweep's output (atomically).
///
/// # Errors
/// [`ScenarioError::Merge`] when the directories are not the complete parts of one sweep,
/// and the errors of writing the results.
pub fn merge(dirs: &[std::path::PathBuf], out: &Path) -> Result<Vec<SweepRow>, ScenarioError> {
    let merge_error = ScenarioError::Merge;
    let first_dir = dirs.first().ok_or(merge_error(MergeError::Nothing))?;
    let mut parts: Vec<(std::path::PathBuf, Manifest)> = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let path = dir.join(MANIFEST);
        let malformed = |message: String| {
            merge_error(MergeError::Manifest {
                path: path.display().to_string(),
                message,
            })
        };
        let text = std::fs::read_to_string(&path).map_err(|e| malformed(e.to_string()))?;
        let manifest: Manifest =
            serde_json::from_str(&text).map_err(|e| malformed(e.to_string()))?;
        parts.push((dir.clone(), manifest));
    }
    let first = parts[0].1.clone();
    let count = first.shard.count;
    let mut holder: Vec<Option<&Path>> = vec![None; count];
    for (dir, m) in &parts {
        let differs = |what| {
            merge_error(MergeError::Mismatch {
                path: dir.display().to_string(),
                first: first_dir.display().to_string(),
                what,
            })
        };
        if m.scenario != first.scenario || m.title != first.title {
            return Err(differs("scenario"));
        }
        if m.axes != first.axes || m.combinations != first.combinations {
            return Err(differs("axes"));
        }
        if m.shard.count != count || m.shard.part == 0 || m.shard.part > count {
            return Err(differs("number of parts"));
        }
        let slot = &mut holder[m.shard.part - 1];
        if let Some(other) = slot {
            return Err(merge_error(MergeError::Duplicate {
                part: m.shard.part,
                count,
                first: other.display().to_string(),
                second: dir.display().to_string(),
            }));
        }
        *slot = Some(dir);
    }
    let missing: Vec<usize> = (1..=count).filter(|k| holder[k - 1].is_none()).collect();
    if !missing.is_empty() {
        return Err(merge_error(MergeError::Missing { missing, count }));
    }
    let axes: Vec<Axis> = first
        .axes
        .iter()
        .map(|(key, values)| Axis {
            key: key.clone(),
            values: values.iter().map(|v| parse_value(v)).collect(),
        })
        .collect();
    let staging = Staging::new(out, "summary.csv")?;
    let not_written = |cause| staging.not_written(cause);
    let runs_dir = staging.subdirectory("runs")?;
    let mut rows: Vec<SweepRow> = Vec::with_capacity(first.combinations);
    for (dir, m) in &parts {
        for row in &m.rows {
            if row.digest.is_some() {
                copy_dir(
                    &dir.join("runs").join(&row.directory),
                    &runs_dir.join(&row.directory),
                )
                .map_err(not_written)?;
            }
            rows.push(SweepRow {
                index: row.index,
                overrides: combination(&axes, row.index),
                directory: row.directory.clone(),
                outcome: match (&row.digest, &row.error) {
                    (Some(d), _) => Ok(d.clone()),
                    (None, message) => Err(ScenarioError::InPart {
                        message: message.clone().unwrap_or_default(),
                    }),
                },
            });
        }
    }
    rows.sort_by_key(|r| r.index);
    let manifest = Manifest::new(
        Path::new(&first.scenario),
        &first.title,
        &axes,
        Shard::WHOLE,
        first.combinations,
        &rows,
    );
    write_results(staging.path(), &manifest, &axes, &rows).map_err(not_written)?;
    staging.commit()?;
    Ok(rows)
}

/// Copy the directory `from` (files and subdirectories) to the new directory `to`.
fn copy_dir(from: &Path, to: &Path) -> Result<(), ScenarioError> {
    std::fs::create_dir_all(to).map_err(|e| write_error(to, &e))?;
    let entries = std::fs::read_dir(from).map_err(|e| ScenarioError::Read {
        path: from.display().to_string(),
        message: e.to_string(),
    })?;
    for entry in entries {
        let entry = entry.map_err(|e| ScenarioError::Read {
            path: from.display().to_string(),
            message: e.to_string(),
        })?;
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            std::fs::copy(entry.path(), &target).map_err(|e| write_error(&target, &e))?;
        }
    }
    Ok(())
}

fn write_error(path: &Path, e: &std::io::Error) -> ScenarioError {
    ScenarioError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    }
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
                fields.push(
                    s.t_diverged
                        .map_or(String::new(), |t| crate::cli::text::Num(t).to_string()),
                );
                // An output this run's model does not have (a swept `model`) stays empty.
                for o in &outputs {
                    fields.push(
                        s.max_abs_error
                            .get(o)
                            .map_or(String::new(), |v| v.to_string()),
                    );
                }
                for o in &outputs {
                    fields.push(
                        s.final_error
                            .get(o)
                            .map_or(String::new(), |v| v.to_string()),
                    );
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
            Err(error) => {
                fields.push("error".into());
                fields.extend(std::iter::repeat_n(
                    String::new(),
                    1 + 2 * outputs.len() + 5,
                ));
                fields.push(csv_field(&error.to_string()));
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
        let c: Vec<Overrides> = combinations(&axes).collect();
        assert_eq!(c.len(), 6);
        assert_eq!(c[0].label(), "h=0.01,prefeedback=true");
        assert_eq!(c[1].label(), "h=0.01,prefeedback=false");
        assert_eq!(c[5].label(), "h=0.1,prefeedback=false");
        assert_eq!(combinations(&[]).count(), 1);
    }

    #[test]
    fn a_huge_sweep_is_counted_without_being_built() {
        // 22 two-valued keys: 4.2 million combinations, never held in memory.
        let axes: Vec<Axis> = (0..22)
            .map(|i| Axis::parse(&format!("k{i}=1,2")).unwrap())
            .collect();
        assert_eq!(combination_count(&axes), Some(1 << 22));
        let last = combination(&axes, (1 << 22) - 1);
        assert!(last.0.iter().all(|(_, v)| v.as_integer() == Some(2)));
        let axes: Vec<Axis> = (0..70)
            .map(|i| Axis::parse(&format!("k{i}=1,2")).unwrap())
            .collect();
        assert_eq!(combination_count(&axes), None);
    }
}
