//! Which light a path vertex samples: one shadow ray per vertex, however many lights the scene
//! has (as pbrt-v4's exhaustive light sampler; an environment image keeps its own shadow ray).
//!
//! Every punctual light and the scene's emissive triangles (as one candidate) get an importance
//! at the vertex, and one is picked in proportion to it:
//! - a punctual light, its unoccluded irradiance on the side the vertex receives light from,
//!   exactly (zero only where it lights nothing);
//! - the emitters, a bound from their box, normal cone and power (pbrt-v4's
//!   `LightBounds::Importance`): zero only where no emitter can light the vertex.
//!
//! A light of zero importance contributes nothing there, so the pick is unbiased; a light of
//! positive importance is picked with that probability and its contribution divided by it.
//! Scenes with a single candidate never pick (see [`Candidates::choose`]).

use crate::color::luminance;
use crate::punctual::punctual_incident;
use aperture_scene::Light;
use glam::Vec3;

/// A bound on what a set of emissive triangles can send to a point: their box, the cone of
/// their normals and their power (two-sided emitters, as the integrator's).
#[derive(Debug, Clone, Copy)]
pub struct EmitterBounds {
    /// Centre and squared radius of a sphere around their box.
    centre: Vec3,
    radius2: f32,
    /// Axis, cosine and sine of the half-angle of a cone holding every triangle's normal.
    axis: Vec3,
    cos_o: f32,
    sin_o: f32,
    /// Total power, in the units of the punctual importance (radiance × area).
    phi: f32,
}

impl EmitterBounds {
    /// The bound of triangles given as `(vertices, power)`; `None` without any.
    pub fn new(triangles: impl IntoIterator<Item = ([Vec3; 3], f32)>) -> Option<Self> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut phi = 0.0f64;
        let mut normals = Vec::new();
        for (p, power) in triangles {
            for v in p {
                lo = lo.min(v);
                hi = hi.max(v);
            }
            phi += f64::from(power);
            // Area-weighted: the cone's axis leans to the triangles that carry the area.
            normals.push((p[1] - p[0]).cross(p[2] - p[0]));
        }
        if normals.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let sum: Vec3 = normals.iter().sum();
        let axis = sum.normalize_or_zero();
        // Each normal's angle to the axis, rounded outwards; a degenerate sum (normals that
        // cancel) leaves the whole sphere.
        let cos_o = if axis == Vec3::ZERO {
            -1.0
        } else {
            normals
                .iter()
                .filter_map(|n| n.try_normalize())
                .map(|n| n.dot(axis) - 1e-4)
                .fold(1.0f32, f32::min)
                .max(-1.0)
        };
        Some(Self {
            centre: (lo + hi) * 0.5,
            radius2: (hi - lo).length_squared() * 0.25,
            axis,
            cos_o,
            sin_o: (1.0 - cos_o * cos_o).max(0.0).sqrt(),
            phi: phi as f32,
        })
    }

    /// An upper bound, up to a constant factor, of the light these emitters send to a point
    /// `p` with normal `n` (facing the side light is received from), or from both sides of
    /// it when `two_sided`. Zero only where no emitter in the bound can light the point.
    pub fn importance(&self, p: Vec3, n: Vec3, two_sided: bool) -> f32 {
        let (centre, radius2) = (self.centre, self.radius2);
        let d2 = p.distance_squared(centre);
        // Directions from `p` into the bounding sphere: a cone of half-angle θ_b around the
        // centre's direction (every direction when `p` is inside).
        let (sin_b, cos_b) = if d2 <= radius2 {
            (0.0, -1.0)
        } else {
            let sin2 = radius2 / d2;
            (sin2.sqrt(), (1.0 - sin2).max(0.0).sqrt())
        };
        let to_p = (p - centre).normalize_or_zero();
        // The emitters' side: the angle between `to_p` and the normal cone, less θ_b (two-
        // sided emitters light both ways).
        let cos_w = self.axis.dot(to_p).abs();
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        let (sin_x, cos_x) = angle_less(sin_w, cos_w, self.sin_o, self.cos_o);
        let (_, cos_emit) = angle_less(sin_x, cos_x, sin_b, cos_b);
        // Area emitters light their whole hemisphere: nothing beyond 90° of every normal.
        if cos_emit <= 0.0 && d2 > radius2 {
            return 0.0;
        }
        // The receiver's side: the angle between its normal and the light's direction, less θ_b.
        let cos_i = if two_sided {
            n.dot(to_p).abs()
        } else {
            -n.dot(to_p)
        };
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        let (_, cos_recv) = angle_less(sin_i, cos_i, sin_b, cos_b);
        let importance = self.phi * cos_emit.max(0.0) * cos_recv.max(0.0) / d2.max(radius2);
        // NaN (a NaN point) lights nothing; an overflow stays the largest weight.
        if importance > 0.0 {
            importance.min(f32::MAX)
        } else {
            0.0
        }
    }
}

