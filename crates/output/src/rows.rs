//! The one place the writer asks the renderer for pixels: a frame's window rendered band by
//! band ([`aperture_render::Bands`], each band's pass values resolved by the renderer), the
//! values stored as the file's channels say and handed on, denoised when asked.

use crate::error::OutputError;
use crate::plan::FilePlan;
use crate::summary::RenderSummary;
use crate::{channels, denoised, header};
use aperture_imageio::MetaValue;
use aperture_render::bands::{band_rows, bands};
use aperture_render::camera::Camera;
use aperture_render::{Bands, Frame};
use std::time::Instant;

/// Rows of pixel values as the file takes them.
pub(crate) type Sink<'s> = dyn FnMut(&[f32]) -> Result<(), OutputError> + 's;

/// Renders `plan` from `frame` through `camera` and hands its rows to `sink`, top to bottom
/// (all at once after denoising, which needs the whole window); returns what it took and the
/// header values known only now.
pub(crate) fn render_rows(
    frame: &Frame,
    camera: &Camera,
    plan: &FilePlan<'_>,
    progress: &(dyn Fn(usize, usize) + Sync),
    sink: &mut Sink<'_>,
) -> Result<(RenderSummary, Vec<(String, MetaValue)>), OutputError> {
    let mut summary = RenderSummary::of(plan.window);
    let rows = band_rows(plan.window, plan.band_bytes, plan.bytes_per_pixel);
    let films = Bands::new(
        frame,
        camera,
        &plan.opts,
        bands(plan.window, rows),
        progress,
    );
    // Denoising needs the whole window: its rows wait here instead of going to the file.
    let mut held: Vec<f32> = Vec::new();
    for band in films {
        let mut band = band?;
        summary.half_clamped += channels::clamp_half(&mut band.values, &plan.specs);
        summary.samples = band.totals.samples;
        summary.dropped = band.totals.dropped;
        summary.render_secs = band.totals.render_secs;
        match plan.denoiser {
            Some(_) => held.extend_from_slice(&band.values),
            None => sink(&band.values)?,
        }
    }
    let cancelled = plan.opts.cancel.is_cancelled();
    if cancelled && !plan.save_partial {
        return Err(OutputError::Interrupted {
            samples: summary.samples,
        });
    }
    let interrupted = plan.save_partial.then_some(cancelled);
    let mut late = header::late_values(&summary, &plan.opts, interrupted);
    if let Some(d) = plan.denoiser {
        let d = (!cancelled).then_some(d);
        let start = Instant::now();
        let (w, h) = (plan.window.width, plan.window.height);
        let values = denoised::denoise_rows(&held, &plan.specs, w, h, d)?;
        let secs = start.elapsed().as_secs_f32();
        summary.denoise_secs = f64::from(secs);
        sink(&values)?;
        late.push((
            denoised::DENOISED.to_string(),
            MetaValue::Int(i32::from(d.is_some())),
        ));
        late.push((denoised::DENOISE_TIME.to_string(), MetaValue::Float(secs)));
    }
    Ok((summary, late))
}
