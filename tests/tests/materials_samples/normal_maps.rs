//! Normal maps with generated and given tangents against the real geometry beside them.

use aperture_render::{build_accel, render, Camera, FilterKind, RenderOptions};
use aperture_scene::Scene;
use aperture_tests::probe::{pixel_hits, sample};

use crate::{front_ortho, horizon_sky, load};

/// How far the normal-mapped cells differ from the real-geometry cells beside them: for each
/// pixel on curved geometry (geometric normal more than 10° off the view axis), the difference
/// to the pixel `s` to its right, where a flat (normal-mapped) quad must be; the best shift `s`
/// is searched, so the layout need not be known.
fn normal_map_mismatch(scene: &Scene) -> f32 {
    let (w, h) = (240u32, 200u32);
    let mut scene = scene.clone();
    scene.cameras = vec![front_ortho(&scene, w, h)];
    let opts = RenderOptions {
        width: w,
        height: h,
        spp: 16,
        max_bounces: 1,
        filter: FilterKind::Box,
        env: horizon_sky(),
        ..RenderOptions::default()
    };
    let accel = build_accel(&scene, Default::default());
    let film = render(&scene, &accel, &opts, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let camera = Camera::new(&scene.cameras[0], w, h);
    let hits = pixel_hits(&accel, &camera, w, h);
    // Per pixel: None (background), Some(true) curved geometry, Some(false) flat.
    let curved: Vec<Option<bool>> = hits
        .iter()
        .map(|hit| {
            let (i, t) = (*hit)?;
            let inst = &scene.instances[i as usize];
            let n = inst.world_geometric_normal(&scene.meshes[inst.mesh as usize], t as usize)?;
            Some(n.z.abs() < 10f32.to_radians().cos())
        })
        .collect();
    let px = film.to_rgba();
    let lum = |i: usize| px[i][0] + px[i][1] + px[i][2];
    let n_curved = curved.iter().filter(|c| **c == Some(true)).count();
    assert!(n_curved > 500, "{n_curved} curved pixels");
    let mut best = f32::INFINITY;
    for s in 3..w / 4 {
        let (mut sum, mut n) = (0.0f32, 0usize);
        for y in 0..h {
            for x in 0..w - s {
                let i = (y * w + x) as usize;
                let j = i + s as usize;
                if curved[i] == Some(true) && curved[j] == Some(false) {
                    sum += (lum(i) - lum(j)).abs();
                    n += 1;
                }
            }
        }
        if 2 * n > n_curved {
            best = best.min(sum / n as f32);
        }
    }
    best
}

/// The same scene with the normal maps' green channel inverted (the DirectX convention):
/// the classic failure the README describes.
fn flip_normal_map_green(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let normal: Vec<u32> = s
        .materials
        .iter()
        .filter_map(|m| m.normal_texture.map(|t| t.texture))
        .collect();
    for t in normal {
        match &mut s.textures[t as usize].texels {
            aperture_scene::Texels::Rgba8(v) => v.iter_mut().for_each(|p| p[1] = 255 - p[1]),
            aperture_scene::Texels::Rgba32F(v) => v.iter_mut().for_each(|p| p[1] = 1.0 - p[1]),
        }
    }
    s
}

/// NormalTangentTest (MikkTSpace tangents) and NormalTangentMirrorTest (`TANGENT` given,
/// mirrored UVs): each normal-mapped cell reflects a horizon like the real geometry beside it.
/// The measure must be clearly better than for the same maps with green inverted.
#[test]
fn normal_tangent_tests_match_real_geometry() {
    for rel in [
        "correctness/NormalTangentTest/NormalTangentTest.glb",
        "correctness/NormalTangentMirrorTest/NormalTangentMirrorTest.glb",
    ] {
        let Some(path) = sample(rel) else { return };
        let scene = load(&path);
        let good = normal_map_mismatch(&scene);
        let flipped = normal_map_mismatch(&flip_normal_map_green(&scene));
        println!("{rel}: mismatch {good:.4}, with green inverted {flipped:.4}");
        assert!(good < 0.7 * flipped, "{rel}: {good} vs {flipped}");
    }
}
