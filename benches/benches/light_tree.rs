//! The light tree (issue 46): its build over ~100 k emissive triangles (one emissive ball of
//! 1,280 triangles instanced 80 times; the emitters' table included), and one vertex's pick
//! among N point lights with the tree and with the exhaustive choice.
//!
//! `cargo bench -p aperture-benches --bench light_tree`

use std::hint::black_box;
use std::time::Duration;

use aperture_scene::{Instance, Light, LightKind};
use aperture_shading::light_bounds::LightBounds;
use aperture_shading::light_choice::Candidates;
use aperture_shading::light_tree::{Leaf, LightTree};
use aperture_shading::lights::EmissiveLights;
use aperture_shading::{test_scenes, Geometry, MaterialOverride, TransmissionModel};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use glam::{Affine3A, Vec3};

fn build(c: &mut Criterion) {
    let mut scene = test_scenes::lit_plane(1.0);
    scene.materials.push(test_scenes::emitter(Vec3::ONE));
    scene.meshes.push(test_scenes::icosphere(3, 1).into());
    for k in 0..80 {
        let at = Vec3::new((k % 10) as f32 * 3.0, 2.0, (k / 10) as f32 * 3.0);
        scene.instances.push(Instance {
            mesh: 1,
            world_from_object: Affine3A::from_translation(at),
            node: 1,
            materials: 0,
        });
    }
    let geom = Geometry::with_transmission(&scene, MaterialOverride::None, TransmissionModel::Gltf);
    let em = EmissiveLights::build(&geom).expect("emitters");
    eprintln!("{} emissive triangles", em.triangles.len());
    let mut g = c.benchmark_group("light_tree");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("emitters_and_tree_100k", |b| {
        b.iter(|| {
            let em = EmissiveLights::build(&geom).expect("emitters");
            black_box(LightTree::build(&geom, Some(&em)))
        })
    });
    g.bench_function("tree_100k", |b| {
        b.iter(|| black_box(LightTree::build(&geom, Some(&em))))
    });
    // The same build on one thread: what the parallel subtrees save.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    g.bench_function("tree_100k_one_thread", |b| {
        b.iter(|| one.install(|| black_box(LightTree::build(&geom, Some(&em)))))
    });
    g.finish();
}

/// `n` point lights on a 40 m square, as the street grid's.
fn lights(n: usize) -> Vec<Light> {
    (0..n)
        .map(|i| {
            let f = i as f32;
            Light {
                name: None,
                kind: LightKind::Point,
                position: Vec3::new(
                    (f * 0.618_034).fract() * 40.0 - 20.0,
                    0.3 + (f * 0.754_877).fract() * 3.7,
                    (f * 0.569_840).fract() * 40.0 - 20.0,
                ),
                direction: Vec3::NEG_Y,
                intensity: Vec3::splat(10.0),
            }
        })
        .collect()
}

fn pick(c: &mut Criterion) {
    let mut g = c.benchmark_group("light_pick");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    for n in [10usize, 32, 64, 100, 1000, 10_000] {
        let lights = lights(n);
        let leaves = lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| Some((LightBounds::punctual(l, 10.0)?, Leaf::Punctual(i as u32))))
            .collect();
        let tree = LightTree::from_leaves(leaves, &lights, 0).expect("tree");
        let points: Vec<Vec3> = (0..256)
            .map(|i| {
                Vec3::new(
                    (i % 16) as f32 * 2.5 - 20.0,
                    0.0,
                    (i / 16) as f32 * 2.5 - 20.0,
                )
            })
            .collect();
        g.bench_with_input(BenchmarkId::new("tree", n), &n, |b, _| {
            b.iter(|| {
                for (k, &p) in points.iter().enumerate() {
                    let u = (k as f32 * 0.618_034).fract();
                    black_box(tree.pick(&lights, p, Vec3::Y, false, u));
                }
            })
        });
        if n <= 1000 {
            let cands = Candidates {
                lights: &lights,
                emitters: None,
            };
            g.bench_with_input(BenchmarkId::new("exhaustive", n), &n, |b, _| {
                b.iter(|| {
                    for (k, &p) in points.iter().enumerate() {
                        let u = (k as f32 * 0.618_034).fract();
                        black_box(cands.pick(p, Vec3::Y, false, u));
                    }
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, build, pick);
criterion_main!(benches);
