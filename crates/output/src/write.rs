//! The one way an image is rendered and written ([`write_image`]): a frame's films, taken as
//! the renderer yields them, turned into the file of SPEC §6 — EXR streamed band by band, or
//! PNG — denoised when a denoiser is given.

use crate::channels::{self, PixelResolver};
use crate::{
    denoised, film_bytes_per_pixel, film_to_image, header, late_values, needs_sample_count,
    placement, ExrOptions, OutputError, RenderSummary,
};
use aperture_denoise::Denoiser;
use aperture_imageio::{ExrLayout, Image, MetaValue, PngOptions};
use aperture_render::bands::{band_rows, bands};
use aperture_render::camera::Camera;
use aperture_render::film::{Film, Window};
use aperture_render::passes::PassSet;
use aperture_render::{Bands, Frame, RenderOptions};
use glam::Mat3;
use std::path::Path;
use std::time::Instant;

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

/// Renders `opts` from `frame` and writes it as `out` says: the one way a still image, each
/// frame of a sequence, a tile or a batch is written. EXR gets the beauty, the passes of
/// `opts.passes` (plus the sample count where [`channels::file_passes`] adds it) and the
/// header of [`header::metadata`], band by band; PNG the beauty after its view transform.
pub fn write_image(
    frame: &Frame,
    opts: &RenderOptions,
    out: &ImageOutput<'_>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    let t0 = Instant::now();
    let opts = frame.options(opts);
    let mut summary = match out.format {
        ImageFormat::Exr(exr) => write_exr(frame, &opts, out.path, &exr, out.denoiser, progress),
        ImageFormat::Png { png, transparent } => {
            let png_out = (out.path, &png, transparent);
            write_png(frame, &opts, png_out, out.denoiser, progress)
        }
    }?;
    let total = t0.elapsed().as_secs_f64();
    summary.write_secs = (total - summary.render_secs - summary.denoise_secs).max(0.0);
    Ok(summary)
}

/// The file [`write_exr`] writes: its channels (the `Noisy Image` ones last when denoising)
/// and header, late values to be filled in.
fn exr_layout(
    frame: &Frame,
    camera: &Camera,
    opts: &RenderOptions,
    window: Window,
    exr: &ExrOptions,
    denoiser: Option<&Denoiser>,
) -> ExrLayout {
    let scene = frame.scene();
    let whole = Window::whole(opts.width, opts.height);
    let mut layout = ExrLayout {
        width: window.width,
        height: window.height,
        placement: placement(window, whole),
        metadata: [
            header::metadata(scene, camera, opts, opts.passes),
            header::split_metadata(scene, opts, window, exr.tile),
        ]
        .concat(),
        channels: channels::channels(opts.passes, exr.half),
    };
    if exr.save_partial {
        let flag = header::late::INTERRUPTED.to_string();
        layout.metadata.push((flag, MetaValue::Int(0)));
    }
    if let Some(d) = denoiser {
        layout.channels.extend(denoised::noisy_channels(exr.half));
        let name = denoised::DENOISER.to_string();
        layout
            .metadata
            .push((name, MetaValue::Text(denoised::describe(d))));
        let flag = denoised::DENOISED.to_string();
        layout.metadata.push((flag, MetaValue::Int(0)));
        let secs = denoised::DENOISE_TIME.to_string();
        layout.metadata.push((secs, MetaValue::Float(0.0)));
    }
    layout
}

