//! Unidirectional path tracing with next-event estimation: punctual lights by NEE alone (they are
//! deltas), emissive triangles and environment images by NEE and BSDF sampling combined with
//! multiple importance sampling (power heuristic). Russian roulette from the fourth vertex on.
//!
//! `max_bounces` has Blender Cycles' meaning: 0 is direct light only (the camera ray's hit is lit
//! by light sampling and by one BSDF-sampled ray that may find an emitter or the environment).

use crate::aov::{Features, SampleAov, Seen};
use crate::bsdf::{Bsdf, Frame, LobeSplit};
use crate::environment::EnvLight;
use crate::lights::{punctual_incident, EmissiveLights};
use crate::sampler::{BounceSample, SampleStream};
use crate::surface::{Geometry, Surface};
use aperture_accel::{Accel, Hit, Ray, SpawnPoint};
use glam::Vec3;

/// Vertices before Russian roulette may end a path.
const RR_START: u32 = 3;
/// Surfaces a single ray may pass through by alpha before it is stopped.
const MAX_ALPHA_PASSES: u32 = 64;

/// Everything a path needs, shared by all threads.
pub(crate) struct Integrator<'a> {
    pub geom: Geometry<'a>,
    pub accel: &'a Accel,
    pub emissive: Option<EmissiveLights>,
    pub env: EnvLight,
    pub max_bounces: u32,
    pub clamp: Clamp,
    /// Record the light passes (with `AOV`): the lobe split of every light sample is work that
    /// only they need.
    pub light_passes: bool,
}

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
    fn apply(self, c: Vec3, scatterings: u32) -> Vec3 {
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

/// Smallest cosine between the view and a shading normal.
const MIN_VIEW_COS: f32 = 0.02;

/// A shading normal bent just far enough towards the viewer `wo` that `wo` is above its
/// hemisphere. Normal maps and interpolated normals can face away from the viewer; shading with
/// such a normal would see the view below the surface and return black. Bending (instead of
/// switching to the geometric normal) keeps the result continuous as the normal crosses over.
fn bend_towards(n: Vec3, wo: Vec3) -> Vec3 {
    let c = n.dot(wo);
    if c >= MIN_VIEW_COS {
        return n;
    }
    (n + wo * (MIN_VIEW_COS - c)).try_normalize().unwrap_or(wo)
}

/// Power heuristic with β = 2.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a2.is_infinite() {
        1.0
    } else {
        0.0
    }
}

