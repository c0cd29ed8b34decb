//! Unidirectional path tracing with next-event estimation: punctual lights by NEE alone (they are
//! deltas), emissive triangles and environment images by NEE and BSDF sampling combined with
//! multiple importance sampling (power heuristic). Russian roulette from the fourth vertex on.
//! Each vertex sends one shadow ray to one light, picked by its importance there among the
//! punctual lights and the emitters ([`aperture_shading::light_choice`]), plus one to an environment image.
//!
//! `max_bounces` has Blender Cycles' meaning: 0 is direct light only (the camera ray's hit is lit
//! by light sampling and by one BSDF-sampled ray that may find an emitter or the environment).
//!
//! Transmission (SPEC §5): ideal (delta) lobes are followed by BSDF sampling alone, which light
//! sampling cannot find, so emitters met after them weigh fully. Thin-walled ideal
//! transmission is a straight line: shadow rays pass it with its transmittance, and a path
//! passing it keeps the MIS state of the vertex before it (both strategies then see the same
//! light through the pane). Refractive boundaries block shadow rays (a bent path is no
//! straight line): caustics through refractive glass come from sampled paths, as in Cycles.
//! Inside a refractive body the path is absorbed by Beer–Lambert (its [`MediumStack`]).

mod direct;
mod in_flight;
mod path;
mod trace;
pub(crate) mod wavefront;

pub(crate) use in_flight::PathInFlight;
pub use path::Clamp;
use path::{Arrival, PathState, Walk};

use crate::aov::{Features, SampleAov, Seen};
use crate::sampler::{BounceSample, SampleStream};
use aperture_accel::{Accel, Hit, Ray, SpawnPoint};
use aperture_shading::bsdf::{Interface, LobeSplit};
use aperture_shading::environment::EnvLight;
use aperture_shading::light_tree::LightTree;
use aperture_shading::lights::EmissiveLights;
use aperture_shading::media::{Crossing, Medium};
use aperture_shading::spectrum;
use aperture_shading::surface::{shading_frame, view_normal, Geometry, SurfaceKind};
use aperture_shading::warp::power_heuristic;
use glam::Vec3;

/// Everything a path needs, shared by all threads.
pub(crate) struct Integrator<'a> {
    pub geom: Geometry<'a>,
    pub accel: &'a Accel,
    pub emissive: Option<&'a EmissiveLights>,
    /// The light tree, for scenes with many lights (else the exhaustive choice).
    pub light_tree: Option<std::sync::Arc<LightTree>>,
    pub env: EnvLight,
    pub max_bounces: u32,
    pub clamp: Clamp,
    /// Record the light passes (with `AOV`): the lobe split of every light sample is work that
    /// only they need.
    pub light_passes: bool,
    /// Multiple-scattering energy compensation of microfacet lobes (see `bsdf::energy`).
    pub energy_compensation: bool,
    /// Whether each vertex picks one light to sample (see [`aperture_shading::light_choice`]): the scene
    /// has two candidates or more (punctual lights, and its emitters as one).
    pub pick_light: bool,
    /// Per instance, how it moves within the shutter (empty: nothing moves): a surface found
    /// on a moving instance is moved to where the instance is at the ray's time.
    pub moving: &'a [Option<crate::motion::MovingInstance>],
    /// Per mesh, its vertices over the shutter when it deforms within it (empty: none does):
    /// a surface found on it is the triangle at the ray's time.
    pub deforming: &'a [Option<aperture_accel::VertexMotion>],
}

