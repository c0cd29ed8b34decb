//! The extended material's value and density: each non-delta lobe's, summed.

use super::{Interface, Principled, COAT, COAT_F0, DIFFUSE, DIFFUSE_T, SHEEN, SPEC};
use crate::bsdf::fresnel::schlick;
use crate::bsdf::sheen;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

impl Principled {
    pub(super) fn lobes(&self, wo: Vec3, wi: Vec3) -> [(Vec3, f32); 5] {
        let mut out = [(Vec3::ZERO, 0.0f32); 5];
        if wi.z == 0.0 {
            return out;
        }
        let below = self.below(wi.z);
        if wi.z > 0.0 {
            out[COAT] = self.coat_lobe(wi);
            if let Some(s) = self.sheen {
                let h = (wo + wi).normalize();
                let a = sheen::alpha(s.roughness);
                out[SHEEN] = (
                    self.view.coat_below * s.color * sheen::brdf(a, h.z, wi.z, wo.z),
                    wi.z * FRAC_1_PI,
                );
            }
        }
        let (f, pdf) = self.spec_lobe(wo, wi);
        out[SPEC] = (below * f, pdf);
        let dielectric = below * (1.0 - self.metallic) * (1.0 - self.transmission);
        if dielectric > 0.0 {
            let wd = match self.view.w_diffuse {
                Some(w) => w,
                None => {
                    let h = (wo + wi.with_z(wi.z.abs())).normalize();
                    1.0 - self.specular * self.fresnel_dielectric(wo.dot(h)).max_element()
                }
            };
            let pdf = wi.z.abs() * FRAC_1_PI;
            if wi.z > 0.0 {
                let k = dielectric * wd * (1.0 - self.diffuse_transmission);
                out[DIFFUSE] = (k * self.base * FRAC_1_PI, pdf);
            } else if self.diffuse_transmission > 0.0 {
                let k = dielectric * wd * self.diffuse_transmission;
                out[DIFFUSE_T] = (k * self.diffuse_transmission_color * FRAC_1_PI, pdf);
            }
        }
        out
    }

    /// The clear coat's value and density (rough coats only).
    fn coat_lobe(&self, wi: Vec3) -> (Vec3, f32) {
        let (Some(c), Some(cv)) = (self.coat, self.view.coat) else {
            return (Vec3::ZERO, 0.0);
        };
        if cv.ggx.is_delta() {
            return (Vec3::ZERO, 0.0);
        }
        let wi_c = cv.frame.to_local(wi);
        if wi_c.z <= 0.0 || cv.wo.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let h = (cv.wo + wi_c).normalize();
        let oh = cv.wo.dot(h);
        if oh <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let f = schlick(Vec3::splat(COAT_F0), oh).x;
        let own = c.weight * f * cv.ggx.d(h) * cv.ggx.g2(cv.wo, wi_c) / (4.0 * cv.wo.z * wi_c.z);
        // The coat's value per unit of the base frame's cosine.
        let value = own * cv.ms * wi_c.z / wi.z;
        (Vec3::splat(value), cv.ggx.vndf_pdf(cv.wo, h) / (4.0 * oh))
    }

    /// The specular layer's value and density (rough layers only).
    fn spec_lobe(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let Some(g) = self.view.ggx else {
            return (Vec3::ZERO, 0.0);
        };
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let oh = wo.dot(h);
            if oh <= 0.0 {
                return (Vec3::ZERO, 0.0);
            }
            let (r, _, p_r) = self.spec_weights(oh);
            let spec = g.d(h) * g.g2(wo, wi) / (4.0 * wo.z * wi.z);
            return (r * spec, g.vndf_pdf(wo, h) / (4.0 * oh) * p_r);
        }
        match self.view.interface {
            Interface::Opaque => (Vec3::ZERO, 0.0),
            Interface::Thin => {
                let wm = wi.with_z(-wi.z);
                let h = (wo + wm).normalize();
                let oh = wo.dot(h);
                if oh <= 0.0 {
                    return (Vec3::ZERO, 0.0);
                }
                let (_, t, p_r) = self.spec_weights(oh);
                let spec = g.d(h) * g.g2(wo, wm) / (4.0 * wo.z * wm.z);
                (t * spec, g.vndf_pdf(wo, h) / (4.0 * oh) * (1.0 - p_r))
            }
            Interface::Refractive { eta } => {
                let mut h = wi * eta + wo;
                if h.length_squared() == 0.0 {
                    return (Vec3::ZERO, 0.0);
                }
                h = h.normalize();
                if h.z < 0.0 {
                    h = -h;
                }
                let (ih, oh) = (wi.dot(h), wo.dot(h));
                if ih >= 0.0 || oh <= 0.0 {
                    return (Vec3::ZERO, 0.0);
                }
                let (_, t, p_r) = self.spec_weights(oh);
                let denom = (ih + oh / eta).powi(2);
                let ft =
                    g.d(h) * g.g2(wo, wi) * (ih * oh / (denom * wi.z * wo.z)).abs() / (eta * eta);
                let pdf = g.vndf_pdf(wo, h) * ih.abs() / denom * (1.0 - p_r);
                (t * ft, pdf)
            }
        }
    }

    /// Value (without cosine) and solid-angle density of the non-delta lobes.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let lobes = self.lobes(wo, wi);
        let mut f = Vec3::ZERO;
        let mut pdf = 0.0;
        for (k, (value, p)) in lobes.iter().enumerate() {
            f += *value;
            pdf += self.probability(k) * p;
        }
        (f, pdf)
    }
}