impl Integrator<'_> {
    /// The closest opaque hit along `ray`, passing through alpha-cut or blended surfaces, with
    /// the rounding-error bound of the hit point (from the ray segment that found it).
    /// `first`, when given, is `accel.intersect(ray)` already found (by a batch query).
    fn trace(
        &self,
        ray: &Ray,
        stream: &SampleStream,
        vertex: u32,
        u_alpha: f32,
        mut first: Option<Option<Hit>>,
    ) -> Option<(Hit, Surface, f32)> {
        let mut r = *ray;
        for pass in 0..MAX_ALPHA_PASSES {
            let hit = match first.take() {
                Some(hit) => hit?,
                None => self.accel.intersect(&r)?,
            };
            let s = self.geom.surface(hit.instance, hit.triangle, hit.u, hit.v);
            let error = self.accel.spawn_point(&r, &hit).error;
            if !self.geom.has_alpha {
                return Some((hit, s, error));
            }
            let u = if pass == 0 {
                u_alpha
            } else {
                stream.extra(vertex, pass)
            };
            if self.geom.is_opaque(&s, u) {
                return Some((hit, s, error));
            }
            // Continue on the far side of the surface.
            let n = if s.ng.dot(r.dir) > 0.0 { s.ng } else { -s.ng };
            r = Ray::new(SpawnPoint { p: s.p, error }.origin(n), r.dir);
        }
        None
    }

    /// The first surface along a ray (unit direction) that is opaque at coverage ½: what the
    /// Depth and Position passes show. Deterministic, unlike a sample: alpha-blended surfaces
    /// count as solid where their alpha is at least ½.
    pub fn first_surface(&self, origin: Vec3, dir: Vec3) -> Option<Vec3> {
        let mut r = Ray::new(origin, dir);
        for _ in 0..MAX_ALPHA_PASSES {
            let hit = self.accel.intersect(&r)?;
            let s = self.geom.surface(hit.instance, hit.triangle, hit.u, hit.v);
            if !self.geom.has_alpha || self.geom.is_opaque(&s, 0.5) {
                return Some(s.p);
            }
            let error = self.accel.spawn_point(&r, &hit).error;
            let n = if s.ng.dot(r.dir) > 0.0 { s.ng } else { -s.ng };
            r = Ray::new(SpawnPoint { p: s.p, error }.origin(n), r.dir);
        }
        None
    }

    /// Fraction of light arriving along a shadow ray from `origin` in unit direction `dir` over
    /// `dist`.
    fn visibility(&self, origin: Vec3, dir: Vec3, dist: f32) -> f32 {
        let tmax = if dist.is_finite() {
            dist * (1.0 - 1e-4)
        } else {
            f32::INFINITY
        };
        let mut ray = Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax,
        };
        if !self.geom.has_alpha {
            return if self.accel.occluded(&ray) { 0.0 } else { 1.0 };
        }
        let mut tr = 1.0;
        for _ in 0..MAX_ALPHA_PASSES {
            let Some(hit) = self.accel.intersect(&ray) else {
                return tr;
            };
            let s = self.geom.surface(hit.instance, hit.triangle, hit.u, hit.v);
            tr *= self.geom.transmittance(&s);
            if tr <= 0.0 {
                return 0.0;
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
        0.0
    }

    /// Radiance along a primary ray (unit direction), and whether it hit geometry. (The render
    /// loop traces primary rays in batches and calls [`Integrator::li_with_first_hit`].)
    #[cfg(test)]
    pub fn li(&self, origin: Vec3, dir: Vec3, stream: &SampleStream) -> (Vec3, bool) {
        self.li_from::<false>(origin, dir, stream, None, &mut SampleAov::default())
    }

    /// [`Integrator::li`] with the primary ray's closest hit already found:
    /// `first = accel.intersect(&Ray::new(origin, dir))` (from a batch query; the result is the
    /// same as `li`'s). With `AOV`, the sample's pass values are recorded into `aov` (which
    /// must start as [`SampleAov::default`]); the radiance is the same bit for bit either way.
    pub fn li_with_first_hit<const AOV: bool>(
        &self,
        origin: Vec3,
        dir: Vec3,
        stream: &SampleStream,
        first: Option<Hit>,
        aov: &mut SampleAov,
    ) -> (Vec3, bool) {
        self.li_from::<AOV>(origin, dir, stream, Some(first), aov)
    }

    #[inline]
    fn li_from<const AOV: bool>(
        &self,
        origin: Vec3,
        dir: Vec3,
        stream: &SampleStream,
        mut first: Option<Option<Hit>>,
        aov: &mut SampleAov,
    ) -> (Vec3, bool) {
        let mut path = PathState::<AOV> {
            l: Vec3::ZERO,
            aov,
            first_split: LobeSplit::DIFFUSE,
            features: Features::default(),
            light_passes: self.light_passes,
        };
        let mut beta = Vec3::ONE;
        let mut ray = Ray::new(origin, dir);
        let mut prev_p = origin;
        let mut prev_pdf = 0.0f32;
        let mut covered = false;
        let mut vertex = 0u32;
        loop {
            let bs = stream.bounce(vertex);
            let Some((hit, s, error)) = self.trace(&ray, stream, vertex, bs.alpha, first.take())
            else {
                self.escape(&mut path, beta, ray.dir, vertex, prev_pdf);
                break;
            };
            if vertex == 0 {
                covered = true;
            }
            let wo = -ray.dir;
            let ng = if s.ng.dot(wo) < 0.0 { -s.ng } else { s.ng };
            let shading = self.geom.shade(&s);
            // Both sides are shaded: the (mapped) normal turns with the vertex normal to the
            // viewer's side of the surface.
            let ns = if s.ns.dot(ng) < 0.0 {
                -shading.normal
            } else {
                shading.normal
            };
            let ns = bend_towards(ns, wo);
            if AOV && vertex == 0 {
                path.aov.normal = ns;
                path.aov.instance = hit.instance;
                path.aov.material = s.material;
            }
            if let Some(c) = shading.unlit {
                path.add(self.clamp.apply(beta * c, vertex), vertex, Seen::Surface);
                if AOV {
                    path.features.at_colour(path.aov, c, ns);
                }
                break;
            }
            if shading.emission != Vec3::ZERO {
                let w = if vertex == 0 {
                    1.0
                } else {
                    match &self.emissive {
                        Some(em) => {
                            let pick = em.pick_probability(hit.instance, hit.triangle);
                            let cos_l = ng.dot(wo).abs();
                            let d2 = (s.p - prev_p).length_squared();
                            let light_pdf = if cos_l > 0.0 && s.area > 0.0 {
                                pick / s.area * d2 / cos_l
                            } else {
                                0.0
                            };
                            power_heuristic(prev_pdf, light_pdf)
                        }
                        None => 1.0,
                    }
                };
                // An emitter found from vertex v has scattered v times on the way to the camera.
                let c = self.clamp.apply(beta * shading.emission * w, vertex);
                path.add(c, vertex, Seen::Surface);
            }
            if vertex > self.max_bounces {
                break;
            }
            let Some(bsdf) = shading.bsdf else { break };
            // `bend_towards` keeps the view above the shading hemisphere; if rounding still
            // says otherwise, fall back to the geometric frame rather than return black.
            let mut frame = Frame::from_normal(ns);
            let mut wo_l = frame.to_local(wo);
            if wo_l.z <= 0.0 {
                frame = Frame::from_normal(ng);
                wo_l = frame.to_local(wo);
            }
            if AOV && (path.light_passes || path.features.pending()) {
                let albedos = bsdf.albedos(wo_l);
                if vertex == 0 {
                    path.aov.set_colours(&albedos);
                }
                let rough = bsdf.glossy_is_rough();
                path.features.at_surface(path.aov, &albedos, rough, ns);
            }
            let v = Vertex {
                bsdf: &bsdf,
                frame,
                wo_l,
                ng,
                p: s.p,
                // Our point is interpolated from the vertices; the accel's bound covers the
                // rounding of instanced transforms, which a few ulps of the point alone would
                // not.
                p_out: SpawnPoint { p: s.p, error }.origin(ng),
                vertex,
            };
            self.direct_punctual(&v, beta, &mut path);
            self.direct_emissive(&v, beta, &bs, &mut path);
            self.direct_environment(&v, beta, stream, &mut path);

            let Some(sample) = bsdf.sample(wo_l, bs.lobe, bs.bsdf) else {
                break;
            };
            let wi = frame.to_world(sample.wi);
            if wi.dot(ng) <= 0.0 {
                break;
            }
            if AOV && path.light_passes && vertex == 0 {
                path.first_split = bsdf.lobe_split(wo_l, sample.wi);
            }
            beta *= sample.f * (sample.wi.z / sample.pdf);
            prev_pdf = sample.pdf;
            if vertex >= RR_START {
                // Survive with probability q and divide by it: unbiased.
                let q = beta.max_element().min(1.0);
                if bs.rr >= q || q.is_nan() {
                    break;
                }
                beta /= q;
            }
            if beta == Vec3::ZERO {
                break;
            }
            prev_p = s.p;
            ray = Ray::new(v.p_out, wi);
            vertex += 1;
        }
        (path.l, covered)
    }

    /// A ray leaving the scene after `vertex` scatterings: the environment it sees. A
    /// constant environment is found by BSDF sampling alone (weight 1); an image is also
    /// light-sampled, so escaping BSDF rays share it by MIS.
    fn escape<const AOV: bool>(
        &self,
        path: &mut PathState<'_, AOV>,
        beta: Vec3,
        dir: Vec3,
        vertex: u32,
        prev_pdf: f32,
    ) {
        if vertex == 0 {
            let seen = self.env.radiance_seen(dir);
            path.add(self.clamp.apply(beta * seen, 0), 0, Seen::Environment);
            if AOV {
                path.features.at_colour(path.aov, seen, Vec3::ZERO);
            }
            return;
        }
        let w = if self.env.is_sampled() {
            power_heuristic(prev_pdf, self.env.pdf(dir))
        } else {
            1.0
        };
        let radiance = self.env.radiance(dir);
        path.add(
            self.clamp.apply(beta * radiance * w, vertex),
            vertex,
            Seen::Environment,
        );
        if AOV {
            path.features.at_colour(path.aov, radiance, Vec3::ZERO);
        }
    }

    /// Next-event estimation towards every punctual light (deltas: light sampling only).
    fn direct_punctual<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        path: &mut PathState<'_, AOV>,
    ) {
        for light in &self.geom.scene.lights {
            let Some((wi, dist, e)) = punctual_incident(light, v.p) else {
                continue;
            };
            if wi.dot(v.ng) <= 0.0 || e == Vec3::ZERO {
                continue;
            }
            let wi_l = v.frame.to_local(wi);
            let (f, _) = v.bsdf.eval(v.wo_l, wi_l);
            let c = beta * f * wi_l.z * e;
            if c != Vec3::ZERO {
                let dist = if dist.is_finite() {
                    (light.position - v.p_out).length()
                } else {
                    dist
                };
                self.add_direct(v, path, c, wi_l, wi, dist);
            }
        }
    }

    /// Next-event estimation towards one emissive triangle picked by power, weighted against
    /// BSDF sampling by MIS.
    fn direct_emissive<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        bs: &BounceSample,
        path: &mut PathState<'_, AOV>,
    ) {
        let Some(em) = &self.emissive else { return };
        let i = em.table.sample(bs.light_pick);
        let t = em.triangles[i];
        let (a, b) = (bs.light[0].sqrt(), bs.light[1]);
        let q = self
            .geom
            .surface(t.instance, t.triangle, a * (1.0 - b), a * b);
        let d = q.p - v.p;
        let d2 = d.length_squared();
        let dist = d2.sqrt();
        let wi = d / dist;
        let cos_l = q.ng.dot(wi).abs();
        if d2 > 0.0 && cos_l > 0.0 && wi.dot(v.ng) > 0.0 && q.area > 0.0 {
            let light_pdf = em.table.pmf(i) / q.area * d2 / cos_l;
            let wi_l = v.frame.to_local(wi);
            let (f, bsdf_pdf) = v.bsdf.eval(v.wo_l, wi_l);
            let le = self.geom.emission(&q);
            let c = beta * f * wi_l.z * le * (power_heuristic(light_pdf, bsdf_pdf) / light_pdf);
            if c != Vec3::ZERO && c.is_finite() {
                let qn = if q.ng.dot(wi) < 0.0 { q.ng } else { -q.ng };
                let target = self.accel.surface_point(t.instance, q.p).origin(qn);
                let to = target - v.p_out;
                let len = to.length();
                self.add_direct(v, path, c, wi_l, to / len, len);
            }
        }
    }

    /// Next-event estimation towards an environment image, weighted against BSDF sampling by
    /// MIS. Only an image is light-sampled; a constant colour is met by BSDF rays alone, so
    /// its pair of sample values (two scrambled Sobol dimensions) is not even drawn.
    fn direct_environment<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        beta: Vec3,
        stream: &SampleStream,
        path: &mut PathState<'_, AOV>,
    ) {
        if !self.env.is_sampled() {
            return;
        }
        let Some(es) = self.env.sample(stream.environment(v.vertex)) else {
            return;
        };
        let wi_l = v.frame.to_local(es.wi);
        if es.wi.dot(v.ng) > 0.0 && es.radiance != Vec3::ZERO {
            let (f, bsdf_pdf) = v.bsdf.eval(v.wo_l, wi_l);
            let c = beta * f * wi_l.z * es.radiance * (power_heuristic(es.pdf, bsdf_pdf) / es.pdf);
            if c != Vec3::ZERO && c.is_finite() {
                self.add_direct(v, path, c, wi_l, es.wi, f32::INFINITY);
            }
        }
    }

    /// The contribution every light sample shares: `c` (light over its density, through the
    /// BSDF) clamped as light after one more scattering, times the shadow ray's visibility
    /// from the vertex along `dir` over `dist`; `wi_l` is the local light direction, which
    /// splits the contribution among the lobes at the first vertex.
    #[inline]
    fn add_direct<const AOV: bool>(
        &self,
        v: &Vertex<'_>,
        path: &mut PathState<'_, AOV>,
        c: Vec3,
        wi_l: Vec3,
        dir: Vec3,
        dist: f32,
    ) {
        let lit = self.clamp.apply(c, v.vertex + 1) * self.visibility(v.p_out, dir, dist);
        path.l += lit;
        if AOV && path.light_passes {
            let split = if v.vertex == 0 {
                v.bsdf.lobe_split(v.wo_l, wi_l)
            } else {
                path.first_split
            };
            path.aov.add_light(lit, v.vertex + 1, &split, Seen::Surface);
        }
    }
}

