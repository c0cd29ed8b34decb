//! The render loop: fixed tiles rendered in parallel by rayon, merged in a fixed order. Every
//! sample value is a pure function of (pixel, index, dimension, seed) and every pixel is owned
//! by one tile, so the image is bit-identical for any thread count and any run.

use crate::adaptive::{self, AdaptiveOptions};
use crate::aov::SampleAov;
use crate::camera::Camera;
use crate::cryptomatte;
use crate::environment::{EnvLight, Environment};
use crate::film::{Accum, AovLayout, CryptoIds, Film, Window};
use crate::filter::{Filter, FilterKind};
use crate::integrator::{Clamp, Integrator, Wavefront};
use crate::lights::EmissiveLights;
use crate::passes::{Pass, PassSet};
use crate::primary::PrimarySamples;
use crate::sampler::{SamplerKind, MAX_SPP};
use crate::spares::{lock, Spares};
use crate::surface::{Geometry, MaterialOverride};
use crate::transmission::TransmissionMode;
use aperture_accel::Accel;
use aperture_scene::Scene;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::any::Any;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Samples whose paths are traced together (see `Job::samples`). 256 rendered `outdoor_dof`
/// 2–3 % faster than 64 or 1,024 (alternated runs, 2026-11-26).
const WAVEFRONT_SAMPLES: usize = 256;

/// Side of a square tile in pixels.
pub const TILE: u32 = 32;

/// Cycles' default `max_bounces`.
pub const DEFAULT_MAX_BOUNCES: u32 = 12;

/// What to render and how.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (1 ..= 65536); with adaptive sampling, the most any pixel takes.
    pub spp: u32,
    /// First sample index of each pixel's sequence (Cycles' "sample offset"): the render takes
    /// samples `sample_offset .. sample_offset + spp`, so batches with offsets 0, 64, 128, …
    /// together are one longer render (SPEC §8). `sample_offset + spp` may not exceed
    /// [`MAX_SPP`]. Not with adaptive sampling: its rounds decide from all of a pixel's samples
    /// so far, which a batch starting past 0 does not have.
    pub sample_offset: u32,
    /// Seed of every sample value.
    pub seed: u32,
    /// Index into `Scene::cameras`.
    pub camera: usize,
    /// Cycles' `max_bounces` (0 = direct light only).
    pub max_bounces: u32,
    /// Reconstruction filter.
    pub filter: FilterKind,
    /// Sample sequence.
    pub sampler: SamplerKind,
    /// What rays leaving the scene see: a colour (black by default) or an HDR image.
    pub env: Environment,
    /// Material override.
    pub material_override: MaterialOverride,
    /// Adaptive sampling (`None`: every pixel takes `spp` samples).
    pub adaptive: Option<AdaptiveOptions>,
    /// Cycles' sample clamping ([`Clamp::OFF`] by default: unbiased).
    pub clamp: Clamp,
    /// Passes to render beside the beauty (none by default; the CLI asks for
    /// [`PassSet::compositing`]).
    pub passes: PassSet,
    /// What transmissive surfaces are (`--transmission`): thin-walled or refractive.
    pub transmission: TransmissionMode,
    /// Give microfacet lobes back the energy single scattering loses, and layer materials by
    /// albedo scaling (on by default; off renders glTF Appendix B's formulas literally).
    pub energy_compensation: bool,
    /// Stops the render early when cancelled (never, by default): the film then holds the
    /// samples taken so far, each pixel's count saying how many.
    pub cancel: crate::Cancel,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 960,
            height: 540,
            spp: 64,
            sample_offset: 0,
            seed: 0,
            camera: 0,
            max_bounces: DEFAULT_MAX_BOUNCES,
            filter: FilterKind::default(),
            sampler: SamplerKind::default(),
            env: Environment::default(),
            material_override: MaterialOverride::None,
            adaptive: None,
            clamp: Clamp::OFF,
            passes: PassSet::NONE,
            transmission: TransmissionMode::Auto,
            energy_compensation: true,
            cancel: crate::Cancel::default(),
        }
    }
}

