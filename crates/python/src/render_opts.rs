//! `scene.render(**options)` and `scene.start(**options)`: the command line's render options
//! under their own names, turned into the renderer's options and the frame to render, with
//! the command line's defaults (960 wide, the camera's aspect, 64 spp, the compositing
//! passes, `auto` conventions, the file's environment), so the same options give the same
//! pixels as `aperture render`.

use crate::errors::value_error;
use crate::load_opts::{time_options, SceneDefaults};
use crate::options::{non_negative, positive, Kwargs};
use aperture_accel::BvhQuality;
use aperture_denoise::{Prefilter, Quality, Settings};
use aperture_render::motion::{MotionOverrides, MotionSettings, ShutterPosition};
use aperture_render::{
    AdaptiveOptions, BvhQualityChoice, Cancel, Clamp, FilterKind, FrameSpec, Pass, PassSet,
    RenderOptions, SamplerKind, Session,
};
use aperture_shading::{EnvLight, Environment, MaterialOverride};
use glam::Vec3;
use pyo3::prelude::*;
use std::path::PathBuf;

/// `env=`: a colour or an equirectangular image file.
#[derive(Debug, Clone)]
pub(crate) enum EnvAsk {
    /// Linear RGB radiance.
    Color(Vec3),
    /// An `.hdr` or `.exr` file.
    File(String),
}

/// A render's options as asked, before the scene says what they resolve to.
#[derive(Debug, Clone)]
pub(crate) struct RenderAsk {
    /// Everything that needs no scene (size, camera, environment and cancel filled in later).
    pub base: RenderOptions,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub camera: Option<String>,
    pub env: Option<EnvAsk>,
    pub env_rotation: f32,
    pub env_strength: f32,
    pub bvh: BvhQualityChoice,
    pub time: Option<f64>,
    pub fps: f32,
    pub motion: MotionOverrides,
    /// Denoising, `None` without.
    pub denoise: Option<DenoiseAsk>,
    pub threads: Option<usize>,
}

/// `denoise=True` with its settings and `oidn=` (the library, as the command line's `--oidn`;
/// else `APERTURE_OIDN`, else the usual places).
#[derive(Debug, Clone)]
pub(crate) struct DenoiseAsk {
    pub settings: Settings,
    pub library: Option<PathBuf>,
}

/// The resolved render: the renderer's options and the frame they render.
pub(crate) struct Plan {
    pub opts: RenderOptions,
    pub spec: FrameSpec,
}

/// The render options of `kw` (what is left of it is the caller's to check).
pub(crate) fn render_ask(kw: &mut Kwargs<'_>, defaults: &SceneDefaults) -> PyResult<RenderAsk> {
    let spp = kw.uint("spp", 1, 65536)?.unwrap_or(64);
    let sample_offset = kw.uint("sample_offset", 0, 65535)?.unwrap_or(0);
    let passes = passes(kw)?;
    let denoise = denoise(kw)?;
    let passes = match denoise.is_some() {
        true => passes
            .with(Pass::DenoisingAlbedo)
            .with(Pass::DenoisingNormal),
        false => passes,
    };
    let base = RenderOptions {
        spp,
        sample_offset,
        seed: kw.uint("seed", 0, i32::MAX as u32)?.unwrap_or(0),
        max_bounces: kw.uint("max_bounces", 0, 1024)?.unwrap_or(12),
        clamp: clamp(kw)?,
        filter: filter(kw)?,
        sampler: kw
            .choice(
                "sampler",
                &[
                    ("sobol", SamplerKind::Sobol),
                    ("random", SamplerKind::Random),
                ],
            )?
            .unwrap_or_default(),
        material_override: kw
            .choice(
                "override_material",
                &[("diffuse", MaterialOverride::Diffuse)],
            )?
            .unwrap_or(MaterialOverride::None),
        adaptive: adaptive(kw, spp)?,
        passes,
        transmission: kw
            .convention("transmission")?
            .unwrap_or(defaults.transmission),
        single_sided: kw
            .convention("single_sided")?
            .unwrap_or(defaults.single_sided),
        energy_compensation: !kw.flag("no_energy_compensation")?.unwrap_or(false),
        ..RenderOptions::default()
    };
    if sample_offset > 0 && base.adaptive.is_some() {
        return Err(value_error(
            "sample_offset cannot be used with noise_threshold",
        ));
    }
    if u64::from(sample_offset) + u64::from(spp) > 65536 {
        return Err(value_error(format!(
            "invalid sample_offset = {sample_offset}: with spp {spp} it passes the sampler's 65536 samples"
        )));
    }
    let (time, fps) = match time_options(kw, defaults.fps)? {
        (None, fps) => (defaults.time, fps),
        (t, fps) => (t, fps),
    };
    Ok(RenderAsk {
        base,
        width: kw.uint("width", 1, 65536)?,
        height: kw.uint("height", 1, 65536)?,
        camera: kw.name_or_index("camera")?,
        env: env(kw)?,
        env_rotation: kw
            .float("env_rotation", f64::is_finite, "must be finite")?
            .unwrap_or(0.0) as f32,
        env_strength: kw
            .float("env_strength", non_negative, "must be finite and ≥ 0")?
            .unwrap_or(1.0) as f32,
        bvh: bvh_quality(kw)?,
        time,
        fps,
        motion: motion(kw)?,
        denoise,
        threads: kw.uint("threads", 1, 4096)?.map(|n| n as usize),
    })
}

