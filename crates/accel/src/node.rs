//! Conservative ray test against the eight quantised child boxes of an obvhs `CwBvhNode`.
//!
//! obvhs' own test clamps the entry distance to a fixed `1e-4` instead of `ray.tmin` and does not
//! account for rounding, so hits are lost at small scales. This one honours `[tmin, tmax]` and
//! widens every slab by a bound on all rounding errors involved:
//! - obvhs quantises child boxes as `floor((child.min - p) / e)`, where the subtraction is rounded:
//!   the stored box can be short of the true one by one rounding of a value below `255 e`;
//! - the slab distances are evaluated as `q * (e / d) + (p - o) / d` (about four roundings);
//! - the triangle test itself accepts hits up to a few ulps of `|v - o|` outside the triangle,
//!   in any axis (the shear mixes them), so the box must accept at least as much.
//!
//! All of these are below `K ε M` in space, where `M` bounds the largest coordinate of `|p - o|`
//! plus the node's extent. `M` is taken once per ray and tree as the largest coordinate of
//! `|corner - o|` over the tree's bounds plus three times its extent (so the slack costs nothing
//! per node and stays tight when the scene sits far from the world origin), and each slab
//! is widened by `K ε M / |d_axis|` in `t` (Ize 2013 scales `tmax` by `1 + 2γ` for the same
//! purpose; an absolute bound also covers rays that start inside a box).

use glam::{Vec3, Vec3A};
use obvhs::cwbvh::node::CwBvhNode;

/// Relative spatial slack of the box test (see the module docs); 64 ulps at unit scale, which
/// costs nothing measurable in traversal.
pub(crate) const SLACK: f32 = 64.0 * f32::EPSILON;

/// Largest magnitude of a reciprocal direction component: zero components become this (keeping
/// their sign), so slab products stay finite and `0 * inf` never makes a NaN.
pub(crate) const INV_LIMIT: f32 = 1e20;

/// obvhs' child-ordering key for a direction whose negative axes are the bits of `neg_bits`
/// (x, y, z from bit 0): 4 in each byte for +x, 2 for +y, 1 for +z.
#[inline(always)]
pub(crate) fn oct_inv4(neg_bits: u32) -> u32 {
    const OCT: [u32; 8] = {
        let mut t = [0u32; 8];
        let mut b = 0;
        while b < 8 {
            let key = (if b & 1 == 0 { 4 } else { 0 })
                | (if b & 2 == 0 { 2 } else { 0 })
                | (if b & 4 == 0 { 1 } else { 0 });
            t[b] = key * 0x0101_0101;
            b += 1;
        }
        t
    };
    OCT[neg_bits as usize & 7]
}

/// A ray prepared for box tests.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BoxRay {
    pub origin: Vec3A,
    pub inv: Vec3A,
    /// Per axis, whether the direction is negative (the far plane is the box minimum).
    pub neg: [bool; 3],
    /// obvhs' child-ordering key for this direction.
    pub oct_inv4: u32,
    pub tmin: f32,
    /// Per-axis widening of every slab, in `t` (see the module docs).
    pub slack: Vec3A,
}

