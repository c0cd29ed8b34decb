//! What one sample contributes to the averaged passes, recorded by the path tracer next to the
//! beauty only when passes are asked for (the integrator is compiled twice; the beauty-only
//! copy carries none of this).
//!
//! Light passes follow Cycles: light that reached the camera without scattering goes to
//! Emission or Environment; after one scattering to the Direct pass, after more to the
//! Indirect pass, of the lobe that scattered first (split per channel by the lobes' shares of
//! the BSDF value). The Color passes hold the first surface's lobe albedos; the output divides
//! Direct and Indirect by them, so `(Direct + Indirect) × Color` summed over the lobes, plus
//! Emission and Environment, is the beauty.

use aperture_shading::bsdf::{Albedos, LobeSplit};
use glam::Vec3;

/// Light pass slots of [`SampleAov::light`], in [`crate::passes::LIGHT_PASSES`] order.
pub mod slot {
    /// Slot of the `Diffuse Direct` pass.
    pub const DIFFUSE_DIRECT: usize = 0;
    /// Slot of the `Diffuse Indirect` pass.
    pub const DIFFUSE_INDIRECT: usize = 1;
    /// Slot of the `Diffuse Color` pass.
    pub const DIFFUSE_COLOR: usize = 2;
    /// Slot of the `Glossy Direct` pass.
    pub const GLOSSY_DIRECT: usize = 3;
    /// Slot of the `Glossy Indirect` pass.
    pub const GLOSSY_INDIRECT: usize = 4;
    /// Slot of the `Glossy Color` pass.
    pub const GLOSSY_COLOR: usize = 5;
    /// Slot of the `Transmission Direct` pass.
    pub const TRANSMISSION_DIRECT: usize = 6;
    /// Slot of the `Transmission Indirect` pass.
    pub const TRANSMISSION_INDIRECT: usize = 7;
    /// Slot of the `Transmission Color` pass.
    pub const TRANSMISSION_COLOR: usize = 8;
    /// Slot of the `Emission` pass.
    pub const EMISSION: usize = 9;
    /// Slot of the `Environment` pass.
    pub const ENVIRONMENT: usize = 10;
}

/// No instance or material: the sample's camera ray hit nothing.
pub const NONE: u32 = u32::MAX;

/// One sample's contribution to the averaged passes and Cryptomatte.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleAov {
    /// World shading normal of the first surface (zero on a miss).
    pub normal: Vec3,
    /// Denoising albedo.
    pub albedo: Vec3,
    /// Denoising normal, world space (turned into camera space once per pixel at output).
    pub denoising_normal: Vec3,
    /// Light passes, by [`slot`].
    pub light: [Vec3; 11],
    /// Instance the camera ray hit first, or [`NONE`].
    pub instance: u32,
    /// Material of that hit, or [`NONE`].
    pub material: u32,
}

impl Default for SampleAov {
    fn default() -> Self {
        Self {
            normal: Vec3::ZERO,
            albedo: Vec3::ZERO,
            denoising_normal: Vec3::ZERO,
            light: [Vec3::ZERO; 11],
            instance: NONE,
            material: NONE,
        }
    }
}

impl SampleAov {
    /// Routes light `c` that reached the camera after `scatterings` scatterings; `split` is
    /// how the scattering that counts (the first) divides among the lobes.
    #[inline]
    pub fn add_light(&mut self, c: Vec3, scatterings: u32, split: &LobeSplit, seen: Seen) {
        let (diffuse, glossy, transmission) = match scatterings {
            0 => {
                let s = match seen {
                    Seen::Surface => slot::EMISSION,
                    Seen::Environment => slot::ENVIRONMENT,
                };
                self.light[s] += c;
                return;
            }
            1 => (
                slot::DIFFUSE_DIRECT,
                slot::GLOSSY_DIRECT,
                slot::TRANSMISSION_DIRECT,
            ),
            _ => (
                slot::DIFFUSE_INDIRECT,
                slot::GLOSSY_INDIRECT,
                slot::TRANSMISSION_INDIRECT,
            ),
        };
        self.light[diffuse] += c * split.diffuse;
        self.light[glossy] += c * split.glossy;
        self.light[transmission] += c * split.transmission;
    }

    /// The first surface's lobe albedos (the Color passes).
    pub fn set_colours(&mut self, a: &Albedos) {
        self.light[slot::DIFFUSE_COLOR] = a.diffuse;
        self.light[slot::GLOSSY_COLOR] = a.glossy;
        self.light[slot::TRANSMISSION_COLOR] = a.transmission;
    }
}

/// What light seen without scattering came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seen {
    /// An emitter or an unlit surface.
    Surface,
    /// The environment.
    Environment,
}

