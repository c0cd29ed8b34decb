//! Watertight ray/triangle intersection (Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013) with the error bounds of pbrt-v4.
//!
//! Why this test: the vertices are moved into a space where the ray is the +z axis, and the 2D
//! edge functions are evaluated on those moved vertices. A vertex is moved identically for every
//! triangle that shares it, so the edge function of a shared edge is bitwise the same (negated)
//! on both sides: a ray cannot slip through. Edge values of exactly zero are recomputed in `f64`,
//! where the products of two `f32` are exact, so the sign of the edge function is never lost.

#[cfg(test)]
use glam::Mat3A;
use glam::{Vec3, Vec3A};

#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) mod lanes;
#[cfg(all(test, target_arch = "aarch64"))]
mod neon_tests;
#[cfg(target_arch = "aarch64")]
mod sheared_neon;

/// A triangle in BVH order: its vertices exactly as given (shared vertices stay bitwise equal,
/// which the watertight test relies on) and its index in the mesh's original `indices`.
#[derive(Debug, Clone, Copy, bytemuck::Zeroable)]
#[repr(C)]
pub(crate) struct Tri {
    pub(crate) p: [Vec3; 3],
    pub(crate) prim: u32,
}

/// Per-ray values of the watertight test, computed once per ray (and per instance, for rays
/// moved into object space).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TriRay {
    /// Ray origin.
    pub origin: Vec3A,
    /// `1 / dir[kz]`: scales z into units of `t`.
    pub sz: f32,
    /// The direction, for the `f64` check of hits close to the origin ([`t_in_front_f64`]).
    pub dir: Vec3A,
    /// `(kx, ky, kz, kz)`: `kz` is the axis of the largest direction component; `kx`, `ky` are
    /// the others, swapped when `dir[kz] < 0` to keep the winding. The shear maps `v - origin`
    /// to `(v[kx] + sx v[kz], v[ky] + sy v[kz], v[kz])` (one product, one sum: the same value
    /// for every triangle sharing the vertex, which is what makes the test watertight), the
    /// product with the matrix of rows `e_kx + sx e_kz`, `e_ky + sy e_kz`, `e_kz` ([`sheared`];
    /// the packets' lanes build that matrix, `lanes::TriLanes`).
    pub perm: [i32; 4],
    /// The origin's components in that order (read by the x86-64 and aarch64 kernels only).
    #[cfg_attr(
        not(any(target_arch = "x86_64", target_arch = "aarch64")),
        allow(dead_code)
    )]
    pub origin_k: Vec3A,
    /// `(sx, sy, 1)`: `sx = -dir[kx] / dir[kz]`, `sy = -dir[ky] / dir[kz]` (only the first two
    /// lanes are used).
    pub s: Vec3A,
}

