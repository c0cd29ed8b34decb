//! Timing ray queries: closest hit and occlusion, one ray at a time, in interleaved batches or in
//! packets,
//! on a rayon pool of a given size; the median, least and most Mrays/s over repeats.

use super::sets::RaySet;
use aperture_accel::{Accel, BvhQuality, Hit, Ray};
use aperture_scene::Scene;
use rayon::prelude::*;
use std::time::Instant;

/// Rays per rayon task in one-ray mode (as the batch queries' `*_many` use).
const CHUNK: usize = 256;

/// Which query is timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Query {
    /// The closest hit ([`Accel::intersect`]).
    Closest,
    /// Any hit ([`Accel::occluded`]).
    Occluded,
}

impl Query {
    /// Both queries.
    pub const ALL: [Query; 2] = [Query::Closest, Query::Occluded];

    /// `closest` or `occluded`.
    pub fn name(self) -> &'static str {
        match self {
            Query::Closest => "closest",
            Query::Occluded => "occluded",
        }
    }
}

/// How the rays are handed to the structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// One query per ray ([`Accel::intersect`], [`Accel::occluded`]), what the renderer calls for
    /// secondary rays.
    OneRay,
    /// Interleaved batches ([`Accel::intersect_many`], [`Accel::occluded_many`]).
    Batch,
    /// Packets of coherent runs ([`Accel::intersect_packets`], [`Accel::occluded_packets`]) on
    /// chunks of the set in its order, what the renderer calls for primary rays.
    Packet,
}

impl Mode {
    /// Every mode.
    pub const ALL: [Mode; 3] = [Mode::OneRay, Mode::Batch, Mode::Packet];

    /// `one-ray`, `batch` or `packet`.
    pub fn name(self) -> &'static str {
        match self {
            Mode::OneRay => "one-ray",
            Mode::Batch => "batch",
            Mode::Packet => "packet",
        }
    }
}

/// Closest hits of `rays` into `out` (one per ray), on the current rayon pool.
pub fn closest_hits(accel: &Accel, rays: &[Ray], mode: Mode, out: &mut [Option<Hit>]) {
    match mode {
        Mode::OneRay => one_ray_at_a_time(rays, out, |r| accel.intersect(r)),
        Mode::Batch => accel.intersect_many(rays, out),
        Mode::Packet => in_chunks(rays, out, |r, o| accel.intersect_packets(r, o)),
    }
}

/// Occlusion answers of `rays` into `out` (one per ray), on the current rayon pool.
pub fn occlusions(accel: &Accel, rays: &[Ray], mode: Mode, out: &mut [bool]) {
    match mode {
        Mode::OneRay => one_ray_at_a_time(rays, out, |r| accel.occluded(r)),
        Mode::Batch => accel.occluded_many(rays, out),
        Mode::Packet => in_chunks(rays, out, |r, o| accel.occluded_packets(r, o)),
    }
}

/// `query` of each chunk of [`CHUNK`] rays into its slots of `out`, on the rayon pool.
fn in_chunks<T: Send>(rays: &[Ray], out: &mut [T], query: impl Fn(&[Ray], &mut [T]) + Sync) {
    rays.par_chunks(CHUNK)
        .zip(out.par_chunks_mut(CHUNK))
        .with_max_len(1)
        .for_each(|(r, o)| query(r, o));
}

/// `query` of every ray into its slot of `out`, one ray at a time, in chunks on the rayon pool.
fn one_ray_at_a_time<T: Send>(rays: &[Ray], out: &mut [T], query: impl Fn(&Ray) -> T + Sync) {
    in_chunks(rays, out, |r, o| {
        for (ray, slot) in r.iter().zip(o) {
            *slot = query(ray);
        }
    });
}

/// The throughput of one query on one set.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// The set's name.
    pub set: String,
    /// The query.
    pub query: Query,
    /// One ray at a time or batched.
    pub mode: Mode,
    /// Threads of the pool.
    pub threads: usize,
    /// Rays in the set.
    pub rays: usize,
    /// Rays that hit something (closest) or are occluded.
    pub hits: usize,
    /// Median Mrays/s over the repeats.
    pub mrays_median: f64,
    /// Least Mrays/s.
    pub mrays_min: f64,
    /// Most Mrays/s.
    pub mrays_max: f64,
}

