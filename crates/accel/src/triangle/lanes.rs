//! The watertight triangle test of [`super::intersect`] for the eight rays of a packet at once
//! (AVX2, or NEON through [`crate::avx`]): one triangle, eight lanes, the scalar test's arithmetic operation for operation, so
//! each lane's answer has the bits of the scalar answer for its ray.
//!
//! Why: a packet's rays mostly reach the same leaves, where the scalar test ran once per ray
//! and triangle (about 60 instructions each); eight lanes cost about twice one. Lanes the
//! vector arithmetic cannot decide exactly as the scalar test does — an edge function of
//! exactly zero (decided again in `f64`), a value that is not finite (where `maxps` and
//! `f32::max` differ on NaN), a hit too close to tell in front of the origin (the `f64` plane
//! test) — are left to the scalar test.

use super::{gamma, TriRay};
use crate::avx::*;
use glam::Vec3;

/// Lanes per test: one AVX2 register of `f32`.
pub(crate) const LANES: usize = 8;

/// The per-ray constants of [`TriRay`] for eight rays, lane by lane (structure of arrays), in
/// registers.
#[derive(Clone, Copy)]
pub(crate) struct TriLanes {
    origin: [__m256; 3],
    /// `shear[c][j]`: component `j` of column `c` of each ray's shear matrix.
    shear: [[__m256; 3]; 3],
    sz: __m256,
    tmin: __m256,
}

/// What [`intersect_lanes`] found: per lane, a hit (`hits`) with its `(t, b1, b2)`, or a lane
/// for the scalar test (`scalar`); lanes in neither miss.
pub(crate) struct LaneHits {
    pub hits: u32,
    pub scalar: u32,
    pub t: [f32; LANES],
    pub b1: [f32; LANES],
    pub b2: [f32; LANES],
}

impl TriLanes {
    /// The lanes of `rays` with their `tmin`s. By register transposes: lanes written one
    /// float at a time and read back as vectors would stall on every load (store forwarding
    /// cannot merge eight stores into one load). The shear matrix is built lane-wise from each
    /// ray's axes: column `kx` is `(1, 0, 0)`, `ky` is `(0, 1, 0)`, `kz` is `(sx, sy, 1)`.
    ///
    /// # Safety
    /// The CPU must support AVX2, and the caller must be compiled for it.
    #[inline(always)]
    pub unsafe fn new(rays: [&TriRay; LANES], tmin: [f32; LANES]) -> Self {
        // SAFETY: AVX2 is guaranteed by the caller; each load reads one `perm` (`[i32; 4]`)
        // in full, the rest are register-only operations.
        unsafe {
            macro_rules! col {
                ($($f:ident).+) => {
                    transpose([0, 1, 2, 3, 4, 5, 6, 7].map(|i| __m128::from(rays[i].$($f).+)))
                };
            }
            macro_rules! lanes {
                ($v:expr) => {
                    _mm256_setr_ps($v[0], $v[1], $v[2], $v[3], $v[4], $v[5], $v[6], $v[7])
                };
            }
            let [ox, oy, oz, _] = col!(origin);
            let [sx, sy, _, _] = col!(s);
            // The axes as floats' bits (`perm` holds `i32`s), compared as integers.
            let [kx, ky, kz, _] = transpose([0, 1, 2, 3, 4, 5, 6, 7].map(|i| {
                _mm_castsi128_ps(_mm_loadu_si128(rays[i].perm.as_ptr() as *const __m128i))
            }));
            let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
            macro_rules! column {
                ($c:expr) => {{
                    let c = _mm256_set1_epi32($c);
                    macro_rules! is {
                        ($k:expr) => {
                            _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_castps_si256($k), c))
                        };
                    }
                    let (x, y, z) = (is!(kx), is!(ky), is!(kz));
                    [
                        _mm256_blendv_ps(_mm256_blendv_ps(zero, sx, z), one, x),
                        _mm256_blendv_ps(_mm256_blendv_ps(zero, sy, z), one, y),
                        _mm256_blendv_ps(zero, one, z),
                    ]
                }};
            }
            let sz = [0, 1, 2, 3, 4, 5, 6, 7].map(|i| rays[i].sz);
            Self {
                origin: [ox, oy, oz],
                shear: [column!(0), column!(1), column!(2)],
                sz: lanes!(sz),
                tmin: lanes!(tmin),
            }
        }
    }
}

