//! What a ray hit: world-space position and normals recomputed from the barycentrics, texture
//! coordinates, vertex colour, tangent frame, and the material evaluated there.
//!
//! Every texture a glTF material references is used — base colour with alpha, metallic (B) and
//! roughness (G), normal map, emissive — each through its own `texCoord` set (any `TEXCOORD_n`) and
//! `KHR_texture_transform` — except the occlusion map. Ambient occlusion is a raster
//! approximation of the shadowing that path tracing computes anyway; applying it too would
//! darken creases twice, so occlusion maps are deliberately ignored.

use crate::bsdf::{bend_towards, Bsdf, Dielectric, Frame};
use crate::media::Medium;
use crate::texture;
use crate::transmission::TransmissionModel;
use aperture_scene::{AlphaMode, Material, Scene, TextureRef};
use glam::{Mat3, Vec2, Vec3, Vec4, Vec4Swizzles};

/// How every surface is shaded, whatever its material says (`--override-material`, whose
/// absence is `None`; the first paragraph of each value's comment is its help there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum MaterialOverride {
    /// Use the scene's materials.
    #[default]
    #[cfg_attr(feature = "clap", value(skip))]
    None,
    /// Two-sided Lambertian of the base colour, emission kept (a "clay" render).
    ///
    /// The base colour: factor × vertex colour × texture.
    Diffuse,
}

/// A point on a triangle of an instance.
#[derive(Debug, Clone, Copy)]
pub struct Surface {
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
    /// The mesh, its triangle's vertices and their barycentric weights: what the further
    /// coordinate sets (`TEXCOORD_2` …) are interpolated from, when a texture asks for one.
    pub corners: (u32, [u32; 3], Vec3),
    /// Vertex colour (white when absent).
    pub color: Vec4,
    /// Material index.
    pub material: u32,
    /// World-space area of the triangle.
    pub area: f32,
}

/// The material evaluated at a surface point.
#[derive(Debug, Clone)]
pub struct Shading {
    /// How the point scatters; `None` for unlit surfaces.
    pub bsdf: Option<Bsdf>,
    /// Emitted radiance (both sides).
    pub emission: Vec3,
    /// `KHR_materials_unlit`: the colour the surface shows.
    pub unlit: Option<Vec3>,
    /// Unit shading normal after normal mapping, on the side of `Surface::ns`.
    pub normal: Vec3,
    /// The direction the shading frame's x axis must follow (an anisotropic lobe's), world.
    pub tangent: Option<Vec3>,
}

/// The shading normal at `s` seen from `wo` (world, unit), `ng` being the geometric normal
/// on the viewer's side: the mapped normal turned to that side with the vertex normal (both
/// sides are shaded) and bent just above the view.
pub fn view_normal(s: &Surface, shading: &Shading, ng: Vec3, wo: Vec3) -> Vec3 {
    let ns = if s.ns.dot(ng) < 0.0 {
        -shading.normal
    } else {
        shading.normal
    };
    bend_towards(ns, wo)
}

/// The shading frame around `ns` (from [`view_normal`]) with its x axis along `tangent` when
/// given, and the view `wo` in it. `bend_towards` keeps the view above the shading hemisphere;
/// if rounding still says otherwise, the geometric normal `ng` (on the viewer's side) gives
/// the frame rather than return black.
#[inline]
pub fn shading_frame(ns: Vec3, ng: Vec3, tangent: Option<Vec3>, wo: Vec3) -> (Frame, Vec3) {
    let mut frame = match tangent {
        Some(t) => Frame::from_normal_tangent(ns, t),
        None => Frame::from_normal(ns),
    };
    let mut wo_l = frame.to_local(wo);
    if wo_l.z <= 0.0 {
        frame = Frame::from_normal(ng);
        wo_l = frame.to_local(wo);
    }
    (frame, wo_l)
}

/// What the specular transmission of a material is at a surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceKind {
    /// No specular transmission.
    Opaque,
    /// Thin-walled transmission.
    Thin,
    /// The boundary of a refractive volume.
    Refractive,
}

/// How a material transmits, before the mesh is known.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Transmits {
    No,
    Thin,
    Refractive,
    /// Refractive where the mesh is closed (`--transmission blender`).
    IfClosed,
}

