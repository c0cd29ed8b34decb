//! What a file will hold, known before a pixel is rendered: the passes rendered for it, the
//! window, its channels and, for EXR, its header. Planned from plain data only; rendering is
//! [`crate::rows`]'s.

use crate::exr_options::{ExrOptions, BAND_BYTES};
use crate::footprint::film_bytes_per_pixel;
use crate::region::{is_whole, needs_sample_count, placement};
use crate::{channels, denoised, header};
use aperture_denoise::Denoiser;
use aperture_imageio::{ChannelSpec, ExrLayout, MetaValue, PngOptions};
use aperture_render::camera::Camera;
use aperture_render::film::Window;
use aperture_render::{PassSet, RenderOptions};
use aperture_scene::Scene;
use std::path::Path;

/// The file format of an image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImageFormat {
    /// EXR with the passes of the render options.
    Exr(ExrOptions),
    /// PNG with its view transform, opaque unless `transparent`.
    Png {
        /// Exposure and view.
        png: PngOptions,
        /// Keep coverage as alpha.
        transparent: bool,
    },
}

/// Where and how an image is written.
#[derive(Clone, Copy)]
pub struct ImageOutput<'a> {
    /// The file.
    pub path: &'a Path,
    /// Its format.
    pub format: ImageFormat,
    /// Denoise the beauty ([`denoised`]): the Denoising passes are rendered for it, and an EXR
    /// keeps the noisy beauty as `Noisy Image`.
    pub denoiser: Option<&'a Denoiser>,
}

/// A file to render and write.
pub(crate) struct FilePlan<'a> {
    /// The render options, with the passes the file needs.
    pub opts: RenderOptions,
    /// The pixels rendered.
    pub window: Window,
    /// The channels rendered, in the order of the renderer's values.
    pub specs: Vec<ChannelSpec>,
    /// The file's channels (with the noisy beauty when denoising) and, for EXR, its header.
    pub layout: ExrLayout,
    /// Bytes a pixel takes while rendered, and the budget of a band.
    pub bytes_per_pixel: usize,
    pub band_bytes: usize,
    /// Denoise the beauty.
    pub denoiser: Option<&'a Denoiser>,
    /// Write what was rendered when the render is cancelled.
    pub save_partial: bool,
}

impl<'a> FilePlan<'a> {
    /// The plan of `out` for a render of `scene` through `camera` with `opts`.
    pub fn new(
        scene: &Scene,
        camera: &Camera,
        opts: &RenderOptions,
        out: &ImageOutput<'a>,
    ) -> Self {
        let (asked, exr) = match out.format {
            ImageFormat::Exr(exr) => (opts.passes, Some(exr)),
            ImageFormat::Png { .. } => (PassSet::NONE, None),
        };
        let denoise = denoised::plan(out.denoiser, asked, exr.is_some_and(|e| e.half));
        let window = exr.and_then(|e| e.region).unwrap_or(Window {
            x0: 0,
            y0: 0,
            width: opts.width,
            height: opts.height,
        });
        let whole = is_whole(window, opts);
        let passes = match exr {
            Some(_) => channels::file_passes(denoise.passes, needs_sample_count(opts, window)),
            None => denoise.passes,
        };
        let opts = RenderOptions {
            passes,
            ..opts.clone()
        };
        let half = exr.is_some_and(|e| e.half);
        let specs = channels::channels(passes, half);
        let bytes_per_pixel = film_bytes_per_pixel(passes, opts.adaptive.is_some(), specs.len());
        let metadata = exr.map_or(Vec::new(), |exr| {
            let mut metadata = header::metadata(scene, camera, &opts, passes);
            metadata.extend(header::split_metadata(
                scene,
                &opts,
                (window, whole),
                exr.tile,
            ));
            if exr.save_partial {
                metadata.push((header::late::INTERRUPTED.to_string(), MetaValue::Int(0)));
            }
            metadata.extend(denoise.metadata);
            metadata
        });
        let layout = ExrLayout {
            width: window.width,
            height: window.height,
            placement: placement(window, &opts),
            metadata,
            channels: [specs.clone(), denoise.channels].concat(),
        };
        Self {
            opts,
            window,
            specs,
            layout,
            bytes_per_pixel,
            band_bytes: exr.map_or(BAND_BYTES, |e: ExrOptions| e.band_bytes),
            denoiser: out.denoiser,
            save_partial: exr.is_some_and(|e| e.save_partial),
        }
    }
}
