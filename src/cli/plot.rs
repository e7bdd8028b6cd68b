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

use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::cli::run::RunResult;
use crate::cli::ScenarioError;
use crate::core::simulate::TrajectoryPoint;

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

/// Draw a figure twice, as `stem.svg` and as `stem.png` (rendered to memory, then encoded
/// with the strongest PNG compression: line plots compress well); evaluates to the two paths.
macro_rules! write_figure {
    ($stem:expr, $size:expr, |$root:ident| $draw:expr) => {{
        let stem: &Path = $stem;
        let size: (u32, u32) = $size;
        let svg = stem.with_extension("svg");
        {
            let $root = SVGBackend::new(&svg, size).into_drawing_area();
            $draw.map_err(|e| plot_error(&svg, e))?;
        }
        let png = stem.with_extension("png");
        let mut pixels = vec![0u8; 3 * size.0 as usize * size.1 as usize];
        {
            let $root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
            $draw.map_err(|e| plot_error(&png, e))?;
        }
        encode_png(&png, &pixels, size)?;
        Ok([svg, png])
    }};
}

/// A named curve.
struct Curve {
    name: String,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

/// Width of the legend strip right of each panel, in pixels.
const LEGEND_WIDTH: u32 = 130;

/// How a panel's vertical axis maps values.
#[derive(Clone, Copy)]
enum Scale {
    /// Linear, range from the data; a diverged run's blow-up beyond `clip_above` times the
    /// range before it is clipped.
    Linear,
    /// Symmetric logarithmic: linear within `±threshold`, logarithmic beyond, so that errors
    /// decaying over decades stay visible next to their initial transient.
    SymLog {
        /// The linear threshold, a power of ten.
        threshold: f64,
    },
}

impl Scale {
    fn map(self, v: f64) -> f64 {
        match self {
            Scale::Linear => v,
            Scale::SymLog { threshold } => v.signum() * (1.0 + v.abs() / threshold).log10(),
        }
    }
}

/// The symmetric-log threshold of a panel of errors: the power of ten at or below their
/// typical late size (the median magnitude over the last quarter of the run), so the floor
/// the errors settle on is drawn with its shape and sign, and the transient before it over
/// decades; between three and seven decades below the largest error.
fn symlog_threshold(curves: &[Curve]) -> f64 {
    let mut late: Vec<f64> = Vec::new();
    let mut largest: f64 = 0.0;
    for c in curves {
        let t_last = c.points.last().map_or(0.0, |p| p.0);
        for &(t, v) in &c.points {
            if v.is_finite() {
                largest = largest.max(v.abs());
                if t >= 0.75 * t_last && v != 0.0 {
                    late.push(v.abs());
                }
            }
        }
    }
    if largest == 0.0 {
        return 1e-8;
    }
    late.sort_by(f64::total_cmp);
    let typical = late.get(late.len() / 2).copied().unwrap_or(largest);
    let floor = (largest * 1e-7).max(f64::MIN_POSITIVE);
    // At least three decades below the largest error, so a transient or a blow-up is drawn
    // on a logarithmic scale too.
    let level = typical.max(floor).min(largest * 1e-3).max(1e-300);
    10f64.powf(level.log10().floor()).max(1e-300)
}

/// Tick positions (in mapped coordinates) and labels of a symmetric-log axis over the mapped
/// range `lo..hi`: zero and the signed powers of ten from the threshold on.
fn symlog_ticks(threshold: f64, lo: f64, hi: f64) -> Vec<(f64, String)> {
    let scale = Scale::SymLog { threshold };
    let mut ticks = Vec::new();
    if (lo..=hi).contains(&0.0) {
        ticks.push((0.0, "0".to_string()));
    }
    let top = lo.abs().max(hi.abs());
    // From ten times the threshold: closer to zero the labels would run into `0`.
    let mut k = threshold.log10().round() as i32 + 1;
    // Every other decade when there are many, so that labels do not collide.
    let decades = (top / 1.0).ceil() as i32 + 1;
    let step = if decades > 8 { 2 } else { 1 };
    loop {
        let v = 10f64.powi(k);
        let y = scale.map(v);
        if !(y.is_finite()) || y > top * 1.0001 {
            break;
        }
        for (sign, text) in [(1.0, format!("1e{k}")), (-1.0, format!("-1e{k}"))] {
            if (lo..=hi).contains(&(sign * y)) {
                ticks.push((sign * y, text));
            }
        }
        k += step;
    }
    ticks
}

/// The axis range of a panel: the data's, padded; when a diverged run's blow-up or the kick
/// of the first samples is much wider than the rest, the range of the rest, with the points
/// beyond clipped (and marked) at the edges.
fn value_range(curves: &[Curve], scale: Scale, diverged_at: Option<f64>) -> (f64, f64, bool) {
    let range = |pred: &dyn Fn(f64) -> bool| {
        curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(|p| pred(p.0))
            // Beyond 1e300 the padding and the tick arithmetic would overflow.
            .map(|p| scale.map(p.1).clamp(-1e300, 1e300))
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (mut lo, mut hi) = range(&|_| true);
    let mut clipped = false;
    if let Scale::Linear = scale {
        // A diverged run: the motion up to 90 % of the time before the divergence sets the
        // range. Otherwise the motion after the first 5 % of the run (a kick of the first
        // samples, from an initial state off the reference, is typical of DPC). A blow-up or a
        // kick more than five times that wide is clipped and marked instead of flattening
        // the rest.
        let t_last = curves
            .iter()
            .filter_map(|c| c.points.last().map(|p| p.0))
            .fold(0.0, f64::max);
        let (elo, ehi) = match diverged_at {
            Some(td) => range(&|t| t <= 0.9 * td),
            None => range(&|t| t >= 0.05 * t_last),
        };
        if elo.is_finite() && ehi.is_finite() {
            let width = (ehi - elo).max(1e-12 * (1.0 + ehi.abs()));
            if hi - lo > 5.0 * width {
                (lo, hi) = (elo - 0.5 * width, ehi + 0.5 * width);
                clipped = true;
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (-1.0, 1.0);
    }
    // A constant signal gets a small range around its value, not one of round-off size.
    let pad = 0.06 * (hi - lo).max(1e-2 * (1.0 + hi.abs()));
    (lo - pad, hi + pad, clipped)
}

/// Draw one panel of time series: the chart left, its legend in a strip right of it (so it
/// never covers data).
#[allow(clippy::too_many_arguments)]
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    y_label: &str,
    t_end: f64,
    curves: &[Curve],
    scale: Scale,
    steps: Option<f64>,
    diverged_at: Option<f64>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (width, _) = area.dim_in_pixel();
    let (plot_area, legend_area) = area.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
    let (lo, hi, clipped) = value_range(curves, scale, diverged_at);
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(title, ("sans-serif", 15))
        .margin_top(6)
        .margin_bottom(4)
        .margin_left(6)
        .margin_right(14)
        .x_label_area_size(34)
        .y_label_area_size(78)
        .build_cartesian_2d(0.0..t_end.max(1e-9), lo..hi)?;
    let span = hi - lo;
    match scale {
        Scale::Linear => chart
            .configure_mesh()
            .x_desc("t [s]")
            .y_desc(y_label)
            .x_label_formatter(&|v| tick(*v, t_end))
            .y_label_formatter(&|v| tick(*v, span))
            .light_line_style(WHITE.mix(0.0))
            .draw()?,
        Scale::SymLog { threshold } => {
            chart
                .configure_mesh()
                .x_desc("t [s]")
                .y_desc(y_label)
                .x_label_formatter(&|v| tick(*v, t_end))
                .y_labels(0)
                .light_line_style(WHITE.mix(0.0))
                .draw()?;
            // Decade ticks drawn by hand: plotters places labels uniformly in the mapped
            // coordinate, which would give unround values.
            let ticks = symlog_ticks(threshold, lo, hi);
            let grid = BLACK.mix(0.12);
            for (y, text) in &ticks {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(0.0, *y), (t_end, *y)],
                    grid,
                )))?;
                let (px, py) = chart.backend_coord(&(0.0, *y));
                let (bx, by) = plot_area.get_base_pixel();
                let (px, py) = (px - bx, py - by);
                plot_area.draw(&Text::new(
                    text.clone(),
                    (px - 8, py),
                    ("sans-serif", 12)
                        .into_font()
                        .color(&BLACK)
                        .pos(Pos::new(HPos::Right, VPos::Center)),
                ))?;
            }
        }
    }
    let (y_lo, y_hi) = (lo, hi);
    let mut legend = Vec::new();
    for c in curves {
        let color = c.color;
        let mut points: Vec<(f64, f64)> = c
            .points
            .iter()
            .filter(|p| p.1.is_finite())
            .map(|&(t, v)| (t, scale.map(v)))
            .collect();
        if let Some(h) = steps {
            points = zero_order_hold(&points, h);
        }
        let clip = |v: f64| v.clamp(y_lo, y_hi);
        let mut beyond = None;
        let drawn: Vec<(f64, f64)> = points
            .iter()
            .map(|&(t, v)| {
                if beyond.is_none() && (v < y_lo || v > y_hi) {
                    beyond = Some((t, clip(v)));
                }
                (t, clip(v))
            })
            .collect();
        if c.dashed {
            chart.draw_series(DashedLineSeries::new(drawn, 6, 4, color.stroke_width(1)))?;
        } else {
            chart.draw_series(LineSeries::new(drawn, color.stroke_width(1)))?;
        }
        if let (true, Some(at)) = (clipped, beyond) {
            chart.draw_series(std::iter::once(TriangleMarker::new(at, 6, RED.filled())))?;
        }
        legend.push((c.name.clone(), color, c.dashed));
    }
    if let Some(td) = diverged_at {
        chart.draw_series(DashedLineSeries::new(
            [(td, y_lo), (td, y_hi)],
            3,
            3,
            RED.stroke_width(1),
        ))?;
    }
    if clipped {
        legend.push(("clipped (▲)".to_string(), RED, false));
    }
    draw_legend(&legend_area, &legend)
}

