//! What `aperture render`'s arguments ask for, as the options the loader, the renderer and the
//! PNG writer take; a flag value that cannot work is a usage error (exit code 2).

use crate::render_args::{EnvArg, RenderArgs};
use anyhow::Context as _;
use aperture_render::{Pass, RenderOptions};
use aperture_scene::{DofOverrides, LoadOptions};
use aperture_shading::{EnvLight, Environment, MaterialOverride};
use clap::error::ErrorKind;
use clap::CommandFactory as _;

/// A usage error in clap's format, exit code 2 (as clap's own parse errors).
pub(crate) fn usage_error(msg: impl std::fmt::Display) -> ! {
    let mut cli = crate::Cli::command();
    let mut cmd = match cli.find_subcommand_mut("render") {
        Some(render) => render.clone().bin_name("aperture render"),
        None => cli,
    };
    cmd.error(ErrorKind::InvalidValue, msg).exit()
}

/// What the arguments give before the scene is read: the output kind, the memory budget, the
/// loader's options, the EXR writer's options and the passes.
pub(crate) struct BeforeLoad {
    pub png_out: bool,
    pub budget: aperture_budget::MemoryBudget,
    pub load: LoadOptions,
    pub exr: aperture_output::ExrOptions,
    pub passes: aperture_render::PassSet,
}

/// The arguments read before the scene: usage errors first, and the film and file checked
/// against the machine when both sides of the image are given.
pub(crate) fn before_load(args: &RenderArgs) -> anyhow::Result<BeforeLoad> {
    let png_out = output_is_png(args);
    let budget = memory_budget(args);
    let load = load_options(args, budget);
    let exr = aperture_output::ExrOptions {
        half: args.half,
        save_partial: args.save_partial,
        ..Default::default()
    };
    let passes = passes(args);
    if let (Some(width), Some(height)) = (args.width, args.height) {
        // Both sides known: checked before the scene is read.
        let early = RenderOptions {
            width,
            height,
            passes,
            ..render_options(args)
        };
        check_footprint(args, png_out, &early, &exr, &budget)?;
    }
    Ok(BeforeLoad {
        png_out,
        budget,
        load,
        exr,
        passes,
    })
}

/// The file loaded into a session; a flag's value the scene refuses (`--focus-object` naming
/// no node, `--scene 9`) is a usage error like any other bad flag value: exit code 2.
pub(crate) fn load_session(
    args: &RenderArgs,
    load: &LoadOptions,
) -> anyhow::Result<aperture_render::Session> {
    use aperture_render::{Session, SessionError};
    use aperture_scene::Error;
    let context = || format!("loading {}", args.scene.display());
    match Session::load(&args.scene, load) {
        Ok(s) => Ok(s),
        Err(SessionError::Scene(e)) => match e {
            Error::InvalidDof { ref key, .. } if key.starts_with("command line") => {
                usage_error(format!("{}: {e}", args.scene.display()))
            }
            Error::NoSuchScene { .. }
            | Error::NoSuchAnimation { .. }
            | Error::NoSuchVariant { .. } => usage_error(format!("{}: {e}", args.scene.display())),
            e => Err(anyhow::Error::new(e).context(context())),
        },
        Err(e) => Err(anyhow::Error::new(e).context(context())),
    }
}

/// What the arguments ask of the loaded scene: the render's options, the EXR writer's (with the
/// part of the image), the BVH quality and the part.
pub(crate) struct RenderPlan {
    pub opts: RenderOptions,
    /// How the image (or each frame) is written: PNG with its options, or EXR.
    pub format: aperture_output::write::ImageFormat,
    pub quality: aperture_accel::BvhQuality,
    pub part: Option<crate::split_args::ImagePart>,
}

