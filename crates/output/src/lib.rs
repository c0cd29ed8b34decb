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
mod exr_options;
mod footprint;
pub mod header;
pub mod merge;
mod plan;
mod rows;
pub mod sequence;
pub mod write;

pub use exr_options::{ExrOptions, BAND_BYTES};
pub use footprint::{
    check_output, film_bytes_per_pixel, footprint, Footprint, FootprintError, OutputKind,
};

use aperture_imageio::{Image, Layer};
use aperture_render::film::{Film, Window};
use aperture_render::resolve::Resolver;
use aperture_render::{scene_camera, RenderError, RenderOptions};
use aperture_scene::Scene;
use glam::Mat3;

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
    Denoise(#[from] denoised::DenoisingError),
    /// The render was cancelled ([`RenderOptions::cancel`]) and nothing was written
    /// ([`ExrOptions::save_partial`] writes what was rendered instead).
    #[error("interrupted after {samples} samples: nothing written")]
    Interrupted {
        /// Samples taken before the render stopped.
        samples: u64,
    },
}

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

/// A rendered film as a plain image with the channels and header of
/// [`write::write_image`]'s EXR
/// (`render_secs` into the header's render time): the same file, for a film already in
/// memory.
pub fn film_to_image(
    film: &Film,
    scene: &Scene,
    opts: &RenderOptions,
    half: bool,
    render_secs: f64,
) -> Result<Image, OutputError> {
    let camera = scene_camera(scene, opts)?;
    let window = film.window();
    let passes = channels::file_passes(film.passes(), plan::needs_sample_count(opts, window));
    let specs = channels::channels(passes, half);
    let world_from_camera = Mat3::from(camera.world_from_camera.matrix3);
    let resolver = Resolver::new(
        film,
        passes,
        world_from_camera,
        scene.world_origin.as_vec3(),
    );
    let mut values = resolver.rows();
    let half_clamped = channels::clamp_half(&mut values, &specs);
    let n = window.pixels();
    let mut image = Image::new(film.width(), film.height());
    image.beauty_type = specs[0].sample_type;
    image.placement = plan::placement(window, opts);
    let stride = specs.len();
    for (p, px) in image.rgba.iter_mut().enumerate() {
        px.copy_from_slice(&values[p * stride..p * stride + 4]);
    }
    // Channels `Layer.c` of one layer are adjacent: group them.
    let mut c = 4;
    while c < stride {
        let (layer, _) = specs[c].name.rsplit_once('.').expect("dotted pass channel");
        let count = specs[c..]
            .iter()
            .take_while(|s| s.name.rsplit_once('.').map(|x| x.0) == Some(layer))
            .count();
        let names: Vec<&str> = specs[c..c + count]
            .iter()
            .map(|s| s.name.rsplit_once('.').expect("dotted").1)
            .collect();
        let data = (0..n)
            .flat_map(|p| {
                values[p * stride + c..p * stride + c + count]
                    .iter()
                    .copied()
            })
            .collect();
        let mut l = Layer::new(layer, &names, data);
        l.sample_type = specs[c].sample_type;
        image.layers.push(l);
        c += count;
    }
    image.metadata = header::metadata(scene, &camera, opts, passes);
    let whole = plan::is_whole(window, opts);
    image
        .metadata
        .extend(header::split_metadata(scene, opts, (window, whole), None));
    let summary = RenderSummary {
        samples: film.total_samples(),
        dropped: film.dropped_samples(),
        render_secs,
        half_clamped,
        ..RenderSummary::of(film.window())
    };
    for (key, value) in header::late_values(&summary, opts, None) {
        if let Some(slot) = image.metadata.iter_mut().find(|(k, _)| *k == key) {
            slot.1 = value;
        }
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_render::bands::{band_rows, bands};
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
