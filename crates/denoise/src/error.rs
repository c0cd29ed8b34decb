//! Why denoising could not run.

use std::path::PathBuf;

/// How to get the library, said by every "not found" error.
pub const HOW_TO_GET: &str = concat!(
    "run tools/oidn/install.sh (or `pip install pyoidn`), or point --oidn / APERTURE_OIDN at ",
    crate::platform::library_name!(),
    " (Blender ships one beside its executable)"
);

/// Why the denoiser could not be loaded or run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DenoiseError {
    /// No OIDN 2.x library in any place of the search order.
    #[error("denoising needs Intel Open Image Denoise 2.x, not found ({tried}): {HOW_TO_GET}")]
    NotFound {
        /// The places tried, and why each failed, in one line.
        tried: String,
    },
    /// The library given explicitly (`--oidn`, `APERTURE_OIDN`) could not be used.
    #[error("cannot use {path} (from {origin}) as Open Image Denoise 2.x: {reason}; {HOW_TO_GET}")]
    Load {
        /// The path given.
        path: PathBuf,
        /// `--oidn` or `APERTURE_OIDN`.
        origin: crate::locate::Origin,
        /// `dlopen`'s message, a missing symbol or a version that is not 2.x.
        reason: String,
    },
    /// Images of different sizes, or a size that does not match the pixels given.
    #[error("denoising {what}: {len} pixels given for a {width}x{height} image")]
    Size {
        /// Which image.
        what: &'static str,
        /// Pixels given.
        len: usize,
        /// Width asked for.
        width: usize,
        /// Height asked for.
        height: usize,
    },
    /// OIDN reported an error while filtering.
    #[error("Open Image Denoise failed while filtering the {stage}: {message}")]
    Filter {
        /// `albedo`, `normal` or `beauty`.
        stage: &'static str,
        /// OIDN's message.
        message: String,
    },
}

#[cfg(test)]
mod tests {
    use super::HOW_TO_GET;

    #[test]
    fn the_hint_names_this_platforms_library() {
        assert!(
            HOW_TO_GET.contains(crate::platform::LIBRARY),
            "{HOW_TO_GET}"
        );
    }
}
