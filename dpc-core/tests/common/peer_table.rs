//! Rows of the peer work-precision table (`bench/peers.sh`), shared by dpc-core's
//! `work_precision` example and the diffsol peer (`bench/diffsol_peer`) so that both print and
//! time their rows the same way as the IDA driver (`bench/ida_peer.c`).
//!
//! A row is `KEY<TAB>| problem | rtol | code | steps | error-test failures | Newton failures |
//! Jacobians | scd | time [ms] |` with `KEY = PP-KK-C` (problem, tolerance exponent, code), by
//! which `bench/peers.sh` sorts the merged rows. The time is the thread's CPU time per solve
//! (the mean over repetitions filling at least 0.3 s of it, at least 3), so that other jobs on
//! the machine do not enter it.
#![allow(dead_code)]

use std::time::Instant;

/// One solve's counters and end state.
pub struct Run {
    /// Accepted steps.
    pub steps: usize,
    /// Steps rejected by the error test.
    pub error_test_failures: usize,
    /// Steps rejected because Newton's iteration failed.
    pub newton_failures: usize,
    /// Jacobian (iteration-matrix) evaluations or, for diffsol, linear-solver setups.
    pub jacobians: usize,
    /// The state at the end point.
    pub y: Vec<f64>,
}

/// CPU time of the calling thread in seconds (`/proc/thread-self/schedstat`, nanoseconds), or
/// `None` where that file does not exist.
pub fn thread_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Mean time in milliseconds of `solve` over repetitions filling at least 0.3 s (at least 3):
/// thread CPU time where available, else wall-clock time.
pub fn time_ms<T>(mut solve: impl FnMut() -> T) -> f64 {
    let wall = Instant::now();
    let cpu0 = thread_cpu_seconds();
    let elapsed = || match (cpu0, thread_cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => wall.elapsed().as_secs_f64(),
    };
    let mut reps = 0u32;
    while reps < 3 || elapsed() < 0.3 {
        // Only the time is kept: the result is the one already scored.
        std::hint::black_box(solve());
        reps += 1;
    }
    elapsed() * 1e3 / f64::from(reps)
}

/// Solves once, scores the end state with `score` and, if the solve succeeded, times it; prints
/// the row (a failure as `failed (message up to its first ';')`).
pub fn row(
    (problem, name): (u8, &str),
    k: i32,
    (code, code_name): (u8, &str),
    score: impl Fn(&[f64]) -> f64,
    solve: impl Fn() -> Result<Run, String>,
) {
    let head = format!("{problem:02}-{k:02}-{code}\t| {name} | 1e-{k} | {code_name} |");
    match solve() {
        Err(e) => {
            // The cause, without the advice that follows it.
            let cause = e.split(';').next().unwrap_or_default();
            println!("{head} failed ({cause}) | | | | | |");
        }
        Ok(run) => {
            let ms = time_ms(&solve);
            println!(
                "{head} {} | {} | {} | {} | {:.2} | {ms:.3} |",
                run.steps,
                run.error_test_failures,
                run.newton_failures,
                run.jacobians,
                score(&run.y)
            );
        }
    }
}
