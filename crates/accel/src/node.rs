//! Conservative ray test against the eight child boxes of a wide node: obvhs' compressed
//! `CwBvhNode` decompressed at build time into [`WideNode`], whose child boxes are `f32` planes
//! relative to the tree's centre (no per-ray dequantisation, and every per-ray constant of the
//! test is computed once per ray instead of once per node).
//!
//! obvhs' own test clamps the entry distance to a fixed `1e-4` instead of `ray.tmin` and does not
//! account for rounding, so hits are lost at small scales. This one honours `[tmin, tmax]` and
//! widens every slab by a bound on all rounding errors involved:
//! - obvhs quantises child boxes as `floor((child.min - p) / e)`, where the subtraction is rounded:
//!   the stored box can be short of the true one by one rounding of a value below `255 e`; the
//!   decompression to `f32` rounds outwards, so it only ever grows the box;
//! - the slab distances are evaluated as `b' * (1 / d) + (-(o - c) * (1 / d) ∓ slack)`, with `b'`
//!   a plane relative to the tree's centre `c` (about five roundings, each of a value below
//!   `(|b'| + |o - c|) / |d|`);
//! - the triangle test itself accepts hits up to a few ulps of `|v - o|` outside the triangle,
//!   in any axis (the shear mixes them), so the box must accept at least as much.
//!
//! All of these are below `K ε M` in space, where `M` bounds the largest coordinate of `|p - o|`
//! plus the node's extent. `M` is taken once per ray and tree as the largest coordinate of
//! `|corner - o|` over the tree's bounds plus three times its extent (so the slack costs nothing
//! per node and stays tight when the scene sits far from the world origin: planes and origin
//! are both taken relative to the tree's centre), and each slab is widened by `K ε M / |d_axis|`
//! in `t` (Ize 2013 scales `tmax` by `1 + 2γ` for the same purpose; an absolute bound also covers
//! rays that start inside a box).

use glam::{Vec3, Vec3A};
use obvhs::cwbvh::node::CwBvhNode;

/// Relative spatial slack of the box test (see the module docs); 64 ulps at unit scale, which
/// costs nothing measurable in traversal.
const SLACK: f32 = 64.0 * f32::EPSILON;

/// Largest magnitude of a reciprocal direction component: zero components become this (keeping
/// their sign), so slab products stay finite and `0 * inf` never makes a NaN.
const INV_LIMIT: f32 = 1e20;

/// The point child planes and ray origins are taken relative to: the centre of the tree's bounds.
#[inline]
pub(crate) fn centre((lo, hi): (Vec3, Vec3)) -> Vec3 {
    (lo + hi) * 0.5
}

/// A ray prepared for box tests.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BoxRay {
    pub inv: Vec3A,
    /// obvhs' child-ordering key for this direction.
    pub oct_inv4: u32,
    pub tmin: f32,
    /// Per axis: `-(o - c) / d` minus the slack (entry planes) and plus the slack (exit planes).
    pub off_lo: Vec3A,
    pub off_hi: Vec3A,
    /// Per axis, the index in [`WideNode::planes`] of the near and far planes. Always below 6:
    /// set only by [`BoxRay::new`] (the unchecked plane loads rely on it).
    near: [usize; 3],
    far: [usize; 3],
}

impl BoxRay {
    /// `bounds`: the tree's bounding box (sizes the rounding slack, and gives the centre the
    /// tree's planes are relative to; pass the bounds its nodes were converted with).
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, (lo, hi): (Vec3, Vec3)) -> Self {
        let inv = dir.to_array().map(|d| {
            let i = 1.0 / d;
            if i.is_finite() {
                i.clamp(-INV_LIMIT, INV_LIMIT)
            } else if d.is_sign_negative() {
                -INV_LIMIT
            } else {
                INV_LIMIT
            }
        });
        let neg = inv.map(|i| i < 0.0);
        let oct_inv4 = (if neg[0] { 0 } else { 0x0404_0404 })
            | (if neg[1] { 0 } else { 0x0202_0202 })
            | (if neg[2] { 0 } else { 0x0101_0101 });
        let inv = Vec3A::from_array(inv);
        let m = (lo - origin).abs().max((hi - origin).abs()).max_element()
            + 3.0 * (hi - lo).max_element();
        let slack = inv.abs() * (SLACK * m);
        let off = -(Vec3A::from(origin - centre((lo, hi))) * inv);
        Self {
            inv,
            oct_inv4,
            tmin,
            off_lo: off - slack,
            off_hi: off + slack,
            near: [0, 1, 2].map(|a| if neg[a] { 3 + a } else { a }),
            far: [0, 1, 2].map(|a| if neg[a] { a } else { 3 + a }),
        }
    }
}

