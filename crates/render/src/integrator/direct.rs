//! Next-event estimation: one routine per light kind sharing one contribution helper, and the
//! shadow ray's transmittance.

use super::path::{PathState, PendingLight, MAX_ALPHA_PASSES};
use super::Integrator;
use crate::sampler::{SampleStream, VertexLightSample};
use aperture_accel::{Ray, SpawnPoint};
use aperture_shading::bsdf::{Bsdf, Frame, LobeSplit};
use aperture_shading::light_choice::{Candidates, Choice, Pick};
use aperture_shading::punctual::punctual_incident;
use aperture_shading::surface::SurfaceKind;
use aperture_shading::warp::power_heuristic;
use glam::Vec3;

/// A scattering vertex, as the light-sampling routines see it.
pub(super) struct Vertex<'b> {
    pub bsdf: &'b Bsdf,
    pub frame: Frame,
    /// The view direction, local.
    pub wo_l: Vec3,
    /// Geometric normal on the viewer's side.
    pub ng: Vec3,
    /// The surface point.
    pub p: Vec3,
    /// Where rays leave the surface on the viewer's side.
    pub p_out: Vec3,
    /// The point with its error bound, for rays leaving on the far side.
    pub spawn: SpawnPoint,
    /// True when lights on the far side count (thin-walled or diffuse transmission).
    pub two_sided: bool,
    /// Scatterings before this vertex.
    pub scatter: u32,
    /// Surface interactions before this vertex (sampler dimensions).
    pub vertex: u32,
    /// Absorption of the medium the vertex lies in.
    pub sigma_a: Vec3,
    /// Probability that light sampling picks the emitters here (1 without a choice).
    pub emitters: f32,
    /// The path's time in the shutter (its rays' [`Ray::time`]).
    pub time: f32,
}

impl Vertex<'_> {
    /// The origin of a shadow ray towards `wi` (world), `None` when the BSDF sends no light
    /// that way (the far side of a surface that does not transmit).
    fn origin_towards(&self, wi: Vec3) -> Option<Vec3> {
        if wi.dot(self.ng) > 0.0 {
            Some(self.p_out)
        } else if self.two_sided {
            Some(self.spawn.origin(-self.ng))
        } else {
            None
        }
    }
}

