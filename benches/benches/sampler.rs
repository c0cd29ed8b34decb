//! Sample generation: the camera's 4-D point (pixel + lens) against the pinhole's 2-D pair,
//! and one path vertex's two 4-D sets, for Owen-scrambled Sobol and the random sampler.
//! Throughput is in primary samples per second (a batch of 64 pixels × 64 samples).
//!
//! `cargo bench -p aperture-benches --bench sampler`

use std::hint::black_box;
use std::time::Duration;

use aperture_render::{SampleStream, SamplerKind};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

const PIXELS: u32 = 64;
const SPP: u32 = 64;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("sampler");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements(u64::from(PIXELS * SPP)));
    for kind in [SamplerKind::Sobol, SamplerKind::Random] {
        let name = format!("{kind:?}").to_lowercase();
        let each = |f: &dyn Fn(&SampleStream) -> f32| {
            let mut acc = 0.0f32;
            for p in 0..PIXELS {
                for i in 0..SPP {
                    acc += f(&SampleStream::new(kind, black_box(p), 7, i, 0));
                }
            }
            acc
        };
        g.bench_function(BenchmarkId::new("camera_4d_thin_lens", &name), |b| {
            b.iter(|| each(&|s| s.camera()[3]))
        });
        g.bench_function(BenchmarkId::new("pixel_2d_pinhole", &name), |b| {
            b.iter(|| each(&|s| s.pixel()[1]))
        });
        g.bench_function(BenchmarkId::new("bounce_vertex", &name), |b| {
            b.iter(|| each(&|s| s.bounce(1).rr + s.vertex_light(1).alpha))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
