//! `aperture render`: scene in, EXR or PNG out.

use crate::progress::Progress;
use crate::render_args::RenderArgs;
use crate::render_opts::{after_load, before_load, usage_error};
use crate::render_summary::{print_summary, JobTimes};
use anyhow::Context as _;
use aperture_output::write::ImageOutput;
use aperture_render::{Frame, FrameSpec, Pass, RenderOptions, Session, SessionError};
use aperture_scene::LoadOptions;
use std::time::Instant;

/// A render stopped by a signal after writing its partial EXR (`--save-partial`).
#[derive(Debug, thiserror::Error)]
#[error("interrupted: {0} holds the samples taken so far (--save-partial)")]
pub struct Interrupted(pub String);

/// Runs `aperture render`: all of it (loading, texture decoding, BVH building, rendering,
/// writing) on one pool of `--threads` workers, so that bound holds for the whole process.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let pool = crate::workers::worker_pool(args.threads)?;
    pool.install(|| run_on(args))
}

/// [`run`] on the pool's workers: the file loaded into a session, the frame posed, the image
/// written, the summary printed.
fn run_on(args: RenderArgs) -> anyhow::Result<()> {
    let t_job = Instant::now();
    let before = before_load(&args)?;
    // The library is needed before anything is loaded, rendered or written.
    let denoiser = args.denoise_options.load_if(args.denoise)?;
    let first = args
        .frames
        .map(|f| f.start as f64 / f64::from(args.when.fps))
        .or(before.load.time.map(f64::from));
    let mut session = load_session(&args, &before.load)?;
    let scene = session.pose(first)?;
    let plan = after_load(&args, &before, scene)?;
    let load_warnings = match args.quiet {
        true => Vec::new(),
        false => crate::load_warnings::load_warnings(scene),
    };
    let scene_warnings = crate::first_image::scene_warnings(scene, &plan.opts.env);
    for w in load_warnings.into_iter().chain(scene_warnings) {
        eprintln!("warning: {}: {w}", args.scene.display());
    }
    let load_secs = t_job.elapsed().as_secs_f64();
    if let Some(frames) = args.frames {
        let out = (plan.format, denoiser.as_ref());
        return crate::frames::run(&args, &mut session, frames, out, &plan.opts, plan.quality);
    }
    let time = before.load.time.map(f64::from);
    let spec = FrameSpec {
        time,
        fps: args.when.fps,
        quality: plan.quality,
        motion: crate::motion_args::settings(&args.motion, session.animated(), time),
        vector: time.is_some() && plan.opts.passes.contains(Pass::Vector),
        view: (plan.opts.camera, plan.opts.width, plan.opts.height),
    };
    let frame = session.frame(&spec)?;
    let bvh_secs = frame.times().build_secs;
    let out = ImageOutput {
        path: &args.output,
        format: plan.format,
        denoiser: denoiser.as_ref(),
    };
    let summary = write_image(&args, frame, &plan.opts, &out)?;
    if plan.opts.cancel.is_cancelled() {
        return Err(Interrupted(args.output.display().to_string()).into());
    }
    let job = JobTimes {
        load_secs,
        bvh_secs,
        total_secs: t_job.elapsed().as_secs_f64(),
    };
    print_summary(&args, &plan.opts, &summary, job, plan.quality, plan.part);
    Ok(())
}

/// Renders the still image and writes it, showing progress.
fn write_image(
    args: &RenderArgs,
    frame: &Frame,
    opts: &RenderOptions,
    out: &ImageOutput<'_>,
) -> anyhow::Result<aperture_output::RenderSummary> {
    let progress = Progress::with_mode(args.quiet, args.progress);
    progress.set_samples(
        u64::from(opts.width) * u64::from(opts.height) * u64::from(args.spp),
        None,
    );
    let report = |done, total| progress.update(done, total);
    let summary = aperture_output::write::write_image(frame, opts, out, &report);
    progress.finish();
    let summary = summary.with_context(|| format!("writing {}", args.output.display()))?;
    progress.frame_written(args.when.frame, &args.output, summary.render_secs);
    Ok(summary)
}

/// The file loaded into a session; a flag's value the scene refuses (`--focus-object` naming
/// no node, `--scene 9`) is a usage error like any other bad flag value: exit code 2.
fn load_session(args: &RenderArgs, load: &LoadOptions) -> anyhow::Result<Session> {
    use aperture_scene::Error;
    match Session::load(&args.scene, load) {
        Ok(s) => Ok(s),
        Err(SessionError::Scene(e)) => match e {
            Error::InvalidDof { ref key, .. } if key.starts_with("command line") => {
                usage_error(format!("{}: {e}", args.scene.display()))
            }
            Error::NoSuchScene { .. }
            | Error::NoSuchAnimation { .. }
            | Error::NoSuchVariant { .. } => usage_error(format!("{}: {e}", args.scene.display())),
            e => Err(anyhow::Error::new(e).context(format!("loading {}", args.scene.display()))),
        },
        Err(e) => Err(anyhow::Error::new(e).context(format!("loading {}", args.scene.display()))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
