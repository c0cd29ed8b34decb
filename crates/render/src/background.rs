//! Pixels that can only see the background. A thin-lens camera's rays through a pixel fill a
//! known pencil (lens points to the pixel's footprint on the focal plane), so the pixels whose
//! rays may meet the scene's bounds form a rectangle of the image that a few projected corners
//! give. Outside it every sample's ray leaves the scene at once; under a constant environment
//! all such samples are the same sample, which the render adds without tracing them (a product
//! shot's background is most of its image).

use crate::aov::SampleAov;
use crate::camera::{Camera, CameraModel};
use crate::environment::Environment;
use crate::filter::Filter;
use crate::integrator::Integrator;
use crate::sampler::{SampleStream, SamplerKind};
use aperture_accel::Accel;
use glam::{DAffine3, DVec3, Vec3};

/// Under a constant environment, the pixels whose rays may meet the scene and the one sample
/// every other pixel's samples are (a camera ray that meets nothing sees the same radiance in
/// every direction).
pub(crate) struct Backdrop {
    /// The pixels traced.
    pub scene: PixelRect,
    /// The sample of the others: radiance, coverage (false), pass values.
    pub l: Vec3,
    pub covered: bool,
    pub record: SampleAov,
}

/// The [`Backdrop`] of a render, when the environment is constant and some pixel of the image
/// can only see it.
pub(crate) fn backdrop(
    integrator: &Integrator<'_>,
    accel: &Accel,
    camera: &Camera,
    filter: &Filter,
    env: &Environment,
) -> Option<Backdrop> {
    if !matches!(env, Environment::Constant(_)) {
        return None;
    }
    let scene = scene_pixels(camera, accel.bounds(), filter.half_width());
    if scene == PixelRect::all(camera.width, camera.height) {
        return None;
    }
    // Any direction and stream: the path ends at its camera ray, before any sample value
    // could matter.
    let stream = SampleStream::new(SamplerKind::Sobol, 0, 0, 0, 0);
    let (l, covered, record) = integrator.missed_sample(Vec3::NEG_Z, &stream);
    Some(Backdrop {
        scene,
        l,
        covered,
        record,
    })
}

/// The pixels (inclusive bounds) whose camera rays may meet the scene; the others' rays
/// provably meet nothing. Empty when `x0 > x1` or `y0 > y1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PixelRect {
    pub x0: i64,
    pub x1: i64,
    pub y0: i64,
    pub y1: i64,
}

impl PixelRect {
    /// Every pixel of a `width × height` image.
    pub fn all(width: u32, height: u32) -> Self {
        Self {
            x0: 0,
            x1: i64::from(width) - 1,
            y0: 0,
            y1: i64::from(height) - 1,
        }
    }

    /// Whether pixel `(x, y)` lies in the rectangle.
    #[inline(always)]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        let (x, y) = (i64::from(x), i64::from(y));
        x >= self.x0 && x <= self.x1 && y >= self.y0 && y <= self.y1
    }
}

/// Rounding margin: the scene's bounds grow by this fraction of their size (and of their
/// distance from the world origin) before they are projected, and the rectangle by one pixel
/// on every side. The render's own rays carry `f32` rounding of about 1e-7 of those sizes.
const PAD: f64 = 1e-3;

/// The pixels of `camera`'s image whose rays (any lens point, any film point within
/// `filter_half` pixels of the pixel's centre) may meet the box `bounds` (world space; `None`
/// for a scene without geometry). Every pixel when the camera is not a perspective one or the
/// box reaches the lens plane (no bound there is useful).
///
/// Why it holds: a ray from lens point `L` (`|L.x| ≤ Rx`, `|L.y| ≤ Ry`, `z = 0`) through the
/// focal-plane point `(p f, −f)` of screen point `p` passes a point `Q` at depth `s > 0` when
/// `p = Q.xy / s − L (1/s − 1/f)`. Over the box (all at `s > 0`) `Q.xy / s` is extreme at a
/// corner (a ratio of linear functions on a convex set), and `|1/s − 1/f|` too (convex in
/// `1/s`): the screen points that see the box lie within those corner extremes widened by
/// `R max |1/s − 1/f|`.
pub(crate) fn scene_pixels(
    camera: &Camera,
    bounds: Option<(Vec3, Vec3)>,
    filter_half: f32,
) -> PixelRect {
    let (w, h) = (camera.width, camera.height);
    let all = PixelRect::all(w, h);
    let Some((lo, hi)) = bounds else {
        // Nothing to see: every ray leaves at once.
        return PixelRect {
            x0: 0,
            x1: -1,
            y0: 0,
            y1: -1,
        };
    };
    let CameraModel::ThinLens {
        tan_half_x,
        tan_half_y,
    } = camera.model
    else {
        return all;
    };
    let Some([x_min, x_max, y_min, y_max]) = screen_window(camera, lo, hi) else {
        return all;
    };
    // Screen (image plane at distance 1) to raster: x right, y down.
    let (tx, ty) = (f64::from(tan_half_x), f64::from(tan_half_y));
    let (wf, hf) = (f64::from(w), f64::from(h));
    let raster_x = |p: f64| (p / tx + 1.0) * 0.5 * wf;
    let raster_y = |p: f64| (1.0 - p / ty) * 0.5 * hf;
    let (x_lo, x_hi) = (raster_x(x_min), raster_x(x_max));
    let (y_lo, y_hi) = (raster_y(y_max), raster_y(y_min));
    // Pixel x samples the film at x + ½ ± filter_half; one more pixel for rounding.
    let m = f64::from(filter_half) + 1.0;
    let rect = [
        x_lo - 0.5 - m,
        x_hi - 0.5 + m,
        y_lo - 0.5 - m,
        y_hi - 0.5 + m,
    ];
    if !(rect.iter().all(|v| v.is_finite()) && tx > 0.0 && ty > 0.0) {
        return all;
    }
    // Whole pixels, within -1 ..= size (outside the image on either side means none).
    let pixel = |v: f64, size: u32| v.clamp(-1.0, f64::from(size)) as i64;
    PixelRect {
        x0: pixel(rect[0].floor(), w).max(0),
        x1: pixel(rect[1].ceil(), w).min(i64::from(w) - 1),
        y0: pixel(rect[2].floor(), h).max(0),
        y1: pixel(rect[3].ceil(), h).min(i64::from(h) - 1),
    }
}