/// `denoise=`, with `denoise_quality=` and `denoise_prefilter=` (Cycles' Quality and
/// Prefilter, the command line's `--denoise-quality` and `--denoise-prefilter`; high and
/// accurate by default) and `oidn=`.
fn denoise(kw: &mut Kwargs<'_>) -> PyResult<Option<DenoiseAsk>> {
    let on = kw.flag("denoise")?.unwrap_or(false);
    let qualities = [Quality::High, Quality::Balanced, Quality::Fast].map(|q| (q.name(), q));
    let prefilters = [Prefilter::Accurate, Prefilter::Fast, Prefilter::None].map(|p| (p.name(), p));
    let quality = kw.choice("denoise_quality", &qualities)?;
    let prefilter = kw.choice("denoise_prefilter", &prefilters)?;
    let library = kw.string("oidn")?.map(PathBuf::from);
    if !on && (quality.is_some() || prefilter.is_some() || library.is_some()) {
        return Err(value_error(
            "denoise_quality, denoise_prefilter and oidn need denoise=True",
        ));
    }
    Ok(on.then(|| DenoiseAsk {
        settings: Settings {
            quality: quality.unwrap_or_default(),
            prefilter: prefilter.unwrap_or_default(),
        },
        library,
    }))
}

/// `passes=`: a list of EXR pass names, or the command line's string (`"default"`, `"all"`,
/// `"none"`, `"Depth,Normal"`); the compositing passes by default.
fn passes(kw: &mut Kwargs<'_>) -> PyResult<PassSet> {
    let Some(v) = kw.take("passes")? else {
        return Ok(PassSet::compositing());
    };
    let list = match v.extract::<String>() {
        Ok(s) => s,
        Err(_) => {
            let names: Vec<String> = v.extract().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(
                    "passes must be a list of pass names or a string",
                )
            })?;
            if names.is_empty() {
                "none".to_owned()
            } else {
                names.join(",")
            }
        }
    };
    PassSet::parse(&list).map_err(|e| value_error(format!("invalid passes: {e}")))
}

/// `clamp_direct=`, `clamp_indirect=` (0 = off).
fn clamp(kw: &mut Kwargs<'_>) -> PyResult<Clamp> {
    let why = "must be finite and ≥ 0 (0 = no clamping)";
    Ok(Clamp {
        direct: kw.float("clamp_direct", non_negative, why)?.unwrap_or(0.0) as f32,
        indirect: kw
            .float("clamp_indirect", non_negative, why)?
            .unwrap_or(0.0) as f32,
    })
}

/// `filter=`: `box`, `gaussian` or `blackman-harris` (the default).
fn filter(kw: &mut Kwargs<'_>) -> PyResult<FilterKind> {
    let choices = [
        ("box", FilterKind::Box),
        ("gaussian", FilterKind::Gaussian),
        ("blackman-harris", FilterKind::BlackmanHarris),
    ];
    Ok(kw.choice("filter", &choices)?.unwrap_or_default())
}

/// `noise_threshold=` and `min_spp=`.
fn adaptive(kw: &mut Kwargs<'_>, spp: u32) -> PyResult<Option<AdaptiveOptions>> {
    let threshold = kw.float("noise_threshold", positive, "must be finite and > 0")?;
    let min_spp = kw.uint("min_spp", 1, 65536)?;
    match (threshold, min_spp) {
        (None, Some(_)) => Err(value_error("min_spp needs noise_threshold")),
        (None, None) => Ok(None),
        (Some(_), Some(m)) if m > spp => Err(value_error(format!(
            "invalid min_spp = {m}: must be at most spp ({spp})"
        ))),
        (Some(t), m) => Ok(Some(AdaptiveOptions {
            threshold: t as f32,
            min_spp: m.unwrap_or_else(|| AdaptiveOptions::auto_min_spp(spp)),
        })),
    }
}

