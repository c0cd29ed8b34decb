//! EXR reading: any file OpenEXR writes, into a plain [`Image`].

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use ::exr::image::FlatSamples;
use ::exr::meta::MetaData;
use ::exr::prelude::traits::{ReadChannels, ReadLayers};

use super::attrs::{chromaticities, get_attributes, meta_value, string};
use super::guard;
use super::write::ChannelSpec;
use crate::error::Error;
use crate::model::{Image, Layer, Placement, SampleType};

/// What an EXR file's header says, without its pixels: what a tool needs to decide whether
/// to read the file (`aperture merge` checks every part before reading any).
#[derive(Debug, Clone, PartialEq)]
pub struct ExrHeader {
    /// Width of the pixels stored (the data window).
    pub width: u32,
    /// Height of the pixels stored.
    pub height: u32,
    /// Where they sit in the whole image, as [`Image::placement`].
    pub placement: Option<Placement>,
    /// Every channel by full name (`R`, `Depth.Z`), sorted by name, of every part.
    pub channels: Vec<ChannelSpec>,
    /// The metadata [`read_exr`] would return.
    pub metadata: Vec<(String, crate::model::MetaValue)>,
}

impl ExrHeader {
    /// The metadata value under `key`, if any.
    pub fn meta(&self, key: &str) -> Option<&crate::model::MetaValue> {
        self.metadata.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// Reads only the header of an EXR file (a few kilobytes, whatever the image's size). A
/// damaged header gives an error, never a panic; damaged pixels are found only by
/// [`read_exr`].
pub fn read_exr_header(path: &Path) -> Result<ExrHeader, Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        message: format!("reading: {e}"),
    })?;
    let reader = std::io::BufReader::new(file);
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| header_of(reader, path)))
        .unwrap_or_else(|_| {
            Err(Error::Exr {
                path: path.to_path_buf(),
                message: "the decoder panicked on a damaged header".into(),
            })
        })
}

fn header_of(reader: impl std::io::Read, path: &Path) -> Result<ExrHeader, Error> {
    let meta = MetaData::read_from_buffered(reader, false).map_err(|e| Error::Exr {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let unsupported = |what: &str| Error::UnsupportedExr {
        path: path.to_path_buf(),
        what: what.into(),
    };
    let first = meta
        .headers
        .first()
        .ok_or_else(|| unsupported("no parts"))?;
    let (size, position) = (first.layer_size, first.own_attributes.layer_position);
    let mut channels = Vec::new();
    let mut metadata = Vec::new();
    for header in &meta.headers {
        if header.layer_size != size || header.own_attributes.layer_position != position {
            return Err(unsupported("parts with different data windows"));
        }
        let part = header.own_attributes.layer_name.as_ref();
        for c in &header.channels.list {
            channels.push(ChannelSpec {
                name: full_name(part, c.name.as_slice()),
                sample_type: match c.sample_type {
                    ::exr::meta::attribute::SampleType::F16 => SampleType::F16,
                    _ => SampleType::F32,
                },
            });
        }
        if metadata.is_empty() {
            metadata = get_attributes(&header.own_attributes);
            for (name, value) in &header.shared_attributes.other {
                if let Some(value) = meta_value(value) {
                    metadata.push((string(name.as_slice()), value));
                }
            }
            metadata.extend(chromaticities(&header.shared_attributes));
        }
    }
    channels.sort_by(|a, b| a.name.cmp(&b.name));
    metadata.sort_by(|a, b| a.0.cmp(&b.0));
    let too_big = || unsupported("image larger than u32");
    let width = u32::try_from(size.width()).map_err(|_| too_big())?;
    let height = u32::try_from(size.height()).map_err(|_| too_big())?;
    let display = first.shared_attributes.display_window;
    Ok(ExrHeader {
        width,
        height,
        placement: placement(display, position, width, height),
        channels,
        metadata,
    })
}

/// Reads an EXR file: the beauty, the other channels as layers, and the metadata.
///
/// - Beauty: the unnamed `R`,`G`,`B`,`A`; `A` = 1 when absent. A luminance-only file (`Y`)
///   gives grey. Failing both, the first layer holding `R`,`G`,`B` (preferring one named
///   `...Combined`, as in Blender's multilayer files) is the beauty and is not repeated
///   among the layers; its name is kept as [`Image::beauty_layer`].
/// - Half and uint samples are converted to f32 (half exactly; uint above 2^24 rounds).
/// - Layers come back sorted by name, channels within one in the order `R G B A X Y Z W U V`
///   then alphabetical; channels outside any layer form the layer named `""`.
/// - Metadata: text, f32 and i32 header attributes (custom ones, and the standard ones
///   [`Image::metadata`] lists), sorted by key; attributes of other types are skipped. Of a
///   multi-part file only the part holding the beauty gives metadata.
/// - The image is the data window; all parts must share it.
///
/// All codecs of exr 1.74 are read; for DWAA/DWAB only scan-line parts (tiled or deep DWA
/// is refused, as its blocks are not checked; see below).
///
/// A damaged or hostile file gives an error, never a panic. As a guard against files that
/// claim a huge image in a few bytes, the decoded samples may take at most 1 GiB or 4096
/// times the file size, whichever is larger; the size counters of DWA blocks are checked
/// before decoding, as the decoder trusts them for allocations.
pub fn read_exr(path: &Path) -> Result<Image, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        message: format!("reading: {e}"),
    })?;
    decode_exr(&bytes, path)
}

