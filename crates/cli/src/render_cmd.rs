//! `aperture render`: scene in, EXR or PNG out.

use crate::progress::Progress;
use crate::render_args::{BvhQualityArg, EnvArg, OverrideArg, RenderArgs, SamplerArg, ViewArg};
use anyhow::Context as _;
use aperture_render::{
    EnvImage, EnvSampling, Environment, MaterialOverride, Pass, RenderOptions, SamplerKind,
};
use aperture_scene::{DofOverrides, LoadOptions};
use clap::error::ErrorKind;
use clap::CommandFactory as _;
use glam::Vec3;
use std::time::Instant;

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

/// A render stopped by a signal after writing its partial EXR (`--save-partial`).
#[derive(Debug, thiserror::Error)]
#[error("interrupted: {0} holds the samples taken so far (--save-partial)")]
pub struct Interrupted(pub String);

/// Checks the film and file of a `width`×`height` render against the memory and disk the job
/// has, printing the warnings; an error says what it needs and what there is.
fn check_footprint(
    args: &RenderArgs,
    opts: &RenderOptions,
    exr: &aperture_output::ExrOptions,
    budget: &aperture_budget::MemoryBudget,
) -> anyhow::Result<()> {
    let kind = if is_png(&args.output) {
        aperture_output::OutputKind::Png { sixteen_bit: false }
    } else {
        aperture_output::OutputKind::Exr
    };
    for w in aperture_output::check_output(opts, kind, exr, &args.output, budget)? {
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
    let png_out = output_is_png(&args);
    let budget = match args.max_memory {
        Some(bytes) => aperture_budget::MemoryBudget::fixed(bytes),
        None => aperture_budget::MemoryBudget::from_system(),
    };
    let load = load_options(&args, budget);
    let exr = aperture_output::ExrOptions {
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
            passes,
            ..render_options(&args)
        };
        check_footprint(&args, &early, &exr, &budget)?;
    }
    let t_load = Instant::now();
    let (animated, scene) = load_posed(&args, &load)?;
    let camera = camera_index(&args, &scene);
    let (width, height) = image_size(&args, &scene.cameras[camera]);
    let quality = bvh_quality(&args, &scene, width, height);
    check_split_and_spp(&args);
    let part = args
        .split
        .window(width, height)
        .unwrap_or_else(|e| usage_error(e));
    if part.is_some() && png_out {
        usage_error(
            "--region and --tile need .exr output: its data window records where the pixels belong",
        );
    }
    let opts = RenderOptions {
        camera,
        width,
        height,
        passes,
        env: environment(&args, budget.limit)?,
        cancel: crate::interrupt::install()?,
        ..render_options(&args)
    };
    check_footprint(&args, &opts, &exr, &budget)?;

    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = args.threads {
        pool = pool.num_threads(t as usize);
    }
    let pool = pool.build().context("starting worker threads")?;
    // --region/--tile apply to every frame of a sequence too.
    let exr = aperture_output::ExrOptions {
        region: part.map(|p| p.window),
        tile: part.and_then(|p| p.tile),
        ..exr
    };
    if let Some(frames) = args.frames {
        let format = if png_out {
            aperture_output::sequence::FrameFormat::Png {
                png: png_options(&args),
                transparent: args.transparent,
            }
        } else {
            aperture_output::sequence::FrameFormat::Exr(exr)
        };
        return crate::frames::run(&args, &animated, frames, format, &opts, quality, &pool);
    }
    let hints = aperture_render::SceneHints::new(&animated, &scene);
    drop(animated);
    let (summary, load_secs) = pool.install(|| -> anyhow::Result<_> {
        // The same structure a sequence builds for this frame, so their images agree bit for bit.
        let accel = aperture_render::build_frame_accel(&scene, quality, &hints, None);
        let load_secs = t_load.elapsed().as_secs_f64();
        let summary = write_image(&args, &scene, &accel, &opts, &exr, png_out)?;
        Ok((summary, load_secs))
    })?;

    if opts.cancel.is_cancelled() {
        return Err(Interrupted(args.output.display().to_string()).into());
    }
    print_summary(&args, &opts, &summary, load_secs, quality, part);
    Ok(())
}

