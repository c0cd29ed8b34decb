//! The report on hand-built scenes.

use super::*;
use aperture_scene::{Camera, Dof, Instance, Light, Material, Mesh};
use glam::{Affine3A, Vec3};

/// Two instances of a two-triangle mesh whose second triangle is emissive.
fn scene() -> Scene {
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        normals: vec![Vec3::Z; 4],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material_ids: vec![0, 1],
        ..Mesh::default()
    };
    let glow = Material {
        emissive_factor: Vec3::ONE,
        ..Material::default()
    };
    let light = |kind| Light {
        name: None,
        kind,
        position: Vec3::ZERO,
        direction: Vec3::NEG_Z,
        intensity: Vec3::ONE,
    };
    Scene {
        meshes: vec![mesh.into()],
        instances: vec![
            Instance {
                mesh: 0,
                world_from_object: Affine3A::IDENTITY,
                node: 0,
                materials: 0,
            },
            Instance {
                mesh: 0,
                world_from_object: Affine3A::from_translation(Vec3::new(2.0, 0.0, 0.0)),
                node: 1,
                materials: 0,
            },
        ],
        materials: vec![Material::default(), glow],
        lights: vec![
            light(LightKind::Point),
            light(LightKind::Point),
            light(LightKind::Directional),
        ],
        cameras: vec![Camera {
            name: "Cam".into(),
            node: Some(2),
            index: Some(0),
            world_from_camera: Affine3A::IDENTITY,
            projection: Projection::Perspective {
                yfov: 0.7,
                aspect_ratio: Some(1.5),
            },
            dof: Dof {
                enabled: true,
                aperture_radius: 0.25,
                focus_object: Some("Target".into()),
                ..Dof::default()
            },
        }],
        ..Scene::default()
    }
}

#[test]
fn json_report_has_the_documented_keys_and_counts() {
    let r = report(&scene(), Convention::Auto, Convention::Auto);
    assert_eq!(r["triangles"]["unique"], 2);
    assert_eq!(r["triangles"]["drawn"], 4);
    assert_eq!(r["triangles"]["emissive_drawn"], 2);
    assert_eq!(r["lights"]["point"], 2);
    assert_eq!(r["lights"]["spot"], 0);
    assert_eq!(r["lights"]["directional"], 1);
    assert_eq!(r["bounds"]["min"], json!([0.0, 0.0, 0.0]));
    assert_eq!(r["bounds"]["max"], json!([3.0, 1.0, 1.0]));
    let c = &r["cameras"][0];
    assert_eq!(c["name"], "Cam");
    assert_eq!(c["node"], 2);
    assert_eq!(c["projection"], "perspective");
    assert_eq!(c["yfov"], 0.7);
    assert_eq!(c["aspect_ratio"], 1.5);
    assert_eq!(c["framed_on"], Value::Null, "a file's camera is not framed");
    let d = &c["dof"];
    assert_eq!(d["enabled"], true);
    assert_eq!(d["aperture_radius"], 0.25);
    assert_eq!(d["focus_distance"], 10.0);
    assert_eq!(d["focus_object"], "Target");
    for key in ["lens_mm", "blades", "rotation", "ratio"] {
        assert!(d.get(key).is_some_and(|v| !v.is_null()), "{key}");
    }
}

/// A recentred scene reports bounds and cameras in the file's coordinates.
#[test]
fn extensions_are_listed_with_what_aperture_does_with_them() {
    use aperture_scene::ExtensionStatus;
    let mut s = scene();
    s.stats.extensions = vec![
        ("KHR_node_visibility".into(), ExtensionStatus::Supported),
        ("KHR_xmp".into(), ExtensionStatus::Ignored),
    ];
    s.stats.hidden_nodes = 3;
    s.stats.keyed_visibility_nodes = 2;
    let r = report(&s, Convention::Auto, Convention::Auto);
    assert_eq!(r["extensions"][0]["name"], "KHR_node_visibility");
    assert_eq!(r["extensions"][0]["status"], "supported");
    assert!(r["extensions"][0].get("why").is_none());
    assert_eq!(r["extensions"][1]["status"], "ignored");
    assert!(r["extensions"][1]["why"]
        .as_str()
        .unwrap()
        .contains("optional"));
    assert_eq!(r["hidden_nodes"], 3);
    assert_eq!(r["keyed_visibility_nodes"], 2);
}

#[test]
fn recentred_scenes_report_file_coordinates() {
    let mut s = scene();
    s.world_origin = glam::DVec3::new(1e6, -2e6, 0.5);
    let r = report(&s, Convention::Auto, Convention::Auto);
    assert_eq!(r["world_origin"], json!([1e6, -2e6, 0.5]));
    assert_eq!(r["bounds"]["min"], json!([1e6, -2e6, 0.5]));
    assert_eq!(r["bounds"]["max"], json!([1e6 + 3.0, -2e6 + 1.0, 1.5]));
    assert_eq!(r["cameras"][0]["position"], json!([1e6, -2e6, 0.5]));
    assert_eq!(
        report(&scene(), Convention::Auto, Convention::Auto)["world_origin"],
        json!([0.0, 0.0, 0.0])
    );
}

/// The automatic camera says it is framed on the stored pose (issue 58), in JSON and text.
#[test]
fn the_automatic_camera_says_what_it_is_framed_on() {
    let mut s = scene();
    s.cameras[0].node = None;
    s.cameras[0].index = None;
    let r = report(&s, Convention::Auto, Convention::Auto);
    assert_eq!(r["cameras"][0]["framed_on"], "stored pose");
}

#[test]
fn empty_scene_has_null_bounds() {
    let r = report(&Scene::default(), Convention::Auto, Convention::Auto);
    assert_eq!(r["bounds"]["min"], Value::Null);
    assert_eq!(r["triangles"]["drawn"], 0);
}
