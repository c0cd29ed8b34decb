//! Render progress: a bar on stderr for people, or JSON lines on stdout for programs (farm
//! wrappers, the Blender engine).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::{IsTerminal as _, Write as _};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// `--progress`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ProgressArg {
    /// A bar with ETA on stderr when it is a terminal (and not --quiet), else nothing.
    #[default]
    Auto,
    /// One JSON object per line on stdout at every update, for programs: `{"event":
    /// "progress", "frame": N|null, "done": D, "total": T, "fraction": F, "samples_done": S,
    /// "samples_total": ST, "elapsed": SECONDS}`; `"event": "frame"` when a frame's file is
    /// written. Not silenced by --quiet.
    Json,
}

/// JSON progress state.
struct JsonLines {
    start: Instant,
    samples_total: AtomicU64,
    frame: Mutex<Option<i64>>,
    /// Highest `done` printed in this frame (tiles finish out of order).
    last: Mutex<usize>,
}

/// A progress bar with ETA, shown only when stderr is a terminal and not `--quiet`, or JSON
/// lines (see [`ProgressArg::Json`]).
pub struct Progress {
    bar: Option<ProgressBar>,
    json: Option<JsonLines>,
}

impl Progress {
    /// Progress as `--progress` and `--quiet` ask.
    pub fn with_mode(quiet: bool, mode: ProgressArg) -> Self {
        match mode {
            ProgressArg::Auto => Self::new(quiet),
            ProgressArg::Json => Self {
                bar: None,
                json: Some(JsonLines {
                    start: Instant::now(),
                    samples_total: AtomicU64::new(0),
                    frame: Mutex::new(None),
                    last: Mutex::new(0),
                }),
            },
        }
    }

    /// The samples the render (or the current frame) will take, for the JSON lines.
    pub fn set_samples(&self, total: u64, frame: Option<i64>) {
        if let Some(j) = &self.json {
            j.samples_total.store(total, Ordering::Relaxed);
            *j.frame.lock().unwrap_or_else(|e| e.into_inner()) = frame;
            *j.last.lock().unwrap_or_else(|e| e.into_inner()) = 0;
        }
    }

    /// Prints one JSON line on stdout (flushed, so a reader sees it at once).
    fn json_line(line: &str) {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "{line}");
        let _ = out.flush();
    }

    /// A JSON line that frame `frame`'s file `path` is written (JSON mode only).
    pub fn frame_written(&self, frame: Option<i64>, path: &std::path::Path, secs: f64) {
        if self.json.is_some() {
            let frame = frame.map_or("null".to_string(), |f| f.to_string());
            let path = serde_json::to_string(&path.display().to_string()).unwrap_or_default();
            Self::json_line(&format!(
                "{{\"event\":\"frame\",\"frame\":{frame},\"path\":{path},\"seconds\":{secs:.3}}}"
            ));
        }
    }

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
        Self { bar, json: None }
    }

    /// `done` of `total` tiles finished (called from worker threads).
    pub fn update(&self, done: usize, total: usize) {
        if let Some(j) = &self.json {
            let mut last = j.last.lock().unwrap_or_else(|e| e.into_inner());
            if done > *last {
                *last = done;
                let fraction = done as f64 / total.max(1) as f64;
                let samples = j.samples_total.load(Ordering::Relaxed);
                let frame = j
                    .frame
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .map_or("null".to_string(), |f| f.to_string());
                Self::json_line(&format!(
                    "{{\"event\":\"progress\",\"frame\":{frame},\"done\":{done},\"total\":{total},\"fraction\":{fraction:.6},\"samples_done\":{},\"samples_total\":{samples},\"elapsed\":{:.3}}}",
                    (fraction * samples as f64).round() as u64,
                    j.start.elapsed().as_secs_f64()
                ));
            }
        }
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