impl Integrator<'_> {
    /// What a vertex may pick from when it samples one light.
    pub(crate) fn candidates(&self) -> Candidates<'_> {
        Candidates {
            lights: &self.geom.scene.lights,
            emitters: self.emissive.as_ref().map(|e| &e.bounds),
        }
    }

    /// Next-event estimation towards the light `choice` picked, its contribution divided by
    /// the probability of the pick; towards every light when the scene leaves no choice (one
    /// punctual light, or emitters alone; `choice` is `None`).
    pub(super) fn direct_lights<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        ls: Option<&VertexLightSample>,
        choice: Option<Choice>,
        path: &mut PathState<AOV>,
    ) {
        let Some(c) = choice else {
            for light in &self.geom.scene.lights {
                self.direct_punctual(v, light, beta, path);
            }
            if self.emissive.is_some() {
                self.direct_emissive(v, beta, ls, 1.0, path);
            }
            return;
        };
        match c.pick {
            Some(Pick::Punctual(i)) => {
                if let Some(light) = self.geom.scene.lights.get(i) {
                    self.direct_punctual(v, light, beta / c.probability, path);
                }
            }
            Some(Pick::Emitters) => {
                let ls = ls.map(|l| VertexLightSample {
                    light_pick: c.u,
                    ..*l
                });
                self.direct_emissive(v, beta, ls.as_ref(), c.probability, path);
            }
            Some(Pick::Triangle(i)) => {
                if let Some(ls) = ls {
                    self.direct_triangle(v, beta, ls, i, c.probability, path);
                }
            }
            None => {}
        }
    }

    /// Next-event estimation towards a punctual light (a delta: light sampling only).
    #[inline]
    fn direct_punctual<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        light: &aperture_scene::Light,
        beta: Vec3,
        path: &mut PathState<AOV>,
    ) {
        let Some((wi, dist, e)) = punctual_incident(light, v.p) else {
            return;
        };
        if e == Vec3::ZERO {
            return;
        }
        let Some(origin) = v.origin_towards(wi) else {
            return;
        };
        let wi_l = v.frame.to_local(wi);
        let (f, _) = v.bsdf.eval(v.wo_l, wi_l);
        let c = beta * f * wi_l.z.abs() * e;
        if c != Vec3::ZERO {
            let dist = if dist.is_finite() {
                (light.position - origin).length()
            } else {
                dist
            };
            self.add_direct(v, path, c, wi_l, origin, wi, dist);
        }
    }

    /// Next-event estimation towards one emissive triangle picked by power, weighted against
    /// BSDF sampling by MIS; `pick` is the probability that the emitters were picked at all.
    fn direct_emissive<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        ls: Option<&VertexLightSample>,
        pick: f32,
        path: &mut PathState<AOV>,
    ) {
        let (Some(em), Some(bs)) = (&self.emissive, ls) else {
            return;
        };
        let i = em.table.sample(bs.light_pick);
        self.direct_triangle(v, beta, bs, i, em.table.pmf(i) * pick, path);
    }

    /// Next-event estimation towards the emissive triangle of index `i`, picked with
    /// probability `pick`, weighted against BSDF sampling by MIS.
    fn direct_triangle<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        bs: &VertexLightSample,
        i: usize,
        pick: f32,
        path: &mut PathState<AOV>,
    ) {
        let Some(t) = self
            .emissive
            .as_ref()
            .and_then(|em| em.triangles.get(i).copied())
        else {
            return;
        };
        let (a, b) = (bs.light[0].sqrt(), bs.light[1]);
        let q = self
            .geom
            .emitter_surface(t.instance, t.triangle, a * (1.0 - b), a * b);
        let d = q.p - v.p;
        let d2 = d.length_squared();
        let dist = d2.sqrt();
        let wi = d / dist;
        let cos_l = q.ng.dot(wi).abs();
        // The back of a culled single-sided emitter is not there: no ray meets it, so light
        // sampling must not either (else MIS would weigh light the other strategy never sees).
        if !(d2 > 0.0 && cos_l > 0.0 && q.area > 0.0) || self.geom.is_culled(&q, wi) {
            return;
        }
        let Some(origin) = v.origin_towards(wi) else {
            return;
        };
        let light_pdf = pick / q.area * d2 / cos_l;
        let wi_l = v.frame.to_local(wi);
        let (f, bsdf_pdf) = v.bsdf.eval(v.wo_l, wi_l);
        let le = self.geom.emission(&q);
        let c = beta * f * wi_l.z.abs() * le * (power_heuristic(light_pdf, bsdf_pdf) / light_pdf);
        if c != Vec3::ZERO && c.is_finite() {
            let qn = if q.ng.dot(wi) < 0.0 { q.ng } else { -q.ng };
            let target = self.accel.surface_point(t.instance, q.p).origin(qn);
            let to = target - origin;
            let len = to.length();
            self.add_direct(v, path, c, wi_l, origin, to / len, len);
        }
    }

    /// Next-event estimation towards an environment image, weighted against BSDF sampling by
    /// MIS. Only an image is light-sampled; a constant colour is met by BSDF rays alone, so
    /// its pair of sample values (two scrambled Sobol dimensions) is not even drawn.
    pub(super) fn direct_environment<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        stream: &SampleStream,
        path: &mut PathState<AOV>,
    ) {
        if !self.env.is_sampled() {
            return;
        }
        let Some(es) = self.env.sample(stream.environment(v.vertex)) else {
            return;
        };
        let Some(origin) = v.origin_towards(es.wi) else {
            return;
        };
        if es.radiance == Vec3::ZERO {
            return;
        }
        let wi_l = v.frame.to_local(es.wi);
        let (f, bsdf_pdf) = v.bsdf.eval(v.wo_l, wi_l);
        let c =
            beta * f * wi_l.z.abs() * es.radiance * (power_heuristic(es.pdf, bsdf_pdf) / es.pdf);
        if c != Vec3::ZERO && c.is_finite() {
            self.add_direct(v, path, c, wi_l, origin, es.wi, f32::INFINITY);
        }
    }

    /// The contribution every light sample shares: `c` (light over its density, through the
    /// BSDF) clamped as light after one more scattering, times the shadow ray's transmittance
    /// from `origin` along `dir` over `dist`; `wi_l` is the local light direction, which
    /// splits the contribution among the lobes at the first vertex. A deferring path keeps it
    /// in its pending samples, for the wavefront to trace the shadow ray with its others.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn add_direct<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        path: &mut PathState<AOV>,
        c: Vec3,
        wi_l: Vec3,
        origin: Vec3,
        dir: Vec3,
        dist: f32,
    ) {
        let clamped = self.clamp.apply(c, v.scatter + 1);
        let split = if !(AOV && path.light_passes) {
            LobeSplit::DIFFUSE
        } else if v.scatter == 0 {
            v.bsdf.lobe_split(v.wo_l, wi_l)
        } else {
            path.first_split
        };
        if path.defer {
            let (ray, absorbed) = shadow_ray(origin, dir, dist, v.sigma_a, v.time);
            path.pending.push(PendingLight {
                ray,
                clamped,
                absorbed,
                scatterings: v.scatter + 1,
                split,
            });
            return;
        }
        let lit = clamped * self.visibility(origin, dir, (dist, v.time), v.sigma_a);
        path.add_lit(lit, v.scatter + 1, &split);
    }

    /// Fraction of light arriving along a shadow ray from `origin` in unit direction `dir` over
    /// `dist`, inside a medium absorbing `sigma_a`: alpha-cut and blended surfaces,
    /// thin-walled ideal transmission and the backs of culled single-sided faces let light
    /// through, refractive boundaries do not (light through them bends).
    pub(super) fn visibility(
        &self,
        origin: Vec3,
        dir: Vec3,
        (dist, time): (f32, f32),
        sigma_a: Vec3,
    ) -> Vec3 {
        let (ray, absorbed) = shadow_ray(origin, dir, dist, sigma_a, time);
        if !self.geom.has_alpha && !self.geom.has_thin {
            if !self.geom.has_culled {
                // Only opaque surfaces: any hit decides.
                return if self.accel.occluded(&ray) {
                    Vec3::ZERO
                } else {
                    absorbed
                };
            }
            return self.past_culled_backs(ray, absorbed);
        }
        self.passing_transmittance(ray, absorbed)
    }

    /// [`Integrator::visibility`] where every surface is opaque but backs of single-sided
    /// faces are culled: a ray that meets nothing is lit; one whose any hit is a surface seen
    /// from its front (or double-sided) is blocked; only one that met a culled back walks the
    /// surfaces ([`Integrator::passing_transmittance`]). Also the answer for a deferred shadow
    /// ray of such a scene found blocked.
    pub(super) fn past_culled_backs(&self, ray: Ray, absorbed: Vec3) -> Vec3 {
        let Some(hit) = self.accel.occluder(&ray) else {
            return absorbed;
        };
        let s = self.hit_surface(&ray, &hit, false);
        if !self.geom.is_culled(&s, ray.dir) {
            return Vec3::ZERO;
        }
        self.passing_transmittance(ray, absorbed)
    }

    /// The fraction of light through the surfaces along shadow `ray` (unit direction), from
    /// `absorbed` (the medium's), surface by surface: [`Integrator::visibility`]'s walk, also
    /// the answer for a deferred shadow ray found blocked in a scene with culled backs.
    pub(super) fn passing_transmittance(&self, mut ray: Ray, absorbed: Vec3) -> Vec3 {
        let dir = ray.dir;
        let mut tr = absorbed;
        for _ in 0..MAX_ALPHA_PASSES {
            let Some(hit) = self.accel.intersect(&ray) else {
                return tr;
            };
            let s = self.hit_surface(&ray, &hit, true);
            tr *= match self.geom.kind(hit.instance, s.material) {
                // The back of a single-sided face is not there for this ray (glTF culling).
                _ if self.geom.is_culled(&s, dir) => Vec3::ONE,
                SurfaceKind::Opaque => Vec3::splat(self.geom.transmittance(&s)),
                SurfaceKind::Thin => {
                    self.geom
                        .pane_transmittance(&s, dir, self.energy_compensation)
                }
                SurfaceKind::Refractive => Vec3::ZERO,
            };
            if tr.max_element() <= 0.0 {
                return Vec3::ZERO;
            }
            let n = if s.ng.dot(dir) > 0.0 { s.ng } else { -s.ng };
            let error = self.accel.spawn_point(&ray, &hit).error;
            let o = SpawnPoint { p: s.p, error }.origin(n);
            let travelled = (o - ray.origin).dot(dir);
            ray.origin = o;
            ray.tmax -= travelled;
            if ray.tmax <= 0.0 {
                return tr;
            }
        }
        Vec3::ZERO
    }
}

/// The shadow ray from `origin` in unit direction `dir` towards a light `dist` away (stopping
/// just short of it), and the transmittance of the medium absorbing `sigma_a` over `dist`.
#[inline]
pub(super) fn shadow_ray(
    origin: Vec3,
    dir: Vec3,
    dist: f32,
    sigma_a: Vec3,
    time: f32,
) -> (Ray, Vec3) {
    let tmax = if dist.is_finite() {
        dist * (1.0 - 1e-4)
    } else {
        f32::INFINITY
    };
    let ray = Ray {
        origin,
        dir,
        tmin: 0.0,
        tmax,
        time,
    };
    let absorbed = if sigma_a == Vec3::ZERO {
        Vec3::ONE
    } else {
        let t = (-sigma_a * dist).exp();
        Vec3::select(sigma_a.cmpgt(Vec3::ZERO), t, Vec3::ONE)
    };
    (ray, absorbed)
}
