//! AVX's eight-float intrinsics that the packet kernels use, written with NEON (aarch64, where
//! NEON is baseline): an eight-float vector is two `float32x4_t` halves, and each function
//! gives what the x86-64 instruction gives, bit for bit, so that one copy of the kernels
//! answers alike on both architectures (as SIMDe and sse2neon do for C).
//!
//! Where NEON's own instruction differs from AVX's, the AVX result is built:
//! - `maxps`/`minps` return the second operand when either is NaN (NEON's `fmax`/`fmin` return
//!   NaN, `fmaxnm`/`fminnm` the number): a comparison and a select, as `node::neon` does;
//! - `blendv` reads only each mask lane's sign bit: the mask is widened from it;
//! - `movemask` gathers sign bits: shifted into place and summed across lanes;
//! - comparisons: AVX's ordered predicates are NEON's comparisons (false on NaN); `NLT_UQ`,
//!   unordered or not less, is the complement of "less".
//!
//! Only the predicates and shuffles the kernels use exist; another is a compile-time error.
//! Every function is `unsafe`, as the x86-64 intrinsics are, and inlined into its caller.
#![allow(non_camel_case_types)]

use std::arch::aarch64::*;

/// AVX's `__m256`: eight floats, lanes 0–3 in `lo`, 4–7 in `hi`.
#[derive(Clone, Copy)]
pub(crate) struct __m256 {
    lo: float32x4_t,
    hi: float32x4_t,
}

/// AVX's `__m256i`, as eight 32-bit integers (all the kernels use).
#[derive(Clone, Copy)]
pub(crate) struct __m256i {
    lo: uint32x4_t,
    hi: uint32x4_t,
}

/// SSE's `__m128`: glam's `Vec3A` converts to it as on x86-64.
pub(crate) type __m128 = float32x4_t;
/// SSE's `__m128i`, as sixteen bytes.
pub(crate) type __m128i = uint8x16_t;

pub(crate) const _CMP_EQ_OQ: i32 = 0x00;
pub(crate) const _CMP_LT_OQ: i32 = 0x11;
pub(crate) const _CMP_LE_OQ: i32 = 0x12;
pub(crate) const _CMP_NLT_UQ: i32 = 0x15;
pub(crate) const _CMP_GE_OQ: i32 = 0x1d;
pub(crate) const _CMP_GT_OQ: i32 = 0x1e;

/// `f` applied to both halves of `a` and `b`.
#[inline(always)]
fn pair(a: __m256, b: __m256, f: impl Fn(float32x4_t, float32x4_t) -> float32x4_t) -> __m256 {
    __m256 {
        lo: f(a.lo, b.lo),
        hi: f(a.hi, b.hi),
    }
}

/// The bitwise operation `$f` on `u32` lanes of `a` and `b`, as one on floats' bits.
macro_rules! on_bits {
    ($f:ident, $a:expr, $b:expr) => {
        // SAFETY: NEON is baseline on aarch64; register-only operations.
        pair($a, $b, |x, y| unsafe {
            vreinterpretq_f32_u32($f(vreinterpretq_u32_f32(x), vreinterpretq_u32_f32(y)))
        })
    };
}

/// SSE's `maxps` on four lanes: `a` where `a > b`, else `b` (so `b` when either is NaN).
#[inline(always)]
pub(crate) fn max_sse(a: float32x4_t, b: float32x4_t) -> float32x4_t {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vbslq_f32(vcgtq_f32(a, b), a, b) }
}

/// SSE's `minps` on four lanes: `a` where `a < b`, else `b` (so `b` when either is NaN).
#[inline(always)]
pub(crate) fn min_sse(a: float32x4_t, b: float32x4_t) -> float32x4_t {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vbslq_f32(vcltq_f32(a, b), a, b) }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_set1_ps(x: f32) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    let v = unsafe { vdupq_n_f32(x) };
    __m256 { lo: v, hi: v }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_setzero_ps() -> __m256 {
    // SAFETY: as above.
    unsafe { _mm256_set1_ps(0.0) }
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) unsafe fn _mm256_setr_ps(
    e0: f32,
    e1: f32,
    e2: f32,
    e3: f32,
    e4: f32,
    e5: f32,
    e6: f32,
    e7: f32,
) -> __m256 {
    let v = [e0, e1, e2, e3, e4, e5, e6, e7];
    // SAFETY: the load reads the eight floats of `v`.
    unsafe { _mm256_loadu_ps(v.as_ptr()) }
}

/// # Safety
/// `p` must point to eight readable floats.
#[inline(always)]
pub(crate) unsafe fn _mm256_loadu_ps(p: *const f32) -> __m256 {
    // SAFETY: forwarded from the caller.
    unsafe {
        __m256 {
            lo: vld1q_f32(p),
            hi: vld1q_f32(p.add(4)),
        }
    }
}

