use std::path::Path;

use base64::Engine;
use glam::{DVec3, Vec3};
use serde_json::{json, Value};

use super::load_bytes;
use crate::error::Error;
use crate::types::{LightKind, LoadOptions, Scene};

/// One triangle (no normals) plus, from byte 44, instancing translations for 3 instances.
fn bin() -> Vec<u8> {
    let mut b = Vec::new();
    let floats = [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, // positions
    ];
    for x in floats {
        b.extend(x.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        b.extend(i.to_le_bytes());
    }
    for x in [0.0f32, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 5.0, 0.0] {
        b.extend(x.to_le_bytes());
    }
    b
}

fn gltf(nodes: Value, scene_nodes: Value, extra: Value) -> Vec<u8> {
    let b = bin();
    let mut j = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": scene_nodes}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 44, "byteLength": 36}
        ],
        "buffers": [{"byteLength": b.len(), "uri": format!("data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&b))}]
    });
    if let (Some(o), Some(e)) = (j.as_object_mut(), extra.as_object()) {
        o.extend(e.clone());
    }
    serde_json::to_vec(&j).unwrap()
}

fn load_json(bytes: &[u8]) -> Result<Scene, Error> {
    load_bytes(bytes, Path::new("."), &LoadOptions::default())
}

#[test]
fn shared_mesh_is_stored_once_with_hierarchy_transforms() {
    let s = load_json(&gltf(
        json!([
            {"translation": [1, 0, 0], "children": [1, 2]},
            {"mesh": 0, "scale": [2, 2, 2]},
            {"mesh": 0, "matrix": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,3,0,1]}
        ]),
        json!([0]),
        json!({}),
    ))
    .unwrap();
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.instances.len(), 2);
    assert_eq!(s.drawn_triangle_count(), 2);
    assert_eq!(s.stats.nodes, 3);
    let a = s.instances[0].world_from_object;
    assert_eq!(a.transform_point3(Vec3::X), Vec3::new(3.0, 0.0, 0.0));
    let b = s.instances[1];
    assert_eq!(
        b.world_from_object.transform_point3(Vec3::X),
        Vec3::new(0.0, 3.0, 0.0)
    );
    assert!(b.is_mirrored() && !s.instances[0].is_mirrored());
    // No NORMAL: flat normals, one vertex per corner, facing +Z for this CCW triangle.
    assert_eq!(s.meshes[0].positions.len(), 3);
    assert!(s.meshes[0].normals.iter().all(|n| *n == Vec3::Z));
    // No material: the glTF default one.
    assert_eq!(s.materials, vec![crate::types::Material::default()]);
}