/// Why a render could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The camera index is out of range.
    #[error("camera {index} does not exist (the scene has {count})")]
    NoSuchCamera {
        /// Requested index.
        index: usize,
        /// Cameras in the scene.
        count: usize,
    },
    /// An option is out of its range.
    #[error("invalid option {name} = {value}: {why}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Its value.
        value: String,
        /// What is allowed.
        why: &'static str,
    },
}

fn check(opts: &RenderOptions) -> Result<(), RenderError> {
    let bad = |name, value: String, why| Err(RenderError::InvalidOption { name, value, why });
    if opts.width == 0 || opts.height == 0 {
        return bad(
            "resolution",
            format!("{}x{}", opts.width, opts.height),
            "both sides must be at least 1",
        );
    }
    if opts.spp == 0 || opts.spp > MAX_SPP {
        return bad("spp", opts.spp.to_string(), "must be in 1..=65536");
    }
    if u64::from(opts.sample_offset) + u64::from(opts.spp) > u64::from(MAX_SPP) {
        return bad(
            "sample_offset",
            opts.sample_offset.to_string(),
            "sample_offset + spp must be at most 65536 (the sampler's sequence length)",
        );
    }
    if opts.sample_offset > 0 && opts.adaptive.is_some() {
        return bad(
            "sample_offset",
            opts.sample_offset.to_string(),
            "must be 0 with adaptive sampling, whose stopping rule needs every sample of a pixel \
             from the first (split an adaptive render into tiles instead)",
        );
    }
    if let Some(a) = opts.adaptive {
        if !(a.threshold.is_finite() && a.threshold > 0.0) {
            return bad(
                "noise_threshold",
                a.threshold.to_string(),
                "must be finite and > 0",
            );
        }
        if a.min_spp == 0 || a.min_spp > opts.spp {
            return bad("min_spp", a.min_spp.to_string(), "must be in 1..=spp");
        }
    }
    for (name, v) in [
        ("clamp_direct", opts.clamp.direct),
        ("clamp_indirect", opts.clamp.indirect),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return bad(
                name,
                v.to_string(),
                "must be finite and ≥ 0 (0 = no clamping)",
            );
        }
    }
    if let Some(why) = opts.env.problem() {
        return bad(
            "env",
            why,
            "must be finite and ≥ 0, with width × height texels",
        );
    }
    Ok(())
}

/// Builds the ray-query structure for a scene.
pub fn build_accel(scene: &Scene, quality: aperture_accel::BvhQuality) -> Accel {
    let still = crate::sequence::SceneHints::still();
    crate::sequence::build_frame_accel(scene, quality, &still, None)
}

/// The BVH preset for a job of `samples` camera samples over `triangles` stored triangles, so a
/// preview does not pay for a build it cannot win back.
///
/// Measured with callgrind (instruction counts, repeatable on a loaded machine): building the
/// 1.04 M-triangle `MetalRoughSpheresNoTextures` takes about 880 fewer instructions per triangle
/// with `fast` than with `medium` (3.17 G against 4.09 G for the whole run), while `fast`'s tree
/// costs 251 more per closest-hit thin-lens ray on `BlenderIO-32bitIndices` (1,406 against
/// 1,155). A path-traced sample casts about three rays, so `fast` wins while
/// `samples < 880 / (3 · 251) · triangles ≈ 1.2 · triangles`; the rule keeps a margin and
/// switches at one half. `high` (1,140 per ray, about four times `medium`'s build) is never
/// chosen: it pays off only for renders far longer than its build, which the user knows better.
pub fn auto_bvh_quality(triangles: usize, samples: u64) -> aperture_accel::BvhQuality {
    if samples.saturating_mul(2) < triangles as u64 {
        aperture_accel::BvhQuality::Fast
    } else {
        aperture_accel::BvhQuality::Medium
    }
}

/// Renders with the scene camera `opts.camera`. `progress(done, total)` is called after each
/// tile (from worker threads).
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    let camera = scene_camera(scene, opts)?;
    render_with_camera(scene, accel, &camera, opts, progress)
}

