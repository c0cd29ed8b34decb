//! The ray-query structure on real glTF samples (loaded with `aperture_scene`): triangle counts
//! match the sample index, and closest hit and occlusion equal brute force on random rays,
//! including the instanced samples (`SimpleInstancing`: 12 -> 1,500 triangles,
//! `BlenderIO-GpuInstancing`: 4,034 -> 7,656,770) and mirrored instances (`NegativeScaleTest`).

#[path = "accel_util.rs"]
mod util;

use aperture_accel::{Accel, BvhQuality, Ray};
use aperture_scene::{load, LoadOptions, Scene};
use util::Rng;

fn load_sample(folder: &str, file: &str) -> Option<Scene> {
    let dir = aperture_tests::samples_dir()?;
    let options = LoadOptions {
        skip_textures: true,
        ..Default::default()
    };
    Some(load(&dir.join(folder).join(file), &options).expect("sample loads"))
}

fn build(scene: &Scene) -> Accel {
    aperture_render::build_accel(scene, BvhQuality::default())
}

/// Rays from around and inside the scene bounds towards random points inside them, so most hit.
fn rays(scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
    let b = scene.bounds();
    let (c, half) = ((b.min + b.max) * 0.5, (b.max - b.min) * 0.5);
    let mut rng = Rng(seed);
    (0..n)
        .map(|i| {
            let o = if i % 2 == 0 {
                c + rng.unit_vector() * half.length() * 1.5
            } else {
                rng.vec_in(b.min, b.max)
            };
            let target = rng.vec_in(c - half * 0.8, c + half * 0.8);
            Ray::new(o, target - o)
        })
        .collect()
}

fn assert_matches_brute_force(accel: &Accel, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for (k, ray) in rays.iter().enumerate() {
        let (a, b) = (accel.intersect(ray), accel.intersect_brute_force(ray));
        assert_eq!(
            a.map(|h| h.t),
            b.map(|h| h.t),
            "ray {k} {ray:?}: {a:?} vs {b:?}"
        );
        if let (Some(a), Some(b)) = (a, b) {
            // Equal t on different triangles only happens on shared edges and vertices, or on
            // instances drawn twice at the same place (same triangle and barycentrics).
            let coincident = (a.triangle, a.u, a.v) == (b.triangle, b.u, b.v);
            if (a.instance, a.triangle) != (b.instance, b.triangle) && !coincident {
                let w = 1.0 - a.u - a.v;
                assert!(a.u.min(a.v).min(w) < 1e-3, "ray {k}: {a:?} vs {b:?}");
            }
        }
        assert_eq!(accel.occluded(ray), b.is_some(), "occlusion of ray {k}");
        hits += a.is_some() as usize;
    }
    assert!(
        hits > rays.len() / 10,
        "only {hits} of {} rays hit",
        rays.len()
    );
    hits
}

#[test]
fn simple_instancing_stores_the_cube_once() {
    let Some(scene) = load_sample("correctness/SimpleInstancing", "SimpleInstancing.glb") else {
        return;
    };
    let accel = build(&scene);
    let s = accel.stats();
    assert_eq!((s.unique_triangles, s.drawn_triangles), (12, 1500));
    assert_eq!(s.degenerate_triangles, 0);
    assert!(s.blas_count <= 2, "{s:?}");
    assert_matches_brute_force(&accel, &rays(&scene, 2000, 1));
}

#[test]
fn gpu_instancing_stores_unique_geometry_once() {
    let Some(scene) = load_sample(
        "benchmark/BlenderIO-GpuInstancing",
        "24_gpu_instancing.gltf",
    ) else {
        return;
    };
    let accel = build(&scene);
    let s = accel.stats();
    assert_eq!(s.drawn_triangles, 7_656_770, "{s:?}");
    assert_eq!(s.unique_triangles, 4034, "{s:?}");
    // Far less than one copy of the drawn triangles (7.66 M x 40 bytes).
    assert!(s.memory_bytes < 10_000_000, "{s:?}");
    // Brute force walks all 7.66 M drawn triangles per ray: keep the count small.
    assert_matches_brute_force(&accel, &rays(&scene, 40, 2));
}

#[test]
fn blender_32bit_indices_and_mirrored_instances() {
    for (folder, file, n) in [
        (
            "benchmark/BlenderIO-32bitIndices",
            "01_vertex_count_32bit.gltf",
            150,
        ),
        (
            "correctness/NegativeScaleTest",
            "NegativeScaleTest.glb",
            1000,
        ),
        (
            "correctness/RecursiveSkeletons",
            "RecursiveSkeletons.glb",
            500,
        ),
        ("benchmark/GlassVaseFlowers", "GlassVaseFlowers.glb", 300),
    ] {
        let Some(scene) = load_sample(folder, file) else {
            return;
        };
        let accel = build(&scene);
        let s = accel.stats();
        assert_eq!(
            s.drawn_triangles + s.degenerate_triangles + s.invalid_index_triangles,
            scene.drawn_triangle_count(),
            "{folder}: {s:?}"
        );
        assert_matches_brute_force(&accel, &rays(&scene, n, 3));
    }
}
