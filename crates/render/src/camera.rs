//! The thin-lens camera of SPEC §2: numbers in (a film position and a lens position), a ray out.
//!
//! For each primary sample the pixel sample's centre ray meets the focal plane at a point found
//! by similar triangles; the primary ray runs from a point on the aperture to that point. A
//! pinhole (`R = 0`) ignores the lens numbers entirely.

use crate::lens::Lens;
use crate::realistic::RealisticLens;
use aperture_scene::Projection;
pub use aperture_shading::warp::{concentric_disc, polygon_corner, uniform_polygon};
use aperture_shading::warp_lens::{clipped_by_disc, disc_in_disc};
use glam::{Affine3A, Vec2, Vec3};

/// The numbers one primary sample gives the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSample {
    /// Film position in raster coordinates: x right in `[0, width]`, y down in `[0, height]`
    /// (row 0 at the top).
    pub p_film: Vec2,
    /// Lens sample in `[0, 1)²`; ignored by a pinhole.
    pub p_lens: Vec2,
    /// Normalised time in the shutter, `[0, 1]` (SPEC §7); ignored by a still camera.
    pub time: f32,
}

/// A primary ray in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraRay {
    /// Origin (a point on the aperture).
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

/// The shape of the aperture, radius included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Aperture {
    /// No lens: every ray starts at the camera's centre.
    Pinhole,
    /// A round aperture of radius `radius`, x divided by `ratio` (anamorphic squeeze).
    Disc {
        /// Lens radius `R`.
        radius: f32,
        /// `aperture_ratio`.
        ratio: f32,
    },
    /// A regular polygon inscribed in the radius-`radius` circle.
    Polygon {
        /// Lens radius `R` (of the circumscribed circle).
        radius: f32,
        /// Number of blades, ≥ 3.
        blades: u32,
        /// `aperture_rotation`, radians.
        rotation: f32,
        /// `aperture_ratio`.
        ratio: f32,
    },
}

impl Aperture {
    /// The aperture a resolved [`aperture_scene::Dof`] describes.
    pub fn from_dof(dof: &aperture_scene::Dof) -> Self {
        let radius = dof.effective_radius();
        let ratio = if dof.ratio > 0.0 { dof.ratio } else { 1.0 };
        if radius <= 0.0 {
            Self::Pinhole
        } else if dof.blades >= 3 {
            Self::Polygon {
                radius,
                blades: dof.blades,
                rotation: dof.rotation,
                ratio,
            }
        } else {
            Self::Disc { radius, ratio }
        }
    }

    /// Maps `u ∈ [0,1)²` uniformly onto the aperture, in lens-plane units (x right, y up).
    #[inline(always)]
    pub fn sample(&self, u: Vec2) -> Vec2 {
        match *self {
            Self::Pinhole => Vec2::ZERO,
            Self::Disc { radius, ratio } => {
                let d = concentric_disc(u) * radius;
                Vec2::new(d.x / ratio, d.y)
            }
            // Out of line: its two `sin_cos` calls would keep the disc from being inlined.
            Self::Polygon { .. } => self.sample_polygon(u),
        }
    }

    /// [`Aperture::sample`] of a polygon (a pinhole or disc gives the centre).
    fn sample_polygon(&self, u: Vec2) -> Vec2 {
        match *self {
            Self::Polygon {
                radius,
                blades,
                rotation,
                ratio,
            } => {
                let d = uniform_polygon(u, blades, rotation) * radius;
                Vec2::new(d.x / ratio, d.y)
            }
            Self::Pinhole | Self::Disc { .. } => Vec2::ZERO,
        }
    }

    /// [`Aperture::sample`] clipped by the lens barrel (optical vignetting): `barrel` is the
    /// centre, in aperture radii, of a disc of the aperture's radius (before the squeeze), and
    /// the point is uniform over the part of the aperture inside it. `None`: [`Aperture::sample`].
    #[inline(always)]
    pub fn sample_clipped(&self, u: Vec2, barrel: Option<Vec2>) -> Vec2 {
        let Some(c) = barrel else {
            return self.sample(u);
        };
        let (d, radius, ratio) = match *self {
            Self::Pinhole => return Vec2::ZERO,
            // The barrel is at most one radius off centre (vignetting ≤ 1): the discs meet.
            Self::Disc { radius, ratio } => {
                (disc_in_disc(u, c, 1.0).unwrap_or(0.5 * c), radius, ratio)
            }
            Self::Polygon {
                radius,
                blades,
                rotation,
                ratio,
            } => {
                let shape = |v| uniform_polygon(v, blades, rotation);
                (clipped_by_disc(u, shape, c, 1.0), radius, ratio)
            }
        };
        let d = d * radius;
        Vec2::new(d.x / ratio, d.y)
    }

    /// `aperture_ratio` (1 for a pinhole).
    pub fn ratio(&self) -> f32 {
        match *self {
            Self::Pinhole => 1.0,
            Self::Disc { ratio, .. } | Self::Polygon { ratio, .. } => ratio,
        }
    }