/// The camera `opts.camera` of the scene, for the options' image size.
pub fn scene_camera(scene: &Scene, opts: &RenderOptions) -> Result<Camera, RenderError> {
    let cam = scene
        .cameras
        .get(opts.camera)
        .ok_or(RenderError::NoSuchCamera {
            index: opts.camera,
            count: scene.cameras.len(),
        })?;
    Ok(Camera::new(cam, opts.width, opts.height))
}

/// Renders through an explicit camera (its width and height must match the options').
pub fn render_with_camera(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    let whole = Window::whole(opts.width, opts.height);
    render_window(scene, accel, camera, opts, whole, progress)
}

/// Renders the pixels of `window` only. Each is bit-identical to the same pixel of a whole
/// render: every sample is a pure function of (pixel, index, dimension, seed), and adaptive
/// sampling, whose stopping rule looks at neighbours, renders the apron of pixels around the
/// window that its decisions can reach and then drops it.
pub fn render_window(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RenderOptions,
    window: Window,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    check(opts)?;
    if !window.fits(opts.width, opts.height) {
        return Err(RenderError::InvalidOption {
            name: "region",
            value: format!(
                "{}x{} at ({}, {})",
                window.width, window.height, window.x0, window.y0
            ),
            why: "must hold a pixel and lie inside the image",
        });
    }
    let integrator = integrator(scene, accel, opts);
    let filter = Filter::new(opts.filter);
    let job = Job {
        integrator: &integrator,
        camera,
        filter: &filter,
        opts,
        layout: AovLayout::new(opts.passes),
        ids: crypto_ids(scene, opts.passes),
        wavefronts: Spares::default(),
    };
    let mut film = match opts.adaptive {
        Some(a) => render_adaptive(&job, &a, window, progress),
        None => render_uniform(&job, window, progress),
    };
    let wanted = opts.passes.contains(Pass::Depth) || opts.passes.contains(Pass::Position);
    if wanted && !opts.cancel.is_cancelled() {
        centre_rays(&job, &mut film);
    }
    Ok(film)
}

/// Units of work [`render_window`] reports progress in for `window`: tiles, times rounds for
/// adaptive sampling (which may finish early, skipping the rest).
pub(crate) fn progress_units(opts: &RenderOptions, window: Window) -> usize {
    match opts.adaptive {
        Some(a) => {
            let rounds = a.rounds(opts.spp);
            let region = window.grown(rounds.len() as u32, opts.width, opts.height);
            tiles_of(region).len() * rounds.len()
        }
        None => tiles_of(window).len(),
    }
}

/// Tiles of at most [`TILE`]² pixels covering `w`, relative to its corner.
fn tiles_of(w: Window) -> Vec<(u32, u32, u32, u32)> {
    (0..w.height.div_ceil(TILE))
        .flat_map(|ty| {
            (0..w.width.div_ceil(TILE)).map(move |tx| {
                let (x0, y0) = (tx * TILE, ty * TILE);
                (x0, y0, TILE.min(w.width - x0), TILE.min(w.height - y0))
            })
        })
        .collect()
}