impl BoxRay {
    /// `bounds`: the tree's bounding box (sizes the rounding slack).
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, (lo, hi): (Vec3, Vec3)) -> Self {
        // Lane-wise (one division, selects instead of a branch per axis): a finite reciprocal is
        // clamped to `INV_LIMIT`, an infinite or NaN one becomes `INV_LIMIT` with the sign of `d`.
        let d = Vec3A::from(dir);
        let i = Vec3A::ONE / d;
        let limit = Vec3A::splat(INV_LIMIT);
        let inv = Vec3A::select(
            i.abs().cmplt(Vec3A::INFINITY),
            i.clamp(-limit, limit),
            limit.copysign(d),
        );
        let neg_bits = inv.cmplt(Vec3A::ZERO).bitmask();
        let neg = [neg_bits & 1 != 0, neg_bits & 2 != 0, neg_bits & 4 != 0];
        let oct_inv4 = oct_inv4(neg_bits);
        // In lanes (`Vec3` arithmetic is scalar here: 20 instructions a ray); the same values
        // for finite inputs.
        let (o, lo, hi) = (Vec3A::from(origin), Vec3A::from(lo), Vec3A::from(hi));
        let m = (lo - o).abs().max((hi - o).abs()).max_element() + 3.0 * (hi - lo).max_element();
        Self {
            origin: o,
            inv,
            neg,
            oct_inv4,
            tmin,
            slack: inv.abs() * (SLACK * m),
        }
    }

    /// The reciprocal exactly as the per-axis scalar code computed it before (the reference of
    /// the lane-wise version in [`BoxRay::new`]).
    #[cfg(test)]
    fn inv_reference(dir: Vec3) -> Vec3A {
        Vec3A::from_array(dir.to_array().map(|d| {
            let i = 1.0 / d;
            if i.is_finite() {
                i.clamp(-INV_LIMIT, INV_LIMIT)
            } else if d.is_sign_negative() {
                -INV_LIMIT
            } else {
                INV_LIMIT
            }
        }))
    }
}

/// Per-node constants of the slab test: `t = q * scale + offset_{lo,hi}` per axis.
#[derive(Clone, Copy)]
struct NodeFrame {
    scale: Vec3A,
    off_lo: Vec3A,
    off_hi: Vec3A,
}

#[inline(always)]
fn frame(node: &CwBvhNode, r: &BoxRay) -> NodeFrame {
    let e = Vec3A::new(
        f32::from_bits((node.e[0] as u32) << 23),
        f32::from_bits((node.e[1] as u32) << 23),
        f32::from_bits((node.e[2] as u32) << 23),
    );
    let off = (Vec3A::from(node.p) - r.origin) * r.inv;
    NodeFrame {
        scale: e * r.inv,
        off_lo: off - r.slack,
        off_hi: off + r.slack,
    }
}

/// obvhs' encoding of a child hit into the node hit mask: internal children set a bit in the top
/// byte (at their traversal priority), leaves set their primitives' bits in the low 24 bits.
#[inline(always)]
fn hitmask_from_children(node: &CwBvhNode, oct_inv4: u32, mut hit8: u32) -> u32 {
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
pub(crate) fn intersect_node(node: &CwBvhNode, r: &BoxRay, tmax: f32) -> u32 {
    let f = frame(node, r);
    let hit8 = child_hits(node, r, &f, tmax).0;
    hitmask_from_children(node, r.oct_inv4, hit8)
}

/// [`intersect_node`] testing all eight children at once with AVX2 and FMA. Inlined into the
/// traversal of the AVX2 query functions, which enable the same features.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(crate) unsafe fn intersect_node_avx2(node: &CwBvhNode, r: &BoxRay, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 and FMA are guaranteed by the caller.
    let hit = unsafe { node_test_avx2(node, r, tmax).0 };
    // `hitmask_from_children` without its data-dependent loop (one iteration per hit child, a
    // branch that mispredicts often): each lane shifts its child's bits to their index, lanes of
    // missed children are masked off, and the eight lanes are OR-ed together.
    // The child bits and their indices are `CwBvhNode::get_child_and_index_bits` lane by lane
    // (there on the eight bytes of a `u64`): a child is internal when bits 3 and 4 of its meta
    // byte are both set; its index is then its slot (low 5 bits) XOR the ray's octant, a leaf's is
    // its first primitive's offset; the bits are the meta byte's top three.
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
        or_lanes(m)
    }
}

