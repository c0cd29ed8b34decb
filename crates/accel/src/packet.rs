//! Packets: eight coherent rays (the lens samples of one pixel, neighbouring pixels) walked
//! through the tree together, one node test for all of them.
//!
//! A packet walks the union of its rays' walks: a child is entered when any active ray's box
//! test (the one-ray test's arithmetic, lane by lane, so the same per-ray answers) hits it, and
//! each leaf's triangles are tested only for the rays that hit that leaf — for two rays or more,
//! each triangle for all of them at once ([`crate::triangle::lanes`], the scalar test's bits
//! lane by lane). The lanes' set-up is done for the eight rays at once too ([`rays`]), and rays
//! that miss the scene's bounds are culled eight at a time ([`cull`]). Children are ordered
//! by the packet's common direction octant. The node loads, the stack and the child ordering
//! are paid once per packet instead of once per ray. A node is tested only for the lanes that
//! entered it (its box lies within its parent's, so no other lane can enter it): child by child
//! for all of them at once, or, when fewer lanes than children remain (rays that have parted),
//! lane by lane with each ray's eight-child test, as the one-ray walk does. Closest hits are
//! the one-ray answers exactly, since [`ClosestLeaf`](crate::walk::ClosestLeaf) breaks ties in
//! `t` by primitive, independently of the visit order.
//!
//! Packets apply when the rays share a direction octant and lie in a narrow cone
//! ([`PACKET_CONE_COS`]); other runs take the interleaved walk ([`Accel::intersect_batch`]).
//!
//! Occlusion keeps the triangle that blocked a whole packet and tries it first on the next one
//! (neighbouring rays are mostly blocked by the same triangle, and any blocker gives the same
//! answer): a packet it blocks whole needs no walk.

use crate::node::Node;
#[cfg(target_arch = "x86_64")]
use crate::triangle::lanes::{intersect_lanes, transpose, TriLanes};
#[cfg(target_arch = "x86_64")]
use crate::triangle::TriRay;
use crate::walk::{stack_for, take_child, BlasLeaf, Group, InlineStack, Leaf, INLINE_STACK};
use crate::{Accel, Hit, Ray};
#[cfg(target_arch = "x86_64")]
use glam::Vec3A;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::__m128;
use std::mem::MaybeUninit;

#[cfg(target_arch = "x86_64")]
mod cull;
#[cfg(target_arch = "x86_64")]
mod rays;
#[cfg(target_arch = "x86_64")]
use rays::PacketRays;

/// Rays per packet: one AVX2 lane each.
pub const PACKET_LANES: usize = 8;

/// A run is traced as a packet when every ray's direction is within this cosine of the first
/// ray's (about 8°): wider runs share too little of their walks to gain.
pub const PACKET_CONE_COS: f32 = 0.99;

/// The lanes of `active` that primitive `b` stops (`leaf.visit`), trying the first active lane
/// alone before the others: a miss there costs one triangle test for the packet.
#[inline(always)]
fn try_blocker<L: Leaf>(
    leaves: &mut [L; PACKET_LANES],
    tmax: &mut [f32; PACKET_LANES],
    active: u32,
    b: u32,
) -> u32 {
    let first = active.trailing_zeros() as usize % PACKET_LANES;
    if !leaves[first].visit(b, &mut tmax[first]) {
        return 0;
    }
    let mut stopped = 1 << first;
    let mut rest = active & !stopped;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize % PACKET_LANES;
        rest &= rest - 1;
        if leaves[i].visit(b, &mut tmax[i]) {
            stopped |= 1 << i;
        }
    }
    stopped
}

