//! EXR writing: one scan-line part, ZIP-compressed (lossless, 16 rows a block), rows streamed
//! top to bottom, so a renderer can hand over an image band by band and never hold all of it.
//!
//! Every file this crate writes goes through [`write_exr_streamed`]; [`write_exr`] and
//! [`encode_exr`] stream a whole [`Image`] through it in one go.

use std::fs::File;
use std::io::{BufWriter, Cursor, Read, Seek, SeekFrom, Write};
use std::path::Path;

use ::exr::block::writer::ChunksWriter as _;
use ::exr::block::{self, chunk::Chunk, BlockIndex, UncompressedBlock};
use ::exr::math::Vec2;
use ::exr::meta::attribute::{ChannelDescription, IntegerBounds, SampleType as ExrSampleType};
use ::exr::meta::header::{Header, ImageAttributes, LayerAttributes};
use ::exr::meta::{BlockDescription, MetaData};
use ::exr::prelude::{f16, Compression, LineOrder, SmallVec};
use rayon::prelude::*;

use super::attrs::{patch_attribute, set_attribute, sort_header_attributes, text};
use crate::atomic::write_atomically_with;
use crate::error::{Error, NameKind};
use crate::model::{Image, MetaValue, Placement, SampleType};

/// Rows per ZIP block (the codec's own block height).
const BLOCK_ROWS: usize = 16;

/// One channel of a streamed file.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSpec {
    /// Full channel name (`R`, `Depth.Z`, `Denoising Albedo.G`).
    pub name: String,
    /// How the file stores it.
    pub sample_type: SampleType,
}

/// Everything about an EXR file but its pixels.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExrLayout {
    /// Width of the pixels written (the data window).
    pub width: u32,
    /// Height of the pixels written.
    pub height: u32,
    /// Where those pixels sit in the whole image; `None` when they are the whole image.
    pub placement: Option<Placement>,
    /// The channels, in the order their values are interleaved in the rows handed to
    /// [`RowWriter::push_rows`] (the file stores them sorted by name, as EXR requires).
    pub channels: Vec<ChannelSpec>,
    /// Header attributes, as [`Image::metadata`] describes them.
    pub metadata: Vec<(String, MetaValue)>,
}

impl ExrLayout {
    /// Checks channel and metadata names and the placement.
    pub fn validate(&self) -> Result<(), Error> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::EmptyImage {
                width: self.width,
                height: self.height,
            });
        }
        if self.channels.is_empty() {
            return Err(Error::InvalidName {
                kind: NameKind::Channel,
                name: String::new(),
                reason: "an EXR file needs at least one channel",
            });
        }
        let mut names: Vec<&str> = Vec::with_capacity(self.channels.len());
        for c in &self.channels {
            let bad = |reason| Error::InvalidName {
                kind: NameKind::Channel,
                name: c.name.clone(),
                reason,
            };
            if c.name.is_empty() || c.name.contains('\0') || c.name.ends_with('.') {
                return Err(bad("must be non-empty, without NUL, not ending in `.`"));
            }
            if c.name.len() > 255 {
                return Err(bad("longer than 255 bytes"));
            }
            if names.contains(&c.name.as_str()) {
                return Err(bad("appears twice"));
            }
            names.push(&c.name);
        }
        crate::model::validate_metadata(&self.metadata)?;
        if let Some(p) = &self.placement {
            let fits = u64::from(p.x) + u64::from(self.width) <= u64::from(p.full_width)
                && u64::from(p.y) + u64::from(self.height) <= u64::from(p.full_height);
            if !fits || p.full_width > i32::MAX as u32 || p.full_height > i32::MAX as u32 {
                return Err(Error::InvalidOption {
                    option: "placement",
                    value: format!(
                        "{}x{} at ({}, {}) in {}x{}",
                        self.width, self.height, p.x, p.y, p.full_width, p.full_height
                    ),
                    reason: "the pixels must lie inside the whole image",
                });
            }
        }
        Ok(())
    }

    /// Bytes one row takes in the file before compression.
    fn row_bytes(&self) -> usize {
        self.channels
            .iter()
            .map(|c| match c.sample_type {
                SampleType::F32 => 4,
                SampleType::F16 => 2,
            })
            .sum::<usize>()
            * self.width as usize
    }
}