#[test]
fn far_scenes_are_recentred_in_f64() {
    // A root at 1e6 (f32 spacing 0.0625 there) with children 0.3 apart: in f32 the
    // composition would round 1e6 + 0.3 to 1e6 + 0.3125.
    let s = load_json(&gltf(
        json!([
            {"translation": [1e6, 0, -1e6], "children": [1, 2, 3]},
            {"mesh": 0, "translation": [0.3, 0, 0]},
            {"mesh": 0, "translation": [-0.3, 0, 0]},
            {"camera": 0, "translation": [0.3, 0, 2]}
        ]),
        json!([0]),
        json!({"cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}]}),
    ))
    .unwrap();
    // Geometry spans x in [-0.3, 1.3], y in [0, 1] around the root.
    assert_eq!(s.world_origin, DVec3::new(1e6 + 0.5, 0.5, -1e6));
    let o = |i: usize| {
        s.instances[i]
            .world_from_object
            .transform_point3(Vec3::ZERO)
    };
    assert!(
        (o(0) - Vec3::new(-0.2, -0.5, 0.0)).length() < 1e-6,
        "{}",
        o(0)
    );
    assert!(
        (o(1) - Vec3::new(-0.8, -0.5, 0.0)).length() < 1e-6,
        "{}",
        o(1)
    );
    let eye = Vec3::from(s.cameras[0].world_from_camera.translation);
    assert!((eye - Vec3::new(-0.2, -0.5, 2.0)).length() < 1e-6, "{eye}");
    assert!(s.stats.warnings.is_empty(), "{:?}", s.stats.warnings);

    // Vertices far from their own mesh origin move into the instance transform.
    let mut b: Value =
        serde_json::from_slice(&gltf(json!([{"mesh": 0}]), json!([0]), json!({}))).unwrap();
    let far: Vec<u8> = [1e6f32, 0.0, 0.0, 1e6 + 1.0, 0.0, 0.0, 1e6, 1.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .chain(bin()[36..].iter().copied())
        .collect();
    b["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&far)
    ));
    b["accessors"][0]["min"] = json!([1e6, 0, 0]);
    b["accessors"][0]["max"] = json!([1e6 + 1.0, 1, 0]);
    let s = load_json(&serde_json::to_vec(&b).unwrap()).unwrap();
    assert_eq!(s.world_origin, DVec3::new(1e6 + 0.5, 0.5, 0.0));
    assert_eq!(s.meshes[0].positions[1], Vec3::new(0.5, -0.5, 0.0));
    assert_eq!(s.bounds().min, Vec3::new(-0.5, -0.5, 0.0));

    // A scene whose own extent f32 cannot hold at millimetres is loaded with a warning.
    let s = load_json(&gltf(
        json!([{"mesh": 0}, {"mesh": 0, "translation": [3e4, 0, 0], "scale": [1e-3, 1e-3, 1e-3]}]),
        json!([0, 1]),
        json!({}),
    ))
    .unwrap();
    assert!(
        s.stats.warnings.iter().any(|w| w.contains("float32")),
        "{:?}",
        s.stats.warnings
    );
}

#[test]
fn gpu_instancing_multiplies_instances_not_geometry() {
    let s = load_json(&gltf(
        json!([{"mesh": 0, "translation": [0, 0, 1],
            "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 2}}}}]),
        json!([0]),
        json!({"extensionsUsed": ["EXT_mesh_gpu_instancing"], "extensionsRequired": ["EXT_mesh_gpu_instancing"]}),
    ))
    .unwrap();
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.unique_triangle_count(), 1);
    assert_eq!(s.drawn_triangle_count(), 3);
    let origins: Vec<Vec3> = s
        .instances
        .iter()
        .map(|i| i.world_from_object.transform_point3(Vec3::ZERO))
        .collect();
    assert_eq!(
        origins,
        [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(5.0, 0.0, 1.0),
            Vec3::new(0.0, 5.0, 1.0)
        ]
    );
}

#[test]
fn lights_in_blender_units_placed_by_nodes() {
    let s = load_json(&gltf(
        json!([
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0],
             "rotation": [-std::f32::consts::FRAC_1_SQRT_2, 0, 0, std::f32::consts::FRAC_1_SQRT_2]},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}}
        ]),
        json!([0, 1]),
        json!({"extensionsUsed": ["KHR_lights_punctual"], "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "intensity": 683, "color": [1, 0.5, 0], "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}},
            {"type": "directional", "intensity": 1366}
        ]}}}),
    ))
    .unwrap();
    assert_eq!(s.lights.len(), 2);
    let spot = &s.lights[0];
    assert!(
        (spot.intensity - Vec3::new(1.0, 0.5, 0.0))
            .abs()
            .max_element()
            < 1e-6
    );
    assert!(
        (spot.direction - Vec3::NEG_Y).length() < 1e-5,
        "{}",
        spot.direction
    );
    assert_eq!(spot.position, Vec3::new(0.0, 2.0, 0.0));
    assert_eq!(
        spot.kind,
        LightKind::Spot {
            inner_cone: 0.1,
            outer_cone: 0.5
        }
    );
    assert!(
        (s.lights[1].intensity - Vec3::splat(2.0))
            .abs()
            .max_element()
            < 1e-6
    );
}

