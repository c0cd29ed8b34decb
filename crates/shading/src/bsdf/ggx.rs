//! The GGX (Trowbridge–Reitz) microfacet distribution with Smith masking-shadowing, in the
//! local frame whose +Z is the normal: the isotropic forms glTF's Appendix B writes (used by
//! the metallic-roughness lobe unchanged) and the anisotropic forms the extended material
//! needs, with visible-normal sampling (Heitz 2018) for both.

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Smallest GGX alpha: sharper lobes than this add only numerical trouble. The extended
/// material treats lobes below it as ideal (delta) mirrors and refractors.
pub const MIN_ALPHA: f32 = 1e-3;

/// Isotropic GGX normal distribution for `nh = n·h`, `a2 = α²`.
pub fn ggx_d(nh: f32, a2: f32) -> f32 {
    let d = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Height-correlated Smith visibility `G / (4 |n·l| |n·v|)`, as glTF's Appendix B writes it.
pub fn smith_v(nl: f32, nv: f32, a2: f32) -> f32 {
    let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    let s = gv + gl;
    if s > 0.0 {
        0.5 / s
    } else {
        0.0
    }
}

/// Smith's masking G1 for isotropic GGX.
pub fn smith_g1(nv: f32, a2: f32) -> f32 {
    2.0 * nv / (nv + (a2 + (1.0 - a2) * nv * nv).sqrt())
}

/// A visible normal of isotropic GGX (Heitz 2018, "Sampling the GGX Distribution of Visible
/// Normals"), for `wo.z > 0`.
pub fn sample_vndf(wo: Vec3, alpha: f32, u: [f32; 2]) -> Vec3 {
    sample_vndf_aniso(wo, alpha, alpha, u)
}

/// [`sample_vndf`] with roughness `ax` along the frame's x and `ay` along its y.
fn sample_vndf_aniso(wo: Vec3, ax: f32, ay: f32, u: [f32; 2]) -> Vec3 {
    let vh = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = TAU * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(1e-6)).normalize()
}

/// An anisotropic GGX distribution: `ax` along the local x axis, `ay` along y.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ggx {
    /// Roughness along x.
    pub ax: f32,
    /// Roughness along y.
    pub ay: f32,
}

impl Ggx {
    /// An isotropic distribution.
    pub fn isotropic(alpha: f32) -> Self {
        Self {
            ax: alpha,
            ay: alpha,
        }
    }

    /// True when the lobe is sharper than [`MIN_ALPHA`] in both directions: treated as an
    /// ideal specular (delta) lobe.
    pub fn is_delta(&self) -> bool {
        self.ax.max(self.ay) < MIN_ALPHA
    }

    /// The isotropic roughness that stands for this lobe in albedo tables: the geometric mean.
    pub fn alpha_mean(&self) -> f32 {
        (self.ax * self.ay).sqrt()
    }

    /// Normal distribution D(m) (zero below the surface).
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (m.x / self.ax, m.y / self.ay);
        let t = x * x + y * y + m.z * m.z;
        1.0 / (PI * self.ax * self.ay * t * t)
    }

    /// Smith's Λ for direction `w` (either hemisphere).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        if z2 <= 0.0 {
            return f32::INFINITY;
        }
        let t2 = (self.ax * self.ax * w.x * w.x + self.ay * self.ay * w.y * w.y) / z2;
        0.5 * ((1.0 + t2).sqrt() - 1.0)
    }

    /// Smith's masking for one direction.
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing of the pair (Heitz 2014), for reflection and
    /// transmission alike (as pbrt does).
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of visible normal `m` seen from `wo` (`wo.z > 0`): `G1(wo) max(0, wo·m) D(m) / wo.z`.
    pub fn vndf_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        let om = wo.dot(m);
        if om <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * om * self.d(m) / wo.z
    }

    /// Draws a visible normal for `wo` (`wo.z > 0`).
    pub fn sample_vndf(&self, wo: Vec3, u: [f32; 2]) -> Vec3 {
        sample_vndf_aniso(wo, self.ax, self.ay, u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The anisotropic forms reduce to the isotropic ones glTF writes.
    #[test]
    fn isotropic_forms_agree() {
        let a = 0.3f32;
        let g = Ggx::isotropic(a);
        let wo = Vec3::new(0.3, -0.2, 0.9).normalize();
        let wi = Vec3::new(-0.5, 0.4, 0.7).normalize();
        let h = (wo + wi).normalize();
        assert!((g.d(h) - ggx_d(h.z, a * a)).abs() < 1e-4 * g.d(h));
        let v = g.g2(wo, wi) / (4.0 * wo.z * wi.z);
        assert!((v - smith_v(wi.z, wo.z, a * a)).abs() < 1e-5 * v, "{v}");
        assert!((g.g1(wo) - smith_g1(wo.z, a * a)).abs() < 1e-5);
    }

    /// Visible normals integrate to one over the hemisphere, anisotropic or not.
    #[test]
    fn vndf_is_normalised() {
        let wo = Vec3::new(0.5, 0.3, 0.6).normalize();
        for g in [
            Ggx::isotropic(0.4),
            Ggx { ax: 0.8, ay: 0.1 },
            Ggx { ax: 0.05, ay: 0.3 },
        ] {
            let n = 600;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    // Uniform in (cos θ, φ): dω = dcos dφ.
                    let z = (i as f32 + 0.5) / n as f32;
                    let phi = TAU * (j as f32 + 0.5) / n as f32;
                    let r = (1.0 - z * z).sqrt();
                    let m = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                    sum += g.vndf_pdf(wo, m) as f64;
                }
            }
            let total = sum * std::f64::consts::TAU / (n * n) as f64;
            assert!((total - 1.0).abs() < 0.01, "{g:?}: {total}");
        }
    }
}
