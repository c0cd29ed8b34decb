//! What the lobes share: the local frame, the lobe kinds and how a value splits between them,
//! and the environment BRDF fit the passes colour with.

use glam::Vec3;

/// An orthonormal frame around a unit normal (Duff et al. 2017, branchless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Tangent.
    pub t: Vec3,
    /// Bitangent.
    pub b: Vec3,
    /// Normal.
    pub n: Vec3,
}

impl Frame {
    /// A frame whose +Z is `n` (unit length).
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            t: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            b: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// World to local.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// Local to world.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }

    /// A frame whose +Z is `n` (unit) and whose +X follows `t` projected onto the plane of
    /// `n`; [`Frame::from_normal`] when `t` is (nearly) parallel to `n`.
    pub fn from_normal_tangent(n: Vec3, t: Vec3) -> Self {
        match (t - n * n.dot(t)).try_normalize() {
            Some(t) => Self {
                t,
                b: n.cross(t),
                n,
            },
            None => Self::from_normal(n),
        }
    }
}

/// The lobe an ideal (delta) sample came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lobe {
    /// Diffuse reflection or transmission.
    Diffuse,
    /// Specular reflection (base or coat).
    Glossy,
    /// Specular transmission.
    Transmission,
}

/// Smallest cosine between the view and a shading normal.
pub const MIN_VIEW_COS: f32 = 0.02;

/// A shading normal bent just far enough towards the viewer `wo` that `wo` is above its
/// hemisphere. Normal maps and interpolated normals can face away from the viewer; shading with
/// such a normal would see the view below the surface and return black. Bending (instead of
/// switching to the geometric normal) keeps the result continuous as the normal crosses over.
pub fn bend_towards(n: Vec3, wo: Vec3) -> Vec3 {
    let c = n.dot(wo);
    if c >= MIN_VIEW_COS {
        return n;
    }
    (n + wo * (MIN_VIEW_COS - c)).try_normalize().unwrap_or(wo)
}

/// Per-channel fractions of a BSDF value that belong to each lobe (they sum to 1 where the
/// value is not zero): how light passes split a contribution, as Cycles splits its
/// Diffuse/Glossy/Transmission passes by closure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LobeSplit {
    /// Diffuse fraction.
    pub diffuse: Vec3,
    /// Glossy (specular reflection) fraction.
    pub glossy: Vec3,
    /// Transmission fraction.
    pub transmission: Vec3,
}

impl LobeSplit {
    /// Everything diffuse.
    pub const DIFFUSE: LobeSplit = LobeSplit {
        diffuse: Vec3::ONE,
        glossy: Vec3::ZERO,
        transmission: Vec3::ZERO,
    };
}

/// Directional albedos of a BSDF's lobes for one view direction (the "Color" passes and the
/// denoising albedo).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Albedos {
    /// Diffuse lobe.
    pub diffuse: Vec3,
    /// Specular reflection lobe, Fresnel included.
    pub glossy: Vec3,
    /// Transmission lobe.
    pub transmission: Vec3,
}

impl LobeSplit {
    /// The per-channel shares of three lobe values (zero where their sum is).
    pub fn from_parts(diffuse: Vec3, glossy: Vec3, transmission: Vec3) -> Self {
        let total = diffuse + glossy + transmission;
        let frac = |v: Vec3| {
            Vec3::select(
                total.cmpgt(Vec3::ZERO),
                (v / total).clamp(Vec3::ZERO, Vec3::ONE),
                Vec3::ZERO,
            )
        };
        Self {
            diffuse: frac(diffuse),
            glossy: frac(glossy),
            transmission: frac(transmission),
        }
    }

    /// All of it in one lobe.
    pub fn pure(lobe: Lobe) -> Self {
        let mut s = Self {
            diffuse: Vec3::ZERO,
            glossy: Vec3::ZERO,
            transmission: Vec3::ZERO,
        };
        *match lobe {
            Lobe::Diffuse => &mut s.diffuse,
            Lobe::Glossy => &mut s.glossy,
            Lobe::Transmission => &mut s.transmission,
        } = Vec3::ONE;
        s
    }
}

/// Directional albedo of a GGX lobe with reflectance `f0` at view cosine `nv`, from Karis'
/// analytic fit of the split-sum integral (perceptual roughness `r`): the colour a pass shows,
/// not a term of the estimator.
pub fn env_brdf(f0: Vec3, r: f32, nv: f32) -> Vec3 {
    let (c0, c1) = ([-1.0, -0.0275, -0.572, 0.022], [1.0, 0.0425, 1.04, -0.04]);
    let v: [f32; 4] = std::array::from_fn(|i| r * c0[i] + c1[i]);
    let a004 = (v[0] * v[0]).min((-9.28 * nv).exp2()) * v[0] + v[1];
    let (a, b) = (-1.04 * a004 + v[2], 1.04 * a004 + v[3]);
    f0 * a + Vec3::splat(b)
}

/// Cycles' line between specular and rough lobes for its denoising features: α above 0.075.
pub const ROUGH_ALPHA: f32 = 0.075;
