//! A packet's eight rays prepared for box tests, lane by lane: built in registers from the
//! rays' origins and directions, with the arithmetic of eight `BoxRay::new`s ([`box_lanes`],
//! which the bounds cull shares).

use super::shape::PACKET_LANES;
use crate::avx::*;
#[cfg(test)]
use crate::node::BoxRay;

/// Eight rays prepared for box tests, lane by lane (structure of arrays of `BoxRay`s).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
pub(super) struct PacketRays {
    pub(super) o_near: [[f32; PACKET_LANES]; 3],
    pub(super) o_far: [[f32; PACKET_LANES]; 3],
    pub(super) ninv: [[f32; PACKET_LANES]; 3],
    pub(super) tmin: [f32; PACKET_LANES],
    /// Where the packet's planes are in a node (its rays share their direction signs), and its
    /// child-ordering key.
    pub(super) rows: crate::node::Rows,
    pub(super) oct_inv4: u32,
}

impl PacketRays {
    /// The lanes of `rays` one float at a time: the reference [`PacketRays::from_rays`] must
    /// match bit for bit.
    #[cfg(test)]
    #[inline(always)]
    pub(super) fn new(rays: &[BoxRay; PACKET_LANES]) -> Self {
        let mut p = Self {
            o_near: [[0.0; PACKET_LANES]; 3],
            o_far: [[0.0; PACKET_LANES]; 3],
            ninv: [[0.0; PACKET_LANES]; 3],
            tmin: [0.0; PACKET_LANES],
            rows: rays[0].rows,
            oct_inv4: rays[0].oct_inv4,
        };
        for (i, r) in rays.iter().enumerate() {
            for a in 0..3 {
                p.o_near[a][i] = r.o_near[a];
                p.o_far[a][i] = r.o_far[a];
                p.ninv[a][i] = r.ninv[a];
            }
            p.tmin[i] = r.tmin;
        }
        p
    }
}

/// What `BoxRay::new` computes for eight rays (origins and directions by lane, tree bounds
/// `(lo, hi)`), with its operations lane by lane: the clamped reciprocal, the slack in space
/// and per axis in `t`, and which lanes have a finite origin and direction (only there is the
/// slack's maximum independent of its order of operations).
pub(super) struct BoxLanes {
    pub(super) inv: [__m256; 3],
    /// `SLACK * M`: the slack in space (`crate::node` module docs).
    pub(super) reach: __m256,
    /// `|inv| * reach` per axis: the slack in `t`.
    pub(super) slack: [__m256; 3],
    /// All ones in the lanes whose origin and direction are finite.
    pub(super) finite: __m256,
}

/// The directions of a run of eight rays in lanes (x, y, z): transposed once per run for the
/// culling and coherence tests.
///
/// # Safety
/// The CPU must support AVX, and the caller must be compiled for it.
#[inline(always)]
pub(super) unsafe fn dir_lanes(run: &[crate::types::Ray; PACKET_LANES]) -> [__m256; 3] {
    // SAFETY: AVX is guaranteed by the caller; register-only operations.
    let [dx, dy, dz, _] = unsafe {
        crate::triangle::lanes::transpose(run.each_ref().map(|r| glam::Vec3A::from(r.dir).into()))
    };
    [dx, dy, dz]
}

