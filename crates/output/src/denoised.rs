//! Denoised images (SPEC §6): the beauty replaced by Open Image Denoise's output, the noisy
//! beauty kept as Cycles keeps it (its `Noisy Image` pass, RGBA), the `Denoising Albedo` and
//! `Denoising Normal` passes kept, alpha untouched, and `aperture:denoised` = 1 in the header so
//! `aperture merge` refuses the file (denoising is not linear: parts are merged first).
//!
//! Everything here works on plain images or rows of values; the render that calls it is
//! [`crate::write::write_image`] with a denoiser.

use crate::channels::HALF_MAX;
use aperture_denoise::{Denoiser, Images};
use aperture_imageio::{ChannelSpec, Image, Layer, MetaValue, PngOptions, SampleType};
use std::path::Path;

/// Header attribute (i32) that is 1 in a denoised file.
pub const DENOISED: &str = "aperture:denoised";
/// Header attribute (text): the denoiser and its settings, e.g. `Open Image Denoise 2.5.1,
/// quality high, prefilter accurate`.
pub const DENOISER: &str = "aperture:denoiser";
/// Header attribute (f32): seconds the denoiser took (filters built and run), beside
/// `aperture:renderTime`, which excludes it; their sum is what a user waits for the image.
pub const DENOISE_TIME: &str = "aperture:denoiseTime";

/// `passes` and the two the denoiser reads (albedo and normal), rendered for it.
pub(crate) fn with_aux(passes: aperture_render::PassSet) -> aperture_render::PassSet {
    use aperture_render::Pass;
    passes
        .with(Pass::DenoisingAlbedo)
        .with(Pass::DenoisingNormal)
}

/// What denoising adds to a file.
pub(crate) struct DenoisePlan {
    /// The passes asked for, and the two the denoiser reads (albedo and normal).
    pub passes: aperture_render::PassSet,
    /// The channels of the noisy beauty, after the others.
    pub channels: Vec<ChannelSpec>,
    /// The header attributes that say it (the denoised flag and time filled in late).
    pub metadata: Vec<(String, MetaValue)>,
}

/// What denoising with `denoiser` adds to a file of `passes` (nothing without one).
pub(crate) fn plan(
    denoiser: Option<&Denoiser>,
    passes: aperture_render::PassSet,
    half: bool,
) -> DenoisePlan {
    match denoiser {
        None => DenoisePlan {
            passes,
            channels: Vec::new(),
            metadata: Vec::new(),
        },
        Some(d) => DenoisePlan {
            passes: with_aux(passes),
            channels: noisy_channels(half),
            metadata: vec![
                (DENOISER.to_string(), MetaValue::Text(describe(d))),
                (DENOISED.to_string(), MetaValue::Int(0)),
                (DENOISE_TIME.to_string(), MetaValue::Float(0.0)),
            ],
        },
    }
}

/// Cycles' name of the noisy beauty kept beside the denoised one.
pub const NOISY_IMAGE: &str = "Noisy Image";
/// The albedo pass the denoiser takes.
pub const ALBEDO: &str = "Denoising Albedo";
/// The normal pass the denoiser takes.
pub const NORMAL: &str = "Denoising Normal";

