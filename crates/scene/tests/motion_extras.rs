//! The motion-blur keys of `scenes[i].extras` (SPEC §7) read from a file, and a wrong one
//! refused with the scene, key and value named.

mod common;

use aperture_scene::{Animated, LoadOptions, ShutterPosition};
use serde_json::json;

/// A file of one empty node in a scene with `extras`.
fn file(extras: serde_json::Value) -> Vec<u8> {
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0], "extras": extras}],
        "nodes": [{"name": "empty"}]
    });
    common::glb::glb(&doc, &[])
}

#[test]
fn scene_extras_are_read() {
    let bytes = file(json!({
        "use_motion_blur": true, "motion_blur_shutter": 0.25, "motion_blur_position": "END",
        "fps": 30.0, "frame_current": 12
    }));
    let doc = Animated::load_bytes(&bytes, ".".as_ref(), &LoadOptions::default()).unwrap();
    let m = doc.motion_extras();
    assert_eq!(m.use_motion_blur, Some(true));
    assert_eq!(m.shutter, Some(0.25));
    assert_eq!(m.position, Some(ShutterPosition::End));
    assert_eq!((m.fps, m.frame_current), (Some(30.0), Some(12)));
}

#[test]
fn a_wrong_key_names_scene_key_and_value() {
    let bytes = file(json!({"motion_blur_shutter": -2}));
    let err = Animated::load_bytes(&bytes, ".".as_ref(), &LoadOptions::default()).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("scenes[0]") && text.contains("motion_blur_shutter") && text.contains("-2"),
        "{text}"
    );
}
