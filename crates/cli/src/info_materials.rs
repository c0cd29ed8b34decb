//! `aperture info`'s material interpretation: which meaning of transmission and of
//! single-sided faces applies to the file (and why), and its material variants.

use aperture_scene::Scene;
use aperture_shading::{Convention, SidesModel, TransmissionModel};
use serde_json::{json, Value};

/// A JSON count (0 when missing).
fn count(v: &Value) -> u64 {
    v.as_u64().unwrap_or(0)
}

/// Which meaning of transmission applies, why, and what it makes of the file's meshes.
pub(crate) fn transmission_json(s: &Scene, convention: Convention) -> Value {
    let (model, why) = convention.resolve::<TransmissionModel>(s);
    let (refractive, thin) = aperture_shading::transmissive_meshes(s, model);
    json!({
        "applies": model.to_string(),
        "why": why,
        "refractive_meshes": refractive,
        "thin_walled_meshes": thin,
    })
}

/// Which meaning of single-sided faces applies (`gltf`: their backs are invisible; `blender`:
/// both sides are seen), why, and how many materials are single-sided.
pub(crate) fn sides_json(s: &Scene, convention: Convention) -> Value {
    let (model, why) = convention.resolve::<SidesModel>(s);
    json!({
        "applies": model.to_string(),
        "why": why,
        "materials": aperture_shading::single_sided_materials(s),
    })
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
