//! `aperture info`'s material interpretation as text (the report's `transmission`,
//! `single_sided` and `variants`, which `aperture_render::info::materials` builds).

use serde_json::Value;

/// A JSON count (0 when missing).
fn count(v: &Value) -> u64 {
    v.as_u64().unwrap_or(0)
}

/// Which transmission and which meaning of single-sided faces apply, and the material
/// variants.
pub(crate) fn print_materials(r: &Value) {
    let tr = &r["transmission"];
    println!(
        "  transmission: {} ({}); {} refractive and {} thin-walled transmissive mesh(es)",
        tr["applies"].as_str().unwrap_or_default(),
        tr["why"].as_str().unwrap_or_default(),
        count(&tr["refractive_meshes"]),
        count(&tr["thin_walled_meshes"]),
    );
    let sides = &r["single_sided"];
    println!(
        "  single-sided faces: {} ({}); {} single-sided material(s), their backs {}",
        sides["applies"].as_str().unwrap_or_default(),
        sides["why"].as_str().unwrap_or_default(),
        count(&sides["materials"]),
        if sides["applies"] == "gltf" {
            "invisible to every ray"
        } else {
            "shaded like their fronts"
        }
    );
    let variants = r["variants"].as_array().cloned().unwrap_or_default();
    if !variants.is_empty() {
        println!(
            "  material variants: {} (drawing {})",
            variants
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            r["variant"]
                .as_str()
                .map_or("the default materials".into(), |v| format!("{v:?}"))
        );
    }
}
