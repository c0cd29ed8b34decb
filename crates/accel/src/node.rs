//! Our 8-wide node ([`Node`]: obvhs' CWBVH topology with each child's box in floats, built by
//! [`layout`]) and the conservative ray test against its eight child boxes.
//!
//! The boxes are exact: a leaf's is the union of its primitives' boxes (a triangle's own `f32`
//! coordinates; an instance's world bounds), an internal child's the union of its children's.
//! (obvhs quantises them to 8 bits relative to the parent, which both widens them and costs a
//! decode per node test.)
//! The test honours `[tmin, tmax]` and widens every slab by a bound on all rounding errors
//! involved:
//! - a slab distance is `(o - b) * -inv`: one rounding in the subtraction, one in the product;
//! - the triangle test itself accepts hits up to a few ulps of `|v - o|` outside the triangle,
//!   in any axis (the shear mixes them), so the box must accept at least as much.
//!
//! All of these are below `K ε M` in space, where `M` bounds the largest coordinate of `|b - o|`.
//! `M` is taken once per ray and tree as the largest coordinate of `|corner - o|` over the tree's
//! bounds (so the slack costs nothing per node and stays tight when the scene sits far from the
//! world origin). The slack is applied by moving the ray's origin: towards each near plane and
//! away from each far plane by `K ε M` plus two ulps of the origin's coordinate (so that the move
//! survives rounding), once per ray ([`BoxRay::new`]). Ize (2013) scales `tmax` by `1 + 2γ` for
//! the same purpose; an absolute bound also covers rays that start inside a box.
//!
//! `K` is 16: the slab distances' rounding is below `2 ε M`, and the triangle test was measured
//! to accept rays at most `0.6 ε M` outside a triangle's box (a million rays aimed just past
//! edges and vertices; `slack_covers_what_the_triangle_test_accepts` keeps that below `K / 4`).
//! A looser slack is not free: a ray leaving a flat leaf (a floor, a wall: a box of zero
//! thickness) enters that leaf again whenever the slack exceeds its origin's offset from the
//! surface, and tests its triangles for nothing. With `K = 64` and `M` padded by three times
//! the tree's extent (a margin kept from obvhs' quantised boxes), every bounce and shadow ray
//! from a floor did.
//!
//! Every path (AVX2, SSE2, NEON, scalar) computes the same operations in the same order: the same bits.

use glam::{Vec3, Vec3A};

pub(crate) mod layout;
#[cfg(target_arch = "aarch64")]
pub(crate) mod neon;

pub(crate) use layout::{child_index, Node};

/// Relative spatial slack of the box test (see the module docs): 16 ulps at unit scale.
pub(crate) const SLACK: f32 = 16.0 * f32::EPSILON;

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

/// The reciprocal of `dir` for slab tests, lane-wise (one division, selects instead of a branch
/// per axis): a finite reciprocal is clamped to `INV_LIMIT`, an infinite or NaN one becomes
/// `INV_LIMIT` with the sign of `dir`.
#[inline(always)]
pub(crate) fn clamped_inv(dir: Vec3) -> Vec3A {
    let d = Vec3A::from(dir);
    let i = Vec3A::ONE / d;
    let limit = Vec3A::splat(INV_LIMIT);
    Vec3A::select(
        i.abs().cmplt(Vec3A::INFINITY),
        i.clamp(-limit, limit),
        limit.copysign(d),
    )
}

/// The box test's slack in space, `K ε M`, for a ray from `o` in a tree of bounds `(lo, hi)`
/// (module docs).
#[inline(always)]
pub(crate) fn reach(o: Vec3A, (lo, hi): (Vec3, Vec3)) -> f32 {
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    let m = (lo - o).abs().max((hi - o).abs()).max_element();
    SLACK * m
}

/// The origins a ray's near and far planes are measured from: `o` moved by `reach` (the slack
/// `K ε M`) plus two ulps of `o`, towards the near planes and away from the far ones (`inv`'s
/// signs say which way). Lane-wise, so the packets' lanes compute the same bits.
#[inline(always)]
pub(crate) fn widened_origins(o: Vec3A, inv: Vec3A, reach: f32) -> (Vec3A, Vec3A) {
    let w = (o.abs() * (2.0 * f32::EPSILON) + Vec3A::splat(reach)).copysign(inv);
    (o + w, o - w)
}

/// A ray prepared for box tests.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BoxRay {
    /// The origin the near planes are measured from (module docs).
    pub o_near: Vec3A,
    /// The origin the far planes are measured from.
    pub o_far: Vec3A,
    /// The negated, clamped reciprocal direction: a slab distance is `(o - b) * ninv`.
    pub ninv: Vec3A,
    /// Where the near and far planes are in a node (the far plane is the box minimum on a
    /// negative axis).
    pub rows: Rows,
    /// obvhs' child-ordering key for this direction.
    pub oct_inv4: u32,
    pub tmin: f32,
}

