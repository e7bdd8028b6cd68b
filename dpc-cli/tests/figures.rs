//! Every figure the command line makes, rendered and checked as a reader would look at it:
//! a PNG of a sensible size that is not blank, and an SVG with the title, the axis labels
//! (with units where the model gives them), the legends and, for a diverged run, the marker
//! of its divergence.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scenario(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenarios")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dpc-cli-figures-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn dpc(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_dpc"))
        .args(args)
        .output()
        .expect("dpc runs");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Width, height and the share of pixels that are not white, of an 8-bit RGB PNG.
fn png_stats(path: &Path) -> (u32, u32, f64) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).expect("PNG written"),
    ));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut pixels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut pixels).expect("PNG data");
    let channels = info.color_type.samples();
    let ink = pixels[..info.buffer_size()]
        .chunks(channels)
        .filter(|p| p.iter().take(3).any(|&c| c < 245))
        .count();
    let total = (info.width * info.height) as f64;
    (info.width, info.height, ink as f64 / total)
}

fn check_png(path: &Path) {
    let bytes = std::fs::metadata(path).expect("PNG written").len();
    let (w, h, ink) = png_stats(path);
    assert!(
        (600..=2600).contains(&w) && (400..=2400).contains(&h),
        "{w}x{h}"
    );
    assert!(bytes < 400_000, "{} is {bytes} bytes", path.display());
    // Lines, text and frames, but not a filled area: between 2 % and 40 % ink.
    assert!((0.02..0.4).contains(&ink), "{}: ink {ink}", path.display());
}

#[test]
fn the_closed_loop_figure_has_titles_labels_legends_and_the_divergence() {
    let out = scratch("wheel");
    dpc(&[
        "simulate",
        scenario("wheel.toml").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "t_end=3",
    ]);
    check_png(&out.join("closed-loop.png"));
    let svg = std::fs::read_to_string(out.join("closed-loop.svg")).unwrap();
    for text in [
        // The scenario's title, each column's run and verdict.
        "Rolling wheel",
        "with preliminary feedback, no divergence",
        "without preliminary feedback, diverged at t = ",
        // Axis labels (with the units the model declares) and panel titles.
        "t [s]",
        "theta [rad]",
        "psi [rad]",
        "theta and its reference",
        "tracking errors y - reference (symmetric log scale)",
        "control inputs (held between samples)",
        // Legends.
        "reference",
        "e_theta [rad]",
        "u1 [N m]",
        // Decade ticks of the error axis.
        "1e-4",
    ] {
        assert!(svg.contains(text), "closed-loop.svg lacks {text:?}");
    }
    // The same units in the header of the trajectory.
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let header = csv.lines().next().unwrap_or_default();
    assert!(
        header.starts_with("t [s],theta [rad],psi [rad],dphi [rad/s]"),
        "{header}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_sweep_over_decades_has_a_logarithmic_parameter_axis() {
    let out = scratch("sweep");
    dpc(&[
        "sweep",
        scenario("wheel.toml").to_str().unwrap(),
        "--set",
        "delta=0.0001,0.001,0.01",
        "--set",
        "t_end=1",
        "--set",
        "compare=[]",
        "--out",
        out.to_str().unwrap(),
    ]);
    check_png(&out.join("sweep.png"));
    let svg = std::fs::read_to_string(out.join("sweep.svg")).unwrap();
    for text in ["sweep", "max |e| over the last quarter", "delta"] {
        assert!(svg.contains(text), "sweep.svg lacks {text:?}");
    }
    // Decade labels on the parameter axis: 1e-4 .. 1e-2 appear as tick labels.
    assert!(
        svg.contains("1e-4") && svg.contains("1e-2"),
        "no decade ticks"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// The most vertices of one polyline of an SVG (plotters draws each curve as one).
fn longest_polyline(svg: &str) -> usize {
    svg.split("points=\"")
        .skip(1)
        .map(|rest| {
            rest.split('"')
                .next()
                .unwrap_or("")
                .split_whitespace()
                .count()
        })
        .max()
        .unwrap_or(0)
}

#[test]
fn with_an_output_step_the_figure_draws_the_motion_between_the_samples() {
    let draw = |name: &str, extra: &[&str]| {
        let out = scratch(name);
        let mut args = vec![
            "simulate",
            scenario("wheel.toml").to_str().unwrap().to_owned().leak(),
            "--out",
            out.to_str().unwrap().to_owned().leak(),
            "--set",
            "t_end=1",
            "--set",
            "compare=[]",
        ];
        args.extend_from_slice(extra);
        dpc(&args);
        check_png(&out.join("closed-loop.png"));
        let svg = std::fs::read_to_string(out.join("closed-loop.svg")).unwrap();
        let _ = std::fs::remove_dir_all(&out);
        longest_polyline(&svg)
    };
    // h = 0.05: 21 samples; the held input is drawn as steps, 2 vertices a sample.
    let samples = draw("samples", &[]);
    // Four more points in each of the 20 intervals: 101 points on each output curve.
    let dense = draw("dense", &["--set", "output_step=0.01"]);
    assert!(samples <= 2 * 21, "{samples}");
    assert!(dense >= 101, "{dense}");
}
