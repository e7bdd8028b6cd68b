//! README's sampling-period study of the wheel (section "Sampling period"): per hold variant
//! and deviation coordinates of the preliminary feedback, the largest period `h` at which the
//! nonlinear loop still tracks (late errors below 0.1 rad), the largest at which it reports no
//! divergence, and the linear sampled-data prediction, found by bisection. A few minutes in
//! release mode:
//!
//! ```sh
//! cargo run --release --example sampling_period
//! ```

#[path = "../tests/common/wheel_loop.rs"]
mod wheel_loop;

use dpc::core::simulate::Hold;
use wheel_loop::{bisect, predicted_critical_period, stays_bounded, tracks, About};

fn main() {
    println!(
        "| hold | about | tracks up to h | bounded up to h | predicted h | bounded / predicted |"
    );
    println!("|---|---|---|---|---|---|");
    for (about, hold) in [
        (About::Nominal, Hold::Input),
        (About::Reference, Hold::Input),
        (About::Nominal, Hold::Correction),
        (About::Reference, Hold::Correction),
    ] {
        let predicted = predicted_critical_period(hold);
        let accurate = bisect(|h| tracks(h, about, hold), 0.02, 2.0 * predicted);
        let bounded = bisect(|h| stays_bounded(h, about, hold), 0.02, 2.0 * predicted);
        println!(
            "| {hold:?} | {about:?} | {accurate:.3} | {bounded:.3} | {predicted:.3} | {:.2} |",
            bounded / predicted
        );
    }
}
