//! What a merge is asked ([`MergeOptions`]), what it made ([`MergeSummary`]) and why it
//! refused ([`MergeError`]): the vocabulary every step of the merge shares.

use aperture_render::film::Window;
use std::path::PathBuf;

/// How [`super::merge_exr`] treats an incomplete set of parts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MergeOptions {
    /// Merge even when some pixels are covered by no part, or some window lacks sample ranges
    /// that others have: the output's data window is then the bounding box of the parts and
    /// uncovered pixels are 0 with a sample count of 0.
    pub allow_partial: bool,
}

/// What a merge put together.
#[derive(Debug, Clone, PartialEq)]
pub struct MergeSummary {
    /// Part files read.
    pub parts: usize,
    /// Distinct data windows (tiles) among them.
    pub windows: usize,
    /// The output's data window.
    pub window: Window,
    /// Size of the whole image.
    pub image_size: (u32, u32),
    /// The sample index ranges the output holds, `A-B,C-D`.
    pub sample_ranges: String,
    /// False when [`MergeOptions::allow_partial`] let missing pixels or samples through.
    pub complete: bool,
}

/// Why parts could not be merged. Every variant about a part names its file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MergeError {
    /// No part files were given.
    #[error("no parts to merge")]
    NoParts,
    /// A part could not be read: missing, truncated or damaged.
    #[error("{source} (a damaged or incomplete part: render it again)")]
    Read {
        /// The part.
        path: PathBuf,
        /// What the reader said (it names the file too).
        source: aperture_imageio::Error,
    },
    /// A part's header lacks what every part of an aperture render has.
    #[error("{}: not a part of an aperture render: its header has no {key}", path.display())]
    NotAPart {
        /// The part.
        path: PathBuf,
        /// The missing header attribute.
        key: &'static str,
    },
    /// A header attribute has a value merge cannot use.
    #[error("{}: header attribute {key} = {value} cannot be used: {why}", path.display())]
    BadHeader {
        /// The part.
        path: PathBuf,
        /// The attribute.
        key: &'static str,
        /// Its value.
        value: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A part renders another scene file than the first part.
    #[error(
        "{}: a render of another scene than {} (scene hash {found}, expected {expected})",
        path.display(), reference.display()
    )]
    OtherScene {
        /// The part.
        path: PathBuf,
        /// The part it was compared with.
        reference: PathBuf,
        /// Its scene hash.
        found: String,
        /// The reference's.
        expected: String,
    },
    /// A part shows the scene in another pose (another --time or --frame, or other
    /// animations) than the first part.
    #[error(
        "{}: the scene in another pose than in {} ({found}, expected {expected}); \
         parts of one image need the same --time/--frame and --animation",
        path.display(), reference.display()
    )]
    OtherPose {
        /// The part.
        path: PathBuf,
        /// The part it was compared with.
        reference: PathBuf,
        /// Its pose.
        found: String,
        /// The reference's.
        expected: String,
    },
    /// A part was rendered with other options than the first part.
    #[error(
        "{}: rendered with other options than {} (options hash {found}, expected {expected}); \
         every option but --spp, --sample-offset, --region and --tile must be the same",
        path.display(), reference.display()
    )]
    OtherOptions {
        /// The part.
        path: PathBuf,
        /// The part it was compared with.
        reference: PathBuf,
        /// Its options hash.
        found: String,
        /// The reference's.
        expected: String,
    },
    /// A part has other channels than the first part.
    #[error("{}: {what} than {}", path.display(), reference.display())]
    OtherChannels {
        /// The part.
        path: PathBuf,
        /// The part it was compared with.
        reference: PathBuf,
        /// The difference.
        what: String,
    },
    /// A part holds a channel merge does not know how to combine.
    #[error("{}: channel {channel} is not a pass aperture writes; merge cannot combine it", path.display())]
    UnknownChannel {
        /// The part.
        path: PathBuf,
        /// The channel.
        channel: String,
    },
    /// Two parts of the same window hold some of the same samples.
    #[error(
        "{}: samples {range} overlap samples {other_range} of {} (both region {region}); \
         batches of one window need disjoint --sample-offset ranges",
        path.display(), other.display()
    )]
    OverlappingSamples {
        /// The part.
        path: PathBuf,
        /// The part it overlaps.
        other: PathBuf,
        /// Its sample range (`Box<str>` here and in [`MergeError::MissingSamples`]: Windows'
        /// 32-byte `PathBuf` would otherwise make the error over clippy's 128-byte limit).
        range: Box<str>,
        /// The other's.
        other_range: Box<str>,
        /// Their window, `X0,Y0,X1,Y1`.
        region: String,
    },
    /// Two parts' windows share pixels without being the same window.
    #[error(
        "{}: region {region} overlaps region {other_region} of {} without being the same",
        path.display(), other.display()
    )]
    OverlappingRegions {
        /// The part.
        path: PathBuf,
        /// The part it overlaps.
        other: PathBuf,
        /// Its window.
        region: String,
        /// The other's.
        other_region: String,
    },
    /// Some pixels are covered by no part.
    #[error(
        "missing part: no part covers region {region}{tiles}; render it, or pass \
         --allow-partial to merge what there is"
    )]
    MissingRegion {
        /// The first uncovered rectangle, `X0,Y0,X1,Y1`.
        region: String,
        /// `(--tile K/N, …)` when the parts are tiles and these are the missing ones.
        tiles: String,
    },
    /// A window lacks samples that other windows have.
    #[error(
        "{}: region {region} has samples {has} but {} has {other_has}: a batch is missing \
         (or pass --allow-partial)",
        path.display(), other.display()
    )]
    MissingSamples {
        /// A part of the window lacking samples.
        path: PathBuf,
        /// Its window.
        region: String,
        /// The ranges it has.
        has: Box<str>,
        /// A part of a window with more.
        other: PathBuf,
        /// The ranges that one has.
        other_has: Box<str>,
    },
    /// A part's pixels do not match its header (the file changed while merging).
    #[error("{}: its pixels do not match its header (did the file change during the merge?)", path.display())]
    PartChanged {
        /// The part.
        path: PathBuf,
    },
    /// A part is denoised: denoising is not linear (the mean of denoised parts is not the
    /// denoised mean), so parts are merged first and denoised once (`merge --denoise`).
    #[error(
        "{}: a denoised part (aperture:denoised = 1): denoising is not linear, so parts must \
         be merged undenoised and the result denoised once: render the parts without \
         --denoise and run `aperture merge ... --denoise`",
        path.display()
    )]
    DenoisedPart {
        /// The part.
        path: PathBuf,
    },
    /// The merged image could not be denoised.
    #[error(transparent)]
    Denoise(crate::denoised::DenoisingError),
    /// The output would overwrite one of the parts.
    #[error("{}: the output is one of the parts", path.display())]
    OutputIsAPart {
        /// The output path.
        path: PathBuf,
    },
    /// The merged image could not be written.
    #[error(transparent)]
    Write(aperture_imageio::Error),
}
