//! `aperture render --frames A..B[:STEP]`: maps the arguments to
//! `aperture_output::sequence::render_sequence` and prints a line per frame with an overall ETA.

use crate::progress::Progress;
use crate::render_args::RenderArgs;
use aperture_accel::BvhQuality;
use aperture_output::sequence::{self, FrameFormat, FrameReport, Sequence};
use aperture_render::sequence::FrameRange;
use aperture_render::RenderOptions;
use aperture_scene::Animated;
use std::time::Instant;

/// Renders the frames of `--frames` with the options and output format of one frame.
pub fn run(
    args: &RenderArgs,
    animated: &Animated,
    frames: FrameRange,
    format: FrameFormat,
    opts: &RenderOptions,
    quality: BvhQuality,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<()> {
    let seq = Sequence {
        animated,
        frames,
        fps: args.when.fps,
        opts,
        quality,
        pattern: &args.output,
        format,
        skip_existing: args.skip_existing,
    };
    let start = Instant::now();
    let (mut rendered, mut secs) = (0usize, 0.0f64);
    let quiet = args.quiet;
    pool.install(|| {
        let progress = Progress::with_mode(quiet, args.progress);
        let samples = u64::from(opts.width) * u64::from(opts.height) * u64::from(opts.spp);
        let mut frames_left = frames.frames();
        progress.set_samples(samples, frames_left.next());
        let report = |done, total| progress.update(done, total);
        let done = sequence::render_sequence(&seq, &report, &mut |r: &FrameReport| {
            if let Some(w) = &r.rendered {
                rendered += 1;
                secs += w.total_secs;
                progress.frame_written(Some(r.frame), &r.path, w.total_secs);
            }
            progress.set_samples(samples, frames_left.next());
            // Dropped samples are reported even with --quiet, as for one frame.
            let dropped = r.rendered.is_some_and(|w| w.summary.dropped > 0);
            if !quiet || dropped {
                let line = frame_line(r, rendered, secs, start.elapsed().as_secs_f64());
                progress.next_frame(&line);
            }
        });
        progress.finish();
        done
    })?;
    Ok(())
}

/// `frame 12 (3/24): shot_0012.exr, 1.21 s (pose 0.01 s, BVH 4.2 ms: 2 built, 5 reused),
/// 0 dropped; ETA 0:25`.
fn frame_line(r: &FrameReport, rendered: usize, secs: f64, elapsed: f64) -> String {
    let (i, n) = r.index;
    let head = format!("frame {} ({}/{n}): {}", r.frame, i + 1, r.path.display());
    let Some(w) = &r.rendered else {
        return format!("{head}: exists, skipped");
    };
    // The frames left at the mean time of the frames rendered so far.
    let left = (n - i - 1) as f64 * secs / rendered.max(1) as f64;
    format!(
        "{head}, {:.2} s (pose {:.2} s, BVH {:.1} ms: {} built, {} reused), {} dropped samples; elapsed {}, ETA {}",
        w.total_secs,
        w.pose_secs,
        w.accel.build_time.as_secs_f64() * 1e3,
        w.accel.blas_count - w.accel.reused_blases,
        w.accel.reused_blases,
        w.summary.dropped,
        clock(elapsed),
        clock(left),
    )
}

fn clock(secs: f64) -> String {
    let s = secs.round() as u64;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}

#[cfg(test)]
mod tests {
    use crate::render_args::RenderArgs;
    use clap::Parser as _;

    fn args(scene: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> RenderArgs {
        let mut argv = vec!["aperture", "render", "-o"];
        let out = out.to_str().unwrap().to_owned();
        let scene = scene.to_str().unwrap().to_owned();
        argv.push(&out);
        argv.push(&scene);
        argv.extend_from_slice(&["--width", "40", "--height", "30", "--spp", "2", "--quiet"]);
        argv.extend_from_slice(extra);
        match crate::Cli::try_parse_from(argv).unwrap().command {
            crate::Command::Render(r) => r,
            _ => unreachable!("render subcommand"),
        }
    }

    /// Every frame of `--frames` is the `--frame N` render of that frame, bit for bit (pixels
    /// and passes; the header holds times), for moving nodes (BoxAnimated) and a skinned,
    /// deforming character (CesiumMan).
    #[test]
    fn sequence_frames_equal_single_frame_renders() {
        for file in [
            "animation/BoxAnimated/BoxAnimated.glb",
            "animation/CesiumMan/CesiumMan.glb",
        ] {
            let Some(scene) = crate::sample(file) else {
                return;
            };
            let dir = std::env::temp_dir().join(format!(
                "aperture-frames-{}-{}",
                std::process::id(),
                file.len()
            ));
            std::fs::create_dir_all(&dir).unwrap();
            let pattern = dir.join("f_####.exr");
            crate::render_cmd::run(args(&scene, &pattern, &["--frames", "3..11:4"])).unwrap();
            let mut frames = Vec::new();
            for n in [3, 7, 11] {
                let single = dir.join(format!("single_{n}.exr"));
                crate::render_cmd::run(args(&scene, &single, &["--frame", &n.to_string()]))
                    .unwrap();
                let a = aperture_imageio::read_exr(&dir.join(format!("f_{n:04}.exr"))).unwrap();
                let b = aperture_imageio::read_exr(&single).unwrap();
                let bits = |im: &aperture_imageio::Image| -> Vec<u32> {
                    let mut v: Vec<u32> = im.rgba.iter().flatten().map(|f| f.to_bits()).collect();
                    for l in &im.layers {
                        v.extend(l.data.iter().map(|f| f.to_bits()));
                    }
                    v
                };
                assert!(bits(&a) == bits(&b), "{file} frame {n}");
                frames.push(a.rgba);
            }
            assert_ne!(frames[0], frames[2], "{file}: the frames move");
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }

    #[test]
    fn frames_and_a_single_time_exclude_each_other() {
        let p = std::path::Path::new("s.glb");
        for bad in [
            &["--frames", "1..3", "--frame", "2"][..],
            &["--frames", "1..3", "--time", "0.5"],
            &["--skip-existing"],
            &["--frames", "3..1"],
        ] {
            let mut argv = vec!["aperture", "render", "s.glb", "-o", "o.exr"];
            argv.extend_from_slice(bad);
            let e = crate::Cli::try_parse_from(argv).err().expect("refused");
            assert_eq!(e.exit_code(), 2, "{bad:?}");
        }
        let a = args(
            p,
            p,
            &["--frames", "1..3", "--fps", "25", "--skip-existing"],
        );
        assert_eq!(a.frames.map(|f| f.frames().count()), Some(3));
        assert!(a.skip_existing && a.when.fps == 25.0);
    }
}