/// `(sin, cos)` of `max(θ_a − θ_b, 0)` from those of `θ_a` and `θ_b` (pbrt-v4's
/// `cosSubClamped` and `sinSubClamped`).
#[inline]
pub(crate) fn angle_less(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> (f32, f32) {
    if cos_a > cos_b {
        (0.0, 1.0)
    } else {
        (sin_a * cos_b - cos_a * sin_b, cos_a * cos_b + sin_a * sin_b)
    }
}

/// The importance of a punctual light at a point `p` with normal `n` facing the side light is
/// received from (both sides when `two_sided`): its unoccluded irradiance there, exactly.
#[inline]
pub fn punctual_importance(light: &Light, p: Vec3, n: Vec3, two_sided: bool) -> f32 {
    let Some((wi, _, e)) = punctual_incident(light, p) else {
        return 0.0;
    };
    let cos = n.dot(wi);
    let cos = if two_sided { cos.abs() } else { cos };
    let importance = luminance(e) * cos;
    if importance.is_finite() && importance > 0.0 {
        importance
    } else {
        0.0
    }
}

/// The light a vertex samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pick {
    /// The punctual light of this index.
    Punctual(usize),
    /// One of the emissive triangles (the caller picks which, by power, with [`Choice::u`]).
    Emitters,
    /// The emissive triangle of this index in [`crate::lights::EmissiveLights::triangles`],
    /// picked by the light tree ([`crate::light_tree`]).
    Triangle(usize),
}

/// A vertex's pick: which light, with what probability, and the probability that the
/// emitters are picked there (for the MIS weight of emitters that BSDF sampling meets).
#[derive(Debug, Clone, Copy)]
pub struct Choice {
    /// The light picked, `None` when there is nothing to pick.
    pub pick: Option<Pick>,
    /// Probability of that pick.
    pub probability: f32,
    /// Probability of picking the emitters here.
    pub emitters: f32,
    /// The uniform number left over after the pick, in `[0, 1)`.
    pub u: f32,
}

/// What a vertex may pick from: the punctual lights and the emitters' bound.
pub struct Candidates<'a> {
    /// The scene's punctual lights.
    pub lights: &'a [Light],
    /// The bound of the emissive triangles, if any.
    pub emitters: Option<&'a EmitterBounds>,
}

impl Candidates<'_> {
    /// Whether there is a choice to make (two candidates or more).
    pub fn choose(&self) -> bool {
        self.lights.len() + usize::from(self.emitters.is_some()) >= 2
    }

    /// One light at `p` (normal `n` on the side light is received from; both sides when
    /// `two_sided`) in proportion to the importances, from the uniform `u` (remapped into
    /// [`Choice::u`]). `pick` is `None` when no light can light the point.
    pub fn pick(&self, p: Vec3, n: Vec3, two_sided: bool, u: f32) -> Choice {
        // Up to `KEPT` punctual importances are kept from the sum for the walk; more are
        // computed again (the same arithmetic, so the same values).
        const KEPT: usize = 8;
        let mut kept = [0.0f32; KEPT];
        let w_emit = self.emitters.map_or(0.0, |b| b.importance(p, n, two_sided));
        let mut total = 0.0f32;
        for (i, l) in self.lights.iter().enumerate() {
            let w = punctual_importance(l, p, n, two_sided);
            if let Some(k) = kept.get_mut(i) {
                *k = w;
            }
            total += w;
        }
        total += w_emit;
        let mut choice = Choice {
            pick: None,
            probability: 0.0,
            emitters: 0.0,
            u,
        };
        if !(total > 0.0 && total.is_finite()) {
            return choice;
        }
        choice.emitters = w_emit / total;
        let weight = |pick: Pick| match pick {
            Pick::Punctual(i) => kept
                .get(i)
                .copied()
                .unwrap_or_else(|| punctual_importance(&self.lights[i], p, n, two_sided)),
            Pick::Emitters | Pick::Triangle(_) => w_emit,
        };
        // The same weights in the same order as `total`, so the walk ends where `target`
        // falls; should rounding leave it past the end, the last candidate that can light the
        // point takes the rest.
        let all = (0..self.lights.len())
            .map(Pick::Punctual)
            .chain([Pick::Emitters])
            .map(|pick| (pick, weight(pick)));
        if let Some((pick, w, x)) = walk(all, u * total) {
            choice.pick = Some(pick);
            choice.probability = w / total;
            choice.u = remap(x, w);
        }
        choice
    }
}

/// `x / w` in `[0, 1)`.
#[inline]
pub(crate) fn remap(x: f32, w: f32) -> f32 {
    (x / w).clamp(0.0, 1.0 - f32::EPSILON / 2.0)
}

/// The candidate where `target` (a uniform number times the weights' total) falls when the
/// `weighted` candidates are laid end to end in their order: the candidate, its weight and how
/// far into it `target` falls. Candidates of no weight are skipped; should rounding leave
/// `target` past the end, the last candidate with weight takes it. The caller's total must sum
/// the same weights in the same order.
#[inline]
pub(crate) fn walk<T>(
    weighted: impl IntoIterator<Item = (T, f32)>,
    target: f32,
) -> Option<(T, f32, f32)> {
    let mut below = 0.0f32;
    let mut last = None;
    for (c, w) in weighted {
        if w <= 0.0 {
            continue;
        }
        let end = target < below + w;
        last = Some((c, w, below));
        if end {
            break;
        }
        below += w;
    }
    last.map(|(c, w, below)| (c, w, target - below))
}

#[cfg(test)]
mod tests;