/// Renders the still image and writes it, showing progress.
fn write_image(
    args: &RenderArgs,
    scene: &aperture_scene::Scene,
    accel: &aperture_accel::Accel,
    opts: &RenderOptions,
    exr: &aperture_output::ExrOptions,
    png_out: bool,
) -> anyhow::Result<aperture_output::RenderSummary> {
    let progress = Progress::with_mode(args.quiet, args.progress);
    progress.set_samples(
        u64::from(opts.width) * u64::from(opts.height) * u64::from(args.spp),
        None,
    );
    let report = |done, total| progress.update(done, total);
    let summary = if png_out {
        aperture_output::render_png(
            scene,
            accel,
            opts,
            &args.output,
            &png_options(args),
            args.transparent,
            &report,
        )
    } else {
        aperture_output::render_exr(scene, accel, opts, &args.output, exr, &report)
    };
    progress.finish();
    let summary = summary.with_context(|| format!("writing {}", args.output.display()))?;
    progress.frame_written(args.when.frame, &args.output, summary.render_secs);
    Ok(summary)
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
        },
        skip_textures: false,
        variant: args.materials.variant.clone(),
        time: args.when.seconds(),
        animation: args.when.selection(),
        memory,
    }
}

/// The file loaded and posed at the time asked for (a sequence's first frame); a flag's value
/// the scene refuses (`--focus-object` naming no node, `--scene 9`) is a usage error like any
/// other bad flag value: exit code 2.
fn load_posed(
    args: &RenderArgs,
    load: &LoadOptions,
) -> anyhow::Result<(aperture_scene::Animated, aperture_scene::Scene)> {
    use aperture_scene::Error;
    let posed = aperture_scene::Animated::load(&args.scene, load).and_then(|animated| {
        let first = args
            .frames
            .map(|f| (f.start as f64 / f64::from(args.when.fps)) as f32);
        let scene = animated.scene_at(first.or(load.time))?;
        Ok((animated, scene))
    });
    match posed {
        Ok(s) => Ok(s),
        Err(e @ Error::InvalidDof { .. }) if matches!(&e, Error::InvalidDof { key, .. } if key.starts_with("command line")) => {
            usage_error(format!("{}: {e}", args.scene.display()))
        }
        Err(
            e @ (Error::NoSuchScene { .. }
            | Error::NoSuchAnimation { .. }
            | Error::NoSuchVariant { .. }),
        ) => usage_error(format!("{}: {e}", args.scene.display())),
        Err(e) => Err(anyhow::Error::new(e).context(format!("loading {}", args.scene.display()))),
    }
}

/// `--camera` (a name, else an index) as an index into the scene's cameras.
fn camera_index(args: &RenderArgs, scene: &aperture_scene::Scene) -> usize {
    match &args.camera {
        None => 0,
        Some(c) => find_camera(c, scene).unwrap_or_else(|e| usage_error(e)),
    }
}

