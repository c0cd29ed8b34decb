//! The camera moving within the shutter: its node and its keyed lens (`yfov`, focus distance,
//! aperture) at the motion steps, interpolated at each sample's time.

use crate::camera::{Aperture, Camera, CameraModel, CameraRay, CameraSample};
use aperture_accel::MotionTransform;

/// A camera keyed at evenly spaced times over the shutter (normalised to `[0, 1]`).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraPath {
    keys: Vec<Camera>,
    world_from_camera: MotionTransform,
}

impl CameraPath {
    /// The path through `keys` (same image size); `None` when there is none, a transform is not
    /// finite, or every key is the same camera (a still camera needs no path).
    pub fn new(keys: Vec<Camera>) -> Option<Self> {
        let first = *keys.first()?;
        if keys.iter().all(|k| *k == first) {
            return None;
        }
        let transforms: Vec<_> = keys.iter().map(|k| k.world_from_camera).collect();
        let world_from_camera = MotionTransform::new(&transforms)?;
        Some(Self {
            keys,
            world_from_camera,
        })
    }

    /// The camera at normalised time `tau`.
    pub fn camera_at(&self, tau: f32) -> Camera {
        let n = self.keys.len();
        let x = tau.clamp(0.0, 1.0) * (n.max(2) - 1) as f32;
        let i = (x as usize).min(n.saturating_sub(2));
        let f = x - i as f32;
        let a = self.keys[i];
        let b = self.keys[(i + 1).min(n - 1)];
        let lerp = |p: f32, q: f32| p + (q - p) * f;
        Camera {
            world_from_camera: self.world_from_camera.at(tau),
            model: lerp_model(a.model, b.model, f),
            aperture: lerp_aperture(a.aperture, b.aperture, f),
            focus_distance: lerp(a.focus_distance, b.focus_distance),
            width: a.width,
            height: a.height,
            lens: crate::lens::Lens {
                barrel_shift: lerp(a.lens.barrel_shift, b.lens.barrel_shift),
                ..a.lens
            },
            realistic: a.realistic,
        }
    }

    /// The ray of `s` through the camera at `s.time`.
    pub fn generate_ray(&self, s: &CameraSample) -> Option<CameraRay> {
        self.camera_at(s.time).generate_ray(s)
    }

    /// [`CameraPath::generate_ray`] of one channel (chromatic aberration).
    pub fn generate_ray_channel(&self, s: &CameraSample, channel: usize) -> Option<CameraRay> {
        self.camera_at(s.time).generate_ray_channel(s, channel)
    }
}

/// The projection between two keys; a change of kind (never keyed by glTF) steps at the middle.
fn lerp_model(a: CameraModel, b: CameraModel, f: f32) -> CameraModel {
    let lerp = |p: f32, q: f32| p + (q - p) * f;
    match (a, b) {
        (
            CameraModel::ThinLens {
                tan_half_x: ax,
                tan_half_y: ay,
            },
            CameraModel::ThinLens {
                tan_half_x: bx,
                tan_half_y: by,
            },
        ) => CameraModel::ThinLens {
            tan_half_x: lerp(ax, bx),
            tan_half_y: lerp(ay, by),
        },
        (
            CameraModel::Orthographic {
                half_x: ax,
                half_y: ay,
            },
            CameraModel::Orthographic {
                half_x: bx,
                half_y: by,
            },
        ) => CameraModel::Orthographic {
            half_x: lerp(ax, bx),
            half_y: lerp(ay, by),
        },
        _ if f < 0.5 => a,
        _ => b,
    }
}

/// The aperture between two keys: the radius interpolated, the shape of the nearer key.
fn lerp_aperture(a: Aperture, b: Aperture, f: f32) -> Aperture {
    let radius = a.radius() + (b.radius() - a.radius()) * f;
    let shape = if f < 0.5 { a } else { b };
    match shape {
        _ if radius <= 0.0 => Aperture::Pinhole,
        Aperture::Pinhole => match if f < 0.5 { b } else { a } {
            Aperture::Pinhole => Aperture::Pinhole,
            other => with_radius(other, radius),
        },
        other => with_radius(other, radius),
    }
}

/// `a` with its radius set to `radius`.
fn with_radius(a: Aperture, radius: f32) -> Aperture {
    match a {
        Aperture::Pinhole => Aperture::Pinhole,
        Aperture::Disc { ratio, .. } => Aperture::Disc { radius, ratio },
        Aperture::Polygon {
            blades,
            rotation,
            ratio,
            ..
        } => Aperture::Polygon {
            radius,
            blades,
            rotation,
            ratio,
        },
    }
}
