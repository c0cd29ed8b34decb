//! Writing and reading images: EXR (scene-referred float, with passes and metadata) and PNG
//! (display-referred, after exposure and a view transform), plus image-error metrics.
//!
//! ```
//! use aperture_imageio::{read_exr, write_image, Image, Layer, MetaValue, PngOptions};
//! let mut image = Image::new(2, 2);
//! image.rgba[0] = [1.0, 0.5, 0.25, 1.0];
//! image.layers.push(Layer::new("depth", &["Z"], vec![1.5; 4]));
//! image.metadata.push(("aperture:radius".into(), MetaValue::Float(0.05)));
//!
//! let dir = std::env::temp_dir();
//! let exr = dir.join(format!("aperture-doc-{}.exr", std::process::id()));
//! write_image(&exr, &image, &PngOptions::default())?;
//! assert_eq!(read_exr(&exr)?, image);
//!
//! let png = exr.with_extension("png");
//! write_image(&png, &image, &PngOptions { exposure: 1.0, ..Default::default() })?;
//! # std::fs::remove_file(exr).unwrap();
//! # std::fs::remove_file(png).unwrap();
//! # Ok::<(), aperture_imageio::Error>(())
//! ```
//!
//! Every writer is atomic: the file appears whole, under its final name, or not at all.

use std::path::Path;

mod atomic;
mod env;
mod error;
mod exr;
pub mod metrics;
mod png;
pub mod view;

pub use crate::env::{decode_env_image, read_env_image, EnvFormat};
pub use crate::error::{Error, NameKind};
pub use crate::exr::{
    decode_exr, decode_exr_within, encode_exr, read_exr, read_exr_header, write_exr,
    write_exr_streamed, ChannelSpec, ExrHeader, ExrLayout, LateValues, RowWriter,
};
pub use crate::png::{encode_png, write_png};

/// A plain float image: beauty RGBA plus optional named passes and header metadata.
/// Rows run top to bottom.
///
/// RGB is *associated* (premultiplied) with A, the EXR convention and what a renderer that
/// averages radiance over samples (background contributing black) naturally produces.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Beauty pass, scene-referred linear Rec.709, `width * height` pixels; A = coverage.
    pub rgba: Vec<[f32; 4]>,
    /// How EXR stores the beauty (half with `--half`; the values here are f32 either way).
    pub beauty_type: SampleType,
    /// The EXR layer of the beauty's `R`,`G`,`B`,`A`: empty for the unprefixed channels
    /// aperture writes; a file read from Blender keeps its `ViewLayer.Combined`, so that
    /// written again its passes stay in one view layer (Blender's Image node shows only the
    /// view layer of its first pass).
    pub beauty_layer: String,
    /// Extra passes, written to EXR as layers (`depth.Z`, `normal.X`, ...); PNG ignores them.
    pub layers: Vec<Layer>,
    /// Header metadata (camera, aperture, focus, samples, seed, render time, ...).
    ///
    /// Keys are EXR attribute names: non-empty, at most 255 bytes, no NUL, each used once.
    /// Custom names become custom attributes. The few standard OpenEXR names with a plain
    /// text or float type (`owner`, `comments`, `capDate`, `software`, `focus` (metres),
    /// `aperture` (f-number), `expTime`, `isoSpeed`, `near`, `far`, ...) are stored as those
    /// standard attributes and must have that type; the structural ones (`channels`,
    /// `dataWindow`, `name`, ...) are refused. Prefer namespaced keys such as
    /// `aperture:radius` for renderer values whose meaning differs from the standard one.
    pub metadata: Vec<(String, MetaValue)>,
    /// Where these pixels sit in a larger image (a tile of a render split across machines);
    /// `None` when they are the whole image. EXR stores it as the data window inside the
    /// display window.
    pub placement: Option<Placement>,
}

/// How an EXR channel stores its samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SampleType {
    /// 32-bit float (the default; always for data such as depth, normals, IDs).
    #[default]
    F32,
    /// 16-bit half float (colour passes with `--half`): 11 bits of precision, at most 65504.
    F16,
}

/// A part of an image inside the whole: the pixels start at `(x, y)` of a
/// `full_width × full_height` image (x right, y down).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Placement {
    /// Column of the first pixel.
    pub x: u32,
    /// Row of the first pixel.
    pub y: u32,
    /// Width of the whole image.
    pub full_width: u32,
    /// Height of the whole image.
    pub full_height: u32,
}

