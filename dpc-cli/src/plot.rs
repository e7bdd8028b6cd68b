//! Figures of closed-loop runs, written as SVG and PNG.
//!
//! [`closed_loop_figure`] lays runs out like the paper's Fig. 5.2: one column per run (the
//! scenario and its comparison runs, e.g. with and without preliminary feedback), and rows
//! for each output against its reference, the tracking errors and the control inputs.
//! [`sweep_figure`] draws the late tracking error against a swept parameter.
//!
//! PNG text is drawn with the DejaVu Sans font compiled into the binary, so no system font
//! is needed.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::run::RunResult;
use crate::ScenarioError;

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn register_font() {
    static FONT: Once = Once::new();
    FONT.call_once(|| {
        // The font is a valid TrueType file compiled in; registration cannot fail on it, and
        // if it ever did, text would be missing from PNGs but SVGs would be unaffected.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> ScenarioError {
    ScenarioError::Write {
        path: path.display().to_string(),
        message: format!("plot: {e}"),
    }
}

/// A named curve.
struct Curve {
    name: String,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

/// Draw one panel of time series.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    t_end: f64,
    curves: &[Curve],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let finite = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.1))
        .filter(|v| v.is_finite());
    let (mut lo, mut hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-12 * (1.0 + hi.abs()));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..t_end.max(1e-9), (lo - pad)..(hi + pad))?;
    let span = hi - lo + 2.0 * pad;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_label_formatter(&|v| tick(*v, span))
        .draw()?;
    for c in curves {
        let color = c.color;
        let points = c.points.iter().copied().filter(|p| p.1.is_finite());
        let anno = if c.dashed {
            chart.draw_series(DashedLineSeries::new(points, 6, 4, color.stroke_width(1)))?
        } else {
            chart.draw_series(LineSeries::new(points, color.stroke_width(1)))?
        };
        anno.label(c.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// A tick label readable at the scale of the axis: fixed notation with as many decimals as
/// the span needs, scientific for very large or very small spans; round-off around zero is
/// shown as 0.
fn tick(v: f64, span: f64) -> String {
    let v = if v.abs() < 1e-9 * span { 0.0 } else { v };
    let magnitude = v.abs().max(span);
    if !(1e-3..1e5).contains(&magnitude) || span < 1e-4 * magnitude {
        return format!("{v:.2e}");
    }
    let decimals = (2.0 - span.log10().floor()).clamp(0.0, 6.0) as usize;
    format!("{v:.decimals$}")
}

fn series(run: &RunResult, f: impl Fn(&dpc::core::simulate::Sample) -> f64) -> Vec<(f64, f64)> {
    run.closed_loop
        .samples
        .iter()
        .map(|s| (s.t, f(s)))
        .collect()
}

fn column_title(run: &RunResult) -> String {
    let verdict = match &run.closed_loop.divergence {
        Some(d) => format!("diverged at t = {:.3}", d.t),
        None => "no divergence".to_string(),
    };
    let pre = if run.scenario.prefeedback {
        "with preliminary feedback"
    } else {
        "without preliminary feedback"
    };
    format!("{} ({pre}; {verdict})", run.label)
}

fn draw_closed_loop<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    runs: &[&RunResult],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let Some(first) = runs.first() else {
        return Ok(());
    };
    let outputs = &first.names.outputs;
    let rows = outputs.len() + 2;
    let columns = root.split_evenly((1, runs.len()));
    for (run, column) in runs.iter().zip(&columns) {
        let t_end = run.scenario.t_end;
        let column = column.titled(&column_title(run), ("sans-serif", 17))?;
        let panels = column.split_evenly((rows, 1));
        for (i, name) in outputs.iter().enumerate() {
            panel(
                &panels[i],
                &format!("{name} and its reference"),
                t_end,
                &[
                    Curve {
                        name: name.clone(),
                        points: series(run, |s| s.y[i]),
                        color: PALETTE[0],
                        dashed: false,
                    },
                    Curve {
                        name: format!("{name}_ref"),
                        points: series(run, |s| s.reference[i]),
                        color: BLACK,
                        dashed: true,
                    },
                ],
            )?;
        }
        let errors: Vec<Curve> = outputs
            .iter()
            .enumerate()
            .map(|(i, name)| Curve {
                name: format!("e_{name}"),
                points: series(run, |s| s.error[i]),
                color: PALETTE[i % PALETTE.len()],
                dashed: false,
            })
            .collect();
        panel(&panels[outputs.len()], "tracking errors", t_end, &errors)?;
        let inputs: Vec<Curve> = run
            .names
            .inputs
            .iter()
            .enumerate()
            .map(|(i, name)| Curve {
                name: name.clone(),
                points: series(run, |s| s.u[i]),
                color: PALETTE[(i + 1) % PALETTE.len()],
                dashed: false,
            })
            .collect();
        panel(&panels[outputs.len() + 1], "control inputs", t_end, &inputs)?;
    }
    root.present()
}

/// Write `stem.svg` and `stem.png` with one column per run; returns the two paths.
///
/// # Errors
/// [`ScenarioError::Write`] when drawing or writing fails.
pub fn closed_loop_figure(
    stem: &Path,
    runs: &[&RunResult],
) -> Result<[std::path::PathBuf; 2], ScenarioError> {
    register_font();
    let outputs = runs.first().map_or(1, |r| r.names.outputs.len());
    let size = (
        560 * runs.len().max(1) as u32,
        250 * (outputs as u32 + 2) + 40,
    );
    let svg = stem.with_extension("svg");
    draw_closed_loop(&SVGBackend::new(&svg, size).into_drawing_area(), runs)
        .map_err(|e| plot_error(&svg, e))?;
    let png = stem.with_extension("png");
    draw_closed_loop(&BitMapBackend::new(&png, size).into_drawing_area(), runs)
        .map_err(|e| plot_error(&png, e))?;
    Ok([svg, png])
}

/// One series of a sweep plot: points `(parameter, error)`; `None` marks a diverged run.
pub struct SweepSeries {
    /// Legend text (the other parameters' values).
    pub name: String,
    /// `(parameter value, worst late error or None if diverged)`.
    pub points: Vec<(f64, Option<f64>)>,
}

fn draw_sweep<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    parameter: &str,
    series: &[SweepSeries],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let (x_lo, x_hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (x_lo, x_hi) = if x_lo.is_finite() && x_hi > x_lo {
        let pad = 0.05 * (x_hi - x_lo);
        (x_lo - pad, x_hi + pad)
    } else if x_lo.is_finite() {
        (
            x_lo - 0.5 * x_lo.abs().max(1.0),
            x_lo + 0.5 * x_lo.abs().max(1.0),
        )
    } else {
        (0.0, 1.0)
    };
    let ys = series
        .iter()
        .flat_map(|s| s.points.iter().filter_map(|p| p.1))
        .filter(|v| v.is_finite() && *v > 0.0);
    let (y_lo, y_hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (y_lo, y_hi) = if y_lo.is_finite() {
        (y_lo / 3.0, y_hi * 30.0)
    } else {
        (1e-6, 1.0)
    };
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!(
                "largest |tracking error| over the last quarter against {parameter} (x: diverged)"
            ),
            ("sans-serif", 16),
        )
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(70)
        .build_cartesian_2d(x_lo..x_hi, (y_lo..y_hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc(parameter)
        .y_desc("max |e|")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (k, s) in series.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let ok: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter_map(|&(x, y)| y.filter(|v| v.is_finite() && *v > 0.0).map(|y| (x, y)))
            .collect();
        chart
            .draw_series(LineSeries::new(ok.iter().copied(), color.stroke_width(2)))?
            .label(s.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
        chart.draw_series(ok.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
        chart.draw_series(
            s.points
                .iter()
                .filter(|p| p.1.is_none())
                .map(|&(x, _)| Cross::new((x, y_hi / 2.0), 6, color.stroke_width(2))),
        )?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()
}

/// Write `stem.svg` and `stem.png` of a sweep.
///
/// # Errors
/// [`ScenarioError::Write`] when drawing or writing fails.
pub fn sweep_figure(
    stem: &Path,
    parameter: &str,
    series: &[SweepSeries],
) -> Result<[std::path::PathBuf; 2], ScenarioError> {
    register_font();
    let size = (900, 560);
    let svg = stem.with_extension("svg");
    draw_sweep(
        &SVGBackend::new(&svg, size).into_drawing_area(),
        parameter,
        series,
    )
    .map_err(|e| plot_error(&svg, e))?;
    let png = stem.with_extension("png");
    draw_sweep(
        &BitMapBackend::new(&png, size).into_drawing_area(),
        parameter,
        series,
    )
    .map_err(|e| plot_error(&png, e))?;
    Ok([svg, png])
}

#[cfg(test)]
mod tests {
    use super::tick;

    #[test]
    fn ticks_suit_the_span() {
        assert_eq!(tick(1.68, 0.2), "1.680");
        assert_eq!(tick(-120.0, 140.0), "-120");
        assert_eq!(tick(-1.11e-16, 1.4), "0.00");
        assert_eq!(tick(2.0e-5, 1e-4), "2.00e-5");
        assert_eq!(tick(8.0e5, 1.8e6), "8.00e5");
    }
}
