//! Drawing directions from the extended material: one lobe by its albedo estimate, then a
//! direction from that lobe (ideal lobes as delta samples).

use super::{Interface, Principled, COAT, COAT_F0, DIFFUSE, SHEEN, SPEC};
use crate::bsdf::fresnel::{refract, schlick};
use crate::bsdf::{cosine_hemisphere, BsdfSample, Lobe};
use glam::Vec3;

impl Principled {
    /// Draws an incident direction for `wo` (local, `wo.z > 0`).
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: [f32; 2]) -> Option<BsdfSample> {
        let cdf = self.view.cdf;
        let k = cdf.iter().position(|&c| u_lobe < c)?;
        let lo = if k == 0 { 0.0 } else { cdf[k - 1] };
        let p = cdf[k] - lo;
        let u_rest = ((u_lobe - lo) / p).clamp(0.0, 1.0 - f32::EPSILON);
        let wi = match k {
            COAT => return self.sample_coat(wo, u, p),
            SPEC => return self.sample_spec(wo, u_rest, u, p),
            SHEEN | DIFFUSE => cosine_hemisphere(u),
            _ => {
                let w = cosine_hemisphere(u);
                w.with_z(-w.z)
            }
        };
        self.finish(wo, wi)
    }

    /// A sample of the non-delta lobes in direction `wi`, with their combined density.
    fn finish(&self, wo: Vec3, wi: Vec3) -> Option<BsdfSample> {
        let (f, pdf) = self.eval(wo, wi);
        (pdf > 0.0 && wi.z != 0.0 && f.is_finite()).then_some(BsdfSample {
            wi,
            f,
            pdf,
            delta: None,
        })
    }

    fn sample_coat(&self, wo: Vec3, u: [f32; 2], p: f32) -> Option<BsdfSample> {
        let (c, cv) = (self.coat?, self.view.coat?);
        if cv.ggx.is_delta() {
            let wi_c = Vec3::new(-cv.wo.x, -cv.wo.y, cv.wo.z);
            let wi = cv.frame.to_world(wi_c);
            if wi.z <= 0.0 {
                return None;
            }
            let f = c.weight * schlick(Vec3::splat(COAT_F0), cv.wo.z).x;
            return Some(BsdfSample::ideal(
                wi,
                Vec3::splat(f / p),
                Lobe::Glossy,
                false,
            ));
        }
        let m = cv.ggx.sample_vndf(cv.wo, u);
        let wi = cv.frame.to_world(2.0 * cv.wo.dot(m) * m - cv.wo);
        if wi.z <= 0.0 {
            return None;
        }
        self.finish(wo, wi)
    }

    fn sample_spec(&self, wo: Vec3, u_rest: f32, u: [f32; 2], p: f32) -> Option<BsdfSample> {
        let Some(g) = self.view.ggx else {
            // Ideal mirror and refractor.
            let (r, t, p_r) = self.spec_weights(wo.z);
            if u_rest < p_r {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                let k = self.below(wo.z) / (p * p_r);
                let mut s = BsdfSample::ideal(wi, r * k, Lobe::Glossy, false);
                if let (Interface::Refractive { eta }, Some(d)) =
                    (self.view.interface, &mut s.delta)
                {
                    d.internal = refract(wo, Vec3::Z, eta).is_none();
                }
                return Some(s);
            }
            let k = self.below(wo.z) / (p * (1.0 - p_r));
            return match self.view.interface {
                Interface::Opaque => None,
                Interface::Thin => Some(BsdfSample::ideal(-wo, t * k, Lobe::Transmission, true)),
                Interface::Refractive { eta } => {
                    let wi = refract(wo, Vec3::Z, eta)?;
                    let w = t * (k / (eta * eta));
                    let straight = (eta - 1.0).abs() < 1e-4;
                    Some(BsdfSample::ideal(wi, w, Lobe::Transmission, straight))
                }
            };
        };
        let m = g.sample_vndf(wo, u);
        let om = wo.dot(m);
        let (_, _, p_r) = self.spec_weights(om);
        let wi = if u_rest < p_r {
            Some(2.0 * om * m - wo).filter(|r| r.z > 0.0)
        } else {
            match self.view.interface {
                Interface::Opaque => None,
                Interface::Thin => {
                    // The mirror image of the reflection through the surface plane.
                    let r = 2.0 * om * m - wo;
                    (r.z > 0.0).then(|| r.with_z(-r.z))
                }
                Interface::Refractive { eta } => refract(wo, m, eta).filter(|t| t.z < 0.0),
            }
        }?;
        self.finish(wo, wi)
    }

    /// The fraction of light passing straight through (thin-walled ideal transmission) along
    /// the view direction: what a shadow ray through this surface carries. Zero unless the
    /// surface is thin-walled and its specular layer an ideal one.
    pub fn straight_transmittance(&self, wo: Vec3) -> Vec3 {
        if self.view.interface != Interface::Thin || self.view.ggx.is_some() {
            return Vec3::ZERO;
        }
        let (_, t, _) = self.spec_weights(wo.z);
        self.below(wo.z) * t
    }
}
