//! A packet's node test: for each child of a node, the lanes whose ray enters it — child by
//! child for many lanes ([`node_lanes_avx2`]), lane by lane for few ([`node_lanes_by_ray`]),
//! the same bits either way.

use super::rays::PacketRays;
use super::shape::PACKET_LANES;
use crate::node::Node;

/// One node's box test for the packet's `active` lanes: per child slot, the lanes whose ray
/// hits it within `[tmin, tmax]` (bit `i` for lane `i`), and the slots some lane hits.
///
/// Each lane computes exactly what [`crate::node::intersect_node_avx2`] computes for its ray:
/// `(o - b) * -inv` from the widened origins, clamped by `tmin` and `tmax`. Child by child:
/// one eight-lane test per child of `valid` (the node's non-empty slots).
///
/// # Safety
/// The CPU must support AVX2 and FMA, and the caller must be compiled for them (inlined into
/// the AVX2 queries, as `node::node_test_avx2`).
#[inline(always)]
pub(super) unsafe fn node_lanes_avx2(
    node: &Node,
    r: &PacketRays,
    tmax: &[f32; PACKET_LANES],
    active: u32,
    mut valid: u32,
) -> ([u8; 8], u32) {
    use crate::avx::*;
    // SAFETY: AVX2 is guaranteed by the caller; every load reads one `[f32; 8]` field in full,
    // or one float of a row.
    unsafe {
        // Macros, not closures: closures do not inherit the target features (a call per
        // intrinsic).
        macro_rules! load {
            ($v:expr) => {
                _mm256_loadu_ps($v.as_ptr())
            };
        }
        let [nx, ny, nz, fx, fy, fz] = r.rows.planes(node);
        let (on, of, ni) = (
            r.o_near.each_ref().map(|v| load!(v)),
            r.o_far.each_ref().map(|v| load!(v)),
            r.ninv.each_ref().map(|v| load!(v)),
        );
        let tmin = load!(r.tmin);
        let tmax = load!(tmax);
        let mut out = [0u8; 8];
        let mut any = 0u32;
        while valid != 0 {
            let c = valid.trailing_zeros() as usize & 7;
            valid &= valid - 1;
            macro_rules! slab {
                ($o:expr, $row:expr, $ninv:expr) => {
                    _mm256_mul_ps(_mm256_sub_ps($o, _mm256_set1_ps($row[c])), $ninv)
                };
            }
            let enter = _mm256_max_ps(
                _mm256_max_ps(tmin, slab!(on[0], nx, ni[0])),
                _mm256_max_ps(slab!(on[1], ny, ni[1]), slab!(on[2], nz, ni[2])),
            );
            let exit = _mm256_min_ps(
                _mm256_min_ps(tmax, slab!(of[0], fx, ni[0])),
                _mm256_min_ps(slab!(of[1], fy, ni[1]), slab!(of[2], fz, ni[2])),
            );
            let hit = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32;
            let hit = hit & active;
            out[c] = hit as u8;
            any |= u32::from(hit != 0) << c;
        }
        (out, any)
    }
}

