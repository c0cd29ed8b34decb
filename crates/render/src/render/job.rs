//! A job: what every sample of one render shares, and how a tile loop gets its samples traced
//! (in runs of [`WAVEFRONT_SAMPLES`], through a [`Wavefront`]).

use super::RenderOptions;
use crate::aov::SampleAov;
use crate::background::Backdrop;
use crate::camera::Camera;
use crate::film::{AovLayout, CryptoIds};
use crate::filter::Filter;
use crate::integrator::{Integrator, Wavefront};
use crate::primary::{PrimarySamples, Start};
use crate::spares::Spares;
use glam::Vec3;
use std::any::Any;

/// Samples whose paths are traced together (see `Job::samples`). 256 rendered `outdoor_dof`
/// 2–3 % faster than 64 or 1,024 (alternated runs, 2026-11-26).
const WAVEFRONT_SAMPLES: usize = 256;

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
    fn camera_ray(
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
    /// eight, bounce and shadow rays interleaved (1.2–1.4× the rays per second of one-ray
    /// queries, packets more; `BENCHMARKS.md`). The results are exactly those of tracing each
    /// sample alone.
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
            PrimarySamples::new(self.camera, self.filter, o.sampler, o.seed, o.sample_offset);
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
            for &(key, start) in &run {
                match start {
                    Start::Traced => match results.next() {
                        Some((l, covered, record)) => f(key, Some((l, covered)), record),
                        None => f(key, None, &none),
                    },
                    Start::NoRay => f(key, None, &none),
                    Start::Background => f(key, background.0, background.1),
                }
            }
        }
        self.wavefronts.give(wavefront);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::background::backdrop;
    use crate::environment::Environment;
    use crate::render::tests::busy_scene;
    use crate::render::{build_accel, integrator};
    use aperture_scene::Scene;
    use glam::Affine3A;

    #[test]
    fn wavefront_gives_each_sample_as_alone() {
        // Lens, emitter, point light and a camera that sees both geometry and background;
        // every sample of a run is compared bit for bit with the same sample traced alone,
        // radiance and pass values, under a constant and an importance-sampled environment
        // (whose shadow rays leave the scene).
        let mut scene = busy_scene();
        // A plane of 3.2 × 3.2 instead of 40 × 40: the view holds background too.
        scene.instances[0].world_from_object = Affine3A::from_scale(Vec3::new(0.08, 1.0, 0.08));
        let accel = build_accel(&scene, Default::default());
        let sky = Environment::Image(std::sync::Arc::new(crate::environment::EnvImage {
            width: 4,
            height: 2,
            texels: (0..8)
                .map(|i| Vec3::new(0.1 * i as f32, 0.3, 0.05))
                .collect(),
            rotation: 0.3,
            strength: 1.0,
            sampling: Default::default(),
        }));
        for env in [Environment::Constant(Vec3::splat(0.2)), sky] {
            let opts = RenderOptions {
                width: 23,
                height: 13,
                spp: 3,
                env,
                ..RenderOptions::default()
            };
            let mut integrator = integrator(&scene, &accel, &opts);
            integrator.light_passes = true;
            check_wavefront::<false>(&scene, &integrator, &opts);
            check_wavefront::<true>(&scene, &integrator, &opts);
        }
    }

    #[test]
    fn one_light_per_vertex_converges_to_every_light() {
        // Two point lights and an emissive ball: three candidates, the ball picked at some
        // vertices and not at others, so both its light samples and its MIS weights depend
        // on the pick. The image's mean radiance with one light picked per vertex equals
        // (within the spread of independently scrambled runs) the mean with every light
        // sampled at every vertex, as it must for an unbiased pick.
        let mut scene = busy_scene();
        scene.lights.push(aperture_scene::Light {
            name: None,
            kind: aperture_scene::LightKind::Point,
            position: Vec3::new(-0.5, 1.0, 2.0),
            direction: Vec3::NEG_Y,
            intensity: Vec3::new(4.0, 6.0, 8.0),
        });
        let accel = build_accel(&scene, Default::default());
        let opts = RenderOptions {
            width: 48,
            height: 32,
            spp: 64,
            ..RenderOptions::default()
        };
        let camera = Camera::new(&scene.cameras[0], opts.width, opts.height);
        let filter = Filter::new(opts.filter);
        let mean = |pick: bool, seed: u32| {
            let mut integrator = integrator(&scene, &accel, &opts);
            assert!(integrator.pick_light);
            integrator.pick_light = pick;
            let opts = RenderOptions {
                seed,
                ..opts.clone()
            };
            let job = lens_job(&integrator, &camera, &filter, &opts);
            let mut sum = Vec3::ZERO;
            for (x, y) in (0..opts.height).flat_map(|y| (0..opts.width).map(move |x| (x, y))) {
                for i in 0..opts.spp {
                    let (stream, ray) = job.camera_ray(x, y, i);
                    if let Some(r) = ray {
                        sum += integrator.li_alone::<false>(r.origin, r.dir, &stream).0;
                    }
                }
            }
            sum / (opts.width * opts.height * opts.spp) as f32
        };
        // Mean and standard error over seeds (each an independent scramble).
        let runs = |pick: bool| {
            let m: Vec<Vec3> = (0..6).map(|seed| mean(pick, seed)).collect();
            let avg = m.iter().sum::<Vec3>() / m.len() as f32;
            let var = m.iter().map(|x| (*x - avg) * (*x - avg)).sum::<Vec3>() / 5.0;
            (avg, (var / 6.0).powf(0.5))
        };
        let (picked, e_picked) = runs(true);
        let (every, e_every) = runs(false);
        assert!(every.min_element() > 0.01, "{every}");
        for c in 0..3 {
            let tolerance = 4.0 * (e_picked[c].powi(2) + e_every[c].powi(2)).sqrt();
            assert!(
                (picked[c] - every[c]).abs() <= tolerance,
                "channel {c}: {picked} against {every} (tolerance {tolerance})"
            );
            // The spread is small enough for the comparison to mean something.
            assert!(
                tolerance < 0.01 * every[c],
                "channel {c}: tolerance {tolerance}"
            );
        }
    }

    /// A job of a thin-lens camera without passes, for tests that trace its samples (pixels
    /// that see only a constant background are not traced, as in a render).
    fn lens_job<'a>(
        integrator: &'a Integrator<'a>,
        camera: &'a Camera,
        filter: &'a Filter,
        opts: &'a RenderOptions,
    ) -> Job<'a> {
        let env = &opts.env;
        Job {
            integrator,
            camera,
            filter,
            opts,
            layout: AovLayout::default(),
            ids: CryptoIds::default(),
            wavefronts: Spares::default(),
            backdrop: backdrop(integrator, integrator.accel, camera, filter, env),
        }
    }

    /// [`Job::samples`] against each sample traced alone ([`Integrator::li_alone`]).
    fn check_wavefront<const AOV: bool>(
        scene: &Scene,
        integrator: &Integrator,
        opts: &RenderOptions,
    ) {
        let camera = Camera::new(&scene.cameras[0], opts.width, opts.height);
        let filter = Filter::new(opts.filter);
        let job = lens_job(integrator, &camera, &filter, opts);
        // Under the constant environment, part of the view is background only, untraced.
        let untraced = job.backdrop.as_ref().map(|b| &b.scene);
        let constant = matches!(opts.env, Environment::Constant(_));
        assert_eq!(untraced.is_some(), constant);
        let mut background = 0;
        // More items than two runs, in an order that jumps between pixels and samples.
        let items: Vec<(usize, u32, u32, u32)> = (0..opts.height)
            .flat_map(|y| (0..opts.width).map(move |x| (x, y)))
            .flat_map(|(x, y)| (0..opts.spp).map(move |i| (x, y, i)))
            .rev()
            .enumerate()
            .map(|(k, (x, y, i))| (k, x, y, i))
            .collect();
        assert!(items.len() > 2 * WAVEFRONT_SAMPLES);
        let mut seen = 0;
        let (mut hits, mut misses, mut lit_passes) = (0, 0, 0);
        job.samples::<_, AOV>(items.iter().copied(), |k, result, record| {
            assert_eq!(k, seen, "results arrive in order");
            seen += 1;
            let (_, x, y, i) = items[k];
            background += untraced.is_some_and(|r| !r.contains(x, y)) as u32;
            let (stream, ray) = job.camera_ray(x, y, i);
            let alone = ray.map(|r| integrator.li_alone::<AOV>(r.origin, r.dir, &stream));
            let bits =
                |r: Option<(Vec3, bool)>| r.map(|(l, c)| (l.to_array().map(f32::to_bits), c));
            let want = alone.map(|(l, c, _)| (l, c));
            assert_eq!(bits(result), bits(want), "pixel ({x}, {y}) sample {i}");
            let want_record = alone.map_or(SampleAov::default(), |(_, _, a)| a);
            assert_eq!(*record, want_record, "pixel ({x}, {y}) sample {i}");
            lit_passes += record.light.iter().any(|c| *c != Vec3::ZERO) as u32;
            match result {
                Some((_, true)) => hits += 1,
                _ => misses += 1,
            }
        });
        assert_eq!(seen, items.len());
        assert!(
            hits > 0 && misses > background,
            "{hits} hits, {misses} misses"
        );
        assert_eq!(background > 0, constant, "{background} background samples");
        assert_eq!(lit_passes > 0, AOV, "light passes recorded only with AOV");
    }
}