/// A camera given by name, else by index, as an index into the scene's cameras; the error
/// lists the cameras there are.
pub(crate) fn find_camera(c: &str, scene: &aperture_scene::Scene) -> Result<usize, String> {
    if let Some(i) = scene.cameras.iter().position(|cam| cam.name == c) {
        return Ok(i);
    }
    match c.parse::<usize>() {
        Ok(i) if i < scene.cameras.len() => Ok(i),
        _ => Err(format!(
            "invalid value '{c}' for '--camera': the scene's cameras are {}",
            scene
                .cameras
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{i} ({:?})", c.name))
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// `--width`/`--height`, the missing side (or both) from the camera's aspect.
fn image_size(args: &RenderArgs, cam: &aperture_scene::Camera) -> (u32, u32) {
    match (args.width, args.height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, aperture_render::default_height(cam, w)),
        (None, Some(h)) => {
            // The camera's aspect from the default 960-wide frame.
            let aspect = 960.0 / aperture_render::default_height(cam, 960) as f32;
            (((h as f32 * aspect).round() as u32).max(1), h)
        }
        (None, None) => (960, aperture_render::default_height(cam, 960)),
    }
}

fn bvh_quality(
    args: &RenderArgs,
    scene: &aperture_scene::Scene,
    width: u32,
    height: u32,
) -> aperture_accel::BvhQuality {
    match args.bvh_quality {
        BvhQualityArg::Auto => aperture_render::auto_bvh_quality(
            scene.unique_triangle_count(),
            u64::from(width) * u64::from(height) * u64::from(args.spp),
        ),
        BvhQualityArg::Fast => aperture_accel::BvhQuality::Fast,
        BvhQualityArg::Medium => aperture_accel::BvhQuality::Medium,
        BvhQualityArg::High => aperture_accel::BvhQuality::High,
    }
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
        filter: args.tracing.filter.into(),
        transmission: args.materials.transmission,
        energy_compensation: !args.materials.no_energy_compensation,
        sampler: match args.sampler {
            SamplerArg::Sobol => SamplerKind::Sobol,
            SamplerArg::Random => SamplerKind::Random,
        },
        material_override: match args.override_material {
            Some(OverrideArg::Diffuse) => MaterialOverride::Diffuse,
            None => MaterialOverride::None,
        },
        ..RenderOptions::default()
    }
}

/// `--env`, `--env-rotation`, `--env-strength`; an image is held to `max_bytes`.
fn environment(args: &RenderArgs, max_bytes: u64) -> anyhow::Result<Environment> {
    Ok(match &args.env {
        None => Environment::Constant(Vec3::ZERO),
        Some(EnvArg::Color(c)) => Environment::Constant(*c * args.env_strength),
        Some(EnvArg::File(path)) => {
            let (width, height, texels) = load_env_image(path, max_bytes)
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
    })
}

/// `--exposure`, `--view`.
fn png_options(args: &RenderArgs) -> aperture_imageio::PngOptions {
    aperture_imageio::PngOptions {
        exposure: args.exposure,
        view: match args.view {
            ViewArg::Standard => aperture_imageio::ViewTransform::Standard,
            ViewArg::Agx => aperture_imageio::ViewTransform::AgX,
        },
        ..Default::default()
    }
}

/// The warnings a finished render owes, and its one-line summary unless `--quiet` (always when
/// samples were dropped).
fn print_summary(
    args: &RenderArgs,
    opts: &RenderOptions,
    summary: &aperture_output::RenderSummary,
    load_secs: f64,
    quality: aperture_accel::BvhQuality,
    part: Option<crate::split_args::ImagePart>,
) {
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
                "region {} of {}x{}",
                aperture_output::header::region_text(&p.window),
                opts.width,
                opts.height
            ),
            None => format!("{}x{}", opts.width, opts.height),
        };
        eprintln!(
            "{}: {size}, {spp}, {render_secs:.2} s ({load_secs:.2} s loading, BVH {quality}), {:.2} Msamples/s, {dropped} dropped samples (NaN/Inf)",
            args.output.display(),
            summary.samples as f64 / render_secs.max(1e-9) / 1e6,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> RenderArgs {
        crate::render_args::tests::parse(args).unwrap()
    }

    /// Runs `aperture render SCENE -o <temp>/NAME.exr ARGS` and returns the EXR read back (the
    /// file is removed).
    fn render_exr(scene: &std::path::Path, name: &str, argv: &[&str]) -> aperture_imageio::Image {
        let out =
            std::env::temp_dir().join(format!("aperture-cli-{}-{name}.exr", std::process::id()));
        let mut args = parse(argv);
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
