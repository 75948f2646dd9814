//! Progress of multi-image and Monte Carlo work, one style everywhere: the command line's
//! [`Progress`] receiver.
//!
//! On a terminal, an indicatif bar on stderr (hidden with `--json` or `--quiet`). Without a
//! terminal (a log, a pipe, CI), one line on stderr every [`LOG_EVERY`] while work runs:
//! what, how far, time left. A run shorter than that prints nothing, so a quick command's
//! stderr stays its one-line error. `--quiet` silences both.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use etl_core::progress::Progress;
use indicatif::{ProgressBar, ProgressStyle};

/// How often a log line is written when stderr is not a terminal.
pub const LOG_EVERY: Duration = Duration::from_secs(5);

/// Set once by `main` from `--quiet`.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Silences every progress report of this process (`--quiet`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// A progress receiver on stderr: a bar on a terminal, log lines otherwise.
pub struct Bar {
    shown: Shown,
}

enum Shown {
    Terminal(ProgressBar),
    Log(Mutex<LogState>),
    Nothing,
}

/// The state of the log lines: the work's name and size, its start, the last line.
struct LogState {
    label: String,
    len: usize,
    done: usize,
    started: Instant,
    last_line: Instant,
}

impl Bar {
    /// A receiver: on a terminal a bar, drawn when `show_bar` (false for `--json`); without
    /// a terminal, log lines; nothing at all under `--quiet`.
    pub fn new(show_bar: bool) -> Self {
        let shown = if QUIET.load(Ordering::Relaxed) {
            Shown::Nothing
        } else if std::io::stderr().is_terminal() {
            if show_bar {
                Shown::Terminal(styled_bar())
            } else {
                Shown::Nothing
            }
        } else {
            let now = Instant::now();
            Shown::Log(Mutex::new(LogState { label: String::new(), len: 0, done: 0, started: now, last_line: now }))
        };
        Bar { shown }
    }
}

fn styled_bar() -> ProgressBar {
    let bar = ProgressBar::new(0);
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})")
    {
        bar.set_style(style);
    }
    bar
}

impl LogState {
    /// The log line of the work so far: `etlcal: rendering 12/30 (40 %), 6 s elapsed, about 9 s left`.
    fn line(&self, now: Instant) -> String {
        let elapsed = now.duration_since(self.started).as_secs_f64();
        let pct = if self.len == 0 { 0.0 } else { 100.0 * self.done as f64 / self.len as f64 };
        let left = if self.done == 0 || self.done >= self.len {
            String::new()
        } else {
            let rest = elapsed * (self.len - self.done) as f64 / self.done as f64;
            format!(", about {rest:.0} s left")
        };
        format!("etlcal: {} {}/{} ({pct:.0} %), {elapsed:.0} s elapsed{left}", self.label, self.done, self.len)
    }
}

impl Progress for Bar {
    fn start(&self, len: usize, label: &str) {
        match &self.shown {
            Shown::Terminal(bar) => {
                bar.reset();
                bar.set_length(len as u64);
                bar.set_message(label.to_owned());
            }
            Shown::Log(state) => {
                if let Ok(mut s) = state.lock() {
                    let now = Instant::now();
                    *s = LogState { label: label.to_owned(), len, done: 0, started: now, last_line: now };
                }
            }
            Shown::Nothing => {}
        }
    }
    fn advance(&self, steps: usize) {
        match &self.shown {
            Shown::Terminal(bar) => bar.inc(steps as u64),
            Shown::Log(state) => {
                if let Ok(mut s) = state.lock() {
                    s.done = s.done.saturating_add(steps);
                    let now = Instant::now();
                    if now.duration_since(s.last_line) >= LOG_EVERY {
                        s.last_line = now;
                        eprintln!("{}", s.line(now));
                    }
                }
            }
            Shown::Nothing => {}
        }
    }
    fn finish(&self) {
        if let Shown::Terminal(bar) = &self.shown {
            bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_log_line_says_what_how_far_and_time_left() {
        let t0 = Instant::now();
        let s = LogState { label: "rendering".into(), len: 30, done: 12, started: t0, last_line: t0 };
        assert_eq!(s.line(t0 + Duration::from_secs(6)), "etlcal: rendering 12/30 (40 %), 6 s elapsed, about 9 s left");
        let done = LogState { done: 30, ..s };
        assert_eq!(done.line(t0 + Duration::from_secs(15)), "etlcal: rendering 30/30 (100 %), 15 s elapsed");
    }
}