/// Receives an image's rows, top to bottom, and writes them out block by block.
pub struct RowWriter<'a> {
    headers: &'a [Header],
    blocks: Vec<(usize, BlockIndex)>,
    next_block: usize,
    width: usize,
    height: usize,
    /// Channel values per pixel in pushed rows.
    stride: usize,
    /// Layout index of each channel in file (name) order, with its sample type.
    order: Vec<(usize, SampleType)>,
    row_bytes: usize,
    pending: Vec<f32>,
    /// Index of the first row in `pending`.
    pending_from: usize,
    received: usize,
    write_chunk: &'a mut dyn FnMut(usize, Chunk) -> ::exr::error::UnitResult,
    path: &'a Path,
}

impl RowWriter<'_> {
    /// Rows received so far.
    pub fn rows_written(&self) -> u32 {
        self.received as u32
    }

    /// Appends whole rows below the ones already given: `values` holds `rows × width ×
    /// channels` numbers, each pixel's channels together in the layout's order. Complete
    /// blocks are compressed (in parallel) and written at once, so memory stays at one block
    /// height plus what the caller holds.
    pub fn push_rows(&mut self, values: &[f32]) -> Result<(), Error> {
        let per_row = self.width * self.stride;
        let rows = values.len() / per_row.max(1);
        if values.len() % per_row != 0 || self.received + rows > self.height {
            return Err(Error::BufferSize {
                what: format!("rows {}.. of {}", self.received, self.path.display()),
                expected: (self.height - self.received) * per_row,
                found: values.len(),
            });
        }
        self.pending.extend_from_slice(values);
        self.received += rows;
        self.flush_blocks()
    }

    /// Writes every block whose rows have all arrived.
    fn flush_blocks(&mut self) -> Result<(), Error> {
        let ready: Vec<(usize, BlockIndex)> = self.blocks[self.next_block..]
            .iter()
            .take_while(|(_, b)| b.pixel_position.y() + b.pixel_size.height() <= self.received)
            .copied()
            .collect();
        if ready.is_empty() {
            return Ok(());
        }
        let headers = self.headers;
        let (pending, from) = (&self.pending, self.pending_from);
        let (width, stride, order, row_bytes) =
            (self.width, self.stride, &self.order, self.row_bytes);
        let chunks: Vec<Result<Chunk, ::exr::error::Error>> = ready
            .par_iter()
            .map(|&(_, index)| {
                let data = block_bytes(pending, from, width, stride, order, row_bytes, index);
                UncompressedBlock { index, data }.compress_to_chunk(headers)
            })
            .collect();
        for ((i, _), chunk) in ready.iter().zip(chunks) {
            let written = chunk.and_then(|c| (self.write_chunk)(*i, c));
            written.map_err(|e| exr_error(self.path, e))?;
        }
        self.next_block += ready.len();
        let last = ready.last().expect("not empty").1;
        let done = last.pixel_position.y() + last.pixel_size.height();
        let consumed = (done - self.pending_from) * self.width * self.stride;
        self.pending.drain(..consumed);
        self.pending_from = done;
        Ok(())
    }
}

/// The uncompressed bytes of one block: for each row, each channel's samples in turn
/// (little-endian), channels in name order. `pending` holds rows from `pending_from` on.
fn block_bytes(
    pending: &[f32],
    pending_from: usize,
    width: usize,
    stride: usize,
    order: &[(usize, SampleType)],
    row_bytes: usize,
    index: BlockIndex,
) -> Vec<u8> {
    let (y0, rows) = (index.pixel_position.y(), index.pixel_size.height());
    let mut out = Vec::with_capacity(rows * row_bytes);
    for y in y0..y0 + rows {
        let row = &pending[(y - pending_from) * width * stride..][..width * stride];
        for &(c, kind) in order {
            let values = row.iter().skip(c).step_by(stride);
            match kind {
                SampleType::F32 => values.for_each(|v| out.extend(v.to_le_bytes())),
                SampleType::F16 => values.for_each(|v| out.extend(f16::from_f32(*v).to_le_bytes())),
            }
        }
    }
    out
}

