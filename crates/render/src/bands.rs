//! An image cut into bands of whole tile rows, rendered one after the other so that memory
//! holds one band's sums (see [`crate::render_bands`]), and the units of work progress counts.

use crate::film::Window;
use crate::options::RenderOptions;
use crate::render::tiles_of;
use crate::render::TILE;

/// Units of work [`crate::render_window`] reports progress in for `window`: tiles, times rounds for
/// adaptive sampling (which may finish early, skipping the rest).
pub fn progress_units(opts: &RenderOptions, window: Window) -> usize {
    match opts.adaptive {
        Some(a) => {
            let rounds = a.rounds(opts.spp);
            let region = window.grown(rounds.len() as u32, opts.width, opts.height);
            tiles_of(region).len() * rounds.len()
        }
        None => tiles_of(window).len(),
    }
}

/// Rows of a band of `window`: whole tile rows whose sums, at `bpp` bytes a pixel, fit in
/// `band_bytes` (at least one tile row, at most the window). The render and its memory
/// estimate (`aperture_output`'s footprint) both take it from here.
pub fn band_rows(window: Window, band_bytes: usize, bpp: usize) -> u32 {
    let rows = band_bytes / (bpp * window.width as usize).max(1);
    let rows = u32::try_from(rows).unwrap_or(u32::MAX);
    (rows / TILE * TILE).max(TILE).min(window.height)
}

/// `window` cut into bands of `rows` rows (the last may be shorter), top to bottom.
pub fn bands(window: Window, rows: u32) -> Vec<Window> {
    let rows = rows.max(1);
    (0..window.height.div_ceil(rows))
        .map(|k| {
            let y0 = window.y0 + k * rows;
            Window {
                y0,
                height: rows.min(window.y0 + window.height - y0),
                ..window
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_window_in_tile_rows() {
        let w = Window {
            x0: 3,
            y0: 10,
            width: 100,
            height: 150,
        };
        // A budget of 70 rows of 100 pixels at 8 bytes: two tile rows per band.
        let b = bands(w, band_rows(w, 100 * 70 * 8, 8));
        assert_eq!(b.iter().map(|b| b.height).collect::<Vec<_>>(), [64, 64, 22]);
        assert_eq!(b[1].y0, 74);
        assert!(b.iter().all(|b| b.x0 == 3 && b.width == 100));
        // Tiny budgets still make progress a tile row at a time; huge ones take it all.
        assert_eq!(band_rows(w, 1, 8), TILE);
        assert_eq!(bands(w, band_rows(w, usize::MAX, 8)).len(), 1);
    }
}
