//! `aperture render`: scene in, EXR or PNG out.

use crate::render_args::RenderArgs;
use crate::render_opts::{after_load, before_load, load_session};
use std::time::Instant;

/// Runs `aperture render`: all of it (loading, texture decoding, BVH building, rendering,
/// writing) on one pool of `--threads` workers, so that bound holds for the whole process.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let pool = crate::workers::worker_pool(args.threads)?;
    pool.install(|| run_on(args))
}

/// [`run`] on the pool's workers: the file loaded into a session, the scene posed, the
/// image (or each frame) rendered and written, the summary printed.
fn run_on(args: RenderArgs) -> anyhow::Result<()> {
    let t_job = Instant::now();
    let before = before_load(&args)?;
    // The library is needed before anything is loaded, rendered or written.
    let denoiser = args.denoise_options.load_if(args.denoise)?;
    let mut session = load_session(&args, &before.load)?;
    let time = before.load.time.map(f64::from);
    let first = args
        .frames
        .map(|f| f.start as f64 / f64::from(args.when.fps))
        .or(time);
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
    let job = crate::frames::JobStart {
        start: t_job,
        load_secs: t_job.elapsed().as_secs_f64(),
    };
    crate::frames::run(&args, &mut session, &plan, time, denoiser.as_ref(), job)
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