/// # Safety
/// `p` must point to eight writable floats.
#[inline(always)]
pub(crate) unsafe fn _mm256_storeu_ps(p: *mut f32, a: __m256) {
    // SAFETY: forwarded from the caller.
    unsafe {
        vst1q_f32(p, a.lo);
        vst1q_f32(p.add(4), a.hi);
    }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_add_ps(a: __m256, b: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    pair(a, b, |x, y| unsafe { vaddq_f32(x, y) })
}

#[inline(always)]
pub(crate) unsafe fn _mm256_sub_ps(a: __m256, b: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    pair(a, b, |x, y| unsafe { vsubq_f32(x, y) })
}

#[inline(always)]
pub(crate) unsafe fn _mm256_mul_ps(a: __m256, b: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    pair(a, b, |x, y| unsafe { vmulq_f32(x, y) })
}

#[inline(always)]
pub(crate) unsafe fn _mm256_div_ps(a: __m256, b: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    pair(a, b, |x, y| unsafe { vdivq_f32(x, y) })
}

/// `maxps`: `a` where `a > b`, else `b` (so `b` when either is NaN).
#[inline(always)]
pub(crate) unsafe fn _mm256_max_ps(a: __m256, b: __m256) -> __m256 {
    pair(a, b, max_sse)
}

/// `minps`: `a` where `a < b`, else `b` (so `b` when either is NaN).
#[inline(always)]
pub(crate) unsafe fn _mm256_min_ps(a: __m256, b: __m256) -> __m256 {
    pair(a, b, min_sse)
}

#[inline(always)]
pub(crate) unsafe fn _mm256_and_ps(a: __m256, b: __m256) -> __m256 {
    on_bits!(vandq_u32, a, b)
}

#[inline(always)]
pub(crate) unsafe fn _mm256_or_ps(a: __m256, b: __m256) -> __m256 {
    on_bits!(vorrq_u32, a, b)
}

#[inline(always)]
pub(crate) unsafe fn _mm256_xor_ps(a: __m256, b: __m256) -> __m256 {
    on_bits!(veorq_u32, a, b)
}

/// `!a & b`.
#[inline(always)]
pub(crate) unsafe fn _mm256_andnot_ps(a: __m256, b: __m256) -> __m256 {
    // `vbic(x, y)` is `x & !y`.
    on_bits!(vbicq_u32, b, a)
}

/// All ones in the lanes where predicate `IMM` holds, else zeros.
#[inline(always)]
pub(crate) unsafe fn _mm256_cmp_ps<const IMM: i32>(a: __m256, b: __m256) -> __m256 {
    const {
        assert!(matches!(
            IMM,
            _CMP_EQ_OQ | _CMP_LT_OQ | _CMP_LE_OQ | _CMP_NLT_UQ | _CMP_GE_OQ | _CMP_GT_OQ
        ))
    };
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    let f = |x, y| unsafe {
        let m = match IMM {
            _CMP_EQ_OQ => vceqq_f32(x, y),
            _CMP_LT_OQ => vcltq_f32(x, y),
            _CMP_LE_OQ => vcleq_f32(x, y),
            _CMP_NLT_UQ => vmvnq_u32(vcltq_f32(x, y)),
            _CMP_GE_OQ => vcgeq_f32(x, y),
            _ => vcgtq_f32(x, y),
        };
        vreinterpretq_f32_u32(m)
    };
    pair(a, b, f)
}

/// Bit `i` for each lane `i` of `a` whose sign bit is set: each lane's upper half narrowed to
/// 16 bits (the sign at bit 15), shifted right to bit `i`, kept alone and summed (five
/// instructions; two masks of four lanes summed apart took eight).
#[inline(always)]
pub(crate) unsafe fn _mm256_movemask_ps(a: __m256) -> i32 {
    const SHIFT: [i16; 8] = [-15, -14, -13, -12, -11, -10, -9, -8];
    const BIT: [u16; 8] = [1, 2, 4, 8, 16, 32, 64, 128];
    // SAFETY: NEON is baseline on aarch64; the loads read the eight values of `SHIFT` and
    // `BIT` (constants, hoisted out of loops).
    unsafe {
        let top = vshrn_high_n_u32::<16>(
            vshrn_n_u32::<16>(vreinterpretq_u32_f32(a.lo)),
            vreinterpretq_u32_f32(a.hi),
        );
        let moved = vshlq_u16(top, vld1q_s16(SHIFT.as_ptr()));
        i32::from(vaddvq_u16(vandq_u16(moved, vld1q_u16(BIT.as_ptr()))))
    }
}

/// `b` in the lanes whose `mask` has its sign bit set, else `a`.
#[inline(always)]
pub(crate) unsafe fn _mm256_blendv_ps(a: __m256, b: __m256, mask: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    let f = |x, y, m: float32x4_t| unsafe {
        let m = vreinterpretq_u32_s32(vshrq_n_s32::<31>(vreinterpretq_s32_f32(m)));
        vbslq_f32(m, y, x)
    };
    __m256 {
        lo: f(a.lo, b.lo, mask.lo),
        hi: f(a.hi, b.hi, mask.hi),
    }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_set1_epi32(x: i32) -> __m256i {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    let v = unsafe { vdupq_n_u32(x as u32) };
    __m256i { lo: v, hi: v }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_castsi256_ps(a: __m256i) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe {
        __m256 {
            lo: vreinterpretq_f32_u32(a.lo),
            hi: vreinterpretq_f32_u32(a.hi),
        }
    }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_castps_si256(a: __m256) -> __m256i {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe {
        __m256i {
            lo: vreinterpretq_u32_f32(a.lo),
            hi: vreinterpretq_u32_f32(a.hi),
        }
    }
}

#[inline(always)]
pub(crate) unsafe fn _mm256_cmpeq_epi32(a: __m256i, b: __m256i) -> __m256i {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe {
        __m256i {
            lo: vceqq_u32(a.lo, b.lo),
            hi: vceqq_u32(a.hi, b.hi),
        }
    }
}

/// `lo` in lanes 0–3, `hi` in lanes 4–7.
#[inline(always)]
pub(crate) unsafe fn _mm256_set_m128(hi: __m128, lo: __m128) -> __m256 {
    __m256 { lo, hi }
}

/// Per half: `a0 b0 a1 b1`.
#[inline(always)]
pub(crate) unsafe fn _mm256_unpacklo_ps(a: __m256, b: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    pair(a, b, |x, y| unsafe { vzip1q_f32(x, y) })
}

/// Per half: `a2 b2 a3 b3`.
#[inline(always)]
pub(crate) unsafe fn _mm256_unpackhi_ps(a: __m256, b: __m256) -> __m256 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    pair(a, b, |x, y| unsafe { vzip2q_f32(x, y) })
}

/// Per half, lanes `IMM` picks: `0x44` is `a0 a1 b0 b1`, `0xee` is `a2 a3 b2 b3` (the two the
/// transposes use).
#[inline(always)]
pub(crate) unsafe fn _mm256_shuffle_ps<const IMM: i32>(a: __m256, b: __m256) -> __m256 {
    const { assert!(IMM == 0x44 || IMM == 0xee) };
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    let f = |x, y| unsafe {
        let (x, y) = (vreinterpretq_f64_f32(x), vreinterpretq_f64_f32(y));
        vreinterpretq_f32_f64(if IMM == 0x44 {
            vzip1q_f64(x, y)
        } else {
            vzip2q_f64(x, y)
        })
    };
    pair(a, b, f)
}

/// # Safety
/// `p` must point to sixteen readable bytes.
#[inline(always)]
pub(crate) unsafe fn _mm_loadu_si128(p: *const __m128i) -> __m128i {
    // SAFETY: forwarded from the caller.
    unsafe { vld1q_u8(p as *const u8) }
}

#[inline(always)]
pub(crate) unsafe fn _mm_castsi128_ps(a: __m128i) -> __m128 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vreinterpretq_f32_u8(a) }
}

