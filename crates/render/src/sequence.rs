//! Frame sequences (SPEC §7, `--frames A..B[:STEP]`): the file is loaded and decoded once, and
//! each frame re-poses it and rebuilds only what moved: the top-level BVH always, the
//! bottom-level BVHs of deforming meshes; the BVHs of static meshes and the world-space BVH of
//! still instances are kept from the frame before. Each frame's image is the single-frame
//! render of that frame, bit for bit: both build with the same [`FrameHints`].

use crate::output::{self, ExrOptions, OutputError, RenderSummary};
use crate::render::RenderOptions;
use aperture_accel::{Accel, AccelStats, BvhQuality, FrameHints, InstanceInput, MeshInput};
use aperture_imageio::PngOptions;
use aperture_scene::{Animated, Scene};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Frames `start`, `start + step`, … up to `end` inclusive (Blender's frame range and step).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: i64,
    /// Last frame (included when the step lands on it).
    pub end: i64,
    /// Frames between renders, ≥ 1.
    pub step: i64,
}

impl FrameRange {
    /// The frames, in order.
    pub fn frames(self) -> impl Iterator<Item = i64> {
        (self.start..=self.end).step_by(self.step.max(1) as usize)
    }

    /// Parses `A..B` or `A..B:STEP` (frames may be negative; `B ≥ A`, `STEP ≥ 1`).
    pub fn parse(s: &str) -> Result<Self, String> {
        let bad =
            || format!("expected A..B or A..B:STEP (whole frames, A ≤ B, STEP ≥ 1), got {s:?}");
        let (range, step) = match s.split_once(':') {
            Some((r, st)) => (r, st.trim().parse::<i64>().map_err(|_| bad())?),
            None => (s, 1),
        };
        let (a, b) = range.split_once("..").ok_or_else(bad)?;
        let (start, end) = (
            a.trim().parse::<i64>().map_err(|_| bad())?,
            b.trim().parse::<i64>().map_err(|_| bad())?,
        );
        if end < start || step < 1 || end - start > 10_000_000 {
            return Err(bad());
        }
        Ok(Self { start, end, step })
    }
}

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

/// What of a posed scene may change between frames, for [`Accel::build_frame`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneHints {
    /// Per instance of the scene: its node moves with time.
    pub moving: Vec<bool>,
    /// Meshes from this index on deform with time.
    pub deforming_from: usize,
}

impl SceneHints {
    /// A still scene: nothing moves or deforms ([`FrameHints::STILL`]).
    pub fn still() -> Self {
        Self {
            moving: Vec::new(),
            deforming_from: FrameHints::STILL.deforming_from,
        }
    }

    /// The hints of `scene`, posed from `animated`.
    pub fn new(animated: &Animated, scene: &Scene) -> Self {
        let moving_nodes = animated.moving_nodes();
        Self {
            moving: scene
                .instances
                .iter()
                .map(|i| moving_nodes.binary_search(&i.node).is_ok())
                .collect(),
            deforming_from: animated.static_mesh_count(),
        }
    }
}

/// The ray-query structure of one frame of `scene` (see [`Accel::build_frame`]); `previous`
/// is the frame before's, whose unchanged parts are taken over. A render of a single frame of
/// an animated file builds with the same hints and no `previous`, so its image is the
/// sequence's frame bit for bit.
pub fn build_frame_accel(
    scene: &Scene,
    quality: BvhQuality,
    hints: &SceneHints,
    previous: Option<Accel>,
) -> Accel {
    let meshes: Vec<MeshInput<'_>> = scene
        .meshes
        .iter()
        .map(|m| MeshInput {
            positions: &m.positions,
            indices: &m.indices,
        })
        .collect();
    let instances: Vec<InstanceInput> = scene
        .instances
        .iter()
        .map(|i| InstanceInput {
            mesh: i.mesh,
            world_from_object: i.world_from_object,
        })
        .collect();
    let frame = FrameHints {
        moving: &hints.moving,
        deforming_from: hints.deforming_from,
        ..FrameHints::STILL
    };
    Accel::build_frame(&meshes, &instances, quality, frame, previous)
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
}

/// Renders every frame of `seq` in turn: `tile_progress(done, total)` during each frame,
/// `frame_done(report)` after each. Stops at the first error (a frame that cannot be posed,
/// rendered or written).
pub fn render_sequence(
    seq: &Sequence<'_>,
    tile_progress: &(dyn Fn(usize, usize) + Sync),
    frame_done: &mut dyn FnMut(&FrameReport),
) -> Result<(), SequenceError> {
    let total = seq.frames.frames().count();
    let mut previous: Option<Accel> = None;
    let mut hints: Option<SceneHints> = None;
    for (index, frame) in seq.frames.frames().enumerate() {
        let path = frame_path(seq.pattern, frame);
        let mut report = FrameReport {
            frame,
            path: path.clone(),
            index: (index, total),
            rendered: None,
        };
        if seq.skip_existing && path.is_file() {
            frame_done(&report);
            continue;
        }
        let t0 = Instant::now();
        let time = (frame as f64 / f64::from(seq.fps)) as f32;
        let scene = seq
            .animated
            .scene_at(Some(time))
            .map_err(|source| SequenceError::Pose { frame, source })?;
        let pose_secs = t0.elapsed().as_secs_f64();
        let h = hints.get_or_insert_with(|| SceneHints::new(seq.animated, &scene));
        // A posed scene with another instance count (cannot happen for one file) rebuilds all.
        let reuse = if h.moving.len() == scene.instances.len() {
            previous.take()
        } else {
            *h = SceneHints::new(seq.animated, &scene);
            None
        };
        let accel = build_frame_accel(&scene, seq.quality, h, reuse);
        let written = match seq.format {
            FrameFormat::Exr(exr) => {
                output::render_exr(&scene, &accel, seq.opts, &path, &exr, tile_progress)
            }
            FrameFormat::Png { png, transparent } => output::render_png(
                &scene,
                &accel,
                seq.opts,
                &path,
                &png,
                transparent,
                tile_progress,
            ),
        };
        let summary = written.map_err(|source| SequenceError::Render { frame, source })?;
        report.rendered = Some(FrameWork {
            summary,
            accel: accel.stats(),
            pose_secs,
            total_secs: t0.elapsed().as_secs_f64(),
        });
        frame_done(&report);
        previous = Some(accel);
    }
    Ok(())
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
    fn ranges_parse_as_blender_writes_them() {
        let r = FrameRange::parse("1..24").unwrap();
        assert_eq!(r.frames().count(), 24);
        let r = FrameRange::parse("-3..10:4").unwrap();
        assert_eq!(r.frames().collect::<Vec<_>>(), [-3, 1, 5, 9]);
        for bad in ["1..", "5..1", "1..10:0", "a..b", "1-10", "1..10:x"] {
            assert!(FrameRange::parse(bad).is_err(), "{bad}");
        }
    }

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