/// The arguments read against the loaded scene (camera, image size, BVH quality, the part of the
/// image, the environment), checked against the machine's memory and disk.
pub(crate) fn after_load(
    args: &RenderArgs,
    before: &BeforeLoad,
    scene: &aperture_scene::Scene,
) -> anyhow::Result<RenderPlan> {
    let camera = camera_index(args, scene);
    let (width, height) =
        aperture_render::image_size(&scene.cameras[camera], args.width, args.height);
    let quality = bvh_quality(args, scene, width, height);
    check_split_and_spp(args);
    let part = image_part(args, width, height, before.png_out);
    let opts = RenderOptions {
        camera,
        width,
        height,
        passes: before.passes,
        env: environment(args, scene, before.budget.limit)?,
        cancel: crate::interrupt::install()?,
        ..render_options(args)
    };
    check_footprint(args, before.png_out, &opts, &before.exr, &before.budget)?;
    // --region/--tile apply to every frame of a sequence too.
    let exr = aperture_output::ExrOptions {
        region: part.map(|p| p.window),
        tile: part.and_then(|p| p.tile),
        ..before.exr
    };
    Ok(RenderPlan {
        opts,
        format: frame_format(args, before.png_out, exr),
        quality,
        part,
    })
}

/// Checks the film and file of a `width`×`height` render against the memory and disk the job
/// has, printing the warnings; an error says what it needs and what there is.
fn check_footprint(
    args: &RenderArgs,
    png_out: bool,
    opts: &RenderOptions,
    exr: &aperture_output::ExrOptions,
    budget: &aperture_budget::MemoryBudget,
) -> anyhow::Result<()> {
    let kind = if png_out {
        aperture_output::OutputKind::Png { sixteen_bit: false }
    } else if args.denoise {
        aperture_output::OutputKind::ExrDenoised
    } else {
        aperture_output::OutputKind::Exr
    };
    for w in aperture_output::check_output(opts, kind, exr, &args.output, budget)? {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// Whether the output is a PNG (else an EXR); any other extension is a usage error.
fn output_is_png(args: &RenderArgs) -> bool {
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => true,
        Some("exr") => false,
        _ => usage_error(format!(
            "invalid value '{}' for '--output <OUTPUT>': the file must end in .exr or .png",
            args.output.display()
        )),
    }
}

/// `--max-memory`, else what the machine (or the job's limit) has.
fn memory_budget(args: &RenderArgs) -> aperture_budget::MemoryBudget {
    match args.max_memory {
        Some(bytes) => aperture_budget::MemoryBudget::fixed(bytes),
        None => aperture_budget::MemoryBudget::from_system(),
    }
}

/// `--passes`, with the sample count when `--samples-pass` or `--save-partial` asks for it.
fn passes(args: &RenderArgs) -> aperture_render::PassSet {
    match args.samples_pass || args.save_partial {
        true => args.passes.with(Pass::SampleCount),
        false => args.passes,
    }
}

/// `--region`/`--tile` as the part of the `width`×`height` image to render; they need EXR
/// output.
fn image_part(
    args: &RenderArgs,
    width: u32,
    height: u32,
    png_out: bool,
) -> Option<crate::split_args::ImagePart> {
    let part = args
        .split
        .window(width, height)
        .unwrap_or_else(|e| usage_error(e));
    if part.is_some() && png_out {
        usage_error(
            "--region and --tile need .exr output: its data window records where the pixels belong",
        );
    }
    part
}

/// How a sequence's frames are written: PNG (`--exposure`, `--view`, `--transparent`) or EXR.
fn frame_format(
    args: &RenderArgs,
    png_out: bool,
    exr: aperture_output::ExrOptions,
) -> aperture_output::write::ImageFormat {
    if png_out {
        aperture_output::write::ImageFormat::Png {
            png: png_options(args),
            transparent: args.transparent,
        }
    } else {
        aperture_output::write::ImageFormat::Exr(exr)
    }
}

/// What the loader needs of the arguments.
fn load_options(args: &RenderArgs, memory: aperture_budget::MemoryBudget) -> LoadOptions {
    LoadOptions {
        scene: args.scene_index,
        dof_overrides: DofOverrides {
            use_dof: args.no_dof.then_some(false),
            aperture_radius: args.aperture_radius,
            aperture_fstop: args.fstop,
            focus_distance: args.focus_distance,
            focus_object: args.focus_object.clone(),
            vignetting: args.aperture_vignetting,
            distortion: args.distortion,
            lens_prescription: args.lens_prescription.clone(),
            aperture_image: args.aperture_image.clone(),
            chromatic_lateral: args.chromatic_lateral,
            chromatic_longitudinal: args.chromatic_longitudinal,
        },
        skip_textures: false,
        variant: args.materials.variant.clone(),
        time: args.when.seconds(),
        animation: args.when.selection(),
        memory,
    }
}

/// `--camera` (a name, a glTF camera index or `node:J`) as an index into the scene's cameras.
fn camera_index(args: &RenderArgs, scene: &aperture_scene::Scene) -> usize {
    match &args.camera {
        None => 0,
        Some(c) => find_camera(c, scene).unwrap_or_else(|e| usage_error(e)),
    }
}

/// `--camera` (a name, a glTF camera index or `node:J`) as an index into the scene's cameras;
/// the error lists the cameras there are.
pub(crate) fn find_camera(c: &str, scene: &aperture_scene::Scene) -> Result<usize, String> {
    scene
        .select_camera(c)
        .map_err(|e| format!("invalid value '{c}' for '--camera': {e}"))
}

/// `--bvh-quality`; `auto` chooses from the triangles and the samples to trace.
fn bvh_quality(
    args: &RenderArgs,
    scene: &aperture_scene::Scene,
    width: u32,
    height: u32,
) -> aperture_accel::BvhQuality {
    args.bvh_quality.resolve(
        scene.unique_triangle_count(),
        u64::from(width) * u64::from(height) * u64::from(args.spp),
    )
}

/// Combinations of sample counts and splitting flags that cannot work: usage errors.
fn check_split_and_spp(args: &RenderArgs) {
    if args.min_spp.is_some_and(|m| m > args.spp) {
        usage_error(format!(
            "invalid value '{}' for '--min-spp': must be at most --spp ({})",
            args.min_spp.unwrap_or(0),
            args.spp
        ));
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
}

/// The render options the arguments give, less the image size, camera, passes, environment and
/// cancellation (which need the scene or the machine).
fn render_options(args: &RenderArgs) -> RenderOptions {
    RenderOptions {
        adaptive: args
            .noise_threshold
            .map(|threshold| aperture_render::AdaptiveOptions {
                threshold,
                min_spp: args
                    .min_spp
                    .unwrap_or_else(|| aperture_render::AdaptiveOptions::auto_min_spp(args.spp)),
            }),
        spp: args.spp,
        sample_offset: args.split.sample_offset,
        seed: args.seed,
        max_bounces: args.tracing.max_bounces,
        clamp: args.tracing.clamp(),
        filter: args.tracing.filter,
        transmission: args.materials.transmission,
        single_sided: args.materials.single_sided,
        energy_compensation: !args.materials.no_energy_compensation,
        sampler: args.sampler,
        material_override: args.override_material.unwrap_or(MaterialOverride::None),
        ..RenderOptions::default()
    }
}

/// `--env` with `--env-rotation` and `--env-strength`; without it, the file's image light,
/// else black.
fn environment(
    args: &RenderArgs,
    scene: &aperture_scene::Scene,
    max_bytes: u64,
) -> anyhow::Result<Environment> {
    let asked = match &args.env {
        None => None,
        Some(EnvArg::Color(c)) => Some(EnvLight::Color(*c)),
        Some(EnvArg::File(path)) => Some(
            load_env_image(path, max_bytes)
                .with_context(|| format!("reading the environment {}", path.display()))?,
        ),
    };
    Ok(aperture_shading::choose_environment(
        asked,
        scene,
        args.env_rotation,
        args.env_strength,
    ))
}

/// `--exposure`, `--view`.
fn png_options(args: &RenderArgs) -> aperture_imageio::PngOptions {
    aperture_imageio::PngOptions {
        exposure: args.exposure,
        view: args.view,
        ..Default::default()
    }
}

/// An environment image's texels (`--env FILE`), within `max_bytes`.
fn load_env_image(path: &std::path::Path, max_bytes: u64) -> anyhow::Result<EnvLight> {
    let im = aperture_imageio::read_env_image(path, max_bytes)?;
    if im.width == 0 || im.height == 0 {
        anyhow::bail!("the image has no pixels");
    }
    Ok(EnvLight::Image {
        width: im.width,
        height: im.height,
        rgba: im.rgba,
    })
}