impl BoxRay {
    /// `bounds`: the tree's bounding box (sizes the rounding slack).
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, bounds: (Vec3, Vec3)) -> Self {
        let inv = clamped_inv(dir);
        let neg_bits = inv.cmplt(Vec3A::ZERO).bitmask();
        let o = Vec3A::from(origin);
        let (o_near, o_far) = widened_origins(o, inv, reach(o, bounds));
        Self {
            o_near,
            o_far,
            ninv: -inv,
            rows: Rows::new(neg_bits),
            oct_inv4: oct_inv4(neg_bits),
            tmin,
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

/// Where a ray's six planes are in [`Node::bounds`]: the byte offsets of its near rows (x, y, z)
/// then its far rows (the minimum row on a positive axis is the near one). Private, so every
/// value is one of [`Rows::new`]'s: offsets of whole rows inside `bounds`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rows([u32; 6]);

impl Rows {
    /// The rows for the direction whose negative axes are the bits of `neg_bits` (x from bit 0).
    #[inline(always)]
    pub fn new(neg_bits: u32) -> Self {
        const ROW: u32 = 32;
        let r = |a: u32, far: bool| {
            let neg = (neg_bits >> a) & 1 == 1;
            (2 * a + u32::from(neg != far)) * ROW
        };
        Self([
            r(0, false),
            r(1, false),
            r(2, false),
            r(0, true),
            r(1, true),
            r(2, true),
        ])
    }

    /// The six rows of `node`'s children in the order a ray meets them: per axis, the near
    /// rows, then the far rows. Row lookups by offset, not by branch: a walk's rays differ in
    /// direction from step to step.
    #[inline(always)]
    pub fn planes<'n>(&self, node: &'n Node) -> [&'n [f32; 8]; 6] {
        let base = node.bounds.as_ptr() as *const u8;
        // SAFETY: each offset is `32 k` with `k < 6` (`Rows::new` is the only constructor), the
        // start of row `k` of `bounds` (`[[f32; 8]; 6]`, 32 bytes a row, 4-byte aligned), which
        // lives as long as `node`.
        self.0
            .map(|off| unsafe { &*(base.add(off as usize) as *const [f32; 8]) })
    }
}

/// obvhs' encoding of a child hit into the node hit mask: internal children set a bit in the top
/// byte (at their traversal priority), leaves set their primitives' bits in the low 24 bits.
#[inline(always)]
fn hitmask_from_children(node: &Node, oct_inv4: u32, mut hit8: u32) -> u32 {
    let (child_bits8, bit_index8) = node.child_and_index_bits(oct_inv4);
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
pub(crate) fn intersect_node(node: &Node, r: &BoxRay, tmax: f32) -> u32 {
    let hit8 = child_hits(node, r, tmax).0;
    hitmask_from_children(node, r.oct_inv4, hit8)
}

/// [`intersect_node`] testing all eight children at once with AVX2. Inlined into the traversal
/// of the AVX2 query functions, which enable the same features.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn intersect_node_avx2(node: &Node, r: &BoxRay, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is guaranteed by the caller.
    let hit = unsafe { node_test_avx2(node, r, tmax).0 };
    // `hitmask_from_children` without its data-dependent loop (one iteration per hit child, a
    // branch that mispredicts often): each lane shifts its child's bits to their index, lanes of
    // missed children are masked off, and the eight lanes are OR-ed together.
    // The child bits and their indices are obvhs' `get_child_and_index_bits` lane by lane (there on
    // the eight bytes of a `u64`): a child is internal when bits 3 and 4 of its meta byte are
    // both set; its index is then its slot (low 5 bits) XOR the ray's octant, a leaf's is its
    // first primitive's offset; the bits are the meta byte's top three.
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

/// The eight children's box test with AVX2: the hit lanes (all ones for a hit child) and each
/// child's entry distance. Shared by [`intersect_node_avx2`] and [`child_hits_enter_avx2`].
///
/// # Safety
/// The CPU must support AVX2, and the caller must be compiled for it (inlined).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn node_test_avx2(
    node: &Node,
    r: &BoxRay,
    tmax: f32,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    let (on, of, ni) = (r.o_near, r.o_far, r.ninv);
    // SAFETY: forwarded from the caller.
    unsafe {
        slabs_avx2(
            r.rows.planes(node),
            [on.x, on.y, on.z],
            [of.x, of.y, of.z],
            [ni.x, ni.y, ni.z],
            [r.tmin, tmax],
        )
    }
}

/// One ray against eight children's boxes (`rows`: the near rows x, y, z, then the far rows,
/// as [`Rows::planes`] gives them): `(o - b) * -inv` per slab from the widened origins `on`
/// (near planes) and `of` (far planes), clamped by `[tmin, tmax]`. The hit lanes (all ones for
/// a hit child) and each child's entry distance. The one-ray walks' node test, and the
/// packets' lane-by-lane one (so both give the same bits).
///
/// # Safety
/// The CPU must support AVX2, and the caller must be compiled for it (inlined).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
#[inline(always)]
pub(crate) unsafe fn slabs_avx2(
    rows: [&[f32; 8]; 6],
    on: [f32; 3],
    of: [f32; 3],
    ni: [f32; 3],
    [tmin, tmax]: [f32; 2],
) -> (crate::avx::__m256, crate::avx::__m256) {
    use crate::avx::*;
    // SAFETY: AVX2 is guaranteed by the caller; each load reads one `[f32; 8]` row in full.
    unsafe {
        let [nx, ny, nz, fx, fy, fz] = rows;
        // Macros, not closures: closures do not inherit the caller's target features.
        macro_rules! slab {
            ($o:expr, $row:expr, $ninv:expr) => {
                _mm256_mul_ps(
                    _mm256_sub_ps(_mm256_set1_ps($o), _mm256_loadu_ps($row.as_ptr())),
                    _mm256_set1_ps($ninv),
                )
            };
        }
        let enter = _mm256_max_ps(
            _mm256_max_ps(_mm256_set1_ps(tmin), slab!(on[0], nx, ni[0])),
            _mm256_max_ps(slab!(on[1], ny, ni[1]), slab!(on[2], nz, ni[2])),
        );
        let exit = _mm256_min_ps(
            _mm256_min_ps(_mm256_set1_ps(tmax), slab!(of[0], fx, ni[0])),
            _mm256_min_ps(slab!(of[1], fy, ni[1]), slab!(of[2], fz, ni[2])),
        );
        (_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit), enter)
    }
}

