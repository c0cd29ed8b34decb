//! Whether a run of rays is coherent enough to walk as a packet: one direction octant, and
//! every direction within [`PACKET_CONE_COS`] of the first.

use super::shape::PACKET_CONE_COS;
use crate::avx::*;
use crate::types::Ray;

/// Whether `rays` share a direction octant and lie within [`PACKET_CONE_COS`] of the first, in
/// world space (a first test; the box test's octant is checked once the rays are set up).
#[inline(always)]
pub(super) fn coherent(rays: &[Ray]) -> bool {
    let Some(first) = rays.first() else {
        return false;
    };
    let sign = |d: glam::Vec3| d.cmplt(glam::Vec3::ZERO).bitmask();
    // `cos(d, d0) >= PACKET_CONE_COS` without square roots or divisions: `d . d0 >= 0` and
    // `(d . d0)^2 >= cos^2 |d|^2 |d0|^2`. Which runs are packets only changes the speed: the
    // answers are the one-ray answers either way.
    let d0 = first.dir;
    let cos2_l0 = PACKET_CONE_COS * PACKET_CONE_COS * d0.length_squared();
    rays.iter().all(|r| {
        let dot = r.dir.dot(d0);
        sign(r.dir) == sign(d0) && dot >= 0.0 && dot * dot >= cos2_l0 * r.dir.length_squared()
    })
}

/// [`coherent`] for a full run whose first direction is `d0` and whose eight directions are
/// `[dx, dy, dz]` in AVX2 lanes ([`super::rays::dir_lanes`]): the same comparisons on the same
/// values, so the same decision, for a tenth of the instructions (the scalar loop recomputes
/// the first ray's octant and runs to the end of every coherent run).
///
/// # Safety
/// The CPU must support AVX2, and the caller must be compiled for it.
#[inline(always)]
pub(super) unsafe fn coherent_lanes(d0: glam::Vec3, [dx, dy, dz]: [__m256; 3]) -> bool {
    // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
    unsafe {
        let cos2_l0 = PACKET_CONE_COS * PACKET_CONE_COS * d0.length_squared();
        let zero = _mm256_setzero_ps();
        // Macros, not closures: closures do not inherit the target features.
        macro_rules! negative {
            ($v:expr) => {
                _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>($v, zero))
            };
        }
        macro_rules! dot {
            ($x:expr, $y:expr, $z:expr) => {
                _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(dx, $x), _mm256_mul_ps(dy, $y)),
                    _mm256_mul_ps(dz, $z),
                )
            };
        }
        // One octant: on each axis, every lane negative or none (so all as the first).
        let octant = [negative!(dx), negative!(dy), negative!(dz)]
            .iter()
            .all(|&m| m == 0 || m == 0xff);
        let dot = dot!(
            _mm256_set1_ps(d0.x),
            _mm256_set1_ps(d0.y),
            _mm256_set1_ps(d0.z)
        );
        let len2 = dot!(dx, dy, dz);
        let ahead = _mm256_cmp_ps::<_CMP_GE_OQ>(dot, zero);
        let narrow = _mm256_cmp_ps::<_CMP_GE_OQ>(
            _mm256_mul_ps(dot, dot),
            _mm256_mul_ps(_mm256_set1_ps(cos2_l0), len2),
        );
        octant && _mm256_movemask_ps(_mm256_and_ps(ahead, narrow)) == 0xff
    }
}

#[cfg(test)]
mod tests {
    use super::super::rays::dir_lanes;
    use super::super::shape::PACKET_LANES;
    use super::*;
    use crate::test_util::{awkward, mix};
    use glam::Vec3;

    /// A direction component in [-1, 1), now and then zero, tiny or not finite.
    fn value(k: u32) -> f32 {
        awkward(k, 1.0)
    }

    /// Eight lanes decide as the scalar loop, on runs from tight cones (packets) to wide ones
    /// and on directions with zero, tiny, infinite or NaN components.
    #[test]
    fn lanes_decide_as_the_scalar_test() {
        if !crate::test_util::lanes8() {
            return;
        }
        let (mut yes, mut no) = (0, 0);
        for case in 0..100_000u32 {
            let k = case * 64;
            let base = Vec3::new(value(k), value(k + 1), value(k + 2));
            // Spread from 1e-4 (inside the cone) to 1 (far outside it).
            let spread = 10f32.powf(-4.0 * ((mix(k + 3) >> 8) as f32 / (1u32 << 24) as f32));
            let run: [Ray; PACKET_LANES] = std::array::from_fn(|i| {
                let j = k + 8 + 3 * i as u32;
                let jitter = Vec3::new(value(j), value(j + 1), value(j + 2)) * spread;
                Ray::new(Vec3::ZERO, base + jitter)
            });
            // SAFETY: AVX2 checked above.
            let got = unsafe { coherent_lanes(run[0].dir, dir_lanes(&run)) };
            assert_eq!(got, coherent(&run), "case {case}: {run:?}");
            if got {
                yes += 1;
            } else {
                no += 1;
            }
        }
        assert!(yes > 2_000 && no > 5_000, "coherent {yes}, not {no}");
    }
}
