//! The ray sets of `aperture bench-rays`, generated deterministically from a scene's camera.
//!
//! Every value comes from the renderer's own pieces: sample values from [`SampleStream`]
//! (Owen-scrambled Sobol, a pure function of pixel, index, dimension and seed), primary rays from
//! [`Camera::generate_ray`], bounce directions from the cosine warp in `warp.rs`, origins off the
//! surface from [`Accel::spawn_point`].

use aperture_accel::{Accel, Hit, Ray};
use aperture_render::camera::{Camera, CameraSample};
use aperture_render::sampler::{SampleStream, SamplerKind};
use aperture_scene::{LightKind, Scene};
use aperture_shading::bsdf::Frame;
use aperture_shading::warp::cosine_hemisphere;
use glam::{Vec2, Vec3};

/// Side of the square pixel tiles the primary rays are ordered by.
pub const BENCH_TILE: u32 = 16;

/// Names of the generated sets, in the order [`generate_sets`] returns them.
pub const SET_NAMES: [&str; 4] = ["primary_tile", "primary_random", "diffuse", "shadow"];

/// A named list of rays.
#[derive(Debug, Clone, PartialEq)]
pub struct RaySet {
    /// The set's name (`primary_tile`, …, or a ray file's stem).
    pub name: String,
    /// The rays, in the order they are timed.
    pub rays: Vec<Ray>,
}

/// What the generated sets depend on besides the scene and camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RaySetOptions {
    /// Lens samples per pixel (consecutive in the primary sets).
    pub lens_samples: u32,
    /// Seed of the sample values and of the random order.
    pub seed: u32,
}

impl Default for RaySetOptions {
    fn default() -> Self {
        Self {
            lens_samples: 16,
            seed: 0,
        }
    }
}

/// One primary sample: its pixel, its index in the pixel, and the camera's numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrimarySample {
    /// Pixel column.
    pub x: u32,
    /// Pixel row (0 at the top).
    pub y: u32,
    /// Sample index within the pixel.
    pub index: u32,
    /// Film and lens position the camera turns into a ray.
    pub sample: CameraSample,
}

/// The primary samples of every pixel of the camera's image in tile order: [`BENCH_TILE`]-pixel
/// square tiles row by row, the pixels of a tile row by row, the `lens_samples` samples of a pixel
/// one after another. Pixel and lens come from one 4-D Sobol point (as the renderer draws them);
/// the film position is the pixel plus the pixel pair (a box filter).
pub fn primary_samples(camera: &Camera, opts: &RaySetOptions) -> Vec<PrimarySample> {
    let (w, h) = (camera.width, camera.height);
    let n = w as usize * h as usize * opts.lens_samples as usize;
    let mut out = Vec::with_capacity(n);
    for ty in (0..h).step_by(BENCH_TILE as usize) {
        for tx in (0..w).step_by(BENCH_TILE as usize) {
            for y in ty..(ty + BENCH_TILE).min(h) {
                for x in tx..(tx + BENCH_TILE).min(w) {
                    for index in 0..opts.lens_samples {
                        let c =
                            SampleStream::new(SamplerKind::Sobol, x, y, index, opts.seed).camera();
                        let sample = CameraSample {
                            p_film: Vec2::new(x as f32 + c[0], y as f32 + c[1]),
                            p_lens: Vec2::new(c[2], c[3]),
                            time: 0.0,
                        };
                        out.push(PrimarySample {
                            x,
                            y,
                            index,
                            sample,
                        });
                    }
                }
            }
        }
    }
    out
}

/// An upper bound on the bytes one primary sample costs while the sets are made and timed: its
/// sample, its ray in both orders, its first hit, its bounce and shadow rays, and the answers a
/// timing writes.
pub const BYTES_PER_PRIMARY_SAMPLE: u64 = 288;

/// An upper bound on the memory [`generate_sets`] and the timing of its sets take for `camera`'s
/// image (check it before generating: a large image with many lens samples needs gigabytes).
pub fn estimated_bytes(camera: &Camera, opts: &RaySetOptions) -> u64 {
    u64::from(camera.width)
        .saturating_mul(u64::from(camera.height))
        .saturating_mul(u64::from(opts.lens_samples))
        .saturating_mul(BYTES_PER_PRIMARY_SAMPLE)
}

/// The world-space ray of a primary sample over `[0, ∞)`, `None` where the camera makes none.
pub fn primary_ray(camera: &Camera, s: &PrimarySample) -> Option<Ray> {
    camera
        .generate_ray(&s.sample)
        .map(|r| Ray::new(r.origin, r.dir))
}

/// SplitMix64: the random order's generator.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// `items` shuffled (Fisher–Yates) by a generator seeded with `seed`: the same permutation for
/// the same seed and length.
pub fn shuffled<T: Clone>(items: &[T], seed: u32) -> Vec<T> {
    let mut out = items.to_vec();
    let mut state = 0x5eed_0000_0000_0000 ^ u64::from(seed);
    for i in (1..out.len()).rev() {
        let j = (splitmix(&mut state) % (i as u64 + 1)) as usize;
        out.swap(i, j);
    }
    out
}

