//! Render progress on stderr.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal as _;

/// A progress bar with ETA, shown only when stderr is a terminal and not `--quiet`.
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// A bar, or nothing when it would only clutter a log.
    pub fn new(quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(0);
            if let Ok(style) = ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} tiles, ETA {eta}",
            ) {
                bar.set_style(style);
            }
            bar
        });
        Self { bar }
    }

    /// `done` of `total` tiles finished (called from worker threads).
    pub fn update(&self, done: usize, total: usize) {
        if let Some(bar) = &self.bar {
            bar.set_length(total as u64);
            // Tiles finish out of order; the counter only grows.
            if done as u64 > bar.position() {
                bar.set_position(done as u64);
            }
        }
    }

    /// Prints a line above the bar (or alone without one) and starts the bar over, for the
    /// next frame of a sequence.
    pub fn next_frame(&self, line: &str) {
        match &self.bar {
            Some(bar) => {
                bar.println(line);
                bar.set_position(0);
            }
            None => eprintln!("{line}"),
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
