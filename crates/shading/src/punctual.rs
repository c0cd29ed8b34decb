//! What a punctual light (point, spot, directional; `KHR_lights_punctual`) delivers to a
//! point: one place for the falloff that light choice estimates and the integrator samples.

use aperture_scene::{Light, LightKind};
use glam::Vec3;

/// Incident light from a punctual light at `p`: direction towards the light, distance (∞ for
/// directional) and the radiance-times-solid-angle it delivers (irradiance at normal incidence).
#[inline]
pub fn punctual_incident(light: &Light, p: Vec3) -> Option<(Vec3, f32, Vec3)> {
    match light.kind {
        LightKind::Directional => Some((-light.direction, f32::INFINITY, light.intensity)),
        LightKind::Point | LightKind::Spot { .. } => {
            let d = light.position - p;
            let d2 = d.length_squared();
            if d2 <= 0.0 || d2.is_nan() {
                return None;
            }
            let dist = d2.sqrt();
            let wi = d / dist;
            let mut e = light.intensity / d2;
            if let LightKind::Spot {
                inner_cone,
                outer_cone,
            } = light.kind
            {
                // glTF's smooth falloff between the cones.
                let cos_outer = outer_cone.cos();
                let scale = 1.0 / (inner_cone.cos() - cos_outer).max(1e-3);
                let cd = light.direction.dot(-wi);
                let a = ((cd - cos_outer) * scale).clamp(0.0, 1.0);
                e *= a * a;
            }
            Some((wi, dist, e))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff() {
        let light = Light {
            name: None,
            kind: LightKind::Spot {
                inner_cone: 0.2,
                outer_cone: 0.4,
            },
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(4.0),
        };
        let (_, _, on_axis) = punctual_incident(&light, Vec3::new(0.0, -2.0, 0.0)).unwrap();
        assert_eq!(on_axis, Vec3::ONE);
        let outside = Vec3::new(2.0 * 0.5f32.tan(), -2.0, 0.0);
        assert_eq!(punctual_incident(&light, outside).unwrap().2, Vec3::ZERO);
        let between = Vec3::new(2.0 * 0.3f32.tan(), -2.0, 0.0);
        let e = punctual_incident(&light, between).unwrap().2.x;
        assert!(e > 0.0 && e < 4.0 / between.length_squared());
    }
}
