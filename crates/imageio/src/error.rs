//! The error type of image input and output, and the kinds of names it reports.

use std::path::PathBuf;

/// What kind of name an [`Error::InvalidName`] is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NameKind {
    /// A layer name.
    Layer,
    /// A channel name (within a layer, or the full `layer.channel`).
    Channel,
    /// A metadata key.
    Metadata,
}

impl std::fmt::Display for NameKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NameKind::Layer => "layer",
            NameKind::Channel => "channel",
            NameKind::Metadata => "metadata key",
        })
    }
}

/// Errors of image input and output.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The extension is neither `.exr` nor `.png`.
    #[error("{path}: unknown image format (use .exr or .png)")]
    UnknownFormat {
        /// The offending path.
        path: PathBuf,
    },
    /// Reading or writing failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The image has no pixels; neither EXR nor PNG can hold that.
    #[error("empty image ({width}x{height})")]
    EmptyImage {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// A pixel buffer does not have the size `width * height` (times channels) promises.
    #[error("{what}: {found} values, expected {expected}")]
    BufferSize {
        /// Which buffer (`rgba`, `layer 0 (`depth`)`).
        what: String,
        /// Values expected.
        expected: usize,
        /// Values found.
        found: usize,
    },
    /// A layer, channel or metadata name cannot be written.
    #[error("{kind} `{name}`: {reason}")]
    InvalidName {
        /// What the name names.
        kind: NameKind,
        /// The name.
        name: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// An option is out of range.
    #[error("option {option} = {value}: {reason}")]
    InvalidOption {
        /// The option (`exposure`).
        option: &'static str,
        /// Its value, printed.
        value: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// The EXR file is damaged, or the EXR encoder refused the data.
    #[error("{path}: EXR: {message}")]
    Exr {
        /// The file.
        path: PathBuf,
        /// The decoder's or encoder's message.
        message: String,
    },
    /// The EXR file is valid but holds something this reader does not handle.
    #[error("{path}: unsupported EXR: {what}")]
    UnsupportedExr {
        /// The file.
        path: PathBuf,
        /// What is not supported.
        what: String,
    },
    /// The EXR file has no beauty: no `R`,`G`,`B` (nor `Y`) channels.
    #[error("{path}: no R, G, B (or Y) channels; channels are: {channels}")]
    NoBeauty {
        /// The file.
        path: PathBuf,
        /// The channels the file has, comma-separated.
        channels: String,
    },
    /// The PNG encoder failed.
    #[error("{path}: PNG: {message}")]
    Png {
        /// The file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
    /// A Radiance HDR (or other non-EXR) image could not be decoded.
    #[error("{path}: {message}")]
    Decode {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        message: String,
    },
    /// Decoding the image would take more memory than allowed.
    #[error("{path}: a {width}x{height} image needs {} decoded, more than the {} allowed", human(*.needed), human(*.limit))]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Width the file claims.
        width: u32,
        /// Height the file claims.
        height: u32,
        /// Bytes decoding needs (u128: a header's u32 × u32 size times a texel's bytes can pass
        /// what a u64 counts).
        needed: u128,
        /// Bytes allowed.
        limit: u64,
    },
    /// Two images compared by a metric differ in size.
    #[error("images differ in size: {left:?} vs {right:?}")]
    SizeMismatch {
        /// (width, height) of the first image.
        left: (u32, u32),
        /// (width, height) of the second image.
        right: (u32, u32),
    },
}

/// Bytes in words for errors ("1.2 GB"), decimal units.
fn human(bytes: impl Into<u128>) -> String {
    let bytes: u128 = bytes.into();
    match bytes {
        0..1000 => format!("{bytes} B"),
        1000..1_000_000 => format!("{:.1} kB", bytes as f64 / 1e3),
        1_000_000..1_000_000_000 => format!("{:.1} MB", bytes as f64 / 1e6),
        _ => format!("{:.1} GB", bytes as f64 / 1e9),
    }
}
