//! Colour helpers, each in one place: luminance (weights shared with `aperture_imageio`'s
//! metrics, evaluated in f32 here) and sRGB decoding (`aperture_imageio`'s, the project's one
//! implementation).

use glam::Vec3;

/// Rec.709 luminance of a linear colour.
pub fn luminance(c: Vec3) -> f32 {
    let [r, g, b] = aperture_imageio::metrics::LUMINANCE_WEIGHTS;
    c.dot(Vec3::new(r as f32, g as f32, b as f32))
}

pub use aperture_imageio::view::srgb_eotf as srgb_to_linear;
