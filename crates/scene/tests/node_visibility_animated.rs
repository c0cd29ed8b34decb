//! `KHR_node_visibility` keyed by `KHR_animation_pointer` (issue 48): the posed scene at a time
//! leaves out the subtrees hidden at that time (instances, lights), with the stored flag's
//! meaning (a keyed hidden parent hides its visible child), a node stored hidden but keyed
//! visible is drawn, and a hidden camera or focus object still works at every time.

use aperture_scene::{Animated, LoadOptions, Scene};
use serde_json::{json, Value};
use std::path::Path;

mod common;

/// Frame `f` at Blender's 24 fps, as `--frame` poses it.
fn frame(f: i64) -> f32 {
    (f as f64 / 24.0) as f32
}

/// The binary buffer: a triangle (positions at 0, u16 indices at 36), three key times at 44
/// (frame 0, and halfway to frames 2 and 4, so no frame falls on a key), the blinking node's
/// keys at 56 (hidden, shown, hidden), the parent's at 59 (shown, hidden, shown), the camera's
/// single key time at 64 and its key at 68 (hidden).
fn bin(blink: [u8; 3]) -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    for t in [0.0f32, 1.5 / 24.0, 3.5 / 24.0] {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    bin.extend_from_slice(&blink);
    bin.extend_from_slice(&[1, 0, 1, 0, 0]);
    bin.extend_from_slice(&0.0f32.to_le_bytes());
    bin.push(0);
    bin
}

fn accessors() -> Value {
    let keys = |offset: usize, count: usize| {
        json!({"bufferView": 2, "byteOffset": offset, "componentType": 5121, "count": count,
            "type": "SCALAR"})
    };
    json!([
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
         "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        {"bufferView": 2, "componentType": 5126, "count": 3, "type": "SCALAR",
         "min": [0.0], "max": [3.5 / 24.0]},
        keys(12, 3),
        keys(15, 3),
        {"bufferView": 2, "byteOffset": 20, "componentType": 5126, "count": 1, "type": "SCALAR",
         "min": [0.0], "max": [0.0]},
        keys(24, 1)
    ])
}

fn channel(sampler: usize, node: usize) -> Value {
    json!({"sampler": sampler, "target": {"path": "pointer", "extensions": {
        "KHR_animation_pointer": {"pointer": format!("/nodes/{node}/extensions/KHR_node_visibility/visible")}}}})
}

fn visible(v: bool) -> Value {
    json!({"KHR_node_visibility": {"visible": v}})
}

/// Nodes: 0 "blink", stored hidden, keyed hidden at frame 0, shown at 2, hidden at 4; 1
/// "parent", keyed shown, hidden at 2, shown at 4, over 2 "child" (stored visible, a mesh and a
/// light); 3 "still", never keyed; 4 "eye", a camera keyed hidden, focused on "blink".
/// `interpolation` is the samplers'.
fn file(interpolation: &str) -> Vec<u8> {
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_node_visibility", "KHR_animation_pointer", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10.0}]}},
        "buffers": [{"byteLength": 69}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 44, "byteLength": 25}],
        "accessors": accessors(),
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1},
            "extras": {"focus_object": "blink", "aperture_fstop": 2.0}}],
        "nodes": [
            {"name": "blink", "mesh": 0, "translation": [-2.0, 0.0, -4.0], "extensions": visible(false)},
            {"name": "parent", "mesh": 0, "children": [2]},
            {"name": "child", "mesh": 0, "translation": [2.0, 0.0, 0.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}, "KHR_node_visibility": {"visible": true}}},
            {"name": "still", "mesh": 0, "translation": [0.0, -2.0, 0.0]},
            {"name": "eye", "camera": 0, "translation": [0.0, 0.0, 6.0]}
        ],
        "animations": [{"channels": [channel(0, 0), channel(1, 1), channel(2, 4)],
            "samplers": [{"input": 2, "output": 3, "interpolation": interpolation},
                {"input": 2, "output": 4, "interpolation": interpolation},
                {"input": 5, "output": 6, "interpolation": "STEP"}]}],
        "scenes": [{"nodes": [0, 1, 3, 4]}]
    });
    common::glb::glb(&doc, &bin([0, 1, 0]))
}

fn load(interpolation: &str) -> Animated {
    Animated::load_bytes(
        &file(interpolation),
        Path::new("."),
        &LoadOptions::default(),
    )
    .unwrap()
}

/// The nodes drawn, in order.
fn drawn(s: &Scene) -> Vec<u32> {
    s.instances.iter().map(|i| i.node).collect()
}

#[test]
fn keyed_visibility_hides_and_shows_subtrees_frame_by_frame() {
    let a = load("STEP");
    assert_eq!(a.toggling_nodes(), [0, 1, 2, 4]);
    assert!(a.moving_nodes().is_empty());
    let stored = a.scene_at(None).unwrap();
    assert_eq!(drawn(&stored), [1, 2, 3], "the stored flags: blink hidden");
    assert_eq!(stored.stats.keyed_visibility_nodes, 3, "blink, parent, eye");
    // Per frame: the nodes drawn, the lights, the nodes hidden (eye always).
    let want: [(&[u32], usize, usize); 5] = [
        (&[1, 2, 3], 1, 2),
        (&[1, 2, 3], 1, 2),
        (&[0, 3], 0, 3),
        (&[0, 3], 0, 3),
        (&[1, 2, 3], 1, 2),
    ];
    for (f, (nodes, lights, hidden)) in want.into_iter().enumerate() {
        let s = a.scene_at(Some(frame(f as i64))).unwrap();
        assert_eq!(drawn(&s), nodes, "frame {f}");
        assert_eq!(s.lights.len(), lights, "frame {f}: the child's light");
        assert_eq!(s.stats.hidden_nodes, hidden, "frame {f}");
        // Only instances come and go: every mesh is the same static one at every frame.
        assert_eq!(s.meshes.len(), a.static_mesh_count(), "frame {f}");
        assert!(s.stats.warnings.is_empty(), "{:?}", s.stats.warnings);
    }
}

#[test]
fn a_keyed_hidden_camera_and_focus_object_still_work() {
    let a = load("STEP");
    let first = a.scene_at(Some(frame(0))).unwrap();
    for f in 0..5 {
        let s = a.scene_at(Some(frame(f))).unwrap();
        assert_eq!(s.cameras.len(), 1, "frame {f}");
        assert_eq!(s.cameras[0].node, Some(4));
        assert_eq!(
            s.cameras[0].world_from_camera,
            first.cameras[0].world_from_camera
        );
        // The camera at z = 6 focuses on "blink" at z = -4, drawn or not.
        assert!(
            (s.cameras[0].dof.focus_distance - 10.0).abs() < 1e-4,
            "frame {f}"
        );
    }
}

#[test]
fn a_linear_bool_is_held_at_its_keys_and_warned() {
    let (step, linear) = (load("STEP"), load("LINEAR"));
    let warned = linear.scene_at(Some(frame(1))).unwrap().stats.warnings;
    assert_eq!(warned.len(), 2, "{warned:?}");
    assert!(
        warned[0].starts_with("animations[0].channels[0]: KHR_node_visibility"),
        "{warned:?}"
    );
    // Interpolated, frame 1 would be two thirds of the way to shown (non-zero: true); held, hidden.
    for f in 0..5 {
        let (s, l) = (
            step.scene_at(Some(frame(f))),
            linear.scene_at(Some(frame(f))),
        );
        assert_eq!(drawn(&s.unwrap()), drawn(&l.unwrap()), "frame {f}");
    }
}
