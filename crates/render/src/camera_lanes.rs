//! The camera rays of [`LANES`] samples at once, lane by lane, for the usual camera: a thin lens
//! (perspective) with a pinhole or round aperture, the round one clipped by the lens barrel
//! (optical vignetting) or shaped by a bokeh image or neither. Each lane does the IEEE operations of
//! [`Camera::generate_ray`] in the same order (no fused multiply-add, no reassociation), so its
//! ray has the same bits; on `Vec4`s, whose operations are SIMD instructions.

use crate::camera::{Aperture, Camera};
use crate::lens::BokehRef;
use aperture_shading::warp::concentric_disc_lanes;
use aperture_shading::warp_lens::disc_in_disc;
use glam::{Affine3A, Vec2, Vec4};

/// Samples whose rays are made together.
pub(crate) const LANES: usize = 4;

/// Rays of a batch: origin and unit direction per axis, and whether the camera made each one
/// (what `generate_ray` returning `Some` means).
pub(crate) struct RayLanes {
    /// World-space origins, x, y and z of each lane.
    pub origin: [[f32; LANES]; 3],
    /// World-space unit directions, x, y and z of each lane.
    pub dir: [[f32; LANES]; 3],
    /// Whether the camera made each lane's ray (its direction is finite).
    pub made: [bool; LANES],
}

/// What the lanes need of a thin-lens camera.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LensLanes {
    width: f32,
    height: f32,
    tan_half: [f32; 2],
    focus_distance: f32,
    /// Radius and `aperture_ratio` of a round aperture; `None` for a pinhole.
    disc: Option<(f32, f32)>,
    /// The lens barrel's offset per unit of screen position (`Lens::barrel_shift`); 0: none.
    barrel_shift: f32,
    /// The bokeh image (`Lens::bokeh`), sampled lane by lane.
    bokeh: Option<BokehRef>,
    world_from_camera: Affine3A,
}

impl LensLanes {
    /// The lanes of `camera`, or `None` for the cameras they do not cover (orthographic, a
    /// polygonal aperture, a lens with distortion or chromatic aberration, a lens
    /// prescription), which make their rays one at a time.
    ///
    /// Vignetting's clipped disc and the bokeh image's point (issue 61) are found lane by lane
    /// in scalar code (Halley steps, rejection: a data-dependent amount of work), the rest of
    /// the ray in the lanes. Distortion's inverse iterates too, before the screen point the
    /// lanes start from: no lanes for it.
    pub fn new(camera: &Camera) -> Option<Self> {
        let (barrel_shift, bokeh) = (camera.lens.barrel_shift, camera.lens.bokeh);
        let others = crate::lens::Lens {
            barrel_shift: 0.0,
            bokeh: None,
            ..camera.lens
        };
        if !others.is_ideal() || camera.realistic.is_some() {
            return None;
        }
        let (tan_half_x, tan_half_y) = camera.model.tan_half()?;
        let disc = match camera.aperture {
            Aperture::Pinhole => None,
            Aperture::Disc { radius, ratio } => Some((radius, ratio)),
            Aperture::Polygon { .. } => return None,
        };
        Some(Self {
            width: camera.width as f32,
            height: camera.height as f32,
            tan_half: [tan_half_x, tan_half_y],
            focus_distance: camera.focus_distance,
            disc,
            barrel_shift,
            bokeh,
            world_from_camera: camera.world_from_camera,
        })
    }