/// The window of the image plane (at distance 1: `[x_min, x_max, y_min, y_max]`) whose screen
/// points' rays may meet the box `lo..hi` (padded by [`PAD`]), lens spread included; `None`
/// when the box reaches the lens plane (no bound there is useful) or a value is not finite.
fn screen_window(camera: &Camera, lo: Vec3, hi: Vec3) -> Option<[f64; 4]> {
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let pad = PAD * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
    let (lo, hi) = (lo - DVec3::splat(pad), hi + DVec3::splat(pad));
    let camera_from_world = dmat(camera).inverse();
    // Lens half-extents (an anamorphic aperture is squeezed in x by its ratio).
    let (rx, ry) = lens_half_extents(camera);
    let inv_f = 1.0 / f64::from(camera.focus_distance);
    let mut window = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut spread = 0.0f64;
    for k in 0..8 {
        let corner = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let q = camera_from_world.transform_point3(corner);
        let s = -q.z;
        // The box reaches the lens plane (or the camera is inside it, or a value is NaN).
        if s.is_nan() || s <= pad {
            return None;
        }
        let (x, y) = (q.x / s, q.y / s);
        window = [
            window[0].min(x),
            window[1].max(x),
            window[2].min(y),
            window[3].max(y),
        ];
        if rx > 0.0 || ry > 0.0 {
            spread = spread.max((1.0 / s - inv_f).abs());
        }
    }
    let (sx, sy) = (rx * spread, ry * spread);
    let window = [
        window[0] - sx,
        window[1] + sx,
        window[2] - sy,
        window[3] + sy,
    ];
    window.iter().all(|v| v.is_finite()).then_some(window)
}

/// `camera.world_from_camera` in `f64`.
fn dmat(camera: &Camera) -> DAffine3 {
    let m = camera.world_from_camera;
    DAffine3::from_cols(
        m.matrix3.x_axis.as_dvec3(),
        m.matrix3.y_axis.as_dvec3(),
        m.matrix3.z_axis.as_dvec3(),
        m.translation.as_dvec3(),
    )
}

