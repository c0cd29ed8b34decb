//! Real glTF files from `../shared/gltf-samples`, loaded and rendered tiny: every image must be
//! finite, non-constant, and drop no sample.

use aperture_render::{build_accel, render, RenderOptions};
use aperture_scene::LoadOptions;
use glam::Vec3;

/// A dozen small scenes covering textures, vertex colours, cameras, punctual lights, emission,
/// unlit, alpha, instancing and mirrored instances.
const SAMPLES: &[&str] = &[
    "correctness/Box/Box.glb",
    "correctness/BoxTextured/BoxTextured.glb",
    "correctness/BoxVertexColors/BoxVertexColors.glb",
    "correctness/Cameras/Cameras.gltf",
    "correctness/CornellBox/CornellBox.glb",
    "correctness/Cubes-PointLight/Cubes.glb",
    "correctness/DeccerCubes/SM_Deccer_Cubes_Textured.glb",
    "correctness/EmissiveStrengthTest/EmissiveStrengthTest.glb",
    "correctness/SimpleInstancing/SimpleInstancing.glb",
    "correctness/TextureTransformTest/TextureTransformTest.gltf",
    "correctness/UnlitTest/UnlitTest.glb",
    "correctness/VertexColorTest/VertexColorTest.glb",
    "correctness/AlphaBlendModeTest/AlphaBlendModeTest.glb",
    "correctness/TwoSidedPlane/TwoSidedPlane.gltf",
    "correctness/NegativeScaleTest/NegativeScaleTest.glb",
];

#[test]
fn samples_render_finite_non_constant_images() {
    let Some(dir) = aperture_tests::samples_dir() else {
        return;
    };
    let opts = RenderOptions {
        width: 48,
        height: 32,
        spp: 4,
        max_bounces: 2,
        // Most samples have no lights: a grey sky lights them.
        env: aperture_shading::Environment::Constant(Vec3::splat(0.8)),
        ..RenderOptions::default()
    };
    for rel in SAMPLES {
        let path = dir.join(rel);
        let scene = aperture_scene::load(&path, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
        let accel = build_accel(&scene, Default::default());
        let film =
            render(&scene, &accel, &opts, &|_, _| {}).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let px = film.to_rgba();
        assert!(
            px.iter().flatten().all(|c| c.is_finite()),
            "{rel}: non-finite pixel"
        );
        let lum = |p: &[f32; 4]| p[0] + p[1] + p[2];
        let (lo, hi) = px
            .iter()
            .map(lum)
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        assert!(hi > lo, "{rel}: constant image ({lo})");
        assert_eq!(film.dropped_samples(), 0, "{rel}: dropped samples");
        let coverage = px.iter().map(|p| p[3]).sum::<f32>() / px.len() as f32;
        println!("{rel}: luminance {lo:.3}..{hi:.3}, coverage {coverage:.2}");
    }
}
