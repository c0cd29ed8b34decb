//! Rays through a lens prescription, surface by surface (pbrt-v4's `TraceLensesFromFilm` and
//! `TraceLensesFromScene`): spherical surfaces, Snell's law, each surface's clear aperture and
//! the stop. Lens space is the camera's: the film at `z = 0`, the glass in front of it along
//! −Z, metres. A ray that misses a surface, falls outside an aperture or is totally reflected
//! inside the glass is blocked (`None`).

use glam::DVec3;

/// One surface in lens space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Surface {
    /// Radius of curvature, metres (positive: centre towards the film); 0 for the stop.
    pub radius: f64,
    /// `z` of the surface's vertex on the axis (negative: in front of the film).
    pub z: f64,
    /// Index of refraction behind the surface (towards the film); air is 1.
    pub eta: f64,
    /// Half the clear aperture, metres.
    pub half_aperture: f64,
}

impl Surface {
    /// Whether this is the aperture stop.
    pub fn is_stop(&self) -> bool {
        self.radius == 0.0
    }
}

/// A ray: origin and direction (not necessarily unit).
pub(crate) type Ray = (DVec3, DVec3);

/// Where ray `(o, d)` meets surface `s`, and the surface's normal there facing against `d`
/// (`None` for the stop's normal); `None` when it misses.
#[inline(always)]
fn hit(s: &Surface, (o, d): Ray) -> Option<(f64, Option<DVec3>)> {
    if s.is_stop() {
        if d.z == 0.0 {
            return None;
        }
        let t = (s.z - o.z) / d.z;
        return (t >= 0.0).then_some((t, None));
    }
    let centre = DVec3::new(0.0, 0.0, s.z + s.radius);
    let oc = o - centre;
    let a = d.length_squared();
    let b = 2.0 * d.dot(oc);
    let c = oc.length_squared() - s.radius * s.radius;
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    // The numerically stable roots.
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let (t0, t1) = if q == 0.0 {
        (0.0, 0.0)
    } else {
        let (r0, r1) = (q / a, c / q);
        (r0.min(r1), r0.max(r1))
    };
    // The surface's vertex side of the sphere: the nearer root when the ray runs towards the
    // centre's side of the vertex.
    let closer = (d.z > 0.0) ^ (s.radius < 0.0);
    let t = if closer { t0 } else { t1 };
    if t.is_nan() || t < 0.0 {
        return None;
    }
    let n = (oc + t * d).normalize();
    let n = if n.dot(d) > 0.0 { -n } else { n };
    Some((t, Some(n)))
}

/// The direction of unit `d` refracted at normal `n` (facing against `d`) from index `eta_i`
/// into `eta_t`; `None` on total internal reflection.
#[inline(always)]
pub(crate) fn refract(d: DVec3, n: DVec3, eta_i: f64, eta_t: f64) -> Option<DVec3> {
    let eta = eta_i / eta_t;
    let cos_i = -n.dot(d);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * d + (eta * cos_i - cos_t) * n)
}

/// One surface crossed: the ray moved to the hit and bent into `eta_t` (`eta_i` before).
#[inline(always)]
fn cross(s: &Surface, ray: Ray, eta_i: f64, eta_t: f64) -> Option<Ray> {
    let (t, n) = hit(s, ray)?;
    let p = ray.0 + t * ray.1;
    if p.x * p.x + p.y * p.y > s.half_aperture * s.half_aperture {
        return None;
    }
    match n {
        None => Some((p, ray.1)),
        Some(n) => Some((p, refract(ray.1.normalize(), n, eta_i, eta_t)?)),
    }
}

/// Ray `(o, d)` from the film side (running towards −Z) traced out of the front surface.
#[inline]
pub(crate) fn from_film(surfaces: &[Surface], mut ray: Ray) -> Option<Ray> {
    for i in (0..surfaces.len()).rev() {
        let s = &surfaces[i];
        if s.is_stop() && ray.1.z >= 0.0 {
            return None;
        }
        let eta_t = if i > 0 { surfaces[i - 1].eta } else { 1.0 };
        ray = cross(s, ray, s.eta, eta_t)?;
    }
    Some(ray)
}

/// Ray `(o, d)` from the scene side (running towards +Z) traced out of the rear surface;
/// `stop_height` gets its distance from the axis at the stop.
pub(crate) fn from_scene(
    surfaces: &[Surface],
    mut ray: Ray,
    mut stop_height: Option<&mut f64>,
) -> Option<Ray> {
    for (i, s) in surfaces.iter().enumerate() {
        if s.is_stop() && ray.1.z <= 0.0 {
            return None;
        }
        let eta_i = if i > 0 { surfaces[i - 1].eta } else { 1.0 };
        ray = cross(s, ray, eta_i, s.eta)?;
        if s.is_stop() {
            if let Some(h) = stop_height.as_deref_mut() {
                *h = ray.0.truncate().length();
            }
        }
    }
    Some(ray)
}
