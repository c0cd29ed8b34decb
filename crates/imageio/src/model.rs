//! The image model: a float beauty with named passes, header metadata and its place in a
//! larger image, and the checks a file writer needs.

use crate::error::{Error, NameKind};

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
