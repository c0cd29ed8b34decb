//! The one way an image is rendered and written ([`write_image`]): a frame's films, taken as
//! the renderer yields them, turned into the file of SPEC §6 — EXR streamed band by band, or
//! PNG — denoised when a denoiser is given.

use crate::error::OutputError;
use crate::plan::FilePlan;
pub use crate::plan::{ImageFormat, ImageOutput};
use crate::rows::render_rows;
use crate::summary::RenderSummary;
#[cfg(doc)]
use crate::{channels, header};
use aperture_imageio::Image;
use aperture_render::{Frame, RenderOptions};
use std::time::Instant;

/// Renders `opts` from `frame` and writes it as `out` says: the one way a still image, each
/// frame of a sequence, a tile or a batch is written. EXR gets the beauty, the passes of
/// `opts.passes` (plus the sample count where [`channels::file_passes`] adds it) and the
/// header of [`header::metadata`], band by band; PNG the beauty after its view transform.
/// The file is planned first ([`FilePlan`]), then rendered ([`render_rows`]).
pub fn write_image(
    frame: &Frame,
    opts: &RenderOptions,
    out: &ImageOutput<'_>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    let t0 = Instant::now();
    let opts = frame.options(opts);
    let camera = frame.camera(&opts)?;
    let plan = FilePlan::new(frame.scene(), &camera, &opts, out);
    let mut summary = match out.format {
        ImageFormat::Exr(_) => {
            let mut summary = RenderSummary::of(plan.window);
            aperture_imageio::write_exr_streamed::<OutputError>(out.path, &plan.layout, |file| {
                let mut sink = |v: &[f32]| Ok(file.push_rows(v)?);
                let (done, late) = render_rows(frame, &camera, &plan, progress, &mut sink)?;
                summary = done;
                Ok(late)
            })?;
            summary
        }
        ImageFormat::Png { png, transparent } => {
            let mut values = Vec::new();
            let mut sink = |v: &[f32]| {
                values.extend_from_slice(v);
                Ok(())
            };
            let (summary, _) = render_rows(frame, &camera, &plan, progress, &mut sink)?;
            // The beauty: the first four values of each pixel (denoised, when it was).
            let stride = plan.layout.channels.len();
            let mut image = Image::new(plan.window.width, plan.window.height);
            for (px, v) in image.rgba.iter_mut().zip(values.chunks_exact(stride)) {
                px.copy_from_slice(&v[..4]);
                // Opaque: RGB is already the radiance over the environment (associated alpha).
                px[3] = if transparent { v[3] } else { 1.0 };
            }
            aperture_imageio::write_png(out.path, &image, &png)?;
            summary
        }
    };
    let total = t0.elapsed().as_secs_f64();
    summary.write_secs = (total - summary.render_secs - summary.denoise_secs).max(0.0);
    Ok(summary)
}