/// Every pixel of `window` at `spp` samples.
fn render_uniform(job: &Job<'_>, window: Window, progress: &(dyn Fn(usize, usize) + Sync)) -> Film {
    let opts = job.opts;
    let tiles = tiles_of(window);
    let total = tiles.len();
    let done = AtomicUsize::new(0);
    // One job per tile: rayon's adaptive splitting otherwise runs chunks of up to a quarter of
    // the tiles (with two threads) as one job that cannot be stolen, leaving a core idle at the
    // end (2 threads were 1.78–1.88× one on `outdoor_dof`; `BENCHMARKS.md`).
    // Each tile goes into the film as it finishes (tiles own disjoint pixels, so the order
    // does not matter), and its buffers serve the next tile: a tile's own fresh accumulators
    // cost page faults, and copying all of them after the last tile ran on one thread.
    let film = Mutex::new(Film::for_window(
        window,
        opts.width,
        opts.height,
        opts.passes,
    ));
    let spare = Spares::<TileSums>::default();
    tiles
        .par_iter()
        .with_max_len(1)
        .for_each(|&(x0, y0, tw, th)| {
            let mut t = spare.take().unwrap_or_default();
            let (x, y) = (window.x0 + x0, window.y0 + y0);
            let dropped = if job.layout.records() {
                job.render_tile::<true>(x, y, tw, th, &mut t)
            } else {
                job.render_tile::<false>(x, y, tw, th, &mut t)
            };
            // A tile cut short by cancelling records the samples each pixel got to.
            lock(&film).merge_tile(x0, y0, tw, &t.acc, &t.taken, dropped);
            spare.give(t);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
        });
    film.into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The samples of a tile as `(pixel k in the tile, x, y, sample i)`, row by row, a pixel's
/// samples together: a counter rather than nested `flat_map`s, whose state checks cost about
/// 30 instructions a sample.
struct TileItems {
    x0: u32,
    x1: u32,
    y1: u32,
    spp: u32,
    /// The next item.
    next: (usize, u32, u32, u32),
}

impl TileItems {
    /// The samples of the `tw × th` tile at `(x0, y0)`, `spp` each.
    fn new(x0: u32, y0: u32, tw: u32, th: u32, spp: u32) -> Self {
        let y1 = y0 + th;
        // An empty tile starts past its end.
        let y = if tw == 0 || spp == 0 { y1 } else { y0 };
        Self {
            x0,
            x1: x0 + tw,
            y1,
            spp,
            next: (0, x0, y, 0),
        }
    }
}

impl Iterator for TileItems {
    type Item = (usize, u32, u32, u32);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        let item = self.next;
        let (k, x, y, i) = item;
        if y >= self.y1 {
            return None;
        }
        self.next = if i + 1 < self.spp {
            (k, x, y, i + 1)
        } else if x + 1 < self.x1 {
            (k + 1, x + 1, y, 0)
        } else {
            (k + 1, self.x0, y + 1, 0)
        };
        Some(item)
    }
}

/// A tile's accumulators and the samples each of its pixels took.
#[derive(Default)]
struct TileSums {
    acc: Accum,
    taken: Vec<u32>,
}

impl TileSums {
    /// Empty sums and counts for `n` pixels, keeping the allocations.
    fn reset(&mut self, n: usize, layout: AovLayout) {
        self.acc.reset(n, layout);
        self.taken.clear();
        self.taken.resize(n, 0);
    }
}

/// Cryptomatte IDs of every instance's node and every material, when the passes need them.
fn crypto_ids(scene: &Scene, passes: PassSet) -> CryptoIds {
    let id = |name: &str| cryptomatte::id_bits(cryptomatte::murmur3_32(name.as_bytes()));
    CryptoIds {
        object: if passes.contains(Pass::CryptoObject) {
            scene
                .instances
                .iter()
                .map(|i| id(&scene.node_name(i.node)))
                .collect()
        } else {
            Vec::new()
        },
        material: if passes.contains(Pass::CryptoMaterial) {
            (0..scene.materials.len())
                .map(|m| id(&material_name(scene, m)))
                .collect()
        } else {
            Vec::new()
        },
    }
}

/// A material's name for compositors: its glTF name, else `materials[N]`.
pub fn material_name(scene: &Scene, index: usize) -> String {
    match scene.materials.get(index).and_then(|m| m.name.as_deref()) {
        Some(name) => name.to_owned(),
        None => format!("materials[{index}]"),
    }
}

