//! The adaptive tile loop: rounds of doubling sample counts over the pixels still active, the
//! decisions between rounds taken by [`crate::adaptive`].

use super::job::Job;
use super::tiles::tiles_of;
use crate::adaptive::{self, AdaptiveOptions};
use crate::aov::SampleAov;
use crate::film::{Accum, AovLayout, Film, Window};
use crate::options::RenderOptions;
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
    // Each tile's buffers, kept from round to round: the region's sums are read during a round
    // and written only after it, so every tile's update is held until then anyway.
    let mut updates: Vec<AdaptiveTile> = tiles.iter().map(|_| AdaptiveTile::default()).collect();
    let total = tiles.len() * rounds.len();
    let done = AtomicUsize::new(0);
    for (r, &target) in rounds.iter().enumerate() {
        // One job per tile, as in `render_uniform`.
        (tiles.par_iter().zip(&mut updates))
            .with_max_len(1)
            .for_each(|(&tile, t)| {
                t.run(job, &sums, &active, tile, target);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            });
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
    /// The window and its apron, in image pixels.
    region: Window,
    acc: Accum,
    /// Per channel, the sums of squared samples, for the error estimate.
    sq: Vec<[f64; 3]>,
    /// Samples each pixel took so far.
    taken: Vec<u32>,
    /// Of those, the ones dropped (no camera ray, or radiance not finite).
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

    /// The pixels the next round samples: those not converged and their eight neighbours, if
    /// they have samples left ([`adaptive::dilate`]).
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

/// The active pixels of one tile during an adaptive round, with their running sums. Kept from
/// round to round for its allocations: [`AdaptiveTile::run`] overwrites all it holds.
#[derive(Default)]
struct AdaptiveTile {
    /// Indices into the region.
    pixels: Vec<usize>,
    acc: Accum,
    /// Per channel, the sums of squared samples, for the error estimate.
    sq: Vec<[f64; 3]>,
    dropped: Vec<u64>,
    /// Samples each pixel took this round (all it was due, unless the render was cancelled).
    taken: Vec<u32>,
    /// This round's samples as `(k, x, y, i)`: sample `i` of pixel `(x, y)`, `pixels[k]`.
    items: Vec<(usize, u32, u32, u32)>,
}

impl AdaptiveTile {
    /// One round of the tile `(x0, y0, tw, th)` of the region: its active pixels, from their
    /// sums so far, up to `target` samples each.
    fn run(
        &mut self,
        job: &Job<'_>,
        sums: &RegionSums,
        active: &[bool],
        (x0, y0, tw, th): (u32, u32, u32, u32),
        target: u32,
    ) {
        let region = sums.region;
        let w = region.width as usize;
        self.pixels.clear();
        self.pixels.extend(
            (y0..y0 + th)
                .flat_map(|y| (x0..x0 + tw).map(move |x| y as usize * w + x as usize))
                .filter(|&i| active[i]),
        );
        let n = self.pixels.len();
        self.acc.reset(n, job.layout);
        for (k, &i) in self.pixels.iter().enumerate() {
            self.acc.copy_pixel(k, &sums.acc, i);
        }
        self.sq.clear();
        self.sq.extend(self.pixels.iter().map(|&i| sums.sq[i]));
        self.dropped.clear();
        self.dropped.resize(n, 0);
        self.taken.clear();
        self.taken.resize(n, 0);
        self.items.clear();
        self.items
            .extend(self.pixels.iter().enumerate().flat_map(|(k, &i)| {
                let (x, y) = (region.x0 + (i % w) as u32, region.y0 + (i / w) as u32);
                (sums.taken[i]..target).map(move |s| (k, x, y, s))
            }));
        let Self {
            acc,
            sq,
            dropped,
            taken,
            items,
            ..
        } = self;
        let mut add = |k: usize, result: Option<(Vec3, bool)>, rec: &SampleAov| {
            taken[k] += 1;
            match result {
                Some((l, hit)) if acc.add(k, l, hit, rec, &job.ids) => {
                    for (s, v) in sq[k].iter_mut().zip(l.to_array()) {
                        *s += f64::from(v) * f64::from(v);
                    }
                }
                _ => dropped[k] += 1,
            }
        };
        let items = items.iter().copied();
        if job.layout.records() {
            job.samples::<_, true>(items, &mut add);
        } else {
            job.samples::<_, false>(items, &mut add);
        }
    }
}
