//! A progressive render (SPEC §9): a frame's image refined pass by pass into one film that
//! can be read between passes. Each pass renders the next samples of every pixel's sequence
//! and sums them onto the film where the last pass left off, so a render that reaches N
//! samples equals the one-shot N-sample render bit for bit, whatever the passes were. The
//! render holds no borrow of its frame: each pass is given the frame it started from, so a
//! progressive render can live beside a session (in a viewport, in a Python object) and be
//! refused by its owner when the scene was edited since.

use crate::camera::Camera;
use crate::film::{Film, Window};
use crate::frame::Frame;
use crate::options::{RenderError, RenderOptions};

/// A frame's image refined pass by pass (see the module documentation).
///
/// ```
/// use aperture_render::{Frame, Progressive, RenderOptions, Window};
/// use aperture_shading::test_scenes;
/// let frame = Frame::still(test_scenes::lit_plane(1.0), Default::default());
/// let opts = RenderOptions { width: 8, height: 8, spp: 4, ..Default::default() };
/// let mut render = Progressive::new(&frame, &opts, Window::whole(8, 8))?;
/// while let Some(total) = render.next_pass(&frame, &|_, _| {})? {
///     assert!(render.film().pixel(4, 4)[0] > 0.0, "readable after the pass to {total}");
/// }
/// let once = frame.render(&opts, &|_, _| {})?;
/// assert_eq!(render.film().to_rgba(), once.to_rgba());
/// # Ok::<(), aperture_render::RenderError>(())
/// ```
pub struct Progressive {
    camera: Camera,
    /// The whole render's options: its samples are `sample_offset .. sample_offset + spp`.
    opts: RenderOptions,
    film: Film,
    /// Samples every pixel has been given so far (its passes' sum).
    done: u32,
}

impl Progressive {
    /// A render of `window` of `frame` with `opts` (its `spp` the samples to reach), no pass
    /// taken yet.
    pub fn new(frame: &Frame, opts: &RenderOptions, window: Window) -> Result<Self, RenderError> {
        let camera = frame.camera(opts)?;
        crate::options::check(opts)?;
        if !window.fits(opts.width, opts.height) {
            return Err(RenderError::InvalidOption {
                name: "region",
                value: format!("{window:?}"),
                why: "must hold a pixel and lie inside the image",
            });
        }
        Ok(Self {
            camera,
            opts: opts.clone(),
            film: Film::for_window(window, opts.width, opts.height, opts.passes),
            done: 0,
        })
    }

    /// Renders the next `samples` samples of every pixel (at most the ones left) from
    /// `frame`, the frame the render started from, and returns the samples each pixel has
    /// now. Adaptive sampling decides from all of a pixel's samples, so an adaptive render
    /// takes all of them in its first pass.
    pub fn step(
        &mut self,
        frame: &Frame,
        samples: u32,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<u32, RenderError> {
        let left = self.opts.spp - self.done;
        let n = match self.opts.adaptive {
            Some(_) => left,
            None => samples.min(left),
        };
        if n == 0 || self.opts.cancel.is_cancelled() {
            return Ok(self.done);
        }
        let pass = RenderOptions {
            sample_offset: self.opts.sample_offset + self.done,
            spp: n,
            ..self.opts.clone()
        };
        frame.render_onto(&self.camera, &pass, &mut self.film, progress)?;
        if !self.opts.cancel.is_cancelled() {
            self.done += n;
        }
        Ok(self.done)
    }

    /// The next pass of the doubling schedule (1, 1, 2, 4, … samples: totals of 1, 2, 4, 8, …,
    /// as Cycles' viewport refines), `None` once every sample is taken or the render was
    /// cancelled.
    pub fn next_pass(
        &mut self,
        frame: &Frame,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Option<u32>, RenderError> {
        if self.is_done() {
            return Ok(None);
        }
        let n = self.done.max(1);
        self.step(frame, n, progress).map(Some)
    }

    /// True once every sample was taken, or the render was cancelled.
    pub fn is_done(&self) -> bool {
        self.done >= self.opts.spp || self.opts.cancel.is_cancelled()
    }

    /// Samples every pixel has been given so far.
    pub fn samples(&self) -> u32 {
        self.done
    }

    /// The samples asked for.
    pub fn target(&self) -> u32 {
        self.opts.spp
    }

    /// The film so far (each pixel's count says how many samples it holds).
    pub fn film(&self) -> &Film {
        &self.film
    }

    /// The options of the whole render.
    pub fn options(&self) -> &RenderOptions {
        &self.opts
    }

    /// The film, the render done with.
    pub fn into_film(self) -> Film {
        self.film
    }
}
