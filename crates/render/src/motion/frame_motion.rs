//! What moves within one frame's shutter: the camera's path, rigid instances' keys and
//! deforming meshes' vertices at the motion steps.

use super::camera_path::CameraPath;
use super::instances::MovingInstance;
use super::shutter::{Shutter, ShutterPosition};

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
    /// Per mesh of the frame's scene: its vertices at the motion steps when it deforms within
    /// the interval (`None`: it keeps the frame's shape), in the mesh's object space at each
    /// step (an instance drawing it is placed by its own keys in `instances`, or by the
    /// frame's placement). Empty when no mesh deforms.
    pub meshes: Vec<Option<aperture_accel::VertexMotion>>,
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
        self.camera.is_some() || !self.instances.is_empty() || !self.meshes.is_empty()
    }

    /// True when geometry moves or deforms within the interval: the frame's ray-query
    /// structure must be built with this motion ([`crate::build_motion_accel`]).
    pub fn moves_geometry(&self) -> bool {
        !self.instances.is_empty() || !self.meshes.is_empty()
    }

    /// The keys of each moving instance, for the accel ([`aperture_accel::FrameHints::motion`]).
    pub fn instance_keys(&self) -> Vec<Option<aperture_accel::MotionTransform>> {
        let keys = |m: &Option<MovingInstance>| m.as_ref().map(|m| m.keys.clone());
        self.instances.iter().map(keys).collect()
    }
}