/// What the hit shader needs to know of a material beyond its parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialInfo {
    /// Shaded by the extended BSDF (it has lobes beyond metallic-roughness).
    extended: bool,
    transmits: Transmits,
    /// The medium inside, for refractive boundaries.
    pub medium: Medium,
    /// `KHR_materials_dispersion` (20 / Abbe number).
    pub dispersion: f32,
}

/// Per-instance data the hit shader needs, computed once per render.
#[derive(Debug)]
pub struct Geometry<'a> {
    /// The scene shaded.
    pub scene: &'a Scene,
    normal_from_object: Vec<Mat3>,
    mirrored: Vec<bool>,
    default_material: Material,
    /// The material override in force.
    pub material_override: MaterialOverride,
    /// True when some material cuts or blends by alpha (then rays may pass through surfaces).
    pub has_alpha: bool,
    /// Per material (and one more for the default material).
    info: Vec<MaterialInfo>,
    /// Per mesh: closed (computed for meshes with `IfClosed` materials only).
    closed: Vec<bool>,
    /// True when some surface may be a refractive boundary.
    pub has_refractive: bool,
    /// True when some surface may be thin-walled transmissive (shadow rays may pass it).
    pub has_thin: bool,
    /// True when the backs of single-sided faces are invisible (`SidesModel::Gltf`, set by
    /// `Geometry::with_sides`) and some material is single-sided: then rays may pass through
    /// surfaces seen from behind.
    pub has_culled: bool,
    /// True when the meshes' vertex data is large enough for a hit's reads to miss the
    /// caches, so that asking for them ahead (`crate::hit_prefetch`) pays for itself.
    pub prefetch_hits: bool,
}

/// Bytes of vertex data (positions, normals, first texture coordinates, indices) above which
/// the hints are worth their instructions ([`prefetch_worth_it`]; the hints are
/// `crate::hit_prefetch`'s). Measured: the 560 k-triangle interior (13.6 MB) renders 2–3 % faster with them; the 58 k-triangle outdoor scene (0.6 MB) and the
/// helmet (2.9 MB) run at the same speed with 2 % more instructions.
pub const PREFETCH_ABOVE: usize = 8 << 20;

/// Whether `scene`'s vertex data is large enough for the hints to pay for themselves.
pub fn prefetch_worth_it(scene: &Scene) -> bool {
    let bytes: usize = scene
        .meshes
        .iter()
        .map(|m| {
            std::mem::size_of_val(m.positions.as_slice())
                + std::mem::size_of_val(m.normals.as_slice())
                + std::mem::size_of_val(m.uv0.as_slice())
                + std::mem::size_of_val(m.indices.as_slice())
        })
        .sum();
    bytes > PREFETCH_ABOVE
}

impl<'a> Geometry<'a> {
    /// Hit shading for `scene` with glTF's meaning of transmission.
    #[cfg(test)]
    pub fn new(scene: &'a Scene, material_override: MaterialOverride) -> Self {
        Self::with_transmission(scene, material_override, TransmissionModel::Gltf)
    }

    /// Hit shading for `scene`, transmissive surfaces interpreted by `model`.
    pub fn with_transmission(
        scene: &'a Scene,
        material_override: MaterialOverride,
        model: TransmissionModel,
    ) -> Self {
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
        let default_material = Material::default();
        let info: Vec<MaterialInfo> = scene
            .materials
            .iter()
            .chain(std::iter::once(&default_material))
            .enumerate()
            .map(|(i, m)| material_info(i as u32, m, material_override, model))
            .collect();
        let needs = scene.meshes_with_material(|id| {
            info.get(id as usize)
                .is_some_and(|i| i.transmits == Transmits::IfClosed)
        });
        let closed: Vec<bool> = scene
            .meshes
            .iter()
            .zip(needs)
            .map(|(mesh, needs)| needs && mesh.is_closed())
            .collect();
        let has_refractive = info
            .iter()
            .any(|i| matches!(i.transmits, Transmits::Refractive))
            || closed.iter().any(|&c| c);
        let has_thin = info
            .iter()
            .any(|i| matches!(i.transmits, Transmits::Thin | Transmits::IfClosed));
        Self {
            scene,
            normal_from_object,
            mirrored,
            default_material,
            material_override,
            has_alpha,
            info,
            closed,
            has_refractive,
            has_thin,
            has_culled: false,
            prefetch_hits: prefetch_worth_it(scene),
        }
    }

