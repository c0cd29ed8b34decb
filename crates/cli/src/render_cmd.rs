//! `aperture render`: scene in, EXR or PNG out.

use crate::progress::Progress;
use anyhow::Context as _;
use aperture_render::{
    EnvImage, EnvSampling, Environment, FilterKind, MaterialOverride, Pass, PassSet, RenderOptions,
    SamplerKind,
};
use aperture_scene::{DofOverrides, LoadOptions};
use clap::error::ErrorKind;
use clap::{CommandFactory as _, ValueEnum};
use glam::Vec3;
use std::path::PathBuf;
use std::time::Instant;

/// `--filter`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FilterArg {
    /// The 1-pixel box.
    Box,
    /// Gaussian, 1.5 px wide (as Cycles).
    Gaussian,
    /// Blackman-Harris, 1.5 px wide (Cycles' default).
    BlackmanHarris,
}

impl From<FilterArg> for FilterKind {
    fn from(f: FilterArg) -> Self {
        match f {
            FilterArg::Box => FilterKind::Box,
            FilterArg::Gaussian => FilterKind::Gaussian,
            FilterArg::BlackmanHarris => FilterKind::BlackmanHarris,
        }
    }
}

/// `--sampler`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SamplerArg {
    /// Owen-scrambled Sobol.
    Sobol,
    /// Independent uniform numbers, for comparison.
    Random,
}

/// `--override-material`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OverrideArg {
    /// Two-sided Lambertian of the base colour, emission kept (a "clay" render).
    Diffuse,
}

/// `--view`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ViewArg {
    /// Clip to [0, 1], then the sRGB transfer function.
    Standard,
    /// Blender's AgX base view (SPEC §6).
    Agx,
}

/// `--bvh-quality`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BvhQualityArg {
    /// Chosen from the job: `fast` when the render takes fewer samples than half the scene's
    /// triangles (a preview of a big scene), else `medium`.
    Auto,
    /// Fastest build.
    Fast,
    /// Balanced.
    Medium,
    /// Fastest traversal.
    High,
}

fn positive_f32(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number > 0, got {s}"))
    }
}

fn non_negative_f32(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number ≥ 0, got {s}"))
    }
}

fn finite_f32(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be a finite number, got {s}"))
    }
}

fn parse_rgb(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [r, g, b] = parts.as_slice() else {
        return Err(format!("expected R,G,B (three numbers), got {s:?}"));
    };
    let v = [r, g, b]
        .map(|c| non_negative_f32(c))
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// `--env`: a colour or an equirectangular HDR image.
#[derive(Debug, Clone, PartialEq)]
pub enum EnvArg {
    /// Uniform radiance, linear R,G,B.
    Color(Vec3),
    /// An equirectangular `.hdr` (Radiance RGBE) or `.exr` file.
    File(PathBuf),
}

/// A value with a comma is a colour; otherwise it names an `.hdr` or `.exr` file.
fn parse_env(s: &str) -> Result<EnvArg, String> {
    if s.contains(',') {
        return parse_rgb(s).map(EnvArg::Color);
    }
    let path = PathBuf::from(s);
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("hdr" | "exr") => Ok(EnvArg::File(path)),
        _ => Err(format!(
            "expected R,G,B or an equirectangular .hdr or .exr file, got {s:?}"
        )),
    }
}

