//! What a ray hit: world-space position and normals recomputed from the barycentrics, texture
//! coordinates, vertex colour, tangent frame, and the material evaluated there.
//!
//! Every texture a glTF material references is used — base colour with alpha, metallic (B) and
//! roughness (G), normal map, emissive — each through its own `texCoord` set (0 or 1) and
//! `KHR_texture_transform` — except the occlusion map. Ambient occlusion is a raster
//! approximation of the shadowing that path tracing computes anyway; applying it too would
//! darken creases twice, so occlusion maps are deliberately ignored.

use crate::bsdf::{Bsdf, Dielectric};
use crate::texture;
use aperture_scene::{AlphaMode, Material, Scene, TextureRef};
use glam::{Mat3, Vec2, Vec3, Vec4, Vec4Swizzles};

/// How every surface is shaded, whatever its material says (`--override-material`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MaterialOverride {
    /// Use the scene's materials.
    #[default]
    None,
    /// Two-sided Lambertian of the base colour (factor × vertex colour × texture), emission kept:
    /// the "clay" render.
    Diffuse,
}

/// A point on a triangle of an instance.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Surface {
    /// World position.
    pub p: Vec3,
    /// Unit geometric normal, on the side the (transformed) vertex normals point to.
    pub ng: Vec3,
    /// Unit shading normal (interpolated vertex normal, before normal mapping).
    pub ns: Vec3,
    /// World tangent (xyz, not unit) with bitangent sign (w, mirroring included); zero when the
    /// mesh has none here.
    pub tangent: Vec4,
    /// Texture coordinate sets 0 and 1.
    pub uv: [Vec2; 2],
    /// Vertex colour (white when absent).
    pub color: Vec4,
    /// Material index.
    pub material: u32,
    /// World-space area of the triangle.
    pub area: f32,
}

/// The material evaluated at a surface point.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Shading {
    /// How the point scatters; `None` for unlit surfaces.
    pub bsdf: Option<Bsdf>,
    /// Emitted radiance (both sides).
    pub emission: Vec3,
    /// `KHR_materials_unlit`: the colour the surface shows.
    pub unlit: Option<Vec3>,
    /// Unit shading normal after normal mapping, on the side of `Surface::ns`.
    pub normal: Vec3,
}

/// Per-instance data the hit shader needs, computed once per render.
#[derive(Debug)]
pub(crate) struct Geometry<'a> {
    pub scene: &'a Scene,
    normal_from_object: Vec<Mat3>,
    mirrored: Vec<bool>,
    default_material: Material,
    pub material_override: MaterialOverride,
    /// True when some material cuts or blends by alpha (then rays may pass through surfaces).
    pub has_alpha: bool,
}

impl<'a> Geometry<'a> {
    pub fn new(scene: &'a Scene, material_override: MaterialOverride) -> Self {
        let normal_from_object = scene
            .instances
            .iter()
            .map(|i| {
                Mat3::from(i.world_from_object.matrix3)
                    .inverse()
                    .transpose()
            })
            .collect();
        let mirrored = scene.instances.iter().map(|i| i.is_mirrored()).collect();
        let has_alpha = scene
            .materials
            .iter()
            .any(|m| m.alpha_mode != AlphaMode::Opaque);
        Self {
            scene,
            normal_from_object,
            mirrored,
            default_material: Material::default(),
            material_override,
            has_alpha,
        }
    }

    /// The surface at barycentrics (`b1`, `b2`) of `triangle` of `instance`.
    pub fn surface(&self, instance: u32, triangle: u32, b1: f32, b2: f32) -> Surface {
        let inst = &self.scene.instances[instance as usize];
        let mesh = &self.scene.meshes[inst.mesh as usize];
        let [i0, i1, i2] = mesh.indices[triangle as usize].map(|i| i as usize);
        let b0 = 1.0 - b1 - b2;
        let m = &inst.world_from_object;
        let (p0, p1, p2) = (mesh.positions[i0], mesh.positions[i1], mesh.positions[i2]);
        let p = m.transform_point3(b0 * p0 + b1 * p1 + b2 * p2);
        let cross = m
            .transform_vector3(p1 - p0)
            .cross(m.transform_vector3(p2 - p0));
        let len = cross.length();
        let nm = &self.normal_from_object[instance as usize];
        let ns = if mesh.normals.is_empty() {
            None
        } else {
            let n = b0 * mesh.normals[i0] + b1 * mesh.normals[i1] + b2 * mesh.normals[i2];
            Some((*nm * n).normalize()).filter(|n| n.is_finite())
        };
        // The world-space cross product flips under a mirroring transform; flip it back so the
        // geometric normal stays on the side glTF calls the front.
        let mut ng = if len > 0.0 && len.is_finite() {
            cross / len
        } else {
            ns.unwrap_or(Vec3::Z)
        };
        if self.mirrored[instance as usize] {
            ng = -ng;
        }
        let ns = ns.unwrap_or(ng);
        let lerp2 = |v: &[Vec2]| {
            if v.is_empty() {
                Vec2::ZERO
            } else {
                b0 * v[i0] + b1 * v[i1] + b2 * v[i2]
            }
        };
        let tangent = if mesh.tangents.is_empty() {
            Vec4::ZERO
        } else {
            let t = b0 * mesh.tangents[i0] + b1 * mesh.tangents[i1] + b2 * mesh.tangents[i2];
            // The handedness sign is per vertex (±1); MikkTSpace splits vertices where it
            // changes, so the first corner's sign is the triangle's. A mirroring transform
            // reverses the cross product that builds the bitangent: flip the sign with it.
            let w = if mesh.tangents[i0].w < 0.0 { -1.0 } else { 1.0 };
            let w = if self.mirrored[instance as usize] {
                -w
            } else {
                w
            };
            m.transform_vector3(t.xyz()).extend(w)
        };
        let color = if mesh.colors.is_empty() {
            Vec4::ONE
        } else {
            b0 * mesh.colors[i0] + b1 * mesh.colors[i1] + b2 * mesh.colors[i2]
        };
        Surface {
            p,
            ng,
            ns,
            tangent,
            uv: [lerp2(&mesh.uv0), lerp2(&mesh.uv1)],
            color,
            material: mesh
                .material_ids
                .get(triangle as usize)
                .copied()
                .unwrap_or(0),
            area: 0.5 * len,
        }
    }

