//! `aperture merge`: the parts of a render split across machines (SPEC §8) put back together,
//! as Cycles' `merge_images` and pbrt's `imgtool assemble` do.
//!
//! - Parts with **disjoint data windows** (tiles, `--region`/`--tile`) are pasted: each pixel
//!   is copied bit for bit, so the result equals the one-machine render exactly.
//! - Parts with the **same data window and disjoint sample ranges** (`--sample-offset`) are
//!   averaged per pixel, weighted by the samples each part took there (its `Debug Sample
//!   Count`, else its `spp`): the beauty, alpha and every averaged pass. Depth and Position
//!   (one centre ray per pixel, the same in every batch) come from the batch with the lowest
//!   offset; the sample counts add up. Light passes, which files store divided by their Color
//!   pass (Cycles' convention), are merged as `Direct × Color` products and divided again, so
//!   the merged passes still add up to the merged beauty. Cryptomatte ranks are merged from
//!   each part's (ID, coverage) pairs into sample counts per ID and ranked again.
//! - Tiles of sample batches (both at once) are averaged per tile, then pasted.
//!
//! Before reading any pixels every part's header is checked (see [`plan`]): the same scene,
//! pose and options (hashes and the pose in the header), windows equal or disjoint, sample ranges disjoint
//! within a window and the same for every window, and every pixel covered (unless
//! [`MergeOptions::allow_partial`]). A refusal names the part; nothing is written. The merge
//! holds the output image, the sums of the window being averaged and one part at a time, so
//! memory does not grow with the number of parts. The output is written atomically.
//!
//! Averaging is exact up to rounding when no sample was dropped (a NaN or infinite sample is
//! counted in `Debug Sample Count` but left out of its pixel's mean, so that pixel's weight is
//! off by the dropped samples). A merged Cryptomatte pixel keeps at most 16 IDs, as a render
//! does, and knows only the six strongest IDs of each part.

mod accumulate;
mod plan;

use crate::header::{self, split};
use aperture_imageio::{Image, MetaValue};
use aperture_render::film::Window;
use plan::{Part, Plan};
use std::path::{Path, PathBuf};

/// How [`merge_exr`] treats an incomplete set of parts.
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
        /// Its sample range.
        range: String,
        /// The other's.
        other_range: String,
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
        has: String,
        /// A part of a window with more.
        other: PathBuf,
        /// The ranges that one has.
        other_has: String,
    },
    /// A part's pixels do not match its header (the file changed while merging).
    #[error("{}: its pixels do not match its header (did the file change during the merge?)", path.display())]
    PartChanged {
        /// The part.
        path: PathBuf,
    },
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

/// Merges the part files `parts` into `out` (EXR, written atomically); see the module
/// documentation for what is pasted, what is averaged and what is refused.
pub fn merge_exr(
    parts: &[PathBuf],
    out: &Path,
    opts: &MergeOptions,
) -> Result<MergeSummary, MergeError> {
    if parts.is_empty() {
        return Err(MergeError::NoParts);
    }
    refuse_overwriting_a_part(parts, out)?;
    let headers = parts
        .iter()
        .map(|p| Part::read(p))
        .collect::<Result<Vec<_>, _>>()?;
    let plan = Plan::new(&headers, opts)?;
    let mut image = accumulate::merge_pixels(&plan, &headers)?;
    image.metadata = merged_metadata(&plan, &headers, &image);
    aperture_imageio::write_exr(out, &image).map_err(MergeError::Write)?;
    Ok(MergeSummary {
        parts: headers.len(),
        windows: plan.groups.len(),
        window: plan.window,
        image_size: plan.full,
        sample_ranges: plan.ranges.to_string(),
        complete: plan.complete,
    })
}

fn refuse_overwriting_a_part(parts: &[PathBuf], out: &Path) -> Result<(), MergeError> {
    let Ok(out_real) = out.canonicalize() else {
        return Ok(()); // the output does not exist yet
    };
    if parts
        .iter()
        .any(|p| p.canonicalize().is_ok_and(|p| p == out_real))
    {
        return Err(MergeError::OutputIsAPart {
            path: out.to_path_buf(),
        });
    }
    Ok(())
}

/// The output's header: the reference part's, with the sample range, region and the
/// render's totals (time, dropped samples, mean spp) of the merged result.
fn merged_metadata(plan: &Plan, parts: &[Part], image: &Image) -> Vec<(String, MetaValue)> {
    let reference = &parts[plan.groups[0].parts[0]];
    let totals = |key: &str| -> (f64, i64, bool) {
        let mut f = 0.0;
        let mut i = 0i64;
        let mut any = false;
        for p in parts {
            match p.meta(key) {
                Some(MetaValue::Float(v)) => (f, any) = (f + f64::from(*v), true),
                Some(MetaValue::Int(v)) => (i, any) = (i + i64::from(*v), true),
                _ => {}
            }
        }
        (f, i, any)
    };
    let merged_parts: i64 = parts
        .iter()
        .map(|p| match p.meta(split::MERGED_PARTS) {
            Some(MetaValue::Int(n)) => i64::from(*n).max(1),
            _ => 1,
        })
        .sum();
    let mut meta: Vec<(String, MetaValue)> = reference
        .metadata
        .iter()
        .filter(|(k, _)| {
            !matches!(
                k.as_str(),
                split::REGION | split::TILE | split::SAMPLE_RANGES | split::MERGED_PARTS
            )
        })
        .cloned()
        .collect();
    let set = |meta: &mut Vec<(String, MetaValue)>, key: &str, value: MetaValue| match meta
        .iter_mut()
        .find(|(k, _)| k == key)
    {
        Some(slot) => slot.1 = value,
        None => meta.push((key.to_string(), value)),
    };
    let clamp = |v: i64| MetaValue::Int(v.clamp(0, i64::from(i32::MAX)) as i32);
    set(
        &mut meta,
        split::SPP,
        clamp(i64::from(plan.ranges.samples())),
    );
    set(
        &mut meta,
        split::SAMPLE_OFFSET,
        clamp(i64::from(plan.ranges.first())),
    );
    set(
        &mut meta,
        split::SAMPLE_RANGES,
        MetaValue::Text(plan.ranges.to_string()),
    );
    set(&mut meta, split::MERGED_PARTS, clamp(merged_parts));
    if plan.window != Window::whole(plan.full.0, plan.full.1) {
        set(
            &mut meta,
            split::REGION,
            MetaValue::Text(header::region_text(&plan.window)),
        );
    }
    if let (secs, _, true) = totals(header::late::RENDER_TIME) {
        set(
            &mut meta,
            header::late::RENDER_TIME,
            MetaValue::Float(secs as f32),
        );
    }
    if let (_, dropped, true) = totals(header::late::DROPPED) {
        set(&mut meta, header::late::DROPPED, clamp(dropped));
    }
    if reference.meta(header::late::MEAN_SPP).is_some() {
        if let Some(counts) = image.layer(accumulate::SAMPLE_COUNT_LAYER) {
            let mean = counts.data.iter().map(|&c| f64::from(c)).sum::<f64>()
                / counts.data.len().max(1) as f64;
            set(
                &mut meta,
                header::late::MEAN_SPP,
                MetaValue::Float(mean as f32),
            );
        }
    }
    meta.sort_by(|a, b| a.0.cmp(&b.0));
    meta
}