/// Eight 4-float vectors as four 8-float ones: `out[k]` holds component `k` of each.
///
/// # Safety
/// The CPU must support AVX, and the caller must be compiled for it.
#[inline(always)]
pub(crate) unsafe fn transpose(v: [__m128; LANES]) -> [__m256; 4] {
    // SAFETY: AVX is guaranteed by the caller; register-only operations.
    unsafe {
        // Vectors i and i + 4 share a register, one per 128-bit half; then a 4×4 transpose
        // within each half.
        let r0 = _mm256_set_m128(v[4], v[0]);
        let r1 = _mm256_set_m128(v[5], v[1]);
        let r2 = _mm256_set_m128(v[6], v[2]);
        let r3 = _mm256_set_m128(v[7], v[3]);
        let t0 = _mm256_unpacklo_ps(r0, r1);
        let t1 = _mm256_unpackhi_ps(r0, r1);
        let t2 = _mm256_unpacklo_ps(r2, r3);
        let t3 = _mm256_unpackhi_ps(r2, r3);
        [
            _mm256_shuffle_ps::<0x44>(t0, t2),
            _mm256_shuffle_ps::<0xee>(t0, t2),
            _mm256_shuffle_ps::<0x44>(t1, t3),
            _mm256_shuffle_ps::<0xee>(t1, t3),
        ]
    }
}

// Shorthands for the kernels below. Macros, not closures: closures do not inherit the target
// features (a call per intrinsic). Each expands inside the caller's `unsafe` block.
macro_rules! set {
    ($x:expr) => {
        _mm256_set1_ps($x)
    };
}
macro_rules! abs {
    ($x:expr) => {
        _mm256_andnot_ps(_mm256_set1_ps(-0.0), $x)
    };
}
macro_rules! mul {
    ($a:expr, $b:expr) => {
        _mm256_mul_ps($a, $b)
    };
}
macro_rules! add {
    ($a:expr, $b:expr) => {
        _mm256_add_ps($a, $b)
    };
}
macro_rules! max3 {
    ($a:expr, $b:expr, $c:expr) => {
        _mm256_max_ps(_mm256_max_ps(abs!($a), abs!($b)), abs!($c))
    };
}
macro_rules! mask {
    ($m:expr) => {
        _mm256_movemask_ps($m) as u32
    };
}

/// Vertex `v` in each lane's ray space: `shear * (v - origin)` as glam's `Mat3A * Vec3A`,
/// `(c0 x + c1 y) + c2 z`, per row.
///
/// # Safety
/// As for [`intersect_lanes`].
#[inline(always)]
unsafe fn moved(l: &TriLanes, v: Vec3) -> [__m256; 3] {
    let o = l.origin;
    let [c0, c1, c2] = l.shear;
    // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
    unsafe {
        let d = [
            _mm256_sub_ps(set!(v.x), o[0]),
            _mm256_sub_ps(set!(v.y), o[1]),
            _mm256_sub_ps(set!(v.z), o[2]),
        ];
        // Written out, not `map`: closures do not inherit the target features.
        [
            add!(
                add!(mul!(c0[0], d[0]), mul!(c1[0], d[1])),
                mul!(c2[0], d[2])
            ),
            add!(
                add!(mul!(c0[1], d[0]), mul!(c1[1], d[1])),
                mul!(c2[1], d[2])
            ),
            add!(
                add!(mul!(c0[2], d[0]), mul!(c1[2], d[1])),
                mul!(c2[2], d[2])
            ),
        ]
    }
}

/// The lanes (as a mask vector) the vector arithmetic cannot decide as the scalar test does:
/// an edge function of exactly zero, or a value that is not finite (|x| unordered with or
/// equal to infinity) among those the maxima read or that a zero or an infinite determinant
/// would make. `v`: the nine moved coordinates, the three edge functions and the determinant.
///
/// # Safety
/// As for [`intersect_lanes`].
#[inline(always)]
unsafe fn odd_lanes(v: [__m256; 13]) -> __m256 {
    // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
    unsafe {
        let (e0, e1, e2) = (v[9], v[10], v[11]);
        let zero = _mm256_setzero_ps();
        let inf = set!(f32::INFINITY);
        let mut odd = _mm256_or_ps(
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_EQ_OQ>(e0, zero),
                _mm256_cmp_ps::<_CMP_EQ_OQ>(e1, zero),
            ),
            _mm256_cmp_ps::<_CMP_EQ_OQ>(e2, zero),
        );
        for x in v {
            odd = _mm256_or_ps(odd, _mm256_cmp_ps::<_CMP_NLT_UQ>(abs!(x), inf));
        }
        odd
    }
}

