//! A rigid transform that moves within a time interval: keys at evenly spaced times over
//! `[0, 1]` (the shutter, normalised), interpolated per ray as the animation itself is
//! (translation and scale linearly, rotation by slerp), and the box a moving object sweeps.

use glam::{Affine3A, Quat, Vec3};

/// One key: scale, rotation, translation (the decomposition of an affine transform).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Trs {
    scale: Vec3,
    rotation: Quat,
    translation: Vec3,
}

/// A transform keyed at `n ≥ 1` evenly spaced times over `[0, 1]`; key `k` at `k / (n − 1)`.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionTransform {
    keys: Vec<Trs>,
}

/// Sub-steps per key interval when bounding a swept box: a rotation between two keys moves a
/// corner along an arc, which the boxes at these sub-steps (padded by the arc's sagitta) hold.
const BOUND_SUBSTEPS: usize = 8;

impl MotionTransform {
    /// Keys `world_from_object` at evenly spaced times; `None` when there is none or one is not
    /// finite. Shear is not kept (glTF node transforms are TRS).
    pub fn new(keys: &[Affine3A]) -> Option<Self> {
        if keys.is_empty() {
            return None;
        }
        let mut out = Vec::with_capacity(keys.len());
        for k in keys {
            let (scale, rotation, translation) = k.to_scale_rotation_translation();
            if !(scale.is_finite() && rotation.is_finite() && translation.is_finite()) {
                return None;
            }
            out.push(Trs {
                scale,
                rotation: rotation.normalize(),
                translation,
            });
        }
        // Slerp along the shorter arc from each key to the next, as glTF's LINEAR does.
        for k in 1..out.len() {
            if out[k].rotation.dot(out[k - 1].rotation) < 0.0 {
                out[k].rotation = -out[k].rotation;
            }
        }
        Some(Self { keys: out })
    }

    /// True when every key is the same (nothing moves).
    pub fn is_still(&self) -> bool {
        self.keys.windows(2).all(|w| w[0] == w[1])
    }

    /// The transform at normalised time `tau` (clamped to `[0, 1]`).
    #[inline]
    pub fn at(&self, tau: f32) -> Affine3A {
        let n = self.keys.len();
        if n == 1 {
            let k = self.keys[0];
            return Affine3A::from_scale_rotation_translation(k.scale, k.rotation, k.translation);
        }
        let x = tau.clamp(0.0, 1.0) * (n - 1) as f32;
        let i = (x as usize).min(n - 2);
        let f = x - i as f32;
        let (a, b) = (self.keys[i], self.keys[i + 1]);
        Affine3A::from_scale_rotation_translation(
            a.scale.lerp(b.scale, f),
            a.rotation.slerp(b.rotation, f).normalize(),
            a.translation.lerp(b.translation, f),
        )
    }

    /// A box holding the object box `(lo, hi)` placed at every time of `[0, 1]`.
    pub fn swept_bounds(&self, (lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
        let steps = (self.keys.len().max(2) - 1) * BOUND_SUBSTEPS;
        let (mut wlo, mut whi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        // Rotation turns the box about the object's origin: its corners lie within `reach`.
        let reach = lo.abs().max(hi.abs()).length();
        let mut pad = 0.0f32;
        for s in 0..=steps {
            let m = self.at(s as f32 / steps as f32);
            for c in 0..8 {
                let p = Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                );
                let w = m.transform_point3(p);
                (wlo, whi) = (wlo.min(w), whi.max(w));
            }
            // A point at distance r from the origin turning by θ between sub-steps leaves the
            // chord by at most r·(1 − cos(θ/2)): padded by that, scaled.
            if s > 0 {
                let prev = self.at((s - 1) as f32 / steps as f32);
                let (s0, r0, _) = prev.to_scale_rotation_translation();
                let (s1, r1, _) = m.to_scale_rotation_translation();
                let theta = r0.angle_between(r1);
                let r = reach * s0.max(s1).max_element();
                pad = pad.max(r * (1.0 - (theta * 0.5).cos()));
            }
        }
        (wlo - Vec3::splat(pad), whi + Vec3::splat(pad))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_met_and_rotation_slerps() {
        let a = Affine3A::from_translation(Vec3::ZERO);
        let b = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            Vec3::new(2.0, 0.0, 0.0),
        );
        let m = MotionTransform::new(&[a, b]).unwrap();
        assert!(!m.is_still());
        assert!(m.at(0.0).abs_diff_eq(a, 1e-6));
        assert!(m.at(1.0).abs_diff_eq(b, 1e-6));
        let half = m.at(0.5);
        let want = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_4),
            Vec3::new(1.0, 0.0, 0.0),
        );
        assert!(half.abs_diff_eq(want, 1e-5));
    }

    #[test]
    fn swept_bounds_hold_every_time() {
        let b = Affine3A::from_rotation_translation(
            Quat::from_rotation_z(3.0),
            Vec3::new(0.0, 3.0, 0.0),
        );
        let m = MotionTransform::new(&[Affine3A::IDENTITY, b]).unwrap();
        let obj = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let (lo, hi) = m.swept_bounds(obj);
        for i in 0..=1000 {
            let t = m.at(i as f32 / 1000.0);
            for c in 0..8 {
                let p = Vec3::new(
                    if c & 1 == 0 { -1.0 } else { 1.0 },
                    if c & 2 == 0 { -1.0 } else { 1.0 },
                    if c & 4 == 0 { -1.0 } else { 1.0 },
                );
                let w = t.transform_point3(p);
                assert!(
                    w.cmpge(lo - 1e-5).all() && w.cmple(hi + 1e-5).all(),
                    "{i} {w}"
                );
            }
        }
    }
}
