//! The adaptive tile loop: rounds of doubling sample counts over the pixels still active, the
//! decisions between rounds taken by [`crate::adaptive`].

use super::job::Job;
use super::tiles::tiles_of;
use super::RenderOptions;
use crate::adaptive::{self, AdaptiveOptions};
use crate::aov::SampleAov;
use crate::film::{Accum, AovLayout, Film, Window};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Rounds of doubling sample counts over the active pixels; between rounds, pixels whose error
/// is below the threshold (and whose neighbours are too) stop. See [`crate::adaptive`].
///
/// The rounds run over `window` grown by the apron its decisions can reach: a pixel's
/// decision after round r depends on pixels up to r away, so with as many apron pixels as
/// decisions, the window's pixels come out as in a whole-image render.
pub(super) fn render_adaptive(
    job: &Job<'_>,
    a: &AdaptiveOptions,
    window: Window,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Film {
    let opts = job.opts;
    let rounds = a.rounds(opts.spp);
    let region = window.grown(rounds.len() as u32, opts.width, opts.height);
    let tiles = tiles_of(region);
    let mut sums = RegionSums::new(region, job.layout);
    let mut active = vec![true; region.pixels()];
    let total = tiles.len() * rounds.len();
    let done = AtomicUsize::new(0);
    for (r, &target) in rounds.iter().enumerate() {
        let updates: Vec<AdaptiveTile> = tiles
            .par_iter()
            .with_max_len(1)
            .map(|&tile| {
                let t = AdaptiveTile::round(job, &sums, &active, tile, target);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                t
            })
            .collect();
        for t in &updates {
            sums.apply(t);
        }
        if r + 1 == rounds.len() || opts.cancel.is_cancelled() {
            break;
        }
        active = sums.active(a, opts.spp);
        if !active.iter().any(|&b| b) {
            break;
        }
    }
    sums.crop(window, opts)
}

/// The running sums of every pixel of the region (the window and its apron) between rounds.
struct RegionSums {
    region: Window,
    acc: Accum,
    /// Per channel, the sums of squared samples, for the error estimate.
    sq: Vec<[f64; 3]>,
    taken: Vec<u32>,
    dropped: Vec<u64>,
}

impl RegionSums {
    /// No samples yet.
    fn new(region: Window, layout: AovLayout) -> Self {
        let n = region.pixels();
        Self {
            region,
            acc: Accum::new(n, layout),
            sq: vec![[0.0f64; 3]; n],
            taken: vec![0u32; n],
            dropped: vec![0u64; n],
        }
    }

    /// Takes in a tile's round.
    fn apply(&mut self, t: &AdaptiveTile) {
        for (k, &i) in t.pixels.iter().enumerate() {
            self.acc.copy_pixel(i, &t.acc, k);
            self.sq[i] = t.sq[k];
            self.dropped[i] += t.dropped[k];
            self.taken[i] += t.taken[k];
        }
    }

    /// The pixels the next round samples: those not converged, or with a neighbour that is
    /// not, and with samples left.
    fn active(&self, a: &AdaptiveOptions, spp: u32) -> Vec<bool> {
        let converged: Vec<bool> = (0..self.taken.len())
            .map(|i| adaptive::pixel_error(&self.acc.sums[i], &self.sq[i]) < f64::from(a.threshold))
            .collect();
        let budget: Vec<bool> = self.taken.iter().map(|&t| t < spp).collect();
        adaptive::dilate(&converged, &budget, self.region.width as usize)
    }

    /// The film of `window`: the region without its apron.
    fn crop(&self, window: Window, opts: &RenderOptions) -> Film {
        let mut film = Film::for_window(window, opts.width, opts.height, opts.passes);
        let w = self.region.width as usize;
        let (dx, dy) = (
            (window.x0 - self.region.x0) as usize,
            (window.y0 - self.region.y0) as usize,
        );
        for y in 0..window.height as usize {
            for x in 0..window.width as usize {
                let (i, k) = ((y + dy) * w + x + dx, y * window.width as usize + x);
                film.accum.copy_pixel(k, &self.acc, i);
                let (t, d) = film.counts_mut();
                t[k] = self.taken[i];
                *d += self.dropped[i];
            }
        }
        film
    }
}

/// The active pixels of one tile during an adaptive round, with their running sums.
struct AdaptiveTile {
    /// Indices into the region.
    pixels: Vec<usize>,
    acc: Accum,
    /// Per channel, the sums of squared samples, for the error estimate.
    sq: Vec<[f64; 3]>,
    dropped: Vec<u64>,
    /// Samples each pixel took this round (all it was due, unless the render was cancelled).
    taken: Vec<u32>,
}

impl AdaptiveTile {
    /// One round of the tile `(x0, y0, tw, th)` of the region: its active pixels, from their
    /// sums so far, up to `target` samples each.
    fn round(
        job: &Job<'_>,
        sums: &RegionSums,
        active: &[bool],
        (x0, y0, tw, th): (u32, u32, u32, u32),
        target: u32,
    ) -> Self {
        let region = sums.region;
        let w = region.width as usize;
        let pixels: Vec<usize> = (y0..y0 + th)
            .flat_map(|y| (x0..x0 + tw).map(move |x| y as usize * w + x as usize))
            .filter(|&i| active[i])
            .collect();
        let mut t = AdaptiveTile {
            acc: Accum::new(pixels.len(), job.layout),
            sq: pixels.iter().map(|&i| sums.sq[i]).collect(),
            dropped: vec![0; pixels.len()],
            taken: vec![0; pixels.len()],
            pixels,
        };
        for (k, &i) in t.pixels.iter().enumerate() {
            t.acc.copy_pixel(k, &sums.acc, i);
        }
        let items: Vec<(usize, u32, u32, u32)> = t
            .pixels
            .iter()
            .enumerate()
            .flat_map(|(k, &i)| {
                let (x, y) = (region.x0 + (i % w) as u32, region.y0 + (i / w) as u32);
                (sums.taken[i]..target).map(move |s| (k, x, y, s))
            })
            .collect();
        let mut add = |k: usize, result: Option<(Vec3, bool)>, rec: &SampleAov| {
            t.taken[k] += 1;
            match result {
                Some((l, hit)) if t.acc.add(k, l, hit, rec, &job.ids) => {
                    for (s, v) in t.sq[k].iter_mut().zip(l.to_array()) {
                        *s += f64::from(v) * f64::from(v);
                    }
                }
                _ => t.dropped[k] += 1,
            }
        };
        if job.layout.records() {
            job.samples::<_, true>(items, &mut add);
        } else {
            job.samples::<_, false>(items, &mut add);
        }
        t
    }
}
