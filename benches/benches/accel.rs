//! Ray-query benchmarks: BVH build time (1 M synthetic triangles, `BlenderIO-32bitIndices` once the
//! glTF loader works) and closest-hit / occlusion throughput on thin-lens primary rays (in random
//! pixel order, as the Embree anchor traces them, and in the renderer's tile order) and diffuse
//! bounce rays, on 1 and 2 threads, over `BlenderIO-32bitIndices` (130 k triangles, the Embree
//! anchor's scene; all presets) and a synthetic ~300 k-triangle scene with instancing. Throughput is in rays
//! ("elements") per second; criterion's median is in `target/criterion/**/new/estimates.json`.
//!
//! `cargo bench -p aperture-benches --bench accel` (filter with e.g. `-- throughput`).

use std::time::Duration;

use aperture_accel::{Accel, BvhQuality, Hit, InstanceInput, MeshInput, Ray};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Affine3A, Vec3};

/// SplitMix64: deterministic rays and scenes.
struct Rng(u64);

impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A height field of `2 nx ny` triangles over `[0, size]^2`, with hills (a terrain-like mesh:
/// large, smooth, many small triangles, like scanned or sculpted assets).
fn terrain(nx: u32, ny: u32, size: f32, origin: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::with_capacity(((nx + 1) * (ny + 1)) as usize);
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (i as f32 / nx as f32 * size, j as f32 / ny as f32 * size);
            let h = 0.08 * size * ((x * 7.0 / size).sin() * (y * 5.0 / size).cos())
                + 0.01 * size * ((x * 61.0 / size).sin() + (y * 47.0 / size).cos());
            pos.push(origin + Vec3::new(x, h, y));
        }
    }
    let mut idx = Vec::with_capacity((2 * nx * ny) as usize);
    for j in 0..ny {
        for i in 0..nx {
            let a = j * (nx + 1) + i;
            let (b, c, d) = (a + 1, a + nx + 1, a + nx + 2);
            idx.push([a, c, b]);
            idx.push([b, c, d]);
        }
    }
    (pos, idx)
}

/// A unit icosphere with `20 * 4^sub` triangles (vertices shared).
fn icosphere(sub: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let m = aperture_shading::test_scenes::icosphere(sub, 0);
    (m.positions, m.indices)
}

struct OwnedScene {
    meshes: Vec<(Vec<Vec3>, Vec<[u32; 3]>)>,
    instances: Vec<InstanceInput>,
}

impl OwnedScene {
    fn build(&self, q: BvhQuality) -> Accel {
        let m: Vec<MeshInput> = self
            .meshes
            .iter()
            .map(|(p, i)| MeshInput {
                positions: p,
                indices: i,
            })
            .collect();
        Accel::build(&m, &self.instances, q)
    }
    fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for inst in &self.instances {
            for p in &self.meshes[inst.mesh as usize].0 {
                let w = inst.world_from_object.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        (lo, hi)
    }
}

/// ~1.0 M triangles: one terrain mesh (drawn once, so flattened).
fn scene_1m() -> OwnedScene {
    OwnedScene {
        meshes: vec![terrain(1000, 500, 100.0, Vec3::ZERO)],
        instances: vec![InstanceInput {
            mesh: 0,
            world_from_object: Affine3A::IDENTITY,
        }],
    }
}

/// ~305 k triangles: a terrain (180 k) with five icospheres (20 k each) drawn once and one
/// icosphere (5 k) drawn 25 times (instanced): 305 k unique, 405 k drawn.
fn scene_300k() -> OwnedScene {
    let mut meshes = vec![terrain(300, 300, 100.0, Vec3::new(-50.0, 0.0, -50.0))];
    let mut instances = vec![InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::IDENTITY,
    }];
    for k in 0..5 {
        let (p, i) = icosphere(5);
        let c = Vec3::new(-30.0 + 15.0 * k as f32, 10.0, (k as f32 * 1.7).sin() * 20.0);
        meshes.push((p.iter().map(|v| c + *v * 6.0).collect(), i));
        instances.push(InstanceInput {
            mesh: meshes.len() as u32 - 1,
            world_from_object: Affine3A::IDENTITY,
        });
    }
    meshes.push(icosphere(4));
    let shared = meshes.len() as u32 - 1;
    for k in 0..25 {
        let c = Vec3::new(
            -40.0 + (k % 5) as f32 * 20.0,
            4.0,
            -40.0 + (k / 5) as f32 * 20.0,
        );
        instances.push(InstanceInput {
            mesh: shared,
            world_from_object: Affine3A::from_scale_rotation_translation(
                Vec3::splat(2.5),
                glam::Quat::from_rotation_y(k as f32),
                c,
            ),
        });
    }
    OwnedScene { meshes, instances }
}

