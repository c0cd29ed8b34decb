//! `aperture info --memory` as text: the report's `memory` (which
//! `aperture_render::info::memory` builds), a line per stage.

use aperture_budget::human_bytes;
use serde_json::Value;

/// A byte count of the report, in words ("12.0 MB"; "?" when missing).
fn size(v: &Value) -> String {
    v.as_u64().map_or("?".into(), human_bytes)
}

/// The report's `memory` object, when there is one (`--memory`).
pub fn print_memory(r: &Value) {
    let m = &r["memory"];
    if m.is_null() {
        return;
    }
    println!("  memory:");
    println!("    file {}", size(&m["file_bytes"]));
    let g = &m["meshes"];
    println!(
        "    meshes {}: positions {}, normals {}, tangents {}, uvs {}, colors {}, indices {}, \
         materials {}",
        size(&g["total"]),
        size(&g["positions"]),
        size(&g["normals"]),
        size(&g["tangents"]),
        size(&g["uvs"]),
        size(&g["colors"]),
        size(&g["indices"]),
        size(&g["material_ids"]),
    );
    let t = &m["textures"];
    let env = match t["environment_bytes"].as_u64() {
        Some(b) => format!(", environment {}", human_bytes(b)),
        None => String::new(),
    };
    println!(
        "    textures {}: {} decoded{env}",
        t["count"],
        size(&t["decoded_bytes"])
    );
    let a = &m["accel"];
    if !a.is_null() {
        println!(
            "    BVH {} ({} triangles, {} nodes, built in {:.2} s): {}: nodes {}, triangles {}, \
             instances {}",
            a["quality"].as_str().unwrap_or_default(),
            a["triangles"],
            a["nodes"],
            a["build_secs"].as_f64().unwrap_or(f64::NAN),
            size(&a["total"]),
            size(&a["node_bytes"]),
            size(&a["triangle_bytes"]),
            size(&a["instance_bytes"]),
        );
    }
    if let Some(b) = m["peak_resident_bytes"].as_u64() {
        println!("    peak resident memory of this run: {}", human_bytes(b));
    }
}
