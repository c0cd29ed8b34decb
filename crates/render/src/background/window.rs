//! The pixels whose camera rays may meet one box: a rectangle of the image, from the box's
//! corners and its crossings of the lens plane.

use crate::camera::Camera;
use glam::{DAffine3, DVec3, Vec3};

/// Rounding margin: a box grows by this fraction of its size (and of its distance from the
/// world origin) before it is projected, and the rectangle by one pixel on every side. The
/// render's own rays carry `f32` rounding of about 1e-7 of those sizes.
const PAD: f64 = 1e-3;

/// A rectangle of pixels (inclusive bounds). Empty when `x0 > x1` or `y0 > y1`.
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

    /// No pixel.
    pub const EMPTY: Self = Self {
        x0: 0,
        x1: -1,
        y0: 0,
        y1: -1,
    };

    /// Whether pixel `(x, y)` lies in the rectangle.
    #[cfg(test)]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        let (x, y) = (i64::from(x), i64::from(y));
        x >= self.x0 && x <= self.x1 && y >= self.y0 && y <= self.y1
    }
}

/// What projecting boxes onto `camera`'s pixels needs, worked out once per render: the camera
/// in `f64`, its lens and focus, its screen-to-raster scale and the filter's reach. `None`
/// when the camera is not a perspective one (or its field of view is not finite): no bound.
///
/// Why it holds: a ray from lens point `L` (`|L.x| ≤ Rx`, `|L.y| ≤ Ry`, `z = 0`) through the
/// focal-plane point `(p f, −f)` of screen point `p` passes a point `Q` at depth `s > 0` when
/// `p = (Q.xy − L (1 − s/f)) / s`. For a fixed `L` that is a ratio of linear functions of `Q`,
/// so over the part of the box in front of the lens (a polytope: the corners at `s > 0` and
/// the edges' crossings of the plane `s = 0`) its extremes lie at vertices; at a vertex the
/// extremes over `L` are `Q.xy / s ± R |1/s − 1/f|`. A crossing (`s = 0`) bounds `p.x` from
/// above only if `Q.x + Rx ≤ 0` (every ray through points near it leaves the image to the
/// left), else `p.x` is unbounded; likewise the other three sides. So a box around the
/// camera gives every pixel, and a ground under it the pixels below its far edge.
pub(crate) struct LensView {
    camera_from_world: DAffine3,
    /// Lens half-extents (an anamorphic aperture is squeezed in x by its ratio).
    rx: f64,
    ry: f64,
    /// Each colour channel's thin lens (one, or three under chromatic aberration): its image's
    /// scale against green's and its `1 / focus distance`.
    channels: Vec<(f64, f64)>,
    /// Screen half-extents at distance 1.
    tx: f64,
    ty: f64,
    width: u32,
    height: u32,
    /// Pixels a rectangle grows by: the filter's half-width plus one for rounding.
    margin: f64,
}

impl LensView {
    /// The view of `camera`, a pixel's samples reaching `filter_half` pixels from its centre.
    /// Vignetting and a bokeh image only shrink the aperture, so the bound holds. Under
    /// chromatic aberration each channel is a thin lens of its own (its image scaled by
    /// `1 ± lateral`, its focus by `1 ± longitudinal`), and the window is the union of the
    /// three. Distortion bends the rays off the thin lens's, so it gets no bound (nor does a
    /// lens prescription).
    pub fn new(camera: &Camera, filter_half: f32) -> Option<Self> {
        if camera.lens.distortion.is_some() || camera.realistic.is_some() {
            return None;
        }
        let f = f64::from(camera.focus_distance);
        let channels: Vec<(f64, f64)> = match camera.lens.chromatic {
            None => vec![(1.0, 1.0 / f)],
            Some(c) => crate::lens::CHANNEL_SIGN
                .iter()
                .map(|&k| {
                    let k = f64::from(k);
                    let scale = 1.0 + k * f64::from(c.lateral);
                    (scale, 1.0 / (f * (1.0 + k * f64::from(c.longitudinal))))
                })
                .collect(),
        };
        if channels
            .iter()
            .any(|&(s, inv_f)| s.is_nan() || s <= 0.0 || inv_f.is_nan())
        {
            return None;
        }
        let (tan_half_x, tan_half_y) = camera.model.tan_half()?;
        let (tx, ty) = (f64::from(tan_half_x), f64::from(tan_half_y));
        if !(tx > 0.0 && ty > 0.0 && tx.is_finite() && ty.is_finite()) {
            return None;
        }
        let (rx, ry) = lens_half_extents(camera);
        Some(Self {
            camera_from_world: dmat(camera).inverse(),
            rx,
            ry,
            channels,
            tx,
            ty,
            width: camera.width,
            height: camera.height,
            margin: f64::from(filter_half) + 1.0,
        })
    }

    /// Every pixel of the image.
    pub fn all(&self) -> PixelRect {
        PixelRect::all(self.width, self.height)
    }

