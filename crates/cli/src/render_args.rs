//! The arguments of `aperture render` (and the tracing options `aperture bench` shares):
//! their types, value parsers and help texts.

use crate::number_args::{finite_f32, non_negative_f32, positive_f32};
use aperture_imageio::ViewTransform;
use aperture_render::{BvhQualityChoice, FilterKind, PassSet, SamplerKind};
use aperture_shading::MaterialOverride;
use glam::Vec3;
use std::path::PathBuf;

fn parse_rgb(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [r, g, b] = parts.as_slice() else {
        return Err(format!("expected R,G,B (three numbers), got {s:?}"));
    };
    let v = [r, g, b]
        .map(|c| non_negative_f32(c))
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// `--env`: a colour or an equirectangular HDR image.
#[derive(Debug, Clone, PartialEq)]
pub enum EnvArg {
    /// Uniform radiance, linear R,G,B.
    Color(Vec3),
    /// An equirectangular `.hdr` (Radiance RGBE) or `.exr` file.
    File(PathBuf),
}

/// A value with a comma is a colour; otherwise it names an `.hdr` or `.exr` file.
fn parse_env(s: &str) -> Result<EnvArg, String> {
    if s.contains(',') {
        return parse_rgb(s).map(EnvArg::Color);
    }
    let path = PathBuf::from(s);
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("hdr" | "exr") => Ok(EnvArg::File(path)),
        _ => Err(format!(
            "expected R,G,B or an equirectangular .hdr or .exr file, got {s:?}"
        )),
    }
}

/// How every render of `aperture render` and `aperture bench` is traced: bounces, clamps and
/// pixel filter (one definition, so both commands take the same options the same way).
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct TracingArgs {
    /// Maximum bounces, as Blender Cycles counts them (0 = direct light only).
    #[arg(long, default_value_t = aperture_render::DEFAULT_MAX_BOUNCES, value_parser = clap::value_parser!(u32).range(0..=1024))]
    pub max_bounces: u32,
    /// Cycles' "Clamp Direct": the most one sample may add (sum of R, G, B) for light seen
    /// directly or after one scattering; 0 = off. Biased: removes fireflies, darkens highlights.
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_f32)]
    pub clamp_direct: f32,
    /// Cycles' "Clamp Indirect" (Blender's default for new scenes is 10): the most one sample
    /// may add for light that scattered more than once; 0 = off (the default here: unbiased).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_f32)]
    pub clamp_indirect: f32,
    /// Pixel filter.
    #[arg(long, value_enum, default_value_t = FilterKind::BlackmanHarris)]
    pub filter: FilterKind,
}

impl TracingArgs {
    /// The clamps as the renderer takes them.
    pub fn clamp(&self) -> aperture_render::Clamp {
        aperture_render::Clamp {
            direct: self.clamp_direct,
            indirect: self.clamp_indirect,
        }
    }
}