/// The eight children's box test with AVX2 and FMA: the hit lanes (all ones for a hit child)
/// and each child's entry distance. Shared by [`intersect_node_avx2`] and
/// [`child_hits_enter_avx2`].
///
/// # Safety
/// The CPU must support AVX2 and FMA, and the caller must be compiled for them (inlined).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn node_test_avx2(
    node: &CwBvhNode,
    r: &BoxRay,
    tmax: f32,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    use std::arch::x86_64::*;
    // `frame` in registers: its three vectors come from one 16-byte load of `p`, `e` and
    // `imask` with the same operations as `frame` (so the same values), then each lane is
    // broadcast. (LLVM lowers the `vpermps` broadcasts back to shuffle + broadcast pairs; the
    // instructions saved are in the loads and the exponent decode.)
    // SAFETY: AVX2 is guaranteed by the caller. The loads read 16 bytes from the start of the
    // node (`p`, then `e` and `imask`) and the 4 bytes of `e` and `imask` (`repr(C)` layout);
    // lane 3 of every vector is never broadcast.
    unsafe {
        let base = node as *const CwBvhNode as *const u8;
        let p = _mm_loadu_ps(base as *const f32);
        let e_bits = _mm_cvtsi32_si128(std::ptr::read_unaligned(
            base.add(std::mem::offset_of!(CwBvhNode, e)) as *const i32,
        ));
        let e = _mm_castsi128_ps(_mm_slli_epi32::<23>(_mm_cvtepu8_epi32(e_bits)));
        let inv: __m128 = r.inv.into();
        let slack: __m128 = r.slack.into();
        let scale = _mm_mul_ps(e, inv);
        let off = _mm_mul_ps(_mm_sub_ps(p, r.origin.into()), inv);
        let off_lo = _mm_sub_ps(off, slack);
        let off_hi = _mm_add_ps(off, slack);
        macro_rules! lanes {
            ($v:expr) => {{
                let v = _mm256_castps128_ps256($v);
                [
                    _mm256_permutevar8x32_ps(v, _mm256_set1_epi32(0)),
                    _mm256_permutevar8x32_ps(v, _mm256_set1_epi32(1)),
                    _mm256_permutevar8x32_ps(v, _mm256_set1_epi32(2)),
                ]
            }};
        }
        child_hits_avx2_wide(node, r, lanes!(scale), lanes!(off_lo), lanes!(off_hi), tmax)
    }
}

/// The children of a node that a ray may enter, and where: what the distance-ordered walk
/// (`walk.rs`) needs of a node, without obvhs' hit-mask encoding.
#[derive(Clone, Copy)]
pub(crate) struct ChildHits {
    /// Bit `c` for each child slot `c` whose box the ray may enter within `[tmin, tmax]` (empty
    /// slots may be set too: their meta byte is zero).
    pub hits: u32,
    /// Each slot's entry distance (`max(tmin, near planes)`, lowered by the slack like the whole
    /// test, so never above the `t` of a hit the triangle test accepts in that child).
    pub enter: [f32; 8],
    /// The primitives of the hit leaves, as bits above `primitive_base_idx` (obvhs' hit mask
    /// below bit 24).
    pub prims: u32,
}

/// [`ChildHits`] of `node` for `[r.tmin, tmax]` (SSE2, or scalar off x86_64).
#[inline(always)]
pub(crate) fn child_hits_enter(node: &CwBvhNode, r: &BoxRay, tmax: f32) -> ChildHits {
    let f = frame(node, r);
    let (hits, enter) = child_hits(node, r, &f, tmax);
    // A leaf's meta byte holds its first primitive's offset (low 5 bits) and its count in unary
    // (top 3 bits); empty slots' is zero.
    let mut leaves = hits & !u32::from(node.imask);
    let mut prims = 0;
    while leaves != 0 {
        let meta = node.child_meta[leaves.trailing_zeros() as usize & 7];
        leaves &= leaves - 1;
        prims |= u32::from(meta >> 5) << (meta & 0x1f);
    }
    ChildHits { hits, enter, prims }
}

