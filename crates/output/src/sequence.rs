//! Frame sequences written to files (SPEC §7, `--frames A..B[:STEP]`): one file a frame, named
//! from a pattern, whole or not at all, so a restarted job can leave the frames it finished.
//! Posing each frame and rebuilding only what moved is the renderer's
//! ([`aperture_render::sequence::for_each_frame`]); each frame's file is the single-frame
//! render's, bit for bit.

use crate::{render_exr, render_png, ExrOptions, OutputError, RenderSummary};
use aperture_accel::{Accel, AccelStats, BvhQuality};
use aperture_denoise::Denoiser;
use aperture_imageio::PngOptions;
use aperture_render::motion::{pose_frame_motion, pose_neighbours, MotionSettings};
use aperture_render::sequence::{for_each_frame, FrameRange, PosedFrame};
use aperture_render::{build_motion_accel, RenderOptions, SceneHints};
use aperture_scene::{Animated, Scene};
use std::path::{Path, PathBuf};
use std::sync::Arc;
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

/// How the frames of a sequence are written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameFormat {
    /// EXR with the passes of the render options.
    Exr(ExrOptions),
    /// PNG with its view transform, opaque unless `transparent`.
    Png {
        /// Exposure and view.
        png: PngOptions,
        /// Keep coverage as alpha.
        transparent: bool,
    },
}

/// What happened to one frame of a sequence.
#[derive(Debug, Clone)]
pub struct FrameReport {
    /// The frame number.
    pub frame: i64,
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
    /// Seconds for the whole frame (posing, BVH, render, writing).
    pub total_secs: f64,
}

/// A sequence to render.
pub struct Sequence<'a> {
    /// The loaded file.
    pub animated: &'a Animated,
    /// Which frames.
    pub frames: FrameRange,
    /// Frames per second: frame N is at N / fps seconds (Blender's exporter).
    pub fps: f32,
    /// The options of every frame.
    pub opts: &'a RenderOptions,
    /// BVH quality.
    pub quality: BvhQuality,
    /// The output name with `#` for the frame number (see [`frame_path`]).
    pub pattern: &'a Path,
    /// The file format.
    pub format: FrameFormat,
    /// Leave frames whose file exists (files are written whole or not at all, so an existing
    /// file is a finished frame): a restarted job goes on where it stopped.
    pub skip_existing: bool,
    /// Denoise every frame ([`crate::render_exr_denoised`], [`crate::render_png_denoised`]).
    pub denoiser: Option<&'a Denoiser>,
    /// Motion blur: each frame's shutter interval posed with these settings (`None`, or a
    /// setting without a shutter: every frame an instant).
    pub motion: Option<MotionSettings>,
}

/// Renders every frame of `seq` in turn: `tile_progress(done, total)` during each frame,
/// `frame_done(report)` after each. Stops at the first error (a frame that cannot be posed,
/// rendered or written).
pub fn render_sequence(
    seq: &Sequence<'_>,
    tile_progress: &(dyn Fn(usize, usize) + Sync),
    frame_done: &mut dyn FnMut(&FrameReport),
) -> Result<(), SequenceError> {
    let skip = |frame| seq.skip_existing && frame_path(seq.pattern, frame).is_file();
    let mut each = |f: PosedFrame<'_>| -> Result<(), SequenceError> {
        let t0 = Instant::now();
        let path = frame_path(seq.pattern, f.frame);
        let mut report = FrameReport {
            frame: f.frame,
            path: path.clone(),
            index: f.index,
            rendered: None,
        };
        if let Some((scene, accel)) = f.posed {
            let opts =
                frame_options(seq, f.frame, scene).map_err(|source| SequenceError::Pose {
                    frame: f.frame,
                    source,
                })?;
            // Instances moving and meshes deforming within the shutter need a structure
            // bounding them over it: the frame's is rebuilt with their motion (nothing of it
            // reused).
            let moving = opts.motion.as_deref().filter(|m| m.moves_geometry());
            let rebuilt = moving.map(|m| {
                let hints = SceneHints::new(seq.animated, scene);
                build_motion_accel(scene, seq.quality, &hints, None, Some(m))
            });
            let accel = rebuilt.as_ref().unwrap_or(accel);
            let written = write_frame(seq, &opts, scene, accel, &path, tile_progress);
            let summary = written.map_err(|source| SequenceError::Render {
                frame: f.frame,
                source,
            })?;
            report.rendered = Some(FrameWork {
                summary,
                accel: accel.stats(),
                pose_secs: f.pose_secs,
                total_secs: f.setup_secs + t0.elapsed().as_secs_f64(),
            });
        }
        frame_done(&report);
        Ok(())
    };
    let pose_error = |frame, source| SequenceError::Pose { frame, source };
    for_each_frame(
        seq.animated,
        seq.frames,
        seq.fps,
        seq.quality,
        &skip,
        &mut each,
        pose_error,
    )
}

/// The options of `frame` (posed as `scene`): the sequence's, with the frame's motion.
fn frame_options(
    seq: &Sequence<'_>,
    frame: i64,
    scene: &Scene,
) -> Result<RenderOptions, aperture_scene::Error> {
    let mut opts = seq.opts.clone();
    let fps = f64::from(seq.fps);
    let frame_time = frame as f64 / fps;
    if opts.passes.contains(aperture_render::Pass::Vector) {
        let at = (opts.camera, opts.width, opts.height);
        opts.vector = pose_neighbours(seq.animated, (frame_time, fps), scene, at)?.map(Arc::new);
    }
    if let Some(settings) = &seq.motion {
        opts.motion = pose_frame_motion(
            seq.animated,
            settings,
            (frame_time, fps),
            scene,
            (opts.camera, opts.width, opts.height),
        )?
        .map(Arc::new);
    }
    Ok(opts)
}

/// One posed frame of `seq` rendered into its file with `opts`.
fn write_frame(
    seq: &Sequence<'_>,
    opts: &RenderOptions,
    scene: &Scene,
    accel: &Accel,
    path: &Path,
    tile_progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    let format = seq.format;
    render_image(
        scene,
        accel,
        opts,
        path,
        format,
        seq.denoiser,
        tile_progress,
    )
}

/// Renders `opts` and writes it to `path` in `format`, denoised when a `denoiser` is given: the
/// one way a still image and each frame of a sequence are written.
pub fn render_image(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    path: &Path,
    format: FrameFormat,
    denoiser: Option<&Denoiser>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    match (format, denoiser) {
        (FrameFormat::Exr(exr), Some(d)) => {
            crate::render_exr_denoised(scene, accel, opts, path, &exr, d, progress)
        }
        (FrameFormat::Png { png, transparent }, Some(d)) => {
            let t = transparent;
            crate::render_png_denoised(scene, accel, opts, path, &png, t, d, progress)
        }
        (FrameFormat::Exr(exr), None) => render_exr(scene, accel, opts, path, &exr, progress),
        (FrameFormat::Png { png, transparent }, None) => {
            render_png(scene, accel, opts, path, &png, transparent, progress)
        }
    }
}

/// Why a sequence stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SequenceError {
    /// The scene could not be posed at a frame.
    #[error("frame {frame}: {source}")]
    Pose {
        /// The frame.
        frame: i64,
        /// What the loader said.
        source: aperture_scene::Error,
    },
    /// A frame could not be rendered or written.
    #[error("frame {frame}: {source}")]
    Render {
        /// The frame.
        frame: i64,
        /// What went wrong.
        source: OutputError,
    },
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
