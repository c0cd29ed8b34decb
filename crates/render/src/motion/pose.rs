//! A frame's motion, posed: the scene at each motion step over the shutter interval, and what
//! of it moves (the camera, rigid instances, deforming meshes).

use super::camera_path::CameraPath;
use super::frame_motion::FrameMotion;
use super::instances::MovingInstance;
use super::settings::MotionSettings;
use crate::camera::Camera;
use aperture_accel::{MotionTransform, VertexMotion};
use aperture_scene::{Animated, Error, Scene};
use glam::{Affine3A, Vec3, Vec3A};

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
        meshes: Vec::new(),
    };
    if !animated.is_animated() {
        return Ok(Some(motion));
    }
    let steps = settings.steps.max(2) as usize;
    let mut cameras = Vec::with_capacity(steps);
    let mut placements: Vec<Vec<Affine3A>> = vec![Vec::with_capacity(steps); frame.instances.len()];
    let mut same_instances = true;
    let mut shapes = StepShapes::new(animated.static_mesh_count(), frame);
    for k in 0..steps {
        let tau = k as f32 / (steps - 1) as f32;
        let mut scene = animated.shape_at(Some(motion.seconds(tau) as f32))?;
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
            shapes.take(&mut scene);
        }
    }
    if cameras.len() == steps {
        motion.camera = CameraPath::new(cameras);
    }
    if same_instances {
        motion.meshes = shapes.finish();
        motion.instances = moving_instances(frame, &placements, &motion.meshes);
    }
    Ok(Some(motion))
}

/// The deforming meshes' positions at each step (the meshes from `first` on, as many as the
/// frame has): what [`FrameMotion::meshes`] is made of.
struct StepShapes {
    first: usize,
    /// Per deforming mesh of the frame: its positions at each step taken so far.
    positions: Vec<Vec<Vec<Vec3>>>,
    /// False once a step's meshes are not the frame's (then no mesh deforms in the motion).
    same: bool,
}

impl StepShapes {
    fn new(first: usize, frame: &Scene) -> Self {
        let n = frame.meshes.len().saturating_sub(first);
        Self {
            first,
            positions: vec![Vec::new(); n],
            same: true,
        }
    }

    /// Takes the deforming meshes' positions out of one step's `scene` (posed like the frame:
    /// the same instances of the same meshes).
    fn take(&mut self, scene: &mut Scene) {
        let deformed = scene.meshes.get_mut(self.first..).unwrap_or_default();
        self.same &= deformed.len() == self.positions.len();
        if !self.same {
            return;
        }
        for (keys, mesh) in self.positions.iter_mut().zip(deformed) {
            // Deformed meshes are this step's own (not shared): no copy is made.
            keys.push(std::mem::take(
                &mut std::sync::Arc::make_mut(mesh).positions,
            ));
        }
    }

    /// Per mesh of the frame, its keys when its vertices move within the interval; empty when
    /// none does.
    fn finish(self) -> Vec<Option<VertexMotion>> {
        if !self.same {
            return Vec::new();
        }
        let mut meshes: Vec<Option<VertexMotion>> = vec![None; self.first];
        for keys in &self.positions {
            let refs: Vec<&[Vec3]> = keys.iter().map(Vec::as_slice).collect();
            meshes.push(VertexMotion::new(&refs).filter(|m| !m.is_still()));
        }
        if meshes.iter().all(Option::is_none) {
            Vec::new()
        } else {
            meshes
        }
    }
}

/// Per instance of `frame`, its motion when its `keys` are not all equal; empty when none moves.
/// An instance of a deforming mesh (`meshes`) moves unless every key is the frame's placement:
/// its mesh's keys are in the object space of each step, which that placement must map.
fn moving_instances(
    frame: &Scene,
    keys: &[Vec<Affine3A>],
    meshes: &[Option<VertexMotion>],
) -> Vec<Option<MovingInstance>> {
    let moving: Vec<Option<MovingInstance>> = frame
        .instances
        .iter()
        .zip(keys)
        .map(|(inst, keys)| {
            let first = keys.first()?;
            let deforms = matches!(meshes.get(inst.mesh as usize), Some(Some(_)));
            let still = if deforms {
                keys.iter().all(|k| *k == inst.world_from_object)
            } else {
                keys.iter().all(|k| k == first)
            };
            if still {
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