/// The children of a node that a ray may enter, and where: what the distance-ordered walk
/// (`walk.rs`) needs of a node, without obvhs' hit-mask encoding.
#[derive(Clone, Copy)]
pub(crate) struct ChildHits {
    /// Bit `c` for each child slot `c` whose box the ray may enter within `[tmin, tmax]`.
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
pub(crate) fn child_hits_enter(node: &Node, r: &BoxRay, tmax: f32) -> ChildHits {
    let (hits, enter) = child_hits(node, r, tmax);
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

/// [`child_hits_enter`] with AVX2 (the same arithmetic as [`intersect_node_avx2`]).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn child_hits_enter_avx2(node: &Node, r: &BoxRay, tmax: f32) -> ChildHits {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is guaranteed by the caller; the load reads exactly the 8 bytes of
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

/// The box test four children at a time with SSE2 (the x86_64 baseline): the hit slots and each
/// slot's entry distance.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn child_hits(node: &Node, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86_64 baseline; each load reads 4 floats of an `[f32; 8]`
    // row, the stores write 4 + 4 floats into `enter`.
    unsafe {
        let [nx, ny, nz, fx, fy, fz] = r.rows.planes(node);
        let (on, of, ni) = (r.o_near, r.o_far, r.ninv);
        let mut hits = 0;
        let mut enter = [0.0; 8];
        for half in 0..2 {
            let k = 4 * half;
            let slab = |o: f32, row: &[f32; 8], ninv: f32| {
                _mm_mul_ps(
                    _mm_sub_ps(_mm_set1_ps(o), _mm_loadu_ps(row.as_ptr().add(k))),
                    _mm_set1_ps(ninv),
                )
            };
            // A NaN ray may enter boxes here (SSE max/min pass NaN through unevenly); it then
            // misses every triangle, so only time is lost on input that is invalid anyway.
            let e = _mm_max_ps(
                _mm_max_ps(_mm_set1_ps(r.tmin), slab(on.x, nx, ni.x)),
                _mm_max_ps(slab(on.y, ny, ni.y), slab(on.z, nz, ni.z)),
            );
            let x = _mm_min_ps(
                _mm_min_ps(_mm_set1_ps(tmax), slab(of.x, fx, ni.x)),
                _mm_min_ps(slab(of.y, fy, ni.y), slab(of.z, fz, ni.z)),
            );
            hits |= (_mm_movemask_ps(_mm_cmple_ps(e, x)) as u32) << k;
            _mm_storeu_ps(enter.as_mut_ptr().add(k), e);
        }
        (hits, enter)
    }
}

/// The box test one child at a time: the whole test on targets without the SIMD paths, and
/// the reference those paths are checked against (the same operations in the same order).
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
fn child_hits_scalar(node: &Node, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
    let [nx, ny, nz, fx, fy, fz] = r.rows.planes(node);
    let (on, of, ni) = (r.o_near, r.o_far, r.ninv);
    let mut hit8 = 0;
    let mut enters = [0.0; 8];
    for c in 0..8 {
        // `max`/`min` as the SSE instructions: the second operand when either is NaN.
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let enter = max(
            max(r.tmin, (on.x - nx[c]) * ni.x),
            max((on.y - ny[c]) * ni.y, (on.z - nz[c]) * ni.z),
        );
        let exit = min(
            min(tmax, (of.x - fx[c]) * ni.x),
            min((of.y - fy[c]) * ni.y, (of.z - fz[c]) * ni.z),
        );
        if enter <= exit {
            hit8 |= 1 << c;
        }
        enters[c] = enter;
    }
    (hit8, enters)
}

#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn child_hits(node: &Node, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
    child_hits_scalar(node, r, tmax)
}

#[cfg(test)]
mod tests;