/// The largest `|x|` and `|y|` of a lens point of `camera`'s aperture.
fn lens_half_extents(camera: &Camera) -> (f64, f64) {
    use crate::camera::Aperture;
    match camera.aperture {
        Aperture::Pinhole => (0.0, 0.0),
        Aperture::Disc { radius, ratio } | Aperture::Polygon { radius, ratio, .. } => {
            let r = f64::from(radius);
            (r / f64::from(ratio), r)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Aperture, CameraSample};
    use glam::{Affine3A, Quat, Vec2};

    /// A small deterministic generator (xorshift).
    struct Rng(u64);

    impl Rng {
        fn f(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn range(&mut self, a: f32, b: f32) -> f32 {
            a + (b - a) * self.f()
        }
    }

    /// Whether the segment from `o` along `d` (`t ≥ 0`) meets the box, in `f64`.
    fn meets(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> bool {
        let (o, d, lo, hi) = (o.as_dvec3(), d.as_dvec3(), lo.as_dvec3(), hi.as_dvec3());
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    return false;
                }
                continue;
            }
            let (u, v) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
        t0 <= t1
    }

    fn camera(rng: &mut Rng, aperture: Aperture, width: u32, height: u32) -> Camera {
        let rot = Quat::from_euler(
            glam::EulerRot::YXZ,
            rng.range(-3.0, 3.0),
            rng.range(-0.7, 0.7),
            rng.range(-0.3, 0.3),
        );
        let pos = Vec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        let tan_half_y = rng.range(0.1, 1.2);
        Camera {
            world_from_camera: Affine3A::from_rotation_translation(rot, pos),
            model: CameraModel::ThinLens {
                tan_half_x: tan_half_y * width as f32 / height as f32,
                tan_half_y,
            },
            aperture,
            focus_distance: rng.range(0.5, 20.0),
            width,
            height,
        }
    }

    #[test]
    fn rays_of_pixels_outside_never_meet_the_box() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut culled, mut kept) = (0usize, 0usize);
        for case in 0..300 {
            let radius = [0.0, 0.05, 0.4, 1.5][case % 4];
            let aperture = match case % 3 {
                _ if radius == 0.0 => Aperture::Pinhole,
                0 => Aperture::Disc { radius, ratio: 1.0 },
                1 => Aperture::Disc { radius, ratio: 0.6 },
                _ => Aperture::Polygon {
                    radius,
                    blades: 5,
                    rotation: 0.3,
                    ratio: 1.4,
                },
            };
            let (width, height) = (24, 18);
            let cam = camera(&mut rng, aperture, width, height);
            // A box somewhere in front of (or around) the camera.
            let at = cam.world_from_camera.transform_point3(Vec3::new(
                rng.range(-4.0, 4.0),
                rng.range(-3.0, 3.0),
                rng.range(-12.0, 1.0),
            ));
            let half = Vec3::new(
                rng.range(0.05, 2.0),
                rng.range(0.05, 2.0),
                rng.range(0.05, 2.0),
            );
            let (lo, hi) = (at - half, at + half);
            let filter_half = [0.5, 0.75][case % 2];
            let rect = scene_pixels(&cam, Some((lo, hi)), filter_half);
            for y in 0..height {
                for x in 0..width {
                    if rect.contains(x, y) {
                        kept += 1;
                        continue;
                    }
                    culled += 1;
                    for _ in 0..24 {
                        // Film points over the filter's support, lens points over the square
                        // around the aperture and its own samples alike.
                        let off =
                            Vec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * filter_half;
                        let s = CameraSample {
                            p_film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + off,
                            p_lens: Vec2::new(rng.f(), rng.f()),
                        };
                        let r = cam
                            .generate_ray(&s)
                            .expect("a perspective camera makes rays");
                        assert!(
                            !meets(r.origin, r.dir, lo, hi),
                            "case {case}: pixel ({x}, {y}) outside {rect:?} meets the box"
                        );
                    }
                }
            }
        }
        // Both kinds occur, so the test checks something either way.
        assert!(
            culled > 10_000 && kept > 10_000,
            "culled {culled}, kept {kept}"
        );
    }

    #[test]
    fn the_rectangle_holds_the_pixels_that_see_the_box() {
        // Pixels whose centre ray meets the box are all inside, however the rectangle is cut.
        let mut rng = Rng(7);
        for _ in 0..200 {
            let cam = Camera {
                model: CameraModel::ThinLens {
                    tan_half_x: 0.96,
                    tan_half_y: 0.6,
                },
                focus_distance: rng.range(4.0, 8.0),
                ..camera(
                    &mut rng,
                    Aperture::Disc {
                        radius: 0.2,
                        ratio: 1.0,
                    },
                    32,
                    20,
                )
            };
            let at = cam
                .world_from_camera
                .transform_point3(Vec3::new(0.0, 0.0, -6.0));
            let (lo, hi) = (at - Vec3::splat(0.7), at + Vec3::splat(0.7));
            let rect = scene_pixels(&cam, Some((lo, hi)), 0.5);
            let mut seen = 0;
            for y in 0..20 {
                for x in 0..32 {
                    let r = cam
                        .centre_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                        .expect("a ray");
                    if meets(r.origin, r.dir, lo, hi) {
                        seen += 1;
                        assert!(rect.contains(x, y), "({x}, {y}) sees the box, {rect:?}");
                    }
                }
            }
            assert!(seen > 0);
            // And the bound is tight enough to matter: a box of 1.4 at distance 6 (in focus
            // or nearly) leaves most of a view 7.2 high outside.
            let area = (rect.x1 - rect.x0 + 1) * (rect.y1 - rect.y0 + 1);
            assert!(area < 32 * 20 / 2, "{rect:?}");
        }
    }

    #[test]
    fn no_bound_where_none_holds() {
        let mut rng = Rng(11);
        let cam = camera(
            &mut rng,
            Aperture::Disc {
                radius: 0.1,
                ratio: 1.0,
            },
            8,
            6,
        );
        let all = PixelRect::all(8, 6);
        // A box around the camera.
        let p: Vec3 = cam.world_from_camera.translation.into();
        assert_eq!(
            scene_pixels(&cam, Some((p - Vec3::ONE, p + Vec3::ONE)), 0.5),
            all
        );
        // Orthographic cameras are not bounded here.
        let ortho = Camera {
            model: CameraModel::Orthographic {
                half_x: 1.0,
                half_y: 1.0,
            },
            ..cam
        };
        let far = cam
            .world_from_camera
            .transform_point3(Vec3::new(0.0, 0.0, -50.0));
        assert_eq!(scene_pixels(&ortho, Some((far, far + Vec3::ONE)), 0.5), all);
        // No geometry: no pixel sees any.
        let none = scene_pixels(&cam, None, 0.5);
        assert!((0..8).all(|x| (0..6).all(|y| !none.contains(x, y))));
    }
}
