//! `aperture info --memory` (issue 59): the bytes of each stage, checked on the demo scene
//! against sizes computed here from the file's own accessors.

mod common;

use common::{aperture, demo_scene};
use serde_json::Value;
use std::collections::BTreeSet;
use std::process::Command;

/// The JSON chunk of a GLB.
fn glb_json(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The meshes the default scene draws (each once, however many nodes draw it).
fn drawn_meshes(doc: &Value) -> BTreeSet<u64> {
    let scene = doc["scene"].as_u64().unwrap_or(0) as usize;
    let mut todo: Vec<u64> = (doc["scenes"][scene]["nodes"].as_array().unwrap().iter())
        .filter_map(Value::as_u64)
        .collect();
    let mut meshes = BTreeSet::new();
    while let Some(n) = todo.pop() {
        let node = &doc["nodes"][n as usize];
        meshes.extend(node["mesh"].as_u64());
        for c in node["children"].as_array().into_iter().flatten() {
            todo.extend(c.as_u64());
        }
    }
    meshes
}

/// The elements of the drawn meshes' accessors under `key` (an attribute such as
/// `POSITION`, or `"indices"`): each accessor counted once when `shared` (the scene stores
/// meshes whose primitives share their geometry accessors once, with other materials), per
/// primitive drawn otherwise.
fn counts(doc: &Value, key: &str, shared: bool) -> u64 {
    let accessor = |p: &Value| match key {
        "indices" => p["indices"].as_u64().unwrap(),
        attr => p["attributes"][attr].as_u64().unwrap(),
    };
    let used: Vec<u64> = drawn_meshes(doc)
        .iter()
        .flat_map(|&m| doc["meshes"][m as usize]["primitives"].as_array().unwrap())
        .map(accessor)
        .collect();
    let unique: BTreeSet<u64> = used.iter().copied().collect();
    let count = |a: &u64| doc["accessors"][*a as usize]["count"].as_u64().unwrap();
    match shared {
        true => unique.iter().map(count).sum(),
        false => used.iter().map(count).sum(),
    }
}

fn info(args: &[&str]) -> Value {
    let run = Command::new(aperture())
        .arg("info")
        .arg(demo_scene())
        .args(args)
        .output()
        .expect("aperture runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&run.stdout).expect("JSON")
}

#[test]
fn memory_reports_the_files_meshes_and_bvh_bytes() {
    let bytes = std::fs::read(demo_scene()).unwrap();
    let doc = glb_json(&bytes);
    let r = info(&["--json", "--memory"]);
    let m = &r["memory"];
    assert_eq!(m["file_bytes"], bytes.len() as u64);
    let g = &m["meshes"];
    let vertices = counts(&doc, "POSITION", true);
    let (corners, drawn_corners) = (
        counts(&doc, "indices", true),
        counts(&doc, "indices", false),
    );
    assert_eq!(vertices, counts(&doc, "NORMAL", true));
    // Vec3 positions and normals and [u32; 3] triangles, stored once; a u32 material for
    // each triangle of each glTF mesh drawn (a shared geometry's other materials as a set).
    let materials = 4 * drawn_corners / 3;
    assert_eq!(g["positions"], 12 * vertices, "{g}");
    assert_eq!(g["normals"], 12 * vertices, "{g}");
    assert_eq!(g["indices"], 4 * corners, "{g}");
    assert_eq!(g["material_ids"], materials, "{g}");
    assert_eq!(g["uvs"], 0);
    assert_eq!(g["total"], 24 * vertices + 4 * corners + materials);
    assert_eq!(m["textures"]["count"], 0);
    assert_eq!(m["textures"]["decoded_bytes"], 0);

    let a = &m["accel"];
    let part = |k: &str| a[k].as_u64().unwrap();
    assert_eq!(a["quality"], "medium");
    assert_eq!(a["triangles"], r["triangles"]["unique"]);
    // Every kept triangle's three points (f32) at least, and some nodes.
    assert!(part("triangle_bytes") >= 36 * part("triangles"), "{a}");
    assert!(part("node_bytes") > 0 && part("nodes") > 0, "{a}");
    let sum = part("node_bytes") + part("triangle_bytes") + part("instance_bytes");
    assert_eq!(part("total"), sum, "{a}");
    if cfg!(target_os = "linux") {
        // The process held at least the scene's meshes and its BVH.
        let peak = m["peak_resident_bytes"].as_u64().unwrap();
        assert!(peak >= sum + g["total"].as_u64().unwrap(), "{m}");
    }
}

#[test]
fn info_without_memory_has_no_memory_report() {
    let r = info(&["--json"]);
    assert!(r.get("memory").is_none(), "{r}");
    assert!(r["triangles"]["unique"].as_u64().unwrap() > 0);
}
