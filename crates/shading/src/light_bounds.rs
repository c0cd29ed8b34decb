//! What a set of lights can send to a point: a box, a cone of emission directions and a power
//! (pbrt-v4's `LightBounds`), and the importance that bounds it at a receiving point. One type
//! for both choices of a light: the exhaustive choice ([`crate::light_choice`]) bounds all of a
//! scene's emissive triangles as one candidate ([`LightBounds::emitters`]), the light tree
//! ([`crate::light_tree`]) each light and each node's subtree, with pbrt's spread angle `θ_e`
//! so that spot lights bound their cone.

use aperture_scene::{Light, LightKind};
use glam::{Quat, Vec3};

/// Slack on cone cosines so that rounding never excludes a direction a light does reach.
const CONE_SLACK: f32 = 1e-4;

/// A bound on the light a set of lights sends out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBounds {
    /// Box around the lights' positions.
    pub lo: Vec3,
    /// Upper corner of the box.
    pub hi: Vec3,
    /// Power, in the units of [`crate::light_choice::punctual_importance`].
    pub phi: f32,
    /// Axis of the cone holding every emitting normal (or spot direction).
    pub axis: Vec3,
    /// Cosine of the cone's half-angle `θ_o` (−1: every direction).
    pub cos_o: f32,
    /// Cosine of how far beyond the cone light still leaves (`θ_e`: π/2 for area lights).
    pub cos_e: f32,
    /// Whether light leaves both sides of the cone's surfaces (emissive triangles).
    pub two_sided: bool,
}