/// [`BoxLanes`] of eight rays.
///
/// # Safety
/// The CPU must support AVX2, and the caller must be compiled for it.
#[inline(always)]
pub(super) unsafe fn box_lanes(
    origin: [__m256; 3],
    dir: [__m256; 3],
    (lo, hi): (glam::Vec3, glam::Vec3),
) -> BoxLanes {
    // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
    unsafe {
        let sign = _mm256_set1_ps(-0.0);
        let inf = _mm256_set1_ps(f32::INFINITY);
        let limit = _mm256_set1_ps(crate::node::INV_LIMIT);
        let mut finite = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        // `(lo - o).abs().max((hi - o).abs()).max_element()` per lane.
        let mut corner = _mm256_setzero_ps();
        let mut inv = [_mm256_setzero_ps(); 3];
        for a in 0..3 {
            let (o, d) = (origin[a], dir[a]);
            finite = _mm256_and_ps(
                finite,
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, o), inf),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, d), inf),
                ),
            );
            // A finite reciprocal clamped to the limit, else the limit with the sign of `d`.
            let i = _mm256_div_ps(_mm256_set1_ps(1.0), d);
            let clamped = _mm256_min_ps(_mm256_max_ps(i, _mm256_xor_ps(limit, sign)), limit);
            let signed = _mm256_or_ps(_mm256_and_ps(d, sign), _mm256_andnot_ps(sign, limit));
            let ok = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, i), inf);
            inv[a] = _mm256_or_ps(_mm256_and_ps(ok, clamped), _mm256_andnot_ps(ok, signed));
            let to_lo = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_set1_ps(lo[a]), o));
            let to_hi = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_set1_ps(hi[a]), o));
            corner = _mm256_max_ps(corner, _mm256_max_ps(to_lo, to_hi));
        }
        let scale = _mm256_mul_ps(_mm256_set1_ps(crate::node::SLACK), corner);
        let slack = inv.map(|i| _mm256_mul_ps(_mm256_andnot_ps(sign, i), scale));
        BoxLanes {
            inv,
            reach: scale,
            slack,
            finite,
        }
    }
}

