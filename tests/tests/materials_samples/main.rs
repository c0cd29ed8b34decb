//! glTF sample models render as their READMEs intend, checked by probing pixel colours.
//!
//! Pixels are attributed to scene objects by tracing each pixel's centre ray through the same
//! camera the render uses: a pixel belongs to an object when it and its 8 neighbours all hit
//! that object (so edges and antialiasing are left out). Expected colours come from the
//! samples' READMEs and reference screenshots, never from the renderer's own texture code.

use aperture_render::{FilterKind, RenderOptions};
use aperture_scene::{LoadOptions, Scene};
use aperture_shading::Environment;
use aperture_tests::probe::Probe;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

mod lights;
mod marks;
mod normal_maps;
mod textures;

/// Under a white sky of radiance 1, a Lambertian surface shows its albedo.
fn white_sky(width: u32, height: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        spp,
        max_bounces: 1,
        filter: FilterKind::Box,
        env: Environment::Constant(Vec3::ONE),
        ..RenderOptions::default()
    }
}

fn load(path: &Path) -> Scene {
    aperture_scene::load(path, &LoadOptions::default()).unwrap()
}

/// An equirectangular sky with a sharp horizon: bright above, dark below.
fn horizon_sky() -> Environment {
    Environment::Image(std::sync::Arc::new(aperture_shading::EnvImage {
        width: 64,
        height: 32,
        texels: (0..64 * 32)
            .map(|i| {
                if i / 64 < 16 {
                    Vec3::new(1.0, 0.9, 0.8)
                } else {
                    Vec3::new(0.02, 0.03, 0.05)
                }
            })
            .collect(),
        rotation: 0.0,
        strength: 1.0,
        sampling: aperture_shading::EnvSampling::Importance,
    }))
}

/// An orthographic camera looking down −Z at the whole scene, so every part of it is seen
/// from the same direction.
fn front_ortho(scene: &Scene, w: u32, h: u32) -> aperture_scene::Camera {
    let b = scene.bounds();
    let half = 0.5 * (b.max - b.min);
    let ymag = half.y.max(half.x * h as f32 / w as f32) * 1.05;
    aperture_scene::Camera {
        name: "front".into(),
        node: None,
        index: None,
        world_from_camera: glam::Affine3A::from_translation(Vec3::new(
            b.center().x,
            b.center().y,
            b.max.z + 5.0,
        )),
        projection: aperture_scene::Projection::Orthographic {
            xmag: ymag * w as f32 / h as f32,
            ymag,
        },
        dof: aperture_scene::Dof::default(),
    }
}

/// Big textured models render with every texture kind, and not one sample is NaN or infinite.
#[test]
fn textured_models_render_without_dropped_samples() {
    for rel in [
        "benchmark/FlightHelmet/FlightHelmet.gltf",
        "benchmark/ToyCar/ToyCar.glb",
        "benchmark/GlamVelvetSofa/GlamVelvetSofa.glb",
        "benchmark/StainedGlassLamp/StainedGlassLamp.gltf",
    ] {
        let Some(dir) = aperture_tests::samples_dir() else {
            return;
        };
        let path = dir.join(rel);
        let path = if path.is_file() {
            path
        } else {
            // Some folders hold the .glb or .gltf variant only.
            let stem = path.with_extension("");
            ["glb", "gltf"]
                .iter()
                .map(|e| stem.with_extension(e))
                .find(|p| p.is_file())
                .unwrap_or_else(|| panic!("{rel} missing"))
        };
        let scene = load(&path);
        let textured = scene
            .materials
            .iter()
            .filter(|m| {
                m.base_color_texture.is_some()
                    || m.metallic_roughness_texture.is_some()
                    || m.normal_texture.is_some()
                    || m.emissive_texture.is_some()
            })
            .count();
        let normal_mapped: Vec<_> = scene
            .materials
            .iter()
            .enumerate()
            .filter(|(_, m)| m.normal_texture.is_some())
            .map(|(i, _)| i as u32)
            .collect();
        // Every normal-mapped triangle has a tangent frame (given or MikkTSpace).
        for mesh in &scene.meshes {
            for (t, mid) in mesh.material_ids.iter().enumerate() {
                if normal_mapped.contains(mid) && !mesh.uv0.is_empty() {
                    for &v in &mesh.indices[t] {
                        assert!(
                            mesh.tangents[v as usize].truncate() != Vec3::ZERO,
                            "{rel}: no tangent"
                        );
                    }
                }
            }
        }
        let probe = Probe::new(&scene, &white_sky(40, 30, 4));
        let px = probe.film.to_rgba();
        assert!(px.iter().flatten().all(|c| c.is_finite()));
        let mut distinct: HashMap<[u32; 3], ()> = HashMap::new();
        for p in &px {
            distinct.insert([p[0].to_bits(), p[1].to_bits(), p[2].to_bits()], ());
        }
        println!(
            "{rel}: {textured} textured and {} normal-mapped materials, {} distinct pixels, warnings {:?}",
            normal_mapped.len(),
            distinct.len(),
            scene.stats.warnings
        );
        assert!(textured > 0, "{rel}: no texture");
        assert!(distinct.len() > 100, "{rel}: image too flat");
    }
}
