//! Loading a textured scene to a render-ready `Scene` (geometry, materials, decoded textures).
//!
//! `load_flight_helmet`: FlightHelmet (95 k triangles, 15 textures); the target is under 1 s.

use aperture_scene::{load, LoadOptions};
use criterion::{criterion_group, criterion_main, Criterion};

fn load_flight_helmet(c: &mut Criterion) {
    let path = aperture_benches::samples_dir().join("benchmark/FlightHelmet/FlightHelmet.gltf");
    if !path.is_file() {
        eprintln!("skipping load_flight_helmet: {} is missing", path.display());
        return;
    }
    let mut group = c.benchmark_group("load");
    group.sample_size(10);
    group.bench_function("load_flight_helmet", |b| {
        b.iter(|| {
            let scene = load(&path, &LoadOptions::default()).expect("FlightHelmet loads");
            assert_eq!(scene.textures.len(), 15);
            scene
        })
    });
    group.finish();
}

criterion_group!(benches, load_flight_helmet);
criterion_main!(benches);