    /// What the hit shader knows of material `id`.
    pub fn info(&self, id: u32) -> &MaterialInfo {
        let last = self.info.len() - 1;
        &self.info[(id as usize).min(last)]
    }

    /// What the material's specular transmission is on this instance's mesh.
    pub fn kind(&self, instance: u32, material: u32) -> SurfaceKind {
        match self.info(material).transmits {
            Transmits::No => SurfaceKind::Opaque,
            Transmits::Thin => SurfaceKind::Thin,
            Transmits::Refractive => SurfaceKind::Refractive,
            Transmits::IfClosed => {
                let mesh = self.scene.instances[instance as usize].mesh;
                if self.closed.get(mesh as usize).copied().unwrap_or(false) {
                    SurfaceKind::Refractive
                } else {
                    SurfaceKind::Thin
                }
            }
        }
    }

    /// The surface at barycentrics (`b1`, `b2`) of `triangle` of `instance`.
    pub fn surface(&self, instance: u32, triangle: u32, b1: f32, b2: f32) -> Surface {
        self.surface_at(instance, triangle, b1, b2, true)
    }

    /// [`Geometry::surface`] as a light sample on an emissive triangle reads it: position,
    /// geometric normal, area, material and texture coordinates, bit for bit; the shading
    /// normal is the geometric one (unless that needs it), no tangent, white vertex colour.
    pub fn emitter_surface(&self, instance: u32, triangle: u32, b1: f32, b2: f32) -> Surface {
        self.surface_at(instance, triangle, b1, b2, false)
    }

    /// [`Geometry::surface`], with the shading attributes (normal, tangent, colour) only if
    /// `shading`; inline, for the path vertex to read the surface where it is built.
    #[inline(always)]
    pub fn surface_at(
        &self,
        instance: u32,
        triangle: u32,
        b1: f32,
        b2: f32,
        shading: bool,
    ) -> Surface {
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
        let flat = len > 0.0 && len.is_finite();
        let nm = &self.normal_from_object[instance as usize];
        // A degenerate triangle's geometric normal is the interpolated one.
        let ns = if mesh.normals.is_empty() || (!shading && flat) {
            None
        } else {
            let n = b0 * mesh.normals[i0] + b1 * mesh.normals[i1] + b2 * mesh.normals[i2];
            Some((*nm * n).normalize()).filter(|n| n.is_finite())
        };
        // The world-space cross product flips under a mirroring transform; flip it back so the
        // geometric normal stays on the side glTF calls the front.
        let mut ng = if flat {
            cross / len
        } else {
            ns.unwrap_or(Vec3::Z)
        };
        let mirrored = self.mirrored[instance as usize];
        if mirrored {
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
        let corners = ([i0, i1, i2], Vec3::new(b0, b1, b2));
        let tangent = if !shading || mesh.tangents.is_empty() {
            Vec4::ZERO
        } else {
            world_tangent(&mesh.tangents, corners, m, mirrored)
        };
        let color = if !shading || mesh.colors.is_empty() {
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
            corners: (
                inst.mesh,
                [i0, i1, i2].map(|i| i as u32),
                Vec3::new(b0, b1, b2),
            ),
            color,
            material: self
                .scene
                .instance_materials(inst)
                .get(triangle as usize)
                .copied()
                .unwrap_or(0),
            area: 0.5 * len,
        }
    }

    /// Material `id`, or the glTF default material when out of range.
    pub fn material(&self, id: u32) -> &Material {
        self.scene
            .materials
            .get(id as usize)
            .unwrap_or(&self.default_material)
    }

    #[inline]
    /// The texture slot `r` sampled at surface point `s` (white when the slot is empty).
    pub fn lookup(&self, r: &Option<TextureRef>, s: &Surface) -> Vec4 {
        // Most material slots have no texture: that answer without a call.
        match r {
            Some(r) => self.lookup_texture(r, s),
            None => Vec4::ONE,
        }
    }

    /// [`Geometry::lookup`] of a slot that has a texture.
    fn lookup_texture(&self, r: &TextureRef, s: &Surface) -> Vec4 {
        let Some(tex) = self.scene.textures.get(r.texture as usize) else {
            return Vec4::ONE;
        };
        let uv = match r.tex_coord {
            0 | 1 => s.uv[r.tex_coord as usize],
            set => self.uv_set(s, set),
        };
        let uv = match &r.transform {
            Some(t) => texture::transform_uv(t, uv),
            None => uv,
        };
        texture::sample(tex, uv)
    }

    /// Texture coordinate set `set` (2 or more) at `s`; zero where the mesh has no such set.
    fn uv_set(&self, s: &Surface, set: u32) -> Vec2 {
        let (mesh, [i0, i1, i2], b) = s.corners;
        let uv = self
            .scene
            .meshes
            .get(mesh as usize)
            .and_then(|m| m.uv_more.get(set as usize - 2));
        match uv {
            Some(v) if !v.is_empty() => {
                b.x * v[i0 as usize] + b.y * v[i1 as usize] + b.z * v[i2 as usize]
            }
            _ => Vec2::ZERO,
        }
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
        self.mapped_normal(&m.normal_texture, m.normal_scale, s)
    }

    /// The interpolated normal perturbed by a tangent-space normal map `map` with `scale`.
    pub fn mapped_normal(&self, map: &Option<TextureRef>, scale: f32, s: &Surface) -> Vec3 {
        if map.is_none() || s.tangent.xyz() == Vec3::ZERO {
            return s.ns;
        }
        let tex = self.lookup(map, s).xyz() * 2.0 - Vec3::ONE;
        let local = Vec3::new(tex.x * scale, tex.y * scale, tex.z);
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
    #[inline]
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
                tangent: None,
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
                tangent: None,
            };
        }
        if self.info(s.material).extended {
            return self.shade_extended(m, s, base, emission, normal);
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
            tangent: None,
        }
    }
}

