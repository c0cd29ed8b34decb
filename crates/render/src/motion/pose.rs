//! A frame's motion, posed: the scene at each motion step over the shutter interval, and what
//! of it moves.

use super::{CameraPath, FrameMotion, MotionSettings};
use crate::camera::Camera;
use aperture_scene::{Animated, Error};

/// What moves within the shutter of the frame at `frame_time` seconds (`fps` frames a second),
/// for camera `camera` and a `width × height` image; `None` when motion blur is off.
/// `frame_origin` is the frame's [`aperture_scene::Scene::world_origin`]: every step is moved
/// into the frame's coordinates.
pub fn pose_frame_motion(
    animated: &Animated,
    settings: &MotionSettings,
    (frame_time, fps): (f64, f64),
    frame_origin: glam::DVec3,
    (camera, width, height): (usize, u32, u32),
) -> Result<Option<FrameMotion>, Error> {
    let Some(shutter) = settings.shutter else {
        return Ok(None);
    };
    let interval = shutter.interval(frame_time, fps);
    let mut motion = FrameMotion {
        shutter,
        interval,
        camera: None,
    };
    if !animated.is_animated() {
        return Ok(Some(motion));
    }
    let steps = settings.steps.max(2);
    let mut cameras = Vec::with_capacity(steps as usize);
    for k in 0..steps {
        let tau = k as f32 / (steps - 1) as f32;
        let scene = animated.shape_at(Some(motion.seconds(tau) as f32))?;
        let offset = (scene.world_origin - frame_origin).as_vec3();
        // The automatic camera frames each pose's bounds: it stays the frame's.
        if let Some(cam) = scene.cameras.get(camera).filter(|c| c.node.is_some()) {
            let mut c = Camera::new(cam, width, height);
            c.world_from_camera.translation += glam::Vec3A::from(offset);
            cameras.push(c);
        }
    }
    if cameras.len() == steps as usize {
        motion.camera = CameraPath::new(cameras);
    }
    Ok(Some(motion))
}
