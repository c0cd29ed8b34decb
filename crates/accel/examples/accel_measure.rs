//! Measures the ray-query structure on a real scene: build time, statistics and single-thread
//! closest-hit / occlusion throughput on ray files (the Embree anchor's format: little-endian
//! f32, 6 per ray, `tmin = 0`, `tmax = ∞`), so our figures can be quoted as a ratio to Embree's
//! on identical rays. Run under `/usr/bin/time -v` for peak resident memory.
//!
//! ```text
//! cargo run --release -p aperture-accel --example accel_measure -- \
//!     SCENE.gltf|SCENE.tris [--quality fast|medium|high] [--rays FILE]... [--build-only]
//!     [--repeats N] [--batch]
//! ```
//! `.tris` files are raw world-space triangles (little-endian f32, 9 per triangle), e.g. written
//! from the Embree anchor's `gltf_io.py`; anything else goes through `aperture_scene::load`.

use std::time::Instant;

use aperture_accel::{Accel, BvhQuality, InstanceInput, MeshInput, Ray};
use glam::{Affine3A, Vec3};

/// Positions and triangles of one mesh.
type Mesh = (Vec<Vec3>, Vec<[u32; 3]>);

fn read_f32s(path: &str) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Nanoseconds this thread has run on a CPU (Linux `schedstat`), or `None` elsewhere. On a shared
/// machine, wall time also counts the time other processes hold the core; rays per on-CPU second
/// leave that out (cache sharing still shows).
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The command line.
struct Args {
    scene_path: String,
    quality: BvhQuality,
    ray_files: Vec<String>,
    build_only: bool,
    batch: bool,
    repeats: usize,
}

fn parse_args() -> Args {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut scene_path = None;
    let mut quality = BvhQuality::default();
    let mut ray_files = Vec::new();
    let mut build_only = false;
    let mut batch = false;
    let mut repeats = 3;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quality" => {
                quality = it
                    .next()
                    .expect("--quality VALUE")
                    .parse()
                    .expect("quality")
            }
            "--rays" => ray_files.push(it.next().expect("--rays FILE").clone()),
            "--build-only" => build_only = true,
            "--batch" => batch = true,
            "--repeats" => repeats = it.next().expect("--repeats N").parse().expect("repeats"),
            _ => scene_path = Some(a.clone()),
        }
    }
    let scene_path = scene_path.expect("usage: accel_measure SCENE [--quality Q] [--rays FILE]...");
    Args {
        scene_path,
        quality,
        ray_files,
        build_only,
        batch,
        repeats,
    }
}

/// The meshes and instances of a `.tris` file or a scene.
fn load_scene(scene_path: &str) -> (Vec<Mesh>, Vec<InstanceInput>) {
    if scene_path.ends_with(".tris") {
        let f = read_f32s(scene_path);
        let pos: Vec<Vec3> = f.chunks_exact(3).map(Vec3::from_slice).collect();
        let idx = (0..pos.len() as u32 / 3)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        (
            vec![(pos, idx)],
            vec![InstanceInput {
                mesh: 0,
                world_from_object: Affine3A::IDENTITY,
            }],
        )
    } else {
        let s = aperture_scene::load(scene_path.as_ref(), &Default::default())
            .unwrap_or_else(|e| panic!("{scene_path}: {e}"));
        let instances = s
            .instances
            .iter()
            .map(|i| InstanceInput {
                mesh: i.mesh,
                world_from_object: i.world_from_object,
            })
            .collect();
        (
            s.meshes
                .into_iter()
                .map(std::sync::Arc::unwrap_or_clone)
                .map(|m| (m.positions, m.indices))
                .collect(),
            instances,
        )
    }
}