/// The world tangent (xyz) with bitangent sign (w) interpolated from `tangents` at the corners
/// (vertex indices, barycentric weights), through `m`, under a `mirrored` transform or not.
fn world_tangent(
    tangents: &[Vec4],
    ([i0, i1, i2], b): ([usize; 3], Vec3),
    m: &glam::Affine3A,
    mirrored: bool,
) -> Vec4 {
    let t = b.x * tangents[i0] + b.y * tangents[i1] + b.z * tangents[i2];
    // The handedness sign is per vertex (±1); MikkTSpace splits vertices where it changes, so
    // the first corner's sign is the triangle's. A mirroring transform reverses the cross
    // product that builds the bitangent: flip the sign with it.
    let w = if tangents[i0].w < 0.0 { -1.0 } else { 1.0 };
    let w = if mirrored { -w } else { w };
    m.transform_vector3(t.xyz()).extend(w)
}

/// How material `index` is shaded and transmits.
fn material_info(
    index: u32,
    m: &Material,
    material_override: MaterialOverride,
    model: TransmissionModel,
) -> MaterialInfo {
    let clay = material_override == MaterialOverride::Diffuse;
    let transmits = if clay || m.unlit || !m.is_transmissive() {
        Transmits::No
    } else {
        match model {
            TransmissionModel::Gltf if m.volume.is_some_and(|v| v.is_volume()) => {
                Transmits::Refractive
            }
            TransmissionModel::Gltf => Transmits::Thin,
            TransmissionModel::Blender => Transmits::IfClosed,
        }
    };
    let ior = if m.ior.is_finite() && m.ior >= 1.0 {
        m.ior
    } else {
        1.5
    };
    MaterialInfo {
        extended: !clay && m.has_extended_lobes(),
        transmits,
        medium: Medium {
            material: index,
            ior,
            sigma_a: m.volume.map_or(Vec3::ZERO, |v| v.sigma_a()),
        },
        dispersion: if m.dispersion.is_finite() {
            m.dispersion.max(0.0)
        } else {
            0.0
        },
    }
}