/// A scattering vertex, as the light-sampling routines see it.
struct Vertex<'b> {
    bsdf: &'b Bsdf,
    frame: Frame,
    /// The view direction, local.
    wo_l: Vec3,
    /// Geometric normal on the viewer's side.
    ng: Vec3,
    /// The surface point.
    p: Vec3,
    /// Where rays leave the surface.
    p_out: Vec3,
    /// Scatterings before this vertex.
    vertex: u32,
}

/// One path's running sums.
struct PathState<'a, const AOV: bool> {
    /// Radiance so far.
    l: Vec3,
    /// The sample's pass values (untouched unless `AOV`).
    aov: &'a mut SampleAov,
    /// How the first vertex's sampled direction split among the lobes.
    first_split: LobeSplit,
    features: Features,
    light_passes: bool,
}

impl<const AOV: bool> PathState<'_, AOV> {
    /// Adds light that reached the camera after `scatterings` scatterings.
    #[inline]
    fn add(&mut self, c: Vec3, scatterings: u32, seen: Seen) {
        self.l += c;
        if AOV && self.light_passes {
            self.aov.add_light(c, scatterings, &self.first_split, seen);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bent_normals_face_the_viewer() {
        let wo = Vec3::new(0.0, 0.6, 0.8);
        // Already facing: unchanged.
        assert_eq!(bend_towards(Vec3::Z, wo), Vec3::Z);
        for n in [
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, -0.8, 0.6),
            -wo,
            Vec3::new(1.0, -0.6, 0.0).normalize(),
        ] {
            let b = bend_towards(n, wo);
            assert!(b.is_finite() && (b.length() - 1.0).abs() < 1e-5, "{b}");
            assert!(b.dot(wo) > 0.0, "{n} -> {b}");
        }
    }

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

    #[test]
    fn power_heuristic_limits() {
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert!((power_heuristic(1.0, 1.0) - 0.5).abs() < 1e-7);
        assert!((power_heuristic(3.0, 1.0) + power_heuristic(1.0, 3.0) - 1.0).abs() < 1e-7);
    }
}