/// Rays per second (millions) of one query over `rays`, by wall time and, where the platform
/// tells, by this thread's on-CPU time; and the query's count of hits.
fn time_query(n: f64, query: impl FnOnce() -> usize) -> (f64, Option<f64>, usize) {
    let (t, c) = (Instant::now(), thread_cpu_ns());
    let count = query();
    let wall = n / t.elapsed().as_secs_f64() / 1e6;
    let cpu = match (c, thread_cpu_ns()) {
        (Some(c0), Some(c1)) => Some(n / ((c1 - c0) as f64 * 1e-9) / 1e6),
        _ => None,
    };
    (wall, cpu, count)
}

/// Times closest hit and occlusion on the rays of `file` and prints the throughputs.
fn measure_file(accel: &Accel, file: &str, repeats: usize, batch: bool) {
    let rays: Vec<Ray> = aperture_accel::read_rays(file.as_ref()).unwrap_or_else(|e| panic!("{e}"));
    let n = rays.len() as f64;
    // One thread, one query at a time (as Embree's rtcIntersect1 loop is measured), or with
    // `--batch` the whole file through the interleaved batch queries.
    let mut closest = Vec::new();
    let mut occluded = Vec::new();
    let mut closest_cpu = Vec::new();
    let mut occluded_cpu = Vec::new();
    let mut hits = 0;
    let mut batch_hits = vec![None; rays.len()];
    let mut batch_occ = vec![false; rays.len()];
    for _ in 0..repeats {
        let (wall, cpu, h) = time_query(n, || {
            if batch {
                accel.intersect_batch(&rays, &mut batch_hits);
                batch_hits.iter().filter(|h| h.is_some()).count()
            } else {
                rays.iter().filter(|r| accel.intersect(r).is_some()).count()
            }
        });
        hits = h;
        closest.push(wall);
        closest_cpu.extend(cpu);
        let (wall, cpu, occ) = time_query(n, || {
            if batch {
                accel.occluded_batch(&rays, &mut batch_occ);
                batch_occ.iter().filter(|&&o| o).count()
            } else {
                rays.iter().filter(|r| accel.occluded(r)).count()
            }
        });
        occluded.push(wall);
        occluded_cpu.extend(cpu);
        assert_eq!(occ, hits, "occlusion disagrees with closest hit");
    }
    if !closest_cpu.is_empty() {
        println!(
            "{file}: per on-CPU second (median of {repeats}): closest {:.3} Mrays/s, occluded {:.3} Mrays/s",
            median(closest_cpu),
            median(occluded_cpu)
        );
    }
    let best = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    println!(
        "{file}: {} rays, hit fraction {:.4}, 1 thread: closest {:.3} Mrays/s, occluded {:.3} Mrays/s (median of {repeats}); best of {repeats} (Embree's statistic): closest {:.3}, occluded {:.3}",
        rays.len(),
        hits as f64 / n,
        median(closest.clone()),
        median(occluded.clone()),
        best(&closest),
        best(&occluded)
    );
}

fn main() {
    let args = parse_args();
    let scene_path = &args.scene_path;
    let quality = args.quality;
    let t0 = Instant::now();
    let (meshes, instances) = load_scene(scene_path);
    let load_s = t0.elapsed().as_secs_f64();
    let inputs: Vec<MeshInput> = meshes
        .iter()
        .map(|(p, i)| MeshInput {
            positions: p,
            indices: i,
        })
        .collect();
    let mut builds = Vec::new();
    let mut accel = None;
    for _ in 0..if args.build_only { 1 } else { 5 } {
        let a = Accel::build(&inputs, &instances, quality);
        builds.push(a.stats().build_time.as_secs_f64());
        accel = Some(a);
    }
    let accel = accel.expect("built");
    println!("scene {scene_path} (loaded in {load_s:.3} s), quality {quality}");
    println!(
        "build median {:.4} s over {} builds",
        median(builds.clone()),
        builds.len()
    );
    println!("{:#?}", accel.stats());

    for file in &args.ray_files {
        measure_file(&accel, file, args.repeats, args.batch);
    }
}
