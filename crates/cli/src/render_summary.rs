//! The lines `aperture render` prints once a still image is written.

use crate::render_args::RenderArgs;
use aperture_render::RenderOptions;

/// The parts of a job's time that come before the render: loading (file → posed scene) and
/// building the frame's BVH; when its first samples were done (the first tile, from the job's
/// start); the whole job's wall time; and the process's peak resident memory (`VmHWM`, Linux).
#[derive(Debug, Clone, Copy)]
pub(crate) struct JobTimes {
    pub load_secs: f64,
    pub bvh_secs: f64,
    pub first_samples_secs: Option<f64>,
    pub total_secs: f64,
    pub peak_bytes: Option<u64>,
}

impl JobTimes {
    /// `, first samples at 1.23 s, peak memory 479.2 MB`: the parts that are known.
    fn extras(&self) -> String {
        let mut out = String::new();
        if let Some(t) = self.first_samples_secs {
            out += &format!(", first samples at {t:.2} s");
        }
        if let Some(b) = self.peak_bytes {
            out += &format!(", peak memory {}", aperture_budget::human_bytes(b));
        }
        out
    }
}

/// The warnings a finished render owes, and its one-line summary unless `--quiet` (always when
/// samples were dropped).
pub(crate) fn print_summary(
    args: &RenderArgs,
    opts: &RenderOptions,
    summary: &aperture_output::RenderSummary,
    job: JobTimes,
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
        // The whole job's wall time, then its parts (the rest is argument checks and set-up).
        let parts = format!(
            "load {:.2} s, BVH {quality} {:.2} s, render {render_secs:.2} s, denoise {:.2} s, write {:.2} s",
            job.load_secs, job.bvh_secs, summary.denoise_secs, summary.write_secs
        );
        eprintln!(
            "{}: {size}, {spp}, {:.2} s ({parts}){}, {:.2} Msamples/s, {dropped} dropped samples (NaN/Inf)",
            args.output.display(),
            job.total_secs,
            job.extras(),
            summary.samples as f64 / render_secs.max(1e-9) / 1e6,
        );
    }
}
