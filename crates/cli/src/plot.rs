//! Plot helpers the bench commands share: a font for the labels, tick text for log axes, a
//! palette, and PNG output through plotters' bitmap backend.

use anyhow::Context as _;
use plotters::coord::{CoordTranslate, Shift};
use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::{
    BitMapBackend, ChartContext, Color as _, DrawingArea, DrawingBackend, IntoDrawingArea,
    RGBColor, SeriesLabelPosition, BLACK, WHITE,
};
use std::path::{Path, PathBuf};

/// Line colours (matplotlib's first seven), in the order series take them.
pub(crate) const PALETTE: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(23, 190, 207),
];

/// Draws a `size` picture with `draw` and writes it as a PNG at `png` (through a temporary file
/// renamed into place). The font must be registered first ([`load_font`]).
pub(crate) fn write_png(
    png: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw(&root)?;
        root.present()
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
    }
    let tmp = png.with_extension("png.tmp");
    image::save_buffer_with_format(
        &tmp,
        &buf,
        size.0,
        size.1,
        image::ColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, png).with_context(|| format!("writing {}", png.display()))
}

/// Registers a sans-serif TrueType font for bitmap text: `APERTURE_FONT`, else the first of a
/// few common system fonts. False when none can be read.
pub(crate) fn load_font() -> bool {
    static LOADED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *LOADED.get_or_init(|| {
        let candidates = std::env::var_os("APERTURE_FONT")
            .map(PathBuf::from)
            .into_iter()
            .chain(
                [
                    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                    "/usr/share/fonts/TTF/DejaVuSans.ttf",
                    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
                    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
                    "/System/Library/Fonts/Supplemental/Arial.ttf",
                    "C:\\Windows\\Fonts\\arial.ttf",
                ]
                .map(PathBuf::from),
            );
        for path in candidates {
            if let Ok(bytes) = std::fs::read(&path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font(
                    "sans-serif",
                    plotters::style::FontStyle::Normal,
                    bytes,
                )
                .is_ok()
                {
                    return true;
                }
            }
        }
        false
    })
}

/// Log-axis tick text: only 1, 2 and 5 times a power of ten, so labels never overlap.
pub(crate) fn tick_label(v: f64) -> String {
    let lead = v / 10f64.powf(v.log10().floor());
    if [1.0, 2.0, 5.0].iter().any(|d| (lead - d).abs() < 1e-6) {
        format!("{}", (v * 1e6).round() / 1e6)
    } else {
        String::new()
    }
}

/// Draws the chart's legend (each series' label) in its upper right corner, in `font_size`
/// pixel text on a white box.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    font_size: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .label_font(("sans-serif", font_size))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
}
