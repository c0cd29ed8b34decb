//! The exit pupil seen from the film (pbrt-v4's `BoundExitPupil` and `SampleExitPupil`): for
//! each of [`BINS`] rings of film radius, the bounds on the rear element's plane of the points
//! whose rays from that ring pass through the whole lens, found once by tracing a
//! low-discrepancy set of rays; a sample's lens point is drawn uniformly in its ring's bounds,
//! rotated to its film point's angle.

use super::trace::{from_film, Surface};
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Rings of film radius, centre to corner (pbrt-v4's 64).
pub const BINS: usize = 64;
/// How far out on the rear element's vertex plane the search for passing points reaches, in
/// rear radii (pbrt's 1.5: where the rear surface curves, rays aimed outside its rim on that
/// plane can still pass).
pub const REAR_REACH: f64 = 1.5;
/// Rays traced per ring to find its bounds.
const RAYS_PER_BIN: u32 = 1 << 14;

/// An axis-aligned rectangle on the rear element's plane (metres); empty when `min > max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bounds {
    pub min: DVec2,
    pub max: DVec2,
}

impl Bounds {
    const EMPTY: Self = Self {
        min: DVec2::splat(f64::INFINITY),
        max: DVec2::splat(f64::NEG_INFINITY),
    };

    /// Whether it holds no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y)
    }

    fn contains(&self, p: DVec2) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    fn add(&mut self, p: DVec2) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Its area (0 when empty).
    pub fn area(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            (self.max - self.min).element_product()
        }
    }

    /// The point at `u ∈ [0,1)²` of it.
    pub fn lerp(&self, u: DVec2) -> DVec2 {
        self.min + u * (self.max - self.min)
    }
}

/// `i`'s radical inverse in base `b` (the Halton sequence's coordinate).
fn radical_inverse(mut i: u32, b: u32) -> f64 {
    let (mut inv, mut f) = (0.0, 1.0 / f64::from(b));
    while i > 0 {
        inv += f * f64::from(i % b);
        i /= b;
        f /= f64::from(b);
    }
    inv
}

/// The exit pupil's bounds of the film ring `[r0, r1]` (metres from the axis), traced along
/// +X: every rear-plane point (within 1.5 rear radii) whose ray from the ring passes.
fn ring_bounds(surfaces: &[Surface], r0: f64, r1: f64) -> Bounds {
    let Some(rear) = surfaces.last() else {
        return Bounds::EMPTY;
    };
    let extent = REAR_REACH * rear.half_aperture;
    let mut b = Bounds::EMPTY;
    for i in 0..RAYS_PER_BIN {
        let x = r0 + (r1 - r0) * ((f64::from(i) + 0.5) / f64::from(RAYS_PER_BIN));
        let film = DVec3::new(x, 0.0, 0.0);
        let u = DVec2::new(radical_inverse(i, 2), radical_inverse(i, 3));
        let p = (2.0 * u - 1.0) * extent;
        if b.contains(p) || from_film(surfaces, (film, p.extend(rear.z) - film)).is_some() {
            b.add(p);
        }
    }
    if b.is_empty() {
        return b;
    }
    // Grown by two sample spacings: the points between the traced ones.
    let grow = 2.0 * (2.0 * extent * std::f64::consts::SQRT_2) / f64::from(RAYS_PER_BIN).sqrt();
    Bounds {
        min: b.min - grow,
        max: b.max + grow,
    }
}

/// The exit pupil's bounds for each of [`BINS`] rings out to `film_radius` (the film's half
/// diagonal), traced in parallel.
pub(crate) fn exit_pupil(surfaces: &[Surface], film_radius: f64) -> Vec<Bounds> {
    (0..BINS)
        .into_par_iter()
        .map(|i| {
            let r0 = film_radius * i as f64 / BINS as f64;
            let r1 = film_radius * (i + 1) as f64 / BINS as f64;
            ring_bounds(surfaces, r0, r1)
        })
        .collect()
}

/// The ring of film point `p` (metres from the axis).
#[inline(always)]
pub(crate) fn bin(p: DVec2, film_radius: f64) -> usize {
    let r = p.length() / film_radius * BINS as f64;
    (r as usize).min(BINS - 1)
}

/// The rear-plane point of film point `p` for lens numbers `u`: uniform in its ring's bounds
/// (drawn along +X) turned to `p`'s angle; and the bounds' area, the sample's density's inverse.
#[inline(always)]
pub(crate) fn sample(bounds: &Bounds, p: DVec2, u: DVec2) -> (DVec2, f64) {
    let q = bounds.lerp(u);
    (rotate_to(q, p), bounds.area())
}

/// Point `q`, given for a film point on +X, turned to film point `p`'s angle.
#[inline(always)]
pub(crate) fn rotate_to(q: DVec2, p: DVec2) -> DVec2 {
    let r = p.length();
    let (sin, cos) = if r > 0.0 {
        (p.y / r, p.x / r)
    } else {
        (0.0, 1.0)
    };
    DVec2::new(cos * q.x - sin * q.y, sin * q.x + cos * q.y)
}