/// [`child_hits_enter`] with AVX2 and FMA (the same arithmetic as [`intersect_node_avx2`]).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(crate) unsafe fn child_hits_enter_avx2(node: &CwBvhNode, r: &BoxRay, tmax: f32) -> ChildHits {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 and FMA are guaranteed by the caller; the load reads exactly the 8 bytes of
    // `child_meta`, the store writes the 8 floats of `enter`.
    unsafe {
        let (hit, e) = node_test_avx2(node, r, tmax);
        let mut enter = [0.0; 8];
        _mm256_storeu_ps(enter.as_mut_ptr(), e);
        // `child_hits_enter`'s loop over the hit leaves, lane-wise: each shifts its count bits
        // to its offset; internal children (offset 24 + slot) set no bit below 24.
        let meta =
            _mm256_cvtepu8_epi32(_mm_loadl_epi64(node.child_meta.as_ptr() as *const __m128i));
        let offset = _mm256_and_si256(meta, _mm256_set1_epi32(0x1f));
        let bits = _mm256_srli_epi32::<5>(meta);
        let m = _mm256_and_si256(_mm256_sllv_epi32(bits, offset), _mm256_castps_si256(hit));
        ChildHits {
            hits: _mm256_movemask_ps(hit) as u32,
            enter,
            prims: or_lanes(m) & 0x00ff_ffff,
        }
    }
}

/// The OR of the eight 32-bit lanes of `m`.
///
/// # Safety
/// The CPU must support AVX2, and the caller must be compiled for it (inlined).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn or_lanes(m: std::arch::x86_64::__m256i) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: register-only AVX2 operations, guaranteed by the caller.
    unsafe {
        let x = _mm_or_si128(_mm256_castsi256_si128(m), _mm256_extracti128_si256::<1>(m));
        let x = _mm_or_si128(x, _mm_shuffle_epi32::<0b01_00_11_10>(x));
        let x = _mm_or_si128(x, _mm_shuffle_epi32::<0b10_11_00_01>(x));
        _mm_cvtsi128_si32(x) as u32
    }
}

/// The SSE2 test below, eight lanes wide, with each slab distance `q * scale + offset` fused
/// (one rounding instead of two, one instruction instead of two: 6 fewer per node). The
/// distances can then differ from the SSE2 path's in the last bit, so both are checked against a
/// scalar reference of their own arithmetic; the slack (module docs) bounds the error of either.
/// `max`/`min`/ordered `<=` behave the same on NaN in both.
#[cfg(all(test, target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
unsafe fn child_hits_avx2(node: &CwBvhNode, r: &BoxRay, f: &NodeFrame, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: forwarded from the caller.
    unsafe { _mm256_movemask_ps(child_hits_avx2_lanes(node, r, f, tmax)) as u32 }
}

/// [`child_hits_avx2`] as a lane mask (all ones for a hit child).
#[cfg(all(test, target_arch = "x86_64"))]
#[inline(always)]
unsafe fn child_hits_avx2_lanes(
    node: &CwBvhNode,
    r: &BoxRay,
    f: &NodeFrame,
    tmax: f32,
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    // SAFETY: forwarded from the caller.
    unsafe {
        let b = |v: Vec3A| {
            [
                _mm256_set1_ps(v.x),
                _mm256_set1_ps(v.y),
                _mm256_set1_ps(v.z),
            ]
        };
        child_hits_avx2_wide(node, r, b(f.scale), b(f.off_lo), b(f.off_hi), tmax).0
    }
}

