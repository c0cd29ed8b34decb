//! The uniform tile loop: every pixel of a window at `spp` samples, in tiles of at most
//! [`TILE`]² pixels rendered in parallel, each traced by [`Job::render_tile`].

use super::job::Job;
use crate::film::{Accum, AovLayout, Film, Window};
use crate::spares::{lock, Spares};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Side of a square tile in pixels.
pub const TILE: u32 = 32;

/// Tiles of at most [`TILE`]² pixels covering `w`, relative to its corner.
pub(crate) fn tiles_of(w: Window) -> Vec<(u32, u32, u32, u32)> {
    (0..w.height.div_ceil(TILE))
        .flat_map(|ty| {
            (0..w.width.div_ceil(TILE)).map(move |tx| {
                let (x0, y0) = (tx * TILE, ty * TILE);
                (x0, y0, TILE.min(w.width - x0), TILE.min(w.height - y0))
            })
        })
        .collect()
}

/// Every pixel of `film`'s window at the job's samples (`sample_offset .. sample_offset + spp`
/// of each pixel's sequence), summed onto what the film holds: a progressive render's pass
/// continues each pixel's sums where the last pass left them, so that its passes together
/// equal one render of all their samples bit for bit. A fresh film (`resume` false) holds zeros:
/// its tiles start from empty sums without reading it.
pub(super) fn accumulate(
    job: &Job<'_>,
    film: &mut Film,
    resume: bool,
    progress: &(dyn Fn(usize, usize) + Sync),
) {
    let window = film.window();
    let tiles = tiles_of(window);
    let total = tiles.len();
    let done = AtomicUsize::new(0);
    // One job per tile: rayon's adaptive splitting otherwise runs chunks of up to a quarter of
    // the tiles (with two threads) as one job that cannot be stolen, leaving a core idle at the
    // end (BENCHMARKS.md, "Threads").
    // Each tile goes into the film as it finishes (tiles own disjoint pixels, so the order
    // does not matter), and its buffers serve the next tile: a tile's own fresh accumulators
    // cost page faults, and copying all of them after the last tile ran on one thread.
    let film = Mutex::new(film);
    let spare = Spares::<TileSums>::default();
    tiles
        .par_iter()
        .with_max_len(1)
        .for_each(|&(x0, y0, tw, th)| {
            let mut t = spare.take().unwrap_or_default();
            t.reset((tw * th) as usize, job.layout);
            if resume {
                t.load(&lock(&film), (x0, y0, tw, th));
            }
            let (x, y) = (window.x0 + x0, window.y0 + y0);
            let dropped = if job.layout.records() {
                job.render_tile::<true>(x, y, tw, th, &mut t)
            } else {
                job.render_tile::<false>(x, y, tw, th, &mut t)
            };
            // A tile cut short by cancelling records the samples each pixel got to.
            lock(&film).merge_tile(x0, y0, tw, &t.acc, &t.taken, dropped);
            spare.give(t);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
        });
}

/// The samples of a tile as `(pixel k in the tile, x, y, sample i)`, row by row, a pixel's
/// samples together: a counter rather than nested `flat_map`s, whose state checks cost about
/// 30 instructions a sample.
struct TileItems {
    x0: u32,
    x1: u32,
    y1: u32,
    spp: u32,
    /// The next item.
    next: (usize, u32, u32, u32),
}

impl TileItems {
    /// The samples of the `tw × th` tile at `(x0, y0)`, `spp` each.
    fn new(x0: u32, y0: u32, tw: u32, th: u32, spp: u32) -> Self {
        let y1 = y0 + th;
        // An empty tile starts past its end.
        let y = if tw == 0 || spp == 0 { y1 } else { y0 };
        Self {
            x0,
            x1: x0 + tw,
            y1,
            spp,
            next: (0, x0, y, 0),
        }
    }
}

impl Iterator for TileItems {
    type Item = (usize, u32, u32, u32);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        let item = self.next;
        let (k, x, y, i) = item;
        if y >= self.y1 {
            return None;
        }
        self.next = if i + 1 < self.spp {
            (k, x, y, i + 1)
        } else if x + 1 < self.x1 {
            (k + 1, x + 1, y, 0)
        } else {
            (k + 1, self.x0, y + 1, 0)
        };
        Some(item)
    }
}

/// A tile's accumulators and the samples each of its pixels took.
#[derive(Default)]
struct TileSums {
    acc: Accum,
    taken: Vec<u32>,
}

impl TileSums {
    /// Empty sums and counts for `n` pixels, keeping the allocations.
    fn reset(&mut self, n: usize, layout: AovLayout) {
        self.acc.reset(n, layout);
        self.taken.clear();
        self.taken.resize(n, 0);
    }

    /// The sums and counts `film` holds for the `tw × th` tile at `(x0, y0)` (relative to its
    /// window), into these reset ones.
    fn load(&mut self, film: &Film, (x0, y0, tw, th): (u32, u32, u32, u32)) {
        let width = film.window().width as usize;
        let counts = film.samples_per_pixel();
        for ty in 0..th as usize {
            let from = (y0 as usize + ty) * width + x0 as usize;
            let to = ty * tw as usize;
            self.acc.copy_pixels(to, &film.accum, from, tw as usize);
            self.taken[to..to + tw as usize].copy_from_slice(&counts[from..from + tw as usize]);
        }
    }
}

impl Job<'_> {
    /// Every pixel of a tile at `spp` more samples into `t` (its sums and the samples each
    /// pixel took: `spp` more, unless the render was cancelled); returns the dropped-sample
    /// count.
    fn render_tile<const AOV: bool>(
        &self,
        x0: u32,
        y0: u32,
        tw: u32,
        th: u32,
        t: &mut TileSums,
    ) -> u64 {
        let (acc, taken) = (&mut t.acc, &mut t.taken);
        let mut dropped = 0u64;
        let items = TileItems::new(x0, y0, tw, th, self.opts.spp);
        self.samples::<_, AOV>(items, |k, result, rec| {
            if let Some(t) = taken.get_mut(k) {
                *t += 1;
            }
            // Without passes, the radiance alone: the layout's checks stay out of the loop.
            let added = |(l, hit)| match AOV {
                true => acc.add(k, l, hit, rec, &self.ids),
                false => acc.add_radiance(k, l, hit),
            };
            if !result.is_some_and(added) {
                dropped += 1;
            }
        });
        dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_items_are_every_sample_of_every_pixel_in_order() {
        for (x0, y0, tw, th, spp) in [
            (3, 5, 4, 3, 2),
            (0, 0, 1, 1, 1),
            (7, 2, 5, 1, 3),
            (1, 1, 2, 2, 0),
            (2, 3, 0, 2, 3),
        ] {
            let want: Vec<_> = (y0..y0 + th)
                .flat_map(|y| {
                    (x0..x0 + tw).flat_map(move |x| {
                        let k = ((y - y0) * tw + (x - x0)) as usize;
                        (0..spp).map(move |i| (k, x, y, i))
                    })
                })
                .collect();
            let items = TileItems::new(x0, y0, tw, th, spp);
            assert_eq!(
                items.collect::<Vec<_>>(),
                want,
                "{tw}x{th} at ({x0}, {y0}), {spp} spp"
            );
        }
    }
}
