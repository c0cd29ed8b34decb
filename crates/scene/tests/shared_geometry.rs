//! glTF meshes whose primitives share their geometry accessors are stored once, whatever their
//! materials (issue 50): one `Mesh` (so one BVH), its triangles counted once, each instance
//! drawing it with its own mesh's materials.

use aperture_scene::{load, load_bytes, LoadOptions};
use serde_json::{json, Value};
use std::path::Path;

mod common;

/// One quad's accessors drawn by four glTF meshes: materials 0, 1, 2 and 0 again, one node each.
fn file(extra_mesh: Option<Value>) -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0,
    ] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let prim = |m: u32| json!({"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": m}]});
    let mut meshes = vec![prim(0), prim(1), prim(2), prim(0)];
    meshes.extend(extra_mesh);
    let nodes: Vec<Value> = (0..meshes.len())
        .map(|m| json!({"mesh": m, "translation": [2.0 * m as f32, 0.0, 0.0]}))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 60}],
        "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "materials": [{"name": "red"}, {"name": "green"}, {"name": "blue"}],
        "meshes": meshes,
        "nodes": nodes,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}]
    });
    common::glb::glb(&doc, &bin)
}

#[test]
fn meshes_sharing_accessors_are_stored_once() {
    let s = load_bytes(&file(None), Path::new("."), &LoadOptions::default()).unwrap();
    assert_eq!(s.meshes.len(), 1, "one mesh for four glTF meshes");
    assert_eq!(s.unique_triangle_count(), 2);
    assert_eq!(s.drawn_triangle_count(), 8);
    assert_eq!(s.stats.primitives, 4);
    let names: Vec<&str> = s
        .instances
        .iter()
        .map(|i| {
            let id = s.instance_materials(i)[0];
            s.materials[id as usize].name.as_deref().unwrap_or("")
        })
        .collect();
    assert_eq!(names, ["red", "green", "blue", "red"]);
    // The same materials as the mesh's own need no set; two other materials, two sets.
    assert_eq!(s.instances[0].materials, 0);
    assert_eq!(s.instances[3].materials, 0);
    assert_eq!(s.material_sets.len(), 2);
    assert!(s.material_sets.iter().all(|set| set.len() == 2));
}

#[test]
fn morphed_meshes_keep_their_own_geometry() {
    // A fifth mesh over the same accessors with a morph target deforms on its own.
    let morphed = json!({"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
        "material": 1, "targets": [{"POSITION": 0}]}], "weights": [0.5]});
    let s = load_bytes(
        &file(Some(morphed)),
        Path::new("."),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.unique_triangle_count(), 4);
}

/// The Khronos file the issue measured: 102 meshes over the same sphere accessors.
#[test]
fn metal_rough_spheres_count_their_triangles_once() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let path = dir.join("correctness/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb");
    let s = load(&path, &LoadOptions::default()).unwrap();
    // Before: 102 meshes, 1,040,409 unique triangles (each sphere stored per material).
    assert_eq!(s.drawn_triangle_count(), 1_040_409);
    assert!(s.meshes.len() <= 5, "{} meshes", s.meshes.len());
    assert!(
        s.unique_triangle_count() < 20_000,
        "{}",
        s.unique_triangle_count()
    );
    let bytes: usize = s.meshes.iter().map(|m| m.positions.len() * 12).sum();
    assert!(bytes < 1 << 20, "{bytes} bytes of positions");
}