/// The Embree anchor's thin-lens camera: on (0.3, 0.2, 1) from the centre at 0.9 of the
/// diagonal, 40° field of view, focus at the centre, lens radius 2 %.
struct ThinLens {
    eye: Vec3,
    fwd: Vec3,
    right: Vec3,
    up: Vec3,
    focus_distance: f32,
    lens_radius: f32,
    tan_half_fov: f32,
}

impl ThinLens {
    fn new((lo, hi): (Vec3, Vec3)) -> Self {
        let c = (lo + hi) * 0.5;
        let ext = (hi - lo).length();
        let eye = c + Vec3::new(0.3, 0.2, 1.0).normalize() * ext * 0.9;
        let fwd = (c - eye).normalize();
        let right = fwd.cross(Vec3::Y).normalize();
        Self {
            eye,
            fwd,
            right,
            up: right.cross(fwd),
            focus_distance: (c - eye).length(),
            lens_radius: 0.02 * ext,
            tan_half_fov: 20f32.to_radians().tan(),
        }
    }

    /// The ray through film point `(px, py)` (−1..1 across, ±0.75 up) and the lens point drawn
    /// from `rng` (radius, then angle).
    fn ray(&self, px: f32, py: f32, rng: &mut Rng) -> Ray {
        let r = rng.f32().sqrt() * self.lens_radius;
        let phi = rng.f32() * std::f32::consts::TAU;
        let th = self.tan_half_fov;
        let focus =
            self.eye + self.focus_distance * (self.fwd + px * th * self.right + py * th * self.up);
        let o = self.eye + r * phi.cos() * self.right + r * phi.sin() * self.up;
        Ray::new(o, (focus - o).normalize())
    }
}

/// Thin-lens primary rays as the Embree anchor makes them: random film and lens points, one
/// after another.
fn thin_lens_rays(bounds: (Vec3, Vec3), n: usize, rng: &mut Rng) -> Vec<Ray> {
    let cam = ThinLens::new(bounds);
    (0..n)
        .map(|_| {
            let px = rng.f32() * 2.0 - 1.0;
            let py = (rng.f32() * 2.0 - 1.0) * 0.75;
            cam.ray(px, py, rng)
        })
        .collect()
}

/// The same camera's thin-lens primary rays in the order a renderer traces them: one sample per
/// pixel of a 4:3 image, in 32-pixel tiles (as `aperture_render` renders), each pixel's film
/// and lens position jittered. Neighbouring rays share most of their nodes, which the random
/// order of [`thin_lens_rays`] (the Embree anchor's) never lets them do.
fn thin_lens_rays_tiled(bounds: (Vec3, Vec3), n: usize, rng: &mut Rng) -> Vec<Ray> {
    let cam = ThinLens::new(bounds);
    // A 4:3 image with about n pixels.
    let w = ((n as f32 * 4.0 / 3.0).sqrt().round() as usize).max(1);
    let h = n.div_ceil(w);
    const TILE: usize = 32;
    let mut rays = Vec::with_capacity(n);
    'tiles: for ty in (0..h).step_by(TILE) {
        for tx in (0..w).step_by(TILE) {
            for y in ty..(ty + TILE).min(h) {
                for x in tx..(tx + TILE).min(w) {
                    if rays.len() == n {
                        break 'tiles;
                    }
                    let px = ((x as f32 + rng.f32()) / w as f32) * 2.0 - 1.0;
                    // Rows run down the image.
                    let py = (1.0 - ((y as f32 + rng.f32()) / h as f32) * 2.0) * 0.75;
                    rays.push(cam.ray(px, py, rng));
                }
            }
        }
    }
    rays
}

fn diffuse_rays(scene: &OwnedScene, accel: &Accel, primary: &[Ray], rng: &mut Rng) -> Vec<Ray> {
    primary
        .iter()
        .filter_map(|ray| {
            let hit: Hit = accel.intersect(ray)?;
            let inst = scene.instances[hit.instance as usize];
            let (p, idx) = &scene.meshes[inst.mesh as usize];
            let v = idx[hit.triangle as usize]
                .map(|i| inst.world_from_object.transform_point3(p[i as usize]));
            let mut n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            if n.dot(ray.dir) > 0.0 {
                n = -n;
            }
            let (t, b) = n.any_orthonormal_pair();
            let (r, phi) = (rng.f32().sqrt(), rng.f32() * std::f32::consts::TAU);
            let d = t * r * phi.cos() + b * r * phi.sin() + n * (1.0 - r * r).max(0.0).sqrt();
            Some(Ray::new(accel.spawn_point(ray, &hit).origin(n), d))
        })
        .collect()
}

