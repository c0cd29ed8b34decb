//! The automatic camera of an animated file without a camera (issue 58, SPEC §3): framed once
//! on the stored pose, so every time gets the same camera (place, field of view, focus) even
//! when keyed visibility hides part of the scene or a node moves.

mod common;

use aperture_scene::{Animated, Camera, LoadOptions, Scene};
use glam::{DVec3, Vec3};
use serde_json::{json, Value};
use std::path::Path;

/// Key times of every channel: shown/at rest, hidden/moved, shown/back.
const TIMES: [f32; 3] = [0.0, 0.5, 1.0];

/// The binary buffer: a unit cube centred on its origin (positions at 0, u16 indices at 96),
/// the key times at 168, the visibility keys at 180 (shown, hidden, shown) and the
/// translation keys at 184.
fn bin(translations: [[f32; 3]; 3]) -> Vec<u8> {
    let mut bin = Vec::new();
    for k in 0..8 {
        for axis in 0..3 {
            let v: f32 = if k & (1 << axis) != 0 { 0.5 } else { -0.5 };
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    let faces: [[u16; 4]; 6] = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    for [a, b, c, d] in faces {
        for i in [a, b, c, a, c, d] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    for t in TIMES {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    bin.extend_from_slice(&[1, 0, 1, 0]);
    for v in translations.into_iter().flatten() {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    bin
}

/// A file drawing the cube once per node of `nodes`, animated by `channel` (sampler 0 keys
/// the visibility flags, sampler 1 the translations, both STEP), without a camera.
fn file(nodes: Value, channel: Value, translations: [[f32; 3]; 3]) -> Vec<u8> {
    let count = nodes.as_array().map_or(0, Vec::len);
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_node_visibility", "KHR_animation_pointer"],
        "buffers": [{"byteLength": 220}],
        "bufferViews": [{"buffer": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 72},
            {"buffer": 0, "byteOffset": 168, "byteLength": 52}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
             "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]},
            {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "SCALAR",
             "min": [0.0], "max": [1.0]},
            {"bufferView": 2, "byteOffset": 12, "componentType": 5121, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "byteOffset": 16, "componentType": 5126, "count": 3, "type": "VEC3"}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": nodes,
        "animations": [{"channels": [channel],
            "samplers": [{"input": 2, "output": 3, "interpolation": "STEP"},
                {"input": 2, "output": 4, "interpolation": "STEP"}]}],
        "scenes": [{"nodes": (0..count).collect::<Vec<_>>()}]
    });
    common::glb::glb(&doc, &bin(translations))
}

fn load(bytes: &[u8]) -> Animated {
    Animated::load_bytes(bytes, Path::new("."), &LoadOptions::default()).unwrap()
}

/// The one camera of a posed scene, which must be the automatic one.
fn automatic(s: &Scene) -> &Camera {
    assert_eq!(s.cameras.len(), 1);
    assert_eq!(s.cameras[0].node, None, "the automatic camera");
    &s.cameras[0]
}

/// Shaped like Khronos' CubeVisibility: three unit cubes in a row, the last one keyed hidden
/// from 0.5 s to 1 s.
fn cube_visibility() -> Vec<u8> {
    let nodes = json!([
        {"name": "left", "mesh": 0, "translation": [-2.0, 0.0, 0.0]},
        {"name": "middle", "mesh": 0},
        {"name": "blink", "mesh": 0, "translation": [2.0, 0.0, 0.0]}
    ]);
    let channel = json!({"sampler": 0, "target": {"path": "pointer", "extensions": {
        "KHR_animation_pointer": {"pointer": "/nodes/2/extensions/KHR_node_visibility/visible"}}}});
    file(nodes, channel, [[0.0; 3]; 3])
}

#[test]
fn a_blinking_cube_does_not_reframe_the_automatic_camera() {
    let a = load(&cube_visibility());
    let stored = a.scene_at(None).unwrap();
    let shown = a.scene_at(Some(0.0)).unwrap();
    let hidden = a.scene_at(Some(0.6)).unwrap();
    assert_eq!(
        hidden.instances.len(),
        2,
        "the blinking cube is hidden at 0.6 s"
    );
    assert_ne!(shown.bounds(), hidden.bounds());
    assert_eq!(automatic(&shown), automatic(&stored));
    assert_eq!(automatic(&hidden), automatic(&stored));
    // Framed on all three cubes (the stored pose): the focus is the eye's distance to their
    // centre, which the camera looks at.
    let c = automatic(&hidden);
    let eye = Vec3::from(c.world_from_camera.translation);
    assert!((eye.length() - c.dof.focus_distance).abs() < 1e-4);
    let forward = Vec3::from(-c.world_from_camera.matrix3.z_axis);
    assert!(forward.dot(-eye.normalize()) > 0.9999);
}

/// One cube keyed to `moves` (at rest, moved, back), stored at `moves[0]`, and with `still`
/// another at the origin.
fn moving(moves: [[f32; 3]; 3], still: bool) -> Vec<u8> {
    let mut nodes = json!([{"name": "mover", "mesh": 0, "translation": moves[0]}]);
    if let (true, Some(list)) = (still, nodes.as_array_mut()) {
        list.push(json!({"name": "still", "mesh": 0}));
    }
    let channel = json!({"sampler": 1, "target": {"node": 0, "path": "translation"}});
    file(nodes, channel, moves)
}

#[test]
fn a_moving_node_does_not_reframe_the_automatic_camera() {
    // The still cube keeps both poses around the file's origin (neither is recentred).
    let a = load(&moving([[0.0; 3], [3.0, 1.0, 0.0], [0.0; 3]], true));
    let stored = a.scene_at(None).unwrap();
    let rest = a.scene_at(Some(0.25)).unwrap();
    let moved = a.scene_at(Some(0.6)).unwrap();
    assert_ne!(rest.bounds(), moved.bounds(), "the cube moves");
    assert_eq!(rest.world_origin, moved.world_origin);
    assert_eq!(automatic(&rest), automatic(&stored));
    assert_eq!(automatic(&moved), automatic(&stored));
}

/// The camera's position in the file's coordinates (a recentred pose adds its origin back).
fn file_position(s: &Scene) -> DVec3 {
    s.world_origin + Vec3::from(automatic(s).world_from_camera.translation).as_dvec3()
}

#[test]
fn a_pose_recentred_elsewhere_keeps_the_camera_where_the_file_has_it() {
    let far = [[1e6, 0.0, 0.0], [1e6 + 40.0, 0.0, 0.0], [1e6, 0.0, 0.0]];
    let a = load(&moving(far, false));
    let stored = a.scene_at(None).unwrap();
    let moved = a.scene_at(Some(0.6)).unwrap();
    assert_ne!(
        stored.world_origin, moved.world_origin,
        "both poses recentred"
    );
    let (want, got) = (automatic(&stored), automatic(&moved));
    assert!(file_position(&stored).distance(file_position(&moved)) < 1e-4);
    assert_eq!(
        got.world_from_camera.matrix3,
        want.world_from_camera.matrix3
    );
    assert_eq!(got.projection, want.projection);
    assert_eq!(got.dof, want.dof);
}
