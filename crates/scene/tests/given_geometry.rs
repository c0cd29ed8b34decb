//! A mesh given its geometry as arrays (`Edit::MeshGeometry`, what Blender's add-on sends
//! instead of exporting the triangles) loads exactly as a file storing those arrays as the
//! primitive's accessors; given geometry shares with no other mesh; bad edits are errors.

use aperture_scene::{Animated, Edit, Geometry, LoadOptions, Scene};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod common;

/// Little-endian bytes of `values`.
fn le<T: Copy, const N: usize>(values: &[T], bytes: fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| bytes(v)).collect()
}

/// Two glTF meshes over one quad's accessors (materials red and green), one node each; with
/// `stored`, mesh 1 reads that geometry from accessors of its own instead.
fn file(dir: &Path, name: &str, stored: Option<&Geometry>) -> PathBuf {
    let quad = [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0,
    ];
    let mut bin = le(&quad, f32::to_le_bytes);
    bin.extend(le(&[0u32, 1, 2, 0, 2, 3], u32::to_le_bytes));
    let mut views = vec![
        json!({"buffer": 0, "byteLength": 48}),
        json!({"buffer": 0, "byteOffset": 48, "byteLength": 24}),
    ];
    let mut accessors = vec![
        json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
               "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}),
        json!({"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"}),
    ];
    let mut add = |bytes: Vec<u8>, count: usize, ty: &str, component: u32| {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        bin.extend(bytes);
        accessors.push(
            json!({"bufferView": views.len() - 1, "componentType": component,
                              "count": count, "type": ty}),
        );
        accessors.len() - 1
    };
    let mut second = json!({"attributes": {"POSITION": 0}, "indices": 1, "material": 1});
    if let Some(g) = stored {
        let flat = |v: &[[f32; 3]]| le(v.as_flattened(), f32::to_le_bytes);
        let p = add(flat(g.positions()), g.positions().len(), "VEC3", 5126);
        let bound = |f: fn(f32, f32) -> f32| {
            let v = g
                .positions()
                .iter()
                .copied()
                .reduce(|a, b| std::array::from_fn(|k| f(a[k], b[k])));
            v.unwrap().to_vec()
        };
        let (min, max) = (bound(f32::min), bound(f32::max));
        let n = add(
            flat(g.normals().unwrap()),
            g.positions().len(),
            "VEC3",
            5126,
        );
        let uv = g.uvs().unwrap();
        let t = add(
            le(uv.as_flattened(), f32::to_le_bytes),
            uv.len(),
            "VEC2",
            5126,
        );
        let tris = g.triangles().as_flattened();
        let i = add(le(tris, u32::to_le_bytes), tris.len(), "SCALAR", 5125);
        accessors[p]["min"] = json!(min);
        accessors[p]["max"] = json!(max);
        second = json!({"attributes": {"POSITION": p, "NORMAL": n, "TEXCOORD_0": t},
                        "indices": i, "material": 1});
    }
    let first = json!({"attributes": {"POSITION": 0}, "indices": 1, "material": 0});
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
        "materials": [{"name": "red"}, {"name": "green"}],
        "meshes": [{"primitives": [first]}, {"primitives": [second]}],
        "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [2.0, 0.0, 0.0]}],
        "scenes": [{"nodes": [0, 1]}]
    });
    let path = dir.join(name);
    std::fs::write(&path, common::glb::glb(&doc, &bin)).unwrap();
    path
}

fn tetrahedron() -> Geometry {
    let p = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let n = vec![
        [-1.0, -1.0, -1.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 3.0],
    ];
    let uv = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5]];
    Geometry::new(
        p,
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        Some(n),
        Some(uv),
    )
    .unwrap()
}

fn given(mesh: usize, g: Geometry) -> Edit {
    Edit::MeshGeometry {
        mesh,
        primitives: Arc::from(vec![g]),
    }
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("aperture-given-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// What a scene holds of its geometry, for comparing two loads (as text: every bit shows).
fn geometry(s: &Scene) -> String {
    let meshes: Vec<String> = (s.meshes.iter())
        .map(|m| {
            format!(
                "{:?}",
                (
                    &m.positions,
                    &m.normals,
                    &m.uv0,
                    &m.indices,
                    &m.material_ids
                )
            )
        })
        .collect();
    let instances: Vec<String> = (s.instances.iter())
        .map(|i| format!("{:?}", (i.mesh, i.world_from_object)))
        .collect();
    format!("{meshes:?} {instances:?}")
}

#[test]
fn given_geometry_loads_as_a_file_storing_it() {
    let dir = tmp("same");
    let shared = file(&dir, "shared.glb", None);
    let stored = file(&dir, "stored.glb", Some(&tetrahedron()));
    let o = LoadOptions::default();
    let before = Animated::load(&shared, &o).unwrap().scene_at(None).unwrap();
    assert_eq!(before.meshes.len(), 1, "the two meshes share one quad");
    let edited = Animated::load_edited(&shared, &o, &[given(1, tetrahedron())]).unwrap();
    let edited = edited.scene_at(None).unwrap();
    let cold = Animated::load(&stored, &o).unwrap().scene_at(None).unwrap();
    assert_eq!(edited.meshes.len(), 2, "the given mesh shares no more");
    assert_eq!(edited.drawn_triangle_count(), 6);
    assert_eq!(geometry(&edited), geometry(&cold));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn without_normals_the_given_triangles_are_flat() {
    let dir = tmp("flat");
    let shared = file(&dir, "shared.glb", None);
    let t = tetrahedron();
    let g = Geometry::new(t.positions().to_vec(), t.triangles().to_vec(), None, None).unwrap();
    let s = Animated::load_edited(&shared, &LoadOptions::default(), &[given(1, g)]).unwrap();
    let s = s.scene_at(None).unwrap();
    let m = s
        .meshes
        .iter()
        .find(|m| m.indices.len() == 4)
        .expect("the given mesh");
    assert_eq!(
        m.positions.len(),
        12,
        "each flat triangle has its own three vertices"
    );
    for (k, tri) in m.indices.iter().enumerate() {
        let [a, b, c] = tri.map(|i| m.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        let n = m.normals[tri[0] as usize];
        assert!(
            (n - face).length() < 1e-6,
            "triangle {k}: {n} against {face}"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn geometry_for_a_missing_mesh_or_primitive_is_an_error() {
    let dir = tmp("bad");
    let shared = file(&dir, "shared.glb", None);
    let o = LoadOptions::default();
    let two = Edit::MeshGeometry {
        mesh: 1,
        primitives: Arc::from(vec![tetrahedron(), tetrahedron()]),
    };
    for (edit, says) in [
        (given(7, tetrahedron()), "meshes[7]"),
        (two, "the mesh has 1"),
    ] {
        let message = Animated::load_edited(&shared, &o, &[edit])
            .unwrap_err()
            .to_string();
        assert!(message.contains(says), "{message} should say {says}");
    }
    std::fs::remove_dir_all(dir).ok();
}
