//! Materials and the textures they sample: the shading half of the scene model, plain data.

use super::texture_ref::TextureRef;
use glam::{Vec3, Vec4};

/// How a material treats alpha.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// Alpha below the cutoff is fully transparent, otherwise fully opaque.
    Mask {
        /// The `alphaCutoff` (glTF default 0.5).
        cutoff: f32,
    },
    /// Alpha is coverage (rendered stochastically).
    Blend,
}

/// glTF metallic-roughness material (SPEC §5) with the extensions we read.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The glTF material name, if any.
    pub name: Option<String>,
    /// Linear RGBA base colour factor.
    pub base_color_factor: Vec4,
    /// Base colour texture (sRGB-encoded).
    pub base_color_texture: Option<TextureRef>,
    /// Metallic factor.
    pub metallic_factor: f32,
    /// Roughness factor (perceptual roughness; alpha = roughness²).
    pub roughness_factor: f32,
    /// Metallic (B) and roughness (G) texture, linear.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map, linear.
    pub normal_texture: Option<TextureRef>,
    /// Normal map scale.
    pub normal_scale: f32,
    /// Occlusion texture (R), linear. Read (for `info`) but ignored by the renderer: ambient
    /// occlusion approximates the shadowing a path tracer computes anyway.
    pub occlusion_texture: Option<TextureRef>,
    /// Occlusion strength.
    pub occlusion_strength: f32,
    /// Linear emissive factor.
    pub emissive_factor: Vec3,
    /// Emissive texture (sRGB-encoded).
    pub emissive_texture: Option<TextureRef>,
    /// `KHR_materials_emissive_strength` (1 when absent).
    pub emissive_strength: f32,
    /// Alpha mode and cutoff.
    pub alpha_mode: AlphaMode,
    /// glTF `doubleSided` (we shade both sides regardless; kept for `info` and culling choices).
    pub double_sided: bool,
    /// `KHR_materials_unlit`.
    pub unlit: bool,
    /// `KHR_materials_ior` (1.5 when absent).
    pub ior: f32,
    /// `KHR_materials_specular` factor (1 when absent).
    pub specular_factor: f32,
    /// `KHR_materials_specular` colour factor (1 when absent).
    pub specular_color_factor: Vec3,
    /// `KHR_materials_specular` texture: its alpha multiplies the specular factor (linear).
    pub specular_texture: Option<TextureRef>,
    /// `KHR_materials_specular` colour texture (sRGB-encoded): multiplies the colour factor.
    pub specular_color_texture: Option<TextureRef>,
    /// `KHR_materials_transmission`.
    pub transmission: Option<crate::pbr::Transmission>,
    /// `KHR_materials_volume`.
    pub volume: Option<crate::pbr::Volume>,
    /// `KHR_materials_clearcoat`.
    pub clearcoat: Option<crate::pbr::Clearcoat>,
    /// `KHR_materials_sheen`.
    pub sheen: Option<crate::pbr::Sheen>,
    /// `KHR_materials_anisotropy`.
    pub anisotropy: Option<crate::pbr::Anisotropy>,
    /// `KHR_materials_iridescence`.
    pub iridescence: Option<crate::pbr::Iridescence>,
    /// `KHR_materials_dispersion`: `20 / V` for Abbe number `V` (0 when absent: no dispersion).
    pub dispersion: f32,
    /// `KHR_materials_diffuse_transmission`.
    pub diffuse_transmission: Option<crate::pbr::DiffuseTransmission>,
    /// `KHR_materials_pbrSpecularGlossiness`: when present it replaces the metallic-roughness
    /// parameters.
    pub specular_glossiness: Option<crate::pbr::SpecularGlossiness>,
}

impl Default for Material {
    /// The glTF default material.
    fn default() -> Self {
        Self {
            name: None,
            base_color_factor: Vec4::ONE,
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive_factor: Vec3::ZERO,
            emissive_texture: None,
            emissive_strength: 1.0,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            unlit: false,
            ior: 1.5,
            specular_factor: 1.0,
            specular_color_factor: Vec3::ONE,
            specular_texture: None,
            specular_color_texture: None,
            transmission: None,
            volume: None,
            clearcoat: None,
            sheen: None,
            anisotropy: None,
            iridescence: None,
            dispersion: 0.0,
            diffuse_transmission: None,
            specular_glossiness: None,
        }
    }
}

impl Material {
    /// True when the material can emit light (a non-zero emissive factor and strength).
    pub fn is_emissive(&self) -> bool {
        self.emissive_strength > 0.0 && self.emissive_factor.max_element() > 0.0
    }

    /// True when light may pass through the surface by specular transmission
    /// (`KHR_materials_transmission` with a factor above 0).
    pub fn is_transmissive(&self) -> bool {
        self.transmission.is_some_and(|t| t.factor > 0.0)
    }

    /// True when the material uses any lobe beyond glTF's core metallic-roughness (and the
    /// IOR and specular extensions): transmission, volume, clear coat, sheen, anisotropy,
    /// iridescence, dispersion, diffuse transmission or specular-glossiness. Materials without
    /// them are shaded exactly as before those extensions existed.
    pub fn has_extended_lobes(&self) -> bool {
        self.is_transmissive()
            || self.clearcoat.is_some_and(|c| c.factor > 0.0)
            || self
                .sheen
                .is_some_and(|s| s.color_factor.max_element() > 0.0)
            || self
                .anisotropy
                .is_some_and(|a| a.strength != 0.0 || a.texture.is_some())
            || self.iridescence.is_some_and(|i| i.factor > 0.0)
            || self.diffuse_transmission.is_some_and(|d| d.factor > 0.0)
            || self.specular_glossiness.is_some()
    }
}

/// Texture coordinate wrapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Repeat (glTF default).
    #[default]
    Repeat,
    /// Mirrored repeat.
    MirroredRepeat,
    /// Clamp to edge.
    ClampToEdge,
}

/// Texture filtering for magnification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Filter {
    /// Bilinear (the default when the sampler says nothing).
    #[default]
    Linear,
    /// Nearest texel.
    Nearest,
}

/// How a texture is sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sampler {
    /// Wrapping along U.
    pub wrap_u: Wrap,
    /// Wrapping along V.
    pub wrap_v: Wrap,
    /// Magnification filter.
    pub mag_filter: Filter,
}

/// How a texture's stored values map to linear values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorSpace {
    /// sRGB-encoded colour (base colour, emissive): RGB decoded to linear on lookup, alpha linear.
    Srgb,
    /// Linear data (normals, metallic-roughness, occlusion).
    Linear,
}

/// Texel storage.
#[derive(Debug, Clone, PartialEq)]
pub enum Texels {
    /// 8 bits per channel, RGBA, rows top to bottom.
    Rgba8(Vec<[u8; 4]>),
    /// 32-bit float RGBA (16-bit and float sources), rows top to bottom, already linear-valued
    /// storage of the encoded values (the colour space still applies).
    Rgba32F(Vec<[f32; 4]>),
}

/// A decoded texture: one glTF image with the sampler and colour space of its use.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// glTF image name or URI, for messages.
    pub name: Option<String>,
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// Texel data, `width * height` long.
    pub texels: Texels,
    /// Encoding of the stored values.
    pub color_space: ColorSpace,
    /// Wrap and filter modes.
    pub sampler: Sampler,
}
