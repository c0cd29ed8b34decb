//! What to render and how ([`RenderOptions`]), and why a render could not start
//! ([`RenderError`]): the options' ranges are checked here, before any work.

use crate::adaptive::AdaptiveOptions;
use crate::filter::FilterKind;
use crate::integrator::Clamp;
use crate::passes::PassSet;
use crate::sampler::{SamplerKind, MAX_SPP};
use aperture_shading::convention::Convention;
use aperture_shading::environment::Environment;
use aperture_shading::surface::MaterialOverride;

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
    pub transmission: Convention,
    /// What the back of a single-sided face is (`--single-sided`). `Blender` by default here
    /// (both sides, what scenes built by hand expect); the command line's default is `Auto`.
    pub single_sided: Convention,
    /// Give microfacet lobes back the energy single scattering loses, and layer materials by
    /// albedo scaling (on by default; off renders glTF Appendix B's formulas literally).
    pub energy_compensation: bool,
    /// What moves within the frame's shutter (SPEC §7); `None`: motion blur off, every sample
    /// at the frame's instant.
    pub motion: Option<std::sync::Arc<crate::motion::FrameMotion>>,
    /// The frames before and after, for the `Vector` pass (`None`: it is zero).
    pub vector: Option<std::sync::Arc<crate::motion::FrameNeighbours>>,
    /// Stops the render early when cancelled (never, by default): the film then holds the
    /// samples taken so far, each pixel's count saying how many.
    pub cancel: crate::cancel::Cancel,
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
            transmission: Convention::Auto,
            single_sided: Convention::Blender,
            energy_compensation: true,
            motion: None,
            vector: None,
            cancel: crate::cancel::Cancel::default(),
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
    /// The camera's `lens_prescription` cannot image (issue 61).
    #[error("camera {camera:?}: lens_prescription = {source_name:?}: {reason}")]
    Lens {
        /// Camera name.
        camera: String,
        /// The prescription's file as written, or `inline`.
        source_name: String,
        /// Why.
        reason: String,
    },
}

pub(crate) fn check(opts: &RenderOptions) -> Result<(), RenderError> {
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
