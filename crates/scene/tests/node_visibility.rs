//! `KHR_node_visibility` (issue 48): a node stored `visible: false` hides its whole subtree
//! (no instance, no light), a visible child of a hidden parent stays hidden, and a hidden camera
//! or focus object still works (SPEC §3).

use aperture_scene::{load_bytes, LoadOptions, Scene};
use serde_json::{json, Value};
use std::path::Path;

mod common;

/// A GLB of `doc` over one triangle's positions (3 × VEC3 float) and indices.
fn glb(doc: &Value) -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    common::glb::glb(doc, &bin)
}

fn hidden() -> Value {
    json!({"KHR_node_visibility": {"visible": false}})
}

/// Nodes: 0 shown; 1 hidden; 2 hidden parent of 3 (visible itself); 4 a hidden light; 5 a
/// hidden camera focused on node 1. With `visibility` false the same file without the flags.
fn file(visibility: bool) -> Vec<u8> {
    let ext = |e: Value| if visibility { e } else { json!({}) };
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_node_visibility", "KHR_lights_punctual", "ACME_optional"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10.0}]}},
        "buffers": [{"byteLength": 44}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1},
            "extras": {"focus_object": "hidden", "aperture_fstop": 2.0}}],
        "nodes": [
            {"name": "shown", "mesh": 0},
            {"name": "hidden", "mesh": 0, "translation": [0.0, 0.0, -7.0], "extensions": ext(hidden())},
            {"name": "parent", "children": [3], "extensions": ext(hidden())},
            {"name": "child", "mesh": 0, "translation": [2.0, 0.0, 0.0],
             "extensions": ext(json!({"KHR_node_visibility": {"visible": true}}))},
            {"name": "lamp", "translation": [0.0, 3.0, 0.0],
             "extensions": {"KHR_lights_punctual": {"light": 0},
                "KHR_node_visibility": {"visible": !visibility}}},
            {"name": "eye", "camera": 0, "translation": [0.0, 0.0, 3.0], "extensions": ext(hidden())}
        ],
        "scenes": [{"nodes": [0, 1, 2, 4, 5]}]
    });
    if visibility {
        doc["extensionsRequired"] = json!(["KHR_node_visibility"]);
    }
    glb(&doc)
}

fn load(visibility: bool) -> Scene {
    load_bytes(&file(visibility), Path::new("."), &LoadOptions::default()).unwrap()
}

#[test]
fn hidden_subtrees_draw_and_light_nothing() {
    let all = load(false);
    assert_eq!(all.instances.len(), 3);
    assert_eq!(all.lights.len(), 1);
    assert_eq!(all.stats.hidden_nodes, 0);
    let s = load(true);
    let nodes: Vec<u32> = s.instances.iter().map(|i| i.node).collect();
    assert_eq!(nodes, vec![0], "only the visible node draws");
    assert!(s.lights.is_empty(), "a hidden light lights nothing");
    // hidden, parent, child, lamp, eye.
    assert_eq!(s.stats.hidden_nodes, 5);
}

#[test]
fn a_hidden_camera_and_a_hidden_focus_object_still_work() {
    let (all, s) = (load(false), load(true));
    assert_eq!(s.cameras.len(), 1);
    assert_eq!(s.cameras[0].node, Some(5));
    assert_eq!(
        s.cameras[0].world_from_camera,
        all.cameras[0].world_from_camera
    );
    // The camera at z = 3 focuses on the hidden node at z = -7.
    assert!((s.cameras[0].dof.focus_distance - 10.0).abs() < 1e-4);
    assert_eq!(
        s.cameras[0].dof.focus_distance,
        all.cameras[0].dof.focus_distance
    );
}

#[test]
fn every_used_extension_is_reported_supported_or_ignored() {
    use aperture_scene::ExtensionStatus::{Ignored, Supported};
    let s = load(true);
    let got: Vec<(&str, _)> = (s.stats.extensions.iter())
        .map(|(n, st)| (n.as_str(), *st))
        .collect();
    assert_eq!(
        got,
        vec![
            ("KHR_node_visibility", Supported),
            ("KHR_lights_punctual", Supported),
            ("ACME_optional", Ignored)
        ]
    );
    assert!(s.stats.warnings.iter().any(|w| w.contains("ACME_optional")));
}