/// The denoising features still to be written: Cycles follows specular bounces to the first
/// rough surface, multiplying their albedo in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Features {
    /// Throughput of the specular bounces followed so far; `None` once written.
    pending: Option<Vec3>,
}

impl Default for Features {
    fn default() -> Self {
        Self {
            pending: Some(Vec3::ONE),
        }
    }
}

impl Features {
    /// True while the features are still to be written.
    #[inline]
    pub fn pending(&self) -> bool {
        self.pending.is_some()
    }

    /// At a surface with lobe albedos `a`: write the features here unless three quarters or
    /// more of the weight is in sharp specular lobes (Cycles' rule), else follow the bounce.
    #[inline]
    pub fn at_surface(&mut self, aov: &mut SampleAov, a: &Albedos, rough: bool, n: Vec3) {
        let Some(t) = self.pending else { return };
        let specular = a.glossy + a.transmission;
        let (wd, ws) = (mean(a.diffuse), mean(specular));
        let sum = wd + ws;
        let non_specular = wd + if rough { ws } else { 0.0 };
        if sum <= 0.0 || non_specular * 4.0 > sum {
            let albedo = if rough {
                a.diffuse + specular
            } else {
                a.diffuse
            };
            aov.albedo = t * albedo;
            aov.denoising_normal = n;
            self.pending = None;
        } else {
            self.pending = Some(t * specular);
        }
    }

    /// At a surface that only shows a colour (unlit) or where the path leaves the scene
    /// seeing `colour`: the features end here.
    #[inline]
    pub fn at_colour(&mut self, aov: &mut SampleAov, colour: Vec3, n: Vec3) {
        if let Some(t) = self.pending.take() {
            aov.albedo = t * colour.clamp(Vec3::ZERO, Vec3::ONE);
            aov.denoising_normal = n;
        }
    }
}

fn mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_is_routed_by_scatterings_and_lobes() {
        let mut a = SampleAov::default();
        let split = LobeSplit {
            diffuse: Vec3::new(1.0, 0.5, 0.0),
            glossy: Vec3::new(0.0, 0.5, 1.0),
            transmission: Vec3::ZERO,
        };
        a.add_light(Vec3::ONE, 0, &split, Seen::Surface);
        a.add_light(Vec3::splat(2.0), 0, &split, Seen::Environment);
        a.add_light(Vec3::splat(4.0), 1, &split, Seen::Surface);
        a.add_light(Vec3::splat(8.0), 3, &split, Seen::Environment);
        assert_eq!(a.light[slot::EMISSION], Vec3::ONE);
        assert_eq!(a.light[slot::ENVIRONMENT], Vec3::splat(2.0));
        assert_eq!(a.light[slot::DIFFUSE_DIRECT], Vec3::new(4.0, 2.0, 0.0));
        assert_eq!(a.light[slot::GLOSSY_DIRECT], Vec3::new(0.0, 2.0, 4.0));
        assert_eq!(a.light[slot::DIFFUSE_INDIRECT], Vec3::new(8.0, 4.0, 0.0));
        assert_eq!(a.light[slot::GLOSSY_INDIRECT], Vec3::new(0.0, 4.0, 8.0));
        let total: Vec3 = a.light.iter().sum();
        assert_eq!(total, Vec3::splat(15.0));
    }

    #[test]
    fn features_follow_sharp_specular_bounces() {
        let mirror = Albedos {
            glossy: Vec3::splat(0.9),
            ..Albedos::default()
        };
        let plaster = Albedos {
            diffuse: Vec3::new(0.8, 0.6, 0.4),
            glossy: Vec3::splat(0.04),
            ..Albedos::default()
        };
        let mut aov = SampleAov::default();
        let mut f = Features::default();
        f.at_surface(&mut aov, &mirror, false, Vec3::Z);
        assert_eq!(aov.albedo, Vec3::ZERO, "a mirror defers");
        f.at_surface(&mut aov, &plaster, true, Vec3::Y);
        assert!((aov.albedo - 0.9 * (plaster.diffuse + plaster.glossy)).length() < 1e-6);
        assert_eq!(aov.denoising_normal, Vec3::Y);
        // Written once: later surfaces change nothing.
        f.at_colour(&mut aov, Vec3::ONE, Vec3::X);
        assert_eq!(aov.denoising_normal, Vec3::Y);
        // A rough metal is a surface, not a mirror.
        let mut aov = SampleAov::default();
        let mut f = Features::default();
        f.at_surface(&mut aov, &mirror, true, Vec3::Z);
        assert_eq!(aov.albedo, Vec3::splat(0.9));
    }
}
