//! `aperture merge`: the parts of a split render (tiles, sample batches) into one EXR.

use anyhow::Context as _;
use aperture_output::merge::{merge_exr, merge_exr_denoised, MergeOptions};
use std::path::PathBuf;

/// Arguments of `aperture merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The part files (EXR written by `aperture render` with --region, --tile or
    /// --sample-offset), in any order.
    #[arg(required = true, value_name = "PARTS")]
    pub parts: Vec<PathBuf>,
    /// The merged EXR (written whole or not at all).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Merge even when tiles or sample batches are missing: the output covers the parts'
    /// bounding box and missing pixels are empty (sample count 0).
    #[arg(long)]
    pub allow_partial: bool,
    /// Denoise the merged image once (Open Image Denoise; see `aperture render --denoise`).
    /// Parts must not be denoised themselves: denoising is not linear.
    #[arg(long)]
    pub denoise: bool,
    /// With --denoise: the library and the settings (see `aperture render --denoise`).
    #[command(flatten)]
    pub denoise_options: crate::denoise_cmd::DenoiseOptions,
    /// No summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `aperture merge`.
pub fn run(args: MergeArgs) -> anyhow::Result<()> {
    let is_exr = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        anyhow::bail!(
            "{}: the merged file must end in .exr (parts are EXR, with their passes)",
            args.output.display()
        );
    }
    let denoiser = args.denoise_options.load_if(args.denoise)?;
    let t0 = std::time::Instant::now();
    let opts = MergeOptions {
        allow_partial: args.allow_partial,
    };
    let summary = match &denoiser {
        Some(d) => merge_exr_denoised(&args.parts, &args.output, &opts, d),
        None => merge_exr(&args.parts, &args.output, &opts),
    }
    .with_context(|| format!("merging into {}", args.output.display()))?;
    if !summary.complete {
        eprintln!(
            "warning: {}: parts are missing (--allow-partial): pixels or samples are incomplete",
            args.output.display()
        );
    }
    if !args.quiet {
        let (w, h) = summary.image_size;
        eprintln!(
            "{}: {} parts ({} windows) of {w}x{h}, samples {}, {:.2} s",
            args.output.display(),
            summary.parts,
            summary.windows,
            summary.sample_ranges,
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
