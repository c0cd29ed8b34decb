//! A material's reference to a texture and its `KHR_texture_transform`: what the core material
//! and the PBR extensions ([`crate::pbr`]) both name.

use glam::Vec2;

/// `KHR_texture_transform` of one texture reference: `uv' = offset + rotate(rotation) * (scale * uv)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureTransform {
    /// UV offset.
    pub offset: Vec2,
    /// Rotation in radians (counter-clockwise in UV space, as the extension defines).
    pub rotation: f32,
    /// UV scale.
    pub scale: Vec2,
}

impl Default for TextureTransform {
    fn default() -> Self {
        Self {
            offset: Vec2::ZERO,
            rotation: 0.0,
            scale: Vec2::ONE,
        }
    }
}

/// A material's reference to a texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into `Scene::textures`.
    pub texture: u32,
    /// Which UV set (`TEXCOORD_n`), after `KHR_texture_transform`'s own `texCoord` override.
    pub tex_coord: u32,
    /// `KHR_texture_transform`, if present.
    pub transform: Option<TextureTransform>,
}
