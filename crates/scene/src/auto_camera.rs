//! The automatic camera of a scene without one (SPEC §3): framed once, on the bounds of the
//! scene as stored, and placed at that same world position at every pose of a shot.

use glam::{Affine3A, DVec3, Mat3, Vec3};

use crate::dof::{self, CameraInput, NodeInfo};
use crate::error::Error;
use crate::types::{Bounds, Camera, LoadOptions, Projection};

/// Vertical field of view of the automatic camera.
const AUTO_YFOV_DEGREES: f32 = 40.0;

/// Where the automatic camera stands and what it focuses on, fixed for a loaded file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Framing {
    /// Camera to world, relative to `origin`.
    world_from_camera: Affine3A,
    /// The world origin of the pose it was framed on (`Scene::world_origin`).
    origin: DVec3,
    /// Vertical field of view, radians.
    yfov: f32,
    /// Distance from the eye to the centre of the bounds: the default focus distance.
    distance: f32,
}

impl Framing {
    /// Frames the bounding sphere of `bounds` (relative to `origin`) from the +Z side, slightly
    /// above.
    pub(crate) fn of(bounds: Bounds, origin: DVec3) -> Self {
        let (center, radius) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), (0.5 * bounds.diagonal()).max(1e-3))
        };
        let yfov = AUTO_YFOV_DEGREES.to_radians();
        // The sphere touches the top and bottom of the frame; wider frames have room to spare.
        let distance = radius / (0.5 * yfov).sin();
        let back = Vec3::new(0.0, 0.3, 1.0).normalize();
        let eye = center + back * distance;
        // Camera +Z points back at the eye from the centre; +X right, +Y up.
        let z = back;
        let x = Vec3::Y.cross(z).normalize();
        let y = z.cross(x);
        Self {
            world_from_camera: Affine3A::from_mat3_translation(Mat3::from_cols(x, y, z), eye),
            origin,
            yfov,
            distance,
        }
    }

    /// The camera in a pose expressed relative to `origin`: the same world position as where it
    /// was framed (bit for bit when the origins agree); pinhole unless the command line asks
    /// for depth of field, resolved against this pose's nodes (a focus object moves).
    pub(crate) fn camera(
        &self,
        origin: DVec3,
        info: &NodeInfo<'_>,
        options: &LoadOptions,
    ) -> Result<Camera, Error> {
        let mut world_from_camera = self.world_from_camera;
        if origin != self.origin {
            // Moved in f64, rounded once: the pose is recentred elsewhere (its geometry moved).
            let eye = Vec3::from(world_from_camera.translation).as_dvec3() + self.origin - origin;
            world_from_camera.translation = eye.as_vec3().into();
        }
        let projection = Projection::Perspective {
            yfov: self.yfov,
            aspect_ratio: None,
        };
        let name = "automatic camera".to_owned();
        let mut dof = dof::resolve(
            &CameraInput {
                name: &name,
                projection,
                world_from_camera,
                physical: None,
                camera_extras: None,
                node_extras: None,
            },
            &options.dof_overrides,
            info,
        )?;
        if options.dof_overrides.focus_distance.is_none()
            && options.dof_overrides.focus_object.is_none()
        {
            // Focus on the scene's centre rather than Blender's 10 m.
            dof.focus_distance = self.distance;
        }
        Ok(Camera {
            name,
            node: None,
            index: None,
            world_from_camera,
            projection,
            dof,
        })
    }
}
