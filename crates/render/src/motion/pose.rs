//! A frame's motion, posed: the scene at each motion step over the shutter interval, and what
//! of it moves (the camera, rigid instances).

use super::{CameraPath, FrameMotion, MotionSettings, MovingInstance};
use crate::camera::Camera;
use aperture_accel::MotionTransform;
use aperture_scene::{Animated, Error, Scene};
use glam::{Affine3A, Vec3A};

/// What moves within the shutter of the frame at `frame_time` seconds (`fps` frames a second)
/// of `frame` (the scene posed at that instant), for camera `camera` and a `width × height`
/// image; `None` when motion blur is off. Every step is moved into the frame's coordinates
/// (its [`Scene::world_origin`]).
pub fn pose_frame_motion(
    animated: &Animated,
    settings: &MotionSettings,
    (frame_time, fps): (f64, f64),
    frame: &Scene,
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
        instances: Vec::new(),
    };
    if !animated.is_animated() {
        return Ok(Some(motion));
    }
    let steps = settings.steps.max(2) as usize;
    let mut cameras = Vec::with_capacity(steps);
    let mut placements: Vec<Vec<Affine3A>> = vec![Vec::with_capacity(steps); frame.instances.len()];
    let mut same_instances = true;
    for k in 0..steps {
        let tau = k as f32 / (steps - 1) as f32;
        let scene = animated.shape_at(Some(motion.seconds(tau) as f32))?;
        let offset = Vec3A::from((scene.world_origin - frame.world_origin).as_vec3());
        // The automatic camera frames each pose's bounds: it stays the frame's.
        if let Some(cam) = scene.cameras.get(camera).filter(|c| c.node.is_some()) {
            let mut c = Camera::new(cam, width, height);
            c.world_from_camera.translation += offset;
            cameras.push(c);
        }
        // The same instances in the same order (a pose that drops one, e.g. a mesh skinned
        // to nothing, leaves instance motion out).
        same_instances &= scene.instances.len() == frame.instances.len()
            && scene
                .instances
                .iter()
                .zip(&frame.instances)
                .all(|(a, b)| a.node == b.node && a.mesh == b.mesh);
        if same_instances {
            for (keys, inst) in placements.iter_mut().zip(&scene.instances) {
                let mut m = inst.world_from_object;
                m.translation += offset;
                keys.push(m);
            }
        }
    }
    if cameras.len() == steps {
        motion.camera = CameraPath::new(cameras);
    }
    if same_instances {
        motion.instances = moving_instances(frame, &placements);
    }
    Ok(Some(motion))
}

/// Per instance of `frame`, its motion when its `keys` are not all equal; empty when none moves.
fn moving_instances(frame: &Scene, keys: &[Vec<Affine3A>]) -> Vec<Option<MovingInstance>> {
    let moving: Vec<Option<MovingInstance>> = frame
        .instances
        .iter()
        .zip(keys)
        .map(|(inst, keys)| {
            let first = keys.first()?;
            if keys.iter().all(|k| k == first) {
                return None;
            }
            Some(MovingInstance {
                keys: MotionTransform::new(keys)?,
                object_from_frame: inst.world_from_object.inverse(),
            })
        })
        .collect();
    if moving.iter().all(Option::is_none) {
        Vec::new()
    } else {
        moving
    }
}
