//! `aperture render --frames A..B[:STEP]`: maps the arguments to
//! `aperture_output::sequence::render_sequence` and prints a line per frame with an overall ETA.

use crate::progress::Progress;
use crate::render_args::RenderArgs;
use aperture_accel::BvhQuality;
use aperture_output::sequence::{self, FrameReport, Sequence};
use aperture_output::write::ImageFormat;
use aperture_render::motion::MotionSettings;
use aperture_render::sequence::FrameRange;
use aperture_render::{RenderOptions, Session};
use std::time::Instant;

/// Renders the frames of `--frames` from `session` with the options and output of one frame.
pub fn run(
    args: &RenderArgs,
    session: &mut Session,
    frames: FrameRange,
    (format, denoiser): (ImageFormat, Option<&aperture_denoise::Denoiser>),
    opts: &RenderOptions,
    quality: BvhQuality,
) -> anyhow::Result<()> {
    let seq = Sequence {
        frames,
        fps: args.when.fps,
        opts,
        quality,
        pattern: &args.output,
        format,
        skip_existing: args.skip_existing,
        denoiser,
        motion: Some(MotionSettings::resolve(
            &session.animated().motion_extras(),
            &args.motion.overrides(),
        )),
    };
    let start = Instant::now();
    let (mut rendered, mut secs) = (0usize, 0.0f64);
    let quiet = args.quiet;
    let progress = Progress::with_mode(quiet, args.progress);
    let samples = u64::from(opts.width) * u64::from(opts.height) * u64::from(opts.spp);
    let mut frames_left = frames.frames();
    progress.set_samples(samples, frames_left.next());
    let report = |done, total| progress.update(done, total);
    let done = sequence::render_sequence(session, &seq, &report, &mut |r: &FrameReport| {
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
    done?;
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