/// Times `query` on `set` in `mode` on `pool`, `repeats` times (at least once).
pub fn time_query(
    accel: &Accel,
    set: &RaySet,
    query: Query,
    mode: Mode,
    pool: &rayon::ThreadPool,
    repeats: u32,
) -> Timing {
    let n = set.rays.len();
    let mut hits = vec![None; n];
    let mut occluded = vec![false; n];
    let mut rates = Vec::new();
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        pool.install(|| match query {
            Query::Closest => closest_hits(accel, &set.rays, mode, &mut hits),
            Query::Occluded => occlusions(accel, &set.rays, mode, &mut occluded),
        });
        let seconds = start.elapsed().as_secs_f64().max(1e-9);
        rates.push(n as f64 / seconds / 1e6);
    }
    let count = match query {
        Query::Closest => hits.iter().filter(|h| h.is_some()).count(),
        Query::Occluded => occluded.iter().filter(|&&o| o).count(),
    };
    rates.sort_by(f64::total_cmp);
    Timing {
        set: set.name.clone(),
        query,
        mode,
        threads: pool.current_num_threads(),
        rays: n,
        hits: count,
        mrays_median: median_sorted(&rates),
        mrays_min: rates[0],
        mrays_max: rates[rates.len() - 1],
    }
}

/// The median of a sorted, non-empty list (the mean of the middle two for an even length).
fn median_sorted(v: &[f64]) -> f64 {
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// What to time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TimingOptions {
    /// BVH presets, each built and timed in turn.
    pub qualities: Vec<BvhQuality>,
    /// Pool sizes (say 1 and all cores).
    pub thread_counts: Vec<usize>,
    /// Timed runs per measurement; the median is reported.
    pub repeats: u32,
}

/// The measurements of one BVH preset.
#[derive(Debug, Clone, PartialEq)]
pub struct QualityRun {
    /// The preset.
    pub quality: BvhQuality,
    /// Wall time of its build.
    pub build_seconds: f64,
    /// Bytes the structure holds (nodes, triangles, instances).
    pub memory_bytes: usize,
    /// One per (set, query, mode, thread count), in that nesting order.
    pub timings: Vec<Timing>,
}

/// Why timing could not run.
#[derive(Debug, thiserror::Error)]
pub enum RayBenchError {
    /// A rayon pool of that size could not be made.
    #[error("cannot start a pool of {threads} threads: {source}")]
    ThreadPool {
        /// The size asked for.
        threads: usize,
        /// Rayon's error.
        source: rayon::ThreadPoolBuildError,
    },
}

/// Builds each preset of `opts` over `scene` and times every query, mode and pool size on every
/// set. `progress` is told each finished measurement.
pub fn time_sets(
    scene: &Scene,
    sets: &[RaySet],
    opts: &TimingOptions,
    progress: &mut dyn FnMut(BvhQuality, &Timing),
) -> Result<Vec<QualityRun>, RayBenchError> {
    let pools = opts
        .thread_counts
        .iter()
        .map(|&threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads.max(1))
                .build()
                .map_err(|source| RayBenchError::ThreadPool { threads, source })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut runs = Vec::new();
    for &quality in &opts.qualities {
        let accel = aperture_render::build_accel(scene, quality);
        let stats = accel.stats();
        let mut timings = Vec::new();
        for set in sets {
            for query in Query::ALL {
                for mode in Mode::ALL {
                    for pool in &pools {
                        let t = time_query(&accel, set, query, mode, pool, opts.repeats);
                        progress(quality, &t);
                        timings.push(t);
                    }
                }
            }
        }
        runs.push(QualityRun {
            quality,
            build_seconds: stats.build_time.as_secs_f64(),
            memory_bytes: stats.memory_bytes,
            timings,
        });
    }
    Ok(runs)
}
