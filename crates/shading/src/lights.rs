//! Lights: punctual lights (sampled by next-event estimation only: they are deltas) and emissive
//! triangles, chosen in proportion to their power through an alias table, with a bound of what
//! they can send to a point (for the choice between them and the punctual lights,
//! [`crate::light_choice`]). The triangle structures exist only when the scene has emissive
//! triangles.

use crate::color::luminance;
use crate::light_bounds::LightBounds;
use crate::surface::Geometry;
use crate::warp::AliasTable;
#[cfg(test)]
use glam::Vec3;

/// One emissive triangle.
#[derive(Debug, Clone, Copy)]
pub struct EmissiveTriangle {
    /// Index of its instance in the scene.
    pub instance: u32,
    /// Index of the triangle in the instance's mesh.
    pub triangle: u32,
}

/// The emissive triangles of a scene, with their selection table.
#[derive(Debug)]
pub struct EmissiveLights {
    /// Every emissive triangle.
    pub triangles: Vec<EmissiveTriangle>,
    /// Selection table over `triangles`, by emitted power.
    pub table: AliasTable,
    /// Each triangle's emitted power, in the units of the punctual lights' importance.
    pub power: Vec<f32>,
    /// For each instance, the light index of each of its triangles (`u32::MAX` when not
    /// emissive); `None` for instances without emissive triangles.
    index: Vec<Option<Box<[u32]>>>,
    /// What they can send to a point, for the choice between them and punctual lights.
    pub bounds: LightBounds,
}

impl EmissiveLights {
    /// Collects emissive triangles; `None` when there are none (no structure is built).
    pub fn build(geom: &Geometry<'_>) -> Option<Self> {
        let scene = geom.scene;
        let emissive: Vec<bool> = scene.materials.iter().map(|m| m.is_emissive()).collect();
        if !emissive.iter().any(|&e| e) {
            return None;
        }
        let mut triangles = Vec::new();
        let mut weights = Vec::new();
        let mut index = Vec::with_capacity(scene.instances.len());
        for (ii, inst) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[inst.mesh as usize];
            let mut map: Option<Box<[u32]>> = None;
            for (ti, &mid) in scene.instance_materials(inst).iter().enumerate() {
                if !emissive.get(mid as usize).copied().unwrap_or(false) {
                    continue;
                }
                let w = triangle_power(geom, ii as u32, ti as u32);
                if !(w > 0.0 && w.is_finite()) {
                    continue;
                }
                map.get_or_insert_with(|| vec![u32::MAX; mesh.indices.len()].into())[ti] =
                    triangles.len() as u32;
                triangles.push(EmissiveTriangle {
                    instance: ii as u32,
                    triangle: ti as u32,
                });
                weights.push(w);
            }
            index.push(map);
        }
        if triangles.is_empty() {
            return None;
        }
        let corners = |t: &EmissiveTriangle| {
            [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
                .map(|(b1, b2)| geom.emitter_surface(t.instance, t.triangle, b1, b2).p)
        };
        let bounds = LightBounds::emitters(
            triangles
                .iter()
                .zip(&weights)
                .map(|(t, &w)| (corners(t), w as f32)),
        )?; // None only for non-finite corners, which a kept (finite-area) triangle has not.
        Some(Self {
            triangles,
            table: AliasTable::new(&weights),
            power: weights.iter().map(|&w| w as f32).collect(),
            index,
            bounds,
        })
    }

    /// Probability that light sampling picks this triangle (0 when it is not a light).
    pub fn pick_probability(&self, instance: u32, triangle: u32) -> f32 {
        self.light_index(instance, triangle)
            .map_or(0.0, |i| self.table.pmf(i))
    }

    /// The index in [`EmissiveLights::triangles`] of this triangle, if it is a light.
    pub fn light_index(&self, instance: u32, triangle: u32) -> Option<usize> {
        match self.index.get(instance as usize) {
            Some(Some(map)) => match map.get(triangle as usize) {
                Some(&i) if i != u32::MAX => Some(i as usize),
                _ => None,
            },
            _ => None,
        }
    }
}

/// Barycentrics where a triangle's emission is probed: the centroid and six points towards the
/// corners and edges, so a texture that lights only part of a triangle still gets weight.
const PROBES: [(f32, f32); 7] = [
    (1.0 / 3.0, 1.0 / 3.0),
    (0.1, 0.1),
    (0.8, 0.1),
    (0.1, 0.8),
    (0.45, 0.1),
    (0.45, 0.45),
    (0.1, 0.45),
];

