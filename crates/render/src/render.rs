//! The render loop: fixed tiles rendered in parallel by rayon. Every sample value is a pure
//! function of (pixel, index, dimension, seed) and every pixel is owned by one tile, so the
//! image is bit-identical for any thread count and any run, whatever order the tiles finish in.
//!
//! Here: the options and their checks, the entry points, and what every render shares (its
//! path tracer, the Cryptomatte IDs, the Depth and Position passes' centre rays). The pixels
//! come from one of two tile loops, `tiles` (every pixel at `spp` samples) or `rounds`
//! (adaptive sampling), both tracing their samples through a `job::Job`.

mod job;
mod rounds;
mod tiles;

use crate::adaptive::AdaptiveOptions;
use crate::camera::Camera;
use crate::cryptomatte;
use crate::environment::{EnvLight, Environment};
use crate::film::{AovLayout, CryptoIds, Film, Window};
use crate::filter::{Filter, FilterKind};
use crate::integrator::{Clamp, Integrator};
use crate::lights::EmissiveLights;
use crate::passes::{Pass, PassSet};
use crate::sampler::{SamplerKind, MAX_SPP};
use crate::spares::Spares;
use crate::surface::{Geometry, MaterialOverride};
use crate::transmission::TransmissionMode;
use aperture_accel::Accel;
use aperture_scene::Scene;
use glam::{Vec2, Vec3};
use job::Job;
use rayon::prelude::*;
use rounds::render_adaptive;
use tiles::{render_uniform, tiles_of};

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
        backdrop: crate::background::backdrop(&integrator, accel, camera, &filter, &opts.env),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes;
    use aperture_accel::BvhQuality;
    use glam::{Affine3A, Vec3};

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
    pub(super) fn busy_scene() -> Scene {
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
