//! The demo's binary buffer, its buffer views and accessors, and the JSON written in sorted
//! key order.

use serde_json::{json, Map, Value};

use super::geometry::Geometry;

/// The binary buffer with its buffer views and accessors.
#[derive(Default)]
pub(super) struct Bin {
    pub(super) data: Vec<u8>,
    pub(super) views: Vec<Value>,
    pub(super) accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": self.data.len(),
            "byteLength": bytes.len(),
            "target": target,
        }));
        self.data.extend_from_slice(bytes);
        self.views.len() - 1
    }

    fn vec3(&mut self, v: &[[f32; 3]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, 34962);
        let mut acc = json!({
            "bufferView": view,
            "componentType": 5126,
            "count": v.len(),
            "type": "VEC3",
        });
        if with_bounds {
            let mut min = [f32::INFINITY; 3];
            let mut max = [f32::NEG_INFINITY; 3];
            for p in v {
                for k in 0..3 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
            // f32 → f64 is exact, and serde_json prints the shortest form that reads back as it.
            acc["min"] = json!(min.map(f64::from));
            acc["max"] = json!(max.map(f64::from));
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Indices as u16 when every index fits, else as u32 (or u32 when `force_u32`).
    fn indices(&mut self, idx: &[u32], force_u32: bool) -> usize {
        let wide = force_u32 || idx.iter().any(|&i| i > u32::from(u16::MAX - 1));
        let (bytes, component): (Vec<u8>, u32) = if wide {
            (idx.iter().flat_map(|i| i.to_le_bytes()).collect(), 5125)
        } else {
            (
                idx.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
                5123,
            )
        };
        let view = self.view(&bytes, 34963);
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": component,
            "count": idx.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    /// Stores a geometry; returns the accessors `(POSITION, NORMAL, indices)`.
    pub(super) fn geometry(&mut self, g: &Geometry, force_u32: bool) -> (usize, usize, usize) {
        (
            self.vec3(&g.positions, true),
            self.vec3(&g.normals, false),
            self.indices(&g.indices, force_u32),
        )
    }
}

/// A triangle primitive of the accessors `(POSITION, NORMAL, indices)` and `material`.
pub(super) fn primitive(acc: (usize, usize, usize), material: usize) -> Value {
    json!({
        "attributes": { "POSITION": acc.0, "NORMAL": acc.1 },
        "indices": acc.2,
        "material": material,
        "mode": 4,
    })
}

/// Rebuilds every object with its keys inserted in sorted order, so the output is the same
/// whether `serde_json::Map` is a `BTreeMap` or (feature `preserve_order`) an `IndexMap`.
pub(super) fn sorted(v: Value) -> Value {
    match v {
        Value::Object(map) => {
            let mut entries: Vec<(String, Value)> = map.into_iter().collect();
            entries.sort_by(|a, b| a.0.cmp(&b.0));
            let mut out = Map::new();
            for (k, v) in entries {
                out.insert(k, sorted(v));
            }
            Value::Object(out)
        }
        Value::Array(items) => Value::Array(items.into_iter().map(sorted).collect()),
        other => other,
    }
}