/// [`node_lanes_avx2`] lane by lane: each lane of `lanes` tests its ray against the node's eight
/// children at once with the one-ray walks' test (`node::slabs_avx2`: the same operations on the
/// same values as the child-by-child test, so the same bits per lane and child), and the per-lane child masks are transposed into per-child
/// lane masks. Cheaper when fewer lanes than children are tested: once a packet's rays part,
/// most nodes are entered by one or two of them.
///
/// # Safety
/// As for [`node_lanes_avx2`].
#[inline(always)]
pub(super) unsafe fn node_lanes_by_ray(
    node: &Node,
    r: &PacketRays,
    tmax: &[f32; PACKET_LANES],
    lanes: u32,
    valid: u32,
) -> ([u8; 8], u32) {
    use crate::avx::*;
    // SAFETY: AVX2 is guaranteed by the caller; every load reads one `[f32; 8]` row in full or
    // one float of a lane.
    unsafe {
        let rows = r.rows.planes(node);
        let lane = |v: &[[f32; PACKET_LANES]; 3], i: usize| [v[0][i], v[1][i], v[2][i]];
        let mut by_lane = 0u64;
        let mut each = lanes;
        while each != 0 {
            let i = each.trailing_zeros() as usize % PACKET_LANES;
            each &= each - 1;
            let (hit, _) = crate::node::slabs_avx2(
                rows,
                lane(&r.o_near, i),
                lane(&r.o_far, i),
                lane(&r.ninv, i),
                [r.tmin[i], tmax[i]],
            );
            let hit = _mm256_movemask_ps(hit) as u64;
            by_lane |= (hit & u64::from(valid)) << (8 * i);
        }
        let by_child = transpose_bits(by_lane);
        let out = by_child.to_le_bytes();
        let any = _mm_movemask_epi8(_mm_cmpeq_epi8(
            _mm_cvtsi64_si128(by_child as i64),
            _mm_setzero_si128(),
        )) as u32;
        (out, !any & 0xff)
    }
}