/// A triangle's emitted power up to constant factors (π, two sides): area × mean luminance of
/// its radiance, the emissive texture included (probed at [`PROBES`]), so dark parts of an
/// emissive texture are rarely picked. Any weight is unbiased: a triangle the probes miss
/// (weight 0) is still found by BSDF sampling, which MIS then weights fully.
fn triangle_power(geom: &Geometry<'_>, instance: u32, triangle: u32) -> f64 {
    let m = geom.material(geom.surface(instance, triangle, 0.0, 0.0).material);
    let probes: &[(f32, f32)] = if m.emissive_texture.is_some() {
        &PROBES
    } else {
        &PROBES[..1]
    };
    let mut sum = 0.0f64;
    let mut area = 0.0f32;
    for &(b1, b2) in probes {
        let s = geom.surface(instance, triangle, b1, b2);
        area = s.area;
        sum += luminance(geom.emission(&s)).max(0.0) as f64;
    }
    sum / probes.len() as f64 * area as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emissive_structures_exist_only_with_emitters() {
        use crate::surface::{Geometry, MaterialOverride};
        let plain = crate::test_scenes::lit_plane(1.0);
        assert!(EmissiveLights::build(&Geometry::new(&plain, MaterialOverride::None)).is_none());
        let mut lit = plain.clone();
        lit.materials.push(crate::test_scenes::emitter(Vec3::ONE));
        // A material that nothing uses builds nothing either.
        assert!(EmissiveLights::build(&Geometry::new(&lit, MaterialOverride::None)).is_none());
        std::sync::Arc::make_mut(&mut lit.meshes[0]).material_ids[1] = 1;
        let em = EmissiveLights::build(&Geometry::new(&lit, MaterialOverride::None)).unwrap();
        assert_eq!(em.triangles.len(), 1);
        assert_eq!(em.pick_probability(0, 1), 1.0);
        assert_eq!(em.pick_probability(0, 0), 0.0);
    }

    /// Two equal emissive triangles, one under the black half of an emissive texture: the
    /// lit one is picked far more often.
    #[test]
    fn emissive_texture_weights_light_selection() {
        use crate::surface::{Geometry, MaterialOverride};
        use aperture_scene::{ColorSpace, Sampler, Texels, Texture, TextureRef};
        let mut s = crate::test_scenes::lit_plane(1.0);
        let mut m = crate::test_scenes::emitter(Vec3::ONE);
        m.emissive_texture = Some(TextureRef {
            texture: 0,
            tex_coord: 0,
            transform: None,
        });
        s.materials.push(m);
        let mid = (s.materials.len() - 1) as u32;
        let n = s.meshes[0].indices.len();
        std::sync::Arc::make_mut(&mut s.meshes[0]).material_ids = vec![mid; n];
        // The texture is white left of u = 0.5 and black right of it.
        s.textures.push(Texture {
            name: None,
            width: 2,
            height: 1,
            texels: Texels::Rgba8(vec![[255; 4], [0, 0, 0, 255]]),
            color_space: ColorSpace::Srgb,
            sampler: Sampler {
                wrap_u: aperture_scene::Wrap::ClampToEdge,
                wrap_v: aperture_scene::Wrap::ClampToEdge,
                mag_filter: aperture_scene::Filter::Nearest,
            },
        });
        // Two triangles of the same area with their own corners: triangle 0 samples the white
        // texel, triangle 1 the black one.
        let mesh = std::sync::Arc::make_mut(&mut s.meshes[0]);
        let p = [mesh.positions[0], mesh.positions[1], mesh.positions[2]];
        mesh.positions = [p, p.map(|v| v + Vec3::X)].concat();
        mesh.normals = vec![Vec3::Y; 6];
        mesh.indices = vec![[0, 1, 2], [3, 4, 5]];
        mesh.material_ids = vec![mid; 2];
        mesh.uv0 = [
            [glam::Vec2::new(0.1, 0.5); 3],
            [glam::Vec2::new(0.9, 0.5); 3],
        ]
        .concat();
        let geom = Geometry::new(&s, MaterialOverride::None);
        let em = EmissiveLights::build(&geom).unwrap();
        let (p0, p1) = (em.pick_probability(0, 0), em.pick_probability(0, 1));
        assert_eq!((p0, p1), (1.0, 0.0));
    }
}