/// `env=`: `(r, g, b)`, `"r,g,b"` or a file path.
fn env(kw: &mut Kwargs<'_>) -> PyResult<Option<EnvAsk>> {
    let Some(v) = kw.take("env")? else {
        return Ok(None);
    };
    let rgb: Vec<f64> = match v.extract::<String>() {
        Ok(s) if !s.contains(',') => return Ok(Some(EnvAsk::File(s))),
        Ok(s) => s
            .split(',')
            .map(|c| c.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| value_error(format!("invalid env = {s:?}: expected R,G,B")))?,
        Err(_) => v.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err("env must be (r, g, b) or a file path")
        })?,
    };
    match rgb.as_slice() {
        [r, g, b] if [r, g, b].iter().all(|c| non_negative(**c)) => Ok(Some(EnvAsk::Color(
            Vec3::new(*r as f32, *g as f32, *b as f32),
        ))),
        _ => Err(value_error(format!(
            "invalid env = {rgb:?}: three finite numbers ≥ 0"
        ))),
    }
}

/// `bvh_quality=`: `auto` (the default), `fast`, `medium` or `high`.
fn bvh_quality(kw: &mut Kwargs<'_>) -> PyResult<BvhQualityChoice> {
    let choices = [
        ("auto", BvhQualityChoice::Auto),
        ("fast", BvhQualityChoice::Preset(BvhQuality::Fast)),
        ("medium", BvhQualityChoice::Preset(BvhQuality::Medium)),
        ("high", BvhQualityChoice::Preset(BvhQuality::High)),
    ];
    Ok(kw.choice("bvh_quality", &choices)?.unwrap_or_default())
}

/// `motion_blur=` (True/False over the file's), `shutter=`, `shutter_position=`,
/// `motion_steps=`.
fn motion(kw: &mut Kwargs<'_>) -> PyResult<MotionOverrides> {
    let positions = [
        ("start", ShutterPosition::Start),
        ("center", ShutterPosition::Center),
        ("end", ShutterPosition::End),
    ];
    Ok(MotionOverrides {
        enabled: kw.flag("motion_blur")?,
        shutter: kw
            .float("shutter", positive, "must be finite and > 0")?
            .map(|s| s as f32),
        position: kw.choice("shutter_position", &positions)?,
        steps: kw.uint("motion_steps", 2, aperture_render::motion::MAX_MOTION_STEPS)?,
    })
}

/// The render `ask` asks of `session`: camera, image size, environment and BVH preset from
/// the scene posed at its time, as `aperture render` resolves them.
pub(crate) fn plan(session: &mut Session, ask: &RenderAsk, cancel: Cancel) -> PyResult<Plan> {
    let motion_extras = session.animated().motion_extras();
    let scene = session.pose(ask.time).map_err(crate::errors::load_error)?;
    let camera = match &ask.camera {
        None => 0,
        Some(c) => scene
            .select_camera(c)
            .map_err(|e| value_error(format!("invalid camera {c:?}: {e}")))?,
    };
    let cam = scene
        .cameras
        .get(camera)
        .ok_or_else(|| value_error("the scene has no camera"))?;
    let (width, height) = aperture_render::image_size(cam, ask.width, ask.height);
    let samples = u64::from(width) * u64::from(height) * u64::from(ask.base.spp);
    let quality = ask.bvh.resolve(scene.unique_triangle_count(), samples);
    let opts = RenderOptions {
        camera,
        width,
        height,
        env: environment(ask, scene)?,
        cancel,
        ..ask.base.clone()
    };
    let settings = MotionSettings::resolve(&motion_extras, &ask.motion);
    // Motion blur needs a time to put the shutter around (as the command line, which warns).
    let motion = settings.shutter.and(ask.time).map(|_| settings);
    let spec = FrameSpec {
        time: ask.time,
        fps: ask.fps,
        quality,
        motion,
        vector: ask.time.is_some() && opts.passes.contains(Pass::Vector),
        view: (camera, width, height),
    };
    Ok(Plan { opts, spec })
}

/// `env=` with its rotation and strength; without it, the file's image light, else black
/// (the command line's rule: `aperture_shading::choose_environment`).
fn environment(ask: &RenderAsk, scene: &aperture_scene::Scene) -> PyResult<Environment> {
    let asked = match &ask.env {
        None => None,
        Some(EnvAsk::Color(c)) => Some(EnvLight::Color(*c)),
        Some(EnvAsk::File(path)) => {
            let budget = aperture_budget::MemoryBudget::from_system().limit;
            let im = aperture_imageio::read_env_image(path.as_ref(), budget)
                .map_err(|e| value_error(format!("reading the environment {path}: {e}")))?;
            Some(EnvLight::Image {
                width: im.width,
                height: im.height,
                rgba: im.rgba,
            })
        }
    };
    Ok(aperture_shading::choose_environment(
        asked,
        scene,
        ask.env_rotation,
        ask.env_strength,
    ))
}
