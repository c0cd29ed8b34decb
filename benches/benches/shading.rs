//! BSDF evaluation and sampling (glTF metallic-roughness: Lambert + GGX/Smith, Schlick) for
//! a diffuse dielectric, a rough metal and a near-mirror metal, in batches of 4096 directions.
//! Throughput is in evaluations (or samples) per second.
//!
//! `cargo bench -p aperture-benches --bench shading`

use std::hint::black_box;
use std::time::Duration;

use aperture_shading::Bsdf;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;

const N: usize = 4096;

fn dirs() -> Vec<(Vec3, Vec3, f32, [f32; 2])> {
    (0..N)
        .map(|i| {
            let f = i as f32;
            let hemi = |a: f32, b: f32| {
                let (u, v) = ((f * a).fract(), (f * b).fract());
                let z = u.max(0.05);
                let r = (1.0 - z * z).sqrt();
                let phi = v * std::f32::consts::TAU;
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            };
            (
                hemi(0.618_034, 0.754_877),
                hemi(0.569_840, 0.324_718),
                (f * 0.412_454).fract(),
                [(f * 0.245_122).fract(), (f * 0.877_438).fract()],
            )
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("shading");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements(N as u64));
    let d = dirs();
    for (name, bsdf) in [
        (
            "diffuse",
            Bsdf::metal_rough(Vec3::new(0.8, 0.2, 0.2), 0.0, 0.5),
        ),
        (
            "rough_metal",
            Bsdf::metal_rough(Vec3::new(1.0, 0.8, 0.4), 1.0, 0.4),
        ),
        (
            "mirror_metal",
            Bsdf::metal_rough(Vec3::splat(0.9), 1.0, 0.02),
        ),
    ] {
        g.bench_with_input(BenchmarkId::new("eval", name), &bsdf, |b, bsdf| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for (wo, wi, _, _) in &d {
                    let (f, pdf) = bsdf.eval(black_box(*wo), *wi);
                    acc += f.x + pdf;
                }
                acc
            })
        });
        g.bench_with_input(BenchmarkId::new("sample", name), &bsdf, |b, bsdf| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for (wo, _, lobe, u) in &d {
                    if let Some(s) = bsdf.sample(black_box(*wo), *lobe, *u) {
                        acc += s.pdf;
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