impl LightBounds {
    /// The bound of a point or spot light; `None` for a directional light (no position) or a
    /// light that sends nothing.
    pub fn punctual(light: &Light, phi: f32) -> Option<Self> {
        if !(phi > 0.0 && phi.is_finite() && light.position.is_finite()) {
            return None;
        }
        let (axis, cos_o, cos_e) = match light.kind {
            LightKind::Directional => return None,
            LightKind::Point => (Vec3::Z, -1.0, 0.0),
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                let axis = light.direction.normalize_or_zero();
                let inner = inner_cone.clamp(0.0, outer_cone.max(0.0));
                // A cone past a hemisphere (or a nameless direction) is bounded as a point.
                if axis == Vec3::ZERO
                    || outer_cone.is_nan()
                    || outer_cone >= std::f32::consts::FRAC_PI_2
                {
                    (Vec3::Z, -1.0, 0.0)
                } else {
                    let cos_o = (inner.cos() - CONE_SLACK).max(-1.0);
                    let cos_e = ((outer_cone - inner).cos() - CONE_SLACK).max(0.0);
                    (axis, cos_o, cos_e)
                }
            }
        };
        Some(Self {
            lo: light.position,
            hi: light.position,
            phi,
            axis,
            cos_o,
            cos_e,
            two_sided: false,
        })
    }

    /// The bound of an emissive triangle (two-sided, as emitters are unless glTF's culling
    /// hides their backs: the tree's leaves make those one-sided) of power `phi`; `None` for
    /// non-finite corners or no power.
    pub fn triangle(p: [Vec3; 3], phi: f32) -> Option<Self> {
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        if !(phi > 0.0 && phi.is_finite() && lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let axis = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let cos_o = if axis == Vec3::ZERO { -1.0 } else { 1.0 };
        Some(Self {
            lo,
            hi,
            phi,
            axis,
            cos_o,
            cos_e: 0.0,
            two_sided: true,
        })
    }

    /// The bound of emissive triangles given as `(vertices, power)`, taken together as one
    /// light (the exhaustive choice's candidate): their box, a cone around their area-weighted
    /// mean normal holding every triangle's, their total power; two-sided, as the integrator's
    /// emitters. `None` without any, or with a non-finite box.
    pub fn emitters(triangles: impl IntoIterator<Item = ([Vec3; 3], f32)>) -> Option<Self> {
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
                .map(|n| n.dot(axis) - CONE_SLACK)
                .fold(1.0f32, f32::min)
                .max(-1.0)
        };
        Some(Self {
            lo,
            hi,
            phi: phi as f32,
            axis,
            cos_o,
            cos_e: 0.0,
            two_sided: true,
        })
    }

    /// The bound of both `self` and `other`.
    pub fn union(&self, other: &Self) -> Self {
        let two_sided = self.two_sided || other.two_sided;
        // Two-sided emitters light the same way along either normal: take the closer one.
        let b_axis = if self.two_sided && other.two_sided && self.axis.dot(other.axis) < 0.0 {
            -other.axis
        } else {
            other.axis
        };
        let (axis, cos_o) = cone_union(self.axis, self.cos_o, b_axis, other.cos_o);
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            axis,
            cos_o,
            cos_e: self.cos_e.min(other.cos_e),
            two_sided,
        }
    }

    /// Centre of the box.
    pub fn centre(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    /// Squared radius of the sphere around the box.
    pub(crate) fn radius2(&self) -> f32 {
        (self.hi - self.lo).length_squared() * 0.25
    }

    /// Sine of the cone's half-angle `θ_o`.
    pub(crate) fn sin_o(&self) -> f32 {
        sin_of(self.cos_o)
    }

    /// An upper bound, up to a constant factor, of the light these lights send to a point `p`
    /// with normal `n` (facing the side light is received from), or from both sides of it
    /// when `two_sided`. Zero only where none of the lights can light the point (pbrt-v4's
    /// `LightBounds::Importance`, with the cases that end at zero taken first);
    /// [`crate::light_tree`]'s 4-wide nodes compute the same, lane by lane.
    #[inline]
    pub fn importance(&self, p: Vec3, n: Vec3, two_sided: bool) -> f32 {
        let (centre, radius2) = (self.centre(), self.radius2());
        let d = p - centre;
        let d2 = d.length_squared();
        let to_p = d.normalize_or_zero();
        // The receiver's side: the angle between its normal and the light's direction.
        let cos_i = if two_sided {
            n.dot(to_p).abs()
        } else {
            -n.dot(to_p)
        };
        if d2 <= radius2 {
            // Inside the bounding sphere every direction is possible (θ_b = π): no cone
            // excludes the point and there is no falloff; a NaN normal lights nothing.
            let (_, cos_recv) = angle_less(sin_of(cos_i), cos_i, 0.0, -1.0);
            return clamp_importance(self.phi * cos_recv.max(0.0) / radius2);
        }
        // Directions from `p` into the bounding sphere: a cone of half-angle θ_b.
        let sin2_b = radius2 / d2;
        let (sin_b, cos_b) = (sin2_b.sqrt(), (1.0 - sin2_b).max(0.0).sqrt());
        // The receiver's side first, less θ_b: a surface facing away ends most visits here.
        let (_, cos_recv) = angle_less(sin_of(cos_i), cos_i, sin_b, cos_b);
        if cos_recv.is_nan() || cos_recv <= 0.0 {
            return 0.0;
        }
        // The lights' side: the angle between `to_p` and the normal cone, less θ_b (two-
        // sided emitters light both ways).
        let cos_w = self.axis.dot(to_p);
        let cos_w = if self.two_sided { cos_w.abs() } else { cos_w };
        let (sin_x, cos_x) = angle_less(sin_of(cos_w), cos_w, self.sin_o(), self.cos_o);
        let (_, cos_emit) = angle_less(sin_x, cos_x, sin_b, cos_b);
        if cos_emit <= self.cos_e {
            return 0.0;
        }
        clamp_importance(self.phi * cos_emit.max(0.0) * cos_recv / d2)
    }
}

