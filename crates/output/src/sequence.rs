//! Images of a session written to files: a still, or a frame sequence (SPEC §7, `--frames
//! A..B[:STEP]`) of one file a frame, named from a pattern, whole or not at all, so a
//! restarted job can leave the frames it finished. A still is the sequence of one frame.
//! Posing each frame and rebuilding only what moved is the render session's
//! ([`aperture_render::Session::frame`]); each frame's file is the single-frame render's, bit
//! for bit.

use crate::error::OutputError;
use crate::summary::RenderSummary;
use crate::write::{write_image, ImageFormat, ImageOutput};
use aperture_accel::{AccelStats, BvhQuality};
use aperture_denoise::Denoiser;
use aperture_render::motion::MotionSettings;
use aperture_render::sequence::FrameRange;
use aperture_render::{FrameSpec, RenderOptions, Session, SessionError};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The output file of `frame`: each run of `#` in the file name becomes the frame number,
/// zero-padded to the run's length (`shot_####.exr` → `shot_0012.exr`), as in Blender; a name
/// without `#` gets four digits before its extension (`shot.exr` → `shot0012.exr`). Negative
/// frames keep their sign (`-012`).
pub fn frame_path(pattern: &Path, frame: i64) -> PathBuf {
    let name = pattern
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let number = |width: usize| {
        if frame < 0 {
            format!("-{:0w$}", -frame, w = width.saturating_sub(1))
        } else {
            format!("{frame:0width$}")
        }
    };
    let renamed = if name.contains('#') {
        let mut out = String::new();
        let mut run = 0;
        for c in name.chars().chain(std::iter::once('\0')) {
            if c == '#' {
                run += 1;
                continue;
            }
            if run > 0 {
                out.push_str(&number(run));
                run = 0;
            }
            if c != '\0' {
                out.push(c);
            }
        }
        out
    } else {
        match name.rsplit_once('.') {
            Some((stem, ext)) => format!("{stem}{}.{ext}", number(4)),
            None => format!("{name}{}", number(4)),
        }
    };
    pattern.with_file_name(renamed)
}

/// What happened to one frame of a sequence.
#[derive(Debug, Clone)]
pub struct FrameReport {
    /// The frame number (`None`: a still image not at a frame).
    pub frame: Option<i64>,
    /// Its file.
    pub path: PathBuf,
    /// Its position in the sequence (0-based) and the sequence's length.
    pub index: (usize, usize),
    /// `None` when the file existed and `skip_existing` left it; else what the render took.
    pub rendered: Option<FrameWork>,
}

/// The work of one rendered frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameWork {
    /// The render and its file.
    pub summary: RenderSummary,
    /// The BVH of the frame: how much was built and how much reused.
    pub accel: AccelStats,
    /// Seconds posing the scene.
    pub pose_secs: f64,
    /// Seconds building what the frame's renders share (its BVH, motion, neighbours).
    pub build_secs: f64,
    /// Seconds for the whole frame (posing, BVH, render, writing).
    pub total_secs: f64,
}

/// Which images a [`Sequence`] renders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Frames {
    /// One image at `time` seconds (`None`: the pose stored in the file), written to the
    /// output path as it is; `frame` is its number, when it has one, for reports.
    Still {
        /// The frame number, if any.
        frame: Option<i64>,
        /// The time.
        time: Option<f64>,
    },
    /// Each frame of the range at `frame / fps` seconds, its file named from the output
    /// pattern ([`frame_path`]).
    Range(FrameRange),
}

/// A sequence to render.
pub struct Sequence<'a> {
    /// Which frames.
    pub frames: Frames,
    /// Frames per second: frame N is at N / fps seconds (Blender's exporter).
    pub fps: f32,
    /// The options of every frame.
    pub opts: &'a RenderOptions,
    /// BVH quality.
    pub quality: BvhQuality,
    /// The output file; for a range, a name with `#` for the frame number (see
    /// [`frame_path`]).
    pub pattern: &'a Path,
    /// The file format.
    pub format: ImageFormat,
    /// Leave frames whose file exists (files are written whole or not at all, so an existing
    /// file is a finished frame): a restarted job goes on where it stopped.
    pub skip_existing: bool,
    /// Denoise every frame.
    pub denoiser: Option<&'a Denoiser>,
    /// Motion blur: each frame's shutter interval posed with these settings (`None`, or a
    /// setting without a shutter, or a still without a time: every frame an instant).
    pub motion: Option<MotionSettings>,
}

