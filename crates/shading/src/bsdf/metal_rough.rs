//! glTF metallic-roughness (glTF 2.0 Appendix B): a Lambertian base under a GGX/Smith specular
//! layer mixed by Schlick's Fresnel, and a GGX conductor with F0 = base colour, mixed by
//! `metallic`. The dielectric F0 is 0.04 by default; `KHR_materials_ior` and
//! `KHR_materials_specular` change it (F0 = ((ior − 1)/(ior + 1))² × specular colour, capped
//! at one) and weight the layer by the specular factor, exactly as those extensions'
//! `fresnel_mix` does: `(1 − w · max(F)) · diffuse + w · F · specular`.
//!
//! With energy compensation ([`MetalRough::compensate`]), the specular lobes get Turquin's
//! multiple-scattering factor and the diffuse base is weighted by what the specular layer does
//! not reflect at this view (albedo scaling) instead of `1 − w · max(F(v·h))`: Appendix B's
//! layering reflects more than it receives at grazing views (7 % at μ = 0.2), which no white
//! furnace may show. Without it the lobe is Appendix B's, bit for bit.

use super::common::{env_brdf, Albedos, LobeSplit};
use super::energy::{ggx_albedo, multiple_scattering, schlick_average};
use super::fresnel::schlick_weight;
use super::ggx::{ggx_d, sample_vndf, smith_g1, smith_v};
use crate::warp::cosine_hemisphere;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The energy-compensation weights of one view (see [`MetalRough::compensate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Compensation {
    /// Multiplies the conductor lobe.
    pub metal: Vec3,
    /// Multiplies the dielectric specular lobe.
    pub dielectric: f32,
    /// Weight of the diffuse base: `1 − w · max(E_spec)`.
    pub diffuse: f32,
}

/// glTF metallic-roughness parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetalRough {
    /// Base colour (linear).
    pub base: Vec3,
    /// Metallic in `[0, 1]`.
    pub metallic: f32,
    /// GGX alpha = perceptual roughness².
    pub alpha: f32,
    /// Dielectric reflectance at normal incidence (0.04 for glTF's default IOR 1.5).
    pub f0: Vec3,
    /// Dielectric specular weight (`KHR_materials_specular`'s factor, 1 by default).
    pub spec_weight: f32,
    /// Energy compensation at the current view; `None`: Appendix B's single scattering.
    pub compensation: Option<Compensation>,
}

impl MetalRough {
    /// Fills [`MetalRough::compensation`] for view cosine `nv`.
    pub fn compensate(&mut self, nv: f32) {
        let (a, b) = ggx_albedo(nv, self.alpha);
        let ms_metal = multiple_scattering(nv, self.alpha, schlick_average(self.base));
        let ms_dielectric = multiple_scattering(
            nv,
            self.alpha,
            schlick_average(Vec3::splat(self.f0.max_element())),
        )
        .x;
        let e_spec = (self.f0 * a + Vec3::splat(b)) * ms_dielectric;
        self.compensation = Some(Compensation {
            metal: ms_metal,
            dielectric: ms_dielectric,
            diffuse: (1.0 - self.spec_weight * e_spec.max_element()).max(0.0),
        });
    }

    /// Probability of drawing the specular lobe, from the Fresnel weight at normal view.
    fn specular_probability(&self, nv: f32) -> f32 {
        let f0 = self.f0.max_element();
        let fd = self.spec_weight * (f0 + (1.0 - f0) * schlick_weight(nv));
        let spec = self.metallic + (1.0 - self.metallic) * fd;
        let diff = (1.0 - self.metallic) * (1.0 - fd) * self.base.max_element();
        if diff <= 0.0 {
            1.0
        } else {
            (spec / (spec + diff)).clamp(0.1, 0.9)
        }
    }

    /// The value at (`wo`, `wi`) given their half vector `h` and `d = D(h)`.
    fn value(&self, wo: Vec3, wi: Vec3, h: Vec3, a2: f32, d: f32) -> Vec3 {
        let voh = wo.dot(h).max(0.0);
        let spec = smith_v(wi.z, wo.z, a2) * d;
        let w = schlick_weight(voh);
        let f_dielectric = self.f0 + (Vec3::ONE - self.f0) * w;
        match self.compensation {
            None => {
                let dielectric =
                    (1.0 - self.spec_weight * f_dielectric.max_element()) * self.base * FRAC_1_PI
                        + self.spec_weight * f_dielectric * spec;
                let metal = (self.base + (Vec3::ONE - self.base) * w) * spec;
                dielectric.lerp(metal, self.metallic)
            }
            Some(c) => {
                let dielectric = c.diffuse * self.base * FRAC_1_PI
                    + self.spec_weight * f_dielectric * (spec * c.dielectric);
                let metal = (self.base + (Vec3::ONE - self.base) * w) * c.metal * spec;
                dielectric.lerp(metal, self.metallic)
            }
        }
    }

    /// Value (without cosine) and solid-angle density; `wo.z > 0` and `wi.z > 0`.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let h = (wo + wi).normalize();
        let a2 = self.alpha * self.alpha;
        let d = ggx_d(h.z, a2);
        let f = self.value(wo, wi, h, a2, d);
        let p_spec = self.specular_probability(wo.z);
        let pdf_spec = smith_g1(wo.z, a2) * d / (4.0 * wo.z);
        let pdf = p_spec * pdf_spec + (1.0 - p_spec) * wi.z * FRAC_1_PI;
        (f, pdf)
    }

    /// Draws an incident direction (not checked against the horizon).
    pub fn sample_direction(&self, wo: Vec3, u_lobe: f32, u: [f32; 2]) -> Vec3 {
        if u_lobe < self.specular_probability(wo.z) {
            let m = sample_vndf(wo, self.alpha, u);
            2.0 * wo.dot(m) * m - wo
        } else {
            cosine_hemisphere(u)
        }
    }

    /// How the value at (`wo`, `wi`) splits between diffuse and glossy.
    pub fn lobe_split(&self, wo: Vec3, wi: Vec3) -> LobeSplit {
        let f = self.eval(wo, wi).0;
        let h = (wo + wi).normalize();
        let w = schlick_weight(wo.dot(h).max(0.0));
        let f_dielectric = self.f0 + (Vec3::ONE - self.f0) * w;
        let weight = match self.compensation {
            None => 1.0 - self.spec_weight * f_dielectric.max_element(),
            Some(c) => c.diffuse,
        };
        let d = (1.0 - self.metallic) * weight * self.base * FRAC_1_PI;
        let frac = |d: f32, f: f32| {
            if f > 0.0 {
                (d / f).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let diffuse = Vec3::new(frac(d.x, f.x), frac(d.y, f.y), frac(d.z, f.z));
        LobeSplit {
            diffuse,
            glossy: Vec3::ONE - diffuse,
            transmission: Vec3::ZERO,
        }
    }

    /// Each lobe's directional albedo seen from `wo`.
    pub fn albedos(&self, wo: Vec3) -> Albedos {
        let nv = wo.z.clamp(0.0, 1.0);
        let r = self.alpha.sqrt();
        let (diffuse_weight, ms_metal, ms_dielectric) = match self.compensation {
            None => {
                let fd = self.spec_weight
                    * (self.f0 + (Vec3::ONE - self.f0) * schlick_weight(nv)).max_element();
                (1.0 - fd, Vec3::ONE, 1.0)
            }
            Some(c) => (c.diffuse, c.metal, c.dielectric),
        };
        Albedos {
            diffuse: (1.0 - self.metallic) * diffuse_weight * self.base,
            glossy: self.metallic * env_brdf(self.base, r, nv) * ms_metal
                + (1.0 - self.metallic)
                    * self.spec_weight
                    * env_brdf(self.f0, r, nv)
                    * ms_dielectric,
            transmission: Vec3::ZERO,
        }
    }
}
