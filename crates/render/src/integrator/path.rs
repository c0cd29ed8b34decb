//! A path's state between vertices and its running sums: how it arrived (for MIS at an
//! emitter), its throughput and media, the light it has gathered, the light samples waiting
//! for their shadow rays, and Cycles' clamps applied to each contribution.

use crate::aov::{Features, SampleAov, Seen};
use aperture_accel::Ray;
use aperture_shading::bsdf::{Bsdf, LobeSplit};
use aperture_shading::media::MediumStack;
use glam::Vec3;

/// Vertices before Russian roulette may end a path.
pub(super) const RR_START: u32 = 3;
/// Surfaces a single ray may pass through by alpha before it is stopped.
pub(super) const MAX_ALPHA_PASSES: u32 = 64;
/// Total internal reflections one path may take (they are not bounces).
pub(super) const MAX_INTERNAL: u32 = 256;

/// Blender Cycles' "Clamp Direct" / "Clamp Indirect": the largest value one sample's
/// contribution may add, as the sum of its R, G and B (0 = no limit). Clamping trades bias
/// (bright caustics and highlights come out darker) for the removal of rare, very bright
/// samples that unidirectional path tracing otherwise converges on very slowly.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Clamp {
    /// Limit for light reaching the camera after at most one scattering (the camera ray's hit
    /// seen directly, and that hit lit by a light or emitter).
    pub direct: f32,
    /// Limit for light that scattered more than once.
    pub indirect: f32,
}

impl Clamp {
    /// No clamping: the unbiased estimate.
    pub const OFF: Clamp = Clamp {
        direct: 0.0,
        indirect: 0.0,
    };

    /// `c` scaled down (hue kept) so that its channel sum is at most the limit for light that
    /// scattered `scatterings` times before reaching the camera (Cycles' `kernel_accum_clamp`).
    #[inline]
    pub(super) fn apply(self, c: Vec3, scatterings: u32) -> Vec3 {
        let limit = if scatterings <= 1 {
            self.direct
        } else {
            self.indirect
        };
        // Off (the default) costs one comparison per contribution on this hot path.
        if limit <= 0.0 {
            return c;
        }
        let sum = c.x.abs() + c.y.abs() + c.z.abs();
        if sum > limit {
            c * (limit / sum)
        } else {
            c
        }
    }
}

/// How the path reached the current vertex: what MIS at an emitter found there needs.
#[derive(Debug, Clone, Copy)]
pub(super) struct Arrival {
    /// The last scattering vertex's position.
    pub(super) p: Vec3,
    /// Solid-angle density of the direction it drew; ∞ for the camera and delta lobes (no
    /// light sample could have found the emitter: weight 1).
    pub(super) pdf: f32,
    /// Probability that light sampling picked the emitters there (1 without a choice).
    pub(super) emitters: f32,
    /// The vertex's normal on the side light is received from, and whether both sides
    /// count: the light tree's probability of a met emitter depends on them.
    pub(super) n: Vec3,
    pub(super) two_sided: bool,
}

/// Where a path is between vertices.
pub(super) struct Walk {
    pub(super) beta: Vec3,
    pub(super) ray: Ray,
    pub(super) arrival: Arrival,
    /// Surface interactions so far: selects the sampler dimensions.
    pub(super) vertex: u32,
    /// Scatterings so far (Cycles' bounces): a straight pass through thin glass after the
    /// first hit is not one.
    pub(super) scatter: u32,
    pub(super) media: MediumStack,
    /// The wavelength a dispersive refraction chose (nm), once chosen.
    pub(super) wavelength: Option<f32>,
    /// The colour channel the camera chose (chromatic aberration; 0 R, 1 G, 2 B), if it did.
    pub(super) channel: Option<u8>,
    /// Total internal reflections so far.
    pub(super) internal: u32,
}

impl Walk {
    /// The walk of a path whose primary ray leaves `origin` along `dir` (unit).
    #[inline]
    pub(super) fn start(origin: Vec3, dir: Vec3) -> Self {
        Walk {
            beta: Vec3::ONE,
            ray: Ray::new(origin, dir),
            arrival: Arrival {
                p: origin,
                pdf: f32::INFINITY,
                emitters: 1.0,
                n: Vec3::ZERO,
                two_sided: false,
            },
            vertex: 0,
            scatter: 0,
            media: MediumStack::default(),
            wavelength: None,
            channel: None,
            internal: 0,
        }
    }

