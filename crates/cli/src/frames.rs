//! The images of `aperture render`: the still image, or the frames of `--frames A..B[:STEP]`,
//! mapped to `aperture_output::sequence::render_sequence` (a still is the sequence of one
//! frame), with one progress display; a line per frame with an overall ETA, or the still's
//! summary.

use crate::progress::Progress;
use crate::render_args::RenderArgs;
use crate::render_opts::RenderPlan;
use crate::render_summary::{print_summary, JobTimes};
use anyhow::Context as _;
use aperture_output::sequence::{self, FrameReport, FrameWork, Frames, Sequence};
use aperture_render::Session;
use std::time::Instant;

/// A render stopped by a signal after writing its partial EXR (`--save-partial`).
#[derive(Debug, thiserror::Error)]
#[error("interrupted: {0} holds the samples taken so far (--save-partial)")]
pub struct Interrupted(pub String);

/// When the job started, and what loading took.
#[derive(Debug, Clone, Copy)]
pub struct JobStart {
    pub start: Instant,
    pub load_secs: f64,
}

/// Renders the images of `args` from `session` as `plan` says (the still at `time` when there
/// is no `--frames`), then prints the still's summary.
pub fn run(
    args: &RenderArgs,
    session: &mut Session,
    plan: &RenderPlan,
    time: Option<f64>,
    denoiser: Option<&aperture_denoise::Denoiser>,
    job: JobStart,
) -> anyhow::Result<()> {
    let frames = match args.frames {
        Some(range) => Frames::Range(range),
        None => Frames::Still {
            frame: args.when.frame,
            time,
        },
    };
    let shutter_time = args.frames.map(|r| r.start as f64).or(time);
    let seq = Sequence {
        frames,
        fps: args.when.fps,
        opts: &plan.opts,
        quality: plan.quality,
        pattern: &args.output,
        format: plan.format,
        skip_existing: args.skip_existing,
        denoiser,
        motion: crate::motion_args::settings(&args.motion, session.animated(), shutter_time),
    };
    let start = Instant::now();
    let (mut rendered, mut secs) = (0usize, 0.0f64);
    let mut last: Option<FrameWork> = None;
    let quiet = args.quiet;
    let progress = Progress::with_mode(quiet, args.progress);
    let o = &plan.opts;
    let samples = u64::from(o.width) * u64::from(o.height) * u64::from(o.spp);
    // The JSON lines' frame: each frame's number in a range, none for a still.
    let mut frames_left = args.frames.into_iter().flat_map(|r| r.frames().map(Some));
    progress.set_samples(samples, frames_left.next().flatten());
    // The job's first samples: when the first tile (or round) of the first image was done.
    let first_samples = std::sync::OnceLock::new();
    let report = |done, total| {
        first_samples.get_or_init(|| job.start.elapsed().as_secs_f64());
        progress.update(done, total)
    };
    let done = sequence::render_sequence(session, &seq, &report, &mut |r: &FrameReport| {
        if let Some(w) = &r.rendered {
            rendered += 1;
            secs += w.total_secs;
            last = Some(*w);
            progress.frame_written(r.frame, &r.path, w.total_secs);
        }
        progress.set_samples(samples, frames_left.next().flatten());
        // Dropped samples are reported even with --quiet, as for one frame.
        let dropped = r.rendered.is_some_and(|w| w.summary.dropped > 0);
        if args.frames.is_some() && (!quiet || dropped) {
            let line = frame_line(r, rendered, secs, start.elapsed().as_secs_f64());
            progress.next_frame(&line);
        }
    });
    progress.finish();
    if args.frames.is_some() {
        return Ok(done?);
    }
    done.with_context(|| format!("writing {}", args.output.display()))?;
    if plan.opts.cancel.is_cancelled() {
        let path = args.output.display().to_string();
        return Err(Interrupted(path).into());
    }
    if let Some(w) = last {
        let job = JobTimes {
            load_secs: job.load_secs,
            bvh_secs: w.build_secs,
            first_samples_secs: first_samples.get().copied(),
            total_secs: job.start.elapsed().as_secs_f64(),
            peak_bytes: aperture_budget::peak_resident_bytes(),
        };
        print_summary(args, &plan.opts, &w.summary, job, plan.quality, plan.part);
    }
    Ok(())
}

/// `frame 12 (3/24): shot_0012.exr, 1.21 s (pose 0.01 s, BVH 4.2 ms: 2 built, 5 reused),
/// 0 dropped; ETA 0:25`.
fn frame_line(r: &FrameReport, rendered: usize, secs: f64, elapsed: f64) -> String {
    let (i, n) = r.index;
    let number = r.frame.map_or(String::new(), |f| f.to_string());
    let head = format!("frame {number} ({}/{n}): {}", i + 1, r.path.display());
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
