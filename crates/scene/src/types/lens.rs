//! The thin lens's imperfections (issue 61): optical vignetting and Brown–Conrady distortion.
//! All zero is the ideal thin lens, bit for bit.

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

/// The thin lens's options beyond blades, rotation and ratio (`docs/lenses.md`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LensOptions {
    /// `aperture_vignetting`, 0–1: how far the lens barrel clips the aperture at the image's
    /// corners, in lens radii (0 = none).
    pub vignetting: f32,
    /// `distortion_k1` … `distortion_p2`.
    pub distortion: Distortion,
}
