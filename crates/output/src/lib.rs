//! A render written out: the film turned into the plain multi-channel image of SPEC §6 and
//! handed to `aperture_imageio`, as pbrt's film writes its own image.
//!
//! ```
//! use aperture_output::write::{write_image, ImageFormat, ImageOutput};
//! use aperture_output::ExrOptions;
//! use aperture_render::{Frame, RenderOptions};
//! use aperture_shading::test_scenes;
//! let frame = Frame::still(test_scenes::lit_plane(1.0), Default::default());
//! let opts = RenderOptions { width: 8, height: 8, spp: 2, ..Default::default() };
//! let path = std::env::temp_dir().join(format!("aperture-doc-{}.exr", std::process::id()));
//! let out = ImageOutput { path: &path, format: ImageFormat::Exr(ExrOptions::default()), denoiser: None };
//! let summary = write_image(&frame, &opts, &out, &|_, _| {})?;
//! assert_eq!(summary.samples, 8 * 8 * 2);
//! assert!(aperture_imageio::read_exr(&path).is_ok());
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), aperture_output::OutputError>(())
//! ```
//!
//! EXR output is streamed: the image is rendered in bands of whole rows, each band resolved
//! and written before the next is rendered, so memory holds one band's sums, not the whole
//! image's (a 4K render with every pass would otherwise need several GB). Bands do not change
//! a pixel: every sample is a pure function of (pixel, index, dimension, seed), and adaptive
//! sampling renders the apron its decisions reach. This crate drives the writing: it takes
//! each band the renderer yields ([`aperture_render::Bands`]) and writes it; the renderer
//! knows nothing of files and never calls back here.

pub mod channels;
pub mod denoised;
mod error;
mod exr_options;
mod film_image;
mod footprint;
pub mod header;
pub mod merge;
mod plan;
mod region;
mod rows;
pub mod sequence;
mod summary;
pub mod write;

pub use error::OutputError;
pub use exr_options::{ExrOptions, BAND_BYTES};
pub use film_image::film_to_image;
pub use footprint::{
    check_output, film_bytes_per_pixel, footprint, Footprint, FootprintError, OutputKind,
};
pub use summary::RenderSummary;

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_render::bands::{band_rows, bands};
    use aperture_render::film::Window;
    use aperture_render::passes::PassSet;
    use aperture_render::TILE;

    #[test]
    fn the_default_budget_renders_common_sizes_in_one_band() {
        // The budget is bytes: it was once divided by the width twice, which cut a 320x240
        // beauty render into four bands and a 1920x1080 one into 34, each rebuilding the
        // integrator and waiting for its last tile.
        let beauty = film_bytes_per_pixel(PassSet::NONE, false, 4);
        let compositing = film_bytes_per_pixel(PassSet::compositing(), false, 40);
        for (width, height, bpp) in [
            (320, 240, beauty),
            (1920, 1080, beauty),
            (320, 240, compositing),
            (640, 480, compositing),
        ] {
            let w = Window::whole(width, height);
            assert_eq!(
                bands(w, band_rows(w, BAND_BYTES, bpp)).len(),
                1,
                "{width}x{height}"
            );
        }
        // Past the budget, bands hold whole tile rows within it.
        let w = Window::whole(8192, 8192);
        let rows = band_rows(w, BAND_BYTES, compositing);
        assert!(rows % TILE == 0 && rows < w.height);
        assert!(rows as usize * w.width as usize * compositing <= BAND_BYTES);
    }

    #[test]
    fn bytes_per_pixel_grow_with_passes() {
        let beauty = film_bytes_per_pixel(PassSet::NONE, false, 4);
        let default = film_bytes_per_pixel(PassSet::compositing(), false, 40);
        let all = film_bytes_per_pixel(PassSet::all(), true, 80);
        assert!(
            beauty < default && default < all,
            "{beauty} {default} {all}"
        );
    }
}
