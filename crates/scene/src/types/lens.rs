//! The thin lens's imperfections (issue 61): optical vignetting, Brown–Conrady distortion, the
//! bokeh image and chromatic aberration. All zero (or absent) is the ideal thin lens, bit for bit.

use std::sync::Arc;

/// Brown–Conrady distortion as OpenCV writes it (`k1, k2, p1, p2, k3`), in normalised image
/// coordinates (image-plane position at distance 1 from the pinhole, y down as OpenCV's).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Distortion {
    /// Radial coefficient of r².
    pub k1: f32,
    /// Radial coefficient of r⁴.
    pub k2: f32,
    /// Radial coefficient of r⁶.
    pub k3: f32,
    /// Tangential coefficient p1.
    pub p1: f32,
    /// Tangential coefficient p2.
    pub p2: f32,
}

impl Distortion {
    /// Whether every coefficient is zero (no distortion).
    pub fn is_zero(&self) -> bool {
        [self.k1, self.k2, self.k3, self.p1, self.p2]
            .iter()
            .all(|c| *c == 0.0)
    }
}

/// A bokeh image (`aperture_image`): the aperture's transmission over the square circumscribing
/// the aperture's circle, as the luminance of the image's texels (stored values, no colour
/// transform, times alpha), rows top (lens +y) to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct ApertureImage {
    /// Where it came from, for messages: the key's value (a path or `texture N`).
    pub source: String,
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// `width × height` transmissions in `[0, 1]`, row-major, top row first.
    pub luminance: Vec<f32>,
    /// `content_hash` of the luminance and size: two cameras with the same image share its
    /// sampling tables.
    pub hash: u64,
}

impl ApertureImage {
    /// The image of `width × height` transmissions (row-major, top row first; clamped to
    /// `[0, 1]`, non-finite ones 0), with its hash; `None` when the sizes disagree.
    pub fn new(source: String, width: u32, height: u32, luminance: Vec<f32>) -> Option<Self> {
        if width == 0 || luminance.len() as u64 != u64::from(width) * u64::from(height) {
            return None;
        }
        let luminance: Vec<f32> = luminance
            .into_iter()
            .map(|l| {
                if l.is_finite() {
                    l.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect();
        let mut bytes = Vec::with_capacity(8 + 4 * luminance.len());
        bytes.extend(width.to_le_bytes());
        bytes.extend(height.to_le_bytes());
        luminance.iter().for_each(|l| bytes.extend(l.to_le_bytes()));
        Some(Self {
            source,
            width,
            height,
            hash: crate::hash::content_hash(&bytes),
            luminance,
        })
    }

    /// Whether every texel transmits the same (the plain aperture).
    pub fn is_constant(&self) -> bool {
        self.luminance.windows(2).all(|w| w[0] == w[1])
    }
}

/// Chromatic aberration (`chromatic_lateral`, `chromatic_longitudinal`): red's image and focus
/// against green's, blue's the opposite (`docs/lenses.md`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Chromatic {
    /// Red's image is `1 + lateral` times green's size, blue's `1 − lateral`.
    pub lateral: f32,
    /// Red's focus distance is `1 + longitudinal` times green's, blue's `1 − longitudinal`.
    pub longitudinal: f32,
}

impl Chromatic {
    /// Whether both are zero (no chromatic aberration).
    pub fn is_zero(&self) -> bool {
        self.lateral == 0.0 && self.longitudinal == 0.0
    }
}

/// The thin lens's options beyond blades, rotation and ratio (`docs/lenses.md`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LensOptions {
    /// `aperture_vignetting`, 0–1: how far the lens barrel clips the aperture at the image's
    /// corners, in lens radii (0 = none).
    pub vignetting: f32,
    /// `distortion_k1` … `distortion_p2`.
    pub distortion: Distortion,
    /// `aperture_image`, loaded; `None`: the plain aperture.
    pub aperture_image: Option<Arc<ApertureImage>>,
    /// `chromatic_lateral`, `chromatic_longitudinal`.
    pub chromatic: Chromatic,
}
