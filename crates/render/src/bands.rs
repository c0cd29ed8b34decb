//! An image cut into bands of whole tile rows, rendered one after the other so that memory
//! holds one band's sums ([`Bands`]: how a large image is streamed to a file, each band's
//! pass values resolved), and the units of work progress counts.

use crate::camera::Camera;
use crate::film::Window;
use crate::frame::Frame;
use crate::options::{RenderError, RenderOptions};
use crate::render::{tiles_of, TILE};
use crate::resolve::Resolver;
use glam::Mat3;
use std::time::Instant;

/// What a [`Bands`] render took, over the bands rendered so far.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BandTotals {
    /// Samples taken, dropped ones included.
    pub samples: u64,
    /// Samples dropped as NaN or infinite.
    pub dropped: u64,
    /// Seconds spent rendering (not in whoever takes the bands).
    pub render_secs: f64,
}

/// One band of [`Bands`].
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Its pixels' values, rows top to bottom ([`Resolver::rows`]).
    pub values: Vec<f32>,
    /// What the bands took so far, this one included.
    pub totals: BandTotals,
}

/// The pixels of `bands` (windows of whole rows, top to bottom; see [`bands`]) of a frame,
/// each band rendered when it is asked for and resolved into the values of `opts.passes`
/// ([`Resolver`]: rows top to bottom, the beauty then each pass), so that memory holds one
/// band's sums while its taker writes the one before. A band's pixels are those of a whole
/// render.
pub struct Bands<'a> {
    frame: &'a Frame,
    camera: &'a Camera,
    opts: &'a RenderOptions,
    bands: std::vec::IntoIter<Window>,
    progress: &'a (dyn Fn(usize, usize) + Sync),
    /// Units of work of the bands before the next one, and of them all.
    done_units: usize,
    total_units: usize,
    totals: BandTotals,
}

impl<'a> Bands<'a> {
    /// The bands of `frame` through `camera` with `opts`; `progress(done, total)` counts over
    /// all of them.
    pub fn new(
        frame: &'a Frame,
        camera: &'a Camera,
        opts: &'a RenderOptions,
        bands: Vec<Window>,
        progress: &'a (dyn Fn(usize, usize) + Sync),
    ) -> Self {
        let total_units = bands.iter().map(|b| progress_units(opts, *b)).sum();
        Self {
            frame,
            camera,
            opts,
            bands: bands.into_iter(),
            progress,
            done_units: 0,
            total_units,
            totals: BandTotals::default(),
        }
    }
}

impl Iterator for Bands<'_> {
    type Item = Result<Band, RenderError>;

    fn next(&mut self) -> Option<Self::Item> {
        let band = self.bands.next()?;
        let t0 = Instant::now();
        let (offset, total) = (self.done_units, self.total_units);
        let progress = self.progress;
        let report = |done: usize, _: usize| progress(offset + done, total);
        let film = self
            .frame
            .render_window(self.camera, self.opts, band, &report);
        self.totals.render_secs += t0.elapsed().as_secs_f64();
        self.done_units += progress_units(self.opts, band);
        Some(film.map(|f| {
            self.totals.samples += f.total_samples();
            self.totals.dropped += f.dropped_samples();
            let world_from_camera = Mat3::from(self.camera.world_from_camera.matrix3);
            let world_origin = self.frame.scene().world_origin.as_vec3();
            Band {
                values: Resolver::new(&f, self.opts.passes, world_from_camera, world_origin).rows(),
                totals: self.totals,
            }
        }))
    }
}

/// Units of work a window's render reports progress in for `window`: tiles, times rounds for
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