    /// The rays of film positions `film` (raster x, y) and lens samples `lens` (ignored by a
    /// pinhole): lane `l` is `Camera::generate_ray` of sample `l`, bit for bit. Always inlined
    /// into `PrimarySamples::fill` (out of line it costs 0.4 % of a round lens's sample).
    #[inline(always)]
    pub fn rays(&self, film: [[f32; LANES]; 2], lens: [[f32; LANES]; 2]) -> RayLanes {
        let [fx, fy] = film.map(Vec4::from_array);
        // `Camera::screen_point`.
        let ps_x = (2.0 * fx / self.width - 1.0) * self.tan_half[0];
        let ps_y = (1.0 - 2.0 * fy / self.height) * self.tan_half[1];
        // `Camera::generate_ray_camera_space`: origin on the lens, direction to the focus point.
        let (lens_x, lens_y, dir) = match self.disc {
            None => (Vec4::ZERO, Vec4::ZERO, [ps_x, ps_y, Vec4::splat(-1.0)]),
            Some((radius, ratio)) => {
                let (dx, dy) = match self.barrel_shift > 0.0 || self.bokeh.is_some() {
                    false => concentric_disc_lanes(lens.map(Vec4::from_array)),
                    true => self.lens_points((ps_x, ps_y), lens),
                };
                let (lx, ly) = (dx * radius / ratio, dy * radius);
                let f = self.focus_distance;
                (
                    lx,
                    ly,
                    [ps_x * f - lx, ps_y * f - ly, Vec4::splat(-f - 0.0)],
                )
            }
        };
        let dir = normalize(dir);
        let made = dir[0].is_finite_mask() & dir[1].is_finite_mask() & dir[2].is_finite_mask();
        // `Camera::generate_ray`: to world space, the direction normalised again.
        let m = &self.world_from_camera.matrix3;
        let (ax, ay, az) = (
            m.x_axis.to_array(),
            m.y_axis.to_array(),
            m.z_axis.to_array(),
        );
        let t = self.world_from_camera.translation.to_array();
        let world_dir: [Vec4; 3] =
            std::array::from_fn(|c| ax[c] * dir[0] + ay[c] * dir[1] + az[c] * dir[2]);
        // The lens point's z is 0, but its product is added all the same (it may be −0).
        let origin: [Vec4; 3] = std::array::from_fn(|c| {
            ax[c] * lens_x + ay[c] * lens_y + Vec4::splat(az[c] * 0.0) + t[c]
        });
        let bits = made.bitmask();
        RayLanes {
            origin: origin.map(|v| v.to_array()),
            dir: normalize(world_dir).map(|v| v.to_array()),
            made: std::array::from_fn(|l| bits & (1 << l) != 0),
        }
    }
}

