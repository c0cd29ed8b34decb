//! The eight-child box test with NEON (aarch64, where NEON is baseline: no run-time detection),
//! as two halves of four lanes: the x86-64 kernels' operations in their order, so the same bits
//! ([`super::intersect_node_avx2`], [`super::child_hits_enter_avx2`]).
//!
//! NEON's `fmax`/`fmin` return NaN when either operand is NaN, and `fmaxnm`/`fminnm` the number;
//! SSE's `maxps`/`minps` return the second operand then. The slabs' maxima and minima are
//! therefore a comparison and a select ([`max_sse`], [`min_sse`]): a NaN slab (a NaN ray, or
//! `0 * inf` on input that is invalid anyway) enters and leaves boxes exactly as on x86-64.
//!
//! Every intrinsic needs the `neon` target feature, which every aarch64 target has (the
//! `unsafe` blocks below are for that, and for the loads and stores their comments name).

use super::{BoxRay, ChildHits, Node};
use crate::avx::{max_sse, min_sse};
use std::arch::aarch64::*;

/// The box test of children `4 half .. 4 half + 4`: the hit lanes (all ones for a hit child)
/// and each child's entry distance; [`super::slabs_avx2`] on four lanes.
#[inline(always)]
fn slabs_half(
    rows: [&[f32; 8]; 6],
    r: &BoxRay,
    tmax: f32,
    half: usize,
) -> (uint32x4_t, float32x4_t) {
    let [nx, ny, nz, fx, fy, fz] = rows;
    let (on, of, ni) = (r.o_near, r.o_far, r.ninv);
    let k = 4 * (half & 1);
    // SAFETY: NEON is baseline on aarch64; `k + 4 <= 8`, so each load reads four floats inside
    // an `[f32; 8]` row.
    unsafe {
        let slab = |o: f32, row: &[f32; 8], ninv: f32| {
            let b = vld1q_f32(row.as_ptr().add(k));
            vmulq_f32(vsubq_f32(vdupq_n_f32(o), b), vdupq_n_f32(ninv))
        };
        let enter = max_sse(
            max_sse(vdupq_n_f32(r.tmin), slab(on.x, nx, ni.x)),
            max_sse(slab(on.y, ny, ni.y), slab(on.z, nz, ni.z)),
        );
        let exit = min_sse(
            min_sse(vdupq_n_f32(tmax), slab(of.x, fx, ni.x)),
            min_sse(slab(of.y, fy, ni.y), slab(of.z, fz, ni.z)),
        );
        (vcleq_f32(enter, exit), enter)
    }
}

/// The eight children's test: the hit lanes of each half and the entry distances.
#[inline(always)]
fn node_test(node: &Node, r: &BoxRay, tmax: f32) -> ([uint32x4_t; 2], [float32x4_t; 2]) {
    let rows = r.rows.planes(node);
    let (h0, e0) = slabs_half(rows, r, tmax, 0);
    let (h1, e1) = slabs_half(rows, r, tmax, 1);
    ([h0, h1], [e0, e1])
}

/// `movemask` of comparison results: bit `c` for each lane `c` of the two halves that is set.
#[inline(always)]
fn mask8(m: [uint32x4_t; 2]) -> u32 {
    const BITS: [u32; 4] = [1, 2, 4, 8];
    // SAFETY: NEON is baseline on aarch64; the load reads the four `u32`s of `BITS`.
    unsafe {
        let bits = vld1q_u32(BITS.as_ptr());
        // Lanes are all ones or all zeros (comparison results).
        let lo = vaddvq_u32(vandq_u32(m[0], bits));
        let hi = vaddvq_u32(vandq_u32(m[1], bits));
        lo | (hi << 4)
    }
}

/// The eight meta bytes of `node`'s children as two vectors of four `u32`s.
#[inline(always)]
fn meta_lanes(node: &Node) -> [uint32x4_t; 2] {
    // SAFETY: NEON is baseline on aarch64; the load reads exactly the 8 bytes of `child_meta`.
    unsafe {
        let wide = vmovl_u8(vld1_u8(node.child_meta.as_ptr()));
        [
            vmovl_u16(vget_low_u16(wide)),
            vmovl_u16(vget_high_u16(wide)),
        ]
    }
}

/// The OR of the eight `u32` lanes of `m`.
#[inline(always)]
fn or_lanes(m: [uint32x4_t; 2]) -> u32 {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe {
        let x = vorrq_u32(m[0], m[1]);
        let x = vorr_u32(vget_low_u32(x), vget_high_u32(x));
        vget_lane_u32::<0>(x) | vget_lane_u32::<1>(x)
    }
}

/// Each lane's `bits << shift`, kept where `hit` is set.
#[inline(always)]
fn shifted(bits: uint32x4_t, shift: uint32x4_t, hit: uint32x4_t) -> uint32x4_t {
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe { vandq_u32(vshlq_u32(bits, vreinterpretq_s32_u32(shift)), hit) }
}

/// [`super::intersect_node`] with NEON, the lane-wise hit mask of
/// [`super::intersect_node_avx2`] (no loop over the hit children).
#[inline(always)]
pub(crate) fn intersect_node_neon(node: &Node, r: &BoxRay, tmax: f32) -> u32 {
    let (hit, _) = node_test(node, r, tmax);
    let meta = meta_lanes(node);
    // SAFETY: NEON is baseline on aarch64; register-only operations.
    unsafe {
        let inner_bits = vdupq_n_u32(0x18);
        let oct = vdupq_n_u32(r.oct_inv4 & 0xff);
        let low5 = vdupq_n_u32(0x1f);
        let lane = |k: usize| {
            let inner = vceqq_u32(vandq_u32(meta[k], inner_bits), inner_bits);
            let index = vandq_u32(veorq_u32(meta[k], vandq_u32(oct, inner)), low5);
            shifted(vshrq_n_u32::<5>(meta[k]), index, hit[k])
        };
        or_lanes([lane(0), lane(1)])
    }
}

/// [`super::child_hits_enter`] with NEON (the arithmetic of [`intersect_node_neon`], the leaf
/// bits of [`super::child_hits_enter_avx2`]).
#[inline(always)]
pub(crate) fn child_hits_enter_neon(node: &Node, r: &BoxRay, tmax: f32) -> ChildHits {
    let (hit, e) = node_test(node, r, tmax);
    let meta = meta_lanes(node);
    let mut enter = [0.0; 8];
    // SAFETY: NEON is baseline on aarch64; the stores write the eight floats of `enter`, four
    // at a time.
    let prims = unsafe {
        vst1q_f32(enter.as_mut_ptr(), e[0]);
        vst1q_f32(enter.as_mut_ptr().add(4), e[1]);
        let low5 = vdupq_n_u32(0x1f);
        // Internal children (offset 24 + slot) set no bit below 24.
        let lane = |k: usize| shifted(vshrq_n_u32::<5>(meta[k]), vandq_u32(meta[k], low5), hit[k]);
        or_lanes([lane(0), lane(1)]) & 0x00ff_ffff
    };
    ChildHits {
        hits: mask8(hit),
        enter,
        prims,
    }
}
