//! The thin-lens camera of SPEC §2: numbers in (a film position and a lens position), a ray out.
//!
//! For each primary sample the pixel sample's centre ray meets the focal plane at a point found
//! by similar triangles; the primary ray runs from a point on the aperture to that point. A
//! pinhole (`R = 0`) ignores the lens numbers entirely.

use aperture_scene::Projection;
pub use aperture_shading::warp::{concentric_disc, polygon_corner, uniform_polygon};
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
        Self {
            world_from_camera: cam.world_from_camera,
            model,
            aperture: Aperture::from_dof(&cam.dof),
            focus_distance: cam.dof.focus_distance,
            width,
            height,
        }
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
        let ps = self.screen_point(s.p_film);
        let (origin, dir) = match (self.model, self.aperture) {
            (CameraModel::ThinLens { .. }, Aperture::Pinhole) => {
                (Vec3::ZERO, Vec3::new(ps.x, ps.y, -1.0))
            }
            (CameraModel::ThinLens { .. }, aperture) => {
                let f = self.focus_distance;
                // Similar triangles: the centre ray through (ps, −1) meets z = −f here.
                let focus = Vec3::new(ps.x * f, ps.y * f, -f);
                let lens = aperture.sample(s.p_lens).extend(0.0);
                (lens, focus - lens)
            }
            (CameraModel::Orthographic { .. }, Aperture::Pinhole) => (ps.extend(0.0), Vec3::NEG_Z),
            (CameraModel::Orthographic { .. }, aperture) => {
                let f = self.focus_distance;
                let focus = Vec3::new(ps.x, ps.y, -f);
                let origin = focus.with_z(0.0) + aperture.sample(s.p_lens).extend(0.0);
                (origin, focus - origin)
            }
        };
        let dir = dir.normalize();
        dir.is_finite().then_some(CameraRay { origin, dir })
    }

    /// The primary ray for one sample, in world space.
    #[inline(always)]
    pub fn generate_ray(&self, s: &CameraSample) -> Option<CameraRay> {
        let r = self.generate_ray_camera_space(s)?;
        let dir = self.world_from_camera.transform_vector3(r.dir).normalize();
        Some(CameraRay {
            origin: self.world_from_camera.transform_point3(r.origin),
            dir,
        })
    }

    /// The ray through raster position `p_film` and the lens centre, in world space: a pinhole
    /// camera's ray, the one the Depth and Position passes trace.
    pub fn centre_ray(&self, p_film: Vec2) -> Option<CameraRay> {
        let ps = self.screen_point(p_film);
        let (origin, dir) = match self.model {
            CameraModel::ThinLens { .. } => (Vec3::ZERO, Vec3::new(ps.x, ps.y, -1.0)),
            CameraModel::Orthographic { .. } => (ps.extend(0.0), Vec3::NEG_Z),
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
mod tests {
    use super::*;
    use aperture_scene::Dof;

    fn scene_camera(radius: f32, blades: u32, focus: f32) -> aperture_scene::Camera {
        test_scene_camera(Dof {
            enabled: true,
            aperture_radius: radius,
            focus_distance: focus,
            blades,
            rotation: 0.2,
            ..Dof::default()
        })
    }

    fn grid(n: u32) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |i| {
            Vec2::new(
                ((i % n) as f32 + 0.37) / n as f32,
                ((i / n) as f32 + 0.61) / n as f32,
            )
        })
    }

    #[test]
    fn focal_plane_point_is_the_same_for_every_lens_sample() {
        for blades in [0, 6] {
            for ortho in [false, true] {
                let mut sc = scene_camera(0.1, blades, 4.0);
                if ortho {
                    sc.projection = Projection::Orthographic {
                        xmag: 2.0,
                        ymag: 1.5,
                    };
                }
                let cam = Camera::new(&sc, 64, 48);
                let p_film = Vec2::new(13.3, 40.2);
                let pin = Camera {
                    aperture: Aperture::Pinhole,
                    ..cam
                }
                .generate_ray_camera_space(&CameraSample {
                    p_film,
                    p_lens: Vec2::ZERO,
                    time: 0.0,
                })
                .unwrap();
                let target = pin.origin + pin.dir * (4.0 / -pin.dir.z);
                let mut origins = Vec::new();
                for p_lens in grid(8) {
                    let r = cam
                        .generate_ray_camera_space(&CameraSample {
                            p_film,
                            p_lens,
                            time: 0.0,
                        })
                        .unwrap();
                    let t = (-4.0 - r.origin.z) / r.dir.z;
                    let hit = r.origin + t * r.dir;
                    assert!(hit.distance(target) < 1e-5, "{hit} vs {target}");
                    origins.push(r.origin);
                }
                // And the lens samples really differ (so the check above means something).
                let spread = origins
                    .iter()
                    .map(|o| o.distance(origins[0]))
                    .fold(0.0f32, f32::max);
                assert!(spread > 0.1, "{spread}");
            }
        }
    }

    #[test]
    fn primary_rays_start_inside_the_aperture() {
        // Disc with squeeze: (x·ratio)² + y² ≤ R².
        let mut sc = scene_camera(0.2, 0, 3.0);
        sc.dof.ratio = 2.0;
        let cam = Camera::new(&sc, 32, 32);
        let mut max_x: f32 = 0.0;
        for p_lens in grid(32) {
            let o = cam
                .generate_ray_camera_space(&CameraSample {
                    p_film: Vec2::new(16.0, 16.0),
                    p_lens,
                    time: 0.0,
                })
                .unwrap()
                .origin;
            assert!(o.z == 0.0);
            assert!((o.x * 2.0).hypot(o.y) <= 0.2 * (1.0 + 1e-5));
            max_x = max_x.max(o.x.abs());
        }
        assert!(max_x > 0.09 && max_x <= 0.1 + 1e-6, "{max_x}");
        // Hexagon: inside every edge's half-plane.
        let sc = scene_camera(0.2, 6, 3.0);
        let cam = Camera::new(&sc, 32, 32);
        let corners: Vec<Vec2> = (0..6).map(|k| polygon_corner(k, 6, 0.2) * 0.2).collect();
        for p_lens in grid(32) {
            let o = cam
                .generate_ray_camera_space(&CameraSample {
                    p_film: Vec2::new(3.0, 29.0),
                    p_lens,
                    time: 0.0,
                })
                .unwrap()
                .origin
                .truncate();
            for k in 0..6 {
                let (a, b) = (corners[k], corners[(k + 1) % 6]);
                assert!((b - a).perp_dot(o - a) >= -1e-6, "{o} outside edge {k}");
            }
        }
    }

    #[test]
    fn zero_radius_is_a_pinhole() {
        let cam = Camera::new(&scene_camera(0.0, 6, 3.0), 16, 16);
        assert_eq!(cam.aperture, Aperture::Pinhole);
        let mut sc = scene_camera(0.3, 0, 3.0);
        sc.dof.enabled = false;
        assert_eq!(Camera::new(&sc, 16, 16).aperture, Aperture::Pinhole);
    }

    #[test]
    fn image_plane_orientation() {
        let mut sc = scene_camera(0.0, 0, 1.0);
        sc.world_from_camera = Affine3A::IDENTITY;
        let cam = Camera::new(&sc, 40, 20);
        let top_left = cam
            .generate_ray(&CameraSample {
                p_film: Vec2::ZERO,
                p_lens: Vec2::ZERO,
                time: 0.0,
            })
            .unwrap();
        assert!(top_left.dir.x < 0.0 && top_left.dir.y > 0.0 && top_left.dir.z < 0.0);
        // Vertical half-angle is yfov/2, horizontal follows the aspect.
        let top = cam
            .generate_ray(&CameraSample {
                p_film: Vec2::new(20.0, 0.0),
                p_lens: Vec2::ZERO,
                time: 0.0,
            })
            .unwrap();
        assert!((top.dir.y / -top.dir.z - (0.4f32).tan()).abs() < 1e-6);
        assert!((top_left.dir.x / top_left.dir.z - 2.0 * (0.4f32).tan()).abs() < 1e-5);
    }

    mod properties {
        //! Property-based checks over the whole parameter space the loader lets through.
        use super::*;
        use proptest::prelude::*;

        /// Lens parameters: radius from 0 (pinhole) over twelve decades, focus from 1e-3 to 1e6,
        /// round or 3 to 16 blades, any rotation, squeeze 0.1 to 10.
        fn dof() -> impl Strategy<Value = Dof> {
            (
                prop_oneof![Just(None), (-9.0f32..2.0f32).prop_map(Some)],
                -3.0f32..6.0f32,
                prop_oneof![Just(0u32), 3u32..=16],
                -10.0f32..10.0,
                -1.0f32..1.0f32,
            )
                .prop_map(|(log_r, log_f, blades, rotation, log_ratio)| Dof {
                    enabled: true,
                    aperture_radius: log_r.map_or(0.0, |l| 10f32.powf(l)),
                    focus_distance: 10f32.powf(log_f),
                    blades,
                    rotation,
                    ratio: 10f32.powf(log_ratio),
                    ..Dof::default()
                })
        }

        fn camera(dof: Dof, ortho: bool, yfov: f32) -> Camera {
            let mut sc = scene_camera(0.0, 0, 1.0);
            sc.dof = dof;
            if ortho {
                sc.projection = Projection::Orthographic {
                    xmag: 2.0,
                    ymag: 1.5,
                };
            } else {
                sc.projection = Projection::Perspective {
                    yfov,
                    aspect_ratio: None,
                };
            }
            Camera::new(&sc, 64, 48)
        }

        /// Lens samples in `[0, 1)²`, edges included.
        fn unit() -> impl Strategy<Value = f32> {
            prop_oneof![Just(0.0f32), Just(1.0 - f32::EPSILON / 2.0), 0.0f32..1.0]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(512))]

            /// Every sample gives a finite unit ray from a point of the aperture (in the lens
            /// plane, inside the squeezed disc or polygon), in camera and world space.
            #[test]
            fn rays_are_finite_unit_and_start_on_the_aperture(
                dof in dof(),
                ortho in any::<bool>(),
                yfov in 0.01f32..3.1,
                fx in 0.0f32..=64.0, fy in 0.0f32..=48.0,
                lx in unit(), ly in unit(),
            ) {
                let cam = camera(dof.clone(), ortho, yfov);
                let s = CameraSample { p_film: Vec2::new(fx, fy), p_lens: Vec2::new(lx, ly), time: 0.0 };
                let r = cam.generate_ray_camera_space(&s).expect("a ray");
                prop_assert!(r.origin.is_finite() && r.dir.is_finite());
                prop_assert!((r.dir.length() - 1.0).abs() < 1e-5);
                prop_assert!(r.dir.z < 0.0, "{}", r.dir);
                let w = cam.generate_ray(&s).expect("a world ray");
                prop_assert!(w.origin.is_finite() && (w.dir.length() - 1.0).abs() < 1e-5);

                // Position on the lens, with the screen offset of orthographic cameras removed.
                let lens = if ortho {
                    r.origin.truncate() - cam.screen_point(s.p_film)
                } else {
                    r.origin.truncate()
                };
                prop_assert_eq!(r.origin.z, 0.0);
                let radius = dof.aperture_radius;
                // Unsqueezed, the point is inside the radius-R circle (all polygons are too);
                // tolerance: a few roundings of R, plus the orthographic screen offset's.
                let tol = 1e-5 * radius + if ortho { 1e-5 * 3.0 } else { 0.0 };
                let unsqueezed = Vec2::new(lens.x * dof.ratio, lens.y);
                prop_assert!(unsqueezed.length() <= radius + tol, "{unsqueezed} vs {radius}");
                if dof.blades >= 3 && radius > 0.0 {
                    // Inside every edge's half-plane of the blade polygon.
                    let n = dof.blades;
                    for k in 0..n {
                        let a = polygon_corner(k, n, dof.rotation) * radius;
                        let b = polygon_corner((k + 1) % n, n, dof.rotation) * radius;
                        let side = (b - a).perp_dot(unsqueezed - a) / (b - a).length();
                        prop_assert!(side >= -tol, "outside edge {} by {}", k, -side);
                    }
                }
            }

            /// The thin-lens rule: all rays of one film point meet at the same point of the
            /// focal plane, the one the pinhole ray through that film point reaches.
            #[test]
            fn the_focal_plane_point_does_not_depend_on_the_lens_sample(
                dof in dof(),
                ortho in any::<bool>(),
                yfov in 0.01f32..3.1,
                fx in 0.0f32..=64.0, fy in 0.0f32..=48.0,
                lx in unit(), ly in unit(),
            ) {
                let cam = camera(dof.clone(), ortho, yfov);
                let f = dof.focus_distance;
                let p_film = Vec2::new(fx, fy);
                let pin = Camera { aperture: Aperture::Pinhole, ..cam }
                    .generate_ray_camera_space(&CameraSample { p_film, p_lens: Vec2::ZERO, time: 0.0 })
                    .expect("a pinhole ray");
                let target = pin.origin + pin.dir * (f / -pin.dir.z);
                let r = cam
                    .generate_ray_camera_space(&CameraSample { p_film, p_lens: Vec2::new(lx, ly), time: 0.0 })
                    .expect("a ray");
                let hit = r.origin + r.dir * ((-f - r.origin.z) / r.dir.z);
                // Rounding: relative 1e-5 of the distances involved (focal point and lens
                // offset; direction normalisation and division each cost a few ulps).
                let scale = target.length() + r.origin.length();
                prop_assert!(
                    hit.distance(target) <= 1e-5 * scale,
                    "{} vs {} (scale {})", hit, target, scale
                );
            }
        }
    }
}