impl Integrator<'_> {
    /// Radiance along a primary ray (unit direction), whether it hit geometry, and the sample's
    /// pass values (recorded with `AOV`), traced one ray at a time: the reference of the render
    /// loop's [`wavefront::Wavefront`].
    #[cfg(test)]
    pub(crate) fn li_alone<const AOV: bool>(
        &self,
        origin: Vec3,
        dir: Vec3,
        stream: &SampleStream,
    ) -> (Vec3, bool, SampleAov) {
        let mut p = self.start_path::<AOV>(origin, dir, false);
        while let Some(ray) = p.ray() {
            let hit = self.accel.intersect(&ray);
            self.advance(&mut p, stream, hit);
        }
        p.finish()
    }

    /// The sample (radiance, coverage, pass values) of a camera ray along `dir` (unit) that
    /// meets nothing: a path started and advanced without a hit.
    pub(crate) fn missed_sample(
        &self,
        dir: Vec3,
        stream: &SampleStream,
    ) -> (Vec3, bool, SampleAov) {
        let mut p = self.start_path::<true>(Vec3::ZERO, dir, false);
        self.advance(&mut p, stream, None);
        (p.path.l, p.covered, p.path.aov)
    }

    /// A path starting with the primary ray from `origin` along `dir` (unit). With `defer`, its
    /// shadow rays wait in [`PathInFlight`] for [`PathInFlight::resolve`] where the scene lets
    /// them (no alpha-cut or thin-walled surfaces, which shadow rays pass through one hit at a
    /// time); otherwise [`Integrator::advance`] traces them as it goes.
    pub(crate) fn start_path<const AOV: bool>(
        &self,
        origin: Vec3,
        dir: Vec3,
        defer: bool,
    ) -> PathInFlight<AOV> {
        let mut p = PathInFlight {
            path: PathState {
                l: Vec3::ZERO,
                aov: SampleAov::default(),
                first_split: LobeSplit::DIFFUSE,
                features: Features::default(),
                light_passes: false,
                defer: false,
                pending: Vec::new(),
            },
            w: Walk::start(origin, dir),
            covered: false,
            live: true,
        };
        // The start itself in one place: `restart_path`.
        self.restart_path(&mut p, origin, dir, defer);
        p
    }

    /// Makes `p` (a path of this integrator's, ended or not) what [`Integrator::start_path`]
    /// would start, in place: a wavefront's slots are reused run after run, and a fresh path
    /// moved in would copy the whole of it. Its pending list keeps its capacity; without
    /// `AOV` the pass values, which nothing writes then, stay as they are.
    pub(crate) fn restart_path<const AOV: bool>(
        &self,
        p: &mut PathInFlight<AOV>,
        origin: Vec3,
        dir: Vec3,
        defer: bool,
    ) {
        let path = &mut p.path;
        path.l = Vec3::ZERO;
        if AOV {
            path.aov = SampleAov::default();
            path.first_split = LobeSplit::DIFFUSE;
            path.features = Features::default();
        }
        path.light_passes = self.light_passes;
        path.defer = defer && !self.geom.has_alpha && !self.geom.has_thin;
        path.pending.clear();
        p.w = Walk::start(origin, dir);
        p.covered = false;
        p.live = true;
    }

    /// The weight that keeps a path of channel `c`'s estimate unbiased: 3 on that channel, 0
    /// on the others.
    #[inline]
    pub(crate) fn channel_weight(c: u8) -> Vec3 {
        let mut weight = Vec3::ZERO;
        weight[usize::from(c.min(2))] = 3.0;
        weight
    }

    /// Makes a just-started path `p` carry channel `channel` ([`Integrator::channel_weight`]);
    /// `None`: all three.
    #[inline]
    pub(crate) fn choose_channel<const AOV: bool>(
        &self,
        p: &mut PathInFlight<AOV>,
        channel: Option<u8>,
    ) {
        if let Some(c) = channel {
            p.w.channel = Some(c);
            p.w.beta *= Self::channel_weight(c);
        }
    }

    /// One vertex of path `p`: `hit` is the closest hit of its ray ([`PathInFlight::ray`]).
    /// Adds what the vertex sees, samples the lights, and moves the path on to its next ray or
    /// ends it. With `AOV`, the sample's pass values are recorded; the radiance is the same bit
    /// for bit either way.
    pub(crate) fn advance<const AOV: bool>(
        &self,
        p: &mut PathInFlight<AOV>,
        stream: &SampleStream,
        hit: Option<Hit>,
    ) {
        debug_assert!(p.live && p.path.pending.is_empty());
        p.live = self.vertex(&mut p.path, &mut p.w, &mut p.covered, stream, hit);
    }

    /// [`Integrator::advance`]'s work; false ends the path.
    #[inline]
    fn vertex<const AOV: bool>(
        &self,
        path: &mut PathState<AOV>,
        w: &mut Walk,
        covered: &mut bool,
        stream: &SampleStream,
        hit: Option<Hit>,
    ) -> bool {
        // Alpha decisions need the light set before the trace; otherwise it (and the bounce
        // set) waits for a hit: most rays of open scenes escape and would draw them for nothing.
        let alpha_ls = self.geom.has_alpha.then(|| stream.vertex_light(w.vertex));
        let ray = w.ray;
        let u_alpha = alpha_ls.map_or(0.5, |l| l.alpha);
        let traced = self.trace(&ray, stream, w.vertex, u_alpha, Some(hit), w);
        let Some((hit, s, error)) = traced else {
            self.escape(path, w);
            return false;
        };
        if w.vertex == 0 {
            *covered = true;
        }
        let wo = -w.ray.dir;
        let ng = if s.ng.dot(wo) < 0.0 { -s.ng } else { s.ng };
        let shading = self.geom.shade(&s);
        let ns = view_normal(&s, &shading, ng, wo);
        if !self.light_seen(path, w, hit, &s, &shading, ng, ns) || w.scatter > self.max_bounces {
            return false;
        }
        let Some(mut bsdf) = shading.bsdf else {
            return false;
        };
        let (frame, wo_l) = shading_frame(ns, ng, shading.tangent, wo);
        let entering = w.ray.dir.dot(s.ng) < 0.0;
        let kind = if self.geom.has_refractive || self.geom.has_thin {
            self.geom.kind(hit.instance, s.material)
        } else {
            SurfaceKind::Opaque
        };
        let (interface, medium) = match kind {
            // Every surface of most scenes: no call.
            SurfaceKind::Opaque => (Interface::Opaque, None),
            _ => self.interface(kind, s.material, entering, stream, w),
        };
        bsdf.prepare(&frame, wo_l, interface, self.energy_compensation);
        if AOV && (path.light_passes || path.features.pending()) {
            path.record_surface(&bsdf, wo_l, w.vertex, ns);
        }
        let two_sided = bsdf.transmits() && kind != SurfaceKind::Refractive;
        let ls = alpha_ls.or_else(|| {
            (self.emissive.is_some() || self.pick_light).then(|| stream.vertex_light(w.vertex))
        });
        let choice = match (self.pick_light, &ls) {
            (true, Some(l)) => Some(match &self.light_tree {
                Some(t) => t.pick(&self.geom.scene.lights, s.p, ng, two_sided, l.light_pick),
                None => self.candidates().pick(s.p, ng, two_sided, l.light_pick),
            }),
            _ => None,
        };
        let v = direct::Vertex {
            bsdf: &bsdf,
            frame,
            wo_l,
            ng,
            p: s.p,
            // Our point is interpolated from the vertices; the accel's bound covers the rounding
            // of instanced transforms, which a few ulps of the point alone would not.
            p_out: SpawnPoint { p: s.p, error }.origin(ng),
            spawn: SpawnPoint { p: s.p, error },
            two_sided,
            scatter: w.scatter,
            vertex: w.vertex,
            sigma_a: w.media.sigma_a(),
            emitters: choice.map_or(1.0, |c| c.emitters),
            time: w.ray.time,
        };
        self.direct_lights(&v, w.beta, ls.as_ref(), choice, path);
        self.direct_environment(&v, w.beta, stream, path);
        let bs = stream.bounce(w.vertex);
        self.continue_path(&v, &bs, medium, entering, w, path)
    }

    /// What the path sees at surface `s` (shading normal `ns`, geometric `ng` on the viewer's
    /// side): an unlit colour, which ends the path (false), or emission, weighed by MIS. At the
    /// camera's hit, the passes record the surface.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn light_seen<const AOV: bool>(
        &self,
        path: &mut PathState<AOV>,
        w: &Walk,
        hit: Hit,
        s: &aperture_shading::surface::Surface,
        shading: &aperture_shading::surface::Shading,
        ng: Vec3,
        ns: Vec3,
    ) -> bool {
        if AOV && w.vertex == 0 {
            path.aov.normal = ns;
            path.aov.instance = hit.instance;
            path.aov.material = s.material;
        }
        if let Some(c) = shading.unlit {
            path.add(
                self.clamp.apply(w.beta * c, w.scatter),
                w.scatter,
                Seen::Surface,
            );
            if AOV {
                path.features.at_colour(&mut path.aov, c, ns);
            }
            return false;
        }
        if shading.emission != Vec3::ZERO {
            let mis = self.emitter_weight(&w.arrival, hit, s, ng, -w.ray.dir);
            // An emitter found after v scatterings has scattered v times on the way to
            // the camera.
            let c = self.clamp.apply(w.beta * shading.emission * mis, w.scatter);
            path.add(c, w.scatter, Seen::Surface);
        }
        true
    }

    /// Samples the BSDF at `v` and moves the walk on to its next ray (through `medium` when it
    /// crosses into it); false ends the path.
    #[inline(always)]
    fn continue_path<const AOV: bool>(
        &self,
        v: &direct::Vertex,
        bs: &BounceSample,
        medium: Option<Medium>,
        entering: bool,
        w: &mut Walk,
        path: &mut PathState<AOV>,
    ) -> bool {
        let bsdf = v.bsdf;
        let Some(sample) = bsdf.sample(v.wo_l, bs.lobe, bs.bsdf) else {
            return false;
        };
        let wi = v.frame.to_world(sample.wi);
        let side = wi.dot(v.ng);
        // Which side of the surface the path continues on is the geometric normal's call:
        // the shading normal may put a sampled direction on the other side than its lobe
        // meant. A surface that only reflects ends such a path (light would leak through
        // it); through one that transmits, the path goes on where the direction points,
        // crossing into the medium behind only if it does cross (as Mitsuba decides).
        let transmitted = side < 0.0;
        if side == 0.0 || (transmitted && !bsdf.transmits()) {
            return false;
        }
        let straight = sample.delta.is_some_and(|d| d.straight);
        let internal = sample.delta.is_some_and(|d| d.internal);
        if AOV && path.light_passes && w.scatter == 0 {
            path.first_split = match sample.delta {
                Some(d) => LobeSplit::pure(d.lobe),
                None => bsdf.lobe_split(v.wo_l, sample.wi),
            };
        }
        if transmitted {
            if let Some(m) = medium {
                w.media.cross(&m, entering);
            }
        }
        w.beta *= sample.weight();
        if !straight {
            // Light sampling covers the far side only where `two_sided` says so: an
            // emitter met through a refractive boundary was found by this sample alone.
            let unsampled = sample.delta.is_some() || (transmitted && !v.two_sided);
            w.arrival = Arrival {
                p: v.p,
                pdf: if unsampled { f32::INFINITY } else { sample.pdf },
                emitters: v.emitters,
                n: v.ng,
                two_sided: v.two_sided,
            };
        }
        if !w.survives_roulette(bs.rr) {
            return false;
        }
        let o = if transmitted {
            v.spawn.origin(-v.ng)
        } else {
            v.p_out
        };
        let time = w.ray.time;
        w.step(
            Ray {
                time,
                ..Ray::new(o, wi)
            },
            internal,
            straight,
        )
    }

    /// The MIS weight of an emitter at `s` found by a path that arrived as `arrival` says.
    fn emitter_weight(
        &self,
        arrival: &Arrival,
        hit: Hit,
        s: &aperture_shading::surface::Surface,
        ng: Vec3,
        wo: Vec3,
    ) -> f32 {
        if arrival.pdf.is_infinite() {
            return 1.0;
        }
        match &self.emissive {
            Some(em) => {
                let pick = match &self.light_tree {
                    Some(t) => em.light_index(hit.instance, hit.triangle).map_or(0.0, |i| {
                        let lights = &self.geom.scene.lights;
                        t.triangle_probability(lights, arrival.p, arrival.n, arrival.two_sided, i)
                    }),
                    None => em.pick_probability(hit.instance, hit.triangle) * arrival.emitters,
                };
                let cos_l = ng.dot(wo).abs();
                let d2 = (s.p - arrival.p).length_squared();
                let light_pdf = if cos_l > 0.0 && s.area > 0.0 {
                    pick / s.area * d2 / cos_l
                } else {
                    0.0
                };
                power_heuristic(arrival.pdf, light_pdf)
            }
            None => 1.0,
        }
    }

    /// The interface a surface of `kind` is for this path, and the medium behind it when it
    /// is a refractive boundary. A dispersive body makes the path choose its wavelength here.
    fn interface(
        &self,
        kind: SurfaceKind,
        material: u32,
        entering: bool,
        stream: &SampleStream,
        w: &mut Walk,
    ) -> (Interface, Option<Medium>) {
        match kind {
            SurfaceKind::Opaque => (Interface::Opaque, None),
            SurfaceKind::Thin => (Interface::Thin, None),
            SurfaceKind::Refractive => {
                let info = self.geom.info(material);
                let mut medium = info.medium;
                if info.dispersion > 0.0 {
                    let lambda = *w.wavelength.get_or_insert_with(|| match w.channel {
                        // The camera's channel (chromatic aberration): a wavelength of it.
                        Some(c) => {
                            let (_, u) = crate::lens::channel_of(stream.wavelength(0));
                            let (lambda, weight) = spectrum::sample_in_channel(c.into(), u);
                            w.beta *= weight;
                            lambda
                        }
                        None => {
                            let (lambda, weight) = spectrum::sample(stream.wavelength(w.vertex));
                            w.beta *= weight;
                            lambda
                        }
                    });
                    medium.ior = spectrum::dispersed_ior(medium.ior, info.dispersion, lambda);
                }
                match w.media.classify(&medium, entering) {
                    Crossing::Real { from, to } => {
                        (Interface::Refractive { eta: to / from }, Some(medium))
                    }
                    // `trace` passes false interfaces; never here.
                    Crossing::False => (Interface::Refractive { eta: 1.0 }, Some(medium)),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use aperture_shading::bsdf::bend_towards;

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
}
