//! What a render will need, computed before anything is loaded or allocated: memory for the
//! film (whole for PNG, one band of rows for EXR) and disk for the file, checked against the
//! machine, so an impossible job fails in a moment with the numbers instead of being killed
//! an hour in.

use std::path::Path;

use aperture_budget::{human_bytes, MemoryBudget, OverBudget};

use crate::channels;
use crate::exr_options::{ExrOptions, BAND_BYTES};
use aperture_render::film::AovLayout;
use aperture_render::passes::Pass;
use aperture_render::{PassSet, RenderOptions, Window};

/// The kinds of output file, which need memory differently.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputKind {
    /// EXR, rendered and written band by band.
    Exr,
    /// EXR with the beauty denoised ([`crate::write::write_image`] with a denoiser): rendered band by band,
    /// but the resolved window is held until it is denoised.
    ExrDenoised,
    /// PNG, rendered whole in memory; 16 bits per channel when `sixteen_bit`.
    Png {
        /// 16 bits per channel.
        sixteen_bit: bool,
    },
}

/// The estimated needs of one render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Footprint {
    /// Peak bytes of the film and its output buffers (not the scene and BVH, which the loader
    /// budgets itself).
    pub memory: u64,
    /// Bytes of the output file before compression: what it takes at most.
    pub disk: u64,
}

/// Why a render cannot start.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FootprintError {
    /// The film does not fit in memory.
    #[error(transparent)]
    Memory(#[from] OverBudget),
    /// The file cannot fit on its disk even compressed four to one.
    #[error("{path}: the EXR needs up to {} ({} even compressed four to one), but its disk has {} free", human_bytes(*.needed), human_bytes(*.needed / 4), human_bytes(*.free))]
    Disk {
        /// The output file.
        path: String,
        /// Uncompressed bytes.
        needed: u64,
        /// Free bytes on its file system.
        free: u64,
    },
}

/// Film bytes per pixel for PNG at its peak: the film's sums twice (every tile's sums are
/// collected before they are merged into the film), or, once the tiles are freed, the film
/// with the resolved RGBA (f32) and the encoder's 8- or 16-bit buffer and output. Measured:
/// 87 bytes a pixel for a 2000x2000 render, estimated 88.
fn png_bytes_per_pixel(adaptive: bool, sixteen_bit: bool) -> u64 {
    let sums = film_bytes_per_pixel(PassSet::NONE, adaptive, 0) as u64;
    let encoded = if sixteen_bit { 8 } else { 4 };
    (2 * sums).max(sums + 16 + 2 * encoded)
}

fn sample_bytes_of(t: aperture_imageio::SampleType) -> u64 {
    match t {
        aperture_imageio::SampleType::F16 => 2,
        _ => 4,
    }
}

/// Estimates what rendering `opts` into `kind` needs (`exr`: the band size, region and half
/// floats of EXR output).
pub fn footprint(opts: &RenderOptions, kind: OutputKind, exr: &ExrOptions) -> Footprint {
    let whole = Window::whole(opts.width, opts.height);
    let adaptive = opts.adaptive.is_some();
    match kind {
        OutputKind::Png { sixteen_bit } => {
            let pixels = whole.pixels() as u64;
            Footprint {
                memory: pixels * png_bytes_per_pixel(adaptive, sixteen_bit),
                disk: pixels * if sixteen_bit { 8 } else { 4 },
            }
        }
        OutputKind::Exr | OutputKind::ExrDenoised => {
            let window = exr.region.unwrap_or(whole);
            let asked = match kind {
                OutputKind::ExrDenoised => crate::denoised::with_aux(opts.passes),
                _ => opts.passes,
            };
            let passes =
                channels::file_passes(asked, crate::region::needs_sample_count(opts, window));
            let specs = channels::channels(passes, exr.half);
            let bpp = film_bytes_per_pixel(passes, adaptive, specs.len());
            let rows = u64::from(aperture_render::bands::band_rows(
                window,
                exr.band_bytes,
                bpp,
            ));
            let (w, bpp) = (u64::from(window.width), bpp as u64);
            // Adaptive rounds render an apron of one pixel per round around the band.
            let apron = if adaptive { 2 * 17 } else { 0 };
            let band = (w + apron) * (rows + apron);
            let sample_bytes: u64 = specs.iter().map(|c| sample_bytes_of(c.sample_type)).sum();
            // An upper bound: a 4000x2000 render with the default passes peaked at 187 MB
            // where this says 473 MB (output::film_bytes_per_pixel counts every Cryptomatte
            // rank slot).
            // Denoising holds the window's values and their denoised copy (4 more channels,
            // the noisy beauty), plus the denoiser's five RGB float images; the file gets the
            // noisy beauty's 4 channels, colour ones (half with --half).
            let (held, noisy) = match kind {
                OutputKind::ExrDenoised => {
                    let channels = specs.len() as u64;
                    let held = window.pixels() as u64 * (4 * (2 * channels + 4) + 5 * 12);
                    (held, 4 * sample_bytes_of(specs[0].sample_type))
                }
                _ => (0, 0),
            };
            Footprint {
                memory: band * bpp + held,
                disk: window.pixels() as u64 * (sample_bytes + noisy),
            }
        }
    }
}

