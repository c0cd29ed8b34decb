//! Writes small glTF files for tests: meshes (positions, normals, indices) placed by node
//! matrices, materials and cameras given as JSON, one embedded `data:` buffer. The loader then
//! reads them as it reads any user's file.

use aperture_scene::Mesh;
use glam::Mat4;
use serde_json::{json, Value};

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A glTF document being written.
#[derive(Debug, Default)]
pub struct GltfWriter {
    buffer: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    /// Materials (glTF JSON objects), indexed by the meshes' `material_ids` (first triangle).
    pub materials: Vec<Value>,
    /// Cameras (glTF JSON objects).
    pub cameras: Vec<Value>,
    /// `extensionsUsed`.
    pub extensions_used: Vec<String>,
    /// `asset.generator`.
    pub generator: Option<String>,
}

impl GltfWriter {
    /// An empty document whose `asset.generator` is `generator`, declaring `extensions`.
    pub fn new(generator: &str, extensions: &[&str]) -> Self {
        Self {
            generator: Some(generator.into()),
            extensions_used: extensions.iter().map(|e| e.to_string()).collect(),
            ..Self::default()
        }
    }

    fn add(&mut self, data: &[u8], target: u32, component: u32, count: usize, kind: &str) -> usize {
        while self.buffer.len() % 4 != 0 {
            self.buffer.push(0);
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": self.buffer.len(),
            "byteLength": data.len(),
            "target": target,
        }));
        self.buffer.extend_from_slice(data);
        self.accessors.push(json!({
            "bufferView": self.views.len() - 1,
            "componentType": component,
            "count": count,
            "type": kind,
        }));
        self.accessors.len() - 1
    }

    /// Adds `mesh` (positions, normals, indices; its first triangle's material) drawn by a
    /// node with `matrix`, named `name`.
    pub fn mesh(&mut self, name: &str, mesh: &Mesh, matrix: Mat4) {
        let floats = |v: &[glam::Vec3]| -> Vec<u8> {
            v.iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes)
                .collect()
        };
        let p = self.add(
            &floats(&mesh.positions),
            34962,
            5126,
            mesh.positions.len(),
            "VEC3",
        );
        let (lo, hi) = mesh.positions.iter().fold(
            (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY),
            |(lo, hi), q| (lo.min(*q), hi.max(*q)),
        );
        self.accessors[p]["min"] = json!(lo.to_array());
        self.accessors[p]["max"] = json!(hi.to_array());
        let n = self.add(
            &floats(&mesh.normals),
            34962,
            5126,
            mesh.normals.len(),
            "VEC3",
        );
        let idx: Vec<u8> = mesh
            .indices
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let i = self.add(&idx, 34963, 5125, mesh.indices.len() * 3, "SCALAR");
        let material = mesh.material_ids.first().copied().unwrap_or(0);
        self.meshes.push(json!({
            "name": name,
            "primitives": [{"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": material}],
        }));
        self.nodes.push(json!({
            "name": name,
            "mesh": self.meshes.len() - 1,
            "matrix": matrix.to_cols_array(),
        }));
    }

    /// Adds a node carrying camera `camera` with `matrix`.
    pub fn camera_node(&mut self, camera: usize, matrix: Mat4) {
        self.nodes
            .push(json!({"name": "camera", "camera": camera, "matrix": matrix.to_cols_array()}));
    }

    /// The `.gltf` file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut asset = json!({"version": "2.0"});
        if let Some(g) = &self.generator {
            asset["generator"] = json!(g);
        }
        let mut doc = json!({
            "asset": asset,
            "scene": 0,
            "scenes": [{"nodes": (0..self.nodes.len()).collect::<Vec<_>>()}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{
                "byteLength": self.buffer.len(),
                "uri": format!("data:application/octet-stream;base64,{}", base64(&self.buffer)),
            }],
        });
        if !self.cameras.is_empty() {
            doc["cameras"] = json!(self.cameras);
        }
        if !self.extensions_used.is_empty() {
            doc["extensionsUsed"] = json!(self.extensions_used);
        }
        serde_json::to_vec_pretty(&doc).expect("JSON")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_the_rfc_examples() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }
}