/// Arguments of `aperture render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
    /// Output file; the format follows the extension (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Samples per pixel (1 to 65536).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
    /// Image width in pixels [default: 960, or from --height and the camera's aspect].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height in pixels [default: from the width and the camera's aspect ratio].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Camera: its name, its glTF camera index N (`cameras[N]`, the N of `camera N` names and
    /// of `info`'s list), or `node:J` for the camera node J (a glTF camera drawn by two nodes)
    /// [default: the first camera node in drawing order, listed first by `info`].
    #[arg(long, value_name = "NAME|N|node:J")]
    pub camera: Option<String>,
    /// Which glTF scene of the file [default: the file's default scene].
    #[arg(long = "scene", value_name = "N")]
    pub scene_index: Option<usize>,
    /// Seed of every sample value (the image is a pure function of scene, options and seed).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=i32::MAX as i64))]
    pub seed: u32,
    /// Worker threads for everything the render does: loading, texture decoding, BVH building,
    /// rendering, writing (the main thread only waits for them) [default: all cores]. The image
    /// does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Lens radius in scene units (turns depth of field on; 0 = pinhole).
    #[arg(long, value_parser = non_negative_f32, allow_hyphen_values = true, conflicts_with_all = ["fstop", "no_dof"])]
    pub aperture_radius: Option<f32>,
    /// f-number: radius = focal length / (2 · F) (Cycles' rule).
    #[arg(long, value_parser = positive_f32, allow_hyphen_values = true, conflicts_with = "no_dof")]
    pub fstop: Option<f32>,
    /// Focus distance along the view axis, scene units.
    #[arg(long, value_parser = positive_f32, allow_hyphen_values = true, conflicts_with = "focus_object")]
    pub focus_distance: Option<f32>,
    /// Focus on a node's origin (node name, or index).
    #[arg(long)]
    pub focus_object: Option<String>,
    /// Optical vignetting: how far the lens barrel clips the aperture at the image's corners, in
    /// lens radii, 0–1 (the file's `aperture_vignetting`; docs/lenses.md) [default: the file's,
    /// else 0].
    #[arg(long, value_parser = crate::number_args::unit_f32)]
    pub aperture_vignetting: Option<f32>,
    /// Lens distortion, OpenCV's Brown–Conrady coefficients `K1[,K2[,K3[,P1[,P2]]]]` (the file's
    /// `distortion_k1` … `distortion_p2`; left-out ones are 0; docs/lenses.md) [default: the
    /// file's, else none].
    #[arg(long, value_name = "K1,K2,K3,P1,P2", value_parser = crate::number_args::distortion, allow_hyphen_values = true)]
    pub distortion: Option<[f32; 5]>,
    /// A real lens traced surface by surface: a lens file in pbrt-v4's format (the file's
    /// `lens_prescription`; docs/lenses.md) [default: the file's, else the thin lens].
    #[arg(long, value_name = "PATH")]
    pub lens_prescription: Option<std::path::PathBuf>,
    /// Bokeh image: the aperture's shape and transmission as a greyscale image (the file's
    /// `aperture_image`; docs/lenses.md) [default: the file's, else the plain aperture].
    #[arg(long, value_name = "PATH")]
    pub aperture_image: Option<std::path::PathBuf>,
    /// Lateral chromatic aberration: red's image is 1 + this times green's size, blue's 1 − this,
    /// −0.5 to 0.5 (the file's `chromatic_lateral`; docs/lenses.md) [default: the file's, else 0].
    #[arg(long, value_parser = crate::number_args::chromatic_f32, allow_hyphen_values = true)]
    pub chromatic_lateral: Option<f32>,
    /// Longitudinal chromatic aberration: red focuses at 1 + this times green's focus distance,
    /// blue at 1 − this, −0.5 to 0.5 (the file's `chromatic_longitudinal`) [default: the
    /// file's, else 0].
    #[arg(long, value_parser = crate::number_args::chromatic_f32, allow_hyphen_values = true)]
    pub chromatic_longitudinal: Option<f32>,
    /// Pinhole camera whatever the file says.
    #[arg(long)]
    pub no_dof: bool,
    /// Bounces, clamps and pixel filter.
    #[command(flatten)]
    pub tracing: TracingArgs,
    /// Time, frame and animation (SPEC §7).
    #[command(flatten)]
    pub when: crate::time_args::TimeArgs,
    /// Motion blur (SPEC §7).
    #[command(flatten)]
    pub motion: crate::motion_args::MotionArgs,
    /// Transmission, variants and energy compensation (SPEC §5).
    #[command(flatten)]
    pub materials: crate::material_args::MaterialArgs,
    /// Sample sequence.
    #[arg(long, value_enum, default_value_t = SamplerKind::Sobol)]
    pub sampler: SamplerKind,
    /// Environment: uniform radiance as linear R,G,B, or an equirectangular .hdr or .exr image
    /// (importance-sampled by luminance) [default: the file's EXT_lights_image_based light,
    /// else black].
    #[arg(long, value_parser = parse_env, allow_hyphen_values = true)]
    pub env: Option<EnvArg>,
    /// Rotation of the environment image about the up axis (+Y), degrees, counter-clockwise
    /// seen from above.
    #[arg(long, default_value_t = 0.0, value_parser = finite_f32, allow_hyphen_values = true)]
    pub env_rotation: f32,
    /// Multiplier on the environment's radiance (image or colour).
    #[arg(long, default_value_t = 1.0, value_parser = non_negative_f32)]
    pub env_strength: f32,
    /// Exposure in stops applied before the PNG view transform.
    #[arg(long, default_value_t = 0.0, value_parser = finite_f32, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Render every surface with an override material.
    #[arg(long, value_enum)]
    pub override_material: Option<MaterialOverride>,
    /// BVH build quality.
    #[arg(long, value_enum, default_value_t = BvhQualityChoice::Auto)]
    pub bvh_quality: BvhQualityChoice,
    /// View transform of PNG output.
    #[arg(long, value_enum, default_value_t = ViewTransform::Standard)]
    pub view: ViewTransform,
    /// Keep coverage as alpha in PNG output too (as Cycles' Film > Transparent). Without it a
    /// PNG is opaque: the environment (black by default) shows where nothing was hit, and dim
    /// partial coverage (bokeh against the sky) stays visible. EXR always stores coverage.
    #[arg(long)]
    pub transparent: bool,
    /// Adaptive sampling (after Blender Cycles'): a pixel stops once the estimated relative
    /// error of its mean (standard error over mean, from the samples' variance) is below this;
    /// smaller is cleaner and slower. Unlike Cycles' threshold (0.01 by default), which is
    /// relative to the square root of the brightness, dark pixels are held to the same relative
    /// error as bright ones. `--spp` becomes the most samples a pixel takes.
    #[arg(long, value_parser = positive_f32, allow_hyphen_values = true)]
    pub noise_threshold: Option<f32>,
    /// With --noise-threshold: samples every pixel takes before it may stop [default: 2√spp
    /// rounded up to a power of two, at least 4].
    #[arg(long, requires = "noise_threshold", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub min_spp: Option<u32>,
    /// EXR passes beside the beauty, with Blender's names: `default` (Depth, Normal, Denoising
    /// Albedo, Denoising Normal, CryptoObject, CryptoMaterial), `all` (adds the light passes
    /// and Position), `none`, or a comma-separated list such as `Depth,Normal,Emission`
    /// (`default,Position` adds to the default). PNG output has the beauty only.
    #[arg(long, default_value = "default", value_parser = PassSet::parse)]
    pub passes: PassSet,
    /// Colour passes (the beauty, light passes, denoising albedo) as half floats in EXR, clamped
    /// to ±65504 with a warning; data passes (depth, normals, IDs) stay float32.
    #[arg(long)]
    pub half: bool,
    /// Add the `Debug Sample Count` pass (the samples each pixel took); adaptive renders
    /// always have it. Same as adding `Debug Sample Count` to --passes.
    #[arg(long)]
    pub samples_pass: bool,
    /// The most memory the render may use (e.g. 8G, 512M) [default: the machine's memory, or
    /// its control group's limit]. Film, textures and geometry are sized against it before
    /// they are allocated; a job that cannot fit fails at once, saying what it needs.
    #[arg(long, value_parser = aperture_budget::parse_bytes)]
    pub max_memory: Option<u64>,
    /// On Ctrl-C (or SIGTERM), write the samples taken so far to the EXR (with `Debug Sample
    /// Count`, and `aperture:interrupted` = 1 in the header) instead of nothing. EXR only; not
    /// with --frames, where an interrupted frame is left unwritten so that --skip-existing
    /// renders it again.
    #[arg(long, conflicts_with = "frames")]
    pub save_partial: bool,
    /// Denoise the beauty with Intel Open Image Denoise 2.x (its RT filter, HDR, albedo and
    /// normal prefiltered, quality high, as Cycles; faster: --denoise-quality,
    /// --denoise-prefilter): the EXR's R,G,B (and the PNG) are the
    /// denoised image, the EXR keeps the noisy one as `Noisy Image` and the Denoising passes.
    /// The library is loaded at run time, found in this order: --oidn, APERTURE_OIDN, the
    /// system library path, tools/oidn/install.sh's copy in ~/.cache/aperture/oidn, a pyoidn
    /// wheel, Blender's lib/ folder. Missing: an error before anything is rendered. Denoised
    /// parts cannot be merged: render parts without it and use `aperture merge --denoise`.
    #[arg(long)]
    pub denoise: bool,
    /// With --denoise: the library and the settings.
    #[command(flatten)]
    pub denoise_options: crate::denoise_cmd::DenoiseOptions,
    /// A part of a render split across machines: --region, --tile, --sample-offset.
    #[command(flatten)]
    pub split: crate::split_args::SplitArgs,
    /// Render a sequence of frames (Blender's frame range: `1..250`, `1..250:2`); `#` in the
    /// output name become the zero-padded frame number (`shot_####.exr`). The file is loaded
    /// once, and only what moves is rebuilt per frame.
    #[arg(long, value_name = "A..B[:STEP]", value_parser = aperture_render::sequence::FrameRange::parse, conflicts_with_all = ["time", "frame"])]
    pub frames: Option<aperture_render::sequence::FrameRange>,
    /// With --frames: leave frames whose file already exists (a restarted job goes on where it
    /// stopped; files are written whole or not at all).
    #[arg(long, requires = "frames")]
    pub skip_existing: bool,
    /// No progress bar, no summary and no load warnings (points skipped, extensions ignored:
    /// `aperture info` lists them).
    #[arg(long, short)]
    pub quiet: bool,
    /// Progress display: a bar on a terminal, or JSON lines on stdout for programs (farm
    /// wrappers, the Blender engine).
    #[arg(long, value_enum, default_value_t = crate::progress::ProgressArg::Auto)]
    pub progress: crate::progress::ProgressArg,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use aperture_render::Pass;
    use clap::Parser as _;

    pub(crate) fn parse(args: &[&str]) -> Result<RenderArgs, clap::Error> {
        let mut argv = vec!["aperture", "render", "s.glb", "-o", "o.exr"];
        argv.extend_from_slice(args);
        match crate::Cli::try_parse_from(argv)?.command {
            crate::Command::Render(r) => Ok(*r),
            _ => unreachable!("render subcommand"),
        }
    }

    #[test]
    fn passes_and_half_parse() {
        let a = parse(&[]).unwrap();
        assert_eq!(a.passes, PassSet::compositing());
        assert!(!a.half);
        let b = parse(&["--passes", "all,Debug Sample Count", "--half"]).unwrap();
        assert!(
            b.half && b.passes.contains(Pass::Position) && b.passes.contains(Pass::SampleCount)
        );
        assert_eq!(parse(&["--passes", "none"]).unwrap().passes, PassSet::NONE);
        let e = parse(&["--passes", "Depth,Albedo"]).expect_err("unknown pass");
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("Albedo"), "{e}");
    }

    #[test]
    fn defaults_follow_the_issue() {
        let a = parse(&[]).unwrap();
        assert_eq!(a.tracing.max_bounces, 12);
        assert_eq!(a.tracing.filter, FilterKind::BlackmanHarris);
        assert_eq!(a.sampler, SamplerKind::Sobol);
        assert_eq!(a.bvh_quality, BvhQualityChoice::Auto);
        assert_eq!(a.view, ViewTransform::Standard);
        assert_eq!(a.env, None);
        assert_eq!(a.width, None);
    }

    #[test]
    fn bad_values_are_usage_errors() {
        for bad in [
            &["--spp", "0"][..],
            &["--aperture-radius", "-0.5"],
            &["--fstop", "0"],
            &["--env", "1,2"],
            &["--env", "1,nan,2"],
            &["--env", "sky.png"],
            &["--env-strength", "-1"],
            &["--env-rotation", "inf"],
            &["--filter", "mitchell"],
            &["--aperture-radius", "0.1", "--fstop", "2"],
            &["--focus-distance", "3", "--focus-object", "Cube"],
            &["--no-dof", "--aperture-radius", "0.1"],
            &["--sampler", "halton"],
            &["--noise-threshold", "0"],
            &["--noise-threshold", "-0.1"],
            &["--min-spp", "4"],
            &["--noise-threshold", "0.01", "--min-spp", "0"],
            &["--clamp-indirect", "-1"],
            &["--clamp-direct", "nan"],
            &["--tile", "4/4"],
            &["--tile", "1"],
            &["--region", "1,2,3"],
            &["--region", "1,1,1,2"],
            &["--region", "0,0,4,4", "--tile", "0/2"],
            &["--sample-offset", "65536"],
            &["--sample-offset", "-64"],
        ] {
            let e = parse(bad).expect_err("must be refused");
            assert_eq!(e.exit_code(), 2, "{bad:?}");
        }
    }

    #[test]
    fn good_values_parse() {
        let a = parse(&[
            "--env",
            "0.5, 1,2",
            "--exposure",
            "-1.5",
            "--override-material",
            "diffuse",
            "--view",
            "agx",
            "--scene",
            "1",
            "--camera",
            "Main",
            "--aperture-radius",
            "0",
        ])
        .unwrap();
        assert_eq!(a.env, Some(EnvArg::Color(Vec3::new(0.5, 1.0, 2.0))));
        let b = parse(&[
            "--env",
            "sky.HDR",
            "--env-rotation",
            "-90",
            "--env-strength",
            "2.5",
        ])
        .unwrap();
        assert_eq!(b.env, Some(EnvArg::File("sky.HDR".into())));
        assert_eq!((b.env_rotation, b.env_strength), (-90.0, 2.5));
        assert_eq!(a.exposure, -1.5);
        assert_eq!(a.override_material, Some(MaterialOverride::Diffuse));
        assert_eq!(a.view, ViewTransform::AgX);
        assert_eq!(a.scene_index, Some(1));
        assert_eq!(a.aperture_radius, Some(0.0));
        assert_eq!(a.tracing.clamp(), aperture_render::Clamp::OFF);
        let c = parse(&["--clamp-indirect", "10", "--clamp-direct", "100"]).unwrap();
        assert_eq!(
            (c.tracing.clamp_direct, c.tracing.clamp_indirect),
            (100.0, 10.0)
        );
    }
}
