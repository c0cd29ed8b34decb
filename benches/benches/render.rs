//! A small full render (lit plane, emissive ball, 64×64, 8 spp, one thread): pinhole against
//! thin lens, uniform against adaptive sampling; and the BVH build of the same scene per preset.
//! Throughput is in samples per second (uniform budget).
//!
//! `cargo bench -p aperture-benches --bench render`

use std::time::Duration;

use aperture_accel::BvhQuality;
use aperture_render::{build_accel, render, AdaptiveOptions, RenderOptions};
use aperture_scene::Scene;
use aperture_shading::test_scenes;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Affine3A, Vec3};

fn scene(lens_radius: f32) -> Scene {
    let mut s = test_scenes::lit_plane(3.0);
    s.cameras[0].dof.enabled = lens_radius > 0.0;
    s.cameras[0].dof.aperture_radius = lens_radius;
    s.cameras[0].dof.focus_distance = 61f32.sqrt();
    s.materials
        .push(test_scenes::emitter(Vec3::new(4.0, 3.0, 2.0)));
    s.meshes.push(test_scenes::icosphere(3, 1).into());
    s.instances.push(aperture_scene::Instance {
        mesh: 1,
        world_from_object: Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.3),
            Default::default(),
            Vec3::new(0.5, 0.3, 1.0),
        ),
        node: 1,
        materials: 0,
    });
    s
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let mut g = c.benchmark_group("render");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    let base = RenderOptions {
        width: 64,
        height: 64,
        spp: 8,
        ..RenderOptions::default()
    };
    g.throughput(Throughput::Elements(64 * 64 * 8));
    for (name, radius, adaptive) in [
        ("pinhole", 0.0, None),
        ("thin_lens", 0.2, None),
        (
            "thin_lens_adaptive_0.05",
            0.2,
            Some(AdaptiveOptions {
                threshold: 0.05,
                min_spp: 4,
            }),
        ),
    ] {
        let s = scene(radius);
        let accel = build_accel(&s, BvhQuality::default());
        let opts = RenderOptions {
            adaptive,
            ..base.clone()
        };
        g.bench_function(BenchmarkId::new("64x64_8spp_1thread", name), |b| {
            b.iter(|| pool.install(|| render(&s, &accel, &opts, &|_, _| {}).expect("render")))
        });
    }
    let s = scene(0.2);
    g.throughput(Throughput::Elements(
        s.meshes.iter().map(|m| m.indices.len() as u64).sum(),
    ));
    for (name, q) in [
        ("fast", BvhQuality::Fast),
        ("medium", BvhQuality::Medium),
        ("high", BvhQuality::High),
    ] {
        g.bench_function(BenchmarkId::new("bvh_build", name), |b| {
            b.iter(|| pool.install(|| build_accel(&s, q)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
