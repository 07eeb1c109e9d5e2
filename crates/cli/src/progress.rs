//! Progress on stderr without `--quiet`: a bar on a terminal, for work that takes longer than
//! about a second (indicatif draws nothing before its first tick interval); with no terminal
//! (piped or redirected output) a plain line at most every [`LINE_EVERY`], with the position
//! when there is one, so a long run is never silent for minutes.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Shortest time between two progress lines written without a terminal.
pub const LINE_EVERY: Duration = Duration::from_secs(10);

/// The line printer of a run without a terminal: a thread that wakes every second and writes
/// `what: done/total (elapsed)` when [`LINE_EVERY`] has passed since the last line.
struct Lines {
    /// What is running (the label of each line).
    what: Arc<Mutex<String>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
    done: Arc<AtomicU64>,
    total: Arc<AtomicU64>,
}

impl Lines {
    fn start(what: String, total: u64) -> Self {
        let what = Arc::new(Mutex::new(what));
        let label = what.clone();
        let stop = Arc::new(AtomicBool::new(false));
        let done = Arc::new(AtomicU64::new(0));
        let total = Arc::new(AtomicU64::new(total));
        let (s, d, t) = (stop.clone(), done.clone(), total.clone());
        let thread = std::thread::Builder::new()
            .name("progress".into())
            .spawn(move || {
                let start = Instant::now();
                let last = Mutex::new(start);
                while !s.load(Ordering::Relaxed) {
                    std::thread::sleep(Duration::from_millis(250));
                    let mut l = last.lock().unwrap_or_else(|e| e.into_inner());
                    if l.elapsed() >= LINE_EVERY && !s.load(Ordering::Relaxed) {
                        *l = Instant::now();
                        let (d, t) = (d.load(Ordering::Relaxed), t.load(Ordering::Relaxed));
                        let secs = start.elapsed().as_secs();
                        let what = label.lock().unwrap_or_else(|e| e.into_inner()).clone();
                        eprintln!("{}", line(&what, d, t, secs));
                    }
                }
            })
            .ok();
        Lines {
            what,
            stop,
            thread,
            done,
            total,
        }
    }

    fn finish(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One progress line: `progress: what: done/total (elapsed, eta)`, or `still running` for
/// work without a count.
fn line(what: &str, done: u64, total: u64, secs: u64) -> String {
    let label = if what.is_empty() { "running" } else { what };
    if total > 1 {
        let eta = if done > 0 && done < total {
            format!(", eta {} s", secs * (total - done) / done)
        } else {
            String::new()
        };
        format!("progress: {label}: {done}/{total} ({secs} s{eta})")
    } else {
        format!("progress: {label}: still running ({secs} s)")
    }
}

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar that is hidden when it should not be drawn (lines instead without a
/// terminal).
pub struct Progress {
    bar: ProgressBar,
    lines: Mutex<Option<Lines>>,
}

impl Progress {
    /// A bar of `total` steps labelled `what`.
    pub fn new(quiet: bool, what: &str, total: u64) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        let terminal = std::io::stderr().is_terminal();
        let lines = (!quiet && !terminal).then(|| Lines::start(what.to_string(), total));
        if !quiet && terminal {
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
        Self {
            bar,
            lines: Mutex::new(lines),
        }
    }

    /// Sets the position.
    pub fn set(&self, done: u64) {
        self.bar.set_position(done);
        if let Some(l) = &*self.lines.lock().unwrap_or_else(|e| e.into_inner()) {
            l.done.store(done, Ordering::Relaxed);
        }
    }

    /// Sets what is running (the bar's message, the label of the next line).
    pub fn set_message(&self, what: &str) {
        self.bar.set_message(what.to_string());
        if let Some(l) = &*self.lines.lock().unwrap_or_else(|e| e.into_inner()) {
            *l.what.lock().unwrap_or_else(|e| e.into_inner()) = what.to_string();
        }
    }

    /// Sets the total.
    pub fn set_total(&self, total: u64) {
        self.bar.set_length(total);
        if let Some(l) = &*self.lines.lock().unwrap_or_else(|e| e.into_inner()) {
            l.total.store(total, Ordering::Relaxed);
        }
    }

    /// Sets the position and the total.
    pub fn update(&self, done: usize, total: usize) {
        self.set_total(total as u64);
        self.set(done as u64);
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
        if let Some(l) = &mut *self.lines.lock().unwrap_or_else(|e| e.into_inner()) {
            l.finish();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_name_the_work_its_count_and_its_stage() {
        assert_eq!(
            line("mass scan", 2, 4, 10),
            "progress: mass scan: 2/4 (10 s, eta 10 s)"
        );
        assert_eq!(
            line("mass scan", 4, 4, 20),
            "progress: mass scan: 4/4 (20 s)"
        );
        assert_eq!(
            line("", 0, 1, 30),
            "progress: running: still running (30 s)"
        );
        // A stage set while running is the label of the next line.
        let progress = Progress {
            bar: ProgressBar::hidden(),
            lines: Mutex::new(Some(Lines::start("spring derivation".to_string(), 1))),
        };
        progress.set_message("spring derivation, the small-motion check");
        let what = {
            let lines = progress.lines.lock().unwrap();
            lines.as_ref().unwrap().what.lock().unwrap().clone()
        };
        assert_eq!(
            line(&what, 0, 1, 10),
            "progress: spring derivation, the small-motion check: still running (10 s)"
        );
        progress.finish();
    }
}