/// The lanes (as a mask vector) whose edge functions do not have both signs: not outside.
///
/// # Safety
/// As for [`intersect_lanes`].
#[inline(always)]
unsafe fn inside_lanes(e0: __m256, e1: __m256, e2: __m256) -> __m256 {
    // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
    unsafe {
        let zero = _mm256_setzero_ps();
        let any_neg = _mm256_or_ps(
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LT_OQ>(e0, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(e1, zero),
            ),
            _mm256_cmp_ps::<_CMP_LT_OQ>(e2, zero),
        );
        let any_pos = _mm256_or_ps(
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(e0, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(e1, zero),
            ),
            _mm256_cmp_ps::<_CMP_GT_OQ>(e2, zero),
        );
        _mm256_andnot_ps(
            _mm256_and_ps(any_neg, any_pos),
            _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
        )
    }
}

/// pbrt-v4's bound on the error of `t`, in the scalar test's order of operations: from the
/// moved `x`, `y` and scaled `z` of the three vertices (`[a, b, c]` each), the largest unscaled
/// `|z|`, the edge functions and `1 / det`.
///
/// # Safety
/// As for [`intersect_lanes`].
#[inline(always)]
unsafe fn t_error(
    [x, y, z]: [[__m256; 3]; 3],
    max_z: __m256,
    [e0, e1, e2]: [__m256; 3],
    inv_det: __m256,
) -> __m256 {
    // SAFETY: AVX2 is guaranteed by the caller; register-only operations.
    unsafe {
        let max_zt = max3!(z[0], z[1], z[2]);
        let delta_z = mul!(set!(gamma(3)), max_zt);
        let max_xt = max3!(x[0], x[1], x[2]);
        let max_yt = max3!(y[0], y[1], y[2]);
        let delta_x = mul!(set!(gamma(5)), add!(max_xt, max_z));
        let delta_y = mul!(set!(gamma(5)), add!(max_yt, max_z));
        let delta_e = mul!(
            set!(2.0),
            add!(
                add!(
                    mul!(mul!(set!(gamma(2)), max_xt), max_yt),
                    mul!(delta_y, max_xt)
                ),
                mul!(delta_x, max_yt)
            )
        );
        let max_e = max3!(e0, e1, e2);
        mul!(
            mul!(
                set!(3.0),
                add!(
                    add!(
                        mul!(mul!(set!(gamma(3)), max_e), max_zt),
                        mul!(delta_e, max_zt)
                    ),
                    mul!(delta_z, max_e)
                )
            ),
            abs!(inv_det)
        )
    }
}

