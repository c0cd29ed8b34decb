//! Watertightness end to end (issue 6, part 3): a camera inside a closed mesh that reflects
//! nothing, inside an emissive shell. Every camera ray hits the black mesh, whose material
//! returns no light, so the only way a pixel gets anything is a ray slipping through a crack
//! between triangles and seeing the shell: every pixel must be exactly 0, at scales 1e-4 to 1e4
//! and far from the origin. A mesh with one triangle removed proves the setup can fail.

#[path = "stress_util.rs"]
mod util;

use aperture_render::Film;
use aperture_scene::Scene;
use aperture_shading::test_scenes::icosphere;
use glam::{Quat, Vec3};
use serde_json::json;
use util::{render_camera, Gltf};

const SIZE: (u32, u32) = (48, 32);
const SPP: u32 = 16;

/// Writes the scene: the black icosphere (shared vertices, as a watertight mesh stores them) of
/// radius 1 with `drop` triangles removed, inside a two-sided emissive icosphere of radius 3,
/// all scaled by `scale` and moved by `translation`. Camera 0 is a wide pinhole off the centre;
/// camera 1 has a large lens, so its rays leave from all over the aperture. Both look at the
/// first triangle.
fn scene(scale: f32, translation: [f64; 3], drop: usize) -> Scene {
    let mut g = Gltf::new();
    g.uses("KHR_materials_specular");
    g.uses("KHR_materials_emissive_strength");
    // Base colour 0 kills the diffuse lobe; specular factor 0 kills the dielectric Fresnel
    // layer, which would otherwise reflect the shell at grazing angles even over black.
    let black = g.material(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
        "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}));
    let glow = g.material(json!({"emissiveFactor": [1, 1, 1], "doubleSided": true,
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}}));
    let sphere = icosphere(3, 0);
    let target = {
        let [a, b, c] = sphere.indices[0].map(|i| sphere.positions[i as usize]);
        (a + b + c) / 3.0
    };
    let inner = g.mesh(
        &sphere.positions,
        Some(&sphere.normals),
        None,
        &sphere.indices[drop..],
        black,
    );
    let outer = g.mesh(
        &sphere.positions,
        Some(&sphere.normals),
        None,
        &sphere.indices,
        glow,
    );
    let eye = [Vec3::new(0.1, -0.2, 0.15), Vec3::new(-0.3, 0.1, -0.2)];
    let look = |eye: Vec3| Quat::from_rotation_arc(Vec3::NEG_Z, (target - eye).normalize());
    let pinhole = g.camera(json!({"type": "perspective",
        "perspective": {"yfov": 2.4, "znear": 0.001}}));
    let lens = g.camera(json!({"type": "perspective",
        "perspective": {"yfov": 1.2, "znear": 0.001},
        "extras": {"aperture_radius": 0.4 * scale, "focus_distance": 0.5 * scale,
                   "aperture_blades": 5}}));
    let children = [
        g.node(json!({"mesh": inner})),
        g.node(json!({"mesh": outer, "scale": [3, 3, 3]})),
        g.node(json!({"camera": pinhole, "translation": eye[0].to_array(),
            "rotation": look(eye[0]).to_array()})),
        g.node(json!({"camera": lens, "translation": eye[1].to_array(),
            "rotation": look(eye[1]).to_array()})),
    ];
    // A rotation, so no triangle edge is aligned with an axis.
    let root = g.node(json!({"children": children, "scale": [scale, scale, scale],
        "rotation": util::quat(Vec3::new(1.0, 2.0, 3.0), 0.7), "translation": translation}));
    g.load(&[root])
}

/// Pixels that received any light, over both cameras.
fn lit_pixels(scene: &Scene) -> usize {
    (0..2)
        .map(|camera| {
            let film: Film = render_camera(scene, SIZE, SPP, 0, 2, camera);
            film.to_rgba()
                .iter()
                .filter(|p| p[..3].iter().any(|&c| c != 0.0))
                .count()
        })
        .sum()
}

#[test]
fn a_closed_black_mesh_lets_no_light_through_at_any_scale() {
    for scale in [1e-4f32, 1e-2, 1.0, 1e2, 1e4] {
        let s = scene(scale, [0.0; 3], 0);
        assert_eq!(lit_pixels(&s), 0, "scale {scale:e}");
    }
    for t in [[1e5, 0.0, 0.0], [-1e6, 1e6, 1e6]] {
        let s = scene(1.0, t, 0);
        assert_eq!(lit_pixels(&s), 0, "translation {t:?}");
    }
}

/// The same scene with the triangle both cameras look at removed: light comes through.
#[test]
fn a_missing_triangle_lets_light_through() {
    for scale in [1e-4f32, 1.0, 1e4] {
        let lit = lit_pixels(&scene(scale, [0.0; 3], 1));
        assert!(lit > 0, "scale {scale:e}: the hole was not seen");
    }
}
