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
mod options;
mod plan;

pub use options::{MergeError, MergeOptions, MergeSummary};

use crate::header::{self, split};
use aperture_imageio::{Image, MetaValue};
use aperture_render::film::Window;
use plan::{Part, Plan};
use std::path::{Path, PathBuf};

/// Merges the part files `parts` into `out` (EXR, written atomically); see the module
/// documentation for what is pasted, what is averaged and what is refused.
pub fn merge_exr(
    parts: &[PathBuf],
    out: &Path,
    opts: &MergeOptions,
) -> Result<MergeSummary, MergeError> {
    merge_exr_with(parts, out, opts, None)
}

/// [`merge_exr`], then the merged image denoised once by `denoiser`
/// ([`crate::denoised::denoise_image`]) before it is written: how a split render is denoised.
pub fn merge_exr_denoised(
    parts: &[PathBuf],
    out: &Path,
    opts: &MergeOptions,
    denoiser: &aperture_denoise::Denoiser,
) -> Result<MergeSummary, MergeError> {
    merge_exr_with(parts, out, opts, Some(denoiser))
}

fn merge_exr_with(
    parts: &[PathBuf],
    out: &Path,
    opts: &MergeOptions,
    denoiser: Option<&aperture_denoise::Denoiser>,
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
    if let Some(d) = denoiser {
        crate::denoised::denoise_image(&mut image, d).map_err(MergeError::Denoise)?;
    }
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
    set(
        &mut meta,
        split::SPP,
        clamped_int(i64::from(plan.ranges.samples())),
    );
    set(
        &mut meta,
        split::SAMPLE_OFFSET,
        clamped_int(i64::from(plan.ranges.first())),
    );
    set(
        &mut meta,
        split::SAMPLE_RANGES,
        MetaValue::Text(plan.ranges.to_string()),
    );
    set(&mut meta, split::MERGED_PARTS, clamped_int(merged_parts));
    if plan.window != Window::whole(plan.full.0, plan.full.1) {
        set(
            &mut meta,
            split::REGION,
            MetaValue::Text(header::region_text(&plan.window)),
        );
    }
    set_totals(&mut meta, reference, parts, image);
    meta.sort_by(|a, b| a.0.cmp(&b.0));
    meta
}

/// Sets `key` in `meta` to `value`, adding it when absent.
fn set(meta: &mut Vec<(String, MetaValue)>, key: &str, value: MetaValue) {
    match meta.iter_mut().find(|(k, _)| k == key) {
        Some(slot) => slot.1 = value,
        None => meta.push((key.to_string(), value)),
    }
}

/// `v` as a header integer, clamped to `0 ..= i32::MAX`.
fn clamped_int(v: i64) -> MetaValue {
    MetaValue::Int(v.clamp(0, i64::from(i32::MAX)) as i32)
}

/// The late values of the merged render: the parts' render times and dropped samples summed,
/// and the mean spp of the merged sample counts (when the reference part has one).
fn set_totals(
    meta: &mut Vec<(String, MetaValue)>,
    reference: &Part,
    parts: &[Part],
    image: &Image,
) {
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
    if let (secs, _, true) = totals(header::late::RENDER_TIME) {
        set(
            meta,
            header::late::RENDER_TIME,
            MetaValue::Float(secs as f32),
        );
    }
    if let (_, dropped, true) = totals(header::late::DROPPED) {
        set(meta, header::late::DROPPED, clamped_int(dropped));
    }
    if reference.meta(header::late::MEAN_SPP).is_some() {
        if let Some(counts) = image.layer(accumulate::SAMPLE_COUNT_LAYER) {
            let mean = counts.data.iter().map(|&c| f64::from(c)).sum::<f64>()
                / counts.data.len().max(1) as f64;
            set(meta, header::late::MEAN_SPP, MetaValue::Float(mean as f32));
        }
    }
}