    pub fn material(&self, id: u32) -> &Material {
        self.scene
            .materials
            .get(id as usize)
            .unwrap_or(&self.default_material)
    }

    fn lookup(&self, r: &Option<TextureRef>, s: &Surface) -> Vec4 {
        let Some(r) = r else { return Vec4::ONE };
        let Some(tex) = self.scene.textures.get(r.texture as usize) else {
            return Vec4::ONE;
        };
        let uv = s.uv[(r.tex_coord as usize).min(1)];
        let uv = match &r.transform {
            Some(t) => texture::transform_uv(t, uv),
            None => uv,
        };
        texture::sample(tex, uv)
    }

    /// Base colour with alpha: factor × vertex colour × texture.
    fn base_color(&self, m: &Material, s: &Surface) -> Vec4 {
        m.base_color_factor * s.color * self.lookup(&m.base_color_texture, s)
    }

    /// Emitted radiance: factor × strength × texture (SPEC §4).
    pub fn emission(&self, s: &Surface) -> Vec3 {
        let m = self.material(s.material);
        if !m.is_emissive() {
            return Vec3::ZERO;
        }
        m.emissive_factor * m.emissive_strength * self.lookup(&m.emissive_texture, s).xyz()
    }

    /// Opacity of the surface for a ray, given a uniform number for stochastic blending:
    /// true when the ray stops here.
    pub fn is_opaque(&self, s: &Surface, u: f32) -> bool {
        let m = self.material(s.material);
        match m.alpha_mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask { cutoff } => self.base_color(m, s).w >= cutoff,
            AlphaMode::Blend => u < self.base_color(m, s).w,
        }
    }

    /// The fraction of light a surface lets through (shadow rays: expected value, no sampling).
    pub fn transmittance(&self, s: &Surface) -> f32 {
        let m = self.material(s.material);
        match m.alpha_mode {
            AlphaMode::Opaque => 0.0,
            AlphaMode::Mask { cutoff } => {
                if self.base_color(m, s).w >= cutoff {
                    0.0
                } else {
                    1.0
                }
            }
            AlphaMode::Blend => (1.0 - self.base_color(m, s).w).clamp(0.0, 1.0),
        }
    }

    /// The shading normal with the material's normal map applied (glTF: tangent-space, +X
    /// along the tangent, +Y along the bitangent, scaled in X and Y by `normal_scale`). Falls
    /// back to the interpolated normal when there is no map, no tangent frame, or the result
    /// is degenerate, so a bad texel never yields NaN.
    pub fn shading_normal(&self, m: &Material, s: &Surface) -> Vec3 {
        if m.normal_texture.is_none() || s.tangent.xyz() == Vec3::ZERO {
            return s.ns;
        }
        let tex = self.lookup(&m.normal_texture, s).xyz() * 2.0 - Vec3::ONE;
        let local = Vec3::new(tex.x * m.normal_scale, tex.y * m.normal_scale, tex.z);
        let n = s.ns;
        // Gram-Schmidt: interpolated tangents drift off the interpolated normal.
        let Some(t) = (s.tangent.xyz() - n * n.dot(s.tangent.xyz())).try_normalize() else {
            return n;
        };
        let b = n.cross(t) * s.tangent.w;
        (t * local.x + b * local.y + n * local.z)
            .try_normalize()
            .filter(|v| v.is_finite())
            .unwrap_or(n)
    }

    /// The material evaluated at `s`.
    pub fn shade(&self, s: &Surface) -> Shading {
        let m = self.material(s.material);
        let base = self.base_color(m, s).xyz().max(Vec3::ZERO);
        let emission = self.emission(s);
        if m.unlit && self.material_override == MaterialOverride::None {
            return Shading {
                bsdf: None,
                emission: Vec3::ZERO,
                unlit: Some(base),
                normal: s.ns,
            };
        }
        let normal = self.shading_normal(m, s);
        if self.material_override == MaterialOverride::Diffuse {
            return Shading {
                bsdf: Some(Bsdf::Lambert {
                    albedo: base.min(Vec3::ONE),
                }),
                emission,
                unlit: None,
                normal,
            };
        }
        let mr = self.lookup(&m.metallic_roughness_texture, s);
        Shading {
            bsdf: Some(Bsdf::metal_rough_dielectric(
                base.min(Vec3::ONE),
                m.metallic_factor * mr.z,
                m.roughness_factor * mr.y,
                &Dielectric {
                    ior: m.ior,
                    specular: m.specular_factor * self.lookup(&m.specular_texture, s).w,
                    specular_color: m.specular_color_factor
                        * self.lookup(&m.specular_color_texture, s).xyz(),
                },
            )),
            emission,
            unlit: None,
            normal,
        }
    }
}
