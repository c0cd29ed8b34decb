//! `KHR_animation_pointer` targets aperture animates (SPEC §7): node TRS and weights, mesh
//! weights, camera `yfov`/`znear`/`zfar`/`xmag`/`ymag`, light colour/intensity/cone angles/range,
//! material factors and texture transforms, and the numeric depth-of-field keys of SPEC §3 at
//! `/cameras/{i}/extras/<key>`, and `KHR_node_visibility`'s `visible` flag. Anything else is
//! ignored (the loader warns once, naming them).

use glam::{Vec2, Vec3, Vec4};
use serde_json::Value;

use crate::types::material::{AlphaMode, Material};
use crate::types::texture_ref::{TextureRef, TextureTransform};

/// A parsed pointer.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Pointer {
    /// `/nodes/{i}/translation|rotation|scale|weights`.
    Node(usize, NodeProperty),
    /// `/nodes/{i}/extensions/KHR_node_visibility/visible`: a bool, keyed as unsigned bytes
    /// (0 is false, anything else true) with STEP interpolation (`KHR_animation_pointer`).
    NodeVisible(usize),
    /// `/meshes/{i}/weights`: the default weights of every node drawing the mesh without its own.
    MeshWeights(usize),
    /// `/cameras/{i}/perspective/...` or `/orthographic/...`.
    Camera(usize, CameraProperty),
    /// `/cameras/{i}/extras/<key>`: a depth-of-field key of SPEC §3.
    CameraExtra(usize, &'static str),
    /// `/extensions/KHR_lights_punctual/lights/{i}/...`.
    Light(usize, LightProperty),
    /// `/materials/{i}/...`.
    Material(usize, MaterialProperty),
}

/// The animatable properties of a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NodeProperty {
    Translation,
    Rotation,
    Scale,
    Weights,
}

/// Animatable camera values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CameraProperty {
    Yfov,
    /// Near and far planes: aperture has none, so they animate nothing visible.
    Clip,
    Xmag,
    Ymag,
}

/// Animatable light values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LightProperty {
    Color,
    Intensity,
    InnerCone,
    OuterCone,
    /// Ignored by the renderer, as by Blender (SPEC §4).
    Range,
}

/// Animatable material values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MaterialProperty {
    BaseColorFactor,
    MetallicFactor,
    RoughnessFactor,
    EmissiveFactor,
    AlphaCutoff,
    NormalScale,
    OcclusionStrength,
    EmissiveStrength,
    Ior,
    SpecularFactor,
    SpecularColorFactor,
    TextureTransform(TextureSlot, TransformField),
}

/// The texture references of a material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TextureSlot {
    BaseColor,
    MetallicRoughness,
    Normal,
    Occlusion,
    Emissive,
    Specular,
    SpecularColor,
}

/// The animatable values of `KHR_texture_transform`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TransformField {
    Offset,
    Rotation,
    Scale,
}

/// SPEC §3's numeric keys: what `/cameras/{i}/extras/<key>` may animate.
pub(crate) const DOF_KEYS: &[&str] = &[
    "focus_distance",
    "aperture_fstop",
    "aperture_radius",
    "lens",
    "sensor_width",
    "sensor_height",
    "aperture_blades",
    "aperture_rotation",
    "aperture_ratio",
];

impl Pointer {
    /// Floats per value (`None`: as many as the file gives, for weights).
    pub fn width(&self) -> Option<usize> {
        use MaterialProperty as M;
        Some(match self {
            Pointer::Node(_, NodeProperty::Translation | NodeProperty::Scale) => 3,
            Pointer::Node(_, NodeProperty::Rotation) => 4,
            Pointer::Node(_, NodeProperty::Weights) | Pointer::MeshWeights(_) => return None,
            Pointer::Camera(..) | Pointer::CameraExtra(..) | Pointer::NodeVisible(_) => 1,
            Pointer::Light(_, LightProperty::Color) => 3,
            Pointer::Light(..) => 1,
            Pointer::Material(_, p) => match p {
                M::BaseColorFactor => 4,
                M::EmissiveFactor | M::SpecularColorFactor => 3,
                M::TextureTransform(_, TransformField::Offset | TransformField::Scale) => 2,
                _ => 1,
            },
        })
    }
}

fn count(root: &Value, key: &str) -> usize {
    root.get(key).and_then(Value::as_array).map_or(0, Vec::len)
}

fn slot(name: &str) -> Option<TextureSlot> {
    Some(match name {
        "baseColorTexture" => TextureSlot::BaseColor,
        "metallicRoughnessTexture" => TextureSlot::MetallicRoughness,
        "normalTexture" => TextureSlot::Normal,
        "occlusionTexture" => TextureSlot::Occlusion,
        "emissiveTexture" => TextureSlot::Emissive,
        "specularTexture" => TextureSlot::Specular,
        "specularColorTexture" => TextureSlot::SpecularColor,
        _ => return None,
    })
}