impl Image {
    /// A black, transparent image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            rgba: vec![[0.0; 4]; width as usize * height as usize],
            beauty_type: SampleType::F32,
            beauty_layer: String::new(),
            layers: Vec::new(),
            metadata: Vec::new(),
            placement: None,
        }
    }

    /// The beauty's four channel names in EXR: `R`,`G`,`B`,`A` within [`Image::beauty_layer`].
    pub fn beauty_channel_names(&self) -> [String; 4] {
        ["R", "G", "B", "A"].map(|c| match self.beauty_layer.as_str() {
            "" => c.to_owned(),
            layer => format!("{layer}.{c}"),
        })
    }

    /// Number of pixels, `width * height`.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Checks that every buffer has the size `width` and `height` promise, that the image is
    /// not empty, and that layer, channel and metadata names can be written to an EXR file.
    pub fn validate(&self) -> Result<(), Error> {
        self.validate_beauty()?;
        let pixels = self.pixel_count();
        // Full channel names as they will appear in the file; the beauty names are taken.
        if self.beauty_layer.contains('\0') {
            let name = &self.beauty_layer;
            return Err(invalid_name(NameKind::Layer, name, "contains NUL"));
        }
        let mut full_names: Vec<String> = self.beauty_channel_names().to_vec();
        for (index, layer) in self.layers.iter().enumerate() {
            let what = || format!("layer {index} (`{}`)", layer.name);
            if layer.name.contains('\0') {
                return Err(invalid_name(NameKind::Layer, &layer.name, "contains NUL"));
            }
            if layer.channels.is_empty() {
                return Err(invalid_name(
                    NameKind::Layer,
                    &layer.name,
                    "has no channels",
                ));
            }
            for channel in &layer.channels {
                if channel.is_empty() || channel.contains('.') || channel.contains('\0') {
                    return Err(invalid_name(
                        NameKind::Channel,
                        channel,
                        "must be non-empty, without `.` or NUL",
                    ));
                }
                let full = layer.full_channel_name(channel);
                if full.len() > 255 {
                    return Err(invalid_name(
                        NameKind::Channel,
                        &full,
                        "longer than 255 bytes",
                    ));
                }
                if full_names.contains(&full) {
                    return Err(invalid_name(NameKind::Channel, &full, "appears twice"));
                }
                full_names.push(full);
            }
            let expected = pixels * layer.channels.len();
            if layer.data.len() != expected {
                return Err(Error::BufferSize {
                    what: what(),
                    expected,
                    found: layer.data.len(),
                });
            }
        }
        validate_metadata(&self.metadata)?;
        if let Some(p) = &self.placement {
            let fits = u64::from(p.x) + u64::from(self.width) <= u64::from(p.full_width)
                && u64::from(p.y) + u64::from(self.height) <= u64::from(p.full_height);
            if !fits {
                return Err(Error::InvalidOption {
                    option: "placement",
                    value: format!("{p:?}"),
                    reason: "the pixels must lie inside the whole image",
                });
            }
        }
        Ok(())
    }

    /// The checks PNG needs: non-empty, and `rgba` of the promised size.
    pub(crate) fn validate_beauty(&self) -> Result<(), Error> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::EmptyImage {
                width: self.width,
                height: self.height,
            });
        }
        let pixels = self.pixel_count();
        if self.rgba.len() != pixels {
            return Err(Error::BufferSize {
                what: "rgba".into(),
                expected: pixels,
                found: self.rgba.len(),
            });
        }
        Ok(())
    }

    /// The layer called `name`, if any.
    pub fn layer(&self, name: &str) -> Option<&Layer> {
        self.layers.iter().find(|layer| layer.name == name)
    }

    /// The metadata value under `key`, if any.
    pub fn meta(&self, key: &str) -> Option<&MetaValue> {
        self.metadata
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, value)| value)
    }
}