/// Decodes EXR bytes; see [`read_exr`]. `path` only names the file in errors.
pub fn decode_exr(bytes: &[u8], path: &Path) -> Result<Image, Error> {
    decode_exr_within(bytes, path, u64::MAX)
}

/// [`decode_exr`] with the decoded samples also held to `max_bytes` (environment maps within
/// the render's memory budget; the fuzz targets within theirs).
pub fn decode_exr_within(bytes: &[u8], path: &Path, max_bytes: u64) -> Result<Image, Error> {
    caught_as_damaged(path, || decode_exr_inner(bytes, path, max_bytes))
}

/// `decode`, with a panic inside turned into an error naming the file: the `exr` decoder can
/// panic on some damaged data (seen: an integer overflow in its B44 decompressor, in builds
/// with overflow checks), and a damaged file must not bring down the caller. Nothing shared is
/// mutated inside, so unwinding leaves no broken state.
pub(super) fn caught_as_damaged(
    path: &Path,
    decode: impl FnOnce() -> Result<Image, Error>,
) -> Result<Image, Error> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(decode)).unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(Error::Exr {
            path: path.to_path_buf(),
            message: format!("the decoder panicked on damaged data: {message}"),
        })
    })
}

/// A channel's samples: the part it came from, its values, its type in the file.
type Channel = (usize, Vec<f32>, SampleType);

/// Every part of a file at its largest resolution level, every channel flat.
type FlatImage = ::exr::image::Image<
    ::exr::prelude::SmallVec<[::exr::image::Layer<::exr::image::AnyChannels<FlatSamples>>; 2]>,
>;

/// The `exr` crate's error, naming the file.
fn exr_error(path: &Path) -> impl Fn(::exr::error::Error) -> Error + '_ {
    move |e| Error::Exr {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// What this reader does not take, naming the file.
fn unsupported(path: &Path) -> impl Fn(String) -> Error + '_ {
    move |what| Error::UnsupportedExr {
        path: path.to_path_buf(),
        what,
    }
}

fn decode_exr_inner(bytes: &[u8], path: &Path, max_bytes: u64) -> Result<Image, Error> {
    let exr_error = exr_error(path);
    let unsupported = unsupported(path);
    check_before_decoding(bytes, path, max_bytes)?;

    // Sequential decoding: reading is not the renderer's hot path, and it keeps a damaged
    // file's error on this thread.
    let image = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .non_parallel()
        .from_buffered(Cursor::new(bytes))
        .map_err(exr_error)?;

    let first = image
        .layer_data
        .first()
        .ok_or_else(|| unsupported("no parts".into()))?;
    let (size, position) = (first.size, first.attributes.layer_position);
    let pixels = size.area();
    let mut channels = channels_by_name(&image, path)?;
    let beauty_prefix = beauty_prefix(&channels, path)?;

    let mut take = |name: &str| channels.remove(name);
    let (rgb, alpha, beauty_part, beauty_type) = match &beauty_prefix {
        Some(p) => {
            let r = take(&format!("{p}R")).expect("checked above");
            let g = take(&format!("{p}G")).expect("checked above");
            let b = take(&format!("{p}B")).expect("checked above");
            let (part, kind) = (r.0, r.2);
            (
                [r.1, g.1, b.1],
                take(&format!("{p}A")).map(|a| a.1),
                part,
                kind,
            )
        }
        None => {
            let (part, y, kind) = take("Y").expect("checked above");
            (
                [y.clone(), y.clone(), y],
                take("A").map(|a| a.1),
                part,
                kind,
            )
        }
    };
    let rgba = (0..pixels)
        .map(|p| {
            let a = alpha.as_ref().map_or(1.0, |a| a[p]);
            [rgb[0][p], rgb[1][p], rgb[2][p], a]
        })
        .collect();

    let layers = group_layers(channels, pixels);

    let metadata = metadata(&image, beauty_part);

    let too_big = || unsupported("image larger than u32".into());
    let (width, height) = (
        u32::try_from(size.width()).map_err(|_| too_big())?,
        u32::try_from(size.height()).map_err(|_| too_big())?,
    );
    let display = image.attributes.display_window;
    let placement = placement(display, position, width, height);
    Ok(Image {
        width,
        height,
        rgba,
        beauty_type,
        beauty_layer: beauty_prefix.map_or(String::new(), layer_of),
        layers,
        metadata,
        placement,
    })
}