/// The Depth and Position passes: the surface seen through each pixel's centre and the lens
/// centre, one ray per pixel, traced once (sharp and deterministic, not a sample).
fn centre_rays(job: &Job<'_>, film: &mut Film) {
    let w = film.window();
    let cam = job.camera;
    let forward = cam.world_from_camera.transform_vector3(Vec3::NEG_Z);
    let hits: Vec<Option<Vec3>> = (0..w.pixels())
        .into_par_iter()
        .map(|i| {
            let (x, y) = (w.x0 + (i as u32 % w.width), w.y0 + (i as u32 / w.width));
            let p_film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = cam.centre_ray(p_film)?;
            job.integrator.first_surface(ray.origin, ray.dir)
        })
        .collect();
    let origin = Vec3::from(cam.world_from_camera.translation);
    let ortho = matches!(cam.model, crate::camera::CameraModel::Orthographic { .. });
    if job.opts.passes.contains(Pass::Depth) {
        film.depth = hits
            .iter()
            .map(|h| match h {
                // Distance along the view axis (from the camera's plane for orthographic).
                Some(p) if ortho || (*p - origin).dot(forward) > 0.0 => (*p - origin).dot(forward),
                _ => DEPTH_BACKGROUND,
            })
            .collect();
    }
    if job.opts.passes.contains(Pass::Position) {
        film.position = hits.iter().map(|h| h.unwrap_or(Vec3::ZERO)).collect();
    }
}

/// Depth where the centre ray meets nothing: Cycles' value.
pub const DEPTH_BACKGROUND: f32 = 1e10;

/// The path tracer of one render.
fn integrator<'a>(scene: &'a Scene, accel: &'a Accel, opts: &RenderOptions) -> Integrator<'a> {
    let (model, _) = opts.transmission.resolve(scene);
    let geom = Geometry::with_transmission(scene, opts.material_override, model);
    let emissive = EmissiveLights::build(&geom);
    let mut integrator = Integrator {
        geom,
        accel,
        emissive,
        env: EnvLight::new(&opts.env),
        max_bounces: opts.max_bounces,
        clamp: opts.clamp,
        light_passes: opts.passes.has_light_passes(),
        energy_compensation: opts.energy_compensation,
        pick_light: false,
    };
    integrator.pick_light = integrator.candidates().choose();
    integrator
}

/// What every sample of one render shares.
struct Job<'a> {
    integrator: &'a Integrator<'a>,
    camera: &'a Camera,
    filter: &'a Filter,
    opts: &'a RenderOptions,
    layout: AovLayout,
    ids: CryptoIds,
    /// Wavefronts reused from tile to tile (of one `AOV` kind per render: a fresh wavefront per
    /// tile allocated its buffers and grew every slot's pending list again). What a wavefront
    /// holds between runs never reaches a result: [`Wavefront::run`] restarts every slot it uses.
    wavefronts: Spares<Box<dyn Any + Send>>,
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
    /// camera makes no ray for it) and `record` its pass values (default unless `AOV`).
    ///
    /// Why in runs: the paths of [`WAVEFRONT_SAMPLES`] samples advance together through a
    /// [`Wavefront`], so that every ray query is a batch: the lens
    /// samples of a pixel (or a row of pixels at low sample counts) are traced as packets of
    /// eight, bounce and shadow rays interleaved (1.2–1.4× the rays per second of one-ray
    /// queries, packets more; `BENCHMARKS.md`). The results are exactly those of tracing each
    /// sample alone.
    fn samples<K: Copy, const AOV: bool>(
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
            let none = SampleAov::default();
            for &(key, traced) in &run {
                match traced.then(|| results.next()).flatten() {
                    Some((l, covered, record)) => f(key, Some((l, covered)), record),
                    None => f(key, None, &none),
                }
            }
        }
        self.wavefronts.give(wavefront);
    }

    /// Every pixel of a tile at `spp` samples into `t` (its sums and the samples each pixel
    /// took: `spp`, unless the render was cancelled); returns the dropped-sample count.
    fn render_tile<const AOV: bool>(
        &self,
        x0: u32,
        y0: u32,
        tw: u32,
        th: u32,
        t: &mut TileSums,
    ) -> u64 {
        t.reset((tw * th) as usize, self.layout);
        let (acc, taken) = (&mut t.acc, &mut t.taken);
        let mut dropped = 0u64;
        let items = TileItems::new(x0, y0, tw, th, self.opts.spp);
        self.samples::<_, AOV>(items, |k, result, rec| {
            if let Some(t) = taken.get_mut(k) {
                *t += 1;
            }
            // Without passes, the radiance alone: the layout's checks stay out of the loop.
            let added = |(l, hit)| match AOV {
                true => acc.add(k, l, hit, rec, &self.ids),
                false => acc.add_radiance(k, l, hit),
            };
            if !result.is_some_and(added) {
                dropped += 1;
            }
        });
        dropped
    }
}