/// `x` in the low eight bytes, zeros above.
#[inline(always)]
pub(crate) unsafe fn _mm_cvtsi64_si128(x: i64) -> __m128i {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vreinterpretq_u8_u64(vsetq_lane_u64::<0>(x as u64, vdupq_n_u64(0))) }
}

#[inline(always)]
pub(crate) unsafe fn _mm_setzero_si128() -> __m128i {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vdupq_n_u8(0) }
}

#[inline(always)]
pub(crate) unsafe fn _mm_cmpeq_epi8(a: __m128i, b: __m128i) -> __m128i {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vceqq_u8(a, b) }
}

/// Bit `i` for each byte `i` of `a` whose top bit is set.
#[inline(always)]
pub(crate) unsafe fn _mm_movemask_epi8(a: __m128i) -> i32 {
    const SHIFT: [i8; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7];
    // SAFETY: NEON is baseline on aarch64; the load reads the sixteen bytes of `SHIFT`.
    unsafe {
        let bits = vshlq_u8(vshrq_n_u8::<7>(a), vld1q_s8(SHIFT.as_ptr()));
        let lo = u32::from(vaddv_u8(vget_low_u8(bits)));
        let hi = u32::from(vaddv_u8(vget_high_u8(bits)));
        (lo | (hi << 8)) as i32
    }
}