/// An 8-wide node: obvhs' `CwBvhNode` with its child boxes decompressed to `f32` planes relative
/// to the tree's centre (rounded outwards), planes of one axis and side contiguous for SIMD loads.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub(crate) struct WideNode {
    /// `[side * 3 + axis][child]`: minimum planes (`side` 0), then maximum planes (`side` 1).
    pub planes: [[f32; 8]; 6],
    /// obvhs' child meta bytes (leaf primitive bits and offsets, internal child slots).
    pub child_meta: [u8; 8],
    pub child_base_idx: u32,
    pub primitive_base_idx: u32,
    /// Bit per child slot: internal node.
    pub imask: u8,
}

/// `x` rounded to `f32` towards minus infinity (`up`: plus infinity).
fn round_f32(x: f64, up: bool) -> f32 {
    let f = x as f32;
    if (up && (f as f64) < x) || (!up && (f as f64) > x) {
        next_toward(f, up)
    } else {
        f
    }
}

/// The next `f32` above (`up`) or below `f` (`f32::next_up`/`next_down`, newer than the MSRV).
/// Only called on finite values (the rounded neighbour of a finite `f64`).
fn next_toward(f: f32, up: bool) -> f32 {
    if !f.is_finite() {
        return f;
    }
    if f == 0.0 {
        let tiny = f32::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    let b = f.to_bits();
    // Away from zero when the step goes the way of the sign.
    f32::from_bits(if (f > 0.0) == up { b + 1 } else { b - 1 })
}

impl WideNode {
    /// Decompresses `n` with planes relative to `centre` (see [`centre`]). Each plane is computed
    /// in `f64` and rounded outwards, so the box contains obvhs' quantised box.
    pub fn from_cwbvh(n: &CwBvhNode, centre: Vec3) -> Self {
        let mut planes = [[0.0f32; 8]; 6];
        let qlo = [&n.child_min_x, &n.child_min_y, &n.child_min_z];
        let qhi = [&n.child_max_x, &n.child_max_y, &n.child_max_z];
        for a in 0..3 {
            let e = f32::from_bits((n.e[a] as u32) << 23) as f64;
            let p = n.p[a] as f64 - centre[a] as f64;
            for c in 0..8 {
                planes[a][c] = round_f32(p + qlo[a][c] as f64 * e, false);
                planes[3 + a][c] = round_f32(p + qhi[a][c] as f64 * e, true);
            }
        }
        Self {
            planes,
            child_meta: n.child_meta,
            child_base_idx: n.child_base_idx,
            primitive_base_idx: n.primitive_base_idx,
            imask: n.imask,
        }
    }

    /// `CwBvhNode::get_child_and_index_bits` on this node's meta bytes.
    #[inline(always)]
    fn get_child_and_index_bits(&self, oct_inv4: u32) -> (u64, u64) {
        let mut oct_inv8 = oct_inv4 as u64;
        oct_inv8 |= oct_inv8 << 32;
        let meta8 = u64::from_le_bytes(self.child_meta);
        let is_inner8 = (meta8 & (meta8 << 1)) & 0x1010_1010_1010_1010;
        let inner_mask8 = (is_inner8 >> 4) * 0xff;
        let bit_index8 = (meta8 ^ (oct_inv8 & inner_mask8)) & 0x1f1f_1f1f_1f1f_1f1f;
        let child_bits8 = (meta8 >> 5) & 0x0707_0707_0707_0707;
        (child_bits8, bit_index8)
    }

    /// Near and far planes of axis `a` for ray `r`, without a branch or a bounds check.
    #[inline(always)]
    fn near_far(&self, r: &BoxRay, a: usize) -> (&[f32; 8], &[f32; 8]) {
        debug_assert!(r.near[a] < 6 && r.far[a] < 6);
        // SAFETY: `BoxRay::new` sets every `near`/`far` entry to `a` or `3 + a` with `a < 3`, and
        // nothing else writes them (private fields), so both indices are below 6.
        unsafe {
            (
                self.planes.get_unchecked(r.near[a]),
                self.planes.get_unchecked(r.far[a]),
            )
        }
    }
}

/// obvhs' encoding of a child hit into the node hit mask: internal children set a bit in the top
/// byte (at their traversal priority), leaves set their primitives' bits in the low 24 bits.
#[inline(always)]
fn hitmask_from_children(node: &WideNode, oct_inv4: u32, mut hit8: u32) -> u32 {
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut mask = 0u32;
    while hit8 != 0 {
        let c = hit8.trailing_zeros() as usize;
        hit8 &= hit8 - 1;
        let bits = ((child_bits8 >> (c * 8)) & 0xff) as u32;
        let index = ((bit_index8 >> (c * 8)) & 0xff) as u32;
        mask |= bits << index;
    }
    mask
}

/// The node's hit mask for `[r.tmin, tmax]`, in obvhs' encoding.
#[inline(always)]
pub(crate) fn intersect_node(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    let hit8 = child_hits(node, r, tmax);
    hitmask_from_children(node, r.oct_inv4, hit8)
}

/// [`intersect_node`] testing all eight children at once with AVX2.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn intersect_node_avx2(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: forwarded from the caller.
    let hit = unsafe { child_hits_avx2_lanes(node, r, tmax) };
    // `hitmask_from_children` without its data-dependent loop (one iteration per hit child, a
    // branch that mispredicts often): each lane shifts its child's bits to their index, lanes of
    // missed children are masked off, and the eight lanes are OR-ed together.
    // The child bits and their indices are `get_child_and_index_bits` lane by lane (there on the
    // eight bytes of a `u64`): a child is internal when bits 3 and 4 of its meta byte are both
    // set; its index is then its slot (low 5 bits) XOR the ray's octant, a leaf's is its first
    // primitive's offset; the bits are the meta byte's top three.
    // SAFETY: AVX2 is guaranteed by the caller; the load reads exactly the 8 bytes of
    // `child_meta`, the rest are register-only operations.
    unsafe {
        let meta =
            _mm256_cvtepu8_epi32(_mm_loadl_epi64(node.child_meta.as_ptr() as *const __m128i));
        let inner_bits = _mm256_set1_epi32(0x18);
        let inner = _mm256_cmpeq_epi32(_mm256_and_si256(meta, inner_bits), inner_bits);
        let oct = _mm256_set1_epi32((r.oct_inv4 & 0xff) as i32);
        let index = _mm256_and_si256(
            _mm256_xor_si256(meta, _mm256_and_si256(oct, inner)),
            _mm256_set1_epi32(0x1f),
        );
        let bits = _mm256_srli_epi32::<5>(meta);
        let m = _mm256_and_si256(_mm256_sllv_epi32(bits, index), _mm256_castps_si256(hit));
        let x = _mm_or_si128(_mm256_castsi256_si128(m), _mm256_extracti128_si256::<1>(m));
        let x = _mm_or_si128(x, _mm_shuffle_epi32::<0b01_00_11_10>(x));
        let x = _mm_or_si128(x, _mm_shuffle_epi32::<0b10_11_00_01>(x));
        _mm_cvtsi128_si32(x) as u32
    }
}

