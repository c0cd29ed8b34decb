//! Why a render could not be written.

use crate::denoised::DenoisingError;
use aperture_render::RenderError;

/// Why a render could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The render could not start.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The image could not be written.
    #[error(transparent)]
    Image(#[from] aperture_imageio::Error),
    /// The image could not be denoised.
    #[error(transparent)]
    Denoise(#[from] DenoisingError),
    /// The render was cancelled ([`aperture_render::RenderOptions::cancel`]) and nothing was written
    /// ([`crate::ExrOptions::save_partial`] writes what was rendered instead).
    #[error("interrupted after {samples} samples: nothing written")]
    Interrupted {
        /// Samples taken before the render stopped.
        samples: u64,
    },
}
