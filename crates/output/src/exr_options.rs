//! How an EXR render is written: half floats, a region or tile, the band size, partial saves.

use aperture_render::film::Window;

/// Most bytes the sums of one band may take (the band height follows from it).
pub const BAND_BYTES: usize = 512 << 20;

/// How an EXR render is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExrOptions {
    /// Colour passes (the beauty, light passes, denoising albedo) as half floats, clamped to
    /// ±65504; data passes stay float32.
    pub half: bool,
    /// Render only this part of the image (a tile); the file's data window is the part and its
    /// display window the whole image.
    pub region: Option<Window>,
    /// `(K, N)` when `region` is band K of N (`--tile K/N`, see [`Window::band`]): recorded
    /// in the header so `aperture merge` can name a missing tile.
    pub tile: Option<(u32, u32)>,
    /// Most bytes the sums of one band of rows may take ([`BAND_BYTES`] by default): lower
    /// it to render in more, smaller bands with less memory. The pixels do not change.
    pub band_bytes: usize,
    /// When the render is cancelled, write the samples taken so far (each pixel's count in
    /// `Debug Sample Count`, `aperture:interrupted` = 1 in the header) instead of nothing.
    /// Ask for [`Pass::SampleCount`](aperture_render::passes::Pass::SampleCount) in the options' passes, so the file has the counts.
    pub save_partial: bool,
}

impl Default for ExrOptions {
    fn default() -> Self {
        Self {
            half: false,
            region: None,
            tile: None,
            band_bytes: BAND_BYTES,
            save_partial: false,
        }
    }
}
