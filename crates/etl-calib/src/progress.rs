//! Progress bars of multi-image and Monte Carlo work (indicatif), one style everywhere.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` steps labelled `label` (e.g. "rendering", "detecting"), drawn on stderr;
/// hidden when `show` is false (JSON output, tests) or stderr is not a terminal.
pub fn bar(len: usize, label: &str, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})")
    {
        b.set_style(style);
    }
    b.set_message(label.to_owned());
    b
}
