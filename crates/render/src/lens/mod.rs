//! The thin lens's imperfections (issue 61), as the camera uses them: the lens barrel that
//! clips the aperture off axis (optical vignetting, cat's-eye bokeh) and Brown–Conrady
//! distortion, the bokeh image (`bokeh.rs`) and chromatic aberration. Pure maths on screen points (image-plane positions at distance 1, y up); the
//! camera (`camera.rs`) calls it. [`Lens::IDEAL`] changes nothing, bit for bit.

mod bokeh;
mod distortion;

use aperture_scene::LensOptions;
pub use aperture_scene::{Chromatic, Distortion};
pub use bokeh::{Bokeh, BokehRef};
use glam::Vec2;

/// What the camera needs of [`LensOptions`], worked out for one image.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Lens {
    /// The barrel's offset per unit of screen position, in aperture radii: for screen point
    /// `ps` the barrel is the disc of the aperture's radius around `−barrel_shift · ps`. 0: no
    /// vignetting.
    pub barrel_shift: f32,
    /// Distortion of a perspective camera; `None` when every coefficient is 0.
    pub distortion: Option<Distortion>,
    /// The bokeh image; `None`: the plain aperture (also for a constant image).
    pub bokeh: Option<BokehRef>,
    /// Chromatic aberration; `None` when both numbers are 0.
    pub chromatic: Option<Chromatic>,
}

/// How a channel's image and focus move against green's: +1 for red, −1 for blue
/// (channels 0 R, 1 G, 2 B).
pub const CHANNEL_SIGN: [f32; 3] = [1.0, 0.0, -1.0];

/// The channel a path carries under chromatic aberration, from the uniform number `u` (the
/// path's wavelength dimension), and a fresh uniform number from what the choice left of `u`.
#[inline]
pub fn channel_of(u: f32) -> (usize, f32) {
    let x = u.clamp(0.0, 1.0) * 3.0;
    let c = (x as usize).min(2);
    (c, (x - c as f32).clamp(0.0, 1.0 - f32::EPSILON / 2.0))
}

impl Lens {
    /// The ideal thin lens.
    pub const IDEAL: Self = Self {
        barrel_shift: 0.0,
        distortion: None,
        bokeh: None,
        chromatic: None,
    };

    /// The lens of `options` for an image whose corner is `corner` from its centre in screen
    /// units. Vignetting `v` puts the barrel `v` aperture radii off centre at the corners
    /// (the image of a round stop of the aperture's radius `v·R / corner` in front of the
    /// lens, focus at infinity). Distortion applies to perspective cameras only.
    pub fn new(options: &LensOptions, corner: f32, radius: f32, perspective: bool) -> Self {
        let v = options.vignetting;
        let barrel_shift = if v > 0.0 && radius > 0.0 && corner > 0.0 && corner.is_finite() {
            v / corner
        } else {
            0.0
        };
        let d = options.distortion;
        let c = options.chromatic;
        Self {
            barrel_shift,
            distortion: (perspective && !d.is_zero()).then_some(d),
            bokeh: None,
            chromatic: (!c.is_zero()).then_some(c),
        }
    }

    /// Whether this is the ideal thin lens.
    pub fn is_ideal(&self) -> bool {
        *self == Self::IDEAL
    }

    /// The barrel's centre, in aperture radii, for the ray bundle of screen point `ps`; `None`
    /// without vignetting.
    #[inline(always)]
    pub fn barrel(&self, ps: Vec2) -> Option<Vec2> {
        (self.barrel_shift > 0.0).then(|| -ps * self.barrel_shift)
    }

    /// The direction (screen point) of the film's distorted screen point `ps`; `None` past the
    /// fold of a strong barrel distortion, where no direction images there.
    #[inline(always)]
    pub fn undistort(&self, ps: Vec2) -> Option<Vec2> {
        match &self.distortion {
            None => Some(ps),
            Some(d) => distortion::undistort(d, ps),
        }
    }

    /// Screen point `ps` and focus distance `f` for channel `channel` (0 R, 1 G, 2 B): the
    /// direction whose image lands at `ps` in that channel's image, `1 ± lateral` times the
    /// size of green's, and that channel's focus, `1 ± longitudinal` times green's. Unchanged
    /// without chromatic aberration and for green.
    #[inline(always)]
    pub fn for_channel(&self, ps: Vec2, f: f32, channel: usize) -> (Vec2, f32) {
        match self.chromatic {
            Some(c) if channel != 1 => {
                let k = CHANNEL_SIGN[channel.min(2)];
                (ps / (1.0 + k * c.lateral), f * (1.0 + k * c.longitudinal))
            }
            _ => (ps, f),
        }
    }

    /// Where on the film (distorted screen point) direction `p` (a screen point) images.
    pub fn distort(&self, p: Vec2) -> Vec2 {
        match &self.distortion {
            None => p,
            Some(d) => distortion::distort(d, p),
        }
    }
}
