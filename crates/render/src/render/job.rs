//! A job: what every sample of one render shares, and how a tile loop gets its samples traced
//! (in runs of [`WAVEFRONT_SAMPLES`], through a [`Wavefront`]).

use crate::aov::SampleAov;
use crate::background::Backdrop;
use crate::camera::Camera;
use crate::film::{AovLayout, CryptoIds};
use crate::filter::Filter;
use crate::frame_lights::FrameLights;
use crate::integrator::wavefront::Wavefront;
use crate::integrator::Integrator;
use crate::options::RenderOptions;
use crate::primary::{PrimarySamples, Start};
use crate::spares::Spares;
use aperture_accel::Accel;
use aperture_scene::Scene;
use aperture_shading::environment::EnvLight;
use aperture_shading::surface::Geometry;
use glam::Vec3;
use std::any::Any;

/// Samples whose paths are traced together (see `Job::samples`). 256 rendered `outdoor_dof`
/// 2–3 % faster than 64 or 1,024 (alternated runs, 2026-11-26).
pub(super) const WAVEFRONT_SAMPLES: usize = 256;

/// What every sample of one render shares.
pub(super) struct Job<'a> {
    pub(super) integrator: &'a Integrator<'a>,
    pub(super) camera: &'a Camera,
    pub(super) filter: &'a Filter,
    pub(super) opts: &'a RenderOptions,
    pub(super) layout: AovLayout,
    pub(super) ids: CryptoIds,
    /// Wavefronts reused from tile to tile (of one `AOV` kind per render: a fresh wavefront per
    /// tile allocated its buffers and grew every slot's pending list again). What a wavefront
    /// holds between runs never reaches a result: [`Wavefront::run`] restarts every slot it uses.
    pub(super) wavefronts: Spares<Box<dyn Any + Send>>,
    /// Pixels that see only a constant background, and their sample (not traced).
    pub(super) backdrop: Option<Backdrop>,
}

impl Job<'_> {
    /// The sample stream of sample `i` of pixel `(x, y)` (index `sample_offset + i` of the
    /// pixel's sequence) and its camera ray (`None` when the camera makes none), drawn alone:
    /// what [`Job::samples`] must give.
    #[cfg(test)]
    pub(super) fn camera_ray(
        &self,
        x: u32,
        y: u32,
        i: u32,
    ) -> (
        crate::sampler::SampleStream,
        Option<crate::camera::CameraRay>,
    ) {
        let o = self.opts;
        let at = (x, y, o.sample_offset + i, o.seed);
        crate::primary::drawn_alone(self.camera, self.filter, o.sampler, at)
    }

    /// Calls `f(key, result, record)` for every `(key, x, y, i)` of `items`, in order, where
    /// `result` is the radiance and coverage of sample `i` of pixel `(x, y)` (`None` when the
    /// camera makes no ray for it) and `record` its pass values (default unless `AOV`). The
    /// samples of pixels that see only a constant background ([`Job::backdrop`]) are that one
    /// sample, neither drawn nor traced.
    ///
    /// Why in runs: the paths of [`WAVEFRONT_SAMPLES`] samples advance together through a
    /// [`Wavefront`], so that every ray query is a batch: the lens
    /// samples of a pixel (or a row of pixels at low sample counts) are traced as packets of
    /// eight, and bounce and shadow rays interleaved (one ray's walk is a chain of dependent
    /// loads; several in flight keep the core busy). The results are exactly those of tracing
    /// each sample alone.
    pub(super) fn samples<K: Copy, const AOV: bool>(
        &self,
        items: impl IntoIterator<Item = (K, u32, u32, u32)>,
        mut f: impl FnMut(K, Option<(Vec3, bool)>, &SampleAov),
    ) {
        let mut items = items.into_iter();
        let mut run = Vec::with_capacity(WAVEFRONT_SAMPLES);
        let mut starts = Vec::with_capacity(WAVEFRONT_SAMPLES);
        let mut wavefront = (self.wavefronts.take())
            .and_then(|w| w.downcast::<Wavefront<AOV>>().ok())
            .unwrap_or_default();
        let o = self.opts;
        let mut primary =
            PrimarySamples::new(self.camera, self.filter, o.sampler, o.seed, o.sample_offset)
                .with_motion(o.motion.as_deref());
        if let Some(b) = &self.backdrop {
            primary = primary.with_scene(&b.scene);
        }
        let none = SampleAov::default();
        // The sample of every background pixel (only `fill` marks any, and only with a
        // backdrop): looked up once, not per sample.
        let background = match &self.backdrop {
            Some(b) => (Some((b.l, b.covered)), if AOV { &b.record } else { &none }),
            None => (None, &none),
        };
        loop {
            if self.opts.cancel.is_cancelled() {
                break;
            }
            run.clear();
            starts.clear();
            primary.fill(&mut items, WAVEFRONT_SAMPLES, &mut run, &mut starts);
            if run.is_empty() {
                break;
            }
            wavefront.run(self.integrator, &starts);
            let mut results = wavefront.results();
            // A lens prescription's weights (none for the thin lens: its radiance as traced).
            let mut weights = primary.weights().iter();
            for &(key, start) in &run {
                match start {
                    Start::Traced => match results.next() {
                        Some((l, covered, record)) => {
                            let l = weights.next().map_or(l, |&w| l * w);
                            f(key, Some((l, covered)), record)
                        }
                        None => f(key, None, &none),
                    },
                    Start::NoRay => f(key, None, &none),
                    Start::Background => f(key, background.0, background.1),
                    Start::Black => f(key, Some((Vec3::ZERO, false)), &none),
                }
            }
        }
        self.wavefronts.give(wavefront);
    }
}

/// How a surface is shaded under `opts` (material override, transmission, single-sided faces).
pub(crate) fn geometry<'a>(scene: &'a Scene, opts: &RenderOptions) -> Geometry<'a> {
    let (model, _) = opts.transmission.resolve(scene);
    let (sides, _) = opts.single_sided.resolve(scene);
    Geometry::with_transmission(scene, opts.material_override, model).with_sides(sides)
}

/// The path tracer of one render of `geom`, lit by the frame's `lights`.
pub(crate) fn integrator<'a>(
    geom: Geometry<'a>,
    accel: &'a Accel,
    lights: &'a FrameLights,
    opts: &'a RenderOptions,
) -> Integrator<'a> {
    let mut integrator = Integrator {
        geom,
        accel,
        emissive: lights.emissive.as_ref(),
        light_tree: lights.tree.clone(),
        env: EnvLight::new(&opts.env),
        max_bounces: opts.max_bounces,
        clamp: opts.clamp,
        light_passes: opts.passes.has_light_passes(),
        energy_compensation: opts.energy_compensation,
        pick_light: false,
        moving: opts.motion.as_deref().map_or(&[], |m| &m.instances),
        deforming: opts.motion.as_deref().map_or(&[], |m| &m.meshes),
    };
    integrator.pick_light = integrator.light_tree.is_some() || integrator.candidates().choose();
    integrator
}
