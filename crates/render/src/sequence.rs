//! Frame sequences (SPEC §7, `--frames A..B[:STEP]`): the file is loaded and decoded once, and
//! each frame re-poses it and rebuilds only what moved: the top-level BVH always, the
//! bottom-level BVHs of deforming meshes; the BVHs of static meshes and the world-space BVH of
//! still instances are kept from the frame before. Each frame's image is the single-frame
//! render of that frame, bit for bit: both build with the same [`SceneHints`]. What becomes of
//! a posed frame (a file, usually) is the caller's.

use crate::frame_accel::{build_frame_accel, SceneHints};
use aperture_accel::{Accel, BvhQuality};
use aperture_scene::{Animated, Scene};
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

/// One frame of a sequence, posed and with its BVH, handed to [`for_each_frame`]'s caller.
pub struct PosedFrame<'a> {
    /// The frame number.
    pub frame: i64,
    /// Its position in the sequence (0-based) and the sequence's length.
    pub index: (usize, usize),
    /// The scene posed at the frame; `None` when `skip` left the frame.
    pub posed: Option<(&'a Scene, &'a Accel)>,
    /// Seconds posing the scene.
    pub pose_secs: f64,
    /// Seconds posing the scene and building its BVH.
    pub setup_secs: f64,
}

/// Poses `animated` at every frame of `frames` in turn (frame N at N / `fps` seconds, as
/// Blender's exporter writes it), builds each frame's BVH from the one before, and hands the
/// frame to `each`. Frames for which `skip(frame)` is true are handed over unposed. Stops at
/// the first error, a pose's or `each`'s.
pub fn for_each_frame<E>(
    animated: &Animated,
    frames: FrameRange,
    fps: f32,
    quality: BvhQuality,
    skip: &dyn Fn(i64) -> bool,
    each: &mut dyn FnMut(PosedFrame<'_>) -> Result<(), E>,
    pose_error: impl Fn(i64, aperture_scene::Error) -> E,
) -> Result<(), E> {
    let total = frames.frames().count();
    let mut previous: Option<Accel> = None;
    for (index, frame) in frames.frames().enumerate() {
        let mut posed = PosedFrame {
            frame,
            index: (index, total),
            posed: None,
            pose_secs: 0.0,
            setup_secs: 0.0,
        };
        if skip(frame) {
            each(posed)?;
            continue;
        }
        let t0 = Instant::now();
        let time = (frame as f64 / f64::from(fps)) as f32;
        let scene = animated
            .scene_at(Some(time))
            .map_err(|source| pose_error(frame, source))?;
        posed.pose_secs = t0.elapsed().as_secs_f64();
        // The hints of this frame's instances (keyed visibility changes which there are): the
        // single-frame render's, so the image is the same. Bottom-level BVHs are taken over
        // by mesh, the world-space one by its placements, whatever instances came or went.
        let hints = SceneHints::new(animated, &scene);
        let accel = build_frame_accel(&scene, quality, &hints, previous.take());
        posed.setup_secs = t0.elapsed().as_secs_f64();
        posed.posed = Some((&scene, &accel));
        each(posed)?;
        previous = Some(accel);
    }
    Ok(())
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
}