    /// The lens radius, 0 for a pinhole.
    pub fn radius(&self) -> f32 {
        match *self {
            Self::Pinhole => 0.0,
            Self::Disc { radius, .. } | Self::Polygon { radius, .. } => radius,
        }
    }
}

/// A camera ready to generate rays for an image of a given size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Camera to world: rotation and translation.
    pub world_from_camera: Affine3A,
    /// Projection model with its image-plane extent.
    pub model: CameraModel,
    /// The aperture.
    pub aperture: Aperture,
    /// Focus distance `f` along the view axis.
    pub focus_distance: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Vignetting and distortion ([`Lens::IDEAL`]: none).
    pub lens: Lens,
    /// A lens prescription traced surface by surface instead of the thin lens (`None`: the
    /// thin lens), or why it cannot image. `model` and `aperture` then describe the thin lens
    /// of the same field of view and entrance pupil (for the passes' projections and bounds).
    /// Shared by every camera of the same prescription, focus and film (interned: see
    /// [`crate::realistic::intern::interned`]).
    pub realistic: Option<&'static Result<RealisticLens, String>>,
}

/// Perspective or orthographic, with the half-extents of the image plane at distance `d = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraModel {
    /// Perspective: the image plane at `z = −1` spans `±tan_half_x`, `±tan_half_y`.
    ThinLens {
        /// `tan(xfov/2)` (from `yfov` and the image aspect).
        tan_half_x: f32,
        /// `tan(yfov/2)`.
        tan_half_y: f32,
    },
    /// Orthographic: the view volume spans `±half_x`, `±half_y` scene units.
    Orthographic {
        /// Half-width.
        half_x: f32,
        /// Half-height (glTF `ymag`).
        half_y: f32,
    },
}

impl CameraModel {
    /// `(tan_half_x, tan_half_y)` of a perspective camera; `None` for an orthographic one.
    pub fn tan_half(&self) -> Option<(f32, f32)> {
        match *self {
            CameraModel::ThinLens {
                tan_half_x,
                tan_half_y,
            } => Some((tan_half_x, tan_half_y)),
            CameraModel::Orthographic { .. } => None,
        }
    }
}

impl Camera {
    /// The camera of a scene camera for a `width × height` image. The vertical extent comes from
    /// the file (`yfov` or `ymag`); the horizontal one from the image's aspect `width / height`.
    pub fn new(cam: &aperture_scene::Camera, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height as f32;
        let model = match cam.projection {
            Projection::Perspective { yfov, .. } => {
                let tan_half_y = (0.5 * yfov).tan();
                CameraModel::ThinLens {
                    tan_half_x: tan_half_y * aspect,
                    tan_half_y,
                }
            }
            Projection::Orthographic { ymag, .. } => CameraModel::Orthographic {
                half_x: ymag.abs() * aspect,
                half_y: ymag.abs(),
            },
        };
        let aperture = Aperture::from_dof(&cam.dof);
        let (corner, perspective) = match model {
            CameraModel::ThinLens {
                tan_half_x,
                tan_half_y,
            } => (tan_half_x.hypot(tan_half_y), true),
            CameraModel::Orthographic { half_x, half_y } => (half_x.hypot(half_y), false),
        };
        Self {
            world_from_camera: cam.world_from_camera,
            model,
            aperture,
            lens: Lens {
                bokeh: crate::lens::Bokeh::of(&cam.dof),
                ..Lens::new(
                    &cam.dof.lens_options,
                    corner,
                    aperture.radius(),
                    perspective,
                )
            },
            focus_distance: cam.dof.focus_distance,
            width,
            height,
            realistic: None,
        }
        .with_prescription(cam, width, height)
    }

    /// The point of the image plane (at `d = 1` for perspective, in scene units for
    /// orthographic) a raster position maps to; +Y up, row 0 at the top.
    #[inline(always)]
    pub fn screen_point(&self, p_film: Vec2) -> Vec2 {
        let ndc = Vec2::new(
            2.0 * p_film.x / self.width as f32 - 1.0,
            1.0 - 2.0 * p_film.y / self.height as f32,
        );
        match self.model {
            CameraModel::ThinLens {
                tan_half_x,
                tan_half_y,
            } => ndc * Vec2::new(tan_half_x, tan_half_y),
            CameraModel::Orthographic { half_x, half_y } => ndc * Vec2::new(half_x, half_y),
        }
    }

    /// The primary ray for one sample, in camera space (the camera looks down −Z).
    #[inline(always)]
    pub fn generate_ray_camera_space(&self, s: &CameraSample) -> Option<CameraRay> {
        self.generate_ray_camera_space_channel(s, 1)
    }

