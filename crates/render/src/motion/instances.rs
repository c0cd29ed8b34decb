//! Rigid instances moving within the shutter: their keyed transforms, and a surface found on
//! one (shaded from the frame's placement) moved to where the instance is at the ray's time.

use aperture_accel::MotionTransform;
use aperture_shading::surface::Surface;
use glam::{Affine3A, Mat3};

/// One moving instance: its keys and its placement at the frame's instant.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingInstance {
    /// `world_from_object` keyed over the shutter.
    pub keys: MotionTransform,
    /// `object_from_world` at the frame's instant (what the scene's instance holds).
    pub object_from_frame: Affine3A,
}

impl MovingInstance {
    /// Moves `s`, shaded with the instance at the frame's placement, to the instance at
    /// normalised time `tau`: point, normals and tangent.
    #[inline]
    pub fn move_surface(&self, s: &mut Surface, tau: f32) {
        let delta = self.keys.at(tau) * self.object_from_frame;
        s.p = delta.transform_point3(s.p);
        let normal_from = Mat3::from(delta.matrix3).inverse().transpose();
        let renormal = |n: glam::Vec3| {
            let m = (normal_from * n).normalize();
            if m.is_finite() {
                m
            } else {
                n
            }
        };
        s.ng = renormal(s.ng);
        s.ns = renormal(s.ns);
        // Not unit, and zero when the surface has none: moved as it is.
        let t = delta.transform_vector3(s.tangent.truncate());
        s.tangent = t.extend(s.tangent.w);
    }
}
