//! The material extensions the `gltf` crate does not type (transmission, volume, clear coat,
//! sheen, anisotropy, iridescence, dispersion, diffuse transmission, specular-glossiness), read
//! from the material's extension JSON. Values of the wrong type or out of range fall back to
//! the extension's default, as a viewer that could not read them would render; texture
//! references to textures that do not exist are dropped.

use glam::{Vec3, Vec4};
use serde_json::Value;

use crate::material::Materials;
use crate::pbr::{
    Anisotropy, Clearcoat, DiffuseTransmission, Iridescence, Sheen, SpecularGlossiness,
    Transmission, Volume,
};
use crate::types::{Material, TextureRef};

/// A finite number at `key`, else `default`.
fn num(v: &Value, key: &str, default: f32) -> f32 {
    v.get(key)
        .and_then(Value::as_f64)
        .map(|x| x as f32)
        .filter(|x| x.is_finite())
        .unwrap_or(default)
}

/// A finite number ≥ 0 at `key`, else `default`.
fn non_negative(v: &Value, key: &str, default: f32) -> f32 {
    Some(num(v, key, default))
        .filter(|x| *x >= 0.0)
        .unwrap_or(default)
}

/// A number in [0, 1] at `key`, else `default`.
fn unit(v: &Value, key: &str, default: f32) -> f32 {
    num(v, key, default).clamp(0.0, 1.0)
}

/// An array of `N` finite numbers at `key`, else `default`.
fn array<const N: usize>(v: &Value, key: &str, default: [f32; N]) -> [f32; N] {
    let Some(a) = v.get(key).and_then(Value::as_array) else {
        return default;
    };
    if a.len() != N {
        return default;
    }
    let mut out = default;
    for (o, x) in out.iter_mut().zip(a) {
        match x.as_f64().map(|x| x as f32).filter(|x| x.is_finite()) {
            Some(x) => *o = x,
            None => return default,
        }
    }
    out
}

fn colour(v: &Value, key: &str, default: Vec3) -> Vec3 {
    Vec3::from(array(v, key, default.to_array())).max(Vec3::ZERO)
}

impl Materials {
    /// A `textureInfo` JSON object (index, texCoord, `KHR_texture_transform`) as a reference.
    fn texture_json(
        &mut self,
        doc: &gltf::Document,
        v: &Value,
        key: &str,
        srgb: bool,
    ) -> Option<TextureRef> {
        let info = v.get(key)?;
        let index = usize::try_from(info.get("index")?.as_u64()?).ok()?;
        let tex = doc.textures().nth(index)?;
        let tex_coord = info
            .get("texCoord")
            .and_then(Value::as_u64)
            .and_then(|t| u32::try_from(t).ok())
            .unwrap_or(0);
        Some(
            self.linear_or_srgb(
                tex,
                tex_coord,
                info.get("extensions")
                    .and_then(|e| e.get("KHR_texture_transform")),
                srgb,
            ),
        )
    }

    /// Fills the extension fields of `out` from the material's extension objects.
    pub(crate) fn read_extensions(
        &mut self,
        doc: &gltf::Document,
        m: &gltf::Material<'_>,
        out: &mut Material,
    ) {
        let Some(ext) = m.extensions() else { return };
        if let Some(v) = ext.get("KHR_materials_transmission") {
            out.transmission = Some(Transmission {
                factor: unit(v, "transmissionFactor", 0.0),
                texture: self.texture_json(doc, v, "transmissionTexture", false),
            });
        }
        if let Some(v) = ext.get("KHR_materials_volume") {
            out.volume = Some(self.volume(doc, v));
        }
        if let Some(v) = ext.get("KHR_materials_clearcoat") {
            out.clearcoat = Some(self.clearcoat(doc, v));
        }
        if let Some(v) = ext.get("KHR_materials_sheen") {
            out.sheen = Some(Sheen {
                color_factor: colour(v, "sheenColorFactor", Vec3::ZERO),
                color_texture: self.texture_json(doc, v, "sheenColorTexture", true),
                roughness_factor: unit(v, "sheenRoughnessFactor", 0.0),
                roughness_texture: self.texture_json(doc, v, "sheenRoughnessTexture", false),
            });
        }
        if let Some(v) = ext.get("KHR_materials_anisotropy") {
            out.anisotropy = Some(Anisotropy {
                strength: unit(v, "anisotropyStrength", 0.0),
                rotation: num(v, "anisotropyRotation", 0.0),
                texture: self.texture_json(doc, v, "anisotropyTexture", false),
            });
        }
        if let Some(v) = ext.get("KHR_materials_iridescence") {
            out.iridescence = Some(self.iridescence(doc, v));
        }
        if let Some(v) = ext.get("KHR_materials_dispersion") {
            out.dispersion = non_negative(v, "dispersion", 0.0);
        }
        if let Some(v) = ext.get("KHR_materials_diffuse_transmission") {
            out.diffuse_transmission = Some(DiffuseTransmission {
                factor: unit(v, "diffuseTransmissionFactor", 0.0),
                texture: self.texture_json(doc, v, "diffuseTransmissionTexture", false),
                color_factor: colour(v, "diffuseTransmissionColorFactor", Vec3::ONE),
                color_texture: self.texture_json(doc, v, "diffuseTransmissionColorTexture", true),
            });
        }
        if let Some(v) = ext.get("KHR_materials_pbrSpecularGlossiness") {
            let sg = self.specular_glossiness(doc, v);
            // The diffuse colour is the base colour (and its alpha the coverage); the core
            // metallic-roughness values are only a fallback for viewers without the extension.
            out.base_color_factor = sg.diffuse_factor;
            out.base_color_texture = sg.diffuse_texture;
            out.metallic_factor = 0.0;
            out.metallic_roughness_texture = None;
            out.specular_glossiness = Some(sg);
        }
    }

