//! `dpc simulate SCENARIO.toml --out DIR` and `dpc sweep SCENARIO.toml --set k=v1,v2 --out DIR`.

use std::path::{Path, PathBuf};

use crate::cli::output::{unique_names, Staging};
use crate::cli::plot::closed_loop_figure;
use crate::cli::progress::{on_terminal, RunProgress};
use crate::cli::registry::Registry;
use crate::cli::report::{write_run, Digest};
use crate::cli::run::RunResult;
use crate::cli::scenario::{Overrides, Scenario};
use crate::cli::sweep::{self, Axis};
use crate::cli::text::{short, Num};
use crate::cli::ScenarioError;
use clap::Args;
use dpc::core::numeric::Time;

use crate::cli::command::sayln;
use dpc::core::linear_analysis::sampled::CriticalPeriod;

/// Arguments of `dpc simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    /// The scenario file (see scenarios/ for examples).
    pub scenario: PathBuf,
    /// Output directory (created if needed; earlier results in it are replaced as a whole
    /// once the new ones are written, and kept if the run fails).
    #[arg(long)]
    pub out: PathBuf,
    /// Override a scenario key, e.g. --set h=0.1 --set plant.params.m=1.2 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// Arguments of `dpc sweep`.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    /// `dpc sweep merge DIR... --out DIR`: join the parts of a sharded sweep.
    #[command(subcommand)]
    pub command: Option<SweepCommand>,
    /// The scenario file.
    #[arg(required = true)]
    pub scenario: Option<PathBuf>,
    /// A swept key and its values, e.g. --set h=0.01,0.05,0.1 (repeatable: all combinations).
    #[arg(long = "set", value_name = "KEY=V1,V2,...", required = true)]
    pub set: Vec<String>,
    /// Output directory (created if needed; earlier sweep results in it are replaced as a
    /// whole when the sweep is written).
    #[arg(long, required = true)]
    pub out: Option<PathBuf>,
    /// The most combinations the sweep may have; a larger sweep is an error before any run.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub max_runs: usize,
    /// Run only part K of N of the combinations (deterministic: those whose index is K - 1
    /// modulo N), e.g. for a Slurm job array `--shard $SLURM_ARRAY_TASK_ID/8`; join the
    /// parts' directories with `dpc sweep merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
}

/// Subcommands of `dpc sweep`.
#[derive(clap::Subcommand)]
pub enum SweepCommand {
    /// Join the output directories of the parts of a sweep (`--shard K/N`) into the
    /// summary.csv, figure and runs of a single run of the whole sweep.
    Merge {
        /// The parts' output directories, each part exactly once.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Output directory of the merged sweep.
        #[arg(long)]
        out: PathBuf,
    },
}

fn describe(summary: &Digest) -> String {
    let verdict = match (summary.t_diverged, &summary.divergence_cause) {
        (Some(t), Some(cause)) => format!("DIVERGED at t = {}: {cause}", Time(t)),
        _ => "no divergence".to_string(),
    };
    let errors: Vec<String> = summary
        .max_abs_error
        .iter()
        .map(|(k, v)| format!("{k} {v:.3e}"))
        .collect();
    let roundoff = if summary.roundoff_level >= 1.0 {
        format!(
            "; round-off level eps * delta^-nu = {:.1e}: the controls carry no correct digit (raise `delta` or lower `nu`)",
            summary.roundoff_level
        )
    } else {
        String::new()
    };
    format!(
        "{}: {verdict}; max |error| over the last quarter: {}; {} samples, {} Newton iterations, {} retries, {:.2} s{roundoff}",
        short(&summary.label),
        errors.join(", "),
        summary.samples,
        summary.newton_iterations,
        summary.retries,
        summary.wall_time_s
    )
}