impl TriRay {
    /// Precomputes the shear for a ray.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let (kx, ky, kz) = axes(dir);
        let d = dir.to_array();
        let sz = 1.0 / d[kz];
        let (sx, sy) = (-d[kx] * sz, -d[ky] * sz);
        let o = origin.to_array();
        Self {
            origin: origin.into(),
            sz,
            dir: dir.into(),
            perm: [kx as i32, ky as i32, kz as i32, kz as i32],
            origin_k: Vec3A::new(o[kx], o[ky], o[kz]),
            s: Vec3A::new(sx, sy, 1.0),
        }
    }

    /// [`TriRay::new`] with AVX, the same bits: the axes from one lane-wise comparison and two
    /// small tables instead of branches, the direction and origin permuted in registers instead
    /// of indexed through the stack. Must be inlined into a function compiled for AVX (the
    /// queries' AVX2 paths: `AVX` of [`TriRay::new_for`]).
    ///
    /// # Safety
    /// The CPU must support AVX, and the caller must be compiled for it.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub unsafe fn new_avx(origin: Vec3, dir: Vec3) -> Self {
        use std::arch::x86_64::*;
        /// `kz` of [`axes`] for the bits `|x| > |y|`, `|x| > |z|`, `|y| > |z|` (bit 0, 1, 2).
        const KZ: [usize; 8] = [2, 2, 2, 0, 1, 2, 1, 0];
        /// `(kx, ky, kz, kz)` of [`axes`] for `2 kz + (dir[kz] < 0)`.
        const PERM: [[i32; 4]; 6] = [
            [1, 2, 0, 0],
            [2, 1, 0, 0],
            [2, 0, 1, 1],
            [0, 2, 1, 1],
            [0, 1, 2, 2],
            [1, 0, 2, 2],
        ];
        // SAFETY: AVX is guaranteed by the caller; register-only operations and one 16-byte
        // load of a `[i32; 4]` table row.
        unsafe {
            let d: __m128 = Vec3A::from(dir).into();
            let o: __m128 = Vec3A::from(origin).into();
            let a = _mm_andnot_ps(_mm_set1_ps(-0.0), d);
            // Lanes (|x|, |x|, |y|) against (|y|, |z|, |z|): `axes`' comparisons (false on NaN).
            let gt = _mm_cmpgt_ps(
                _mm_permute_ps::<0b00_01_00_00>(a),
                _mm_permute_ps::<0b00_10_10_01>(a),
            );
            let kz = KZ[(_mm_movemask_ps(gt) & 7) as usize];
            let neg = (_mm_movemask_ps(_mm_cmplt_ps(d, _mm_setzero_ps())) >> kz) & 1;
            let perm = PERM[2 * kz + neg as usize];
            let pv = _mm_loadu_si128(perm.as_ptr() as *const __m128i);
            let dk = _mm_permutevar_ps(d, pv);
            let sz = _mm_div_ps(_mm_set1_ps(1.0), _mm_permute_ps::<0xaa>(dk));
            // `-d[k] * sz` per lane; `(sx, sy, 1, 1)` as `Vec3A::new(sx, sy, 1.0)` leaves it.
            let s = _mm_mul_ps(_mm_xor_ps(dk, _mm_set1_ps(-0.0)), sz);
            Self {
                origin: origin.into(),
                sz: _mm_cvtss_f32(sz),
                dir: dir.into(),
                perm,
                origin_k: _mm_permutevar_ps(o, pv).into(),
                s: _mm_blend_ps::<0b1100>(s, _mm_set1_ps(1.0)).into(),
            }
        }
    }

    /// [`TriRay::new_avx`] with `AVX`, else [`TriRay::new`] (the same bits).
    ///
    /// # Safety
    /// With `AVX`, as for [`TriRay::new_avx`].
    #[inline(always)]
    pub unsafe fn new_for<const AVX: bool>(origin: Vec3, dir: Vec3) -> Self {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: forwarded from the caller.
            return unsafe { Self::new_avx(origin, dir) };
        }
        Self::new(origin, dir)
    }

    /// `(kx, ky, kz)` as indices (see [`TriRay::perm`]; `% 3` so that no value could index
    /// past a 3-array).
    #[inline(always)]
    fn axes(&self) -> [usize; 3] {
        [0, 1, 2].map(|c| self.perm[c] as usize % 3)
    }

    /// The shear as a matrix (see [`TriRay::perm`]), built as columns: column `kx` is
    /// `(1, 0, 0)`, `ky` is `(0, 1, 0)`, `kz` is `(sx, sy, 1)`. The reference of the lanes'.
    #[cfg(test)]
    pub fn shear(&self) -> Mat3A {
        let [kx, ky, kz] = self.axes();
        let mut cols = [Vec3A::ZERO; 3];
        cols[kx] = Vec3A::X;
        cols[ky] = Vec3A::Y;
        cols[kz] = self.s;
        Mat3A::from_cols(cols[0], cols[1], cols[2])
    }
}