/// [`child_hits_avx2_lanes`] with the frame's lanes already broadcast (`[x, y, z]` each), and
/// each child's entry distance.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn child_hits_avx2_wide(
    node: &CwBvhNode,
    r: &BoxRay,
    scale: [std::arch::x86_64::__m256; 3],
    off_lo: [std::arch::x86_64::__m256; 3],
    off_hi: [std::arch::x86_64::__m256; 3],
    tmax: f32,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is guaranteed by the caller; each load reads exactly one `[u8; 8]` field.
    unsafe {
        #[inline(always)]
        unsafe fn load8(b: &[u8; 8]) -> __m256 {
            // SAFETY: as above.
            unsafe {
                _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(
                    b.as_ptr() as *const __m128i
                )))
            }
        }
        // Macros, not closures: closures do not inherit the caller's target features, and an
        // AVX2 intrinsic that is not inlined costs a call per instruction.
        macro_rules! pick {
            ($neg:expr, $lo:expr, $hi:expr) => {
                if $neg {
                    (load8($hi), load8($lo))
                } else {
                    (load8($lo), load8($hi))
                }
            };
        }
        let (nx, fx) = pick!(r.neg[0], &node.child_min_x, &node.child_max_x);
        let (ny, fy) = pick!(r.neg[1], &node.child_min_y, &node.child_max_y);
        let (nz, fz) = pick!(r.neg[2], &node.child_min_z, &node.child_max_z);
        let enter = _mm256_max_ps(
            _mm256_max_ps(
                _mm256_set1_ps(r.tmin),
                _mm256_fmadd_ps(nx, scale[0], off_lo[0]),
            ),
            _mm256_max_ps(
                _mm256_fmadd_ps(ny, scale[1], off_lo[1]),
                _mm256_fmadd_ps(nz, scale[2], off_lo[2]),
            ),
        );
        let exit = _mm256_min_ps(
            _mm256_min_ps(
                _mm256_set1_ps(tmax),
                _mm256_fmadd_ps(fx, scale[0], off_hi[0]),
            ),
            _mm256_min_ps(
                _mm256_fmadd_ps(fy, scale[1], off_hi[1]),
                _mm256_fmadd_ps(fz, scale[2], off_hi[2]),
            ),
        );
        (_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit), enter)
    }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn child_hits(node: &CwBvhNode, r: &BoxRay, f: &NodeFrame, tmax: f32) -> (u32, [f32; 8]) {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86_64 baseline; the loads read exactly 8 bytes of `[u8; 8]`
    // fields, the stores write 4 + 4 floats into `enter`.
    unsafe {
        #[inline(always)]
        unsafe fn load8(b: &[u8; 8]) -> (__m128, __m128) {
            // SAFETY: `b` is 8 readable bytes; SSE2 is baseline.
            unsafe {
                let z = _mm_setzero_si128();
                let v = _mm_loadl_epi64(b.as_ptr() as *const __m128i);
                let v16 = _mm_unpacklo_epi8(v, z);
                (
                    _mm_cvtepi32_ps(_mm_unpacklo_epi16(v16, z)),
                    _mm_cvtepi32_ps(_mm_unpackhi_epi16(v16, z)),
                )
            }
        }
        let (near_x, far_x) = if r.neg[0] {
            (&node.child_max_x, &node.child_min_x)
        } else {
            (&node.child_min_x, &node.child_max_x)
        };
        let (near_y, far_y) = if r.neg[1] {
            (&node.child_max_y, &node.child_min_y)
        } else {
            (&node.child_min_y, &node.child_max_y)
        };
        let (near_z, far_z) = if r.neg[2] {
            (&node.child_max_z, &node.child_min_z)
        } else {
            (&node.child_min_z, &node.child_max_z)
        };
        let sx = _mm_set1_ps(f.scale.x);
        let sy = _mm_set1_ps(f.scale.y);
        let sz = _mm_set1_ps(f.scale.z);
        let lx = _mm_set1_ps(f.off_lo.x);
        let ly = _mm_set1_ps(f.off_lo.y);
        let lz = _mm_set1_ps(f.off_lo.z);
        let hx = _mm_set1_ps(f.off_hi.x);
        let hy = _mm_set1_ps(f.off_hi.y);
        let hz = _mm_set1_ps(f.off_hi.z);
        let (nx0, nx1) = load8(near_x);
        let (fx0, fx1) = load8(far_x);
        let (ny0, ny1) = load8(near_y);
        let (fy0, fy1) = load8(far_y);
        let (nz0, nz1) = load8(near_z);
        let (fz0, fz1) = load8(far_z);
        let t0 = _mm_set1_ps(r.tmin);
        let t1 = _mm_set1_ps(tmax);
        // A NaN ray may enter boxes here (SSE max/min pass NaN through unevenly); it then misses
        // every triangle, so only time is lost on input that is invalid anyway.
        let enter0 = _mm_max_ps(
            _mm_max_ps(t0, _mm_add_ps(_mm_mul_ps(nx0, sx), lx)),
            _mm_max_ps(
                _mm_add_ps(_mm_mul_ps(ny0, sy), ly),
                _mm_add_ps(_mm_mul_ps(nz0, sz), lz),
            ),
        );
        let exit0 = _mm_min_ps(
            _mm_min_ps(t1, _mm_add_ps(_mm_mul_ps(fx0, sx), hx)),
            _mm_min_ps(
                _mm_add_ps(_mm_mul_ps(fy0, sy), hy),
                _mm_add_ps(_mm_mul_ps(fz0, sz), hz),
            ),
        );
        let enter1 = _mm_max_ps(
            _mm_max_ps(t0, _mm_add_ps(_mm_mul_ps(nx1, sx), lx)),
            _mm_max_ps(
                _mm_add_ps(_mm_mul_ps(ny1, sy), ly),
                _mm_add_ps(_mm_mul_ps(nz1, sz), lz),
            ),
        );
        let exit1 = _mm_min_ps(
            _mm_min_ps(t1, _mm_add_ps(_mm_mul_ps(fx1, sx), hx)),
            _mm_min_ps(
                _mm_add_ps(_mm_mul_ps(fy1, sy), hy),
                _mm_add_ps(_mm_mul_ps(fz1, sz), hz),
            ),
        );
        let m0 = _mm_movemask_ps(_mm_cmple_ps(enter0, exit0)) as u32;
        let m1 = _mm_movemask_ps(_mm_cmple_ps(enter1, exit1)) as u32;
        let mut enter = [0.0; 8];
        _mm_storeu_ps(enter.as_mut_ptr(), enter0);
        _mm_storeu_ps(enter.as_mut_ptr().add(4), enter1);
        (m0 | (m1 << 4), enter)
    }
}