    /// Russian roulette from vertex [`RR_START`] on, with the uniform number `u`: the walk
    /// survives with probability `q` and its throughput is divided by it (unbiased). False
    /// ends the path, as does a throughput of zero.
    #[inline(always)]
    pub(super) fn survives_roulette(&mut self, u: f32) -> bool {
        if self.vertex >= RR_START {
            let q = self.beta.max_element().min(1.0);
            if u >= q || q.is_nan() {
                return false;
            }
            self.beta /= q;
        }
        self.beta != Vec3::ZERO
    }

    /// Moves the walk on to its next vertex along `ray`, counting what the step was; false
    /// ends the path.
    #[inline(always)]
    pub(super) fn step(&mut self, ray: Ray, internal: bool, straight: bool) -> bool {
        self.ray = ray;
        self.vertex += 1;
        // A straight pass through a pane is a scattering only as the camera's first hit
        // (so what is seen through glass fills the Transmission passes, as in Cycles).
        // Total internal reflection is no choice of the light's: it does not count
        // against `max_bounces` (a glass wall guiding light would go dark at the limit),
        // but a path takes at most `MAX_INTERNAL` of them.
        if internal {
            self.internal += 1;
            if self.internal > MAX_INTERNAL {
                return false;
            }
        } else if !straight || self.scatter == 0 {
            self.scatter += 1;
        }
        true
    }
}

/// One path's running sums.
pub(super) struct PathState<const AOV: bool> {
    /// Radiance so far.
    pub(super) l: Vec3,
    /// The sample's pass values (untouched unless `AOV`).
    pub(super) aov: SampleAov,
    /// How the first vertex's sampled direction split among the lobes.
    pub(super) first_split: LobeSplit,
    pub(super) features: Features,
    pub(super) light_passes: bool,
    /// Light samples wait for their shadow rays in `pending` rather than tracing them.
    pub(super) defer: bool,
    /// Light samples of the current vertex whose shadow rays are not traced yet.
    pub(super) pending: Vec<PendingLight>,
}

impl<const AOV: bool> PathState<AOV> {
    /// Adds light that reached the camera after `scatterings` scatterings.
    #[inline]
    pub(super) fn add(&mut self, c: Vec3, scatterings: u32, seen: Seen) {
        self.l += c;
        if AOV && self.light_passes {
            self.aov.add_light(c, scatterings, &self.first_split, seen);
        }
    }

    /// Adds a light sample's contribution `lit` (after `scatterings` scatterings, split among
    /// the lobes as `split`).
    #[inline]
    pub(super) fn add_lit(&mut self, lit: Vec3, scatterings: u32, split: &LobeSplit) {
        self.l += lit;
        if AOV && self.light_passes {
            self.aov.add_light(lit, scatterings, split, Seen::Surface);
        }
    }

    /// Records a surface's albedos and roughness for the passes (the colour passes at the
    /// camera's hit, the denoising features where they are still pending).
    #[inline(always)]
    pub(super) fn record_surface(&mut self, bsdf: &Bsdf, wo_l: Vec3, vertex: u32, ns: Vec3) {
        let albedos = bsdf.albedos(wo_l);
        if vertex == 0 {
            self.aov.set_colours(&albedos);
        }
        let rough = bsdf.glossy_is_rough();
        self.features.at_surface(&mut self.aov, &albedos, rough, ns);
    }
}

/// A light sample whose shadow ray is not traced yet.
pub(crate) struct PendingLight {
    /// The shadow ray.
    pub ray: Ray,
    /// The contribution, clamped, if nothing blocks the ray.
    pub clamped: Vec3,
    /// The transmittance of the medium the ray crosses.
    pub absorbed: Vec3,
    /// Scatterings of the light on its way to the camera.
    pub scatterings: u32,
    /// How the contribution splits among the lobes (light passes).
    pub split: LobeSplit,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_scales_by_channel_sum_and_keeps_hue() {
        let c = Clamp {
            direct: 3.0,
            indirect: 1.0,
        };
        let v = Vec3::new(4.0, 2.0, 0.0);
        // Direct: the camera ray's hit (0 scatterings) and its lighting (1).
        for n in [0, 1] {
            let d = c.apply(v, n);
            assert!((d.x + d.y + d.z - 3.0).abs() < 1e-6, "{d}");
            assert!((d.x / d.y - 2.0).abs() < 1e-6);
        }
        let i = c.apply(v, 2);
        assert!((i.x + i.y + i.z - 1.0).abs() < 1e-6, "{i}");
        // Below the limit, or with no limit: unchanged.
        assert_eq!(c.apply(Vec3::splat(0.2), 2), Vec3::splat(0.2));
        assert_eq!(Clamp::OFF.apply(v * 1e6, 5), v * 1e6);
    }
}
