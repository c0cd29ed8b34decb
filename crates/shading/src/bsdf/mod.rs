//! Scattering at a surface point, in a local frame whose +Z is the shading normal. Callers
//! orient the frame so `wo.z > 0` (both sides are shaded).
//!
//! - [`Bsdf::Lambert`]: the material override's clay.
//! - [`Bsdf::MetalRough`]: glTF metallic-roughness (Appendix B) with `KHR_materials_ior` and
//!   `KHR_materials_specular` ([`metal_rough`]), what every material without the extended
//!   lobes is.
//! - [`Bsdf::Principled`]: the extended material of SPEC §5 ([`principled`]): transmission,
//!   volume boundaries, clear coat, sheen, anisotropy, iridescence, diffuse transmission.
//!
//! Microfacet lobes are GGX with height-correlated Smith masking ([`ggx`]); directions are
//! drawn from the visible normals (Heitz 2018). Energy compensation ([`energy`]) is applied by
//! [`Bsdf::prepare`] at each view.

mod common;
mod energy;
mod fresnel;
mod ggx;
pub mod metal_rough;
pub mod principled;
mod sheen;

pub use metal_rough::{Compensation, MetalRough};
pub use principled::{CoatLayer, Interface, Principled, SheenLayer, ThinFilm};

pub use crate::warp::cosine_hemisphere;
pub use common::{
    bend_towards, env_brdf, Albedos, Frame, Lobe, LobeSplit, MIN_VIEW_COS, ROUGH_ALPHA,
};

use ggx::MIN_ALPHA;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// A surface's scattering function.
#[derive(Debug, Clone, PartialEq)]
pub enum Bsdf {
    /// Ideal diffuse reflection (the material override's clay).
    Lambert {
        /// Reflectance.
        albedo: Vec3,
    },
    /// glTF metallic-roughness.
    MetalRough(MetalRough),
    /// The extended material (transmission, coat, sheen, anisotropy, iridescence …), boxed:
    /// it is five times the size of the others, and every hit moves a `Bsdf` around (a
    /// measured 1.5 % of an opaque scene's instructions when it was inline).
    Principled(Box<Principled>),
}

/// Dielectric Fresnel parameters of `KHR_materials_ior` and `KHR_materials_specular`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dielectric {
    /// Index of refraction (glTF default 1.5).
    pub ior: f32,
    /// Specular weight (`specularFactor` × texture alpha).
    pub specular: f32,
    /// Specular F0 tint (`specularColorFactor` × texture).
    pub specular_color: Vec3,
}

impl Default for Dielectric {
    /// glTF's defaults: IOR 1.5 (F0 = 0.04), untinted, full weight.
    fn default() -> Self {
        Self {
            ior: 1.5,
            specular: 1.0,
            specular_color: Vec3::ONE,
        }
    }
}

impl Dielectric {
    /// F0 and weight: `min(((ior − 1)/(ior + 1))² · colour, 1)` and the weight clamped to [0, 1].
    /// Bad values (NaN, negative) fall back to the defaults instead of poisoning the image.
    fn f0_and_weight(&self) -> (Vec3, f32) {
        // KHR_materials_ior allows ior = 0 to mean "infinitely reflective" (F0 = 1).
        let r = if self.ior == 0.0 {
            1.0
        } else if self.ior.is_finite() && self.ior >= 1.0 {
            ((self.ior - 1.0) / (self.ior + 1.0)).powi(2)
        } else {
            0.04
        };
        let tint = if self.specular_color.is_finite() {
            self.specular_color.max(Vec3::ZERO)
        } else {
            Vec3::ONE
        };
        let w = if self.specular.is_finite() {
            self.specular.clamp(0.0, 1.0)
        } else {
            1.0
        };
        ((r * tint).min(Vec3::ONE), w)
    }
}

/// An ideal specular direction: no density exists, only the throughput it carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeltaSample {
    /// `f · |cos| / pdf` of the sample.
    pub weight: Vec3,
    /// Which lobe.
    pub lobe: Lobe,
    /// True when the direction is the view's continuation (`wi = −wo`, thin-walled
    /// transmission): the path goes on along a straight line.
    pub straight: bool,
    /// True for total internal reflection: the only way light could go, not a choice.
    pub internal: bool,
}

impl BsdfSample {
    /// An ideal specular sample in direction `wi` carrying `weight`.
    pub fn ideal(wi: Vec3, weight: Vec3, lobe: Lobe, straight: bool) -> Self {
        Self {
            wi,
            f: Vec3::ZERO,
            pdf: 0.0,
            delta: Some(DeltaSample {
                weight,
                lobe,
                straight,
                internal: false,
            }),
        }
    }
}

/// A sampled direction with its value and density.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSample {
    /// Incident direction, local (below the surface for transmission).
    pub wi: Vec3,
    /// BSDF value (without the cosine); zero for a delta sample.
    pub f: Vec3,
    /// Solid-angle density of `wi`; zero for a delta sample.
    pub pdf: f32,
    /// Set when the direction is an ideal specular one.
    pub delta: Option<DeltaSample>,
}

