//! The material extensions of glTF's PBR "next" model (SPEC §5), as plain data: each is `None`
//! on a [`crate::Material`] when the file does not use it, so a renderer can skip what a
//! material does not have. Factors are stored as written; textures multiply them (the channel
//! each texture contributes is named on its field).

use glam::{Vec3, Vec4};

use crate::types::texture_ref::TextureRef;

/// `KHR_materials_transmission`: specular transmission through the dielectric base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transmission {
    /// `transmissionFactor` (0 when absent).
    pub factor: f32,
    /// `transmissionTexture`: its R channel multiplies the factor (linear).
    pub texture: Option<TextureRef>,
}

/// `KHR_materials_volume`: the mesh bounds a homogeneous absorbing medium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Volume {
    /// `thicknessFactor`: 0 makes the surface thin-walled (glTF default 0).
    pub thickness_factor: f32,
    /// `thicknessTexture` (G channel). A path tracer measures thickness along rays instead;
    /// kept for `info`.
    pub thickness_texture: Option<TextureRef>,
    /// `attenuationDistance` in scene units (+∞ when absent: no absorption).
    pub attenuation_distance: f32,
    /// `attenuationColor` (white when absent).
    pub attenuation_color: Vec3,
}

impl Volume {
    /// Absorption coefficient per scene unit, `σ = −ln(attenuationColor) / attenuationDistance`
    /// (SPEC §5); zero without a finite positive distance. Colour channels at 0 give a very
    /// large but finite σ, so a product with a zero distance never makes NaN.
    pub fn sigma_a(&self) -> Vec3 {
        let d = self.attenuation_distance;
        if !(d.is_finite() && d > 0.0) {
            return Vec3::ZERO;
        }
        let c = self.attenuation_color.clamp(Vec3::splat(1e-30), Vec3::ONE);
        let s = Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / d;
        if s.is_finite() {
            s.max(Vec3::ZERO)
        } else {
            Vec3::ZERO
        }
    }

    /// True when the surface bounds a volume (thickness above 0), false when thin-walled.
    pub fn is_volume(&self) -> bool {
        self.thickness_factor > 0.0
    }
}

/// `KHR_materials_clearcoat`: a GGX coat of IOR 1.5 over everything else.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearcoat {
    /// `clearcoatFactor`.
    pub factor: f32,
    /// `clearcoatTexture` (R channel).
    pub texture: Option<TextureRef>,
    /// `clearcoatRoughnessFactor` (perceptual).
    pub roughness_factor: f32,
    /// `clearcoatRoughnessTexture` (G channel).
    pub roughness_texture: Option<TextureRef>,
    /// `clearcoatNormalTexture`: the coat's own normal map (tangent space, linear). Without
    /// it the coat uses the interpolated normal, not the base's normal map.
    pub normal_texture: Option<TextureRef>,
    /// The coat normal map's `scale`.
    pub normal_scale: f32,
}

/// `KHR_materials_sheen`: a "Charlie" sheen layer over the base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sheen {
    /// `sheenColorFactor` (linear).
    pub color_factor: Vec3,
    /// `sheenColorTexture` (RGB, sRGB-encoded).
    pub color_texture: Option<TextureRef>,
    /// `sheenRoughnessFactor` (perceptual).
    pub roughness_factor: f32,
    /// `sheenRoughnessTexture` (A channel).
    pub roughness_texture: Option<TextureRef>,
}

/// `KHR_materials_anisotropy`: anisotropic GGX roughness of the specular layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anisotropy {
    /// `anisotropyStrength` in [0, 1].
    pub strength: f32,
    /// `anisotropyRotation`: radians, counter-clockwise from the tangent.
    pub rotation: f32,
    /// `anisotropyTexture`: RG a direction in tangent space (encoded as `2x − 1`), B a
    /// strength multiplier (linear).
    pub texture: Option<TextureRef>,
}

/// `KHR_materials_iridescence`: a thin film over the base whose Fresnel interferes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iridescence {
    /// `iridescenceFactor`.
    pub factor: f32,
    /// `iridescenceTexture` (R channel).
    pub texture: Option<TextureRef>,
    /// `iridescenceIor` of the film (1.3 by default).
    pub ior: f32,
    /// `iridescenceThicknessMinimum` in nanometres (100).
    pub thickness_min: f32,
    /// `iridescenceThicknessMaximum` in nanometres (400).
    pub thickness_max: f32,
    /// `iridescenceThicknessTexture` (G channel) between the two; the maximum without it.
    pub thickness_texture: Option<TextureRef>,
}

/// `KHR_materials_diffuse_transmission`: Lambertian transmission through the diffuse base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseTransmission {
    /// `diffuseTransmissionFactor`.
    pub factor: f32,
    /// `diffuseTransmissionTexture` (A channel).
    pub texture: Option<TextureRef>,
    /// `diffuseTransmissionColorFactor` (linear).
    pub color_factor: Vec3,
    /// `diffuseTransmissionColorTexture` (RGB, sRGB-encoded).
    pub color_texture: Option<TextureRef>,
}

/// `KHR_materials_pbrSpecularGlossiness` (archived), converted to metallic-roughness at shading
/// time as the Khronos sample viewer does: base colour = diffuse, metallic 0, roughness =
/// 1 − glossiness, dielectric F0 = specular.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecularGlossiness {
    /// `diffuseFactor` (linear RGBA).
    pub diffuse_factor: Vec4,
    /// `diffuseTexture` (sRGB RGB, linear alpha).
    pub diffuse_texture: Option<TextureRef>,
    /// `specularFactor` (linear).
    pub specular_factor: Vec3,
    /// `glossinessFactor`.
    pub glossiness_factor: f32,
    /// `specularGlossinessTexture`: RGB specular (sRGB), A glossiness (linear).
    pub specular_glossiness_texture: Option<TextureRef>,
}
