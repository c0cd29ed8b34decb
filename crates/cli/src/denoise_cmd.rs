//! `aperture denoise IN.exr -o OUT.exr|png`, and loading the denoiser for `render --denoise`
//! and `merge --denoise`.

use anyhow::Context as _;
use aperture_denoise::{Denoiser, Prefilter, Quality, Settings};
use std::path::PathBuf;

/// How to denoise, shared by `render --denoise`, `merge --denoise`, `denoise` and `bench`:
/// the library and Cycles' two Denoising settings.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct DenoiseOptions {
    /// The Open Image Denoise library to load (or its folder), before all other places:
    /// libOpenImageDenoise.so.2, OpenImageDenoise.dll on Windows, libOpenImageDenoise.2.dylib
    /// on macOS.
    #[arg(long, value_name = "PATH")]
    pub oidn: Option<PathBuf>,
    /// The denoising network, as Cycles' Denoising "Quality": high (the default), balanced
    /// (with the accurate prefilter about half high's time; otherwise the same), fast (a
    /// small network for the image, for previews).
    #[arg(long, value_enum, value_name = "QUALITY")]
    pub denoise_quality: Option<Quality>,
    /// How the albedo and normal guide it, as Cycles' Denoising "Prefilter": accurate (the
    /// default: each denoised first, three filters in all), fast (taken as noisy, one filter),
    /// none (taken as noise-free, one filter; for converged albedo and normal).
    #[arg(long, value_enum, value_name = "PREFILTER")]
    pub denoise_prefilter: Option<Prefilter>,
}

impl DenoiseOptions {
    /// Whether any of these was given (they mean nothing without `--denoise`).
    pub fn given(&self) -> bool {
        self.oidn.is_some() || self.denoise_quality.is_some() || self.denoise_prefilter.is_some()
    }

    /// The settings asked for, Cycles' defaults for the rest.
    pub fn settings(&self) -> Settings {
        Settings {
            quality: self.denoise_quality.unwrap_or_default(),
            prefilter: self.denoise_prefilter.unwrap_or_default(),
        }
    }

    /// The denoiser when `wanted`; without it, an error if any option was given anyway.
    pub fn load_if(&self, wanted: bool) -> anyhow::Result<Option<Denoiser>> {
        match (wanted, self.given()) {
            (true, _) => Ok(Some(self.load()?)),
            (false, true) => anyhow::bail!(
                "--oidn, --denoise-quality and --denoise-prefilter only apply when denoising (--denoise)"
            ),
            (false, false) => Ok(None),
        }
    }

    /// Loads Open Image Denoise (`--oidn`, else `APERTURE_OIDN`, else the documented search)
    /// with these settings, before anything is rendered or written; the error is one line
    /// saying how to get it.
    pub fn load(&self) -> anyhow::Result<Denoiser> {
        Ok(Denoiser::load(self.oidn.as_deref())?.with_settings(self.settings()))
    }
}

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
    /// The library and the settings (see `aperture render --denoise`).
    #[command(flatten)]
    pub denoise: DenoiseOptions,
    /// PNG exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// No summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `aperture denoise`.
pub fn run(args: DenoiseArgs) -> anyhow::Result<()> {
    aperture_imageio::Format::from_path(&args.output)?;
    let denoiser = args.denoise.load()?;
    let t0 = std::time::Instant::now();
    let png = aperture_imageio::PngOptions {
        exposure: args.exposure,
        ..Default::default()
    };
    aperture_output::denoised::denoise_file(&args.input, &args.output, &png, &denoiser)
        .with_context(|| format!("denoising {}", args.input.display()))?;
    if !args.quiet {
        eprintln!(
            "{}: denoised with Open Image Denoise {} ({}; {}), {:.2} s",
            args.output.display(),
            denoiser.version_string(),
            denoiser.path().display(),
            denoiser.settings(),
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