/// The legend of a panel, top-aligned in its strip.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBColor, bool)],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    for (k, (name, color, dashed)) in entries.iter().enumerate() {
        let y = 34 + 18 * k as i32;
        let style = color.stroke_width(2);
        if *dashed {
            area.draw(&PathElement::new(vec![(4, y), (10, y)], style))?;
            area.draw(&PathElement::new(vec![(14, y), (20, y)], style))?;
        } else {
            area.draw(&PathElement::new(vec![(4, y), (20, y)], style))?;
        }
        area.draw(&Text::new(
            name.clone(),
            (26, y),
            ("sans-serif", 13)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

/// Points of a held signal as steps: each value kept until the next sample, the last one for
/// the sampling period `h` (no further: a run that stopped early does not look held on).
fn zero_order_hold(points: &[(f64, f64)], h: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(2 * points.len());
    for (k, &(t, v)) in points.iter().enumerate() {
        out.push((t, v));
        let next = points.get(k + 1).map_or(t + h, |p| p.0);
        out.push((next, v));
    }
    out
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

/// A quantity at the samples (the held inputs, drawn as steps).
fn series(run: &RunResult, f: impl Fn(&dpc::core::simulate::Sample) -> f64) -> Vec<(f64, f64)> {
    run.closed_loop
        .samples
        .iter()
        .map(|s| (s.t, f(s)))
        .collect()
}

/// A quantity of the plant's motion: at the samples and, where the run recorded it
/// (`output_step`), between them, so that the curve is the continuous motion and not a
/// polygon through the samples.
fn motion(run: &RunResult, f: impl Fn(&TrajectoryPoint<'_>) -> f64) -> Vec<(f64, f64)> {
    run.closed_loop.trajectory().map(|p| (p.t, f(&p))).collect()
}

fn column_title(run: &RunResult) -> String {
    let verdict = match &run.closed_loop.divergence {
        Some(d) => format!("diverged at t = {}", dpc::core::numeric::Time(d.t)),
        None => "no divergence".to_string(),
    };
    let pre = if run.scenario.prefeedback {
        "with preliminary feedback"
    } else {
        "without preliminary feedback"
    };
    format!("{}: {pre}, {verdict}", run.label)
}

/// `name [unit]`, or the name alone when the model gives no unit.
fn labelled(name: &str, unit: Option<&str>) -> String {
    match unit {
        Some(u) if !u.is_empty() => format!("{name} [{u}]"),
        _ => name.to_string(),
    }
}

/// The unit every one of `names` has, if they share one.
fn common_unit<'a>(names: &[String], unit: impl Fn(&str) -> Option<&'a str>) -> Option<&'a str> {
    let first = unit(names.first()?)?;
    names
        .iter()
        .all(|n| unit(n) == Some(first))
        .then_some(first)
}

/// Pixel height of the figure title band.
const TITLE_HEIGHT: u32 = 34;

fn figure_title(runs: &[&RunResult]) -> String {
    runs.first()
        .map(|r| match &r.scenario.title {
            Some(t) => t.clone(),
            None => format!("model {}", r.scenario.model),
        })
        .unwrap_or_default()
}

fn draw_closed_loop<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    runs: &[&RunResult],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let Some(first) = runs.first() else {
        return root.present();
    };
    let root = root.titled(&figure_title(runs), ("sans-serif", 20))?;
    let outputs = &first.names.outputs;
    let rows = outputs.len() + 2;
    let columns = root.split_evenly((1, runs.len()));
    for (run, column) in runs.iter().zip(&columns) {
        let t_end = run.scenario.t_end;
        let diverged_at = run.closed_loop.divergence.as_ref().map(|d| d.t);
        let column = column.titled(&column_title(run), ("sans-serif", 16))?;
        let panels = column.split_evenly((rows, 1));
        let unit = |name: &str| run.names.unit(name);
        for (i, name) in outputs.iter().enumerate() {
            panel(
                &panels[i],
                &format!("{name} and its reference"),
                &labelled(name, unit(name)),
                t_end,
                &[
                    Curve {
                        name: name.clone(),
                        points: motion(run, |p| p.y[i]),
                        color: PALETTE[0],
                        dashed: false,
                    },
                    Curve {
                        name: "reference".to_string(),
                        points: motion(run, |p| p.reference[i]),
                        color: BLACK,
                        dashed: true,
                    },
                ],
                Scale::Linear,
                None,
                diverged_at,
            )?;
        }
        let errors: Vec<Curve> = outputs
            .iter()
            .enumerate()
            .map(|(i, name)| Curve {
                name: labelled(&format!("e_{name}"), unit(name)),
                points: motion(run, |p| p.error[i]),
                color: PALETTE[i % PALETTE.len()],
                dashed: false,
            })
            .collect();
        panel(
            &panels[outputs.len()],
            "tracking errors y - reference (symmetric log scale)",
            &labelled("error", common_unit(outputs, unit)),
            t_end,
            &errors,
            Scale::SymLog {
                threshold: symlog_threshold(&errors),
            },
            None,
            diverged_at,
        )?;
        let inputs: Vec<Curve> = run
            .names
            .inputs
            .iter()
            .enumerate()
            .map(|(i, name)| Curve {
                name: labelled(name, unit(name)),
                points: series(run, |s| s.u[i]),
                color: PALETTE[(i + 1) % PALETTE.len()],
                dashed: false,
            })
            .collect();
        let input_label = match run.names.inputs.as_slice() {
            [one] => labelled(one, unit(one)),
            all => labelled("input", common_unit(all, unit)),
        };
        panel(
            &panels[outputs.len() + 1],
            "control inputs (held between samples)",
            &input_label,
            t_end,
            &inputs,
            Scale::Linear,
            Some(run.scenario.h),
            diverged_at,
        )?;
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
        640 * runs.len().max(1) as u32,
        230 * (outputs as u32 + 2) + TITLE_HEIGHT + 30,
    );
    write_figure!(stem, size, |root| draw_closed_loop(&root, runs))
}

/// One series of a sweep plot: points `(parameter, error)`; `None` marks a diverged run.
pub struct SweepSeries {
    /// Legend text (the other parameters' values).
    pub name: String,
    /// `(parameter value, worst late error or None if diverged)`.
    pub points: Vec<(f64, Option<f64>)>,
}

/// Whether swept values span decades (all positive, largest at least 100 times the smallest):
/// then the parameter axis is logarithmic.
fn spans_decades(xs: impl Iterator<Item = f64>) -> bool {
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    lo.is_finite() && lo > 0.0 && hi >= 100.0 * lo
}

fn draw_sweep<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    parameter: &str,
    series: &[SweepSeries],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let (width, _) = root.dim_in_pixel();
    let (plot_area, legend_area) = root.split_horizontally(width.saturating_sub(LEGEND_WIDTH + 60));
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let log_x = spans_decades(xs.clone());
    let (x_lo, x_hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
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
    let caption =
        format!("largest |tracking error| over the last quarter against {parameter} (x: diverged)");
    if log_x {
        let chart = ChartBuilder::on(&plot_area)
            .caption(caption, ("sans-serif", 15))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(78)
            .build_cartesian_2d(
                (x_lo / 1.3..x_hi * 1.3).log_scale(),
                (y_lo..y_hi).log_scale(),
            )?;
        sweep_series(chart, parameter, series, y_hi, &|v| format!("{v:.0e}"))?;
    } else {
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
        let span = x_hi - x_lo;
        let chart = ChartBuilder::on(&plot_area)
            .caption(caption, ("sans-serif", 15))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(78)
            .build_cartesian_2d(x_lo..x_hi, (y_lo..y_hi).log_scale())?;
        sweep_series(chart, parameter, series, y_hi, &|v| tick(*v, span))?;
    }
    let legend: Vec<(String, RGBColor, bool)> = series
        .iter()
        .enumerate()
        .map(|(k, s)| (s.name.clone(), PALETTE[k % PALETTE.len()], false))
        .collect();
    draw_legend(&legend_area, &legend)?;
    root.present()
}

/// The curves and markers of a sweep on a chart whose parameter axis is linear or
/// logarithmic.
fn sweep_series<DB, X>(
    mut chart: ChartContext<'_, DB, Cartesian2d<X, LogCoord<f64>>>,
    parameter: &str,
    series: &[SweepSeries],
    y_hi: f64,
    x_format: &dyn Fn(&f64) -> String,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(parameter)
        .y_desc("max |e| over the last quarter")
        .x_label_formatter(x_format)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (k, s) in series.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let ok: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter_map(|&(x, y)| y.filter(|v| v.is_finite() && *v > 0.0).map(|y| (x, y)))
            .collect();
        chart.draw_series(LineSeries::new(ok.iter().copied(), color.stroke_width(2)))?;
        chart.draw_series(ok.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
        chart.draw_series(
            s.points
                .iter()
                .filter(|p| p.1.is_none())
                .map(|&(x, _)| Cross::new((x, y_hi / 2.0), 6, color.stroke_width(2))),
        )?;
    }
    Ok(())
}

/// Write `stem.svg` and `stem.png` of a sweep.
///
/// # Errors
/// [`ScenarioError::Write`] when drawing or writing fails.
pub fn sweep_figure(
    stem: &Path,
    title: &str,
    parameter: &str,
    series: &[SweepSeries],
) -> Result<[std::path::PathBuf; 2], ScenarioError> {
    register_font();
    write_figure!(stem, (1000, 600), |root| draw_sweep(
        &root, title, parameter, series
    ))
}

/// Write RGB `pixels` of `size` as a PNG file.
fn encode_png(path: &Path, pixels: &[u8], size: (u32, u32)) -> Result<(), ScenarioError> {
    let file = std::fs::File::create(path).map_err(|e| plot_error(path, e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), size.0, size.1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Best);
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    let mut writer = encoder.write_header().map_err(|e| plot_error(path, e))?;
    writer
        .write_image_data(pixels)
        .map_err(|e| plot_error(path, e))?;
    writer.finish().map_err(|e| plot_error(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_suit_the_span() {
        assert_eq!(tick(1.68, 0.2), "1.680");
        assert_eq!(tick(-120.0, 140.0), "-120");
        assert_eq!(tick(-1.11e-16, 1.4), "0.00");
        assert_eq!(tick(2.0e-5, 1e-4), "2.00e-5");
        assert_eq!(tick(8.0e5, 1.8e6), "8.00e5");
    }

    #[test]
    fn symmetric_log_ticks_are_signed_decades_within_the_range() {
        let threshold = 1e-5;
        let scale = Scale::SymLog { threshold };
        let (lo, hi) = (scale.map(-2e-2), scale.map(3e-4));
        let labels: Vec<String> = symlog_ticks(threshold, lo, hi)
            .into_iter()
            .map(|(_, l)| l)
            .collect();
        assert_eq!(labels, ["0", "1e-4", "-1e-4", "-1e-3", "-1e-2"]);
        // Zero outside the range (a constant error) is no tick.
        let (lo, hi) = (scale.map(0.2) - 0.01, scale.map(0.2) + 0.01);
        assert!(symlog_ticks(threshold, lo, hi).is_empty());
    }

    #[test]
    fn the_threshold_follows_the_late_errors() {
        let curve = |points: Vec<(f64, f64)>| Curve {
            name: String::new(),
            points,
            color: BLACK,
            dashed: false,
        };
        // A transient of 1e-2 settling on an oscillation of about 3e-5.
        let settling = curve(
            (0..100)
                .map(|k| {
                    let t = k as f64 * 0.1;
                    (t, 1e-2 * (-t).exp() + 3e-5 * (3.0 * t).sin())
                })
                .collect(),
        );
        assert_eq!(symlog_threshold(&[settling]), 1e-5);
        // Errors that never settle are still drawn over three decades.
        let growing = curve((0..10).map(|k| (k as f64, 0.5 * k as f64)).collect());
        assert_eq!(symlog_threshold(&[growing]), 1e-3);
        assert_eq!(symlog_threshold(&[curve(vec![(0.0, 0.0)])]), 1e-8);
    }

    #[test]
    fn held_inputs_are_steps_that_end_one_period_after_the_last_sample() {
        let steps = zero_order_hold(&[(0.0, 1.0), (0.5, 2.0)], 0.5);
        assert_eq!(steps, [(0.0, 1.0), (0.5, 1.0), (0.5, 2.0), (1.0, 2.0)]);
    }

    #[test]
    fn decades_decide_the_parameter_axis() {
        assert!(spans_decades([1e-4, 1e-3, 1e-2].into_iter()));
        assert!(!spans_decades([0.01, 0.05, 0.1].into_iter()));
        assert!(!spans_decades([-1.0, 1e3].into_iter()));
    }
}