/// The test's axes for a direction: `kz` the axis of the largest component, `kx`, `ky` the
/// others, swapped when `dir[kz] < 0` to keep the winding.
#[inline(always)]
fn axes(dir: Vec3) -> (usize, usize, usize) {
    let a = dir.abs();
    let kz = if a.x > a.y {
        if a.x > a.z {
            0
        } else {
            2
        }
    } else if a.y > a.z {
        1
    } else {
        2
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if dir[kz] < 0.0 {
        (ky, kx, kz)
    } else {
        (kx, ky, kz)
    }
}

#[inline(always)]
fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// Vertex `k` of `tri` moved into the ray's space: `(d[kx] + sx d[kz], d[ky] + sy d[kz], d[kz])`
/// for `d = p[k] - origin`, one product and one sum per coordinate. The same values as the
/// product with the shear matrix (whose other terms are products with exact zeros), except
/// for the sign of a zero coordinate, which decides no edge function (a zero one is decided
/// again in `f64`), and where `d` overflows (there `0 * inf` made the product NaN).
///
/// With `AVX` (x86_64) it must be inlined into a function compiled for AVX: one unaligned load
/// of four floats (within the `Tri`, whose `prim` follows `p`), one permute, one product and
/// one sum, against three loads and nine operations for the matrix product.
#[inline(always)]
fn sheared<const AVX: bool>(r: &TriRay, tri: &Tri, k: usize) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        use std::arch::x86_64::*;
        // SAFETY: AVX is guaranteed by the caller (see above). `Tri` is `repr(C)`, `p` first:
        // the 16 bytes from vertex `k < 3` end at most at byte 40, the end of the `Tri`; the
        // fourth float read (the next vertex's x, or `prim`'s bits) is dropped by the permute.
        unsafe {
            let v = _mm_loadu_ps((tri as *const Tri as *const f32).add(3 * k));
            let perm = _mm_loadu_si128(r.perm.as_ptr() as *const __m128i);
            let d = _mm_sub_ps(_mm_permutevar_ps(v, perm), r.origin_k.into());
            let z = _mm_shuffle_ps::<0xaa>(d, d);
            let x = _mm_add_ps(d, _mm_mul_ps(r.s.into(), z));
            return _mm_blend_ps::<0b1100>(x, d).into();
        }
    }
    #[cfg(target_arch = "aarch64")]
    if AVX {
        // `AVX` on aarch64: the NEON path (`walk::detect_avx2`).
        return sheared_neon::sheared_neon(tri.p[k].into(), &r.perm, r.origin_k, r.s);
    }
    let d = (Vec3A::from(tri.p[k]) - r.origin).to_array();
    let [kx, ky, kz] = r.axes();
    let (dx, dy, dz) = (d[kx], d[ky], d[kz]);
    Vec3A::new(dx + r.s.x * dz, dy + r.s.y * dz, dz)
}

