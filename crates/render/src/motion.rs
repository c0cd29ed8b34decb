//! Motion blur (SPEC §7): the shutter, the settings that turn it on, and what moves within
//! one frame's shutter, keyed at motion steps and interpolated at each sample's time.
//!
//! A sample's time is a named sample dimension ([`crate::SampleStream::time`]), mapped by the
//! [`Shutter`] (rolling or not) to a normalised time `τ ∈ [0, 1]` over the frame's interval;
//! the camera is the [`CameraPath`] at `τ`, rigid instances are keyed transforms and deforming
//! meshes are vertex positions at the motion steps (both interpolated by the accel at `τ`).
//! With motion blur off nothing here is built and every sample is at the frame's instant, as
//! before.

mod camera_path;
mod deforming;
mod frame_motion;
mod instances;
mod pose;
mod settings;
mod shutter;
mod vector;

pub use camera_path::CameraPath;
pub use deforming::deform_surface;
pub use frame_motion::FrameMotion;
pub use instances::MovingInstance;
pub use pose::pose_frame_motion;
pub use settings::{MotionOverrides, MotionSettings, DEFAULT_MOTION_STEPS, MAX_MOTION_STEPS};
pub use shutter::{RollingShutter, Shutter, ShutterPosition, DEFAULT_SHUTTER_FRAMES};
pub use vector::{pose_neighbours, raster_of, DeformedNeighbours, FrameNeighbours};