/// The node's non-empty child slots (bit `c` for slot `c`): an empty slot has a zero meta byte.
#[inline(always)]
pub(super) fn valid_slots(node: &Node) -> u32 {
    // Per byte `b`, `((b & 0x7f) + 0x7f) | b` has bit 7 set iff `b != 0` (the sum carries into
    // bit 7 iff a low bit is set, and never out of the byte).
    let x = u64::from_le_bytes(node.child_meta);
    let high = (((x & 0x7f7f_7f7f_7f7f_7f7f) + 0x7f7f_7f7f_7f7f_7f7f) | x) & 0x8080_8080_8080_8080;
    // Gather the eight high bits into the low byte.
    ((high >> 7).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
}

/// The 8×8 bit matrix `x` (byte `i`, bit `j`) transposed (byte `j`, bit `i`).
#[inline(always)]
fn transpose_bits(mut x: u64) -> u64 {
    // Hacker's Delight, transpose8: swap 1×1, 2×2 and 4×4 blocks.
    let t = (x ^ (x >> 7)) & 0x00aa_00aa_00aa_00aa;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_cccc_0000_cccc;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_f0f0_f0f0;
    x ^ t ^ (t << 28)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::avx::__m128;
    use crate::triangle::lanes::transpose;
    use glam::{Vec3, Vec3A};

    /// 64 bits from the crate's test hash of a counter.
    fn mix(k: u64) -> u64 {
        let lo = crate::test_util::mix(k as u32);
        let hi = crate::test_util::mix(lo ^ (k >> 32) as u32 ^ 0x9e37_79b9);
        (u64::from(hi) << 32) | u64::from(lo)
    }

    /// A uniform value in `[0, 1)` from a counter.
    fn unit(k: u64) -> f32 {
        (mix(k) >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn transpose_bits_swaps_lanes_and_children() {
        for k in 0..10_000 {
            let x = mix(k) & mix(k + 1_000_000);
            let t = transpose_bits(x);
            for i in 0..8 {
                for j in 0..8 {
                    assert_eq!((x >> (8 * i + j)) & 1, (t >> (8 * j + i)) & 1, "{x:#x}");
                }
            }
        }
    }

    #[test]
    fn valid_slots_are_the_non_empty_meta_bytes() {
        for k in 0..10_000u64 {
            let mut node = test_node(k);
            for (c, b) in node.child_meta.iter_mut().enumerate() {
                *b = match mix(k * 8 + c as u64) % 4 {
                    0 => 0,
                    1 => 0x80,
                    2 => 1,
                    _ => mix(k ^ c as u64) as u8,
                };
            }
            let want = (0..8)
                .filter(|&c| node.child_meta[c] != 0)
                .fold(0, |m, c| m | 1 << c);
            assert_eq!(valid_slots(&node), want, "{:?}", node.child_meta);
        }
    }

    /// A node of eight random boxes in `[-1, 1]^3`, some slots empty.
    fn test_node(k: u64) -> Node {
        let mut bounds = [[0.0f32; 8]; 6];
        let mut meta = [0u8; 8];
        for c in 0..8 {
            let empty = mix(k * 131 + c as u64) % 5 == 0;
            for a in 0..3 {
                let (u, v) = (
                    unit(k * 977 + (c * 3 + a) as u64),
                    unit(k * 613 + (c * 3 + a) as u64),
                );
                let (lo, hi) = (2.0 * u.min(v) - 1.0, 2.0 * u.max(v) - 1.0);
                (bounds[2 * a][c], bounds[2 * a + 1][c]) = if empty {
                    (f32::INFINITY, f32::NEG_INFINITY)
                } else {
                    (lo, hi)
                };
            }
            meta[c] = if empty { 0 } else { 0b0010_0000 | c as u8 };
        }
        Node {
            bounds,
            child_base_idx: 0,
            primitive_base_idx: 0,
            child_meta: meta,
            imask: 0,
        }
    }

    /// The lane-by-lane node test gives the child-by-child one's bits for every lane and child,
    /// whichever lanes are asked for.
    #[test]
    fn lanes_by_ray_match_lanes_by_child() {
        if !crate::test_util::lanes8() {
            return;
        }
        let bounds = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let (mut packets, mut hits) = (0, 0);
        for k in 0..20_000u64 {
            // Eight rays of one octant from around the box, towards points near its centre.
            let signs = Vec3::new(
                if mix(k) & 1 == 0 { 1.0 } else { -1.0 },
                if mix(k) & 2 == 0 { 1.0 } else { -1.0 },
                if mix(k) & 4 == 0 { 1.0 } else { -1.0 },
            );
            let mut origins = [__m128::from(Vec3A::ZERO); PACKET_LANES];
            let mut dirs = origins;
            let mut tmin = [0.0; PACKET_LANES];
            let mut tmax = [f32::INFINITY; PACKET_LANES];
            for i in 0..PACKET_LANES {
                let j = k * 64 + 8 * i as u64;
                let d = (Vec3::new(unit(j), unit(j + 1), unit(j + 2)) + 0.05) * signs;
                let o = -d * 2.5 + Vec3::new(unit(j + 3), unit(j + 4), unit(j + 5)) - 0.5;
                origins[i] = Vec3A::from(o).into();
                dirs[i] = Vec3A::from(d).into();
                tmin[i] = if i % 3 == 0 { 0.0 } else { 0.5 * unit(j + 6) };
                tmax[i] = if i % 2 == 0 {
                    f32::INFINITY
                } else {
                    4.0 * unit(j + 7)
                };
            }
            // SAFETY: AVX2 checked above.
            let Some(packet) = (unsafe {
                let [ox, oy, oz, _] = transpose(origins);
                let [dx, dy, dz, _] = transpose(dirs);
                PacketRays::from_rays([ox, oy, oz], [dx, dy, dz], tmin, bounds)
            }) else {
                continue;
            };
            packets += 1;
            let node = test_node(k);
            let valid = valid_slots(&node);
            let lanes = (mix(k + 7) & 0xff) as u32;
            // SAFETY: AVX2 and FMA checked above.
            let (by_child, by_ray) = unsafe {
                (
                    node_lanes_avx2(&node, &packet, &tmax, lanes, valid),
                    node_lanes_by_ray(&node, &packet, &tmax, lanes, valid),
                )
            };
            assert_eq!(by_ray, by_child, "case {k}: lanes {lanes:#b}");
            hits += by_child.1.count_ones();
        }
        assert!(
            packets > 15_000 && hits > 20_000,
            "{packets} packets, {hits} hits"
        );
    }
}
