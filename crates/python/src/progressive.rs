//! `r = scene.start(**options)`: a progressive render (SPEC §9) whose film is read between
//! steps. Each step renders the next samples of every pixel's sequence onto the film where
//! the last left off (as `aperture_render::Progressive`, which borrows its frame and so cannot
//! live in a Python object: the frame is taken from the session at each step instead), so a
//! render that reaches N samples equals the one-shot N-sample render bit for bit.

use crate::errors::{load_error, output_error, render_error, value_error, RenderError};
use crate::images::RenderResult;
use crate::interrupt::{run, with_threads};
use crate::render_opts::{plan, RenderAsk};
use crate::state::{lock, Shared, State};
use aperture_render::camera::Camera;
use aperture_render::Frame;
use aperture_render::{Cancel, Film, FrameSpec, RenderOptions, Window};
use pyo3::prelude::*;
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

/// What the render has reached.
struct Inner {
    spec: FrameSpec,
    opts: RenderOptions,
    camera: Camera,
    film: Film,
    /// Samples every pixel has been given so far.
    done: u32,
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
    inner: Mutex<Inner>,
}

impl Render {
    /// A render of `ask` from `state`'s session, no samples taken yet.
    pub(crate) fn start(py: Python<'_>, state: &Shared, ask: RenderAsk) -> PyResult<Self> {
        if ask.denoise {
            return Err(value_error(
                "a progressive render is not denoised: denoise its final image with scene.render(denoise=True)",
            ));
        }
        let cancel = Cancel::new();
        let inner = run(py, &cancel, || {
            let mut guard = lock(state);
            let st = &mut *guard;
            let plan = plan(&mut st.session, &ask, cancel.clone())?;
            st.last_spec = Some(plan.spec.clone());
            let edits = st.session.edits().len();
            let frame = st.session.frame(&plan.spec).map_err(load_error)?;
            let opts = frame.options(&plan.opts);
            let camera = frame.camera(&opts).map_err(render_error)?;
            let whole = Window::whole(opts.width, opts.height);
            Ok(Inner {
                spec: plan.spec,
                film: Film::for_window(whole, opts.width, opts.height, opts.passes),
                opts,
                camera,
                done: 0,
                edits,
                secs: 0.0,
            })
        })?;
        Ok(Self {
            state: state.clone(),
            cancel,
            threads: ask.threads,
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
            let left = inner.opts.spp - inner.done;
            let asked = samples.map_or(inner.done.max(1), |n| n.min(i64::from(u32::MAX)) as u32);
            let n = match inner.opts.adaptive {
                Some(_) => left,
                None => asked.min(left),
            };
            if n == 0 || self.cancel.is_cancelled() {
                return Ok(inner.done);
            }
            let frame = frame_of(&mut guard, inner)?;
            let pass = RenderOptions {
                sample_offset: inner.opts.sample_offset + inner.done,
                spp: n,
                ..inner.opts.clone()
            };
            let t0 = Instant::now();
            let film = &mut inner.film;
            with_threads(self.threads, || {
                frame.render_onto(&inner.camera, &pass, film, &|_, _| {})
            })?
            .map_err(render_error)?;
            inner.secs += t0.elapsed().as_secs_f64();
            if !self.cancel.is_cancelled() {
                inner.done += n;
            }
            Ok(inner.done)
        })
    }

    /// The film so far as a render result (`image, passes = r.image()`): each pixel the mean
    /// of the samples it has.
    fn image(&self, py: Python<'_>) -> PyResult<RenderResult> {
        let (image, samples) = py.detach(|| -> PyResult<_> {
            let mut guard = lock(&self.state);
            let inner = self.inner();
            let frame = frame_of(&mut guard, &inner)?;
            let image = aperture_output::film_to_image(
                &inner.film,
                frame.scene(),
                &inner.opts,
                false,
                inner.secs,
            )
            .map_err(output_error)?;
            Ok((image, inner.film.total_samples()))
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
        py.detach(|| self.inner().done)
    }

    /// The samples asked for (`spp`).
    #[getter]
    fn target(&self, py: Python<'_>) -> u32 {
        py.detach(|| self.inner().opts.spp)
    }

    /// True once every sample is taken, or the render was cancelled.
    #[getter]
    fn done(&self, py: Python<'_>) -> bool {
        let (done, spp) = py.detach(|| {
            let inner = self.inner();
            (inner.done, inner.opts.spp)
        });
        done >= spp || self.cancel.is_cancelled()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        py.detach(|| {
            let inner = self.inner();
            format!(
                "<aperture.Render {}x{} {}/{} spp>",
                inner.opts.width, inner.opts.height, inner.done, inner.opts.spp
            )
        })
    }
}