#[test]
fn camera_scale_is_removed_and_automatic_camera_frames_bounds() {
    let cam =
        json!({"cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}]});
    let s = load_json(&gltf(
        json!([{"mesh": 0}, {"camera": 0, "scale": [3, 3, 3], "translation": [0, 0, 4]}]),
        json!([0, 1]),
        cam,
    ))
    .unwrap();
    let c = &s.cameras[0];
    assert_eq!(c.node, Some(1));
    assert!((c.world_from_camera.matrix3.determinant() - 1.0).abs() < 1e-5);
    assert_eq!(
        Vec3::from(c.world_from_camera.translation),
        Vec3::new(0.0, 0.0, 4.0)
    );

    let s = load_json(&gltf(json!([{"mesh": 0}]), json!([0]), json!({}))).unwrap();
    assert_eq!(s.cameras.len(), 1);
    let c = &s.cameras[0];
    assert_eq!(c.node, None);
    let eye = Vec3::from(c.world_from_camera.translation);
    let forward = Vec3::from(-c.world_from_camera.matrix3.z_axis);
    let to_center = (s.bounds().center() - eye).normalize();
    assert!(forward.dot(to_center) > 0.9999);
    assert!(eye.z > s.bounds().max.z && eye.y > s.bounds().center().y);
    assert!(!c.dof.enabled);
}

#[test]
fn dof_sources_reach_the_camera() {
    let extra = json!({"cameras": [{"name": "Lens", "type": "perspective",
        "perspective": {"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1},
        "extensions": {"EXT_camera_physical": {"focalLength": 0.05, "fStop": 4.0, "focusDistance": 2.0}},
        "extras": {"aperture_blades": 6}}]});
    let nodes = json!([
        {"mesh": 0, "name": "Target", "translation": [0, 0, -3]},
        {"camera": 0, "translation": [0, 0, 4], "extras": {"focus_object": {"name": "Target", "type": "Object"}}}
    ]);
    let s = load_json(&gltf(nodes.clone(), json!([0, 1]), extra.clone())).unwrap();
    let d = &s.cameras[0].dof;
    assert!(d.enabled);
    assert_eq!(d.lens_mm, 50.0);
    assert!((d.aperture_radius - 0.05 / 8.0).abs() < 1e-7);
    assert!((d.focus_distance - 7.0).abs() < 1e-5);
    assert_eq!(d.focus_object.as_deref(), Some("Target"));
    assert_eq!(d.blades, 6);
    // The command line wins over every file source.
    let opts = LoadOptions {
        dof_overrides: crate::types::DofOverrides {
            aperture_radius: Some(0.5),
            focus_distance: Some(1.5),
            ..Default::default()
        },
        ..LoadOptions::default()
    };
    let s = load_bytes(&gltf(nodes, json!([0, 1]), extra), Path::new("."), &opts).unwrap();
    assert_eq!(
        (
            s.cameras[0].dof.aperture_radius,
            s.cameras[0].dof.focus_distance
        ),
        (0.5, 1.5)
    );
    assert_eq!(s.cameras[0].dof.focus_object, None);
}

#[test]
fn only_images_of_drawn_materials_are_decoded() {
    // Material 1 is used by no primitive; its image file does not exist.
    let extra = json!({
        "images": [{"uri": "does-not-exist.png"}],
        "textures": [{"source": 0}],
        "materials": [{"name": "used"}, {"name": "unused", "emissiveTexture": {"index": 0}}]
    });
    let mut bytes: Value =
        serde_json::from_slice(&gltf(json!([{"mesh": 0}]), json!([0]), extra)).unwrap();
    bytes["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = load_json(&serde_json::to_vec(&bytes).unwrap()).unwrap();
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].name.as_deref(), Some("used"));
    assert!(s.textures.is_empty());
    // Used, the same file is an error that names the image.
    bytes["meshes"][0]["primitives"][0]["material"] = json!(1);
    let e = load_json(&serde_json::to_vec(&bytes).unwrap()).unwrap_err();
    assert!(e.to_string().contains("images[0].uri"), "{e}");
}

#[test]
fn material_extensions_are_read_without_warnings() {
    let extra = json!({
        "materials": [{"name": "Glass", "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": {"thicknessFactor": 0.5, "attenuationDistance": 2.0,
                                     "attenuationColor": [0.5, 0.5, 1.0]},
            "KHR_materials_ior": {"ior": 1.4},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.2},
            "KHR_materials_sheen": {"sheenColorFactor": [0.1, 0.2, 0.3], "sheenRoughnessFactor": 0.4},
            "KHR_materials_dispersion": {"dispersion": 0.5}
        }}]
    });
    let mut bytes: Value = serde_json::from_slice(&gltf(
        json!([{"mesh": 0}, {"mesh": 0}]),
        json!([0, 1]),
        extra,
    ))
    .unwrap();
    bytes["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = load_json(&serde_json::to_vec(&bytes).unwrap()).unwrap();
    assert!(
        !s.stats.warnings.iter().any(|w| w.contains("Glass")),
        "{:?}",
        s.stats.warnings
    );
    let m = &s.materials[0];
    assert_eq!(m.ior, 1.4);
    assert_eq!(m.transmission.map(|t| t.factor), Some(1.0));
    let v = m.volume.unwrap();
    assert!(v.is_volume() && v.attenuation_distance == 2.0);
    assert_eq!(
        m.clearcoat.map(|c| (c.factor, c.roughness_factor)),
        Some((0.7, 0.2))
    );
    assert_eq!(
        m.sheen.map(|c| c.color_factor),
        Some(glam::Vec3::new(0.1, 0.2, 0.3))
    );
    assert_eq!(m.dispersion, 0.5);
    assert!(m.has_extended_lobes());
}
