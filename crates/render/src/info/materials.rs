//! The report's material interpretation: which meaning of transmission and of
//! single-sided faces applies to the file (and why), and its material variants.

use aperture_scene::Scene;
use aperture_shading::{Convention, SidesModel, TransmissionModel};
use serde_json::{json, Value};

/// Which meaning of transmission applies, why, and what it makes of the file's meshes.
pub fn transmission_json(s: &Scene, convention: Convention) -> Value {
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
pub fn sides_json(s: &Scene, convention: Convention) -> Value {
    let (model, why) = convention.resolve::<SidesModel>(s);
    json!({
        "applies": model.to_string(),
        "why": why,
        "materials": aperture_shading::single_sided_materials(s),
    })
}