/// Reads an equirectangular environment image (HDR or EXR, by content) as linear RGB
/// texels, rows top to bottom, refusing one whose texels would not fit `max_bytes`.
fn load_env_image(path: &std::path::Path, max_bytes: u64) -> anyhow::Result<(u32, u32, Vec<Vec3>)> {
    let im = aperture_imageio::read_env_image(path, max_bytes)?;
    let (w, h) = (im.width, im.height);
    let texels: Vec<Vec3> = im
        .rgba
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    if w == 0 || h == 0 {
        anyhow::bail!("the image has no pixels");
    }
    // Non-finite or negative texels would poison every sample that sees them.
    let texels = texels
        .into_iter()
        .map(|t: Vec3| {
            if t.is_finite() {
                t.max(Vec3::ZERO)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    Ok((w, h, texels))
}

/// How every render of `aperture render` and `aperture bench` is traced: bounces, clamps and
/// pixel filter (one definition, so both commands take the same options the same way).
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct TracingArgs {
    /// Maximum bounces, as Blender Cycles counts them (0 = direct light only).
    #[arg(long, default_value_t = aperture_render::DEFAULT_MAX_BOUNCES, value_parser = clap::value_parser!(u32).range(0..=1024))]
    pub max_bounces: u32,
    /// Cycles' "Clamp Direct": the most one sample may add (sum of R, G, B) for light seen
    /// directly or after one scattering; 0 = off. Biased: removes fireflies, darkens highlights.
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_f32)]
    pub clamp_direct: f32,
    /// Cycles' "Clamp Indirect" (Blender's default for new scenes is 10): the most one sample
    /// may add for light that scattered more than once; 0 = off (the default here: unbiased).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_f32)]
    pub clamp_indirect: f32,
    /// Pixel filter.
    #[arg(long, value_enum, default_value_t = FilterArg::BlackmanHarris)]
    pub filter: FilterArg,
}

impl TracingArgs {
    /// The clamps as the renderer takes them.
    pub fn clamp(&self) -> aperture_render::Clamp {
        aperture_render::Clamp {
            direct: self.clamp_direct,
            indirect: self.clamp_indirect,
        }
    }
}

/// Arguments of `aperture render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
    /// Output file; the format follows the extension (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Samples per pixel (1 to 65536).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
    /// Image width in pixels [default: 960, or from --height and the camera's aspect].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height in pixels [default: from the width and the camera's aspect ratio].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Camera by name or index [default: the first].
    #[arg(long)]
    pub camera: Option<String>,
    /// Which glTF scene of the file [default: the file's default scene].
    #[arg(long = "scene", value_name = "N")]
    pub scene_index: Option<usize>,
    /// Seed of every sample value (the image is a pure function of scene, options and seed).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=i32::MAX as i64))]
    pub seed: u32,
    /// Worker threads [default: all cores]. The image does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Lens radius in scene units (turns depth of field on; 0 = pinhole).
    #[arg(long, value_parser = non_negative_f32, allow_hyphen_values = true, conflicts_with_all = ["fstop", "no_dof"])]
    pub aperture_radius: Option<f32>,
    /// f-number: radius = focal length / (2 · F) (Cycles' rule).
    #[arg(long, value_parser = positive_f32, allow_hyphen_values = true, conflicts_with = "no_dof")]
    pub fstop: Option<f32>,
    /// Focus distance along the view axis, scene units.
    #[arg(long, value_parser = positive_f32, allow_hyphen_values = true, conflicts_with = "focus_object")]
    pub focus_distance: Option<f32>,
    /// Focus on a node's origin (node name, or index).
    #[arg(long)]
    pub focus_object: Option<String>,
    /// Pinhole camera whatever the file says.
    #[arg(long)]
    pub no_dof: bool,
    /// Bounces, clamps and pixel filter.
    #[command(flatten)]
    pub tracing: TracingArgs,
    /// Time, frame and animation (SPEC §7).
    #[command(flatten)]
    pub when: crate::time_args::TimeArgs,
    /// Transmission, variants and energy compensation (SPEC §5).
    #[command(flatten)]
    pub materials: crate::material_args::MaterialArgs,
    /// Sample sequence.
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    pub sampler: SamplerArg,
    /// Environment: uniform radiance as linear R,G,B, or an equirectangular .hdr or .exr image
    /// (importance-sampled by luminance) [default: black].
    #[arg(long, value_parser = parse_env, allow_hyphen_values = true)]
    pub env: Option<EnvArg>,
    /// Rotation of the environment image about the up axis (+Y), degrees, counter-clockwise
    /// seen from above.
    #[arg(long, default_value_t = 0.0, value_parser = finite_f32, allow_hyphen_values = true)]
    pub env_rotation: f32,
    /// Multiplier on the environment's radiance (image or colour).
    #[arg(long, default_value_t = 1.0, value_parser = non_negative_f32)]
    pub env_strength: f32,
    /// Exposure in stops applied before the PNG view transform.
    #[arg(long, default_value_t = 0.0, value_parser = finite_f32, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Render every surface with an override material.
    #[arg(long, value_enum)]
    pub override_material: Option<OverrideArg>,
    /// BVH build quality.
    #[arg(long, value_enum, default_value_t = BvhQualityArg::Auto)]
    pub bvh_quality: BvhQualityArg,
    /// View transform of PNG output.
    #[arg(long, value_enum, default_value_t = ViewArg::Standard)]
    pub view: ViewArg,
    /// Keep coverage as alpha in PNG output too (as Cycles' Film > Transparent). Without it a
    /// PNG is opaque: the environment (black by default) shows where nothing was hit, and dim
    /// partial coverage (bokeh against the sky) stays visible. EXR always stores coverage.
    #[arg(long)]
    pub transparent: bool,
    /// Adaptive sampling (after Blender Cycles'): a pixel stops once the estimated relative
    /// error of its mean (standard error over mean, from the samples' variance) is below this;
    /// smaller is cleaner and slower. Unlike Cycles' threshold (0.01 by default), which is
    /// relative to the square root of the brightness, dark pixels are held to the same relative
    /// error as bright ones. `--spp` becomes the most samples a pixel takes.
    #[arg(long, value_parser = positive_f32, allow_hyphen_values = true)]
    pub noise_threshold: Option<f32>,
    /// With --noise-threshold: samples every pixel takes before it may stop [default: 2√spp
    /// rounded up to a power of two, at least 4].
    #[arg(long, requires = "noise_threshold", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub min_spp: Option<u32>,
    /// EXR passes beside the beauty, with Blender's names: `default` (Depth, Normal, Denoising
    /// Albedo, Denoising Normal, CryptoObject, CryptoMaterial), `all` (adds the light passes
    /// and Position), `none`, or a comma-separated list such as `Depth,Normal,Emission`
    /// (`default,Position` adds to the default). PNG output has the beauty only.
    #[arg(long, default_value = "default", value_parser = PassSet::parse)]
    pub passes: PassSet,
    /// Colour passes (the beauty, light passes, denoising albedo) as half floats in EXR, clamped
    /// to ±65504 with a warning; data passes (depth, normals, IDs) stay float32.
    #[arg(long)]
    pub half: bool,
    /// Add the `Debug Sample Count` pass (the samples each pixel took); adaptive renders
    /// always have it. Same as adding `Debug Sample Count` to --passes.
    #[arg(long)]
    pub samples_pass: bool,
    /// The most memory the render may use (e.g. 8G, 512M) [default: the machine's memory, or
    /// its control group's limit]. Film, textures and geometry are sized against it before
    /// they are allocated; a job that cannot fit fails at once, saying what it needs.
    #[arg(long, value_parser = aperture_budget::parse_bytes)]
    pub max_memory: Option<u64>,
    /// On Ctrl-C (or SIGTERM), write the samples taken so far to the EXR (with `Debug Sample
    /// Count`, and `aperture:interrupted` = 1 in the header) instead of nothing. EXR only; not
    /// with --frames, where an interrupted frame is left unwritten so that --skip-existing
    /// renders it again.
    #[arg(long, conflicts_with = "frames")]
    pub save_partial: bool,
    /// A part of a render split across machines: --region, --tile, --sample-offset.
    #[command(flatten)]
    pub split: crate::split_args::SplitArgs,
    /// Render a sequence of frames (Blender's frame range: `1..250`, `1..250:2`); `#` in the
    /// output name become the zero-padded frame number (`shot_####.exr`). The file is loaded
    /// once, and only what moves is rebuilt per frame.
    #[arg(long, value_name = "A..B[:STEP]", value_parser = aperture_render::sequence::FrameRange::parse, conflicts_with_all = ["time", "frame"])]
    pub frames: Option<aperture_render::sequence::FrameRange>,
    /// With --frames: leave frames whose file already exists (a restarted job goes on where it
    /// stopped; files are written whole or not at all).
    #[arg(long, requires = "frames")]
    pub skip_existing: bool,
    /// No progress bar and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Progress display: a bar on a terminal, or JSON lines on stdout for programs (farm
    /// wrappers, the Blender engine).
    #[arg(long, value_enum, default_value_t = crate::progress::ProgressArg::Auto)]
    pub progress: crate::progress::ProgressArg,
}

