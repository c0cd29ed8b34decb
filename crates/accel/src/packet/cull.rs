//! Which of a run's eight rays provably miss the scene's bounds: [`Accel::misses_bounds`] for
//! eight rays at once, so that a run of camera rays around a lone asset is answered for a few
//! instructions a ray (most rays of a product shot miss it).

use super::shape::PACKET_LANES;
use crate::avx::*;
use crate::structure::Accel;
use crate::triangle::lanes::transpose;
use crate::types::Ray;
use glam::Vec3A;

impl Accel {
    /// The lanes of `run` (eight rays, their directions in lanes: [`super::rays::dir_lanes`]) that
    /// [`Accel::misses_bounds`] culls, bit `i` for ray `i`: the same arithmetic lane by lane (a
    /// ray that starts inside the bounds, or whose origin or direction is not finite, is never
    /// culled).
    ///
    /// # Safety
    /// The CPU must support AVX2, and the caller must be compiled for it.
    #[inline(always)]
    pub(super) unsafe fn misses_bounds_lanes(
        &self,
        run: &[Ray; PACKET_LANES],
        [dx, dy, dz]: [__m256; 3],
    ) -> u32 {
        let (lo, hi) = self.tlas_bounds;
        // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
        unsafe {
            let [ox, oy, oz, _] = transpose(run.each_ref().map(|r| Vec3A::from(r.origin).into()));
            let t = run.each_ref().map(|r| r.tmin);
            let tmin = _mm256_setr_ps(t[0], t[1], t[2], t[3], t[4], t[5], t[6], t[7]);
            let t = run.each_ref().map(|r| r.tmax);
            let tmax = _mm256_setr_ps(t[0], t[1], t[2], t[3], t[4], t[5], t[6], t[7]);
            let b = super::rays::box_lanes([ox, oy, oz], [dx, dy, dz], (lo, hi));
            let mut inside = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
            // The slab test against the bounds, widened by the slack.
            let mut enter = tmin;
            let mut exit = tmax;
            for (a, o) in [ox, oy, oz].into_iter().enumerate() {
                let (l, h) = (_mm256_set1_ps(lo[a]), _mm256_set1_ps(hi[a]));
                inside = _mm256_and_ps(
                    inside,
                    _mm256_and_ps(
                        _mm256_cmp_ps::<_CMP_GE_OQ>(o, l),
                        _mm256_cmp_ps::<_CMP_LE_OQ>(o, h),
                    ),
                );
                let t0 = _mm256_mul_ps(_mm256_sub_ps(l, o), b.inv[a]);
                let t1 = _mm256_mul_ps(_mm256_sub_ps(h, o), b.inv[a]);
                let near = _mm256_sub_ps(_mm256_min_ps(t0, t1), b.slack[a]);
                let far = _mm256_add_ps(_mm256_max_ps(t0, t1), b.slack[a]);
                enter = _mm256_max_ps(near, enter);
                exit = _mm256_min_ps(far, exit);
            }
            let missed = _mm256_cmp_ps::<_CMP_GT_OQ>(enter, exit);
            // Rays starting inside, or not finite, are walked.
            let culled = _mm256_andnot_ps(inside, _mm256_and_ps(b.finite, missed));
            _mm256_movemask_ps(culled) as u32
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::rays::dir_lanes;
    use super::PACKET_LANES;
    use crate::structure::Accel;
    use crate::test_util::{awkward, mix};
    use crate::types::{BvhQuality, InstanceInput, MeshInput, Ray};
    use glam::{Affine3A, Vec3};

    /// A coordinate in [-4, 4), now and then zero, tiny or not finite.
    fn coord(k: u32) -> f32 {
        awkward(k, 4.0)
    }

    /// Eight rays at once cull exactly the rays `misses_bounds` culls, one by one.
    #[test]
    fn lanes_cull_as_misses_bounds_does() {
        if !crate::test_util::lanes8() {
            return;
        }
        // Two triangles spanning [-1, 1] x [-0.5, 0.5] x [-2, 0.3].
        let positions = vec![
            Vec3::new(-1.0, -0.5, -2.0),
            Vec3::new(1.0, -0.5, 0.3),
            Vec3::new(0.0, 0.5, -1.0),
            Vec3::new(-1.0, 0.5, 0.0),
        ];
        let indices = vec![[0, 1, 2], [0, 2, 3]];
        let meshes = [MeshInput {
            positions: &positions,
            indices: &indices,
        }];
        let instances = [InstanceInput {
            mesh: 0,
            world_from_object: Affine3A::IDENTITY,
        }];
        let accel = Accel::build(&meshes, &instances, BvhQuality::Medium);
        let (mut culled, mut walked) = (0, 0);
        for case in 0..30_000u32 {
            let k = case * 64;
            let run: [Ray; PACKET_LANES] = std::array::from_fn(|i| {
                let j = k + 8 * i as u32;
                let mut r = Ray::new(
                    Vec3::new(coord(j), coord(j + 1), coord(j + 2)),
                    Vec3::new(coord(j + 3), coord(j + 4), coord(j + 5)),
                );
                if mix(j + 6) % 3 == 0 {
                    r.tmax = (mix(j + 7) % 8) as f32 * 0.5;
                }
                r
            });
            // SAFETY: AVX2 checked above.
            let got = unsafe { accel.misses_bounds_lanes(&run, dir_lanes(&run)) };
            for (i, ray) in run.iter().enumerate() {
                let want = accel.misses_bounds(ray);
                assert_eq!(got >> i & 1 == 1, want, "case {case} ray {i}: {ray:?}");
                if want {
                    culled += 1;
                } else {
                    walked += 1;
                }
            }
        }
        assert!(
            culled > 10_000 && walked > 10_000,
            "culled {culled} walked {walked}"
        );
    }
}