impl BsdfSample {
    /// The throughput the sample carries: `f · |cos| / pdf`, or the delta weight.
    pub fn weight(&self) -> Vec3 {
        match self.delta {
            Some(d) => d.weight,
            None => self.f * (self.wi.z.abs() / self.pdf),
        }
    }
}

impl Bsdf {
    /// glTF metallic-roughness from its factors (roughness is perceptual).
    pub fn metal_rough(base: Vec3, metallic: f32, roughness: f32) -> Self {
        Self::metal_rough_dielectric(base, metallic, roughness, &Dielectric::default())
    }

    /// glTF metallic-roughness with the dielectric layer of `KHR_materials_ior` and
    /// `KHR_materials_specular`.
    pub fn metal_rough_dielectric(
        base: Vec3,
        metallic: f32,
        roughness: f32,
        dielectric: &Dielectric,
    ) -> Self {
        let r = roughness.clamp(0.0, 1.0);
        let (f0, spec_weight) = dielectric.f0_and_weight();
        let metallic = if metallic.is_nan() { 0.0 } else { metallic };
        if metallic <= 0.0 && spec_weight == 0.0 {
            // No specular layer at all (`KHR_materials_specular` factor 0 on a dielectric): the
            // glTF BSDF is exactly Lambert. Saying so skips the GGX terms in every evaluation
            // and stops the 10 % of samples the lobe mixture would send to a lobe of weight 0.
            return Self::Lambert { albedo: base };
        }
        Self::MetalRough(MetalRough {
            base,
            metallic: metallic.clamp(0.0, 1.0),
            alpha: (r * r).max(MIN_ALPHA),
            f0,
            spec_weight,
            compensation: None,
        })
    }

    /// Computes what depends on the view `wo` (local to `frame`, `wo.z > 0`): energy
    /// compensation when `energy`, and for the extended material its layers' weights, the
    /// `interface` its transmission crosses and its coat normal in `frame`.
    pub fn prepare(&mut self, frame: &Frame, wo: Vec3, interface: Interface, energy: bool) {
        match self {
            Self::Lambert { .. } => {}
            Self::MetalRough(m) => {
                if energy {
                    m.compensate(wo.z);
                }
            }
            Self::Principled(p) => p.prepare(frame, wo, interface, energy),
        }
    }

    /// True when some lobe may send light through the surface (both hemispheres matter).
    pub fn transmits(&self) -> bool {
        match self {
            Self::Principled(p) => p.transmits(),
            _ => false,
        }
    }

    /// Value (without cosine) and solid-angle density for the pair of local directions;
    /// delta lobes contribute nothing. Inline: the clay's arm is a few multiplies, which a call
    /// and a result passed through memory would cost more than.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if wo.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        match self {
            Self::Principled(p) => p.eval(wo, wi),
            _ if wi.z <= 0.0 => (Vec3::ZERO, 0.0),
            Self::Lambert { albedo } => (*albedo * FRAC_1_PI, wi.z * FRAC_1_PI),
            Self::MetalRough(m) => m.eval(wo, wi),
        }
    }

    /// Draws an incident direction for `wo` (local, `wo.z > 0`). Always inline: a call returns
    /// the sample through memory, and the clay's few operations wait on that copy.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: [f32; 2]) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = match self {
            Self::Lambert { .. } => cosine_hemisphere(u),
            Self::MetalRough(m) => m.sample_direction(wo, u_lobe, u),
            Self::Principled(p) => return p.sample(wo, u_lobe, u),
        };
        let (f, pdf) = self.eval(wo, wi);
        (pdf > 0.0 && wi.z > 0.0).then_some(BsdfSample {
            wi,
            f,
            pdf,
            delta: None,
        })
    }

    /// Throughput of light passing straight through the surface along the view (thin-walled
    /// ideal transmission); zero for every other surface.
    pub fn straight_transmittance(&self, wo: Vec3) -> Vec3 {
        match self {
            Self::Principled(p) => p.straight_transmittance(wo),
            _ => Vec3::ZERO,
        }
    }
}

impl Bsdf {
    /// How the value at (`wo`, `wi`) splits between the lobes.
    pub fn lobe_split(&self, wo: Vec3, wi: Vec3) -> LobeSplit {
        match self {
            Self::Lambert { .. } => LobeSplit::DIFFUSE,
            Self::MetalRough(m) => m.lobe_split(wo, wi),
            Self::Principled(p) => p.lobe_split(wo, wi),
        }
    }

    /// Each lobe's directional albedo seen from `wo` (local, `wo.z > 0`).
    pub fn albedos(&self, wo: Vec3) -> Albedos {
        match self {
            Self::Lambert { albedo } => Albedos {
                diffuse: *albedo,
                ..Albedos::default()
            },
            Self::MetalRough(m) => m.albedos(wo),
            Self::Principled(p) => p.albedos(wo),
        }
    }

    /// True when the specular lobe is rough enough to count as a surface for denoising
    /// features (Cycles: α > 0.075); a sharper one is followed to what it reflects.
    pub fn glossy_is_rough(&self) -> bool {
        match self {
            Self::Lambert { .. } => true,
            Self::MetalRough(m) => m.alpha > ROUGH_ALPHA,
            Self::Principled(p) => p.glossy_is_rough(),
        }
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_principled;
