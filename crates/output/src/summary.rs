//! What a written render took.

use aperture_render::film::Window;

/// What a written render took.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSummary {
    /// The pixels rendered.
    pub window: Window,
    /// Samples taken, dropped ones included.
    pub samples: u64,
    /// Samples dropped as NaN or infinite.
    pub dropped: u64,
    /// Seconds spent rendering (not writing).
    pub render_secs: f64,
    /// Seconds spent denoising.
    pub denoise_secs: f64,
    /// Seconds spent resolving and writing the file (the rest of the job).
    pub write_secs: f64,
    /// Colour values clamped to the half-float range (`--half`).
    pub half_clamped: u64,
}

impl RenderSummary {
    /// Nothing done yet for `window`.
    pub fn of(window: Window) -> Self {
        Self {
            window,
            samples: 0,
            dropped: 0,
            render_secs: 0.0,
            denoise_secs: 0.0,
            write_secs: 0.0,
            half_clamped: 0,
        }
    }

    /// Mean samples per pixel.
    pub fn mean_spp(&self) -> f64 {
        self.samples as f64 / self.window.pixels().max(1) as f64
    }
}
