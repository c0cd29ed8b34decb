//! The wavefront: the paths of a run of samples advanced together, one vertex at a time, so
//! that each ray query of the run is one batch — the camera rays as packets, then per round
//! every path's bounce ray and every shadow ray of the round — rather than one ray at a time
//! (pbrt-v4's wavefront integrator and Mitsuba 3's LLVM backend work in such streams).
//!
//! Each path runs exactly the arithmetic it runs alone ([`Integrator::advance`] is the one
//! vertex step of both): the batch queries return what one-ray queries do, and a path's
//! pending light samples are added back before its next vertex, in the order they were made.
//! So every sample's value is bit-identical to tracing it alone. A sample whose camera ray
//! meets nothing takes no path at all when no pass values are recorded: its radiance is what
//! the path's one step would add ([`Integrator::background`]).

use super::in_flight::PathInFlight;
use super::Integrator;
use crate::aov::SampleAov;
use crate::sampler::SampleStream;
use aperture_accel::{Hit, Ray};
use glam::Vec3;

/// A camera ray as the camera made it, ready to start a path: origin, unit direction, the
/// sample's stream, its normalised time in the shutter, and the colour channel it was made for
/// under chromatic aberration (`None`: all three).
#[derive(Debug, Clone, Copy)]
pub(crate) struct CameraStart {
    pub origin: Vec3,
    pub dir: Vec3,
    pub stream: SampleStream,
    pub time: f32,
    pub channel: Option<u8>,
}

/// Paths between asking for a hit's vertex data and shading it.
const AHEAD: usize = 4;

/// The buffers of a wavefront, kept from one run to the next.
#[derive(Default)]
pub(crate) struct Wavefront<const AOV: bool> {
    paths: Vec<PathInFlight<AOV>>,
    /// Indices of the paths still going.
    live: Vec<usize>,
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    shadows: Vec<Ray>,
    blocked: Vec<bool>,
}

impl<const AOV: bool> Wavefront<AOV> {
    /// Traces the paths of primary rays `starts` to
    /// their ends; [`Wavefront::results`] then gives each one's radiance, coverage and pass
    /// values, in order.
    pub fn run(&mut self, integrator: &Integrator<'_>, starts: &[CameraStart]) {
        let accel = integrator.accel;
        self.start_paths(integrator, starts);
        let mut camera_rays = true;
        while !self.live.is_empty() {
            if camera_rays {
                // The hits of the live paths' camera rays, in `live` order.
                let mut j = 0;
                for &i in &self.live {
                    self.hits[j] = self.hits[i];
                    j += 1;
                }
                self.hits.truncate(j);
                camera_rays = false;
            } else {
                let paths = &self.paths;
                self.rays.clear();
                self.rays
                    .extend(self.live.iter().filter_map(|&i| paths[i].ray()));
                self.hits.clear();
                self.hits.resize(self.rays.len(), None);
                accel.intersect_batch(&self.rays, &mut self.hits);
            }
            self.shadows.clear();
            let geom = &integrator.geom;
            for (k, (&i, &hit)) in self.live.iter().zip(&self.hits).enumerate() {
                // The hit data of later paths, asked for ahead (`Geometry::prefetch`): their
                // corner indices `2 AHEAD` paths ahead, their vertices `AHEAD` ahead.
                if geom.prefetch_hits {
                    if let Some(&Some(h)) = self.hits.get(k + 2 * AHEAD) {
                        geom.prefetch_corners(h.instance, h.triangle);
                    }
                    if let Some(&Some(h)) = self.hits.get(k + AHEAD) {
                        geom.prefetch(h.instance, h.triangle);
                    }
                }
                let p = &mut self.paths[i];
                integrator.advance(p, &starts[i].stream, hit);
                self.shadows.extend(p.shadow_rays());
            }
            self.resolve_shadows(integrator);
            let paths = &self.paths;
            self.live.retain(|&i| paths[i].live);
        }
    }

    /// Traces the camera rays of `starts` (a pixel's lens samples are coherent: packets) and
    /// sets up a path for each; a sample whose ray meets nothing is answered at once, without a
    /// path, where no pass needs one. The live paths' camera hits are left in `hits`.
    fn start_paths(&mut self, integrator: &Integrator<'_>, starts: &[CameraStart]) {
        let accel = integrator.accel;
        self.rays.clear();
        let camera_rays = starts.iter().map(|s| Ray {
            time: s.time,
            ..Ray::new(s.origin, s.dir)
        });
        self.rays.extend(camera_rays);
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        accel.intersect_packets(&self.rays, &mut self.hits);
        // Slots are re-initialised in place: their pending lists keep their capacity.
        self.paths.truncate(starts.len());
        self.live.clear();
        for (k, (s, hit)) in starts.iter().zip(&self.hits).enumerate() {
            let (origin, dir) = (s.origin, s.dir);
            if self.paths.len() == k {
                let fresh = integrator.start_path::<AOV>(origin, dir, true);
                self.paths.push(fresh);
            }
            let p = &mut self.paths[k];
            if !AOV && hit.is_none() {
                // A path ended by its camera ray: its slot only holds the result.
                p.path.l = match s.channel {
                    Some(c) => integrator.background(dir) * Integrator::channel_weight(c),
                    None => integrator.background(dir),
                };
                p.path.pending.clear();
                (p.covered, p.live) = (false, false);
            } else {
                integrator.restart_path(p, origin, dir, true);
                integrator.choose_channel(p, s.channel);
                p.w.ray.time = s.time;
                self.live.push(k);
            }
        }
    }

    /// Traces the shadow rays of this round's light samples and hands each path its answers.
    fn resolve_shadows(&mut self, integrator: &Integrator<'_>) {
        if !self.shadows.is_empty() {
            self.blocked.clear();
            self.blocked.resize(self.shadows.len(), false);
            integrator
                .accel
                .occluded_packets(&self.shadows, &mut self.blocked);
            // A blocked ray may only have met culled backs: those walk the surfaces.
            let culled = integrator.geom.has_culled;
            let through = |ray: Ray, absorbed: Vec3| {
                if culled {
                    integrator.past_culled_backs(ray, absorbed)
                } else {
                    Vec3::ZERO
                }
            };
            let mut at = 0;
            for &i in &self.live {
                let p = &mut self.paths[i];
                let n = p.path.pending.len();
                p.resolve(&self.blocked[at..at + n], through);
                at += n;
            }
        }
    }

    /// The results of the last [`Wavefront::run`], in the order of its `starts`: radiance,
    /// whether the camera ray hit geometry, pass values.
    pub fn results(&self) -> impl Iterator<Item = (Vec3, bool, &SampleAov)> + '_ {
        self.paths
            .iter()
            .map(|p| (p.path.l, p.covered, &p.path.aov))
    }
}