impl Sequence<'_> {
    /// Each image: its frame number, time and file.
    fn images(&self) -> Vec<(Option<i64>, Option<f64>, PathBuf)> {
        match self.frames {
            Frames::Still { frame, time } => vec![(frame, time, self.pattern.to_path_buf())],
            Frames::Range(range) => range
                .frames()
                .map(|f| {
                    let time = f as f64 / f64::from(self.fps);
                    (Some(f), Some(time), frame_path(self.pattern, f))
                })
                .collect(),
        }
    }

    /// The frame spec of an image at `time`: motion blur and the Vector pass need a time.
    fn spec(&self, time: Option<f64>) -> FrameSpec {
        let o = self.opts;
        FrameSpec {
            time,
            fps: self.fps,
            quality: self.quality,
            motion: self.motion.filter(|_| time.is_some()),
            vector: time.is_some() && o.passes.contains(aperture_render::Pass::Vector),
            view: (o.camera, o.width, o.height),
        }
    }
}

/// Renders every frame of `seq` from `session` in turn: `tile_progress(done, total)` during
/// each frame, `frame_done(report)` after each. Each frame poses the session anew, which
/// rebuilds only what moved (the bottom-level BVHs of static meshes are kept). Stops at the
/// first error (a frame that cannot be posed, rendered or written).
pub fn render_sequence(
    session: &mut Session,
    seq: &Sequence<'_>,
    tile_progress: &(dyn Fn(usize, usize) + Sync),
    frame_done: &mut dyn FnMut(&FrameReport),
) -> Result<(), SequenceError> {
    let images = seq.images();
    let total = images.len();
    for (index, (frame, time, path)) in images.into_iter().enumerate() {
        let mut report = FrameReport {
            frame,
            path,
            index: (index, total),
            rendered: None,
        };
        if !(seq.skip_existing && report.path.is_file()) {
            let t0 = Instant::now();
            let posed = session.frame(&seq.spec(time));
            let posed = posed.map_err(|source| SequenceError::Pose { frame, source })?;
            let out = ImageOutput {
                path: &report.path,
                format: seq.format,
                denoiser: seq.denoiser,
            };
            let written = write_image(posed, seq.opts, &out, tile_progress);
            let summary = written.map_err(|source| SequenceError::Render { frame, source })?;
            report.rendered = Some(FrameWork {
                summary,
                accel: posed.accel().stats(),
                pose_secs: posed.times().pose_secs,
                build_secs: posed.times().build_secs,
                total_secs: t0.elapsed().as_secs_f64(),
            });
        }
        frame_done(&report);
    }
    Ok(())
}

/// Why a sequence stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SequenceError {
    /// The scene could not be posed at a frame.
    #[error("{}{source}", frame_prefix(*.frame))]
    Pose {
        /// The frame (`None`: a still not at a frame).
        frame: Option<i64>,
        /// What the session said.
        source: SessionError,
    },
    /// A frame could not be rendered or written.
    #[error("{}{source}", frame_prefix(*.frame))]
    Render {
        /// The frame (`None`: a still not at a frame).
        frame: Option<i64>,
        /// What went wrong.
        source: OutputError,
    },
}

/// `frame N: ` before a frame's error; nothing for a still not at a frame.
fn frame_prefix(frame: Option<i64>) -> String {
    frame.map_or(String::new(), |f| format!("frame {f}: "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_become_padded_frame_numbers() {
        let p = |s: &str, f| frame_path(Path::new(s), f).display().to_string();
        assert_eq!(p("out/shot_####.exr", 12), "out/shot_0012.exr");
        assert_eq!(p("shot_#.png", 123), "shot_123.png");
        assert_eq!(p("a##_b###.exr", 7), "a07_b007.exr");
        assert_eq!(p("shot.exr", 5), "shot0005.exr");
        assert_eq!(p("shot_####.exr", -12), "shot_-012.exr");
        // Only the file name is templated, not the folders.
        assert_eq!(p("take#/f_##.exr", 3), "take#/f_03.exr");
    }
}