/// `(sin, cos)` of `max(θ_a − θ_b, 0)` from those of `θ_a` and `θ_b` (pbrt-v4's
/// `cosSubClamped` and `sinSubClamped`).
#[inline]
fn angle_less(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> (f32, f32) {
    if cos_a > cos_b {
        (0.0, 1.0)
    } else {
        (sin_a * cos_b - cos_a * sin_b, cos_a * cos_b + sin_a * sin_b)
    }
}

/// `sin θ` from `cos θ` for `θ ∈ [0, π]`.
#[inline]
fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

/// An importance as the choices take it: NaN and negatives are zero, an overflow the largest
/// weight.
#[inline]
fn clamp_importance(importance: f32) -> f32 {
    if importance > 0.0 {
        importance.min(f32::MAX)
    } else {
        0.0
    }
}

/// The smallest cone (axis, cosine of half-angle) holding two cones (pbrt-v4's
/// `DirectionCone::Union`), widened by [`CONE_SLACK`] for rounding.
fn cone_union(a: Vec3, cos_a: f32, b: Vec3, cos_b: f32) -> (Vec3, f32) {
    // The whole sphere holds everything; the same axis needs no angle (and the build's buckets
    // meet both cases most: merged cones soon cover the sphere, a mesh's faces share normals).
    if cos_a <= -1.0 || cos_b <= -1.0 {
        return (a, -1.0);
    }
    if a == b {
        return (a, cos_a.min(cos_b));
    }
    let theta_a = cos_a.clamp(-1.0, 1.0).acos();
    let theta_b = cos_b.clamp(-1.0, 1.0).acos();
    let theta_d = angle_between(a, b);
    let pi = std::f32::consts::PI;
    if (theta_d + theta_b).min(pi) <= theta_a {
        return (a, cos_a);
    }
    if (theta_d + theta_a).min(pi) <= theta_b {
        return (b, cos_b);
    }
    let theta_o = (theta_a + theta_d + theta_b) * 0.5;
    if theta_o >= pi {
        return (a, -1.0);
    }
    let Some(w) = a.cross(b).try_normalize() else {
        return (a, -1.0);
    };
    let axis = Quat::from_axis_angle(w, theta_o - theta_a) * a;
    (axis, (theta_o.cos() - CONE_SLACK).max(-1.0))
}

/// The angle between unit vectors, accurate when they are close (pbrt's `AngleBetween`):
/// `acos` of their dot product is off by 3e-4 rad for vectors one rounding apart, which made
/// two triangles of one plane a cone around the whole sphere.
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    let half = |v: Vec3| (v.length() * 0.5).clamp(-1.0, 1.0).asin();
    if a.dot(b) < 0.0 {
        std::f32::consts::PI - 2.0 * half(a + b)
    } else {
        2.0 * half(a - b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_union_holds_both_cones() {
        let (axis, cos) = cone_union(Vec3::X, 1.0, Vec3::Y, 1.0);
        assert!(axis.dot(Vec3::X) >= cos && axis.dot(Vec3::Y) >= cos);
        assert!((cos - std::f32::consts::FRAC_PI_4.cos()).abs() < 1e-3);
        assert_eq!(cone_union(Vec3::X, 1.0, -Vec3::X, 1.0).1, -1.0);
    }

    /// Equal normals whose dot product rounds below 1 (two triangles of one plane) stay a
    /// narrow cone: their `acos` angle, 3e-4 rad with no axis to turn about, once made them
    /// the whole sphere.
    #[test]
    fn equal_normals_stay_a_narrow_cone() {
        let a = Vec3::new(0.473_290_1, 0.045_734_37, 0.879_718_6);
        assert!(a.dot(a) < 1.0, "the case needs a dot product below 1");
        let (axis, cos) = cone_union(a, 1.0, a, 1.0);
        assert!(cos > 0.999 && axis == a, "{cos}");
        assert_eq!(cone_union(a, 1.0, a, 0.5), (a, 0.5));
        let b = Vec3::new(a.x, a.y, f32::from_bits(a.z.to_bits() + 1));
        let (axis, cos) = cone_union(a, 1.0, b, 1.0);
        assert!(
            cos > 0.999 && axis.dot(a) >= cos && axis.dot(b) >= cos,
            "{cos}"
        );
        assert_eq!(cone_union(a, 1.0, b, -1.0).1, -1.0);
    }

    #[test]
    fn point_bound_is_zero_only_behind_the_receiver() {
        let light = Light {
            name: None,
            kind: LightKind::Point,
            position: Vec3::Y,
            direction: Vec3::NEG_Y,
            intensity: Vec3::ONE,
        };
        let b = LightBounds::punctual(&light, 1.0).unwrap();
        assert!(b.importance(Vec3::ZERO, Vec3::Y, false) > 0.0);
        assert_eq!(b.importance(Vec3::ZERO, Vec3::NEG_Y, false), 0.0);
        assert!(b.importance(Vec3::ZERO, Vec3::NEG_Y, true) > 0.0);
    }
}