/// Checks that rendering `opts` into `path` fits: memory against `budget` (an error above it;
/// a warning above what is free right now) and, for EXR, disk (an error when the file cannot
/// fit even compressed four to one; a warning when it may not fit uncompressed). Returns the
/// warnings.
pub fn check_output(
    opts: &RenderOptions,
    kind: OutputKind,
    exr: &ExrOptions,
    path: &Path,
    budget: &MemoryBudget,
) -> Result<Vec<String>, FootprintError> {
    let f = footprint(opts, kind, exr);
    let (what, hint) = match kind {
        OutputKind::Png { .. } => (
            format!("a {}x{} PNG render", opts.width, opts.height),
            "; EXR output renders in bands and needs far less (-o NAME.exr)",
        ),
        OutputKind::Exr | OutputKind::ExrDenoised => (
            format!(
                "a {}x{} EXR render ({} bands of rows)",
                opts.width,
                opts.height,
                if exr.band_bytes == BAND_BYTES {
                    "default"
                } else {
                    "smaller"
                }
            ),
            "",
        ),
    };
    budget.check_with_hint(&what, f.memory, hint)?;
    let mut warnings = Vec::new();
    if let Some(m) = aperture_budget::system_memory() {
        if f.memory > m.available {
            warnings.push(format!(
                "{what} needs about {} of memory; {} is free now",
                human_bytes(f.memory),
                human_bytes(m.available)
            ));
        }
    }
    if let Some(free) = aperture_budget::free_disk_bytes(path) {
        let exr = matches!(kind, OutputKind::Exr | OutputKind::ExrDenoised);
        if exr && f.disk / 4 > free {
            return Err(FootprintError::Disk {
                path: path.display().to_string(),
                needed: f.disk,
                free,
            });
        }
        if f.disk > free {
            warnings.push(format!(
                "{}: the file may take up to {} uncompressed; its disk has {} free",
                path.display(),
                human_bytes(f.disk),
                human_bytes(free)
            ));
        }
    }
    Ok(warnings)
}

/// Bytes the sums of one pixel take while rendering with `passes`, and while writing it
/// (`channels` values of its row): what decides a band's height.
pub fn film_bytes_per_pixel(passes: PassSet, adaptive: bool, channels: usize) -> usize {
    let layout = AovLayout::new(passes);
    let crypto = usize::from(layout.crypto_object) + usize::from(layout.crypto_material);
    let accum =
        std::mem::size_of::<aperture_render::film::PixelSum>() + 8 * layout.stride + 128 * crypto;
    let film = accum
        + 4
        + 4 * usize::from(passes.contains(Pass::Depth))
        + 12 * usize::from(passes.contains(Pass::Position))
        + 16 * usize::from(passes.contains(Pass::Vector));
    // Adaptive rounds keep their own state (sums, squares, counts, flags) beside the film.
    let rounds = if adaptive { accum + 24 + 8 + 4 + 3 } else { 0 };
    film + rounds + 4 * channels
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(w: u32, h: u32) -> RenderOptions {
        RenderOptions {
            width: w,
            height: h,
            passes: PassSet::compositing(),
            ..RenderOptions::default()
        }
    }

    #[test]
    fn a_denoised_exr_holds_its_whole_window() {
        let exr = ExrOptions::default();
        let (d, e) = (OutputKind::ExrDenoised, OutputKind::Exr);
        let held = |w: u32| {
            let o = opts(w, w);
            footprint(&o, d, &exr).memory - footprint(&o, e, &exr).memory
        };
        // Band-bounded without denoising; the whole window's values with it.
        assert_eq!(held(8000) / held(1000), 64);
        assert!(held(8000) > 8000 * 8000 * 100, "{}", held(8000));
        let o = opts(8000, 8000);
        assert!(footprint(&o, d, &exr).disk > footprint(&o, e, &exr).disk);
    }

    #[test]
    fn png_memory_grows_with_the_image_and_exr_memory_with_one_band() {
        let png = OutputKind::Png { sixteen_bit: false };
        let exr = ExrOptions::default();
        let small = footprint(&opts(1000, 1000), png, &exr);
        let big = footprint(&opts(65536, 65536), png, &exr);
        assert_eq!(big.memory / small.memory, 4294);
        assert!(big.memory > 100_000_000_000, "{}", big.memory);
        let e = footprint(&opts(65536, 65536), OutputKind::Exr, &exr);
        // One band: at this width the band is one tile row (32 rows), above BAND_BYTES.
        assert!(
            e.memory < 3 << 30 && e.memory * 100 < big.memory,
            "{}",
            e.memory
        );
        assert!(e.disk > 100_000_000_000, "{}", e.disk);
    }

    #[test]
    fn a_65536_square_png_is_refused_with_both_sizes() {
        let e = check_output(
            &opts(65536, 65536),
            OutputKind::Png { sixteen_bit: false },
            &ExrOptions::default(),
            Path::new("/tmp/x.png"),
            &MemoryBudget::fixed(23_000_000_000),
        )
        .unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("a 65536x65536 PNG render needs "), "{m}");
        assert!(
            m.contains("GB but the memory limit (--max-memory) is 23.0 GB"),
            "{m}"
        );
        assert!(check_output(
            &opts(64, 64),
            OutputKind::Png { sixteen_bit: false },
            &ExrOptions::default(),
            Path::new("/tmp/x.png"),
            &MemoryBudget::fixed(1 << 30),
        )
        .unwrap()
        .is_empty());
    }
}