    /// `KHR_materials_volume` from its JSON object.
    fn volume(&mut self, doc: &gltf::Document, v: &Value) -> Volume {
        Volume {
            thickness_factor: non_negative(v, "thicknessFactor", 0.0),
            thickness_texture: self.texture_json(doc, v, "thicknessTexture", false),
            attenuation_distance: Some(num(v, "attenuationDistance", f32::INFINITY))
                .filter(|d| *d > 0.0)
                .unwrap_or(f32::INFINITY),
            attenuation_color: colour(v, "attenuationColor", Vec3::ONE),
        }
    }

    /// `KHR_materials_clearcoat` from its JSON object.
    fn clearcoat(&mut self, doc: &gltf::Document, v: &Value) -> Clearcoat {
        let normal = v.get("clearcoatNormalTexture");
        Clearcoat {
            factor: unit(v, "clearcoatFactor", 0.0),
            texture: self.texture_json(doc, v, "clearcoatTexture", false),
            roughness_factor: unit(v, "clearcoatRoughnessFactor", 0.0),
            roughness_texture: self.texture_json(doc, v, "clearcoatRoughnessTexture", false),
            normal_texture: self.texture_json(doc, v, "clearcoatNormalTexture", false),
            normal_scale: normal.map_or(1.0, |n| num(n, "scale", 1.0)),
        }
    }

    /// `KHR_materials_iridescence` from its JSON object.
    fn iridescence(&mut self, doc: &gltf::Document, v: &Value) -> Iridescence {
        Iridescence {
            factor: unit(v, "iridescenceFactor", 0.0),
            texture: self.texture_json(doc, v, "iridescenceTexture", false),
            ior: Some(num(v, "iridescenceIor", 1.3))
                .filter(|x| *x >= 1.0)
                .unwrap_or(1.3),
            thickness_min: non_negative(v, "iridescenceThicknessMinimum", 100.0),
            thickness_max: non_negative(v, "iridescenceThicknessMaximum", 400.0),
            thickness_texture: self.texture_json(doc, v, "iridescenceThicknessTexture", false),
        }
    }

    /// `KHR_materials_pbrSpecularGlossiness` from its JSON object.
    fn specular_glossiness(&mut self, doc: &gltf::Document, v: &Value) -> SpecularGlossiness {
        SpecularGlossiness {
            diffuse_factor: Vec4::from(array(v, "diffuseFactor", [1.0; 4]))
                .clamp(Vec4::ZERO, Vec4::ONE),
            diffuse_texture: self.texture_json(doc, v, "diffuseTexture", true),
            specular_factor: colour(v, "specularFactor", Vec3::ONE),
            glossiness_factor: unit(v, "glossinessFactor", 1.0),
            specular_glossiness_texture: self.texture_json(
                doc,
                v,
                "specularGlossinessTexture",
                true,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn bad_values_fall_back_to_defaults() {
        let v = json!({"a": "x", "b": -2.0, "c": [1, 2], "d": [0.5, 0.25, 2.0], "e": 7.0});
        assert_eq!(num(&v, "a", 3.0), 3.0);
        assert_eq!(non_negative(&v, "b", 1.0), 1.0);
        assert_eq!(unit(&v, "e", 0.0), 1.0);
        assert_eq!(array(&v, "c", [9.0; 3]), [9.0; 3]);
        assert_eq!(colour(&v, "d", Vec3::ZERO), Vec3::new(0.5, 0.25, 2.0));
    }

    #[test]
    fn volume_sigma_follows_the_attenuation_formula() {
        let v = Volume {
            thickness_factor: 1.0,
            thickness_texture: None,
            attenuation_distance: 2.0,
            attenuation_color: Vec3::new(0.5, 1.0, 0.0),
        };
        let s = v.sigma_a();
        assert!((s.x - std::f32::consts::LN_2 / 2.0).abs() < 1e-6, "{s}");
        assert_eq!(s.y, 0.0);
        assert!(s.z.is_finite() && s.z > 30.0);
        let none = Volume {
            attenuation_distance: f32::INFINITY,
            ..v
        };
        assert_eq!(none.sigma_a(), Vec3::ZERO);
        assert!(
            v.is_volume()
                && !Volume {
                    thickness_factor: 0.0,
                    ..v
                }
                .is_volume()
        );
    }
}
