//! The extended material at a surface point: every extension's factor times its texture
//! (each through its own `texCoord` and `KHR_texture_transform`), turned into the parameters
//! of [`Principled`]. Materials without extended lobes never come here.

use crate::bsdf::{Bsdf, CoatLayer, Principled, SheenLayer, ThinFilm};
use crate::surface::{Geometry, Shading, Surface};
use aperture_scene::Material;
use glam::{Vec2, Vec3, Vec4Swizzles};

/// F0 of glTF's default IOR 1.5, against which specular-glossiness F0 is a tint.
const F0_IOR_1_5: f32 = 0.04;

fn finite_or(x: f32, default: f32) -> f32 {
    if x.is_finite() {
        x
    } else {
        default
    }
}

impl Geometry<'_> {
    /// The extended BSDF of `m` at `s` (`base` and `emission` already evaluated, `normal` the
    /// mapped shading normal).
    pub fn shade_extended(
        &self,
        m: &Material,
        s: &Surface,
        base: Vec3,
        emission: Vec3,
        normal: Vec3,
    ) -> Shading {
        let mut p = self.base_layer(m, s, base);
        let tangent = self.anisotropy(m, s, normal, &mut p);
        if let Some(t) = m.transmission {
            p.transmission = (t.factor * self.lookup(&t.texture, s).x).clamp(0.0, 1.0);
        }
        if let Some(d) = m.diffuse_transmission {
            p.diffuse_transmission = (d.factor * self.lookup(&d.texture, s).w).clamp(0.0, 1.0);
            p.diffuse_transmission_color = (d.color_factor
                * self.lookup(&d.color_texture, s).xyz())
            .clamp(Vec3::ZERO, Vec3::ONE);
        }
        if let Some(sh) = m.sheen {
            let color = (sh.color_factor * self.lookup(&sh.color_texture, s).xyz())
                .clamp(Vec3::ZERO, Vec3::ONE);
            if color.max_element() > 0.0 {
                p.sheen = Some(SheenLayer {
                    color,
                    roughness: (sh.roughness_factor * self.lookup(&sh.roughness_texture, s).w)
                        .clamp(0.0, 1.0),
                });
            }
        }
        if let Some(c) = m.clearcoat {
            let weight = (c.factor * self.lookup(&c.texture, s).x).clamp(0.0, 1.0);
            if weight > 0.0 {
                p.coat = Some(CoatLayer {
                    weight,
                    roughness: (c.roughness_factor * self.lookup(&c.roughness_texture, s).y)
                        .clamp(0.0, 1.0),
                    normal: self.mapped_normal(&c.normal_texture, c.normal_scale, s),
                });
            }
        }
        if let Some(i) = m.iridescence {
            let factor = (i.factor * self.lookup(&i.texture, s).x).clamp(0.0, 1.0);
            if factor > 0.0 {
                let thickness = match i.thickness_texture {
                    Some(_) => {
                        let g = self.lookup(&i.thickness_texture, s).y;
                        i.thickness_min + (i.thickness_max - i.thickness_min) * g
                    }
                    None => i.thickness_max,
                };
                p.thin_film = Some(ThinFilm {
                    factor,
                    ior: i.ior,
                    thickness: finite_or(thickness, 0.0).max(0.0),
                });
            }
        }
        Shading {
            bsdf: Some(Bsdf::Principled(Box::new(p))),
            emission,
            unlit: None,
            normal,
            tangent,
        }
    }

    /// Base colour, metal, roughness and the specular layer's IOR and tint, from
    /// metallic-roughness or (converted as the Khronos sample viewer does) from
    /// specular-glossiness.
    fn base_layer(&self, m: &Material, s: &Surface, base: Vec3) -> Principled {
        let base = base.min(Vec3::ONE);
        if let Some(sg) = m.specular_glossiness {
            let t = self.lookup(&sg.specular_glossiness_texture, s);
            let gloss = (sg.glossiness_factor * t.w).clamp(0.0, 1.0);
            let mut p = Principled::new(base, 0.0, 1.0 - gloss);
            p.specular_color = (sg.specular_factor * t.xyz() / F0_IOR_1_5).max(Vec3::ZERO);
            return p;
        }
        let mr = self.lookup(&m.metallic_roughness_texture, s);
        let metallic = finite_or(m.metallic_factor * mr.z, 0.0);
        let roughness = finite_or(m.roughness_factor * mr.y, 1.0);
        let mut p = Principled::new(base, metallic, roughness);
        p.ior = if m.ior == 0.0 || (m.ior.is_finite() && m.ior >= 1.0) {
            m.ior
        } else {
            1.5
        };
        p.specular = finite_or(
            m.specular_factor * self.lookup(&m.specular_texture, s).w,
            1.0,
        )
        .clamp(0.0, 1.0);
        let tint = m.specular_color_factor * self.lookup(&m.specular_color_texture, s).xyz();
        p.specular_color = if tint.is_finite() {
            tint.max(Vec3::ZERO)
        } else {
            Vec3::ONE
        };
        p
    }

    /// `KHR_materials_anisotropy`: stretches the specular roughness along a direction of the
    /// tangent plane; returns that direction (world), which the shading frame's x axis must
    /// follow. Without a tangent frame the direction is undefined and the lobe stays isotropic.
    fn anisotropy(
        &self,
        m: &Material,
        s: &Surface,
        normal: Vec3,
        p: &mut Principled,
    ) -> Option<Vec3> {
        let a = m.anisotropy?;
        let (dir, strength) = match a.texture {
            Some(_) => {
                let t = self.lookup(&a.texture, s);
                let d = Vec2::new(t.x, t.y) * 2.0 - Vec2::ONE;
                (d.try_normalize().unwrap_or(Vec2::X), a.strength * t.z)
            }
            None => (Vec2::X, a.strength),
        };
        let strength = finite_or(strength, 0.0).clamp(0.0, 1.0);
        if strength <= 0.0 || s.tangent.xyz() == Vec3::ZERO {
            return None;
        }
        let t = (s.tangent.xyz() - normal * normal.dot(s.tangent.xyz())).try_normalize()?;
        let b = normal.cross(t) * s.tangent.w;
        let (sin, cos) = finite_or(a.rotation, 0.0).sin_cos();
        let d = Vec2::new(cos * dir.x - sin * dir.y, sin * dir.x + cos * dir.y);
        let world = (t * d.x + b * d.y).try_normalize()?;
        let alpha = p.alpha.y;
        p.alpha = Vec2::new(alpha + (1.0 - alpha) * strength * strength, alpha);
        Some(world)
    }
}

impl Geometry<'_> {
    /// What light a thin-walled transmissive surface at `s` lets through straight along `dir`
    /// (a shadow ray's transmittance): what alpha lets pass, plus over the rest the ideal
    /// straight transmission of its BSDF (zero where the surface is rough: light through it
    /// scatters, so no straight line exists).
    pub fn pane_transmittance(&self, s: &Surface, dir: Vec3, energy: bool) -> Vec3 {
        let free = self.transmittance(s);
        if free >= 1.0 {
            return Vec3::ONE;
        }
        let mut shading = self.shade(s);
        let wo = -dir;
        let ng = if s.ng.dot(wo) < 0.0 { -s.ng } else { s.ng };
        let ns = crate::surface::view_normal(s, &shading, ng, wo);
        let Some(mut bsdf) = shading.bsdf.take() else {
            return Vec3::splat(free);
        };
        let (frame, wo_l) = crate::surface::shading_frame(ns, ng, shading.tangent, wo);
        bsdf.prepare(&frame, wo_l, crate::bsdf::Interface::Thin, energy);
        Vec3::splat(free) + (1.0 - free) * bsdf.straight_transmittance(wo_l)
    }
}