/// A period found by bisection, to the four significant digits it is known to (the bisection
/// stops far below the sampling period's own precision): `0.02065`, not `0.020653320312499997`.
fn significant(h: f64) -> String {
    if !(h.is_finite() && h > 0.0) {
        return Num(h).to_string();
    }
    let decimals = (3.0 - h.log10().floor()).clamp(0.0, 15.0) as usize;
    let text = format!("{h:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Run `dpc simulate`: the scenario and its comparison runs, written into a staging
/// directory that replaces `--out` only when everything is written.
pub fn simulate(registry: &Registry, args: &SimulateArgs) -> Result<(), ScenarioError> {
    let overrides = Overrides::parse(args.set.iter().map(String::as_str))?;
    let scenario = Scenario::load(&args.scenario, &overrides)?;
    // Every comparison scenario is read before any run, so a bad entry costs no run.
    let mut compared = Vec::new();
    for extra in scenario.comparisons()? {
        let mut all = overrides.clone();
        all.0.extend(extra.0.iter().cloned());
        compared.push((Scenario::load(&args.scenario, &all)?, extra.label()));
    }
    let staging = Staging::new(&args.out, "summary.json")?;
    let written = write_all(registry, &scenario, &overrides, &compared, staging.path());
    match written {
        Ok(()) => {
            staging.commit()?;
            let out = &args.out;
            sayln!(
                "wrote {}, {}, {} and {}",
                out.join("summary.json").display(),
                out.join("trajectory.csv").display(),
                out.join("closed-loop.svg").display(),
                out.join("closed-loop.png").display()
            );
            Ok(())
        }
        Err(cause) => Err(staging.not_written(cause)),
    }
}

/// Run the scenario and its comparisons and write everything into `dir`.
fn write_all(
    registry: &Registry,
    scenario: &Scenario,
    overrides: &Overrides,
    compared: &[(Scenario, String)],
    dir: &Path,
) -> Result<(), ScenarioError> {
    let mut runs: Vec<RunResult> = Vec::new();
    let main_label = if overrides.0.is_empty() {
        "scenario".to_string()
    } else {
        overrides.label()
    };
    runs.push(registry.run_with_progress(
        scenario,
        &main_label,
        &mut RunProgress::new(on_terminal()),
    )?);
    let summary = write_run(dir, &runs[0])?;
    if let Some(d) = &summary.linear_design {
        let n = &d.nominal;
        if !n.solved_for.is_empty() {
            let value = |name: &str| -> Option<f64> {
                match name.strip_prefix("der(").and_then(|r| r.strip_suffix(')')) {
                    Some(state) => n.rate.get(state).copied(),
                    None => [&n.state, &n.algebraic, &n.input]
                        .iter()
                        .find_map(|m| m.get(name).copied()),
                }
            };
            sayln!(
                "nominal completed by the trim solver ({} iterations, residual {:.1e}): {}",
                n.trim_iterations,
                n.trim_residual,
                n.solved_for
                    .iter()
                    .map(|name| match value(name) {
                        Some(v) => format!("{name} = {v:.6}"),
                        None => name.clone(),
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if n.free_directions > 0 {
            sayln!(
                "note: the nominal is not unique ({} free direction(s)); the trim solver took the solution nearest the guesses (x0 for states)",
                n.free_directions
            );
        }
        if let Some(where_) = &n.not_steady {
            sayln!(
                "note: the nominal is not a steady motion up to t_end: {where_}; K_n is designed at t = 0"
            );
        }
        sayln!(
            "linear analysis of the controller's model: DPC alone predicted {}; eig(Abar_4) = [{}]",
            if d.dpc_stable_without_prefeedback {
                "stable"
            } else {
                "UNSTABLE"
            },
            d.abar4_eigenvalues
                .iter()
                .map(|[re, im]| format!("{re:.4}{im:+.4}i"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let critical = match d.sampled.critical_period {
            CriticalPeriod::At(h) => format!("loses stability at h = {}", significant(h)),
            CriticalPeriod::StableUpTo(h) => {
                format!("stable for every h up to {}", significant(h))
            }
            CriticalPeriod::UnstableAtAnyPeriod => "unstable at every period".to_string(),
        };
        sayln!(
            "linear sampled-data prediction ({} hold): spectral radius {:.4} at h = {}, {critical}",
            match summary.scenario.hold {
                dpc::core::simulate::Hold::Input => "input",
                dpc::core::simulate::Hold::Correction => "correction",
            },
            d.sampled.spectral_radius,
            Num(summary.scenario.h)
        );
        if d.linearisation_drift > 1e-6 {
            sayln!(
                "note: the linearisation changes along the nominal motion by {:.2e} (relative) up to t_end; K_n is designed at t = 0",
                d.linearisation_drift
            );
        }
    }
    sayln!("{}", describe(&summary.digest()));
    let names = unique_names(compared.iter().map(|(_, label)| label.clone()));
    for ((s, label), name) in compared.iter().zip(names) {
        let r = registry.run_with_progress(s, label, &mut RunProgress::new(on_terminal()))?;
        let summary = write_run(&dir.join("compare").join(name), &r)?;
        sayln!("{}", describe(&summary.digest()));
        runs.push(r);
    }
    let refs: Vec<&RunResult> = runs.iter().collect();
    closed_loop_figure(&dir.join("closed-loop"), &refs)?;
    Ok(())
}

/// Run `dpc sweep`.
pub fn sweep(registry: &Registry, args: &SweepArgs) -> Result<(), ScenarioError> {
    if let Some(SweepCommand::Merge { parts, out }) = &args.command {
        let rows = sweep::merge(parts, out)?;
        report_rows(&rows);
        sayln!(
            "merged {} parts ({} runs) into {} and {}",
            parts.len(),
            rows.len(),
            out.join("summary.csv").display(),
            out.join("sweep.svg").display()
        );
        return Ok(());
    }
    // clap requires both without the subcommand.
    let (Some(scenario), Some(out)) = (&args.scenario, &args.out) else {
        return Ok(());
    };
    let axes = args
        .set
        .iter()
        .map(|s| Axis::parse(s))
        .collect::<Result<Vec<_>, _>>()?;
    let shard = match &args.shard {
        Some(text) => sweep::Shard::parse(text)?,
        None => sweep::Shard::WHOLE,
    };
    let rows = sweep::sweep(
        registry,
        scenario,
        &axes,
        out,
        args.max_runs,
        on_terminal(),
        shard,
    )?;
    report_rows(&rows);
    sayln!(
        "wrote {} and {}",
        out.join("summary.csv").display(),
        out.join("sweep.svg").display()
    );
    Ok(())
}

/// One line per run of a sweep.
fn report_rows(rows: &[sweep::SweepRow]) {
    for row in rows {
        match &row.outcome {
            Ok(s) => sayln!("{}", describe(s)),
            Err(e) => sayln!("{}: error: {e}", short(&row.overrides.label())),
        }
    }
}