fn build(c: &mut Criterion) {
    let scene = scene_1m();
    let mut g = c.benchmark_group("build");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    let tris = scene.meshes[0].1.len() as u64;
    g.throughput(Throughput::Elements(tris));
    for q in BvhQuality::ALL {
        g.bench_function(BenchmarkId::new("terrain_1M", q), |b| {
            b.iter(|| scene.build(q))
        });
    }
    let path = aperture_benches::samples_dir()
        .join("benchmark/BlenderIO-32bitIndices/01_vertex_count_32bit.gltf");
    match aperture_scene::load(&path, &Default::default()) {
        Ok(s) => {
            for q in BvhQuality::ALL {
                g.bench_function(BenchmarkId::new("BlenderIO-32bitIndices", q), |b| {
                    b.iter(|| aperture_render::build_accel(&s, q))
                });
            }
        }
        Err(e) => eprintln!("skipping BlenderIO-32bitIndices build: {e}"),
    }
    g.finish();
}

/// `BlenderIO-32bitIndices` (130 k triangles, the Embree anchor's scene) when the loader can
/// read it, else the synthetic ~300 k-triangle scene.
fn throughput_scene() -> (&'static str, OwnedScene) {
    let path = aperture_benches::samples_dir()
        .join("benchmark/BlenderIO-32bitIndices/01_vertex_count_32bit.gltf");
    match aperture_scene::load(&path, &Default::default()) {
        Ok(s) => (
            "blenderio32",
            OwnedScene {
                instances: s
                    .instances
                    .iter()
                    .map(|i| InstanceInput {
                        mesh: i.mesh,
                        world_from_object: i.world_from_object,
                    })
                    .collect(),
                meshes: s
                    .meshes
                    .into_iter()
                    .map(std::sync::Arc::unwrap_or_clone)
                    .map(|m| (m.positions, m.indices))
                    .collect(),
            },
        ),
        Err(e) => {
            eprintln!("BlenderIO-32bitIndices unavailable ({e}): synthetic scene");
            ("synthetic300k", scene_300k())
        }
    }
}

fn throughput(c: &mut Criterion) {
    let mut g = c.benchmark_group("throughput");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let n = 100_000;
    let mut scenes = vec![throughput_scene()];
    if scenes[0].0 != "synthetic300k" {
        scenes.push(("synthetic300k", scene_300k()));
    }
    for (k, (label, scene)) in scenes.iter().enumerate() {
        let mut rng = Rng(7);
        let primary = thin_lens_rays(scene.bounds(), n, &mut rng);
        // Its own stream, so the other sets stay the rays earlier runs measured.
        let tiled = thin_lens_rays_tiled(scene.bounds(), n, &mut Rng(11));
        // All presets on the first scene only (that is where they are compared).
        let qualities: &[BvhQuality] = if k == 0 {
            &BvhQuality::ALL
        } else {
            &[BvhQuality::Medium]
        };
        for &q in qualities {
            let accel = scene.build(q);
            let bounce = diffuse_rays(scene, &accel, &primary, &mut rng);
            for threads in [1usize, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                let mut hits = vec![None; n];
                let mut occl = vec![false; n];
                // Every quality on primary closest hit (to choose the presets); the rest at default.
                let sets: &[(&str, &[Ray])] = if q == BvhQuality::default() {
                    &[
                        ("primary", &primary),
                        ("primary_tiled", &tiled),
                        ("diffuse", &bounce),
                    ]
                } else {
                    &[("primary", &primary), ("primary_tiled", &tiled)]
                };
                for (name, rays) in sets {
                    g.throughput(Throughput::Elements(rays.len() as u64));
                    g.bench_function(format!("{label}/closest/{name}/{q}/{threads}t"), |b| {
                        b.iter(|| pool.install(|| accel.intersect_many(rays, &mut hits)))
                    });
                    if q == BvhQuality::default() {
                        g.bench_function(format!("{label}/occluded/{name}/{q}/{threads}t"), |b| {
                            b.iter(|| pool.install(|| accel.occluded_many(rays, &mut occl)))
                        });
                    }
                }
            }
        }
    }
    g.finish();
}

criterion_group!(benches, build, throughput);
criterion_main!(benches);