/// Metadata keys: 1 to 255 bytes, no NUL, each used once.
pub(crate) fn validate_metadata(metadata: &[(String, MetaValue)]) -> Result<(), Error> {
    let mut keys: Vec<&str> = Vec::with_capacity(metadata.len());
    for (key, _) in metadata {
        if key.is_empty() || key.len() > 255 || key.contains('\0') {
            return Err(invalid_name(
                NameKind::Metadata,
                key,
                "must be 1 to 255 bytes, without NUL",
            ));
        }
        if keys.contains(&key.as_str()) {
            return Err(invalid_name(NameKind::Metadata, key, "appears twice"));
        }
        keys.push(key);
    }
    Ok(())
}

fn invalid_name(kind: NameKind, name: &str, reason: &'static str) -> Error {
    Error::InvalidName {
        kind,
        name: name.to_owned(),
        reason,
    }
}

/// A named pass with one or more channels, stored channel-interleaved per pixel.
///
/// In an EXR file the channel is called `name.channel` (`depth.Z`). A layer with an empty
/// name holds channels that belong to no layer (a bare `Z` written by another tool).
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Layer name (`depth`, `normal`, `samples`, ...).
    pub name: String,
    /// Channel names within the layer (`Z`; `X`,`Y`,`Z`; ...).
    pub channels: Vec<String>,
    /// `width * height * channels.len()` values.
    pub data: Vec<f32>,
    /// How EXR stores the samples.
    pub sample_type: SampleType,
}

impl Layer {
    /// A float32 layer.
    pub fn new(name: &str, channels: &[&str], data: Vec<f32>) -> Self {
        Self {
            name: name.to_owned(),
            channels: channels.iter().map(|c| c.to_string()).collect(),
            data,
            sample_type: SampleType::F32,
        }
    }

    /// The channel's name in an EXR file: `layer.channel`, or `channel` for the unnamed layer.
    pub fn full_channel_name(&self, channel: &str) -> String {
        if self.name.is_empty() {
            channel.to_owned()
        } else {
            format!("{}.{channel}", self.name)
        }
    }
}

/// A metadata value for the EXR header.
#[derive(Debug, Clone, PartialEq)]
pub enum MetaValue {
    /// Text.
    Text(String),
    /// A float.
    Float(f32),
    /// An integer.
    Int(i32),
    /// A 4×4 matrix (`m44f`), the 16 values in file order: row-major, for Imath's convention
    /// of row vectors (a point transforms as `p · M`, the translation in the last row).
    /// `worldToCamera` and `worldToNDC` must have this type.
    Matrix([f32; 16]),
    /// CIE xy chromaticities of red, green, blue and white, in that order; only as
    /// `chromaticities`.
    Chromaticities([f32; 8]),
}

/// The display transform applied before quantising to PNG (`--view`; the first paragraph of
/// each value's comment is its help there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ViewTransform {
    /// Clip to [0, 1], then the sRGB transfer function.
    #[default]
    Standard,
    /// Blender's AgX base view (SPEC §6).
    ///
    /// No look, approximated; see [`view::agx`].
    #[cfg_attr(feature = "clap", value(name = "agx"))]
    AgX,
}

/// How to turn scene-referred values into a PNG.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PngOptions {
    /// Exposure in stops: values are multiplied by `2^exposure` first.
    pub exposure: f32,
    /// View transform.
    pub view: ViewTransform,
    /// Write 16 bits per channel instead of 8.
    pub sixteen_bit: bool,
}

impl Default for PngOptions {
    fn default() -> Self {
        Self {
            exposure: 0.0,
            view: ViewTransform::Standard,
            sixteen_bit: false,
        }
    }
}

/// The formats [`write_image`] chooses between.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Format {
    /// OpenEXR, scene-referred float.
    Exr,
    /// PNG, display-referred.
    Png,
}

impl Format {
    /// The format named by the path's extension (case-insensitive `.exr` or `.png`).
    pub fn from_path(path: &Path) -> Result<Self, Error> {
        let ext = path
            .extension()
            .and_then(|ext| ext.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            _ => Err(Error::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Writes `image` to `path`, choosing EXR or PNG by the extension. The file is written whole or
/// not at all (a temporary file beside it, then a rename).
///
/// `png` is used only for PNG; EXR stores scene-referred values unchanged.
pub fn write_image(path: &Path, image: &Image, png: &PngOptions) -> Result<(), Error> {
    match Format::from_path(path)? {
        Format::Exr => write_exr(path, image),
        Format::Png => write_png(path, image, png),
    }
}

#[cfg(test)]
mod tests;