fn transform_field(name: &str) -> Option<TransformField> {
    Some(match name {
        "offset" => TransformField::Offset,
        "rotation" => TransformField::Rotation,
        "scale" => TransformField::Scale,
        _ => return None,
    })
}

/// The material property at the path after `/materials/{i}/`.
fn material_property(rest: &[&str]) -> Option<MaterialProperty> {
    use MaterialProperty as M;
    const TT: &str = "KHR_texture_transform";
    Some(match rest {
        ["pbrMetallicRoughness", "baseColorFactor"] => M::BaseColorFactor,
        ["pbrMetallicRoughness", "metallicFactor"] => M::MetallicFactor,
        ["pbrMetallicRoughness", "roughnessFactor"] => M::RoughnessFactor,
        ["emissiveFactor"] => M::EmissiveFactor,
        ["alphaCutoff"] => M::AlphaCutoff,
        ["normalTexture", "scale"] => M::NormalScale,
        ["occlusionTexture", "strength"] => M::OcclusionStrength,
        ["extensions", "KHR_materials_emissive_strength", "emissiveStrength"] => {
            M::EmissiveStrength
        }
        ["extensions", "KHR_materials_ior", "ior"] => M::Ior,
        ["extensions", "KHR_materials_specular", "specularFactor"] => M::SpecularFactor,
        ["extensions", "KHR_materials_specular", "specularColorFactor"] => M::SpecularColorFactor,
        ["pbrMetallicRoughness", tex, "extensions", ext, field] if *ext == TT => {
            M::TextureTransform(slot(tex)?, transform_field(field)?)
        }
        [tex, "extensions", ext, field] if *ext == TT => {
            M::TextureTransform(slot(tex)?, transform_field(field)?)
        }
        ["extensions", "KHR_materials_specular", tex, "extensions", ext, field] if *ext == TT => {
            M::TextureTransform(slot(tex)?, transform_field(field)?)
        }
        _ => return None,
    })
}

/// Parses a JSON pointer; `None` for anything aperture does not animate or an index the file
/// does not have.
pub(crate) fn parse(pointer: &str, root: &Value) -> Option<Pointer> {
    let parts: Vec<&str> = pointer.strip_prefix('/')?.split('/').collect();
    let index = |s: &str, key: &str| -> Option<usize> {
        let i: usize = s.parse().ok()?;
        (i < count(root, key)).then_some(i)
    };
    let lights = root
        .get("extensions")
        .and_then(|e| e.get("KHR_lights_punctual"))
        .and_then(|e| e.get("lights"))
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    Some(match parts.as_slice() {
        ["nodes", i, prop] => Pointer::Node(
            index(i, "nodes")?,
            match *prop {
                "translation" => NodeProperty::Translation,
                "rotation" => NodeProperty::Rotation,
                "scale" => NodeProperty::Scale,
                "weights" => NodeProperty::Weights,
                _ => return None,
            },
        ),
        ["nodes", i, "extensions", "KHR_node_visibility", "visible"] => {
            Pointer::NodeVisible(index(i, "nodes")?)
        }
        ["meshes", i, "weights"] => Pointer::MeshWeights(index(i, "meshes")?),
        ["cameras", i, "extras", key] => {
            Pointer::CameraExtra(index(i, "cameras")?, DOF_KEYS.iter().find(|k| *k == key)?)
        }
        ["cameras", i, kind, prop] => Pointer::Camera(
            index(i, "cameras")?,
            match (*kind, *prop) {
                ("perspective", "yfov") => CameraProperty::Yfov,
                ("perspective" | "orthographic", "znear" | "zfar") => CameraProperty::Clip,
                ("orthographic", "xmag") => CameraProperty::Xmag,
                ("orthographic", "ymag") => CameraProperty::Ymag,
                _ => return None,
            },
        ),
        ["extensions", "KHR_lights_punctual", "lights", i, rest @ ..] => {
            let i: usize = i.parse().ok()?;
            if i >= lights {
                return None;
            }
            Pointer::Light(
                i,
                match rest {
                    ["color"] => LightProperty::Color,
                    ["intensity"] => LightProperty::Intensity,
                    ["range"] => LightProperty::Range,
                    ["spot", "innerConeAngle"] => LightProperty::InnerCone,
                    ["spot", "outerConeAngle"] => LightProperty::OuterCone,
                    _ => return None,
                },
            )
        }
        ["materials", i, rest @ ..] => {
            Pointer::Material(index(i, "materials")?, material_property(rest)?)
        }
        _ => return None,
    })
}

