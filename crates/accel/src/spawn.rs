//! Where secondary rays start: hit points with error bounds, and offsets off the surface.

use crate::structure::Accel;
use crate::types::{Hit, Ray};
use glam::Vec3;

/// A hit's position in world space with a bound on its rounding error: where secondary rays
/// start from (see [`SpawnPoint::origin`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpawnPoint {
    /// The hit position, `origin + t * dir` of the ray that found it.
    pub p: Vec3,
    /// Bound on the distance from `p` to the exact surface point (world units, any direction).
    pub error: f32,
}

impl SpawnPoint {
    /// The origin of a ray leaving the surface on the side `n` points to (pass the geometric
    /// normal flipped towards the new ray's direction): `p` pushed past its error bound along `n`,
    /// then by a few ulps with [`offset_ray_origin`].
    ///
    /// Why not only `offset_ray_origin`: on instanced meshes the point's error comes from the
    /// transform's magnitudes (say a coordinate near 0 computed from terms near 1e4), which a
    /// few ulps of the point's own coordinates do not cover.
    ///
    /// Near zero (coordinates below 1/32) the last step is the error bound rather than
    /// `offset_ray_origin`'s fixed 1/65536 units: the bound already covers the rounding that
    /// fixed step guards against, and a fixed step is a large part of a scene measured in units
    /// of 1e-4 (it lost contact shadows there). An `error` of 0 means "not known": then the
    /// fixed step stays, exactly as `offset_ray_origin`.
    #[inline]
    pub fn origin(&self, n: Vec3) -> Vec3 {
        let n = n.normalize_or_zero();
        if self.error > 0.0 {
            offset_ulps(self.p + n * (2.0 * self.error), n, self.error)
        } else {
            offset_ray_origin(self.p, n)
        }
    }
}

impl Accel {
    /// The world position of `hit` (found by `ray`) with a bound on its error, for spawning
    /// secondary rays with [`SpawnPoint::origin`].
    pub fn spawn_point(&self, ray: &Ray, hit: &Hit) -> SpawnPoint {
        let p = ray.origin + ray.dir * hit.t;
        let ray_part = ray.origin.abs().max_element() + (ray.dir * hit.t).abs().max_element();
        let transform_part = self.magnitude_of(hit.instance);
        // A few roundings of each magnitude: o + t d (2), the triangle test's t (a few), and the
        // object/world transforms of the ray and of the vertices (about 3 each).
        SpawnPoint {
            p,
            error: 16.0 * f32::EPSILON * (ray_part + transform_part),
        }
    }

    /// The bound on magnitudes met moving points of `instance` between object and world space.
    fn magnitude_of(&self, instance: u32) -> f32 {
        self.instance_magnitude
            .get(instance as usize)
            .copied()
            .unwrap_or(0.0)
    }

    /// A point `p` computed on a triangle of instance `instance` (say by interpolating its
    /// vertices, as a light sample is), with a bound on its rounding error: where a ray towards
    /// or from that point may start or end without meeting the triangle itself.
    pub fn surface_point(&self, instance: u32, p: Vec3) -> SpawnPoint {
        let transform_part = self.magnitude_of(instance);
        // Interpolation (a few roundings of the vertex magnitudes) and the object-to-world
        // transform (about 3 of the transform's).
        SpawnPoint {
            p,
            error: 16.0 * f32::EPSILON * (p.abs().max_element() + transform_part),
        }
    }
}

/// Moves a surface point off its surface along the geometric normal so that a ray leaving it
/// cannot hit the same surface again (Wächter and Binder, Ray Tracing Gems ch. 6): the offset is
/// a few float ulps of the point's magnitude, not a fixed epsilon. `n` need not face the ray;
/// pass the normal flipped to the side the new ray leaves on.
///
/// It covers the rounding of a point computed from values of its own magnitude (barycentric
/// interpolation of world-space vertices). Points on instanced meshes, or computed as
/// `o + t d`, can carry more error; use [`Accel::spawn_point`] and [`SpawnPoint::origin`] there.
/// Coordinates below 1/32 move by a fixed `n / 65536` (as in the paper), which is large
/// compared with scenes of millimetre scale: harmless for self-intersection, but such scenes
/// are better modelled in larger units.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    offset_ulps(p, n, 1.0 / 65536.0)
}

/// Wächter and Binder's offset: 256 ulps along `n` for coordinates of at least 1/32, and
/// `float_scale · n` for those below, whose ulps are too fine to cover a rounding error that
/// comes from larger magnitudes elsewhere.
///
/// The three coordinates at once in SSE2, branch-free: the same bits as the per-coordinate
/// form ([`offset_ulps_scalar`], which targets other than x86-64 and aarch64 take), at about a
/// third of its instructions (it runs at every path vertex).
#[cfg(target_arch = "x86_64")]
#[inline]
fn offset_ulps(p: Vec3, n: Vec3, float_scale: f32) -> Vec3 {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86_64 baseline; the store writes the four floats of `out`.
    unsafe {
        let pv = _mm_setr_ps(p.x, p.y, p.z, 0.0);
        let nv = _mm_setr_ps(n.x, n.y, n.z, 0.0);
        let scaled = _mm_mul_ps(_mm_set1_ps(INT_SCALE), nv);
        // `as i32`: truncation that saturates and takes NaN to 0, where `cvttps` gives
        // `i32::MIN` for all three.
        let of_i = _mm_cvttps_epi32(scaled);
        let high = _mm_castps_si128(_mm_cmpge_ps(scaled, _mm_set1_ps(2_147_483_648.0)));
        let of_i = _mm_or_si128(
            _mm_and_si128(high, _mm_set1_epi32(i32::MAX)),
            _mm_andnot_si128(high, of_i),
        );
        let of_i = _mm_andnot_si128(_mm_castps_si128(_mm_cmpunord_ps(scaled, scaled)), of_i);
        // Negative coordinates step by −of_i (wrapping): (x ^ −1) − (−1) = −x.
        let neg = _mm_castps_si128(_mm_cmplt_ps(pv, _mm_setzero_ps()));
        let step = _mm_sub_epi32(_mm_xor_si128(of_i, neg), neg);
        let moved = _mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(pv), step));
        let small = _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.0), pv), _mm_set1_ps(ORIGIN));
        let near = _mm_add_ps(pv, _mm_mul_ps(_mm_set1_ps(float_scale), nv));
        let out = _mm_or_ps(_mm_and_ps(small, near), _mm_andnot_ps(small, moved));
        let mut lanes = [0.0f32; 4];
        _mm_storeu_ps(lanes.as_mut_ptr(), out);
        Vec3::new(lanes[0], lanes[1], lanes[2])
    }
}

