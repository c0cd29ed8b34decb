//! The valid base every damaged input is made from: a one-triangle scene, and where the files go.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use aperture_scene::LoadOptions;
use serde_json::{json, Value};

/// A valid one-triangle scene: 3 float positions (36 bytes) then 3 u16 indices (6 bytes + 2 pad).
pub fn triangle_bin() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            b.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    b.extend([0, 0]);
    b
}

/// The triangle scene's JSON, its buffer at `uri` (`None`: the GLB's own BIN chunk).
pub fn triangle_json(uri: Option<&str>) -> Value {
    let mut buffer = json!({"byteLength": 44});
    if let Some(u) = uri {
        buffer["uri"] = json!(u);
    }
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "buffers": [buffer]
    })
}

/// Where the damaged files are written.
pub fn folder() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("damaged-inputs")
}

/// Loads bytes as a GLB or glTF from memory; true when it panicked.
pub fn panics(bytes: &[u8], dir: &Path) -> bool {
    catch_unwind(AssertUnwindSafe(|| {
        let _ = aperture_scene::load_bytes(bytes, dir, &LoadOptions::default());
    }))
    .is_err()
}
