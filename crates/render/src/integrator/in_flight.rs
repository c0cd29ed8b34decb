//! A path in flight between vertices: its walk, its running sums and the light samples whose
//! shadow rays it waits on (what [`super::wavefront::Wavefront`] advances, run by run).

use super::path::{PathState, Walk};
#[cfg(test)]
use crate::aov::SampleAov;
use aperture_accel::Ray;
use glam::Vec3;

/// A path between vertices: its walk and running sums.
pub(crate) struct PathInFlight<const AOV: bool> {
    pub(super) path: PathState<AOV>,
    pub(super) w: Walk,
    pub(super) covered: bool,
    pub(super) live: bool,
}

impl<const AOV: bool> PathInFlight<AOV> {
    /// The ray whose closest hit the next `Integrator::advance` needs; `None` once the path
    /// has ended.
    #[inline]
    pub fn ray(&self) -> Option<Ray> {
        self.live.then_some(self.w.ray)
    }

    /// The shadow rays of the light samples waiting since the last vertex.
    #[inline]
    pub fn shadow_rays(&self) -> impl Iterator<Item = Ray> + '_ {
        self.path.pending.iter().map(|p| p.ray)
    }

    /// Adds the waiting light samples, given whether each one's shadow ray is `blocked` (in
    /// the order of [`PathInFlight::shadow_rays`]). The arithmetic of an immediate light
    /// sample: the clamped contribution times the medium's transmittance, or, when blocked,
    /// times `through(ray, transmittance)` (zero, or what passes culled backs).
    #[inline]
    pub fn resolve(&mut self, blocked: &[bool], through: impl Fn(Ray, Vec3) -> Vec3) {
        // Taken out and put back (emptied) so that its capacity serves the next vertex.
        let mut pending = std::mem::take(&mut self.path.pending);
        for (p, &b) in pending.iter().zip(blocked) {
            let lit = p.clamped
                * if b {
                    through(p.ray, p.absorbed)
                } else {
                    p.absorbed
                };
            self.path.add_lit(lit, p.scatterings, &p.split);
        }
        pending.clear();
        self.path.pending = pending;
    }

    /// The path's radiance, whether its camera ray hit geometry, and its pass values.
    #[cfg(test)]
    pub fn finish(self) -> (Vec3, bool, SampleAov) {
        (self.path.l, self.covered, self.path.aov)
    }
}