/// The SSE2 test below, eight lanes wide: the same operations in the same order (separate
/// multiply and add, never fused; `max`/`min`/ordered `<=` with the same NaN behaviour), so both
/// paths give identical masks.
#[cfg(all(test, target_arch = "x86_64"))]
#[inline(always)]
unsafe fn child_hits_avx2(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: forwarded from the caller.
    unsafe { _mm256_movemask_ps(child_hits_avx2_lanes(node, r, tmax)) as u32 }
}

/// [`child_hits_avx2`] as a lane mask (all ones for a hit child).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn child_hits_avx2_lanes(
    node: &WideNode,
    r: &BoxRay,
    tmax: f32,
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is guaranteed by the caller; each load reads exactly one `[f32; 8]` field,
    // 32-byte aligned (`WideNode` is `align(32)` and every plane array sits at a multiple of 32).
    unsafe {
        macro_rules! t {
            ($p:expr, $s:expr, $o:expr) => {
                _mm256_add_ps(
                    _mm256_mul_ps(_mm256_load_ps($p.as_ptr()), _mm256_set1_ps($s)),
                    _mm256_set1_ps($o),
                )
            };
        }
        let (nx, fx) = node.near_far(r, 0);
        let (ny, fy) = node.near_far(r, 1);
        let (nz, fz) = node.near_far(r, 2);
        let enter = _mm256_max_ps(
            _mm256_max_ps(_mm256_set1_ps(r.tmin), t!(nx, r.inv.x, r.off_lo.x)),
            _mm256_max_ps(t!(ny, r.inv.y, r.off_lo.y), t!(nz, r.inv.z, r.off_lo.z)),
        );
        let exit = _mm256_min_ps(
            _mm256_min_ps(_mm256_set1_ps(tmax), t!(fx, r.inv.x, r.off_hi.x)),
            _mm256_min_ps(t!(fy, r.inv.y, r.off_hi.y), t!(fz, r.inv.z, r.off_hi.z)),
        );
        _mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)
    }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn child_hits(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86_64 baseline; each load reads 4 floats of an `[f32; 8]`
    // field at offset 0 or 4, 16-byte aligned (`WideNode` is `align(32)`, fields at multiples of
    // 32 bytes).
    unsafe {
        macro_rules! t {
            ($p:expr, $k:expr, $s:expr, $o:expr) => {
                _mm_add_ps(_mm_mul_ps(_mm_load_ps($p.as_ptr().add($k)), $s), $o)
            };
        }
        let (nx, fx) = node.near_far(r, 0);
        let (ny, fy) = node.near_far(r, 1);
        let (nz, fz) = node.near_far(r, 2);
        let sx = _mm_set1_ps(r.inv.x);
        let sy = _mm_set1_ps(r.inv.y);
        let sz = _mm_set1_ps(r.inv.z);
        let lx = _mm_set1_ps(r.off_lo.x);
        let ly = _mm_set1_ps(r.off_lo.y);
        let lz = _mm_set1_ps(r.off_lo.z);
        let hx = _mm_set1_ps(r.off_hi.x);
        let hy = _mm_set1_ps(r.off_hi.y);
        let hz = _mm_set1_ps(r.off_hi.z);
        let t0 = _mm_set1_ps(r.tmin);
        let t1 = _mm_set1_ps(tmax);
        let mut m = 0u32;
        for k in [0usize, 4] {
            // A NaN ray may enter boxes here (SSE max/min pass NaN through unevenly); it then
            // misses every triangle, so only time is lost on input that is invalid anyway.
            let enter = _mm_max_ps(
                _mm_max_ps(t0, t!(nx, k, sx, lx)),
                _mm_max_ps(t!(ny, k, sy, ly), t!(nz, k, sz, lz)),
            );
            let exit = _mm_min_ps(
                _mm_min_ps(t1, t!(fx, k, sx, hx)),
                _mm_min_ps(t!(fy, k, sy, hy), t!(fz, k, sz, hz)),
            );
            m |= (_mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32) << k;
        }
        m
    }
}

