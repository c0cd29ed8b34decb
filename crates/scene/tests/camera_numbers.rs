//! One camera numbering (issue 50): in a file whose camera nodes use glTF cameras in another
//! order than their indices, `camera N` names, [`Scene::select_camera`] and `Camera::index` all
//! mean glTF camera `N`, and `node:J` tells apart two nodes carrying the same camera.

use aperture_scene::{load_bytes, LoadOptions};
use serde_json::json;
use std::path::Path;

mod common;

#[test]
fn camera_numbers_are_gltf_indices_whatever_the_node_order() {
    let doc = json!({
        "asset": {"version": "2.0"},
        "cameras": [
            {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
            {"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.1}}
        ],
        "nodes": [
            {"camera": 1, "translation": [0.0, 0.0, 5.0]},
            {"camera": 0, "translation": [0.0, 0.0, 7.0]},
            {"camera": 1, "translation": [0.0, 0.0, 9.0]}
        ],
        "scenes": [{"nodes": [0, 1, 2]}]
    });
    let bytes = common::glb::glb(&doc, &[]);
    let s = load_bytes(&bytes, Path::new("."), &LoadOptions::default()).unwrap();
    let names: Vec<_> = s.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["camera 1", "camera 0", "camera 1"]);
    let indices: Vec<_> = s.cameras.iter().map(|c| c.index).collect();
    assert_eq!(indices, [Some(1), Some(0), Some(1)]);
    // `--camera 0` is the camera named "camera 0", on node 1.
    let zero = s.select_camera("0").unwrap();
    assert_eq!(
        (s.cameras[zero].name.as_str(), s.cameras[zero].node),
        ("camera 0", Some(1))
    );
    assert_eq!(s.select_camera("camera 0").unwrap(), zero);
    // Camera 1 is drawn twice: `1` is its first node, `node:2` the other.
    assert_eq!(s.cameras[s.select_camera("1").unwrap()].node, Some(0));
    assert_eq!(s.cameras[s.select_camera("node:2").unwrap()].node, Some(2));
    assert_eq!(s.camera_selector(2), "1 (node:2)");
    let e = s.select_camera("2").unwrap_err().to_string();
    assert!(
        e.contains("no camera \"2\"") && e.contains("0 \"camera 0\""),
        "{e}"
    );
}