    /// The pixels whose rays (any lens point, any film point within the filter's reach) may
    /// meet the box `lo..hi` (world space); every pixel when a value is NaN.
    pub fn rect(&self, lo: Vec3, hi: Vec3) -> PixelRect {
        let (w, h) = (self.width, self.height);
        let Some([x_min, x_max, y_min, y_max]) = self.screen_window(lo, hi) else {
            return self.all();
        };
        if x_min > x_max || y_min > y_max {
            // The box lies behind the lens.
            return PixelRect::EMPTY;
        }
        // Screen (image plane at distance 1) to raster: x right, y down.
        let (wf, hf) = (f64::from(w), f64::from(h));
        let raster_x = |p: f64| (p / self.tx + 1.0) * 0.5 * wf;
        let raster_y = |p: f64| (1.0 - p / self.ty) * 0.5 * hf;
        let (x_lo, x_hi) = (raster_x(x_min), raster_x(x_max));
        let (y_lo, y_hi) = (raster_y(y_max), raster_y(y_min));
        // Pixel x samples the film at x + ½ ± the filter's half-width.
        let m = self.margin;
        let rect = [
            x_lo - 0.5 - m,
            x_hi - 0.5 + m,
            y_lo - 0.5 - m,
            y_hi - 0.5 + m,
        ];
        if rect.iter().any(|v| v.is_nan()) {
            return self.all();
        }
        // Whole pixels, within -1 ..= size (outside the image on either side means none); an
        // unbounded side is the image's edge.
        let pixel = |v: f64, size: u32| v.clamp(-1.0, f64::from(size)) as i64;
        PixelRect {
            x0: pixel(rect[0].floor(), w).max(0),
            x1: pixel(rect[1].ceil(), w).min(i64::from(w) - 1),
            y0: pixel(rect[2].floor(), h).max(0),
            y1: pixel(rect[3].ceil(), h).min(i64::from(h) - 1),
        }
    }

    /// The window of the image plane (at distance 1: `[x_min, x_max, y_min, y_max]`, infinite
    /// where unbounded, empty when the box lies behind the lens) whose screen points' rays may
    /// meet the box `lo..hi` (padded by [`PAD`]), lens spread included, in any channel; `None`
    /// when a value is NaN.
    fn screen_window(&self, lo: Vec3, hi: Vec3) -> Option<[f64; 4]> {
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let pad = PAD * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
        let (lo, hi) = (lo - DVec3::splat(pad), hi + DVec3::splat(pad));
        let corners: [DVec3; 8] = std::array::from_fn(|k| {
            self.camera_from_world.transform_point3(DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ))
        });
        let mut union = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for &(scale, inv_f) in &self.channels {
            // A channel's film point is its direction's screen point times `scale` (> 0).
            let w = self.channel_window(&corners, inv_f)?;
            union = [
                union[0].min(w[0] * scale),
                union[1].max(w[1] * scale),
                union[2].min(w[2] * scale),
                union[3].max(w[3] * scale),
            ];
        }
        Some(union)
    }

    /// [`LensView::screen_window`] of one thin lens focused at `1 / inv_f`, from the padded
    /// box's corners in camera space.
    fn channel_window(&self, corners: &[DVec3; 8], inv_f: f64) -> Option<[f64; 4]> {
        let (rx, ry) = (self.rx, self.ry);
        let mut window = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for q in corners {
            let s = -q.z;
            if s > 0.0 {
                let spread = (1.0 / s - inv_f).abs();
                let (x, y) = (q.x / s, q.y / s);
                window = [
                    window[0].min(x - rx * spread),
                    window[1].max(x + rx * spread),
                    window[2].min(y - ry * spread),
                    window[3].max(y + ry * spread),
                ];
            }
        }
        // The edges (corner pairs one bit apart) crossing the lens plane.
        for a in 0..8 {
            for bit in [1, 2, 4] {
                let b = a ^ bit;
                let (qa, qb) = (corners[a], corners[b]);
                let (sa, sb) = (-qa.z, -qb.z);
                if !(sa > 0.0 && sb <= 0.0) {
                    continue;
                }
                let q = qa + (qb - qa) * (sa / (sa - sb));
                if q.x + rx > 0.0 {
                    window[1] = f64::INFINITY;
                }
                if q.x - rx < 0.0 {
                    window[0] = f64::NEG_INFINITY;
                }
                if q.y + ry > 0.0 {
                    window[3] = f64::INFINITY;
                }
                if q.y - ry < 0.0 {
                    window[2] = f64::NEG_INFINITY;
                }
            }
        }
        (!window.iter().any(|v| v.is_nan())).then_some(window)
    }
}

/// The pixels of `camera`'s image whose rays may meet the box `lo..hi` ([`LensView::rect`]);
/// every pixel when the camera has no [`LensView`].
#[cfg(test)]
pub(crate) fn box_pixels(camera: &Camera, lo: Vec3, hi: Vec3, filter_half: f32) -> PixelRect {
    LensView::new(camera, filter_half).map_or(PixelRect::all(camera.width, camera.height), |v| {
        v.rect(lo, hi)
    })
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
