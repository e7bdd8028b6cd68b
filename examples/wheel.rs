//! The paper's nonlinear example end to end (Section 5): DPC on the wheel of the Appendix,
//! without and with the preliminary feedback, written to disk as CSV and SVG plots laid out
//! like the paper's Fig. 5.2 (output against reference, tracking errors, steering torque).
//!
//! ```sh
//! cargo run --release --example wheel -- out/wheel
//! ```

use dpc::core::dpc::{Dpc, DpcOptions, Extraction, Nominal, Prefeedback};
use dpc::core::linalg::NalgebraLu;
use dpc::core::linear::{analyze, AnalysisOptions};
use dpc::core::linearize::{linearize, OperatingPoint};
use dpc::core::simulate::{simulate, ClosedLoop, ClosedLoopOptions, Hold};
use dpc::nalgebra::Complex;
use dpc_models::{Wheel, WheelReference, WheelTracking};
use plotters::prelude::*;
use std::error::Error;
use std::f64::consts::FRAC_PI_2;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The nominal motion `x0(t) = [pi/2, -6t, 0, 0, -6]`, `u0 = 0`.
struct Upright;

impl Nominal for Upright {
    fn state(&self, t: f64, x0: &mut [f64]) {
        x0.copy_from_slice(&[FRAC_PI_2, -6.0 * t, 0.0, 0.0, -6.0]);
    }
    fn input(&self, _t: f64, u0: &mut [f64]) {
        u0.fill(0.0);
    }
}

fn run(with_prefeedback: bool) -> Result<ClosedLoop, Box<dyn Error>> {
    let mut dpc = Dpc::new(
        WheelTracking::default(),
        WheelReference::default(),
        NalgebraLu::<7>::new(),
        DpcOptions {
            delta: 1e-3,
            extraction: Extraction::Extrapolated,
            ..DpcOptions::default()
        },
    )?;
    if with_prefeedback {
        let sys = linearize(
            &Wheel::default(),
            OperatingPoint {
                t: 0.0,
                x: &[FRAC_PI_2, 0.0, 0.0, 0.0, -6.0],
                xdot: &[0.0, -6.0, 0.0, 0.0, 0.0],
                z: &[],
                u: &[0.0, 0.0],
            },
        )?;
        let analysis = analyze(
            &sys,
            &AnalysisOptions {
                w: Some(vec![vec![5.0], vec![5.0]]),
                poles: Some(vec![Complex::new(-5.0, 0.0); 3]),
                ..AnalysisOptions::default()
            },
        )?;
        println!(
            "linear analysis: eig(Abar_4) = {:?}, DPC alone predicted stable: {}",
            analysis
                .abar4_eigenvalues
                .iter()
                .map(|c| format!("{:.4}{:+.4}i", c.re, c.im))
                .collect::<Vec<_>>(),
            analysis.dpc_stable
        );
        let k_n = analysis.k_n.ok_or("the analysis built no K_n")?;
        dpc = dpc.with_prefeedback(Prefeedback {
            k_n,
            nominal: Box::new(Upright),
        })?;
    }
    Ok(simulate(
        &Wheel::default(),
        &mut dpc,
        &[FRAC_PI_2, 0.0, 0.0, 0.0, -6.0],
        &ClosedLoopOptions {
            h: 0.05,
            t_end: 20.0,
            hold: Hold::Input,
            ..ClosedLoopOptions::default()
        },
    )?)
}

fn write_csv(path: &Path, run: &ClosedLoop) -> Result<(), Box<dyn Error>> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(
        f,
        "t,theta,psi,dphi,dtheta,dpsi,u1,u2,theta_ref,psi_ref,e_theta,e_psi"
    )?;
    for s in &run.samples {
        let row: Vec<String> = std::iter::once(s.t)
            .chain(s.x.iter().copied())
            .chain(s.u.iter().copied())
            .chain(s.reference.iter().copied())
            .chain(s.error.iter().copied())
            .map(|v| format!("{v}"))
            .collect();
        writeln!(f, "{}", row.join(","))?;
    }
    Ok(())
}

/// A named curve `(t, value)` with its colour.
type Series<'a> = (&'a str, Vec<(f64, f64)>, RGBColor);

/// One panel of the figure.
fn panel(
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    title: &str,
    series: &[Series<'_>],
) -> Result<(), Box<dyn Error>> {
    let t_max = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.0))
        .fold(0.0_f64, f64::max);
    let (mut lo, mut hi) = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-9);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_max.max(1e-9), (lo - pad)..(hi + pad))?;
    chart.configure_mesh().x_desc("t [s]").draw()?;
    for (name, points, color) in series {
        let color = *color;
        chart
            .draw_series(LineSeries::new(points.iter().copied(), color))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

fn plot(path: &Path, without: &ClosedLoop, with: &ClosedLoop) -> Result<(), Box<dyn Error>> {
    let root = SVGBackend::new(path, (1100, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 2));
    let col = |r: &ClosedLoop, f: &dyn Fn(&dpc::core::simulate::Sample) -> f64| {
        r.samples.iter().map(|s| (s.t, f(s))).collect::<Vec<_>>()
    };
    panel(
        &panels[0],
        "without preliminary feedback: theta, theta_ref",
        &[
            ("theta", col(without, &|s| s.x[0]), BLUE),
            ("theta_ref", col(without, &|s| s.reference[0]), BLACK),
        ],
    )?;
    panel(
        &panels[1],
        "without preliminary feedback: steering torque u1",
        &[("u1", col(without, &|s| s.u[0]), RED)],
    )?;
    panel(
        &panels[2],
        "with preliminary feedback: theta, theta_ref",
        &[
            ("theta", col(with, &|s| s.x[0]), BLUE),
            ("theta_ref", col(with, &|s| s.reference[0]), BLACK),
        ],
    )?;
    panel(
        &panels[3],
        "with preliminary feedback: e_theta",
        &[("e_theta", col(with, &|s| s.error[0]), BLUE)],
    )?;
    panel(
        &panels[4],
        "with preliminary feedback: e_psi",
        &[("e_psi", col(with, &|s| s.error[1]), BLUE)],
    )?;
    panel(
        &panels[5],
        "with preliminary feedback: steering torque u1",
        &[("u1", col(with, &|s| s.u[0]), RED)],
    )?;
    root.present()?;
    Ok(())
}

fn summary(name: &str, run: &ClosedLoop) {
    let last = run.samples.last();
    println!(
        "{name}: {} samples, diverged: {}, final errors {:?}, retries {}, failed samples {}",
        run.samples.len(),
        run.divergence
            .as_ref()
            .map_or("no".to_string(), |d| format!(
                "at t = {} ({})",
                d.t, d.cause
            )),
        last.map(|s| s.error.clone()).unwrap_or_default(),
        run.retries,
        run.failed_samples
    );
}

fn main() -> Result<(), Box<dyn Error>> {
    let out: PathBuf = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from("out/wheel"), PathBuf::from);
    std::fs::create_dir_all(&out)?;
    let without = run(false)?;
    let with = run(true)?;
    summary("DPC without preliminary feedback", &without);
    summary("DPC with preliminary feedback", &with);
    write_csv(&out.join("trajectory-without-prefeedback.csv"), &without)?;
    write_csv(&out.join("trajectory-with-prefeedback.csv"), &with)?;
    plot(&out.join("fig-5-2.svg"), &without, &with)?;
    println!("wrote {}", out.display());
    Ok(())
}