/// A primary ray's first hit with what secondary rays need: where they start from and the
/// surface's geometric normal facing the camera.
struct FirstHit {
    sample: PrimarySample,
    ray: Ray,
    hit: Hit,
    normal: Vec3,
}

/// The unit geometric normal of the hit triangle, flipped to face against `dir`.
fn facing_normal(scene: &Scene, hit: &Hit, dir: Vec3) -> Option<Vec3> {
    let inst = scene.instances.get(hit.instance as usize)?;
    let mesh = scene.meshes.get(inst.mesh as usize)?;
    let tri = mesh.indices.get(hit.triangle as usize)?;
    let p = tri.map(|i| {
        mesh.positions
            .get(i as usize)
            .map(|&p| inst.world_from_object.transform_point3(p))
    });
    let [Some(a), Some(b), Some(c)] = p else {
        return None;
    };
    let n = (b - a).cross(c - a).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    Some(if n.dot(dir) > 0.0 { -n } else { n })
}

fn first_hits(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    samples: &[PrimarySample],
) -> Vec<FirstHit> {
    samples
        .iter()
        .filter_map(|s| {
            let ray = primary_ray(camera, s)?;
            let hit = accel.intersect(&ray)?;
            let normal = facing_normal(scene, &hit, ray.dir)?;
            Some(FirstHit {
                sample: *s,
                ray,
                hit,
                normal,
            })
        })
        .collect()
}

/// Diffuse bounce rays: from each first hit, a cosine-distributed direction about the geometric
/// normal (the sample's first bounce values), starting off the surface.
fn diffuse_rays(accel: &Accel, hits: &[FirstHit], seed: u32) -> Vec<Ray> {
    hits.iter()
        .filter_map(|h| {
            let s = &h.sample;
            let u = SampleStream::new(SamplerKind::Sobol, s.x, s.y, s.index, seed)
                .bounce(0)
                .bsdf;
            let dir = Frame::from_normal(h.normal)
                .to_world(cosine_hemisphere(u))
                .normalize_or_zero();
            let origin = accel.spawn_point(&h.ray, &h.hit).origin(h.normal);
            (dir != Vec3::ZERO).then(|| Ray::new(origin, dir))
        })
        .collect()
}

/// Where shadow rays go: the scene's first point light, else a point above the scene's bounds
/// (over the centre, half a diagonal above the top). `None` for a scene with no geometry.
pub fn shadow_target(scene: &Scene) -> Option<Vec3> {
    if let Some(light) = scene
        .lights
        .iter()
        .find(|l| matches!(l.kind, LightKind::Point))
    {
        return Some(light.position);
    }
    let b = scene.bounds();
    if b.is_empty() {
        return None;
    }
    let centre = 0.5 * (b.min + b.max);
    let diagonal = (b.max - b.min).length();
    let p = Vec3::new(centre.x, b.max.y + 0.5 * diagonal.max(1e-3), centre.z);
    p.is_finite().then_some(p)
}

/// Shadow rays from each first hit towards `target`, ending just short of it (`tmax` is
/// 0.9999 of the distance), starting off the surface on the target's side.
fn shadow_rays(accel: &Accel, hits: &[FirstHit], target: Vec3) -> Vec<Ray> {
    hits.iter()
        .filter_map(|h| {
            let to = target - h.ray.origin - h.ray.dir * h.hit.t;
            let n = if h.normal.dot(to) < 0.0 {
                -h.normal
            } else {
                h.normal
            };
            let origin = accel.spawn_point(&h.ray, &h.hit).origin(n);
            let d = target - origin;
            let dist = d.length();
            let dir = d / dist;
            (dist > 0.0 && dir.is_finite()).then_some(Ray {
                origin,
                dir,
                tmin: 0.0,
                tmax: dist * 0.9999,
                time: 0.0,
            })
        })
        .collect()
}

/// The four generated sets, named as [`SET_NAMES`]: thin-lens primary rays in tile order, the
/// same rays in random order (shuffled with the seed), diffuse bounce rays and shadow rays from
/// the primary rays' first hits (found with `accel`, in tile order). Secondary sets have one ray
/// per primary ray that hits a surface.
pub fn generate_sets(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RaySetOptions,
) -> Vec<RaySet> {
    let samples = primary_samples(camera, opts);
    let tile: Vec<Ray> = samples
        .iter()
        .filter_map(|s| primary_ray(camera, s))
        .collect();
    let random = shuffled(&tile, opts.seed);
    let hits = first_hits(scene, accel, camera, &samples);
    let diffuse = diffuse_rays(accel, &hits, opts.seed);
    let shadow = shadow_target(scene).map_or_else(Vec::new, |t| shadow_rays(accel, &hits, t));
    [tile, random, diffuse, shadow]
        .into_iter()
        .zip(SET_NAMES)
        .map(|(rays, name)| RaySet {
            name: name.to_owned(),
            rays,
        })
        .collect()
}