/// A render stopped by a signal after writing its partial EXR (`--save-partial`).
#[derive(Debug, thiserror::Error)]
#[error("interrupted: {0} holds the samples taken so far (--save-partial)")]
pub struct Interrupted(pub String);

/// Checks the film and file of a `width`×`height` render against the memory and disk the job
/// has, printing the warnings; an error says what it needs and what there is.
fn check_footprint(
    args: &RenderArgs,
    opts: &RenderOptions,
    exr: &aperture_render::output::ExrOptions,
    budget: &aperture_budget::MemoryBudget,
) -> anyhow::Result<()> {
    let kind = if is_png(&args.output) {
        aperture_render::OutputKind::Png { sixteen_bit: false }
    } else {
        aperture_render::OutputKind::Exr
    };
    for w in aperture_render::check_output(opts, kind, exr, &args.output, budget)? {
        eprintln!("warning: {w}");
    }
    Ok(())
}

fn is_png(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
}

/// A usage error in clap's format, exit code 2 (as clap's own parse errors).
fn usage_error(msg: impl std::fmt::Display) -> ! {
    let mut cli = crate::Cli::command();
    let mut cmd = match cli.find_subcommand_mut("render") {
        Some(render) => render.clone().bin_name("aperture render"),
        None => cli,
    };
    cmd.error(ErrorKind::InvalidValue, msg).exit()
}

