//! A real lens's prescription (issue 61, `lens_prescription`): its surfaces front to back, as
//! pbrt-v4's lens files list them. The render crate traces rays through them.

/// One surface of a prescription, in millimetres, as one row of pbrt-v4's lens file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensSurface {
    /// Radius of curvature (positive: the centre lies behind the surface, towards the film);
    /// 0 for the aperture stop, a flat disc.
    pub radius: f32,
    /// Distance along the axis to the next surface (for the last one, to the film).
    pub thickness: f32,
    /// Index of refraction of the medium behind the surface (0 or 1: air).
    pub ior: f32,
    /// Clear aperture diameter (for the stop, its widest opening).
    pub aperture: f32,
}

impl LensSurface {
    /// Whether this is the aperture stop.
    pub fn is_stop(&self) -> bool {
        self.radius == 0.0
    }
}

/// A lens prescription and the f-number asked of it.
#[derive(Debug, Clone, PartialEq)]
pub struct LensPrescription {
    /// Where it came from, for messages: the file's path as written, or `inline`.
    pub source: String,
    /// The surfaces, front (scene side) to back (film side); exactly one is the stop.
    pub surfaces: Vec<LensSurface>,
    /// `aperture_fstop` of the source that decided the aperture, if any: the stop is closed
    /// down to give it (never opened past its row's diameter).
    pub fstop: Option<f32>,
}

impl LensPrescription {
    /// The index of the aperture stop.
    pub fn stop(&self) -> Option<usize> {
        self.surfaces.iter().position(LensSurface::is_stop)
    }
}
