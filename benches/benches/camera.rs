//! Camera ray generation: pinhole, round thin lens and six-bladed thin lens (SPEC §2), in
//! batches of 4096 film/lens samples. Throughput is in rays per second.
//!
//! `cargo bench -p aperture-benches --bench camera`

use std::hint::black_box;
use std::time::Duration;

use aperture_render::{Camera, CameraSample};
use aperture_scene::Dof;
use aperture_shading::test_scenes;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Vec2, Vec3};

const N: usize = 4096;

fn samples() -> Vec<CameraSample> {
    // A deterministic low-discrepancy-ish spread over a 320x180 film and the unit lens square.
    (0..N)
        .map(|i| {
            let f = i as f32;
            CameraSample {
                p_film: Vec2::new(
                    (f * 0.618_034).fract() * 320.0,
                    (f * 0.754_877).fract() * 180.0,
                ),
                p_lens: Vec2::new((f * 0.569_840).fract(), (f * 0.324_718).fract()),
                time: 0.0,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("camera");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements(N as u64));
    let s = samples();
    let dof = |radius: f32, blades: u32| Dof {
        enabled: radius > 0.0,
        aperture_radius: radius,
        focus_distance: 2.0,
        blades,
        ..Dof::default()
    };
    for (name, d) in [
        ("pinhole", dof(0.0, 0)),
        ("disc", dof(0.02, 0)),
        ("hexagon", dof(0.02, 6)),
    ] {
        let cam = test_scenes::look_at_camera(Vec3::new(0.0, 1.0, 3.0), Vec3::ZERO, 0.7, d);
        let camera = Camera::new(&cam, 320, 180);
        g.bench_with_input(BenchmarkId::new("generate_ray", name), &camera, |b, cam| {
            b.iter(|| {
                let mut acc = Vec3::ZERO;
                for sample in &s {
                    if let Some(r) = cam.generate_ray(black_box(sample)) {
                        acc += r.dir;
                    }
                }
                acc
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