/// Whether `rays` share a direction octant and lie within [`PACKET_CONE_COS`] of the first, in
/// world space (a first test; the box test's octant is checked once the rays are set up).
#[inline(always)]
fn coherent(rays: &[Ray]) -> bool {
    let Some(first) = rays.first() else {
        return false;
    };
    let sign = |d: glam::Vec3| d.cmplt(glam::Vec3::ZERO).bitmask();
    // `cos(d, d0) >= PACKET_CONE_COS` without square roots or divisions: `d . d0 >= 0` and
    // `(d . d0)^2 >= cos^2 |d|^2 |d0|^2`. Which runs are packets only changes the speed: the
    // answers are the one-ray answers either way.
    let d0 = first.dir;
    let cos2_l0 = PACKET_CONE_COS * PACKET_CONE_COS * d0.length_squared();
    rays.iter().all(|r| {
        let dot = r.dir.dot(d0);
        sign(r.dir) == sign(d0) && dot >= 0.0 && dot * dot >= cos2_l0 * r.dir.length_squared()
    })
}

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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn node_lanes_avx2(
    node: &Node,
    r: &PacketRays,
    tmax: &[f32; PACKET_LANES],
    active: u32,
    mut valid: u32,
) -> ([u8; 8], u32) {
    use std::arch::x86_64::*;
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
/// children at once (the same operations on the same values as the child-by-child test, so the
/// same bits per lane and child), and the per-lane child masks are transposed into per-child
/// lane masks. Cheaper when fewer lanes than children are tested: once a packet's rays part,
/// most nodes are entered by one or two of them.
///
/// # Safety
/// As for [`node_lanes_avx2`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn node_lanes_by_ray(
    node: &Node,
    r: &PacketRays,
    tmax: &[f32; PACKET_LANES],
    lanes: u32,
    valid: u32,
) -> ([u8; 8], u32) {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is guaranteed by the caller; every load reads one `[f32; 8]` row in full or
    // one float of a lane.
    unsafe {
        let [nx, ny, nz, fx, fy, fz] = r.rows.planes(node).map(|row| _mm256_loadu_ps(row.as_ptr()));
        let mut by_lane = 0u64;
        let mut each = lanes;
        while each != 0 {
            let i = each.trailing_zeros() as usize % PACKET_LANES;
            each &= each - 1;
            macro_rules! slab {
                ($o:expr, $row:expr, $ninv:expr) => {
                    _mm256_mul_ps(
                        _mm256_sub_ps(_mm256_set1_ps($o[i]), $row),
                        _mm256_set1_ps($ninv[i]),
                    )
                };
            }
            let (on, of, ni) = (&r.o_near, &r.o_far, &r.ninv);
            let enter = _mm256_max_ps(
                _mm256_max_ps(_mm256_set1_ps(r.tmin[i]), slab!(on[0], nx, ni[0])),
                _mm256_max_ps(slab!(on[1], ny, ni[1]), slab!(on[2], nz, ni[2])),
            );
            let exit = _mm256_min_ps(
                _mm256_min_ps(_mm256_set1_ps(tmax[i]), slab!(of[0], fx, ni[0])),
                _mm256_min_ps(slab!(of[1], fy, ni[1]), slab!(of[2], fz, ni[2])),
            );
            let hit = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u64;
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
fn valid_slots(node: &Node) -> u32 {
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

/// Lanes at a leaf from which its triangles are tested for all of them at once (fewer take
/// the one-ray test, lane by lane).
#[cfg(target_arch = "x86_64")]
const MIN_LANES: u32 = 2;

/// The triangle-test constants of the packet's leaves, lane by lane.
///
/// # Safety
/// As for [`node_lanes_avx2`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn gather_lanes<'s, L: BlasLeaf<'s>>(leaves: &[L; PACKET_LANES]) -> TriLanes {
    let mut rays = [leaves[0].triangles().1; PACKET_LANES];
    let mut tmin = [0.0; PACKET_LANES];
    for (i, leaf) in leaves.iter().enumerate() {
        let (_, ray, t) = leaf.triangles();
        rays[i] = ray;
        tmin[i] = t;
    }
    // SAFETY: forwarded from the caller.
    unsafe { TriLanes::new(rays, tmin) }
}

/// Triangles `first..first + count` of a leaf for lanes `todo`, each triangle tested for all
/// of them at once: what each lane's `visit` of them, in order, would do (lanes are
/// independent, so taking the triangles in the outer loop changes nothing). Lanes the
/// eight-lane test leaves undecided take their scalar `visit`. Returns the lanes stopped.
///
/// # Safety
/// As for [`node_lanes_avx2`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn leaf_lanes<'s, L: BlasLeaf<'s>>(
    lanes: &TriLanes,
    leaves: &mut [L; PACKET_LANES],
    tmax: &mut [f32; PACKET_LANES],
    first: u32,
    count: u32,
    mut todo: u32,
) -> u32 {
    let tris = leaves[todo.trailing_zeros() as usize % PACKET_LANES]
        .triangles()
        .0;
    let mut stopped = 0;
    for primitive in first..first + count {
        let Some(tri) = tris.get(primitive as usize) else {
            // Unreachable for a well-formed tree; `visit` skips it too.
            continue;
        };
        // SAFETY: forwarded from the caller.
        let h = unsafe { intersect_lanes(lanes, &tri.p, tmax, todo) };
        let mut each = h.hits | h.scalar;
        while each != 0 {
            let i = each.trailing_zeros() as usize % PACKET_LANES;
            each &= each - 1;
            let stop = if h.scalar & (1 << i) != 0 {
                leaves[i].visit(primitive, &mut tmax[i])
            } else {
                leaves[i].record(primitive, (h.t[i], h.b1[i], h.b2[i]), &mut tmax[i])
            };
            if stop {
                stopped |= 1 << i;
                todo &= !(1 << i);
            }
        }
        if todo == 0 {
            break;
        }
    }
    stopped
}

/// The walk of one packet over `nodes`: `leaves[i]` visits the primitives of the leaves its ray
/// hits (and may shrink `tmax[i]`). Returns the lanes whose leaf stopped its walk. Lanes outside
/// `active` are ignored.
///
/// # Safety
/// As for [`node_lanes_avx2`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn walk_packet<'s, L: BlasLeaf<'s>>(
    nodes: &[Node],
    r: &PacketRays,
    tmax: &mut [f32; PACKET_LANES],
    leaves: &mut [L; PACKET_LANES],
    mut active: u32,
    stack: &mut [MaybeUninit<Group>],
) -> u32 {
    let mut stopped = 0u32;
    if nodes.is_empty() {
        return stopped;
    }
    // The lanes' triangle-test constants, gathered at the first leaf that enough lanes reach.
    let mut tri_lanes: Option<TriLanes> = None;
    let oct = r.oct_inv4 & 0xff;
    let mut sp = 0;
    // The root as a group of one internal child at priority 7 (obvhs convention).
    let mut current: Group = (0, 0x8000_0000);
    // Per slot of the current group's node, the lanes that entered that child (a byte each;
    // the root's: all). Kept beside each stacked group, so that a node is tested only for the
    // lanes that entered it (a child's box lies within its parent's, so no other lane can).
    let mut cur_lanes = u64::MAX;
    let mut lane_stack = [MaybeUninit::<u64>::uninit(); INLINE_STACK];
    loop {
        if current.1 & 0xff00_0000 == 0 {
            if sp == 0 {
                return stopped;
            }
            sp -= 1;
            // SAFETY: slots below `sp` were written before `sp` passed them.
            current = unsafe { stack[sp].assume_init() };
            // SAFETY: a slot of `lane_stack` that exists was written with `stack[sp]`. (The
            // packets run only on trees whose stack fits `INLINE_STACK`; all lanes would be the
            // safe answer otherwise.)
            cur_lanes = lane_stack
                .get(sp)
                .map_or(u64::MAX, |l| unsafe { l.assume_init() });
            continue;
        }
        let pushed_at = sp;
        let (index, slot) = take_child(&mut current, stack, &mut sp, oct);
        if sp > pushed_at {
            // The group's other children went on the stack: their lanes go beside them.
            if let Some(l) = lane_stack.get_mut(pushed_at) {
                *l = MaybeUninit::new(cur_lanes);
            }
        }
        let here = (cur_lanes >> (8 * (slot & 7))) as u32 & 0xff & active;
        if here == 0 {
            continue;
        }
        let Some(node) = nodes.get(index as usize) else {
            // Unreachable for a well-formed tree; never read out of bounds.
            return stopped;
        };
        let valid = valid_slots(node);
        // SAFETY: AVX2 and FMA are guaranteed by the caller.
        let (lanes, mut any) = unsafe {
            if here.count_ones() < valid.count_ones() {
                node_lanes_by_ray(node, r, tmax, here, valid)
            } else {
                node_lanes_avx2(node, r, tmax, here, valid)
            }
        };
        let mut inner = 0u32;
        while any != 0 {
            let c = any.trailing_zeros() as usize;
            any &= any - 1;
            let lane_bits = lanes[c];
            let meta = node.child_meta[c] as u32;
            if meta & 0x18 == 0x18 {
                // An internal child: its priority bit (24 + slot ^ octant), as obvhs places it.
                inner |= 1 << ((meta & 0x1f) ^ oct);
                continue;
            }
            let first = node.primitive_base_idx + (meta & 0x1f);
            let count = (meta >> 5).count_ones();
            let mut todo = u32::from(lane_bits) & active;
            if todo.count_ones() >= MIN_LANES {
                // Enough lanes: each triangle for all of them at once.
                let lanes = match &mut tri_lanes {
                    Some(l) => l,
                    // SAFETY: forwarded from the caller.
                    None => tri_lanes.insert(unsafe { gather_lanes(leaves) }),
                };
                // SAFETY: forwarded from the caller.
                let s = unsafe { leaf_lanes(lanes, leaves, tmax, first, count, todo) };
                stopped |= s;
                active &= !s;
                if active == 0 {
                    return stopped;
                }
                continue;
            }
            while todo != 0 {
                let i = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                for primitive in first..first + count {
                    if leaves[i].visit(primitive, &mut tmax[i]) {
                        stopped |= 1 << i;
                        active &= !(1 << i);
                        break;
                    }
                }
            }
            if active == 0 {
                return stopped;
            }
        }
        current = (node.child_base_idx, inner | node.imask as u32);
        cur_lanes = u64::from_le_bytes(lanes);
    }
}

impl Accel {
    /// [`Accel::intersect_batch`] for rays that come in coherent runs (the lens samples of a
    /// pixel, a row of pixels): each run of [`PACKET_LANES`] rays that share a direction octant
    /// and a narrow cone is walked as one packet; other runs are interleaved as in
    /// `intersect_batch`. The answers are exactly [`Accel::intersect`]'s, ray by ray.
    pub fn intersect_packets(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when `detect_avx2` found every feature it enables.
            return unsafe { self.intersect_packets_avx2(rays, out) };
        }
        self.intersect_batch(rays, out)
    }

    /// [`Accel::occluded_batch`] in packets, as [`Accel::intersect_packets`].
    pub fn occluded_packets(&self, rays: &[Ray], out: &mut [bool]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `intersect_packets`.
            return unsafe { self.occluded_packets_avx2(rays, out) };
        }
        self.occluded_batch(rays, out)
    }

    /// # Safety
    /// As for [`Accel::intersect_batch`]'s AVX2 path.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn intersect_packets_avx2(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        // SAFETY: forwarded.
        unsafe { self.packets_impl::<crate::walk::ClosestLeaf<true>>(rays, out) }
    }

    /// # Safety
    /// As for [`Accel::intersect_batch`]'s AVX2 path.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn occluded_packets_avx2(&self, rays: &[Ray], out: &mut [bool]) {
        // SAFETY: forwarded.
        unsafe { self.packets_impl::<crate::walk::AnyLeaf<true>>(rays, out) }
    }

    /// The packet queries with leaves of type `L`: runs of [`PACKET_LANES`] rays, each a packet
    /// when [`coherent`], else interleaved.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn packets_impl<'s, L: BlasLeaf<'s>>(&'s self, rays: &[Ray], out: &mut [L::Answer]) {
        let n = rays.len().min(out.len());
        let (rays, out) = (&rays[..n], &mut out[..n]);
        let Some((entry, blas)) = self.single_entry() else {
            return self.batch_impl::<true, L>(rays, out);
        };
        let mut inline: InlineStack = [MaybeUninit::uninit(); INLINE_STACK];
        let mut heap = Vec::new();
        let stack = stack_for(self.max_blas_depth, &mut inline, &mut heap);
        // Consecutive incoherent runs are interleaved together (one batch per stretch: the
        // interleaved walk refills its lanes, which a batch per run of 8 would not).
        let mut loose = 0;
        // Any hit: the triangle that blocked every lane of the last packet, tried first on the
        // next (neighbouring rays are mostly blocked by the same one; any blocker gives the
        // same answer). Kept only while whole packets are blocked, so that unblocked runs
        // (most shadow rays) pay nothing for it.
        let mut blocker: Option<u32> = None;
        for at in (0..n).step_by(PACKET_LANES) {
            let end = (at + PACKET_LANES).min(n);
            let run = &rays[at..end];
            // Rays that provably meet nothing stay inactive (their answers: a miss); a run of
            // only those is answered here, before the coherence test. A run whose first ray
            // starts inside the scene (a camera inside it, shadow rays) is not checked further:
            // culling only saves work, and the runs that gain start outside.
            let mut active = (1u32 << run.len()) - 1;
            if !self.starts_inside(&run[0]) {
                if let Ok(eight) = <&[Ray; PACKET_LANES]>::try_from(run) {
                    // SAFETY: forwarded from the caller.
                    active &= !unsafe { self.misses_bounds_lanes(eight) };
                } else {
                    for (i, ray) in run.iter().enumerate() {
                        active &= !(u32::from(self.misses_bounds(ray)) << i);
                    }
                }
            }
            if active == 0 {
                self.batch_impl::<true, L>(&rays[loose..at], &mut out[loose..at]);
                loose = end;
                out[at..end].fill_with(L::miss);
                continue;
            }
            if run.len() < 2 || !coherent(run) {
                continue;
            }
            // Lanes past the run's end copy its last ray and stay inactive. Loops, not
            // `array::from_fn`, whose closures stayed calls.
            let (o0, d0) = Self::object_ray(entry, &run[0]);
            // SAFETY: AVX2 (and so AVX) is guaranteed by the caller.
            let leaf0 = L::start(&blas.tris, unsafe { TriRay::new_avx(o0, d0) }, run[0].tmin);
            let mut leaves = [leaf0; PACKET_LANES];
            let mut tmax = [run[0].tmax; PACKET_LANES];
            let mut tmin = [run[0].tmin; PACKET_LANES];
            let mut origins = [__m128::from(Vec3A::from(o0)); PACKET_LANES];
            let mut dirs = [__m128::from(Vec3A::from(d0)); PACKET_LANES];
            for i in 1..PACKET_LANES {
                let ray = &run[i.min(run.len() - 1)];
                let (o, d) = Self::object_ray(entry, ray);
                // SAFETY: as above.
                leaves[i] = L::start(&blas.tris, unsafe { TriRay::new_avx(o, d) }, ray.tmin);
                (tmax[i], tmin[i]) = (ray.tmax, ray.tmin);
                origins[i] = Vec3A::from(o).into();
                dirs[i] = Vec3A::from(d).into();
            }
            // The octant that decides is the box test's, in the tree's space: it follows the
            // sign of a zero component, which the world-space check above does not see.
            // SAFETY: forwarded from the caller.
            let Some(packet) = (unsafe {
                let [ox, oy, oz, _] = transpose(origins);
                let [dx, dy, dz, _] = transpose(dirs);
                PacketRays::from_rays([ox, oy, oz], [dx, dy, dz], tmin, blas.box_bounds)
            }) else {
                continue;
            };
            self.batch_impl::<true, L>(&rays[loose..at], &mut out[loose..at]);
            loose = end;
            let mut stopped = 0;
            if let Some(b) = blocker {
                stopped = try_blocker(&mut leaves, &mut tmax, active, b);
            }
            if stopped != active {
                // SAFETY: forwarded from the caller.
                stopped |= unsafe {
                    walk_packet(
                        &blas.nodes,
                        &packet,
                        &mut tmax,
                        &mut leaves,
                        active & !stopped,
                        stack,
                    )
                };
            }
            blocker = if stopped == active {
                leaves[active.trailing_zeros() as usize % PACKET_LANES].blocker()
            } else {
                None
            };
            for (i, answer) in out[at..end].iter_mut().enumerate() {
                *answer = leaves[i].answer(blas, entry, stopped & (1 << i) != 0);
            }
        }
        self.batch_impl::<true, L>(&rays[loose..], &mut out[loose..]);
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::triangle::lanes::transpose;
    use glam::Vec3;

    /// A counter-based generator (SplitMix64's finaliser).
    fn mix(k: u64) -> u64 {
        let mut z = k.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

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
        if !is_x86_feature_detected!("avx2") || !is_x86_feature_detected!("fma") {
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
