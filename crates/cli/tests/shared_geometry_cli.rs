//! Two glTF meshes over the same accessors, one red and one green, render each in its own
//! colour though they share one mesh and BVH (issue 50).

mod common;

use aperture_imageio::read_exr;
use common::{aperture, quad_glb, quad_json, Scratch};
use serde_json::json;
use std::process::Command;

#[test]
fn shared_geometry_keeps_each_meshes_material() {
    let mut doc = quad_json();
    let colour = |c: [f32; 4]| {
        json!({"doubleSided": true, "pbrMetallicRoughness":
        {"baseColorFactor": c, "metallicFactor": 0.0}})
    };
    doc["materials"] = json!([colour([1.0, 0.0, 0.0, 1.0]), colour([0.0, 1.0, 0.0, 1.0])]);
    let prim = |m: u32| json!({"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": m}]});
    doc["meshes"] = json!([prim(0), prim(1)]);
    doc["cameras"] = json!([{"type": "orthographic",
        "orthographic": {"xmag": 2.2, "ymag": 1.1, "znear": 0.1, "zfar": 100.0}}]);
    doc["nodes"] = json!([
        {"mesh": 0, "translation": [-1.1, 0.0, 0.0]},
        {"mesh": 1, "translation": [1.1, 0.0, 0.0]},
        {"camera": 0, "translation": [0.0, 0.0, 5.0]}
    ]);
    doc["scenes"] = json!([{"nodes": [0, 1, 2]}]);
    let dir = Scratch::new("shared-geometry");
    let scene = dir.path("two.glb");
    std::fs::write(&scene, quad_glb(&doc)).unwrap();
    let out = dir.path("two.exr");
    let status = Command::new(aperture())
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args([
            "--width", "16", "--height", "8", "--spp", "4", "--env", "1,1,1", "--quiet",
        ])
        .status()
        .unwrap();
    assert!(status.success());
    let img = read_exr(&out).unwrap();
    let at = |x: usize, y: usize| img.rgba[y * 16 + x];
    let (left, right) = (at(4, 4), at(12, 4));
    assert!(
        left[0] > 0.3 && left[1] < 0.05,
        "left should be red: {left:?}"
    );
    assert!(
        right[1] > 0.3 && right[0] < 0.05,
        "right should be green: {right:?}"
    );
    let info = Command::new(aperture())
        .arg("info")
        .arg(&scene)
        .output()
        .unwrap();
    let text = String::from_utf8(info.stdout).unwrap();
    assert!(
        text.contains("meshes 1 ") && text.contains("triangles: 2 unique, 4 drawn"),
        "{text}"
    );
}