/// Why an image could not be denoised.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DenoisingError {
    /// The image lacks a channel the denoiser needs.
    #[error(
        "cannot denoise: missing channel{} {}; denoising needs the beauty R,G,B and the \
         passes Denoising Albedo.R,G,B and Denoising Normal.X,Y,Z (aperture writes them with \
         the default --passes; Blender with View Layer > Passes > Denoising Data)",
        if missing.len() == 1 { "" } else { "s" }, missing.join(", ")
    )]
    Missing {
        /// The full names of the missing channels.
        missing: Vec<String>,
    },
    /// The image is denoised already.
    #[error("already denoised ({DENOISED} = 1 in its header): denoising twice would blur it")]
    AlreadyDenoised,
    /// The denoiser failed.
    #[error(transparent)]
    Denoiser(#[from] aperture_denoise::DenoiseError),
    /// The file could not be read or written.
    #[error(transparent)]
    Image(#[from] aperture_imageio::Error),
}

/// The `Noisy Image` channels a denoised render adds, after the others.
pub fn noisy_channels(half: bool) -> Vec<ChannelSpec> {
    let sample_type = if half {
        SampleType::F16
    } else {
        SampleType::F32
    };
    ["R", "G", "B", "A"]
        .map(|c| ChannelSpec {
            name: format!("{NOISY_IMAGE}.{c}"),
            sample_type,
        })
        .into()
}

/// Checks a file's channel names (as [`aperture_imageio::read_exr_header`] lists them) for
/// what denoising needs: the beauty (`R,G,B`, or Blender's `<view layer>.Combined.R,G,B`) and
/// the two Denoising passes (with or without a view-layer prefix).
pub fn check_channels(names: &[&str]) -> Result<(), DenoisingError> {
    let has = |full: &str| {
        names
            .iter()
            .any(|n| *n == full || n.ends_with(&format!(".{full}")))
    };
    let mut missing = Vec::new();
    let beauty = ["R", "G", "B"].iter().all(|c| names.contains(c))
        || ["R", "G", "B"]
            .iter()
            .all(|c| has(&format!("Combined.{c}")));
    if !beauty {
        missing.extend(["R", "G", "B"].map(String::from));
    }
    for (pass, channels) in [(ALBEDO, ["R", "G", "B"]), (NORMAL, ["X", "Y", "Z"])] {
        for c in channels {
            let full = format!("{pass}.{c}");
            if !has(&full) {
                missing.push(full);
            }
        }
    }
    if missing.is_empty() {
        Ok(())
    } else {
        Err(DenoisingError::Missing { missing })
    }
}

/// The three channels `names` of the layer `pass` (or `<prefix>.pass`) as RGB triples;
/// `Err` lists the channels missing.
fn aux(
    image: &Image,
    pass: &str,
    names: [&str; 3],
) -> Result<(String, Vec<[f32; 3]>), Vec<String>> {
    let all_missing = || {
        names
            .iter()
            .map(|c| format!("{pass}.{c}"))
            .collect::<Vec<String>>()
    };
    let layer = image
        .layers
        .iter()
        .find(|l| l.name == pass || l.name.ends_with(&format!(".{pass}")))
        .ok_or_else(all_missing)?;
    let index: Vec<Option<usize>> = names
        .iter()
        .map(|c| layer.channels.iter().position(|x| x == c))
        .collect();
    let missing: Vec<String> = names
        .iter()
        .zip(&index)
        .filter(|(_, i)| i.is_none())
        .map(|(c, _)| format!("{pass}.{c}"))
        .collect();
    if !missing.is_empty() {
        return Err(missing);
    }
    let idx: Vec<usize> = index.into_iter().flatten().collect();
    let n = layer.channels.len();
    let pixels = layer
        .data
        .chunks_exact(n)
        .map(|p| [p[idx[0]], p[idx[1]], p[idx[2]]].map(finite))
        .collect();
    let prefix = layer.name[..layer.name.len() - pass.len()].to_string();
    Ok((prefix, pixels))
}

/// NaN and infinities, which the filter would spread, as 0.
fn finite(v: f32) -> f32 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

/// The value written for a denoised colour: within the half range when stored as half.
fn store(v: f32, half: bool) -> f32 {
    if half {
        v.clamp(-HALF_MAX, HALF_MAX)
    } else {
        v
    }
}

/// The value of [`DENOISER`] for `denoiser`.
pub fn describe(denoiser: &Denoiser) -> String {
    format!(
        "Open Image Denoise {}, {}",
        denoiser.version_string(),
        denoiser.settings()
    )
}

/// Denoises `image` in place (see the module documentation): a [`NOISY_IMAGE`] layer (with
/// the albedo layer's view-layer prefix, if any) holds the old beauty.
pub fn denoise_image(image: &mut Image, denoiser: &Denoiser) -> Result<(), DenoisingError> {
    if matches!(image.meta(DENOISED), Some(MetaValue::Int(v)) if *v != 0) {
        return Err(DenoisingError::AlreadyDenoised);
    }
    let albedo = aux(image, ALBEDO, ["R", "G", "B"]);
    let normal = aux(image, NORMAL, ["X", "Y", "Z"]);
    let ((prefix, albedo), (_, normal)) = match (albedo, normal) {
        (Ok(a), Ok(n)) => (a, n),
        (a, n) => {
            let mut missing = a.err().unwrap_or_default();
            missing.extend(n.err().unwrap_or_default());
            return Err(DenoisingError::Missing { missing });
        }
    };
    // A file denoised by Cycles already has its Noisy Image (and a denoised beauty): the
    // noisy one is what is denoised, and it stays.
    let noisy_name = format!("{prefix}{NOISY_IMAGE}");
    let had_noisy = aux(image, NOISY_IMAGE, ["R", "G", "B"])
        .ok()
        .filter(|(p, _)| *p == prefix)
        .map(|(_, px)| px);
    let colour: Vec<[f32; 3]> = match &had_noisy {
        Some(px) => px.clone(),
        None => image
            .rgba
            .iter()
            .map(|p| [p[0], p[1], p[2]].map(finite))
            .collect(),
    };
    let clean = denoiser.denoise(&Images {
        width: image.width as usize,
        height: image.height as usize,
        colour: &colour,
        albedo: &albedo,
        normal: &normal,
    })?;
    let mut noisy = Layer::new(
        &noisy_name,
        &["R", "G", "B", "A"],
        image.rgba.iter().flatten().copied().collect(),
    );
    noisy.sample_type = image.beauty_type;
    let half = image.beauty_type == SampleType::F16;
    for (p, c) in image.rgba.iter_mut().zip(&clean) {
        for k in 0..3 {
            p[k] = store(c[k], half);
        }
    }
    if had_noisy.is_none() {
        image.layers.push(noisy);
    }
    image
        .metadata
        .retain(|(k, _)| k != DENOISED && k != DENOISER);
    image.metadata.push((DENOISED.into(), MetaValue::Int(1)));
    image
        .metadata
        .push((DENOISER.into(), MetaValue::Text(describe(denoiser))));
    Ok(())
}

/// Rows of a render (`specs` channels a pixel, the beauty first) with the beauty denoised and
/// the [`noisy_channels`] appended to each pixel; with no `denoiser` (an interrupted render
/// saved as it is) the beauty stays noisy, copied into both.
pub fn denoise_rows(
    values: &[f32],
    specs: &[ChannelSpec],
    width: u32,
    height: u32,
    denoiser: Option<&Denoiser>,
) -> Result<Vec<f32>, DenoisingError> {
    let stride = specs.len();
    let find = |name: &str| specs.iter().position(|s| s.name == name);
    let (Some(a), Some(n)) = (find("Denoising Albedo.R"), find("Denoising Normal.X")) else {
        return Err(DenoisingError::Missing {
            missing: vec![format!("{ALBEDO}.R"), format!("{NORMAL}.X")],
        });
    };
    let triple = |at: usize| -> Vec<[f32; 3]> {
        values
            .chunks_exact(stride)
            .map(|p| [p[at], p[at + 1], p[at + 2]].map(finite))
            .collect()
    };
    let colour = triple(0);
    let clean = match denoiser {
        Some(d) => d.denoise(&Images {
            width: width as usize,
            height: height as usize,
            colour: &colour,
            albedo: &triple(a),
            normal: &triple(n),
        })?,
        None => colour,
    };
    let half = specs[0].sample_type == SampleType::F16;
    let mut out = Vec::with_capacity(values.len() / stride * (stride + 4));
    for (p, c) in values.chunks_exact(stride).zip(&clean) {
        out.extend(c.iter().map(|v| store(*v, half)));
        out.extend_from_slice(&p[3..]);
        out.extend_from_slice(&p[..4]);
    }
    Ok(out)
}

/// `aperture denoise`: reads the EXR `input`, denoises it and writes `output` (EXR with the
/// passes and the noisy beauty, or PNG with `png`'s exposure and view). Nothing is written on
/// error.
pub fn denoise_file(
    input: &Path,
    output: &Path,
    png: &PngOptions,
    denoiser: &Denoiser,
) -> Result<(), DenoisingError> {
    let header = aperture_imageio::read_exr_header(input)?;
    let names: Vec<&str> = header.channels.iter().map(|c| c.name.as_str()).collect();
    check_channels(&names)?;
    let mut image = aperture_imageio::read_exr(input)?;
    denoise_image(&mut image, denoiser)?;
    aperture_imageio::write_image(output, &image, png)?;
    Ok(())
}