/// The beauty part's attributes and the file's shared ones, sorted by name.
fn metadata(image: &FlatImage, beauty_part: usize) -> Vec<(String, crate::model::MetaValue)> {
    let mut metadata = get_attributes(&image.layer_data[beauty_part].attributes);
    for (name, value) in &image.attributes.other {
        if let Some(value) = meta_value(value) {
            metadata.push((string(name.as_slice()), value));
        }
    }
    metadata.extend(chromaticities(&image.attributes));
    metadata.sort_by(|a, b| a.0.cmp(&b.0));
    metadata
}

/// The checks that keep a damaged or hostile file from costing more than it is worth, before
/// the `exr` crate decodes it: DWA blocks, chunk sizes against the file, and the decoded size
/// against `max_bytes` (and against 4,096 bytes of samples per byte of file, at least 1 GiB).
fn check_before_decoding(bytes: &[u8], path: &Path, max_bytes: u64) -> Result<(), Error> {
    let exr_error = exr_error(path);
    let unsupported = unsupported(path);
    let meta = MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(exr_error)?;
    match guard::check_dwa_blocks(bytes, &meta) {
        Ok(()) => {}
        Err(guard::DwaProblem::Unsupported(what)) => return Err(unsupported(what)),
        Err(guard::DwaProblem::Damaged(message)) => {
            return Err(Error::Exr {
                path: path.to_path_buf(),
                message,
            })
        }
    }
    guard::check_chunk_sizes(bytes, &meta).map_err(|message| Error::Exr {
        path: path.to_path_buf(),
        message,
    })?;
    let limit = (1u64 << 30).max(4096 * bytes.len() as u64).min(max_bytes);
    // u128: a data window's width × height × channels × 4 can pass what a u64 counts.
    let mut decoded = 0u128;
    for header in &meta.headers {
        let samples = header.layer_size.width() as u128
            * header.layer_size.height() as u128
            * header.channels.list.len() as u128;
        decoded = decoded.saturating_add(samples * 4);
    }
    if decoded > u128::from(limit) {
        return Err(unsupported(format!(
            "{decoded} bytes of samples from a {}-byte file",
            bytes.len()
        )));
    }
    Ok(())
}

/// Every channel of every part, by full name (`layer.channel`), as f32 samples.
fn channels_by_name(image: &FlatImage, path: &Path) -> Result<BTreeMap<String, Channel>, Error> {
    let unsupported = unsupported(path);
    let first = &image.layer_data[0];
    let (size, position) = (first.size, first.attributes.layer_position);
    let pixels = size.area();
    let mut channels: BTreeMap<String, Channel> = BTreeMap::new();
    for (part_index, part) in image.layer_data.iter().enumerate() {
        if part.size != size || part.attributes.layer_position != position {
            return Err(unsupported("parts with different data windows".into()));
        }
        let name = part.attributes.layer_name.as_ref();
        for channel in &part.channel_data.list {
            let full = full_name(name, channel.name.as_slice());
            let (samples, kind): (Vec<f32>, _) = match &channel.sample_data {
                FlatSamples::F16(v) => (v.iter().map(|h| h.to_f32()).collect(), SampleType::F16),
                FlatSamples::F32(v) => (v.clone(), SampleType::F32),
                FlatSamples::U32(v) => (v.iter().map(|&u| u as f32).collect(), SampleType::F32),
            };
            if samples.len() != pixels {
                return Err(unsupported(format!("subsampled channel `{full}`")));
            }
            channels.insert(full, (part_index, samples, kind));
        }
    }
    Ok(channels)
}

/// A channel's full name (`layer.channel`) in a part named `part`. Parts written as the exr
/// crate writes them name the layer and hold short channel names (`R`); Blender 5's multi-part
/// files, as OpenEXR's own convention has it, repeat the part's name in each channel's
/// (`ViewLayer.Depth.Z` in part `ViewLayer.Depth`), which must not be prefixed again.
fn full_name(part: Option<&::exr::meta::attribute::Text>, channel: &[u8]) -> String {
    let channel = string(channel);
    match part.map(|p| string(p.as_slice())) {
        Some(part) if !part.is_empty() && !channel.starts_with(&format!("{part}.")) => {
            format!("{part}.{channel}")
        }
        _ => channel,
    }
}