/// Sets a material value from an animation sample.
pub(crate) fn apply_material(m: &mut Material, property: MaterialProperty, v: &[f64]) {
    use MaterialProperty as M;
    let f = |i: usize| v.get(i).copied().unwrap_or(0.0) as f32;
    match property {
        M::BaseColorFactor => m.base_color_factor = Vec4::new(f(0), f(1), f(2), f(3)),
        M::MetallicFactor => m.metallic_factor = f(0),
        M::RoughnessFactor => m.roughness_factor = f(0),
        M::EmissiveFactor => m.emissive_factor = Vec3::new(f(0), f(1), f(2)),
        M::AlphaCutoff => {
            if let AlphaMode::Mask { cutoff } = &mut m.alpha_mode {
                *cutoff = f(0);
            }
        }
        M::NormalScale => m.normal_scale = f(0),
        M::OcclusionStrength => m.occlusion_strength = f(0),
        M::EmissiveStrength => m.emissive_strength = f(0),
        M::Ior => m.ior = f(0),
        M::SpecularFactor => m.specular_factor = f(0),
        M::SpecularColorFactor => m.specular_color_factor = Vec3::new(f(0), f(1), f(2)),
        M::TextureTransform(slot, field) => {
            let reference: Option<&mut TextureRef> = match slot {
                TextureSlot::BaseColor => m.base_color_texture.as_mut(),
                TextureSlot::MetallicRoughness => m.metallic_roughness_texture.as_mut(),
                TextureSlot::Normal => m.normal_texture.as_mut(),
                TextureSlot::Occlusion => m.occlusion_texture.as_mut(),
                TextureSlot::Emissive => m.emissive_texture.as_mut(),
                TextureSlot::Specular => m.specular_texture.as_mut(),
                TextureSlot::SpecularColor => m.specular_color_texture.as_mut(),
            };
            // A material without the texture has nothing to transform.
            if let Some(r) = reference {
                let t = r.transform.get_or_insert_with(TextureTransform::default);
                match field {
                    TransformField::Offset => t.offset = Vec2::new(f(0), f(1)),
                    TransformField::Rotation => t.rotation = f(0),
                    TransformField::Scale => t.scale = Vec2::new(f(0), f(1)),
                }
            }
        }
    }
}

/// Sets a depth-of-field key in a camera's `extras` (creating the object if needed).
pub(crate) fn apply_camera_extra(extras: &mut Option<Value>, key: &str, v: f64) {
    let value = if key == "aperture_blades" {
        // An integer key: a keyed blade count steps between whole numbers.
        Value::from(v.round().max(0.0) as u64)
    } else {
        serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
    };
    match extras {
        Some(Value::Object(map)) => {
            map.insert(key.to_owned(), value);
        }
        _ => {
            let mut map = serde_json::Map::new();
            map.insert(key.to_owned(), value);
            *extras = Some(Value::Object(map));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn pointers_parse_into_what_they_animate() {
        let root = json!({"nodes": [{}], "cameras": [{}], "materials": [{}], "meshes": [{}],
            "extensions": {"KHR_lights_punctual": {"lights": [{}]}}});
        let p = |s: &str| parse(s, &root);
        assert_eq!(
            p("/nodes/0/rotation"),
            Some(Pointer::Node(0, NodeProperty::Rotation))
        );
        assert_eq!(p("/nodes/1/rotation"), None);
        assert_eq!(
            p("/cameras/0/extras/focus_distance"),
            Some(Pointer::CameraExtra(0, "focus_distance"))
        );
        assert_eq!(p("/cameras/0/extras/use_dof"), None);
        assert_eq!(
            p("/cameras/0/perspective/yfov"),
            Some(Pointer::Camera(0, CameraProperty::Yfov))
        );
        assert_eq!(
            p("/extensions/KHR_lights_punctual/lights/0/spot/outerConeAngle"),
            Some(Pointer::Light(0, LightProperty::OuterCone))
        );
        assert_eq!(
            p("/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/offset"),
            Some(Pointer::Material(
                0,
                MaterialProperty::TextureTransform(TextureSlot::BaseColor, TransformField::Offset)
            ))
        );
        assert_eq!(
            p("/materials/0/extensions/KHR_materials_transmission/transmissionFactor"),
            None
        );
        assert_eq!(p("/meshes/0/weights"), Some(Pointer::MeshWeights(0)));
        assert_eq!(
            p("/nodes/0/extensions/KHR_node_visibility/visible"),
            Some(Pointer::NodeVisible(0))
        );
        assert_eq!(p("/nodes/1/extensions/KHR_node_visibility/visible"), None);
        assert_eq!(p("nodes/0/rotation"), None);
    }

    #[test]
    fn material_and_extras_values_are_set() {
        let mut m = Material::default();
        apply_material(
            &mut m,
            MaterialProperty::BaseColorFactor,
            &[0.5, 0.25, 1.0, 1.0],
        );
        assert_eq!(m.base_color_factor, Vec4::new(0.5, 0.25, 1.0, 1.0));
        let mut extras = None;
        apply_camera_extra(&mut extras, "focus_distance", 2.5);
        apply_camera_extra(&mut extras, "aperture_blades", 5.6);
        assert_eq!(
            extras,
            Some(json!({"focus_distance": 2.5, "aperture_blades": 6}))
        );
    }
}
