//! Motion blur (SPEC §7): the shutter, the settings that turn it on, and what moves within
//! one frame's shutter, keyed at motion steps and interpolated at each sample's time.
//!
//! A sample's time is a named sample dimension ([`crate::SampleStream::time`]), mapped by the
//! [`Shutter`] (rolling or not) to a normalised time `τ ∈ [0, 1]` over the frame's interval;
//! the camera is the [`CameraPath`] at `τ`. With motion blur off nothing here is built and
//! every sample is at the frame's instant, as before.

mod camera_path;
mod instances;
mod pose;
mod settings;
mod shutter;
mod vector;

pub use camera_path::CameraPath;
pub use instances::MovingInstance;
pub use pose::pose_frame_motion;
pub use settings::{MotionOverrides, MotionSettings, DEFAULT_MOTION_STEPS, MAX_MOTION_STEPS};
pub use shutter::{RollingShutter, Shutter, ShutterPosition, DEFAULT_SHUTTER_FRAMES};
pub use vector::{pose_neighbours, raster_of, FrameNeighbours};

/// What moves within one frame's shutter.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMotion {
    /// The shutter.
    pub shutter: Shutter,
    /// When it opens and closes, seconds.
    pub interval: (f64, f64),
    /// The camera's path, when the camera (or a lens key) moves within the interval.
    pub camera: Option<CameraPath>,
    /// Per instance of the frame's scene: how it moves within the interval (`None`: still).
    /// Empty when no instance moves.
    pub instances: Vec<Option<MovingInstance>>,
}

impl FrameMotion {
    /// The time in seconds of normalised time `tau`.
    pub fn seconds(&self, tau: f32) -> f64 {
        let (open, close) = self.interval;
        open + f64::from(tau) * (close - open)
    }

    /// The frame's own instant as a normalised time: where the shutter's position puts it.
    pub fn frame_time(&self) -> f32 {
        match self.shutter.position {
            ShutterPosition::Start => 0.0,
            ShutterPosition::Center => 0.5,
            ShutterPosition::End => 1.0,
        }
    }

    /// True when something within the interval moves (else samples need no time).
    pub fn moves(&self) -> bool {
        self.camera.is_some() || !self.instances.is_empty()
    }

    /// The keys of each moving instance, for the accel ([`aperture_accel::FrameHints::motion`]).
    pub fn instance_keys(&self) -> Vec<Option<aperture_accel::MotionTransform>> {
        let keys = |m: &Option<MovingInstance>| m.as_ref().map(|m| m.keys.clone());
        self.instances.iter().map(keys).collect()
    }
}