/// The layer a channel prefix (`ViewLayer.Combined.`) names (`ViewLayer.Combined`).
fn layer_of(prefix: String) -> String {
    prefix.strip_suffix('.').unwrap_or_default().to_owned()
}

/// The beauty's channel prefix: `""` for unprefixed `R,G,B`, `None` for luminance `Y`, else a
/// layer with `R,G,B` (`*.Combined.` first, as Blender's multilayer files name it).
fn beauty_prefix(
    channels: &BTreeMap<String, Channel>,
    path: &Path,
) -> Result<Option<String>, Error> {
    let has = |name: &str| channels.contains_key(name);
    Ok(if has("R") && has("G") && has("B") {
        Some(String::new())
    } else if has("Y") {
        None
    } else {
        let prefixes: Vec<String> = channels
            .keys()
            .filter_map(|k| k.strip_suffix(".R").map(|p| format!("{p}.")))
            .filter(|p| has(&format!("{p}G")) && has(&format!("{p}B")))
            .collect();
        let chosen = prefixes
            .iter()
            .find(|p| p.ends_with("Combined."))
            .or(prefixes.first());
        match chosen {
            Some(p) => Some(p.clone()),
            None => {
                return Err(Error::NoBeauty {
                    path: path.to_path_buf(),
                    channels: channels.keys().cloned().collect::<Vec<_>>().join(", "),
                })
            }
        }
    })
}

/// The channels left after the beauty, grouped into layers by the name before their last dot,
/// interleaved per pixel in conventional channel order.
fn group_layers(channels: BTreeMap<String, Channel>, pixels: usize) -> Vec<Layer> {
    let mut grouped: BTreeMap<String, Vec<(String, Vec<f32>, SampleType)>> = BTreeMap::new();
    for (full, (_, samples, kind)) in channels {
        let (layer, channel) = match full.rfind('.') {
            Some(dot) => (full[..dot].to_owned(), full[dot + 1..].to_owned()),
            None => (String::new(), full),
        };
        grouped
            .entry(layer)
            .or_default()
            .push((channel, samples, kind));
    }
    grouped
        .into_iter()
        .map(|(name, mut list)| {
            list.sort_by(|a, b| {
                channel_rank(&a.0)
                    .cmp(&channel_rank(&b.0))
                    .then(a.0.cmp(&b.0))
            });
            let stride = list.len();
            let mut data = vec![0.0; pixels * stride];
            // A layer is half when all its channels are.
            let sample_type = if list.iter().all(|c| c.2 == SampleType::F16) {
                SampleType::F16
            } else {
                SampleType::F32
            };
            for (index, (_, samples, _)) in list.iter().enumerate() {
                for (p, &value) in samples.iter().enumerate() {
                    data[p * stride + index] = value;
                }
            }
            Layer {
                name,
                channels: list.into_iter().map(|(channel, ..)| channel).collect(),
                data,
                sample_type,
            }
        })
        .collect()
}

/// Conventional channel order within a layer, so `R,G,B` does not come back as `B,G,R`.
fn channel_rank(channel: &str) -> usize {
    ["R", "G", "B", "A", "X", "Y", "Z", "W", "U", "V"]
        .iter()
        .position(|c| *c == channel)
        .unwrap_or(usize::MAX)
}

/// Where the data window sits in the display window; `None` when they are the same, or when
/// the data window is not inside the display window (overscan), which [`Image`] cannot
/// describe: then the data window is the image.
fn placement(
    display: ::exr::meta::attribute::IntegerBounds,
    position: ::exr::math::Vec2<i32>,
    width: u32,
    height: u32,
) -> Option<Placement> {
    let (dx, dy) = (display.position.x(), display.position.y());
    let x = u32::try_from(i64::from(position.x()) - i64::from(dx)).ok()?;
    let y = u32::try_from(i64::from(position.y()) - i64::from(dy)).ok()?;
    let full_width = u32::try_from(display.size.width()).ok()?;
    let full_height = u32::try_from(display.size.height()).ok()?;
    let same = x == 0 && y == 0 && full_width == width && full_height == height;
    let inside = u64::from(x) + u64::from(width) <= u64::from(full_width)
        && u64::from(y) + u64::from(height) <= u64::from(full_height);
    (!same && inside).then_some(Placement {
        x,
        y,
        full_width,
        full_height,
    })
}