/// The EXR of [`write_image`]: the bands the renderer yields, each resolved and written before
/// the next is rendered (denoising holds the whole window instead, then writes it).
fn write_exr(
    frame: &Frame,
    opts: &RenderOptions,
    path: &Path,
    exr: &ExrOptions,
    denoiser: Option<&Denoiser>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    let with_aux = match denoiser {
        Some(_) => denoised::with_aux(opts.passes),
        None => opts.passes,
    };
    let camera = frame.camera(opts)?;
    let window = exr.region.unwrap_or(Window::whole(opts.width, opts.height));
    let passes = channels::file_passes(with_aux, needs_sample_count(opts, window));
    let opts = RenderOptions {
        passes,
        ..opts.clone()
    };
    let layout = exr_layout(frame, &camera, &opts, window, exr, denoiser);
    let specs = channels::channels(passes, exr.half);
    let bpp = film_bytes_per_pixel(passes, opts.adaptive.is_some(), layout.channels.len());
    let bands = bands(window, band_rows(window, exr.band_bytes, bpp));
    let world_from_camera = Mat3::from(camera.world_from_camera.matrix3);
    let world_origin = frame.scene().world_origin.as_vec3();
    let mut summary = RenderSummary::of(window);
    // Denoising needs the whole window: its rows wait here instead of going to the file.
    let mut held: Vec<f32> = Vec::new();
    aperture_imageio::write_exr_streamed::<OutputError>(path, &layout, |rows| {
        let mut films = Bands::new(frame, &camera, &opts, bands, progress);
        for film in &mut films {
            let film = film?;
            let resolver =
                PixelResolver::new(&film, passes, exr.half, world_from_camera, world_origin);
            let (values, clamped) = resolver.rows(specs.len());
            if denoiser.is_some() {
                held.extend_from_slice(&values);
            } else {
                rows.push_rows(&values)?;
            }
            summary.half_clamped += clamped;
        }
        let totals = films.totals();
        summary.samples = totals.samples;
        summary.dropped = totals.dropped;
        summary.render_secs = totals.render_secs;
        let cancelled = opts.cancel.is_cancelled();
        if cancelled && !exr.save_partial {
            return Err(OutputError::Interrupted {
                samples: summary.samples,
            });
        }
        let mut late = late_values(&summary, &opts);
        if exr.save_partial {
            let flag = header::late::INTERRUPTED.to_string();
            late.push((flag, MetaValue::Int(i32::from(cancelled))));
        }
        if let Some(d) = denoiser {
            let d = (!cancelled).then_some(d);
            let start = Instant::now();
            let values = denoised::denoise_rows(&held, &specs, window.width, window.height, d)?;
            let secs = start.elapsed().as_secs_f32();
            summary.denoise_secs = f64::from(secs);
            rows.push_rows(&values)?;
            let flag = denoised::DENOISED.to_string();
            late.push((flag, MetaValue::Int(i32::from(d.is_some()))));
            late.push((denoised::DENOISE_TIME.to_string(), MetaValue::Float(secs)));
        }
        Ok(late)
    })?;
    Ok(summary)
}

/// The PNG of [`write_image`] (beauty only): exposure and view transform from `png`; opaque
/// unless `transparent` (RGB is already the radiance over the environment, associated alpha,
/// so an opaque pixel is the same RGB with A = 1).
fn write_png(
    frame: &Frame,
    opts: &RenderOptions,
    (path, png, transparent): (&Path, &PngOptions, bool),
    denoiser: Option<&Denoiser>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    let passes = match denoiser {
        Some(_) => denoised::with_aux(PassSet::NONE),
        None => PassSet::NONE,
    };
    let opts = RenderOptions {
        passes,
        ..opts.clone()
    };
    let t0 = Instant::now();
    let film = frame.render(&opts, progress)?;
    if opts.cancel.is_cancelled() {
        return Err(OutputError::Interrupted {
            samples: film.total_samples(),
        });
    }
    let mut summary = RenderSummary::of(film.window());
    summary.render_secs = t0.elapsed().as_secs_f64();
    summary.samples = film.total_samples();
    summary.dropped = film.dropped_samples();
    let mut image = match denoiser {
        Some(d) => {
            let mut image = film_to_image(&film, frame.scene(), &opts, false, summary.render_secs)?;
            let t1 = Instant::now();
            denoised::denoise_image(&mut image, d)?;
            summary.denoise_secs = t1.elapsed().as_secs_f64();
            image
        }
        None => plain_image(&film),
    };
    if !transparent {
        for p in &mut image.rgba {
            p[3] = 1.0;
        }
    }
    aperture_imageio::write_png(path, &image, png)?;
    Ok(summary)
}

/// The beauty of a film as a plain image.
fn plain_image(film: &Film) -> Image {
    let mut image = Image::new(film.width(), film.height());
    image.rgba = film.to_rgba();
    image
}
