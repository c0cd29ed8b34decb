//! `r = scene.start(**options)`: a progressive render (SPEC §9) whose film is read between
//! steps: an `aperture_render::Progressive`, each step rendered from the session's frame
//! (refused once the scene was edited since the start), so a render that reaches N samples
//! equals the one-shot N-sample render bit for bit. Started with `denoise=True`, its images
//! are denoised (the viewport's denoising): the film of N samples then equals
//! `scene.render(spp=N, denoise=True)` with the same settings.

use crate::errors::{load_error, output_error, render_error, value_error, RenderError};
use crate::images::RenderResult;
use crate::interrupt::{run, with_threads};
use crate::render::denoiser;
use crate::render_opts::{plan, RenderAsk};
use crate::state::{lock, Shared, State};
use aperture_denoise::Denoiser;
use aperture_render::Frame;
use aperture_render::{Cancel, FrameSpec, Progressive, Window};
use pyo3::prelude::*;
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

/// What the render has reached.
struct Inner {
    spec: FrameSpec,
    render: Progressive,
    /// The session's edits when the render started: an edit since makes it refuse to go on.
    edits: usize,
    secs: f64,
}

/// A progressive render: `step(n)` adds samples, `image()` reads the film, `cancel()` stops
/// it (also from another thread, during a step).
#[pyclass(module = "aperture", frozen)]
pub struct Render {
    state: Shared,
    cancel: Cancel,
    threads: Option<usize>,
    /// Open Image Denoise, loaded at the start when the render was started with `denoise=True`.
    denoiser: Option<Denoiser>,
    inner: Mutex<Inner>,
}

impl Render {
    /// A render of `ask` from `state`'s session, no samples taken yet.
    pub(crate) fn start(py: Python<'_>, state: &Shared, ask: RenderAsk) -> PyResult<Self> {
        let denoiser = denoiser(ask.denoise.as_ref())?;
        let cancel = Cancel::new();
        let inner = run(py, &cancel, || {
            let mut guard = lock(state);
            let st = &mut *guard;
            let plan = plan(&mut st.session, &ask, cancel.clone())?;
            st.last_spec = Some(plan.spec.clone());
            let edits = st.session.edits().len();
            let frame = st.session.frame(&plan.spec).map_err(load_error)?;
            let opts = frame.options(&plan.opts);
            let whole = Window::whole(opts.width, opts.height);
            let render = Progressive::new(frame, &opts, whole).map_err(render_error)?;
            Ok(Inner {
                spec: plan.spec,
                render,
                edits,
                secs: 0.0,
            })
        })?;
        Ok(Self {
            state: state.clone(),
            cancel,
            threads: ask.threads,
            denoiser,
            inner: Mutex::new(inner),
        })
    }

    fn inner(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The session's frame for `inner`, refused when the scene was edited since the start.
fn frame_of<'s>(st: &'s mut State, inner: &Inner) -> PyResult<&'s Frame> {
    if st.session.edits().len() != inner.edits {
        return Err(RenderError::new_err(
            "the scene was edited since this render started: start a new one",
        ));
    }
    st.last_spec = Some(inner.spec.clone());
    st.session.frame(&inner.spec).map_err(load_error)
}

#[pymethods]
impl Render {
    /// Renders the next `samples` samples of every pixel (at most the ones left; `None`: the
    /// next pass of the doubling schedule 1, 1, 2, 4, …) and returns the samples each pixel
    /// has now. Adaptive renders take all their samples in the first step.
    #[pyo3(signature = (samples=None))]
    fn step(&self, py: Python<'_>, samples: Option<i64>) -> PyResult<u32> {
        if let Some(n) = samples.filter(|&n| n < 1) {
            return Err(value_error(format!("invalid samples = {n}: must be ≥ 1")));
        }
        run(py, &self.cancel, || {
            let mut guard = lock(&self.state);
            let mut inner = self.inner();
            let inner = &mut *inner;
            if inner.render.is_done() {
                return Ok(inner.render.samples());
            }
            let frame = frame_of(&mut guard, inner)?;
            let t0 = Instant::now();
            let render = &mut inner.render;
            let total = with_threads(self.threads, || match samples {
                // The doubling schedule 1, 1, 2, 4, …
                None => render.next_pass(frame, &|_, _| {}).map(|n| n.unwrap_or(0)),
                Some(n) => render.step(frame, n.min(i64::from(u32::MAX)) as u32, &|_, _| {}),
            })?
            .map_err(render_error)?;
            inner.secs += t0.elapsed().as_secs_f64();
            Ok(total.max(inner.render.samples()))
        })
    }

    /// The film so far as a render result (`image, passes = r.image()`): each pixel the mean
    /// of the samples it has, denoised when the render was started with `denoise=True`
    /// (`denoise=False`: the noisy film, e.g. before the viewport's first denoised sample).
    #[pyo3(signature = (denoise=None))]
    fn image(&self, py: Python<'_>, denoise: Option<bool>) -> PyResult<RenderResult> {
        let denoiser = match (denoise, &self.denoiser) {
            (Some(true), None) => {
                return Err(value_error(
                    "image(denoise=True) needs a render started with denoise=True",
                ))
            }
            (Some(false), _) => None,
            (_, d) => d.as_ref(),
        };
        let (image, samples) = py.detach(|| -> PyResult<_> {
            let (mut image, samples) = {
                let mut guard = lock(&self.state);
                let inner = self.inner();
                let frame = frame_of(&mut guard, &inner)?;
                let image = aperture_output::film_to_image(
                    inner.render.film(),
                    frame.scene(),
                    inner.render.options(),
                    false,
                    inner.secs,
                )
                .map_err(output_error)?;
                (image, inner.render.film().total_samples())
            };
            // After the locks: the session's edits need not wait for the denoiser.
            if let Some(d) = denoiser {
                aperture_output::denoised::denoise_image(&mut image, d)
                    .map_err(|e| RenderError::new_err(e.to_string()))?;
            }
            Ok((image, samples))
        })?;
        RenderResult::new(py, image, samples)
    }

    /// Stops the render: a step under way returns within a batch of samples, and no step
    /// renders after it.
    fn cancel(&self) {
        self.cancel.cancel();
    }

    /// Samples every pixel has so far.
    #[getter]
    fn samples(&self, py: Python<'_>) -> u32 {
        py.detach(|| self.inner().render.samples())
    }

    /// The samples asked for (`spp`).
    #[getter]
    fn target(&self, py: Python<'_>) -> u32 {
        py.detach(|| self.inner().render.target())
    }

    /// True once every sample is taken, or the render was cancelled.
    #[getter]
    fn done(&self, py: Python<'_>) -> bool {
        py.detach(|| self.inner().render.is_done()) || self.cancel.is_cancelled()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        py.detach(|| {
            let r = &self.inner().render;
            let o = r.options();
            let (done, spp) = (r.samples(), r.target());
            format!(
                "<aperture.Render {}x{} {done}/{spp} spp>",
                o.width, o.height
            )
        })
    }
}
