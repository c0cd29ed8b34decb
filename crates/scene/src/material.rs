//! Materials and textures. Materials are built on first use by a drawn primitive; a texture is one
//! (image, sampler, colour space) combination, and only images such textures use are decoded, in
//! parallel.

use std::collections::HashMap;
use std::path::Path;

use glam::{Vec2, Vec3, Vec4};
use serde_json::Value;

use crate::accessor::Buffers;
use crate::error::Error;
use crate::types::{
    AlphaMode, ColorSpace, Filter, Material, Sampler, Texels, Texture, TextureRef,
    TextureTransform, Wrap,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct TexKey {
    image: usize,
    sampler: Option<usize>,
    srgb: bool,
}

/// Builds materials and texture references lazily, in first-use order.
#[derive(Default)]
pub(crate) struct Materials {
    by_gltf: HashMap<Option<usize>, u32>,
    pub materials: Vec<Material>,
    keys: Vec<TexKey>,
    by_key: HashMap<TexKey, u32>,
    /// One line per (material, extension) the renderer shows only approximately.
    pub warnings: Vec<String>,
}

/// Material extensions the renderer cannot show exactly yet, with what it renders instead. Each
/// degrades to the metallic-roughness base underneath it, which is what the extension's own
/// fallback rule asks of a viewer that ignores it. Empty since issue 14: every material
/// extension Blender's exporter writes (and the Khronos ones beside them) is rendered.
const DEGRADED: &[(&str, &str)] = &[];

/// Warnings for the extensions of `m` that degrade (see [`DEGRADED`]), naming the material.
fn degrade_warnings(m: &gltf::Material<'_>) -> Vec<String> {
    let Some(ext) = m.extensions() else {
        return Vec::new();
    };
    let who = match m.name() {
        Some(n) => format!("material \"{n}\" (materials[{}])", m.index().unwrap_or(0)),
        None => format!("materials[{}]", m.index().unwrap_or(0)),
    };
    DEGRADED
        .iter()
        .filter(|(name, _)| ext.contains_key(*name))
        .map(|(name, instead)| format!("{who}: {name} is not supported; rendered {instead}"))
        .collect()
}

/// `KHR_texture_transform` from its JSON (normal and occlusion textures expose only JSON).
fn transform_from_json(v: &Value) -> (TextureTransform, Option<u32>) {
    let pair = |key: &str, default: Vec2| {
        v.get(key)
            .and_then(Value::as_array)
            .filter(|a| a.len() == 2)
            .and_then(|a| Some(Vec2::new(a[0].as_f64()? as f32, a[1].as_f64()? as f32)))
            .unwrap_or(default)
    };
    (
        TextureTransform {
            offset: pair("offset", Vec2::ZERO),
            rotation: v.get("rotation").and_then(Value::as_f64).unwrap_or(0.0) as f32,
            scale: pair("scale", Vec2::ONE),
        },
        v.get("texCoord")
            .and_then(Value::as_u64)
            .and_then(|t| u32::try_from(t).ok()),
    )
}

impl Materials {
    fn texture(&mut self, tex: &gltf::Texture<'_>, srgb: bool) -> u32 {
        let key = TexKey {
            image: tex.source().index(),
            sampler: tex.sampler().index(),
            srgb,
        };
        *self.by_key.entry(key).or_insert_with(|| {
            self.keys.push(key);
            (self.keys.len() - 1) as u32
        })
    }

    fn info(&mut self, info: Option<gltf::texture::Info<'_>>, srgb: bool) -> Option<TextureRef> {
        let info = info?;
        let mut tex_coord = info.tex_coord();
        let transform = info.texture_transform().map(|t| {
            if let Some(tc) = t.tex_coord() {
                tex_coord = tc;
            }
            TextureTransform {
                offset: t.offset().into(),
                rotation: t.rotation(),
                scale: t.scale().into(),
            }
        });
        Some(TextureRef {
            texture: self.texture(&info.texture(), srgb),
            tex_coord,
            transform,
        })
    }

    fn linear(
        &mut self,
        tex: gltf::Texture<'_>,
        tex_coord: u32,
        ext: Option<&Value>,
    ) -> TextureRef {
        self.linear_or_srgb(tex, tex_coord, ext, false)
    }

    /// A texture reference from its parts, `ext` being its `KHR_texture_transform` JSON.
    pub(crate) fn linear_or_srgb(
        &mut self,
        tex: gltf::Texture<'_>,
        tex_coord: u32,
        ext: Option<&Value>,
        srgb: bool,
    ) -> TextureRef {
        let mut tex_coord = tex_coord;
        let transform = ext.map(|v| {
            let (t, tc) = transform_from_json(v);
            if let Some(tc) = tc {
                tex_coord = tc;
            }
            t
        });
        TextureRef {
            texture: self.texture(&tex, srgb),
            tex_coord,
            transform,
        }
    }

    /// Our index of each glTF material built so far (for animation pointers).
    pub fn gltf_indices(&self) -> HashMap<usize, u32> {
        self.by_gltf
            .iter()
            .filter_map(|(k, v)| Some(((*k)?, *v)))
            .collect()
    }

    /// Our index of a glTF material (None = the glTF default material), creating it on first use.
    pub fn get(&mut self, doc: &gltf::Document, index: Option<usize>) -> u32 {
        if let Some(&i) = self.by_gltf.get(&index) {
            return i;
        }
        let m = match index.and_then(|i| doc.materials().nth(i)) {
            Some(m) => self.build(doc, &m),
            None => Material::default(),
        };
        self.materials.push(m);
        let i = (self.materials.len() - 1) as u32;
        self.by_gltf.insert(index, i);
        i
    }

    fn build(&mut self, doc: &gltf::Document, m: &gltf::Material<'_>) -> Material {
        self.warnings.extend(degrade_warnings(m));
        let pbr = m.pbr_metallic_roughness();
        let base_color_texture = self.info(pbr.base_color_texture(), true);
        let metallic_roughness_texture = self.info(pbr.metallic_roughness_texture(), false);
        let normal = m.normal_texture();
        let normal_scale = normal.as_ref().map_or(1.0, |n| n.scale());
        let normal_texture = normal.map(|n| {
            self.linear(
                n.texture(),
                n.tex_coord(),
                n.extension_value("KHR_texture_transform"),
            )
        });
        let occlusion = m.occlusion_texture();
        let occlusion_strength = occlusion.as_ref().map_or(1.0, |o| o.strength());
        let occlusion_texture = occlusion.map(|o| {
            self.linear(
                o.texture(),
                o.tex_coord(),
                o.extension_value("KHR_texture_transform"),
            )
        });
        let emissive_texture = self.info(m.emissive_texture(), true);
        let specular = m.specular();
        let specular_texture = specular
            .as_ref()
            .and_then(|s| self.info(s.specular_texture(), false));
        let specular_color_texture = specular
            .as_ref()
            .and_then(|s| self.info(s.specular_color_texture(), true));
        let mut out = Material {
            name: m.name().map(str::to_owned),
            base_color_factor: Vec4::from(pbr.base_color_factor()),
            base_color_texture,
            metallic_factor: pbr.metallic_factor(),
            roughness_factor: pbr.roughness_factor(),
            metallic_roughness_texture,
            normal_texture,
            normal_scale,
            occlusion_texture,
            occlusion_strength,
            emissive_factor: Vec3::from(m.emissive_factor()),
            emissive_texture,
            emissive_strength: m.emissive_strength().unwrap_or(1.0),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                    cutoff: m.alpha_cutoff().unwrap_or(0.5),
                },
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            double_sided: m.double_sided(),
            unlit: m.unlit(),
            ior: m.ior().unwrap_or(1.5),
            specular_factor: specular.as_ref().map_or(1.0, |s| s.specular_factor()),
            specular_color_factor: specular
                .as_ref()
                .map_or(Vec3::ONE, |s| Vec3::from(s.specular_color_factor())),
            specular_texture,
            specular_color_texture,
            ..Material::default()
        };
        self.read_extensions(doc, m, &mut out);
        out
    }

    /// Decodes the referenced images (each once, in parallel) and builds the textures.
    /// With `skip` every texture is a 1×1 white placeholder.
    pub fn textures(
        &self,
        doc: &gltf::Document,
        buffers: &Buffers,
        base_dir: &Path,
        skip: bool,
        budget: &aperture_budget::MemoryBudget,
    ) -> Result<Vec<Texture>, Error> {
        let sampler_of = |s| sampler_of(doc, s);
        let image_name = |i| image_name(doc, i);
        if skip {
            return Ok(self
                .keys
                .iter()
                .map(|k| Texture {
                    name: image_name(k.image),
                    width: 1,
                    height: 1,
                    texels: Texels::Rgba8(vec![[255; 4]]),
                    color_space: color_space(k.srgb),
                    sampler: sampler_of(k.sampler),
                })
                .collect());
        }
        let mut images: Vec<usize> = self.keys.iter().map(|k| k.image).collect();
        images.sort_unstable();
        images.dedup();
        let mut uses_left = vec![0usize; images.len()];
        for k in &self.keys {
            if let Ok(s) = images.binary_search(&k.image) {
                uses_left[s] += 1;
            }
        }
        let decoded =
            crate::texels::decode_images(doc, buffers, base_dir, &images, &uses_left, budget)?;
        let mut slot: Vec<Option<(u32, u32, Texels)>> = decoded.into_iter().map(Some).collect();
        let mut out = Vec::with_capacity(self.keys.len());
        for k in &self.keys {
            let Ok(s) = images.binary_search(&k.image) else {
                continue;
            };
            uses_left[s] -= 1;
            // The last use takes the texels; earlier ones (same image, other sampler or
            // colour space) get a copy.
            let (w, h, texels) = if uses_left[s] == 0 {
                slot[s].take()
            } else {
                slot[s].clone()
            }
            .ok_or_else(|| Error::Invalid {
                at: format!("images[{}]", k.image),
                reason: "decoded image missing".into(),
            })?;
            out.push(Texture {
                name: image_name(k.image),
                width: w,
                height: h,
                texels,
                color_space: color_space(k.srgb),
                sampler: sampler_of(k.sampler),
            });
        }
        Ok(out)
    }
}

/// The sampler at index `s` of the file (the glTF default without one).
fn sampler_of(doc: &gltf::Document, s: Option<usize>) -> Sampler {
    s.and_then(|i| doc.samplers().nth(i))
        .map_or(Sampler::default(), |s| {
            let wrap = |w| match w {
                gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
                gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
                gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            };
            Sampler {
                wrap_u: wrap(s.wrap_s()),
                wrap_v: wrap(s.wrap_t()),
                mag_filter: match s.mag_filter() {
                    Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
                    _ => Filter::Linear,
                },
            }
        })
}

/// An image's name for messages and listings: its `name`, else its external URI.
fn image_name(doc: &gltf::Document, i: usize) -> Option<String> {
    doc.images().nth(i).and_then(|im| {
        im.name().map(str::to_owned).or(match im.source() {
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                Some(uri.to_owned())
            }
            _ => None,
        })
    })
}

/// The colour space of a texture used as colour (`srgb`) or as data.
fn color_space(srgb: bool) -> ColorSpace {
    if srgb {
        ColorSpace::Srgb
    } else {
        ColorSpace::Linear
    }
}
