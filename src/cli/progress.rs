//! Progress on a terminal: one bar routine for `dpc sweep` (runs done) and `dpc simulate`
//! (the simulated time of a run that takes longer than a second), drawn on stderr only when
//! stderr is a terminal, so that piped or redirected output stays free of it.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use dpc::core::simulate::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long a run goes without a bar: shorter runs draw nothing.
pub const RUN_BAR_DELAY: Duration = Duration::from_secs(1);

/// Whether progress is drawn: stderr is a terminal.
pub fn on_terminal() -> bool {
    std::io::stderr().is_terminal()
}

/// A bar of `len` steps, `counts` (an indicatif template such as `"{pos}/{len} runs"`) after
/// it, then the elapsed time and the estimate of the time left; drawn on stderr when
/// `visible`, hidden otherwise.
pub fn bar(len: u64, counts: &str, visible: bool) -> ProgressBar {
    let target = if visible {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(len), target);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{bar:40}} {counts}, {{elapsed}} elapsed, eta {{eta}}"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// Steps of a run's bar: its simulated time in thousandths.
const RUN_STEPS: u64 = 1000;

/// The progress of one closed-loop run ([`Progress`]): a bar of the simulated time that
/// appears on a terminal once the run has taken [`RUN_BAR_DELAY`], and is cleared when the
/// run ends (dropped). Never drawn when not `visible`.
#[derive(Debug)]
pub struct RunProgress {
    bar: ProgressBar,
    visible: bool,
    started: Instant,
    shown: bool,
}

impl RunProgress {
    /// A run starting now; `visible`: whether it may draw (see [`on_terminal`]).
    pub fn new(visible: bool) -> Self {
        Self {
            bar: bar(RUN_STEPS, "{percent:>3}% simulated", false),
            visible,
            started: Instant::now(),
            shown: false,
        }
    }

    /// Whether the bar has been drawn.
    pub fn shown(&self) -> bool {
        self.shown
    }
}

impl Progress for RunProgress {
    fn sample(&mut self, t: f64, t_final: f64) {
        if !self.visible {
            return;
        }
        if !self.shown {
            if self.started.elapsed() < RUN_BAR_DELAY {
                return;
            }
            self.shown = true;
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        let done = if t_final > 0.0 { t / t_final } else { 1.0 };
        self.bar
            .set_position((done.clamp(0.0, 1.0) * RUN_STEPS as f64) as u64);
    }
}

impl Drop for RunProgress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_off_the_terminal_never_draws() {
        let mut progress = RunProgress::new(false);
        for k in 0..=10 {
            progress.sample(k as f64, 10.0);
        }
        assert!(!progress.shown());
        assert!(bar(3, "{pos}/{len} runs", false).is_hidden());
    }

    #[test]
    fn a_short_run_draws_nothing() {
        // Visible, but done well within the delay.
        let mut progress = RunProgress {
            bar: bar(RUN_STEPS, "{percent}%", false),
            visible: true,
            started: Instant::now() + Duration::from_secs(3600),
            shown: false,
        };
        progress.sample(1.0, 2.0);
        assert!(!progress.shown());
    }
}