/// Runs `aperture render`.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("exr" | "png")) {
        usage_error(format!(
            "invalid value '{}' for '--output <OUTPUT>': the file must end in .exr or .png",
            args.output.display()
        ));
    }
    let budget = match args.max_memory {
        Some(bytes) => aperture_budget::MemoryBudget::fixed(bytes),
        None => aperture_budget::MemoryBudget::from_system(),
    };
    let load = LoadOptions {
        scene: args.scene_index,
        dof_overrides: DofOverrides {
            use_dof: args.no_dof.then_some(false),
            aperture_radius: args.aperture_radius,
            aperture_fstop: args.fstop,
            focus_distance: args.focus_distance,
            focus_object: args.focus_object.clone(),
        },
        skip_textures: false,
        variant: args.materials.variant.clone(),
        time: args.when.seconds(),
        animation: args.when.selection(),
        memory: budget,
    };
    let exr = aperture_render::output::ExrOptions {
        half: args.half,
        save_partial: args.save_partial,
        ..Default::default()
    };
    let passes = match args.samples_pass || args.save_partial {
        true => args.passes.with(Pass::SampleCount),
        false => args.passes,
    };
    if let (Some(width), Some(height)) = (args.width, args.height) {
        // Both sides known: checked before the scene is read.
        let early = RenderOptions {
            width,
            height,
            spp: args.spp,
            passes,
            adaptive: args
                .noise_threshold
                .map(|threshold| aperture_render::AdaptiveOptions {
                    threshold,
                    min_spp: 1,
                }),
            ..RenderOptions::default()
        };
        check_footprint(&args, &early, &exr, &budget)?;
    }
    let t_load = Instant::now();
    let posed = aperture_scene::Animated::load(&args.scene, &load).and_then(|animated| {
        // A sequence checks its cameras and sizes on its first frame.
        let first = args
            .frames
            .map(|f| (f.start as f64 / f64::from(args.when.fps)) as f32);
        let scene = animated.scene_at(first.or(load.time))?;
        Ok((animated, scene))
    });
    let (animated, scene) = match posed {
        Ok(s) => s,
        // A flag's value the scene refuses (`--focus-object` naming no node, `--scene 9`) is a
        // usage error like any other bad flag value: exit code 2.
        Err(e @ aperture_scene::Error::InvalidDof { .. }) if matches!(&e, aperture_scene::Error::InvalidDof { key, .. } if key.starts_with("command line")) => {
            usage_error(format!("{}: {e}", args.scene.display()))
        }
        Err(
            e @ (aperture_scene::Error::NoSuchScene { .. }
            | aperture_scene::Error::NoSuchAnimation { .. }
            | aperture_scene::Error::NoSuchVariant { .. }),
        ) => usage_error(format!("{}: {e}", args.scene.display())),
        Err(e) => {
            return Err(anyhow::Error::new(e).context(format!("loading {}", args.scene.display())))
        }
    };
    let camera_index = match &args.camera {
        None => 0,
        Some(c) => match scene.cameras.iter().position(|cam| &cam.name == c) {
            Some(i) => i,
            None => match c.parse::<usize>() {
                Ok(i) if i < scene.cameras.len() => i,
                _ => usage_error(format!(
                    "invalid value '{c}' for '--camera': the scene's cameras are {}",
                    scene
                        .cameras
                        .iter()
                        .enumerate()
                        .map(|(i, c)| format!("{i} ({:?})", c.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            },
        },
    };
    let cam = &scene.cameras[camera_index];
    let (width, height) = match (args.width, args.height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, aperture_render::default_height(cam, w)),
        (None, Some(h)) => {
            // The camera's aspect from the default 960-wide frame.
            let aspect = 960.0 / aperture_render::default_height(cam, 960) as f32;
            (((h as f32 * aspect).round() as u32).max(1), h)
        }
        (None, None) => (960, aperture_render::default_height(cam, 960)),
    };
    let quality = match args.bvh_quality {
        BvhQualityArg::Auto => aperture_render::auto_bvh_quality(
            scene.unique_triangle_count(),
            u64::from(width) * u64::from(height) * u64::from(args.spp),
        ),
        BvhQualityArg::Fast => aperture_accel::BvhQuality::Fast,
        BvhQualityArg::Medium => aperture_accel::BvhQuality::Medium,
        BvhQualityArg::High => aperture_accel::BvhQuality::High,
    };
    if args.min_spp.is_some_and(|m| m > args.spp) {
        usage_error(format!(
            "invalid value '{}' for '--min-spp': must be at most --spp ({})",
            args.min_spp.unwrap_or(0),
            args.spp
        ));
    }
    let part = args
        .split
        .window(width, height)
        .unwrap_or_else(|e| usage_error(e));
    if part.is_some() && ext.as_deref() != Some("exr") {
        usage_error(
            "--region and --tile need .exr output: its data window records where the pixels belong",
        );
    }
    if args.split.sample_offset > 0 && args.noise_threshold.is_some() {
        usage_error(
            "--sample-offset cannot be used with --noise-threshold: adaptive sampling decides from \
             every sample of a pixel from the first (split an adaptive render with --tile instead)",
        );
    }
    if u64::from(args.split.sample_offset) + u64::from(args.spp) > 65536 {
        usage_error(format!(
            "invalid value '{}' for '--sample-offset': with --spp {} it passes the sampler's 65536 samples",
            args.split.sample_offset, args.spp
        ));
    }
    let adaptive = args
        .noise_threshold
        .map(|threshold| aperture_render::AdaptiveOptions {
            threshold,
            min_spp: args
                .min_spp
                .unwrap_or_else(|| aperture_render::AdaptiveOptions::auto_min_spp(args.spp)),
        });
    let opts = RenderOptions {
        adaptive,
        width,
        height,
        spp: args.spp,
        sample_offset: args.split.sample_offset,
        seed: args.seed,
        camera: camera_index,
        max_bounces: args.tracing.max_bounces,
        clamp: args.tracing.clamp(),
        filter: args.tracing.filter.into(),
        transmission: args.materials.transmission,
        energy_compensation: !args.materials.no_energy_compensation,
        sampler: match args.sampler {
            SamplerArg::Sobol => SamplerKind::Sobol,
            SamplerArg::Random => SamplerKind::Random,
        },
        env: match &args.env {
            None => Environment::Constant(Vec3::ZERO),
            Some(EnvArg::Color(c)) => Environment::Constant(*c * args.env_strength),
            Some(EnvArg::File(path)) => {
                let (width, height, texels) = load_env_image(path, budget.limit)
                    .with_context(|| format!("reading the environment {}", path.display()))?;
                Environment::Image(std::sync::Arc::new(EnvImage {
                    width,
                    height,
                    texels,
                    rotation: args.env_rotation.to_radians(),
                    strength: args.env_strength,
                    sampling: EnvSampling::Importance,
                }))
            }
        },
        material_override: match args.override_material {
            Some(OverrideArg::Diffuse) => MaterialOverride::Diffuse,
            None => MaterialOverride::None,
        },
        passes,
        cancel: crate::interrupt::install()?,
    };
    check_footprint(&args, &opts, &exr, &budget)?;

    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(t) = args.threads {
            b = b.num_threads(t as usize);
        }
        b.build().context("starting worker threads")?
    };
    if let Some(frames) = args.frames {
        return crate::frames::run(&args, &animated, frames, &opts, quality, &pool);
    }
    let hints = aperture_render::sequence::SceneHints::new(&animated, &scene);
    drop(animated);
    let png = aperture_imageio::PngOptions {
        exposure: args.exposure,
        view: match args.view {
            ViewArg::Standard => aperture_imageio::ViewTransform::Standard,
            ViewArg::Agx => aperture_imageio::ViewTransform::AgX,
        },
        ..Default::default()
    };
    let exr = aperture_render::output::ExrOptions {
        half: args.half,
        save_partial: args.save_partial,
        region: part.map(|p| p.window),
        tile: part.and_then(|p| p.tile),
        ..Default::default()
    };
    let (summary, load_secs) = pool.install(|| -> anyhow::Result<_> {
        // The same structure a sequence builds for this frame, so their images agree bit for bit.
        let accel = aperture_render::sequence::build_frame_accel(&scene, quality, &hints, None);
        let load_secs = t_load.elapsed().as_secs_f64();
        let progress = Progress::with_mode(args.quiet, args.progress);
        progress.set_samples(
            u64::from(width) * u64::from(height) * u64::from(args.spp),
            None,
        );
        let report = |done, total| progress.update(done, total);
        let summary = if ext.as_deref() == Some("png") {
            aperture_render::output::render_png(
                &scene,
                &accel,
                &opts,
                &args.output,
                &png,
                args.transparent,
                &report,
            )
        } else {
            aperture_render::output::render_exr(&scene, &accel, &opts, &args.output, &exr, &report)
        };
        progress.finish();
        let summary = summary.with_context(|| format!("writing {}", args.output.display()))?;
        progress.frame_written(args.when.frame, &args.output, summary.render_secs);
        Ok((summary, load_secs))
    })?;

    if opts.cancel.is_cancelled() {
        return Err(Interrupted(args.output.display().to_string()).into());
    }
    if summary.half_clamped > 0 {
        eprintln!(
            "warning: {}: {} colour values beyond ±65504 were clamped to fit half floats (--half)",
            args.output.display(),
            summary.half_clamped
        );
    }
    let dropped = summary.dropped;
    if !args.quiet || dropped > 0 {
        let spp = match opts.adaptive {
            None if opts.sample_offset > 0 => format!(
                "{} spp (samples {}..{})",
                opts.spp,
                opts.sample_offset,
                opts.sample_offset + opts.spp
            ),
            None => format!("{} spp", opts.spp),
            Some(a) => format!(
                "adaptive {}..{} spp (mean {:.1}, threshold {})",
                a.min_spp,
                opts.spp,
                summary.mean_spp(),
                a.threshold
            ),
        };
        let render_secs = summary.render_secs;
        let size = match part {
            Some(p) => format!(
                "region {} of {width}x{height}",
                aperture_render::output::header::region_text(&p.window)
            ),
            None => format!("{width}x{height}"),
        };
        eprintln!(
            "{}: {size}, {spp}, {render_secs:.2} s ({load_secs:.2} s loading, BVH {quality}), {:.2} Msamples/s, {dropped} dropped samples (NaN/Inf)",
            args.output.display(),
            summary.samples as f64 / render_secs.max(1e-9) / 1e6,
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser as _;

    fn parse(args: &[&str]) -> Result<RenderArgs, clap::Error> {
        let mut argv = vec!["aperture", "render", "s.glb", "-o", "o.exr"];
        argv.extend_from_slice(args);
        match crate::Cli::try_parse_from(argv)?.command {
            crate::Command::Render(r) => Ok(r),
            _ => unreachable!("render subcommand"),
        }
    }

    #[test]
    fn passes_and_half_parse() {
        let a = parse(&[]).unwrap();
        assert_eq!(a.passes, PassSet::compositing());
        assert!(!a.half);
        let b = parse(&["--passes", "all,Debug Sample Count", "--half"]).unwrap();
        assert!(
            b.half && b.passes.contains(Pass::Position) && b.passes.contains(Pass::SampleCount)
        );
        assert_eq!(parse(&["--passes", "none"]).unwrap().passes, PassSet::NONE);
        let e = parse(&["--passes", "Depth,Albedo"]).expect_err("unknown pass");
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("Albedo"), "{e}");
    }

    #[test]
    fn defaults_follow_the_issue() {
        let a = parse(&[]).unwrap();
        assert_eq!(a.tracing.max_bounces, 12);
        assert_eq!(a.tracing.filter, FilterArg::BlackmanHarris);
        assert_eq!(a.sampler, SamplerArg::Sobol);
        assert_eq!(a.env, None);
        assert_eq!(a.width, None);
    }

    #[test]
    fn bad_values_are_usage_errors() {
        for bad in [
            &["--spp", "0"][..],
            &["--aperture-radius", "-0.5"],
            &["--fstop", "0"],
            &["--env", "1,2"],
            &["--env", "1,nan,2"],
            &["--env", "sky.png"],
            &["--env-strength", "-1"],
            &["--env-rotation", "inf"],
            &["--filter", "mitchell"],
            &["--aperture-radius", "0.1", "--fstop", "2"],
            &["--focus-distance", "3", "--focus-object", "Cube"],
            &["--no-dof", "--aperture-radius", "0.1"],
            &["--sampler", "halton"],
            &["--noise-threshold", "0"],
            &["--noise-threshold", "-0.1"],
            &["--min-spp", "4"],
            &["--noise-threshold", "0.01", "--min-spp", "0"],
            &["--clamp-indirect", "-1"],
            &["--clamp-direct", "nan"],
            &["--tile", "4/4"],
            &["--tile", "1"],
            &["--region", "1,2,3"],
            &["--region", "1,1,1,2"],
            &["--region", "0,0,4,4", "--tile", "0/2"],
            &["--sample-offset", "65536"],
            &["--sample-offset", "-64"],
        ] {
            let e = parse(bad).expect_err("must be refused");
            assert_eq!(e.exit_code(), 2, "{bad:?}");
        }
    }

    #[test]
    fn good_values_parse() {
        let a = parse(&[
            "--env",
            "0.5, 1,2",
            "--exposure",
            "-1.5",
            "--override-material",
            "diffuse",
            "--view",
            "agx",
            "--scene",
            "1",
            "--camera",
            "Main",
            "--aperture-radius",
            "0",
        ])
        .unwrap();
        assert_eq!(a.env, Some(EnvArg::Color(Vec3::new(0.5, 1.0, 2.0))));
        let b = parse(&[
            "--env",
            "sky.HDR",
            "--env-rotation",
            "-90",
            "--env-strength",
            "2.5",
        ])
        .unwrap();
        assert_eq!(b.env, Some(EnvArg::File("sky.HDR".into())));
        assert_eq!((b.env_rotation, b.env_strength), (-90.0, 2.5));
        assert_eq!(a.exposure, -1.5);
        assert_eq!(a.override_material, Some(OverrideArg::Diffuse));
        assert_eq!(a.view, ViewArg::Agx);
        assert_eq!(a.scene_index, Some(1));
        assert_eq!(a.aperture_radius, Some(0.0));
        assert_eq!(a.tracing.clamp(), aperture_render::Clamp::OFF);
        let c = parse(&["--clamp-indirect", "10", "--clamp-direct", "100"]).unwrap();
        assert_eq!(
            (c.tracing.clamp_direct, c.tracing.clamp_indirect),
            (100.0, 10.0)
        );
    }

    /// Runs `aperture render SCENE -o <temp>/NAME.exr ARGS` and returns the EXR read back (the
    /// file is removed).
    fn render_exr(scene: &std::path::Path, name: &str, argv: &[&str]) -> aperture_imageio::Image {
        let out =
            std::env::temp_dir().join(format!("aperture-cli-{}-{name}.exr", std::process::id()));
        let mut args = parse(argv).unwrap();
        args.scene = scene.to_path_buf();
        args.output = out.clone();
        run(args).unwrap();
        let image = aperture_imageio::read_exr(&out).unwrap();
        std::fs::remove_file(&out).unwrap();
        image
    }

    /// The whole command on a real sample: EXR out, read back; `--threads 1` and `--threads 2`
    /// give the same pixels.
    #[test]
    fn renders_a_sample_to_exr_identically_for_any_thread_count() {
        let Some(box_glb) = crate::box_textured_sample() else {
            return;
        };
        let images: Vec<_> = ["1", "2"]
            .map(|threads| {
                render_exr(
                    &box_glb,
                    threads,
                    &[
                        "--width",
                        "24",
                        "--height",
                        "16",
                        "--spp",
                        "2",
                        "--threads",
                        threads,
                        "--env",
                        "1,1,1",
                        "--quiet",
                    ],
                )
            })
            .into();
        assert_eq!(images[0].rgba, images[1].rgba);
        // Adaptive sampling with the samples pass: the layer holds each pixel's count.
        let adaptive = render_exr(
            &box_glb,
            "adaptive",
            &[
                "--width",
                "24",
                "--height",
                "16",
                "--spp",
                "16",
                "--noise-threshold",
                "0.05",
                "--min-spp",
                "4",
                "--samples-pass",
                "--env",
                "1,1,1",
                "--quiet",
            ],
        );
        let counts = &adaptive
            .layer("Debug Sample Count")
            .expect("sample count layer")
            .data;
        assert_eq!(counts.len(), 24 * 16);
        assert!(counts.iter().all(|&n| (4.0..=16.0).contains(&n)));
        // The uniform environment converges at the minimum; the box's edges do not.
        assert!(
            counts.contains(&4.0) && counts.contains(&16.0),
            "{counts:?}"
        );
        assert_eq!((images[0].width, images[0].height), (24, 16));
        assert!(images[0].rgba.iter().any(|p| p[3] == 1.0));
        assert_eq!(
            images[0].meta("aperture:spp"),
            Some(&aperture_imageio::MetaValue::Int(2))
        );
    }

    /// `--env FILE.hdr` and `--env FILE.exr` with a constant colour light a scene like the
    /// same `--env R,G,B`; `--env-strength 2` doubles it.
    #[test]
    fn environment_files_light_like_the_constant_colour() {
        let Some(box_glb) = crate::box_textured_sample() else {
            return;
        };
        let dir = std::env::temp_dir();
        let id = std::process::id();
        let c = [0.4f32, 0.6, 0.9];
        let hdr = dir.join(format!("aperture-env-{id}.hdr"));
        image::DynamicImage::ImageRgb32F(image::Rgb32FImage::from_pixel(16, 8, image::Rgb(c)))
            .save(&hdr)
            .unwrap();
        let exr = dir.join(format!("aperture-env-{id}.exr"));
        let mut im = aperture_imageio::Image::new(16, 8);
        im.rgba = vec![[c[0], c[1], c[2], 1.0]; 16 * 8];
        aperture_imageio::write_exr(&exr, &im).unwrap();
        let mean = |env: &[&str]| {
            let mut argv = vec!["--width", "24", "--height", "16", "--spp", "16", "--quiet"];
            argv.extend_from_slice(env);
            let img = render_exr(&box_glb, "env-out", &argv);
            let n = img.rgba.len() as f32;
            img.rgba
                .iter()
                .fold(Vec3::ZERO, |s, p| s + Vec3::new(p[0], p[1], p[2]))
                / n
        };
        let constant = mean(&["--env", "0.4,0.6,0.9"]);
        let hdr_s = hdr.to_str().unwrap().to_owned();
        let exr_s = exr.to_str().unwrap().to_owned();
        let from_hdr = mean(&["--env", &hdr_s, "--env-rotation", "30"]);
        let from_exr = mean(&["--env", &exr_s]);
        let doubled = mean(&["--env", &exr_s, "--env-strength", "2"]);
        std::fs::remove_file(&hdr).unwrap();
        std::fs::remove_file(&exr).unwrap();
        // RGBE stores 8-bit mantissas: about 1% error.
        assert!(
            (from_hdr - constant).abs().max_element() < 0.03 * constant.max_element(),
            "{from_hdr} vs {constant}"
        );
        assert!(
            (from_exr - constant).abs().max_element() < 0.02 * constant.max_element(),
            "{from_exr} vs {constant}"
        );
        assert!(
            (doubled - 2.0 * from_exr).abs().max_element() < 0.02 * doubled.max_element(),
            "{doubled} vs 2 × {from_exr}"
        );
    }
}
