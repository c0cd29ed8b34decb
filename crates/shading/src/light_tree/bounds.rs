//! What a set of lights can send to a point: a box, a cone of emission directions and a power
//! (pbrt-v4's `LightBounds`), for the light tree's leaves and inner nodes. The importance is
//! the one [`crate::light_choice::EmitterBounds`] gives the emitters as one candidate, with
//! pbrt's spread angle `θ_e` so that spot lights bound their cone.

use crate::light_choice::angle_less;
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

    /// The bound of an emissive triangle (two-sided, as the integrator's emitters) of power
    /// `phi`; `None` for non-finite corners or no power.
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

    /// An upper bound, up to a constant factor, of the light these lights send to a point `p`
    /// with normal `n` (facing the side light is received from), or from both sides of it
    /// when `two_sided`. Zero only where none of the lights can light the point.
    pub fn importance(&self, p: Vec3, n: Vec3, two_sided: bool) -> f32 {
        let centre = self.centre();
        let radius2 = (self.hi - self.lo).length_squared() * 0.25;
        let d2 = p.distance_squared(centre);
        // Directions from `p` into the bounding sphere: a cone of half-angle θ_b.
        let (sin_b, cos_b) = if d2 <= radius2 {
            (0.0, -1.0)
        } else {
            let sin2 = radius2 / d2;
            (sin2.sqrt(), (1.0 - sin2).max(0.0).sqrt())
        };
        let to_p = (p - centre).normalize_or_zero();
        let cos_w = self.axis.dot(to_p);
        let cos_w = if self.two_sided { cos_w.abs() } else { cos_w };
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        let sin_o = (1.0 - self.cos_o * self.cos_o).max(0.0).sqrt();
        let (sin_x, cos_x) = angle_less(sin_w, cos_w, sin_o, self.cos_o);
        let (_, cos_emit) = angle_less(sin_x, cos_x, sin_b, cos_b);
        if cos_emit <= self.cos_e && d2 > radius2 {
            return 0.0;
        }
        let cos_i = if two_sided {
            n.dot(to_p).abs()
        } else {
            -n.dot(to_p)
        };
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        let (_, cos_recv) = angle_less(sin_i, cos_i, sin_b, cos_b);
        // Inside the sphere every direction is possible: no emission falloff.
        let emit = if d2 <= radius2 { 1.0 } else { cos_emit };
        let importance = self.phi * emit.max(0.0) * cos_recv.max(0.0) / d2.max(radius2);
        if importance > 0.0 {
            importance.min(f32::MAX)
        } else {
            0.0
        }
    }
}

/// The smallest cone (axis, cosine of half-angle) holding two cones (pbrt-v4's
/// `DirectionCone::Union`), widened by [`CONE_SLACK`] for rounding.
fn cone_union(a: Vec3, cos_a: f32, b: Vec3, cos_b: f32) -> (Vec3, f32) {
    let theta_a = cos_a.clamp(-1.0, 1.0).acos();
    let theta_b = cos_b.clamp(-1.0, 1.0).acos();
    let theta_d = a.dot(b).clamp(-1.0, 1.0).acos();
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