impl LensLanes {
    /// Each lane's lens point in aperture radii, before the squeeze (`Camera::lens_point`
    /// before its radius): the bokeh image's, or the unit disc's clipped by the lens barrel
    /// around `−barrel_shift · ps`. Out of line, so the plain disc's lanes stay as lean as they
    /// were.
    #[inline(never)]
    fn lens_points(&self, (ps_x, ps_y): (Vec4, Vec4), lens: [[f32; LANES]; 2]) -> (Vec4, Vec4) {
        let (px, py) = (ps_x.to_array(), ps_y.to_array());
        let (mut dx, mut dy) = ([0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            let ps = Vec2::new(px[l], py[l]);
            let barrel = (self.barrel_shift > 0.0).then(|| -ps * self.barrel_shift);
            let u = Vec2::new(lens[0][l], lens[1][l]);
            let d = match (self.bokeh, barrel) {
                (Some(b), barrel) => b.sample(u, barrel),
                (None, Some(c)) => disc_in_disc(u, c, 1.0).unwrap_or(0.5 * c),
                (None, None) => aperture_shading::warp::concentric_disc(u),
            };
            (dx[l], dy[l]) = (d.x, d.y);
        }
        (Vec4::from_array(dx), Vec4::from_array(dy))
    }
}

/// `Vec3::normalize` lane by lane: times the reciprocal of the length.
#[inline(always)]
fn normalize(v: [Vec4; 3]) -> [Vec4; 3] {
    let inv = Vec4::ONE / (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c * inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::camera::{CameraRay, CameraSample};
    use crate::sampler::hash_u32;
    use aperture_scene::Dof;
    use glam::{Vec2, Vec3};

    fn camera(radius: f32, ratio: f32) -> Camera {
        camera_with(radius, ratio, aperture_scene::LensOptions::default())
    }

    /// A round-aperture camera with lens options `lens`.
    fn camera_with(radius: f32, ratio: f32, lens: aperture_scene::LensOptions) -> Camera {
        let mut sc = crate::camera::test_scene_camera(Dof {
            enabled: true,
            aperture_radius: radius,
            focus_distance: 4.0,
            ratio,
            lens_options: lens,
            ..Dof::default()
        });
        // Tilted as well, so that every matrix entry takes part.
        sc.world_from_camera *= Affine3A::from_rotation_x(-0.7);
        Camera::new(&sc, 37, 23)
    }

    /// A float in [0, 1) from a hash, with exact values (0, 0.5, the largest below 1) mixed in.
    fn unit(x: &mut u32) -> f32 {
        *x = hash_u32(*x);
        match *x % 16 {
            0 => 0.0,
            1 => 0.5,
            2 => 1.0 - f32::EPSILON / 2.0,
            _ => (*x >> 8) as f32 / (1u32 << 24) as f32,
        }
    }

    #[test]
    fn lanes_are_the_scalar_rays_bit_for_bit() {
        let bits = |r: Option<CameraRay>| {
            r.map(|r| {
                (
                    r.origin.to_array().map(f32::to_bits),
                    r.dir.to_array().map(f32::to_bits),
                )
            })
        };
        let mut x = 5u32;
        let vignetted = |mut cam: Camera, shift: f32| {
            cam.lens.barrel_shift = shift;
            cam
        };
        // A bokeh image: a ring brighter on one side, 16×16.
        let ring: Vec<f32> = (0..256)
            .map(|i| {
                let (x, y) = ((i % 16) as f32 - 7.5, (i / 16) as f32 - 7.5);
                let r = (x * x + y * y).sqrt();
                if (4.0..7.5).contains(&r) {
                    0.3 + 0.7 * (x + 8.0) / 16.0
                } else {
                    0.0
                }
            })
            .collect();
        let image = aperture_scene::ApertureImage::new("ring".into(), 16, 16, ring);
        let bokeh = aperture_scene::LensOptions {
            aperture_image: Some(std::sync::Arc::new(image.expect("an image"))),
            ..Default::default()
        };
        let imaged = camera_with(0.2, 1.3, bokeh.clone());
        assert!(imaged.lens.bokeh.is_some());
        for cam in [
            camera(0.0, 1.0),
            camera(0.1, 1.0),
            camera(0.3, 1.7),
            vignetted(camera(0.1, 1.0), 0.7),
            vignetted(camera(0.3, 1.7), 1.6),
            imaged,
            vignetted(camera_with(0.2, 1.0, bokeh), 0.9),
        ] {
            let lanes_of = LensLanes::new(&cam).unwrap();
            for _ in 0..400 {
                let mut film = [[0.0; LANES]; 2];
                let mut lens = [[0.0; LANES]; 2];
                for l in 0..LANES {
                    // Film positions over and past the image, and lens samples at the centre.
                    film[0][l] = unit(&mut x) * 40.0 - 1.0;
                    film[1][l] = unit(&mut x) * 25.0 - 1.0;
                    lens[0][l] = unit(&mut x);
                    lens[1][l] = unit(&mut x);
                }
                let got = lanes_of.rays(film, lens);
                for l in 0..LANES {
                    let want = cam.generate_ray(&CameraSample {
                        p_film: Vec2::new(film[0][l], film[1][l]),
                        p_lens: Vec2::new(lens[0][l], lens[1][l]),
                        time: 0.0,
                    });
                    let ray = got.made[l].then(|| CameraRay {
                        origin: Vec3::new(got.origin[0][l], got.origin[1][l], got.origin[2][l]),
                        dir: Vec3::new(got.dir[0][l], got.dir[1][l], got.dir[2][l]),
                    });
                    assert_eq!(
                        bits(ray),
                        bits(want),
                        "film {film:?} lens {lens:?} lane {l}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_lanes_refuse_other_cameras() {
        let mut cam = camera(0.1, 1.0);
        cam.aperture = Aperture::Polygon {
            radius: 0.1,
            blades: 6,
            rotation: 0.0,
            ratio: 1.0,
        };
        assert!(LensLanes::new(&cam).is_none());
        let mut cam = camera(0.1, 1.0);
        cam.model = CameraModel::Orthographic {
            half_x: 1.0,
            half_y: 1.0,
        };
        assert!(LensLanes::new(&cam).is_none());
        let mut cam = camera(0.1, 1.0);
        cam.lens.chromatic = Some(crate::lens::Chromatic {
            lateral: 0.01,
            longitudinal: 0.0,
        });
        assert!(LensLanes::new(&cam).is_none());
    }
}