/// The watertight test of triangle `p` for the `lanes` of `l` (bit `i` for lane `i`), each
/// within its `[tmin, tmax[i]]`.
///
/// # Safety
/// The CPU must support AVX2, and the caller must be compiled for it (inlined into the AVX2
/// packet queries).
#[inline(always)]
pub(crate) unsafe fn intersect_lanes(
    l: &TriLanes,
    p: &[Vec3; 3],
    tmax: &[f32; LANES],
    lanes: u32,
) -> LaneHits {
    // SAFETY: AVX2 is guaranteed by the caller; every load reads one `[f32; 8]` in full and
    // every store writes one.
    unsafe {
        let [ax, ay, az] = moved(l, p[0]);
        let [bx, by, bz] = moved(l, p[1]);
        let [cx, cy, cz] = moved(l, p[2]);
        // Edge functions; e0 is the weight of p0, e1 of p1, e2 of p2.
        let e0 = _mm256_sub_ps(mul!(bx, cy), mul!(by, cx));
        let e1 = _mm256_sub_ps(mul!(cx, ay), mul!(cy, ax));
        let e2 = _mm256_sub_ps(mul!(ax, by), mul!(ay, bx));
        let det = add!(add!(e0, e1), e2);
        let max_z = max3!(az, bz, cz);
        let sz = l.sz;
        let (az, bz, cz) = (mul!(az, sz), mul!(bz, sz), mul!(cz, sz));
        // Lanes for the scalar test.
        let odd = odd_lanes([ax, ay, az, bx, by, bz, cx, cy, cz, e0, e1, e2, det]);
        let scalar_lanes = mask!(odd) & lanes;
        // Both signs among the edge functions: outside (all finite and non-zero here, so
        // `det` is not zero either).
        let candidates = lanes & !scalar_lanes & mask!(inside_lanes(e0, e1, e2));
        if candidates == 0 {
            // Most tests end here, as the scalar test's do after its sign test.
            return LaneHits {
                hits: 0,
                scalar: scalar_lanes,
                t: [0.0; LANES],
                b1: [0.0; LANES],
                b2: [0.0; LANES],
            };
        }
        let t_scaled = add!(add!(mul!(e0, az), mul!(e1, bz)), mul!(e2, cz));
        let inv_det = _mm256_div_ps(set!(1.0), det);
        let t = mul!(t_scaled, inv_det);
        let in_range = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(t, l.tmin),
            _mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_loadu_ps(tmax.as_ptr())),
        );
        let xyz = [[ax, bx, cx], [ay, by, cy], [az, bz, cz]];
        let delta_t = t_error(xyz, max_z, [e0, e1, e2], inv_det);
        let decided = candidates & mask!(in_range);
        // Hits too close to call go to the scalar test, which decides them in `f64`.
        let close = decided & mask!(_mm256_cmp_ps::<_CMP_LE_OQ>(t, delta_t));
        let mut out = LaneHits {
            hits: decided & !close,
            scalar: scalar_lanes | close,
            t: [0.0; LANES],
            b1: [0.0; LANES],
            b2: [0.0; LANES],
        };
        _mm256_storeu_ps(out.t.as_mut_ptr(), t);
        _mm256_storeu_ps(out.b1.as_mut_ptr(), mul!(e1, inv_det));
        _mm256_storeu_ps(out.b2.as_mut_ptr(), mul!(e2, inv_det));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::mix;
    use crate::triangle::intersect;
    use crate::triangle::Tri;

    /// The scalar test's AVX path ([`intersect`] with `AVX`), compiled for AVX as the queries
    /// that inline it.
    #[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2,fma"))]
    unsafe fn intersect_avx(
        r: &TriRay,
        tri: &Tri,
        tmin: f32,
        tmax: f32,
    ) -> Option<(f32, f32, f32)> {
        intersect::<true>(r, tri, tmin, tmax)
    }

    /// A uniform value in `[-1, 1)` from a counter.
    fn unit(k: u32) -> f32 {
        (mix(k) >> 8) as f32 / (1u32 << 23) as f32 - 1.0
    }

    /// Values that stress the test: exact zeros, ties, tiny and huge magnitudes.
    fn odd(k: u32) -> f32 {
        const V: [f32; 8] = [0.0, -0.0, 1.0, -1.0, 1e-30, 3e30, 0.5, f32::MIN_POSITIVE];
        V[mix(k) as usize % V.len()]
    }

    /// Case `k`'s value `j`: with `stress`, now and then an exact or extreme value.
    fn pick(k: u32, stress: bool, j: u32) -> f32 {
        if stress && mix(k + j) % 5 == 0 {
            odd(k + j)
        } else {
            unit(k + j)
        }
    }

    /// Case `k`'s eight rays at `tri` (through a vertex or edge now and then) or anywhere,
    /// with their `tmin` and `tmax`.
    fn case_rays(
        k: u32,
        stress: bool,
        tri: &[Vec3; 3],
    ) -> (Vec<TriRay>, [f32; LANES], [f32; LANES]) {
        let mut rays = Vec::new();
        let mut tmin = [0.0; LANES];
        let mut tmax = [0.0; LANES];
        for i in 0..LANES as u32 {
            let q = |j: u32| pick(k, stress, 16 + 6 * i + j);
            let origin = Vec3::new(q(0), q(1), q(2) + 2.0 * unit(k + 60));
            let target = match mix(k + 61 + i) % 4 + 2 * u32::from(!stress) {
                0 => tri[0],
                1 => (tri[1] + tri[2]) * 0.5,
                2 => Vec3::new(q(3), q(4), q(5)),
                3 => (tri[0] + tri[1] + tri[2]) / 3.0,
                4 => Vec3::new(q(3), q(4), q(5)),
                _ => tri[1] * 0.25 + tri[2] * 0.25 + tri[0] * 0.5,
            };
            let dir = if stress && mix(k + 62 + i) % 7 == 0 {
                Vec3::new(q(3), 0.0, -0.0)
            } else {
                target - origin
            };
            rays.push(TriRay::new(origin, dir));
            tmin[i as usize] = if mix(k + 63 + i) % 3 == 0 { 0.0 } else { 1e-4 };
            tmax[i as usize] = match mix(k + 40 + i) % 3 {
                0 => f32::INFINITY,
                1 => 0.7,
                _ => 1e3,
            };
        }
        (rays, tmin, tmax)
    }

    /// How the lanes answered, counted over the cases.
    #[derive(Default)]
    struct Tally {
        hits: u32,
        /// Lanes left to the scalar test, ordinary cases only.
        scalar: u32,
        misses: u32,
    }

    /// One case's (number, stressed) eight-lane answer `h` (for lanes `want`) against the scalar test's, lane by
    /// lane, counted into `tally`.
    fn check_case(
        (case, stress): (u32, bool),
        tri: [Vec3; 3],
        rays: &[TriRay],
        (tmin, tmax): ([f32; LANES], [f32; LANES]),
        want: u32,
        h: &LaneHits,
        tally: &mut Tally,
    ) {
        for i in 0..LANES {
            let t = Tri { p: tri, prim: 0 };
            let expected = intersect::<false>(&rays[i], &t, tmin[i], tmax[i]);
            // SAFETY: AVX2 and FMA checked by the caller.
            let avx = unsafe { intersect_avx(&rays[i], &t, tmin[i], tmax[i]) };
            let bits = |h: Option<(f32, f32, f32)>| h.map(|h| [h.0, h.1, h.2].map(f32::to_bits));
            assert_eq!(bits(avx), bits(expected), "case {case} lane {i}: AVX path");
            let bit = 1u32 << i;
            if want & bit == 0 {
                continue;
            }
            if h.scalar & bit != 0 {
                tally.scalar += u32::from(!stress);
            } else if h.hits & bit != 0 {
                let got = (h.t[i], h.b1[i], h.b2[i]);
                let e = expected.unwrap_or_else(|| {
                    panic!("case {case} lane {i}: {got:?} where the scalar test misses")
                });
                assert_eq!(
                    [got.0, got.1, got.2].map(f32::to_bits),
                    [e.0, e.1, e.2].map(f32::to_bits),
                    "case {case} lane {i}"
                );
                tally.hits += 1;
            } else {
                assert!(
                    expected.is_none(),
                    "case {case} lane {i}: missed {expected:?}"
                );
                tally.misses += 1;
            }
        }
    }

    /// The eight-lane answer of every lane against the scalar test's, bit for bit: the
    /// lanes it decides must hit exactly where the scalar test hits, with its `(t, b1, b2)`,
    /// and miss exactly where it misses. The scalar test's two paths (portable, and AVX's
    /// permuted loads) must answer alike on every lane, the lanes left to them too.
    #[test]
    fn lanes_answer_as_the_scalar_test_does() {
        if !crate::test_util::lanes8() {
            return;
        }
        let mut tally = Tally::default();
        for case in 0..40_000u32 {
            let k = case * 64;
            // Every other case draws exact and extreme values too; the others, ordinary ones.
            let stress = case % 2 == 0;
            let pick = |j: u32| pick(k, stress, j);
            // A triangle near the origin, or with a vertex or edge on exact values.
            let tri = [
                Vec3::new(pick(1), pick(2), pick(3)),
                Vec3::new(pick(4), pick(5), pick(6)),
                Vec3::new(pick(7), pick(8), pick(9)),
            ];
            let (rays, tmin, tmax) = case_rays(k, stress, &tri);
            let refs: [&TriRay; LANES] = std::array::from_fn(|i| &rays[i]);
            // SAFETY: AVX2 checked above.
            let lanes = unsafe { TriLanes::new(refs, tmin) };
            let all = (1u32 << LANES) - 1;
            let want = mix(k + 50) & all | 1;
            // SAFETY: AVX2 checked above.
            let h = unsafe { intersect_lanes(&lanes, &tri, &tmax, want) };
            assert_eq!(h.hits & h.scalar, 0);
            assert_eq!((h.hits | h.scalar) & !want, 0, "lanes outside the mask");
            check_case(
                (case, stress),
                tri,
                &rays,
                (tmin, tmax),
                want,
                &h,
                &mut tally,
            );
        }
        let Tally {
            hits,
            scalar,
            misses,
        } = tally;
        // Every kind of answer is exercised, and on ordinary rays the lanes decide nearly all.
        assert!(
            hits > 10_000 && misses > 10_000,
            "hits {hits} misses {misses}"
        );
        assert!(
            scalar * 50 < hits + misses,
            "scalar {scalar} of {}",
            hits + misses
        );
    }
}