/// Intersects the ray with triangle `tri`. Returns `(t, b1, b2)` (barycentric weights of `p1`
/// and `p2`) for a hit with `tmin <= t <= tmax`. Both faces count. With `AVX`, see [`sheared`].
#[inline(always)]
pub(crate) fn intersect<const AVX: bool>(
    r: &TriRay,
    tri: &Tri,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    let a = sheared::<AVX>(r, tri, 0);
    let b = sheared::<AVX>(r, tri, 1);
    let c = sheared::<AVX>(r, tri, 2);
    let (ax, ay, az) = (a.x, a.y, a.z);
    let (bx, by, bz) = (b.x, b.y, b.z);
    let (cx, cy, cz) = (c.x, c.y, c.z);

    // Edge functions; e0 is the weight of p0, e1 of p1, e2 of p2.
    let mut e0 = bx * cy - by * cx;
    let mut e1 = cx * ay - cy * ax;
    let mut e2 = ax * by - ay * bx;
    // `|` and `&`, not `||` and `&&`: one branch per decision instead of a chain of them (the
    // sign test below decides hit or miss and is taken either way about as often: each link of
    // a chain was a misprediction to pay).
    if (e0 == 0.0) | (e1 == 0.0) | (e2 == 0.0) {
        // Exactly zero may be a lost sign: products of two f32 are exact in f64.
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        e0 = (bx * cy - by * cx) as f32;
        e1 = (cx * ay - cy * ax) as f32;
        e2 = (ax * by - ay * bx) as f32;
    }
    let negative = (e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0);
    let positive = (e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0);
    if negative & positive {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 || det.is_nan() {
        return None;
    }
    // pbrt-v4's x/y error terms add max|z| assuming |dir| is about 1; for unnormalised directions
    // (any scale) they need z before it is scaled by 1/dir[kz], in the same units as x and y.
    let az = az * r.sz;
    let bz = bz * r.sz;
    let cz = cz * r.sz;
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !(t >= tmin && t <= tmax) {
        return None;
    }
    // pbrt-v4: reject hits whose t is not provably positive (they may lie behind the origin),
    // unless the f64 plane distance proves them in front (`t_in_front_f64`). No value here is
    // NaN (a NaN coordinate makes `det` or `t` NaN), so the lane-wise maxima (`maxps`) equal
    // `f32::max`'s.
    let m = a.abs().max(b.abs()).max(c.abs());
    let (max_xt, max_yt, max_z) = (m.x, m.y, m.z);
    let max_zt = Vec3A::new(az, bz, cz).abs().max_element();
    let delta_z = gamma(3) * max_zt;
    let delta_x = gamma(5) * (max_xt + max_z);
    let delta_y = gamma(5) * (max_yt + max_z);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = Vec3A::new(e0, e1, e2).abs().max_element();
    let delta_t =
        3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t <= delta_t {
        return t_in_front_f64(r, &tri.p)
            .filter(|t| *t >= tmin && *t <= tmax)
            .map(|t| (t, e1 * inv_det, e2 * inv_det));
    }
    Some((t, e1 * inv_det, e2 * inv_det))
}

/// Where the ray meets the plane of triangle `p`, if provably in front of its origin, decided
/// in `f64`. pbrt-v4's bound above grows with the triangle's extent seen from the origin: a ray
/// leaving a concave corner meets the other surface's large triangles a few 1e-5 away, closer
/// than that bound, and would pass through them (light leaking out of a closed room). In `f64`
/// the edges of `f32` points are exact, their cross products round once, and the two dot
/// products `w . n`, `d . n` a few times more: both are known to about 1e-15 of their
/// magnitudes, so a margin of 1e-12 decides their signs beyond doubt. The `t` returned is then
/// also more accurate than the `f32` one. Called only for hits the bound would reject, and kept
/// out of line: merely being callable holds registers in the hot test.
#[cold]
#[inline(never)]
fn t_in_front_f64(r: &TriRay, p: &[Vec3; 3]) -> Option<f32> {
    const MARGIN: f64 = 1e-12;
    let (o, d) = (
        Vec3::from(r.origin).as_dvec3(),
        Vec3::from(r.dir).as_dvec3(),
    );
    let [a, b, c] = p.map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    let w = a - o;
    // t = (w . n) / (d . n): in front when both have the same sign, each clear of its error.
    let (num, den) = (w.dot(n), d.dot(n));
    let (num_mag, den_mag) = (w.abs().dot(n.abs()), d.abs().dot(n.abs()));
    let sure = num * den > 0.0 && num.abs() > MARGIN * num_mag && den.abs() > MARGIN * den_mag;
    sure.then_some((num / den) as f32)
}

/// Watertight intersection of a ray with one triangle, in the ray's space: `(t, u, v)` with `u`, `v`
/// the barycentric weights of `p[1]` and `p[2]`, for hits with `ray.tmin <= t <= ray.tmax`.
///
/// This is the exact test the BVH runs on every triangle; it is public so that callers (and tests)
/// can compare against brute force with identical arithmetic.
pub fn intersect_triangle(ray: &crate::types::Ray, p: [Vec3; 3]) -> Option<(f32, f32, f32)> {
    let r = TriRay::new(ray.origin, ray.dir);
    intersect::<false>(&r, &Tri { p, prim: 0 }, ray.tmin, ray.tmax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::Ray;

    #[test]
    fn shear_is_the_documented_matrix() {
        for dir in [
            Vec3::new(0.3, -0.2, -1.0),
            Vec3::new(-2.0, 0.5, 0.1),
            Vec3::new(0.1, 3.0, -0.4),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(-0.0, -1.0, 0.0),
        ] {
            let r = TriRay::new(Vec3::ZERO, dir);
            let (kx, ky, kz) = axes(dir);
            let d = dir.to_array();
            let sz = 1.0 / d[kz];
            let mut rows = [[0.0f32; 3]; 3];
            rows[0][kx] = 1.0;
            rows[0][kz] = -d[kx] * sz;
            rows[1][ky] = 1.0;
            rows[1][kz] = -d[ky] * sz;
            rows[2][kz] = 1.0;
            let want = Mat3A::from_cols_array_2d(&rows).transpose();
            assert_eq!(
                r.shear().to_cols_array().map(f32::to_bits),
                want.to_cols_array().map(f32::to_bits),
                "{dir}"
            );
        }
    }

    /// The AVX construction has the scalar one's bits, field by field, on directions with
    /// ties between components, zeros of both signs, tiny, huge, infinite and NaN ones.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_construction_matches_the_scalar_one() {
        if !is_x86_feature_detected!("avx") {
            return;
        }
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -0.5,
            2.0,
            -3.0,
            1e-30,
            -1e-30,
            1e30,
            f32::INFINITY,
            -f32::INFINITY,
            f32::NAN,
        ];
        let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
        let mut cases = 0;
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let (o, d) = (Vec3::new(z, -x, 7.0), Vec3::new(x, y, z));
                    let want = TriRay::new(o, d);
                    // SAFETY: AVX checked above.
                    let got = unsafe { TriRay::new_avx(o, d) };
                    assert_eq!(got.perm, want.perm, "{d}");
                    assert_eq!(got.sz.to_bits(), want.sz.to_bits(), "{d}");
                    assert_eq!(bits(got.origin_k)[..3], bits(want.origin_k)[..3], "{d}");
                    assert_eq!(bits(got.s)[..3], bits(want.s)[..3], "{d}");
                    assert_eq!(bits(got.origin)[..3], bits(want.origin)[..3], "{d}");
                    assert_eq!(bits(got.dir)[..3], bits(want.dir)[..3], "{d}");
                    cases += 1;
                }
            }
        }
        assert_eq!(cases, values.len().pow(3));
    }

    #[test]
    fn barycentrics_reconstruct_the_hit_point() {
        let p = [
            Vec3::new(-1.0, -1.0, -3.0),
            Vec3::new(2.0, -1.0, -3.5),
            Vec3::new(0.0, 1.5, -2.5),
        ];
        for (x, y) in [(0.1, 0.2), (-0.1, -0.2), (0.15, 0.0)] {
            let ray = Ray::new(Vec3::ZERO, Vec3::new(x, y, -1.0));
            let (t, u, v) = intersect_triangle(&ray, p).expect("inside");
            let on_tri = p[0] * (1.0 - u - v) + p[1] * u + p[2] * v;
            let on_ray = ray.origin + ray.dir * t;
            assert!((on_tri - on_ray).length() < 1e-5, "{on_tri} vs {on_ray}");
        }
    }

    #[test]
    fn hits_do_not_depend_on_direction_length() {
        // Tiny and huge scenes give tiny and huge unnormalised directions (dir = target - origin).
        for scale in [1e-6f32, 1e-4, 1.0, 1e4, 1e6] {
            let p = [
                Vec3::new(-1.0, -1.0, -3.0) * scale,
                Vec3::new(2.0, -1.0, -3.5) * scale,
                Vec3::new(0.0, 1.5, -2.5) * scale,
            ];
            for k in 0..3 {
                let target = (p[0] + p[1] + p[2]) / 3.0 * 0.5 + p[k] * 0.5;
                for len in [1e-3f32, 1.0, 1e3] {
                    let dir = target / target.length() * scale * len;
                    let hit = intersect_triangle(&Ray::new(Vec3::ZERO, dir), p);
                    let t = hit.map(|h| h.0 * dir.length());
                    assert!(
                        t.is_some_and(|t| (t - target.length()).abs() < 1e-4 * target.length()),
                        "scale {scale} len {len} vertex {k}: {hit:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn both_faces_and_all_axes() {
        let p = [Vec3::X, Vec3::Y, Vec3::Z];
        let c = (p[0] + p[1] + p[2]) / 3.0;
        for dir in [c, -c, Vec3::new(1.0, 0.2, 0.3), Vec3::new(0.2, -1.0, 0.3)] {
            let o = c - dir * 2.0;
            let hit = intersect_triangle(&Ray::new(o, dir), p);
            assert!(
                hit.is_some_and(|h| (h.0 - 2.0).abs() < 1e-5),
                "{dir}: {hit:?}"
            );
        }
    }

    #[test]
    fn honours_tmin_and_tmax() {
        let p = [
            Vec3::new(-1.0, -1.0, -2.0),
            Vec3::new(1.0, -1.0, -2.0),
            Vec3::new(0.0, 1.0, -2.0),
        ];
        let mut ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
        assert!(intersect_triangle(&ray, p).is_some());
        ray.tmax = 1.9;
        assert!(intersect_triangle(&ray, p).is_none());
        ray.tmax = 3.0;
        ray.tmin = 2.1;
        assert!(intersect_triangle(&ray, p).is_none());
        // Behind the origin.
        ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(intersect_triangle(&ray, p).is_none());
    }

    #[test]
    fn degenerate_input_does_not_panic_or_hit() {
        let ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
        let flat = [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(3.0, 0.0, -1.0),
        ];
        assert!(intersect_triangle(&ray, flat).is_none());
        let nan = [Vec3::NAN, Vec3::X, Vec3::Y];
        assert!(intersect_triangle(&ray, nan).is_none());
        let zero_dir = Ray::new(Vec3::ZERO, Vec3::ZERO);
        let _ = intersect_triangle(&zero_dir, [Vec3::X, Vec3::Y, Vec3::Z]);
    }

    #[test]
    fn shared_edge_is_hit_exactly_once_or_twice_never_zero() {
        // Two triangles sharing the diagonal of a square, rays through points on the diagonal.
        let q = [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.3),
            Vec3::new(1.0, 1.0, -1.1),
            Vec3::new(0.0, 1.0, -0.7),
        ];
        let t0 = [q[0], q[1], q[2]];
        let t1 = [q[0], q[2], q[3]];
        // Interior points of the diagonal (its ends are corners of the square's outline).
        for i in 1..1000 {
            let s = i as f32 / 1000.0;
            let target = q[0] + (q[2] - q[0]) * s;
            let origin = Vec3::new(0.3137, 0.771, 2.0);
            let ray = Ray::new(origin, target - origin);
            let hits = intersect_triangle(&ray, t0).is_some() as u32
                + intersect_triangle(&ray, t1).is_some() as u32;
            assert!(
                hits >= 1,
                "ray through the shared edge at s={s} slipped through"
            );
        }
    }

    /// The two triangles of an 8 m floor quad (y = 0, x and z in [-4, 4]).
    fn floor() -> [[Vec3; 3]; 2] {
        let c = |x: f32, z: f32| Vec3::new(x, 0.0, z);
        [
            [c(-4.0, -4.0), c(4.0, -4.0), c(4.0, 4.0)],
            [c(-4.0, -4.0), c(4.0, 4.0), c(-4.0, 4.0)],
        ]
    }

    /// A ray leaving a wall just above a large floor, as a bounce off the wall's foot does,
    /// meets the floor a few 1e-5 away: in front of it beyond doubt, though closer than the
    /// f32 error bound of a hit on so large a triangle. It must hit (light used to leak out
    /// of a closed room there).
    #[test]
    fn hits_close_to_the_origin_on_large_triangles_count() {
        let dir = Vec3::new(0.969_221_3, -0.236_580_04, -0.068_116_87);
        let mut hits = 0;
        for k in 0..200 {
            let origin = Vec3::new(
                -3.25 + k as f32 * 0.01,
                1.287_460_3e-5,
                -2.0 + k as f32 * 0.013,
            );
            let ray = Ray::new(origin, dir);
            let h = floor().iter().find_map(|t| intersect_triangle(&ray, *t));
            let (t, _, _) = h.unwrap_or_else(|| panic!("ray {k} from {origin} leaks through"));
            // Within a few ulps of the floor's 4 m coordinates.
            let want = origin.y / -dir.y;
            assert!((t - want).abs() <= 1e-6, "{t} vs {want}");
            hits += 1;
        }
        assert_eq!(hits, 200);
    }

    /// A ray never hits the triangle it starts on, nor one it leaves from just in front.
    #[test]
    fn rays_leaving_the_plane_still_miss() {
        let dir = Vec3::new(0.3, 0.8, -0.2);
        for y in [0.0f32, 1e-7, 1e-5] {
            let ray = Ray::new(Vec3::new(0.5, y, 0.25), dir);
            assert!(
                floor()
                    .iter()
                    .all(|t| intersect_triangle(&ray, *t).is_none()),
                "{y}"
            );
            let down = Ray::new(Vec3::new(0.5, -y, 0.25), -dir);
            assert!(
                floor()
                    .iter()
                    .all(|t| intersect_triangle(&down, *t).is_none()),
                "{y}"
            );
        }
    }
}