#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn child_hits(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    child_hits_scalar(node, r, tmax)
}

/// The same test one child and axis at a time (the non-x86 path, and the reference of the unit
/// tests).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn child_hits_scalar(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    let mut hit8 = 0;
    let inv = r.inv.to_array();
    let off_lo = r.off_lo.to_array();
    let off_hi = r.off_hi.to_array();
    for c in 0..8 {
        let mut enter = r.tmin;
        let mut exit = tmax;
        for a in 0..3 {
            let (n, f) = node.near_far(r, a);
            enter = enter.max(n[c] * inv[a] + off_lo[a]);
            exit = exit.min(f[c] * inv[a] + off_hi[a]);
        }
        if enter <= exit {
            hit8 |= 1 << c;
        }
    }
    hit8
}

#[cfg(test)]
pub(crate) fn child_hits_reference(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    child_hits_scalar(node, r, tmax)
}

#[cfg(test)]
pub(crate) fn child_hits_fast(node: &WideNode, r: &BoxRay, tmax: f32) -> u32 {
    child_hits(node, r, tmax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::{aabb::Aabb, cwbvh::builder::build_cwbvh, BvhBuildParams};
    use std::time::Duration;

    fn lcg(s: &mut u64) -> f32 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*s >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn simd_matches_scalar_reference() {
        let mut s = 7u64;
        let boxes: Vec<Aabb> = (0..500)
            .map(|_| {
                let c = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 100.0;
                let h = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 3.0;
                Aabb::new(c - h, c + h)
            })
            .collect();
        let bvh = build_cwbvh(
            &boxes,
            BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        let bounds = (Vec3::splat(-10.0), Vec3::splat(110.0));
        let nodes: Vec<WideNode> = bvh
            .nodes
            .iter()
            .map(|n| WideNode::from_cwbvh(n, centre(bounds)))
            .collect();
        let mut nonzero = 0;
        for i in 0..2000 {
            let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 120.0 - 10.0;
            let mut d = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) - 0.5;
            if i % 5 == 0 {
                d.y = 0.0; // exercises the clamped reciprocal
            }
            let r = BoxRay::new(
                o,
                d,
                if i % 3 == 0 { 5.0 } else { 0.0 },
                (Vec3::splat(-10.0), Vec3::splat(110.0)),
            );
            let tmax = if i % 4 == 0 { 50.0 } else { f32::INFINITY };
            for node in &nodes {
                let a = child_hits_fast(node, &r, tmax);
                assert_eq!(a, child_hits_reference(node, &r, tmax));
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: AVX2 was detected.
                    assert_eq!(a, unsafe { child_hits_avx2(node, &r, tmax) });
                    // SAFETY: AVX2 was detected.
                    let full = unsafe { intersect_node_avx2(node, &r, tmax) };
                    assert_eq!(full, intersect_node(node, &r, tmax));
                }
                nonzero += (a != 0) as usize;
            }
        }
        assert!(nonzero > 100);
    }

    #[test]
    fn decompressed_boxes_contain_the_quantised_ones() {
        let mut s = 11u64;
        let boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 1e4 + 3e4;
                let h = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 0.01;
                Aabb::new(c - h, c + h)
            })
            .collect();
        let bvh = build_cwbvh(
            &boxes,
            BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        let c = Vec3::new(3.5e4, 3.3e4, 3.1e4);
        for n in &bvh.nodes {
            let w = WideNode::from_cwbvh(n, c);
            let q = [
                (&n.child_min_x, &n.child_max_x),
                (&n.child_min_y, &n.child_max_y),
                (&n.child_min_z, &n.child_max_z),
            ];
            for (a, (qlo, qhi)) in q.iter().enumerate() {
                let e = f32::from_bits((n.e[a] as u32) << 23) as f64;
                for k in 0..8 {
                    let lo = n.p[a] as f64 + qlo[k] as f64 * e;
                    let hi = n.p[a] as f64 + qhi[k] as f64 * e;
                    assert!(w.planes[a][k] as f64 + c[a] as f64 <= lo);
                    assert!(w.planes[3 + a][k] as f64 + c[a] as f64 >= hi);
                }
            }
        }
    }

    #[test]
    fn honours_tmin() {
        // obvhs' own test ignores tmin; this one must reject boxes entirely before it.
        let boxes = vec![
            Aabb::new(Vec3A::new(0.0, -1.0, -1.0), Vec3A::new(1.0, 1.0, 1.0)),
            Aabb::new(Vec3A::new(10.0, -1.0, -1.0), Vec3A::new(11.0, 1.0, 1.0)),
        ];
        let bvh = build_cwbvh(
            &boxes,
            BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        let root = &WideNode::from_cwbvh(
            &bvh.nodes[0],
            centre((Vec3::splat(-1.0), Vec3::splat(11.0))),
        );
        let all = child_hits_fast(
            root,
            &BoxRay::new(
                Vec3::new(-5.0, 0.0, 0.0),
                Vec3::X,
                0.0,
                (Vec3::splat(-1.0), Vec3::splat(11.0)),
            ),
            f32::INFINITY,
        );
        let late = child_hits_fast(
            root,
            &BoxRay::new(
                Vec3::new(-5.0, 0.0, 0.0),
                Vec3::X,
                8.0,
                (Vec3::splat(-1.0), Vec3::splat(11.0)),
            ),
            f32::INFINITY,
        );
        let early = child_hits_fast(
            root,
            &BoxRay::new(
                Vec3::new(-5.0, 0.0, 0.0),
                Vec3::X,
                0.0,
                (Vec3::splat(-1.0), Vec3::splat(11.0)),
            ),
            8.0,
        );
        assert_eq!(all.count_ones(), 2);
        assert_eq!(late.count_ones(), 1);
        assert_eq!(early.count_ones(), 1);
        assert_ne!(late, early);
    }
}
