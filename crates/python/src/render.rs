//! `scene.render(**options)`: one render of the session's frame, without the GIL and
//! cancelled by Ctrl-C, turned into the image the EXR would hold.

use crate::errors::{load_error, output_error, render_error, RenderError};
use crate::images::RenderResult;
use crate::interrupt::{run, run_inline, with_threads};
use crate::render_opts::{plan, DenoiseAsk, RenderAsk};
use crate::state::{lock, Shared};
use aperture_denoise::Denoiser;
use aperture_imageio::Image;
use aperture_render::Cancel;
use pyo3::prelude::*;
use std::time::Instant;

/// Open Image Denoise with `ask`'s settings, loaded before anything is rendered (as the
/// command line does); `None` without denoising.
pub(crate) fn denoiser(ask: Option<&DenoiseAsk>) -> PyResult<Option<Denoiser>> {
    match ask {
        None => Ok(None),
        Some(a) => Denoiser::load(a.library.as_deref())
            .map(|d| Some(d.with_settings(a.settings)))
            .map_err(|e| RenderError::new_err(e.to_string())),
    }
}

/// Renders of at most this many samples run on the calling thread, without the thread that
/// watches for Ctrl-C (starting it, and waking the caller when the render is done, cost
/// 0.3–1 ms on the 2-core test host: a third of a 64×64 1-spp render's overhead); they take
/// milliseconds on the demo, and Python raises the `KeyboardInterrupt` once they return.
const INLINE_SAMPLES: u64 = 128 * 128;

/// Whether `ask` is small enough for [`INLINE_SAMPLES`] (an unknown size is not).
fn small(ask: &RenderAsk) -> bool {
    let Some(w) = ask.width else { return false };
    let h = ask.height.unwrap_or(w);
    let samples = u64::from(w) * u64::from(h) * u64::from(ask.base.spp);
    ask.denoise.is_none() && samples <= INLINE_SAMPLES
}

/// Renders `ask` from `state`'s session into the image of the EXR (denoised when asked).
pub(crate) fn render(py: Python<'_>, state: &Shared, ask: RenderAsk) -> PyResult<RenderResult> {
    let denoiser = denoiser(ask.denoise.as_ref())?;
    let cancel = Cancel::new();
    let inline = small(&ask);
    let work = || -> PyResult<(Image, u64)> {
        let mut guard = lock(state);
        let st = &mut *guard;
        let plan = plan(&mut st.session, &ask, cancel.clone())?;
        st.last_spec = Some(plan.spec.clone());
        let frame = st.session.frame(&plan.spec).map_err(load_error)?;
        let opts = frame.options(&plan.opts);
        let t0 = Instant::now();
        let film =
            with_threads(ask.threads, || frame.render(&opts, &|_, _| {}))?.map_err(render_error)?;
        let secs = t0.elapsed().as_secs_f64();
        let mut image = aperture_output::film_to_image(&film, frame.scene(), &opts, false, secs)
            .map_err(output_error)?;
        if let Some(d) = &denoiser {
            aperture_output::denoised::denoise_image(&mut image, d)
                .map_err(|e| RenderError::new_err(e.to_string()))?;
        }
        Ok((image, film.total_samples()))
    };
    let (image, samples) = match inline {
        true => run_inline(py, work)?,
        false => run(py, &cancel, work)?,
    };
    RenderResult::new(py, image, samples)
}
