//! `aperture denoise IN.exr -o OUT.exr|png`, and loading the denoiser for `render --denoise`
//! and `merge --denoise`.

use anyhow::Context as _;
use aperture_denoise::Denoiser;
use std::path::{Path, PathBuf};

/// Arguments of `aperture denoise`.
#[derive(clap::Args, Debug)]
pub struct DenoiseArgs {
    /// An EXR with the beauty and the Denoising Albedo and Denoising Normal passes (an
    /// `aperture render` EXR with the default --passes, or a Blender multilayer EXR with
    /// Denoising Data).
    #[arg(value_name = "IN.exr")]
    pub input: PathBuf,
    /// The denoised image: EXR (passes kept, the noisy beauty as `Noisy Image`) or PNG.
    #[arg(short, long, value_name = "OUT.exr|png")]
    pub output: PathBuf,
    /// The Open Image Denoise library to use (see `--oidn` of `aperture render`).
    #[arg(long, value_name = "PATH")]
    pub oidn: Option<PathBuf>,
    /// PNG exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// No summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Loads Open Image Denoise (`--oidn`, else `APERTURE_OIDN`, else the documented search),
/// before anything is rendered or written; the error is one line saying how to get it.
pub fn load_denoiser(oidn: Option<&Path>) -> anyhow::Result<Denoiser> {
    Ok(Denoiser::load(oidn)?)
}

/// Runs `aperture denoise`.
pub fn run(args: DenoiseArgs) -> anyhow::Result<()> {
    aperture_imageio::Format::from_path(&args.output)?;
    let denoiser = load_denoiser(args.oidn.as_deref())?;
    let t0 = std::time::Instant::now();
    let png = aperture_imageio::PngOptions {
        exposure: args.exposure,
        ..Default::default()
    };
    aperture_output::denoised::denoise_file(&args.input, &args.output, &png, &denoiser)
        .with_context(|| format!("denoising {}", args.input.display()))?;
    if !args.quiet {
        eprintln!(
            "{}: denoised with Open Image Denoise {} ({}), {:.2} s",
            args.output.display(),
            denoiser.version_string(),
            denoiser.path().display(),
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