impl PacketRays {
    /// `PacketRays::new` of the `BoxRay::new`s of eight rays in the tree's space
    /// (`origin`, `dir`, `tmin`; tree bounds `bounds`), computed for all lanes at once
    /// ([`box_lanes`]), so the same bits. `None` when a lane's origin or direction is not
    /// finite or the lanes' direction signs differ (no packet then).
    ///
    /// # Safety
    /// The CPU must support AVX2, and the caller must be compiled for it.
    #[inline(always)]
    pub(super) unsafe fn from_rays(
        origin: [__m256; 3],
        dir: [__m256; 3],
        tmin: [f32; PACKET_LANES],
        bounds: (glam::Vec3, glam::Vec3),
    ) -> Option<Self> {
        // SAFETY: AVX2 is guaranteed by the caller; each store writes one `[f32; 8]`.
        unsafe {
            let b = box_lanes(origin, dir, bounds);
            if _mm256_movemask_ps(b.finite) != 0xff {
                return None;
            }
            let mut p = Self {
                o_near: [[0.0; PACKET_LANES]; 3],
                o_far: [[0.0; PACKET_LANES]; 3],
                ninv: [[0.0; PACKET_LANES]; 3],
                tmin,
                rows: crate::node::Rows::new(0),
                oct_inv4: 0,
            };
            let mut neg_bits = 0u32;
            let sign = _mm256_set1_ps(-0.0);
            for (a, (o, inv)) in origin.into_iter().zip(b.inv).enumerate() {
                let negative =
                    _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(inv, _mm256_setzero_ps()))
                        as u32;
                if negative != 0 && negative != 0xff {
                    return None;
                }
                neg_bits |= (negative & 1) << a;
                // `node::widened_origins`, lane by lane.
                let w = _mm256_add_ps(
                    _mm256_mul_ps(
                        _mm256_andnot_ps(sign, o),
                        _mm256_set1_ps(2.0 * f32::EPSILON),
                    ),
                    b.reach,
                );
                let w = _mm256_or_ps(_mm256_andnot_ps(sign, w), _mm256_and_ps(sign, inv));
                _mm256_storeu_ps(p.o_near[a].as_mut_ptr(), _mm256_add_ps(o, w));
                _mm256_storeu_ps(p.o_far[a].as_mut_ptr(), _mm256_sub_ps(o, w));
                _mm256_storeu_ps(p.ninv[a].as_mut_ptr(), _mm256_xor_ps(inv, sign));
            }
            p.rows = crate::node::Rows::new(neg_bits);
            p.oct_inv4 = crate::node::oct_inv4(neg_bits);
            Some(p)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::mix;
    use crate::triangle::lanes::transpose;
    use glam::{Vec3, Vec3A};

    /// A coordinate from a counter: uniform, exactly zero (a direction along an axis), tiny
    /// (a reciprocal past the clamp) or large.
    fn coord(k: u32) -> f32 {
        let u = (mix(k) >> 8) as f32 / (1u32 << 23) as f32 - 1.0;
        match mix(k ^ 0x55) % 8 {
            0 => 0.0,
            1 => -0.0,
            2 => u * 1e-25,
            3 => u * 1e6,
            _ => u,
        }
    }

    /// The lanes built at once have the bits of eight `BoxRay::new`s put in lanes.
    #[test]
    fn packet_rays_at_once_match_box_rays_lane_by_lane() {
        if !crate::test_util::lanes8() {
            return;
        }
        let bounds = (Vec3::new(-3.0, -0.5, -7.0), Vec3::new(4.0, 2.5, 1.0));
        let (mut built, mut declined) = (0, 0);
        for case in 0..20_000u32 {
            let k = case * 64;
            let mut origins = [__m128::from(Vec3A::ZERO); PACKET_LANES];
            let mut dirs = origins;
            let mut tmin = [0.0; PACKET_LANES];
            let mut boxes = [BoxRay::new(Vec3::ZERO, Vec3::ONE, 0.0, bounds); PACKET_LANES];
            // Half the cases share one direction's signs (packets), half mix them.
            let base = Vec3::new(coord(k), coord(k + 1), coord(k + 2));
            for i in 0..PACKET_LANES as u32 {
                let o = Vec3::new(
                    coord(k + 8 * i + 3),
                    coord(k + 8 * i + 4),
                    coord(k + 8 * i + 5),
                );
                let jitter = Vec3::new(
                    coord(k + 8 * i + 6),
                    coord(k + 8 * i + 7),
                    coord(k + 8 * i + 8),
                );
                let d = if case % 2 == 0 {
                    base * (1.0 + 0.01 * i as f32)
                } else {
                    jitter
                };
                let t = if i % 3 == 0 { 0.0 } else { 1e-4 * i as f32 };
                boxes[i as usize] = BoxRay::new(o, d, t, bounds);
                origins[i as usize] = Vec3A::from(o).into();
                dirs[i as usize] = Vec3A::from(d).into();
                tmin[i as usize] = t;
            }
            // SAFETY: AVX2 checked above.
            let got = unsafe {
                let [ox, oy, oz, _] = transpose(origins);
                let [dx, dy, dz, _] = transpose(dirs);
                PacketRays::from_rays([ox, oy, oz], [dx, dy, dz], tmin, bounds)
            };
            let same_signs = boxes.iter().all(|b| b.rows == boxes[0].rows);
            let Some(got) = got else {
                assert!(!same_signs, "case {case}: declined a packet of one octant");
                declined += 1;
                continue;
            };
            assert!(same_signs, "case {case}: a packet of mixed octants");
            let want = PacketRays::new(&boxes);
            let bits = |v: &[[f32; PACKET_LANES]; 3]| v.map(|a| a.map(f32::to_bits));
            assert_eq!(bits(&got.o_near), bits(&want.o_near), "case {case} o_near");
            assert_eq!(bits(&got.o_far), bits(&want.o_far), "case {case} o_far");
            assert_eq!(bits(&got.ninv), bits(&want.ninv), "case {case} ninv");
            assert_eq!(got.tmin.map(f32::to_bits), want.tmin.map(f32::to_bits));
            assert_eq!(
                (got.rows, got.oct_inv4),
                (want.rows, want.oct_inv4),
                "case {case}"
            );
            built += 1;
        }
        assert!(
            built > 5_000 && declined > 5_000,
            "built {built} declined {declined}"
        );
    }
}