    /// [`Camera::generate_ray_camera_space`] for channel `channel` (0 R, 1 G, 2 B) of a lens
    /// with chromatic aberration; green's is the plain ray.
    #[inline(always)]
    pub fn generate_ray_camera_space_channel(
        &self,
        s: &CameraSample,
        channel: usize,
    ) -> Option<CameraRay> {
        let ps = self.lens.undistort(self.screen_point(s.p_film))?;
        let (ps, f) = self.lens.for_channel(ps, self.focus_distance, channel);
        let barrel = self.lens.barrel(ps);
        let (origin, dir) = match (self.model, self.aperture) {
            (CameraModel::ThinLens { .. }, Aperture::Pinhole) => {
                (Vec3::ZERO, Vec3::new(ps.x, ps.y, -1.0))
            }
            (CameraModel::ThinLens { .. }, aperture) => {
                // Similar triangles: the centre ray through (ps, −1) meets z = −f here.
                let focus = Vec3::new(ps.x * f, ps.y * f, -f);
                let lens = self.lens_point(aperture, s.p_lens, barrel).extend(0.0);
                (lens, focus - lens)
            }
            (CameraModel::Orthographic { .. }, Aperture::Pinhole) => (ps.extend(0.0), Vec3::NEG_Z),
            (CameraModel::Orthographic { .. }, aperture) => {
                let focus = Vec3::new(ps.x, ps.y, -f);
                let lens = self.lens_point(aperture, s.p_lens, barrel).extend(0.0);
                let origin = focus.with_z(0.0) + lens;
                (origin, focus - origin)
            }
        };
        let dir = dir.normalize();
        dir.is_finite().then_some(CameraRay { origin, dir })
    }

    /// The lens point of `aperture` for `u`: the bokeh image's when there is one, else the
    /// plain (barrel-clipped) aperture's.
    #[inline(always)]
    fn lens_point(&self, aperture: Aperture, u: Vec2, barrel: Option<Vec2>) -> Vec2 {
        match self.lens.bokeh {
            None => aperture.sample_clipped(u, barrel),
            Some(b) => {
                let d = b.sample(u, barrel) * aperture.radius();
                Vec2::new(d.x / aperture.ratio(), d.y)
            }
        }
    }

    /// The primary ray for one sample, in world space.
    #[inline(always)]
    pub fn generate_ray(&self, s: &CameraSample) -> Option<CameraRay> {
        self.generate_ray_channel(s, 1)
    }

    /// [`Camera::generate_ray`] of channel `channel` (0 R, 1 G, 2 B) of a lens with chromatic
    /// aberration ([`crate::lens::channel_of`] picks it); green's is the plain ray. A lens
    /// prescription traces its own glass (no channel).
    #[inline(always)]
    pub fn generate_ray_channel(&self, s: &CameraSample, channel: usize) -> Option<CameraRay> {
        if self.realistic.is_some() {
            return self.generate_ray_weighted(s).map(|(r, _)| r);
        }
        let r = self.generate_ray_camera_space_channel(s, channel)?;
        let dir = self.world_from_camera.transform_vector3(r.dir).normalize();
        Some(CameraRay {
            origin: self.world_from_camera.transform_point3(r.origin),
            dir,
        })
    }

    /// The ray through raster position `p_film` and the lens centre, in world space: a pinhole
    /// camera's ray, the one the Depth and Position passes trace.
    pub fn centre_ray(&self, p_film: Vec2) -> Option<CameraRay> {
        let (origin, dir) = match self.realistic_lens() {
            Some(r) => r.centre_ray(p_film)?,
            None => self.thin_centre_ray(p_film)?,
        };
        let dir = self
            .world_from_camera
            .transform_vector3(dir.normalize())
            .normalize();
        dir.is_finite().then(|| CameraRay {
            origin: self.world_from_camera.transform_point3(origin),
            dir,
        })
    }

    /// [`Camera::centre_ray`] of the thin lens, in camera space.
    fn thin_centre_ray(&self, p_film: Vec2) -> Option<(Vec3, Vec3)> {
        let ps = self.lens.undistort(self.screen_point(p_film))?;
        Some(match self.model {
            CameraModel::ThinLens { .. } => (Vec3::ZERO, Vec3::new(ps.x, ps.y, -1.0)),
            CameraModel::Orthographic { .. } => (ps.extend(0.0), Vec3::NEG_Z),
        })
    }

    /// Circle-of-confusion diameter in pixels of a point at depth `z` (SPEC §2), perspective only.
    pub fn coc_pixels(&self, z: f32) -> f32 {
        match self.model {
            CameraModel::ThinLens { tan_half_y, .. } => {
                self.aperture.radius()
                    * (1.0 / self.focus_distance - 1.0 / z).abs()
                    * self.height as f32
                    / tan_half_y
            }
            CameraModel::Orthographic { .. } => 0.0,
        }
    }
}

/// The scene camera of the render crate's camera tests: perspective (`yfov` 0.8), placed off
/// the axes and turned, with depth of field `dof`.
#[cfg(test)]
pub(crate) fn test_scene_camera(dof: aperture_scene::Dof) -> aperture_scene::Camera {
    aperture_scene::Camera {
        name: "test".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.5, -1.0, 3.0))
            * Affine3A::from_rotation_y(0.3),
        projection: Projection::Perspective {
            yfov: 0.8,
            aspect_ratio: None,
        },
        dof,
    }
}

#[cfg(test)]
mod tests;
