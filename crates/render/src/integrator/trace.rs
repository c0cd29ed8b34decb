//! Following a ray to the surface it scatters at (through alpha-cut surfaces and false
//! interfaces of nested dielectrics, absorbed on the way inside a medium), and what a ray
//! leaving the scene sees.

use super::path::{PathState, Walk, MAX_ALPHA_PASSES};
use super::Integrator;
use crate::aov::Seen;
use crate::sampler::SampleStream;
use aperture_accel::{Hit, Ray, SpawnPoint};
use aperture_shading::media::Crossing;
use aperture_shading::surface::{Surface, SurfaceKind};
use aperture_shading::warp::power_heuristic;
use glam::Vec3;

/// Beer–Lambert transmittance over `t` for absorption `sigma` (1 where σ = 0, even for an
/// infinite `t`).
fn absorption(sigma: Vec3, t: f32) -> Vec3 {
    Vec3::select(sigma.cmpgt(Vec3::ZERO), (-sigma * t).exp(), Vec3::ONE)
}

impl Integrator<'_> {
    /// The surface of `hit` on `ray`: shaded where the instance is at the frame's instant, its
    /// triangle taken at the ray's time when its mesh deforms within the shutter, then moved
    /// to where the instance is at the ray's time when it moves within the shutter.
    #[inline(always)]
    pub(super) fn hit_surface(&self, ray: &Ray, hit: &Hit, shading: bool) -> Surface {
        let mut s = self
            .geom
            .surface_at(hit.instance, hit.triangle, hit.u, hit.v, shading);
        if !self.deforming.is_empty() {
            self.deform_hit(&mut s, hit, ray.time);
        }
        if let Some(Some(m)) = self.moving.get(hit.instance as usize) {
            m.move_surface(&mut s, ray.time);
        }
        s
    }

    /// `s` (of `hit`) on its mesh's triangle at normalised time `tau`, when that mesh deforms.
    #[cold]
    fn deform_hit(&self, s: &mut Surface, hit: &Hit, tau: f32) {
        let Some(inst) = self.geom.scene.instances.get(hit.instance as usize) else {
            return;
        };
        if let Some(Some(keys)) = self.deforming.get(inst.mesh as usize) {
            crate::motion::deform_surface(s, keys, &inst.world_from_object, tau);
        }
    }

    /// The closest surface along `ray` that scatters, passing through alpha-cut or blended
    /// surfaces and false interfaces of nested dielectrics (updating `w.media`), with the
    /// rounding-error bound of the hit point (from the ray segment that found it). Absorption
    /// of the media crossed multiplies `w.beta`. `first`, when given, is
    /// `accel.intersect(ray)` already found (by a batch query).
    #[inline(always)]
    pub(super) fn trace(
        &self,
        ray: &Ray,
        stream: &SampleStream,
        vertex: u32,
        u_alpha: f32,
        first: Option<Option<Hit>>,
        w: &mut Walk,
    ) -> Option<(Hit, Surface, f32)> {
        if self.geom.has_alpha || self.geom.has_refractive {
            return self.trace_passing(ray, stream, vertex, u_alpha, first, w);
        }
        // Nothing to pass through but culled backs: the first hit is the surface (inline, so
        // that a ray that escapes costs no call and the surface is built where the vertex
        // reads it). A culled back is passed as `trace_passing` passes it, from this hit.
        let hit = first.unwrap_or_else(|| self.accel.intersect(ray))?;
        let s = self.hit_surface(ray, &hit, true);
        if self.geom.has_culled {
            if self.geom.is_culled(&s, ray.dir) {
                return self.trace_passing(ray, stream, vertex, u_alpha, Some(Some(hit)), w);
            }
            let sigma = w.media.sigma_a();
            if sigma != Vec3::ZERO {
                w.beta *= absorption(sigma, hit.t * ray.dir.length());
            }
        }
        Some((hit, s, self.accel.spawn_point(ray, &hit).error))
    }

    /// [`Integrator::trace`] in a scene with alpha-cut, blended or refractive surfaces, or
    /// single-sided faces whose backs no ray sees.
    fn trace_passing(
        &self,
        ray: &Ray,
        stream: &SampleStream,
        vertex: u32,
        u_alpha: f32,
        mut first: Option<Option<Hit>>,
        w: &mut Walk,
    ) -> Option<(Hit, Surface, f32)> {
        let mut r = *ray;
        for pass in 0..MAX_ALPHA_PASSES {
            let hit = match first.take() {
                Some(hit) => hit?,
                None => self.accel.intersect(&r)?,
            };
            let s = self.hit_surface(&r, &hit, true);
            let error = self.accel.spawn_point(&r, &hit).error;
            let sigma = w.media.sigma_a();
            if sigma != Vec3::ZERO {
                w.beta *= absorption(sigma, hit.t * r.dir.length());
            }
            let opaque = !self.geom.is_culled(&s, r.dir)
                && (!self.geom.has_alpha || {
                    let u = if pass == 0 {
                        u_alpha
                    } else {
                        stream.extra(vertex, pass)
                    };
                    self.geom.is_opaque(&s, u)
                });
            if opaque && !self.is_false_interface(&hit, &s, &r, w) {
                return Some((hit, s, error));
            }
            // Continue on the far side of the surface.
            let n = if s.ng.dot(r.dir) > 0.0 { s.ng } else { -s.ng };
            r = Ray {
                time: r.time,
                ..Ray::new(SpawnPoint { p: s.p, error }.origin(n), r.dir)
            };
        }
        None
    }

    /// True (and the path's media updated) when `s` is a refractive surface the path's media
    /// make a false interface.
    fn is_false_interface(&self, hit: &Hit, s: &Surface, r: &Ray, w: &mut Walk) -> bool {
        if !self.geom.has_refractive
            || self.geom.kind(hit.instance, s.material) != SurfaceKind::Refractive
        {
            return false;
        }
        let medium = self.geom.info(s.material).medium;
        let entering = r.dir.dot(s.ng) < 0.0;
        if w.media.classify(&medium, entering) == Crossing::False {
            w.media.cross(&medium, entering);
            return true;
        }
        false
    }

    /// The first surface along a ray (unit direction) that is opaque at coverage ½: what the
    /// Depth, Position and Vector passes show (with the instance it lies on). Deterministic,
    /// unlike a sample: alpha-blended surfaces count as solid where their alpha is at least ½.
    /// One ray alone: the reference [`Integrator::first_surfaces`] is tested against.
    #[cfg(test)]
    pub fn first_surface(
        &self,
        origin: Vec3,
        dir: Vec3,
        time: f32,
    ) -> Option<(Vec3, aperture_accel::Hit)> {
        let r = Ray {
            time,
            ..Ray::new(origin, dir)
        };
        let hit = self.accel.intersect(&r)?;
        self.surface_from(r, hit)
    }

    /// The first surface along each of `rays` (unit directions) that is opaque at coverage ½,
    /// into `out`: what the Depth, Position and Vector passes show (with the instance it lies
    /// on). Deterministic, unlike a sample: alpha-blended surfaces count as solid where their
    /// alpha is at least ½. The first hits are found together, as packets where the rays are
    /// coherent (a row of pixels' centre rays); a ray that meets a culled back or a
    /// see-through surface goes on alone. `hits` is scratch.
    pub fn first_surfaces(
        &self,
        rays: &[Ray],
        hits: &mut Vec<Option<Hit>>,
        out: &mut Vec<Option<(Vec3, Hit)>>,
    ) {
        hits.clear();
        hits.resize(rays.len(), None);
        self.accel.intersect_packets(rays, hits);
        out.clear();
        out.extend(
            rays.iter()
                .zip(hits.iter())
                .map(|(r, h)| h.and_then(|hit| self.surface_from(*r, hit))),
        );
    }

    /// The first opaque surface along `r`, whose closest hit `hit` is.
    fn surface_from(&self, mut r: Ray, mut hit: Hit) -> Option<(Vec3, Hit)> {
        let time = r.time;
        for pass in 0..MAX_ALPHA_PASSES {
            if pass > 0 {
                hit = self.accel.intersect(&r)?;
            }
            let s = self.hit_surface(&r, &hit, true);
            let seen = !self.geom.is_culled(&s, r.dir);
            if seen && (!self.geom.has_alpha || self.geom.is_opaque(&s, 0.5)) {
                return Some((s.p, hit));
            }
            let error = self.accel.spawn_point(&r, &hit).error;
            let n = if s.ng.dot(r.dir) > 0.0 { s.ng } else { -s.ng };
            r = Ray {
                time,
                ..Ray::new(SpawnPoint { p: s.p, error }.origin(n), r.dir)
            };
        }
        None
    }

    /// The radiance of a sample whose camera ray meets nothing, without pass values: what
    /// [`Integrator::escape`] adds to a path just started (β = 1, in air, seen by the camera),
    /// bit for bit, without the path.
    #[inline]
    pub(crate) fn background(&self, dir: Vec3) -> Vec3 {
        Vec3::ZERO + self.clamp.apply(Vec3::ONE * self.env.radiance_seen(dir), 0)
    }

    /// A ray leaving the scene: the environment it sees. Seen by the camera (or after ideal
    /// specular lobes only) it is filtered as a background and weighs fully; a constant
    /// environment is found by BSDF sampling alone (weight 1); an image is also light-sampled,
    /// so escaping BSDF rays share it by MIS. Inside an absorbing medium (an open mesh) an
    /// infinite path is absorbed.
    pub(super) fn escape<const AOV: bool>(&self, path: &mut PathState<AOV>, w: &Walk) {
        let dir = w.ray.dir;
        let sigma = w.media.sigma_a();
        let beta = if sigma == Vec3::ZERO {
            w.beta
        } else {
            w.beta * absorption(sigma, f32::INFINITY)
        };
        if w.arrival.pdf.is_infinite() {
            let seen = self.env.radiance_seen(dir);
            path.add(
                self.clamp.apply(beta * seen, w.scatter),
                w.scatter,
                Seen::Environment,
            );
            if AOV {
                path.features.at_colour(&mut path.aov, seen, Vec3::ZERO);
            }
            return;
        }
        let mis = if self.env.is_sampled() {
            power_heuristic(w.arrival.pdf, self.env.pdf(dir))
        } else {
            1.0
        };
        let radiance = self.env.radiance(dir);
        path.add(
            self.clamp.apply(beta * radiance * mis, w.scatter),
            w.scatter,
            Seen::Environment,
        );
        if AOV {
            path.features.at_colour(&mut path.aov, radiance, Vec3::ZERO);
        }
    }
}
