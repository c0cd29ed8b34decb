//! The lines `aperture render` prints once a still image is written.

use crate::render_args::RenderArgs;
use aperture_render::RenderOptions;

/// The warnings a finished render owes, and its one-line summary unless `--quiet` (always when
/// samples were dropped).
pub(crate) fn print_summary(
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
