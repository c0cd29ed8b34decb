//! A vertex moved into a ray's space with NEON (aarch64): the x86-64 path of
//! `triangle::sheared` (a permute, one product, one sum) in registers, the same bits as the
//! scalar form, which indexes the coordinates through the stack.

use glam::Vec3A;
use std::arch::aarch64::*;

/// `v` in the ray's space: `d = v[perm] - origin_k`, then `(d.x + s.x d.z, d.y + s.y d.z, d.z)`
/// (lane 3: `d`'s). `perm` holds the axes `(kx, ky, kz, kz)` (each 0, 1 or 2), `origin_k` the
/// origin permuted alike and `s` the shear `(sx, sy, 1)`.
#[inline(always)]
pub(crate) fn sheared_neon(v: Vec3A, perm: &[i32; 4], origin_k: Vec3A, s: Vec3A) -> Vec3A {
    // SAFETY: NEON is baseline on aarch64 (every intrinsic needs it); the loads read the four
    // `i32`s of `perm` and of `KEEP_D`.
    unsafe {
        let p = vld1q_u32(perm.as_ptr() as *const u32);
        // Byte `4 j + b` of the result takes byte `4 perm[j] + b` of `v` (`perm[j] <= 2`: no
        // carries between the bytes).
        let index = vaddq_u32(
            vmulq_u32(p, vdupq_n_u32(0x0404_0404)),
            vdupq_n_u32(0x0302_0100),
        );
        let bytes = vreinterpretq_u8_f32(float32x4_t::from(v));
        let permuted = vreinterpretq_f32_u8(vqtbl1q_u8(bytes, vreinterpretq_u8_u32(index)));
        let d = vsubq_f32(permuted, origin_k.into());
        let z = vdupq_laneq_f32::<2>(d);
        let x = vaddq_f32(d, vmulq_f32(s.into(), z));
        const KEEP_D: [u32; 4] = [0, 0, u32::MAX, u32::MAX];
        vbslq_f32(vld1q_u32(KEEP_D.as_ptr()), d, x).into()
    }
}
