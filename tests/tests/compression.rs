//! Compressed geometry (SPEC §5): `KHR_draco_mesh_compression` samples load and render, and an
//! `EXT_meshopt_compression` copy of a sample (written here with meshoptimizer's encoder) renders
//! bit-identical to the file it was made from.

use aperture_render::RenderOptions;
use aperture_scene::{load, LoadOptions};
use aperture_tests::meshopt_writer::{self, IndexMode};
use glam::Vec3;

fn tiny() -> RenderOptions {
    RenderOptions {
        width: 48,
        height: 36,
        spp: 4,
        max_bounces: 2,
        env: aperture_shading::Environment::Constant(Vec3::splat(0.8)),
        ..RenderOptions::default()
    }
}

#[test]
fn meshopt_copies_render_bit_identical() {
    let Some(dir) = aperture_tests::samples_dir() else {
        return;
    };
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("meshopt");
    std::fs::create_dir_all(&out).unwrap();
    for rel in [
        "correctness/BoxTextured/BoxTextured.glb",
        "correctness/NormalTangentMirrorTest/NormalTangentMirrorTest.glb",
    ] {
        let original = dir.join(rel);
        let (json, bin) = meshopt_writer::split_glb(&std::fs::read(&original).unwrap());
        // The triangle codec keeps each triangle but may rotate its corners (same winding).
        let (tjson, tbin, _) = meshopt_writer::compress(&json, &bin, IndexMode::Triangles);
        let tri = out.join(format!(
            "triangles-{}",
            original.file_name().unwrap().to_string_lossy()
        ));
        std::fs::write(&tri, meshopt_writer::join_glb(&tjson, &tbin)).unwrap();
        let rotated = load(&tri, &LoadOptions::default()).unwrap();
        let plain = load(&original, &LoadOptions::default()).unwrap();
        for (mp, mr) in plain.meshes.iter().zip(&rotated.meshes) {
            assert_eq!(mp.positions, mr.positions, "{rel}");
            for (p, r) in mp.indices.iter().zip(&mr.indices) {
                let turns = [*r, [r[1], r[2], r[0]], [r[2], r[0], r[1]]];
                assert!(turns.contains(p), "{rel}: triangle {p:?} decoded as {r:?}");
            }
        }
        // The index sequence codec keeps every index: the render must not change at all.
        let (cjson, cbin, views) = meshopt_writer::compress(&json, &bin, IndexMode::Indices);
        assert!(views >= 2, "{rel}: only {views} views compressed");
        let copy = out.join(original.file_name().unwrap());
        std::fs::write(&copy, meshopt_writer::join_glb(&cjson, &cbin)).unwrap();
        let a = load(&original, &LoadOptions::default()).unwrap();
        let b = load(&copy, &LoadOptions::default()).unwrap();
        for (ma, mb) in a.meshes.iter().zip(&b.meshes) {
            assert_eq!(ma.positions, mb.positions, "{rel}");
            assert_eq!(ma.normals, mb.normals, "{rel}");
            assert_eq!(ma.indices, mb.indices, "{rel}");
            assert_eq!(ma.uv0, mb.uv0, "{rel}");
        }
        let fa = aperture_tests::render_checked(&a, &tiny()).to_rgba();
        let fb = aperture_tests::render_checked(&b, &tiny()).to_rgba();
        let same = fa
            .iter()
            .zip(&fb)
            .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits));
        println!(
            "{rel}: {views} views meshopt-compressed, {} -> {} bytes of BIN; render bit-identical: {same}",
            bin.len(),
            cbin.len()
        );
        assert!(same, "{rel}: the meshopt copy renders differently");
    }
}

#[test]
fn draco_samples_load_and_render() {
    let Some(dir) = aperture_tests::samples_dir() else {
        return;
    };
    for (rel, triangles) in [
        ("unsupported/Box-Draco/Box.gltf", 12),
        ("compression/Avocado-Draco/Avocado.gltf", 682),
    ] {
        let path = dir.join(rel);
        let s = load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert_eq!(s.drawn_triangle_count(), triangles, "{rel}");
        // The decoded positions lie inside the POSITION accessor's bounds (Draco's quantisation
        // grid) and fill them.
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        let acc = &json["accessors"][json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize];
        let v = |k: &str| {
            Vec3::from_slice(
                &acc[k]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect::<Vec<_>>(),
            )
        };
        let (lo, hi) = (v("min"), v("max"));
        let b = s.bounds();
        let slack = (hi - lo) * 0.01;
        assert!(
            b.min.cmpge(lo - 1e-6).all() && b.max.cmple(hi + 1e-6).all(),
            "{rel}: {b:?} outside {lo}..{hi}"
        );
        assert!(
            b.min.cmple(lo + slack).all() && b.max.cmpge(hi - slack).all(),
            "{rel}: {b:?} does not fill {lo}..{hi}"
        );
        assert!(s.meshes[0]
            .normals
            .iter()
            .all(|n| (n.length() - 1.0).abs() < 1e-3));
        let px = aperture_tests::render_checked(&s, &tiny()).to_rgba();
        let lum: Vec<f32> = px.iter().map(|p| p[0] + p[1] + p[2]).collect();
        let (lo, hi) = lum
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let coverage = px.iter().map(|p| p[3]).sum::<f32>() / px.len() as f32;
        println!("{rel}: bounds {b:?}, luminance {lo:.3}..{hi:.3}, coverage {coverage:.2}");
        assert!(hi > lo && coverage > 0.05, "{rel}: nothing drawn");
    }
}