/// Rounds of doubling sample counts over the active pixels; between rounds, pixels whose error
/// is below the threshold (and whose neighbours are too) stop. See [`crate::adaptive`].
///
/// The rounds run over `window` grown by the apron its decisions can reach: a pixel's
/// decision after round r depends on pixels up to r away, so with as many apron pixels as
/// decisions, the window's pixels come out as in a whole-image render.
fn render_adaptive(
    job: &Job<'_>,
    a: &AdaptiveOptions,
    window: Window,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Film {
    let opts = job.opts;
    let rounds = a.rounds(opts.spp);
    let region = window.grown(rounds.len() as u32, opts.width, opts.height);
    let (w, n) = (region.width as usize, region.pixels());
    let tiles = tiles_of(region);
    let mut state = Accum::new(n, job.layout);
    let mut sq = vec![[0.0f64; 3]; n];
    let mut taken = vec![0u32; n];
    let mut dropped = vec![0u64; n];
    let mut active = vec![true; n];
    let total = tiles.len() * rounds.len();
    let done = AtomicUsize::new(0);
    for (r, &target) in rounds.iter().enumerate() {
        let updates: Vec<AdaptiveTile> = tiles
            .par_iter()
            .with_max_len(1)
            .map(|&(x0, y0, tw, th)| {
                let pixels: Vec<usize> = (y0..y0 + th)
                    .flat_map(|y| (x0..x0 + tw).map(move |x| y as usize * w + x as usize))
                    .filter(|&i| active[i])
                    .collect();
                let mut t = AdaptiveTile {
                    acc: Accum::new(pixels.len(), job.layout),
                    sq: pixels.iter().map(|&i| sq[i]).collect(),
                    dropped: vec![0; pixels.len()],
                    taken: vec![0; pixels.len()],
                    pixels,
                };
                for (k, &i) in t.pixels.iter().enumerate() {
                    t.acc.copy_pixel(k, &state, i);
                }
                let items: Vec<(usize, u32, u32, u32)> = t
                    .pixels
                    .iter()
                    .enumerate()
                    .flat_map(|(k, &i)| {
                        let (x, y) = (region.x0 + (i % w) as u32, region.y0 + (i / w) as u32);
                        (taken[i]..target).map(move |s| (k, x, y, s))
                    })
                    .collect();
                let mut add = |k: usize, result: Option<(Vec3, bool)>, rec: &SampleAov| {
                    t.taken[k] += 1;
                    match result {
                        Some((l, hit)) if t.acc.add(k, l, hit, rec, &job.ids) => {
                            for (s, v) in t.sq[k].iter_mut().zip(l.to_array()) {
                                *s += f64::from(v) * f64::from(v);
                            }
                        }
                        _ => t.dropped[k] += 1,
                    }
                };
                if job.layout.records() {
                    job.samples::<_, true>(items, &mut add);
                } else {
                    job.samples::<_, false>(items, &mut add);
                }
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                t
            })
            .collect();
        for t in updates {
            for (k, &i) in t.pixels.iter().enumerate() {
                state.copy_pixel(i, &t.acc, k);
                sq[i] = t.sq[k];
                dropped[i] += t.dropped[k];
                taken[i] += t.taken[k];
            }
        }
        if r + 1 == rounds.len() || opts.cancel.is_cancelled() {
            break;
        }
        let converged: Vec<bool> = (0..n)
            .map(|i| adaptive::pixel_error(&state.sums[i], &sq[i]) < f64::from(a.threshold))
            .collect();
        let budget: Vec<bool> = taken.iter().map(|&t| t < opts.spp).collect();
        active = adaptive::dilate(&converged, &budget, w);
        if !active.iter().any(|&b| b) {
            break;
        }
    }
    // Keep the window, drop the apron.
    let mut film = Film::for_window(window, opts.width, opts.height, opts.passes);
    let (dx, dy) = (
        (window.x0 - region.x0) as usize,
        (window.y0 - region.y0) as usize,
    );
    for y in 0..window.height as usize {
        for x in 0..window.width as usize {
            let (i, k) = ((y + dy) * w + x + dx, y * window.width as usize + x);
            film.accum.copy_pixel(k, &state, i);
            let (t, d) = film.counts_mut();
            t[k] = taken[i];
            *d += dropped[i];
        }
    }
    film
}

/// The active pixels of one tile during an adaptive round, with their running sums.
struct AdaptiveTile {
    /// Indices into the region.
    pixels: Vec<usize>,
    acc: Accum,
    /// Per channel, the sums of squared samples, for the error estimate.
    sq: Vec<[f64; 3]>,
    dropped: Vec<u64>,
    /// Samples each pixel took this round (all it was due, unless the render was cancelled).
    taken: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes;
    use aperture_accel::BvhQuality;
    use glam::{Affine3A, Vec3};

    #[test]
    fn tile_items_are_every_sample_of_every_pixel_in_order() {
        for (x0, y0, tw, th, spp) in [
            (3, 5, 4, 3, 2),
            (0, 0, 1, 1, 1),
            (7, 2, 5, 1, 3),
            (1, 1, 2, 2, 0),
            (2, 3, 0, 2, 3),
        ] {
            let want: Vec<_> = (y0..y0 + th)
                .flat_map(|y| {
                    (x0..x0 + tw).flat_map(move |x| {
                        let k = ((y - y0) * tw + (x - x0)) as usize;
                        (0..spp).map(move |i| (k, x, y, i))
                    })
                })
                .collect();
            let items = TileItems::new(x0, y0, tw, th, spp);
            assert_eq!(
                items.collect::<Vec<_>>(),
                want,
                "{tw}x{th} at ({x0}, {y0}), {spp} spp"
            );
        }
    }
    #[test]
    fn previews_of_big_scenes_build_fast() {
        // A 1-spp 960×540 preview of a 7.7 M-triangle scene, and of a 130 k one.
        assert_eq!(auto_bvh_quality(7_700_000, 518_400), BvhQuality::Fast);
        assert_eq!(auto_bvh_quality(130_000, 518_400), BvhQuality::Medium);
        // The README's demo render (18 k triangles, 64 spp) and an empty scene.
        assert_eq!(auto_bvh_quality(18_000, 33_177_600), BvhQuality::Medium);
        assert_eq!(auto_bvh_quality(0, 1), BvhQuality::Medium);
        // The switch sits at samples = triangles / 2, and huge jobs do not overflow.
        assert_eq!(auto_bvh_quality(1_000_001, 500_000), BvhQuality::Fast);
        assert_eq!(auto_bvh_quality(1_000_000, 500_000), BvhQuality::Medium);
        assert_eq!(auto_bvh_quality(usize::MAX, u64::MAX), BvhQuality::Medium);
    }

    /// A plane under a point light, an emissive ball, depth of field: every code path.
    fn busy_scene() -> Scene {
        let mut s = test_scenes::lit_plane(3.0);
        s.cameras[0].dof.enabled = true;
        s.cameras[0].dof.aperture_radius = 0.2;
        s.cameras[0].dof.focus_distance = 5.0;
        s.materials
            .push(test_scenes::emitter(Vec3::new(4.0, 2.0, 1.0)));
        s.meshes.push(test_scenes::icosphere(1, 1));
        s.instances.push(aperture_scene::Instance {
            mesh: 1,
            world_from_object: Affine3A::from_translation(Vec3::new(1.0, 0.5, 1.0)),
            node: 1,
        });
        s
    }

    fn render_in_pool(threads: usize, scene: &Scene, opts: &RenderOptions) -> Film {
        let accel = build_accel(scene, Default::default());
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(scene, &accel, opts, &|_, _| {}).unwrap())
    }

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

    /// A job of a thin-lens camera without passes, for tests that trace its samples.
    fn lens_job<'a>(
        integrator: &'a Integrator<'a>,
        camera: &'a Camera,
        filter: &'a Filter,
        opts: &'a RenderOptions,
    ) -> Job<'a> {
        Job {
            integrator,
            camera,
            filter,
            opts,
            layout: AovLayout::default(),
            ids: CryptoIds::default(),
            wavefronts: Spares::default(),
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
        assert!(hits > 0 && misses > 0, "{hits} hits, {misses} misses");
        assert_eq!(lit_passes > 0, AOV, "light passes recorded only with AOV");
    }

    #[test]
    fn identical_for_any_thread_count_and_run() {
        let scene = busy_scene();
        // Not a multiple of the tile size, so edge tiles are partial.
        let opts = RenderOptions {
            width: 45,
            height: 37,
            spp: 4,
            ..RenderOptions::default()
        };
        let one = render_in_pool(1, &scene, &opts);
        let two = render_in_pool(2, &scene, &opts);
        let again = render_in_pool(2, &scene, &opts);
        assert_eq!(one, two);
        assert_eq!(two, again);
        let px = one.to_rgba();
        assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite())));
        assert!(px.iter().any(|p| p[0] != px[0][0]));
        // Another seed changes the image (the comparison above is not vacuous).
        let other = render_in_pool(2, &scene, &RenderOptions { seed: 1, ..opts });
        assert_ne!(one, other);
    }

    #[test]
    fn non_finite_samples_are_dropped_and_counted() {
        let mut scene = busy_scene();
        // An emitter of infinite strength: every sample that sees it is infinite.
        scene.materials[1].emissive_strength = f32::INFINITY;
        let accel = build_accel(&scene, Default::default());
        let opts = RenderOptions {
            width: 24,
            height: 24,
            spp: 2,
            ..RenderOptions::default()
        };
        let film = render(&scene, &accel, &opts, &|_, _| {}).unwrap();
        assert!(film.dropped_samples() > 0);
        assert!(film.to_rgba().iter().flatten().all(|c| c.is_finite()));
        let sum: u64 = (0..24)
            .flat_map(|y| (0..24).map(move |x| (x, y)))
            .map(|(x, y)| film.pixel_sum(x, y).count as u64)
            .sum();
        assert_eq!(sum + film.dropped_samples(), 24 * 24 * 2);
    }

    #[test]
    fn progress_reports_every_tile() {
        let scene = busy_scene();
        let accel = build_accel(&scene, Default::default());
        let opts = RenderOptions {
            width: 40,
            height: 40,
            spp: 1,
            ..RenderOptions::default()
        };
        let calls = AtomicUsize::new(0);
        let last = AtomicUsize::new(0);
        render(&scene, &accel, &opts, &|done, total| {
            calls.fetch_add(1, Ordering::Relaxed);
            assert!(done <= total);
            last.fetch_max(done, Ordering::Relaxed);
            assert_eq!(total, 4);
        })
        .unwrap();
        assert_eq!(calls.into_inner(), 4);
        assert_eq!(last.into_inner(), 4);
    }

    #[test]
    fn bad_options_are_refused() {
        let scene = busy_scene();
        let accel = build_accel(&scene, Default::default());
        for opts in [
            RenderOptions {
                spp: 0,
                ..RenderOptions::default()
            },
            RenderOptions {
                width: 0,
                ..RenderOptions::default()
            },
            RenderOptions {
                camera: 3,
                ..RenderOptions::default()
            },
            RenderOptions {
                env: Environment::Constant(Vec3::new(-1.0, 0.0, 0.0)),
                ..RenderOptions::default()
            },
            // Past the end of the sampler's sequence.
            RenderOptions {
                spp: 64,
                sample_offset: MAX_SPP - 63,
                ..RenderOptions::default()
            },
            // A batch past the first sample with adaptive sampling.
            RenderOptions {
                sample_offset: 64,
                adaptive: Some(AdaptiveOptions {
                    threshold: 0.01,
                    min_spp: 4,
                }),
                ..RenderOptions::default()
            },
        ] {
            assert!(render(&scene, &accel, &opts, &|_, _| {}).is_err());
        }
    }
}