fn exr_error(path: &Path, e: ::exr::error::Error) -> Error {
    Error::Exr {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The header of a layout: one scan-line part, ZIP16, rows top to bottom.
fn header(layout: &ExrLayout) -> Result<Header, Error> {
    let mut channels: Vec<ChannelDescription> = layout
        .channels
        .iter()
        .map(|c| {
            let kind = match c.sample_type {
                SampleType::F32 => ExrSampleType::F32,
                SampleType::F16 => ExrSampleType::F16,
            };
            ChannelDescription::named(text(&c.name), kind)
        })
        .collect();
    channels.sort_by(|a, b| a.name.cmp(&b.name));
    let size = Vec2(layout.width as usize, layout.height as usize);
    let (position, display) = match &layout.placement {
        Some(p) => (
            Vec2(p.x as i32, p.y as i32),
            IntegerBounds::new(
                Vec2(0, 0),
                Vec2(p.full_width as usize, p.full_height as usize),
            ),
        ),
        None => (Vec2(0, 0), IntegerBounds::new(Vec2(0, 0), size)),
    };
    let mut image_attrs = ImageAttributes::new(display);
    let mut attrs = LayerAttributes {
        layer_position: position,
        ..LayerAttributes::default()
    };
    for (key, value) in &layout.metadata {
        set_attribute(&mut image_attrs, &mut attrs, key, value)?;
    }
    let header = Header::new(text(""), size, SmallVec::from_vec(channels))
        .with_encoding(
            Compression::ZIP16,
            BlockDescription::ScanLines,
            // Increasing: rows top to bottom in the file, and a deterministic block order.
            LineOrder::Increasing,
        )
        .with_shared_attributes(image_attrs)
        .with_attributes(attrs);
    Ok(header)
}

/// Streams an EXR file into `sink`: the header, then the blocks `produce` hands over through
/// the [`RowWriter`]. Attributes come out in hash-map order; the caller sorts them.
fn write_stream<W: Write + Seek, E: From<Error>>(
    sink: W,
    layout: &ExrLayout,
    path: &Path,
    produce: impl FnOnce(&mut RowWriter<'_>) -> Result<LateValues, E>,
) -> Result<LateValues, E> {
    layout.validate()?;
    let header = header(layout)?;
    let mut failure: Option<E> = None;
    let mut late = LateValues::new();
    let result = block::write(
        sink,
        SmallVec::from_vec(vec![header]),
        true,
        |meta, writer| {
            let MetaData { headers, .. } = &meta;
            let blocks: Vec<(usize, BlockIndex)> =
                block::enumerate_ordered_header_block_indices(headers).collect();
            let mut write_chunk = |i: usize, chunk: Chunk| writer.write_chunk(i, chunk);
            let mut rows = RowWriter {
                headers,
                blocks,
                next_block: 0,
                width: layout.width as usize,
                height: layout.height as usize,
                stride: layout.channels.len(),
                order: file_order(layout),
                row_bytes: layout.row_bytes(),
                pending: Vec::new(),
                pending_from: 0,
                received: 0,
                write_chunk: &mut write_chunk,
                path,
            };
            let outcome = produce(&mut rows).and_then(|values| {
                if rows.received == rows.height {
                    late = values;
                    Ok(())
                } else {
                    Err(E::from(Error::BufferSize {
                        what: format!("rows of {}", path.display()),
                        expected: rows.height,
                        found: rows.received,
                    }))
                }
            });
            outcome.map_err(|e| {
                failure = Some(e);
                ::exr::error::Error::Aborted
            })
        },
    );
    if let Some(e) = failure {
        return Err(e);
    }
    result.map_err(|e| E::from(exr_error(path, e)))?;
    Ok(late)
}

/// Header values known only once the pixels are written (a render's time, its dropped
/// samples), as `(key, value)`: each replaces the value of an attribute of the same key and
/// type (f32 or i32) that the layout already holds.
pub type LateValues = Vec<(String, MetaValue)>;

/// Sorts the header of the file in `bytes` and patches the late values into it.
fn finish_header(bytes: &mut [u8], late: &LateValues, path: &Path) -> Result<(), Error> {
    for (key, value) in late {
        if !patch_attribute(bytes, key, value) {
            return Err(Error::InvalidName {
                kind: NameKind::Metadata,
                name: key.clone(),
                reason: "a late value needs an attribute of its key and type in the layout",
            });
        }
    }
    if sort_header_attributes(bytes) {
        Ok(())
    } else {
        Err(Error::Exr {
            path: path.to_path_buf(),
            message: "the encoder wrote an unexpected header layout".into(),
        })
    }
}

/// Layout index and type of each channel, in the order the file stores them (by name).
fn file_order(layout: &ExrLayout) -> Vec<(usize, SampleType)> {
    let mut order: Vec<usize> = (0..layout.channels.len()).collect();
    order.sort_by(|&a, &b| {
        layout.channels[a]
            .name
            .as_bytes()
            .cmp(layout.channels[b].name.as_bytes())
    });
    order
        .into_iter()
        .map(|i| (i, layout.channels[i].sample_type))
        .collect()
}

/// Writes an EXR file whose rows `produce` hands over top to bottom through the
/// [`RowWriter`], without ever holding the whole image: how a renderer writes a large image
/// band by band. `produce` returns [`LateValues`] for attributes it could only know at the
/// end. The file appears whole under `path`, or not at all: an error from `produce` (or too
/// few rows) leaves no file behind.
///
/// The file is one scan-line part, ZIP-compressed (lossless, 16 rows a block), channels as
/// [`ExrLayout`] gives them, header attributes sorted by name so the bytes depend only on
/// the layout and the values.
pub fn write_exr_streamed<E: From<Error>>(
    path: &Path,
    layout: &ExrLayout,
    produce: impl FnOnce(&mut RowWriter<'_>) -> Result<LateValues, E>,
) -> Result<(), E> {
    layout.validate()?;
    write_atomically_with(path, |file| {
        let late = write_stream(BufWriter::new(&*file), layout, path, produce)?;
        finish_file_header(file, &late, path).map_err(E::from)
    })
}

/// [`finish_header`] on the header at the start of `file`, in place, reading only as much of
/// the file as the header takes.
fn finish_file_header(file: &mut File, late: &LateValues, path: &Path) -> Result<(), Error> {
    let io = |e: std::io::Error| Error::Io {
        path: path.to_path_buf(),
        message: format!("sorting the header: {e}"),
    };
    let len = file.metadata().map_err(io)?.len();
    let mut size = 1 << 16;
    loop {
        let take = size.min(len);
        let mut head = vec![0; take as usize];
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.read_exact(&mut head).map_err(io)?;
        if take == len || super::guard::walk_header(&head, 8).is_some() {
            finish_header(&mut head, late, path)?;
            file.seek(SeekFrom::Start(0)).map_err(io)?;
            return file.write_all(&head).map_err(io);
        }
        size *= 4;
    }
}

/// The layout of `image`: the beauty's `R,G,B,A` (unprefixed unless it has a
/// [`Image::beauty_layer`]), each layer's channels as `layer.channel`.
fn image_layout(image: &Image) -> ExrLayout {
    let mut channels: Vec<ChannelSpec> = image
        .beauty_channel_names()
        .map(|name| ChannelSpec {
            name,
            sample_type: image.beauty_type,
        })
        .into();
    for layer in &image.layers {
        for c in &layer.channels {
            channels.push(ChannelSpec {
                name: layer.full_channel_name(c),
                sample_type: layer.sample_type,
            });
        }
    }
    ExrLayout {
        width: image.width,
        height: image.height,
        placement: image.placement,
        channels,
        metadata: image.metadata.clone(),
    }
}

/// Hands `image` to a [`RowWriter`] a block height at a time.
fn push_image(image: &Image, rows: &mut RowWriter<'_>) -> Result<(), Error> {
    let w = image.width as usize;
    let stride = 4 + image.layers.iter().map(|l| l.channels.len()).sum::<usize>();
    let mut band = Vec::with_capacity(BLOCK_ROWS * w * stride);
    for y0 in (0..image.height as usize).step_by(BLOCK_ROWS) {
        band.clear();
        for p in y0 * w..(y0 + BLOCK_ROWS).min(image.height as usize) * w {
            band.extend_from_slice(&image.rgba[p]);
            for layer in &image.layers {
                let n = layer.channels.len();
                band.extend_from_slice(&layer.data[p * n..(p + 1) * n]);
            }
        }
        rows.push_rows(&band)?;
    }
    Ok(())
}

/// Encodes `image` as EXR into memory, laid out as [`write_exr`] describes. `path` only names
/// the file in errors.
pub fn encode_exr(image: &Image, path: &Path) -> Result<Vec<u8>, Error> {
    image.validate()?;
    let mut bytes = Vec::new();
    let late = write_stream(
        Cursor::new(&mut bytes),
        &image_layout(image),
        path,
        |rows| push_image(image, rows).map(|()| LateValues::new()),
    )?;
    // The encoder writes custom attributes in hash-map order, which changes from run to run;
    // sorting them makes the file a pure function of the image.
    finish_header(&mut bytes, &late, path)?;
    Ok(bytes)
}

/// Writes `image` to `path` as EXR, atomically.
///
/// The file is one scan-line part, ZIP-compressed (lossless, 16 rows a block), rows top to
/// bottom: the beauty in the unnamed layer's `R`,`G`,`B`,`A` (premultiplied, as EXR expects),
/// so every viewer shows it (or in [`Image::beauty_layer`]'s, for a file read from Blender); each [`crate::Layer`] as `name.channel` channels beside it, in
/// its [`SampleType`]; [`Image::metadata`] as header attributes; [`Image::placement`] as the
/// data window inside the display window. The bytes depend only on `image`.
pub fn write_exr(path: &Path, image: &Image) -> Result<(), Error> {
    image.validate()?;
    write_exr_streamed(path, &image_layout(image), |rows| {
        push_image(image, rows).map(|()| LateValues::new())
    })
}
