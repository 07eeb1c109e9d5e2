//! Progress bars on stderr, shown only on a terminal, without `--quiet`, and for work that
//! takes longer than about a second (indicatif draws nothing before its first tick interval).

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar that is hidden when it should not be drawn.
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar of `total` steps labelled `what`.
    pub fn new(quiet: bool, what: &str, total: u64) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        if !quiet && std::io::stderr().is_terminal() {
            bar.set_draw_target(ProgressDrawTarget::stderr_with_hz(8));
            bar.set_style(
                ProgressStyle::with_template(
                    "{msg:>12} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            bar.set_message(what.to_string());
            // Nothing is drawn for short runs: the first draw happens after a second.
            bar.enable_steady_tick(Duration::from_millis(1000));
        }
        Self { bar }
    }

    /// Sets the position.
    pub fn set(&self, done: u64) {
        self.bar.set_position(done);
    }

    /// Sets the total.
    pub fn set_total(&self, total: u64) {
        self.bar.set_length(total);
    }

    /// Sets the position and the total.
    pub fn update(&self, done: usize, total: usize) {
        self.set_total(total as u64);
        self.set(done as u64);
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