/// [`offset_ulps`] with NEON (aarch64): `fcvtzs` saturates and takes NaN to 0 as `as i32`
/// does, so the conversion needs no fix-up.
#[cfg(target_arch = "aarch64")]
#[inline]
fn offset_ulps(p: Vec3, n: Vec3, float_scale: f32) -> Vec3 {
    use std::arch::aarch64::*;
    // SAFETY: NEON is baseline on aarch64 (every intrinsic needs it); the loads read the four
    // floats of `pa` and `na`, the store writes the four of `out`.
    unsafe {
        let (pa, na) = ([p.x, p.y, p.z, 0.0], [n.x, n.y, n.z, 0.0]);
        let (pv, nv) = (vld1q_f32(pa.as_ptr()), vld1q_f32(na.as_ptr()));
        let of_i = vcvtq_s32_f32(vmulq_f32(vdupq_n_f32(INT_SCALE), nv));
        // Negative coordinates step by −of_i (wrapping): (x ^ −1) − (−1) = −x.
        let neg = vreinterpretq_s32_u32(vcltq_f32(pv, vdupq_n_f32(0.0)));
        let step = vsubq_s32(veorq_s32(of_i, neg), neg);
        let moved = vreinterpretq_f32_s32(vaddq_s32(vreinterpretq_s32_f32(pv), step));
        let small = vcltq_f32(vabsq_f32(pv), vdupq_n_f32(ORIGIN));
        let near = vaddq_f32(pv, vmulq_f32(vdupq_n_f32(float_scale), nv));
        let mut out = [0.0f32; 4];
        vst1q_f32(out.as_mut_ptr(), vbslq_f32(small, near, moved));
        Vec3::new(out[0], out[1], out[2])
    }
}

#[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
#[inline]
fn offset_ulps(p: Vec3, n: Vec3, float_scale: f32) -> Vec3 {
    offset_ulps_scalar(p, n, float_scale)
}

/// Coordinates of at least this magnitude move by ulps, smaller ones by `float_scale · n`.
const ORIGIN: f32 = 1.0 / 32.0;
/// The ulps a unit normal component moves a coordinate by.
const INT_SCALE: f32 = 256.0;

/// [`offset_ulps`] coordinate by coordinate, as the paper writes it.
#[cfg_attr(any(target_arch = "x86_64", target_arch = "aarch64"), allow(dead_code))]
fn offset_ulps_scalar(p: Vec3, n: Vec3, float_scale: f32) -> Vec3 {
    let of_i = (INT_SCALE * n).to_array().map(|x| x as i32);
    let pa = p.to_array();
    let mut out = [0.0f32; 3];
    for k in 0..3 {
        // Wrapping: near zero (handled by the float branch below) or for huge normals the
        // integer step may overflow; the paper's C relies on two's complement wrapping too.
        let bits = pa[k].to_bits() as i32;
        let step = if pa[k] < 0.0 {
            of_i[k].wrapping_neg()
        } else {
            of_i[k]
        };
        let moved = bits.wrapping_add(step);
        let p_i = f32::from_bits(moved as u32);
        out[k] = if pa[k].abs() < ORIGIN {
            pa[k] + float_scale * n[k]
        } else {
            p_i
        };
    }
    Vec3::from_array(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::mix;

    /// A value from a counter, over every float class the offset meets: zeros, tiny and huge
    /// magnitudes, both signs, the 1/32 boundary, infinities and NaN.
    fn value(k: u32) -> f32 {
        const SPECIAL: [f32; 12] = [
            0.0,
            -0.0,
            ORIGIN,
            -ORIGIN,
            1.0 / 64.0,
            1e-30,
            -3e38,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1e-45,
        ];
        let h = mix(k);
        if h % 4 == 0 {
            SPECIAL[(h >> 8) as usize % SPECIAL.len()]
        } else {
            // Any bit pattern: every exponent and sign.
            f32::from_bits(mix(h))
        }
    }

    #[test]
    fn the_simd_offset_has_the_bits_of_the_scalar_one() {
        let mut checked = 0;
        for k in 0..200_000u32 {
            let p = Vec3::new(value(6 * k), value(6 * k + 1), value(6 * k + 2));
            // Unit normals, as the callers pass, and raw values (saturating conversions).
            let raw = Vec3::new(value(6 * k + 3), value(6 * k + 4), value(6 * k + 5));
            let unit = raw.normalize_or_zero();
            for n in [unit, raw, raw * 1e-3] {
                for scale in [1.0 / 65536.0, 3e-7, 0.5] {
                    let a = offset_ulps(p, n, scale).to_array().map(f32::to_bits);
                    let b = offset_ulps_scalar(p, n, scale).to_array().map(f32::to_bits);
                    assert_eq!(a, b, "p {p:?} n {n:?} scale {scale}");
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 1_800_000);
    }
}