/// The box test one child at a time: the whole test on targets without the SIMD paths, and
/// the reference those paths are checked against.
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
fn child_hits_scalar(node: &CwBvhNode, r: &BoxRay, f: &NodeFrame, tmax: f32) -> (u32, [f32; 8]) {
    child_hits_scalar_with::<false>(node, r, f, tmax)
}

/// [`child_hits_scalar`], with the slab distances fused (`mul_add`) when `FMA`: the reference of
/// the AVX2 path.
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
fn child_hits_scalar_with<const FMA: bool>(
    node: &CwBvhNode,
    r: &BoxRay,
    f: &NodeFrame,
    tmax: f32,
) -> (u32, [f32; 8]) {
    let mut hit8 = 0;
    let mut enters = [0.0; 8];
    let lo = [&node.child_min_x, &node.child_min_y, &node.child_min_z];
    let hi = [&node.child_max_x, &node.child_max_y, &node.child_max_z];
    let scale = f.scale.to_array();
    let off_lo = f.off_lo.to_array();
    let off_hi = f.off_hi.to_array();
    for c in 0..8 {
        let mut enter = r.tmin;
        let mut exit = tmax;
        for a in 0..3 {
            let (n, fa) = if r.neg[a] {
                (hi[a][c], lo[a][c])
            } else {
                (lo[a][c], hi[a][c])
            };
            let (tn, tf) = if FMA {
                (
                    (n as f32).mul_add(scale[a], off_lo[a]),
                    (fa as f32).mul_add(scale[a], off_hi[a]),
                )
            } else {
                (
                    n as f32 * scale[a] + off_lo[a],
                    fa as f32 * scale[a] + off_hi[a],
                )
            };
            enter = enter.max(tn);
            exit = exit.min(tf);
        }
        if enter <= exit {
            hit8 |= 1 << c;
        }
        enters[c] = enter;
    }
    (hit8, enters)
}

#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn child_hits(node: &CwBvhNode, r: &BoxRay, f: &NodeFrame, tmax: f32) -> (u32, [f32; 8]) {
    child_hits_scalar(node, r, f, tmax)
}

/// Scalar reference of the same test, for unit tests.
#[cfg(test)]
pub(crate) fn child_hits_reference(node: &CwBvhNode, r: &BoxRay, tmax: f32) -> u32 {
    let f = frame(node, r);
    child_hits_scalar(node, r, &f, tmax).0
}

#[cfg(test)]
pub(crate) fn child_hits_fast(node: &CwBvhNode, r: &BoxRay, tmax: f32) -> u32 {
    let f = frame(node, r);
    child_hits(node, r, &f, tmax).0
}

#[cfg(test)]
mod tests;
