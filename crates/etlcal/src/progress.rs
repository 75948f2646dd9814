//! Progress bars of multi-image and Monte Carlo work (indicatif), one style everywhere:
//! the command line's [`Progress`] receiver.

use etl_core::progress::Progress;
use indicatif::{ProgressBar, ProgressStyle};

/// A bar on stderr, hidden when `show` is false (JSON output) or stderr is not a terminal.
pub struct Bar {
    bar: ProgressBar,
}

impl Bar {
    /// A bar, drawn when `show`.
    pub fn new(show: bool) -> Self {
        let bar = if show { ProgressBar::new(0) } else { ProgressBar::hidden() };
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>10} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})")
        {
            bar.set_style(style);
        }
        Bar { bar }
    }
}

impl Progress for Bar {
    fn start(&self, len: usize, label: &str) {
        self.bar.reset();
        self.bar.set_length(len as u64);
        self.bar.set_message(label.to_owned());
    }
    fn advance(&self, steps: usize) {
        self.bar.inc(steps as u64);
    }
    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
