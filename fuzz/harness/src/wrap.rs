//! Compressed streams wrapped in the smallest glTF file that makes the loader decode them, so
//! the fuzzer mutates the stream (and a few header bytes), not JSON it would mostly break.

use serde_json::{json, Value};

/// A GLB file of `json` and a BIN chunk.
pub fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_string().into_bytes();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b);
    }
    out
}

/// Header of a Draco fuzz input: points (u16), triangles (u16), then the Draco attribute ids
/// of POSITION, NORMAL and TEXCOORD_0 (255: absent), then the stream.
const DRACO_HEADER: usize = 7;

/// The fuzz input for a Draco stream with these counts and attribute ids (for seeds).
pub fn draco_input(points: u16, triangles: u16, ids: [Option<u8>; 3], stream: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(DRACO_HEADER + stream.len());
    out.extend_from_slice(&points.to_le_bytes());
    out.extend_from_slice(&triangles.to_le_bytes());
    out.extend(ids.map(|i| i.unwrap_or(255)));
    out.extend_from_slice(stream);
    out
}

/// A GLB whose one primitive is the Draco stream of `data` (see [`draco_input`]).
pub fn draco(data: &[u8]) -> Option<Vec<u8>> {
    let head = data.get(..DRACO_HEADER)?;
    let stream = &data[DRACO_HEADER..];
    let points = u16::from_le_bytes([head[0], head[1]]);
    let triangles = u16::from_le_bytes([head[2], head[3]]);
    let mut attributes = serde_json::Map::new();
    let mut ids = serde_json::Map::new();
    let mut accessors =
        vec![json!({"componentType": 5125, "count": u32::from(triangles) * 3, "type": "SCALAR"})];
    for ((name, ty), &id) in [
        ("POSITION", "VEC3"),
        ("NORMAL", "VEC3"),
        ("TEXCOORD_0", "VEC2"),
    ]
    .iter()
    .zip(&head[4..7])
    {
        if id == 255 {
            continue;
        }
        let mut acc = json!({"componentType": 5126, "count": points, "type": ty});
        if *name == "POSITION" {
            acc["min"] = json!([-1e3, -1e3, -1e3]);
            acc["max"] = json!([1e3, 1e3, 1e3]);
        }
        attributes.insert((*name).into(), json!(accessors.len()));
        ids.insert((*name).into(), json!(id));
        accessors.push(acc);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{
            "attributes": attributes,
            "indices": 0,
            "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": ids}}
        }]}],
        "accessors": accessors,
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": stream.len()}],
        "buffers": [{"byteLength": stream.len()}]
    });
    Some(glb(&doc, stream))
}

/// The `mode` of an `EXT_meshopt_compression` view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshoptMode {
    /// Vertex attributes (with an optional filter).
    Attributes,
    /// Triangle indices.
    Triangles,
    /// Index sequences.
    Indices,
}

const FILTERS: [&str; 5] = ["NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL", "COLOR"];

/// Header of a meshopt fuzz input: mode (low 2 bits) and filter (bits 2-4), byteStride (u8),
/// count (u16), then the compressed bytes.
const MESHOPT_HEADER: usize = 4;

/// The fuzz input for a compressed view (for seeds); `filter` indexes
/// `NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL, COLOR`.
pub fn meshopt_input(
    mode: MeshoptMode,
    filter: u8,
    stride: u8,
    count: u16,
    bytes: &[u8],
) -> Vec<u8> {
    let m = match mode {
        MeshoptMode::Attributes => 0,
        MeshoptMode::Triangles => 1,
        MeshoptMode::Indices => 2,
    };
    let mut out = vec![m | (filter << 2), stride];
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(bytes);
    out
}

/// A GLB with one `EXT_meshopt_compression` view over `data` (see [`meshopt_input`]); the
/// loader decodes every compressed view as it reads the buffers.
pub fn meshopt(data: &[u8]) -> Option<Vec<u8>> {
    let head = data.get(..MESHOPT_HEADER)?;
    let bytes = &data[MESHOPT_HEADER..];
    let mode = ["ATTRIBUTES", "TRIANGLES", "INDICES", "ATTRIBUTES"][usize::from(head[0] & 3)];
    let filter = FILTERS[usize::from(head[0] >> 2) % FILTERS.len()];
    let stride = u64::from(head[1]);
    let count = u64::from(u16::from_le_bytes([head[2], head[3]]));
    let length = stride * count;
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "extensionsRequired": ["EXT_meshopt_compression"],
        "buffers": [
            {"byteLength": bytes.len()},
            {"byteLength": length, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": [{"buffer": 1, "byteLength": length, "byteStride": stride.max(4),
            "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": 0, "byteLength": bytes.len(),
                "byteStride": stride, "count": count, "mode": mode, "filter": filter
            }}}]
    });
    Some(glb(&doc, bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapped_streams_are_well_formed_glb() {
        let g = draco(&draco_input(3, 1, [Some(0), None, None], b"DRACO")).unwrap();
        assert!(g.starts_with(b"glTF"));
        assert_eq!(
            u32::from_le_bytes(g[8..12].try_into().unwrap()) as usize,
            g.len()
        );
        let e = aperture_scene::load_bytes(
            &g,
            std::path::Path::new("."),
            &aperture_scene::LoadOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");
        assert!(draco(&[1, 2]).is_none());
        let m = meshopt(&meshopt_input(MeshoptMode::Attributes, 0, 12, 3, b"xyz")).unwrap();
        let e = aperture_scene::load_bytes(
            &m,
            std::path::Path::new("."),
            &aperture_scene::LoadOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("EXT_meshopt_compression"), "{e}");
    }
}
