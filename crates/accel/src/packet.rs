// layout: long-fn packets_impl (the packet queries' loop over runs is kept whole: with the
// culling and the lanes' set-up in #[inline(always)] helpers it took 3.3 % more callgrind
// instructions for closest-hit packets and 2.5 % more for occlusion packets)
// layout: long-fn walk_packet (one packet's walk is kept whole: with the pop, the node test and
// the leaf visit in #[inline(always)] helpers it took 0.3 % more callgrind instructions for
// closest-hit packets)
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
//! The kernels are written with AVX's eight-float intrinsics: AVX2 on x86-64 (detected at run
//! time), and on aarch64 [`crate::avx`]'s NEON versions of the same operations, which give the
//! same bits (NEON is baseline there). Other architectures take the interleaved walk.
//!
//! Occlusion keeps the triangle that blocked a whole packet and tries it first on the next one
//! (neighbouring rays are mostly blocked by the same triangle, and any blocker gives the same
//! answer): a packet it blocks whole needs no walk.

use crate::structure::Accel;
use crate::types::{Hit, Ray};
pub use shape::{PACKET_CONE_COS, PACKET_LANES};

mod shape;

// The kernels and what they use: x86-64 and aarch64 only (AVX2, or NEON through `crate::avx`).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
mod cone;
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
mod cull;
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
mod node_lanes;
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
mod rays;
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
use {
    crate::avx::__m128,
    crate::node::Node,
    crate::triangle::lanes::{intersect_lanes, transpose, TriLanes},
    crate::triangle::TriRay,
    crate::walk::{stack_for, take_child, BlasLeaf, Group, InlineStack, Leaf, INLINE_STACK},
    glam::Vec3A,
    node_lanes::{node_lanes_avx2, node_lanes_by_ray, valid_slots},
    rays::PacketRays,
    std::mem::MaybeUninit,
};

/// The lanes of `active` that primitive `b` stops (`leaf.visit`), trying the first active lane
/// alone before the others: a miss there costs one triangle test for the packet.
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
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

/// Lanes at a leaf from which its triangles are tested for all of them at once (fewer take
/// the one-ray test, lane by lane).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
const MIN_LANES: u32 = 2;

/// The triangle-test constants of the packet's leaves, lane by lane.
///
/// # Safety
/// As for [`node_lanes_avx2`].
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
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
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
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
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
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
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // SAFETY: the NEON kernels (`detect_avx2`): NEON is baseline on aarch64.
            return unsafe { self.packets_impl::<crate::walk::ClosestLeaf<true>>(rays, out) };
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
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // SAFETY: as in `intersect_packets`.
            return unsafe { self.packets_impl::<crate::walk::AnyLeaf<true>>(rays, out) };
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
    /// when [`cone::coherent`], else interleaved.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA (on x86-64; NEON on aarch64 is baseline).
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
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
            // A full run's directions in lanes, transposed once for culling and coherence.
            let full = match <&[Ray; PACKET_LANES]>::try_from(run) {
                // SAFETY: forwarded from the caller.
                Ok(eight) => Some((eight, unsafe { rays::dir_lanes(eight) })),
                Err(_) => None,
            };
            let mut active = (1u32 << run.len()) - 1;
            if !self.starts_inside(&run[0]) {
                if let Some((eight, dirs)) = full {
                    // SAFETY: forwarded from the caller.
                    active &= !unsafe { self.misses_bounds_lanes(eight, dirs) };
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
            let coherent = match full {
                // SAFETY: forwarded from the caller.
                Some((eight, dirs)) => unsafe { cone::coherent_lanes(eight[0].dir, dirs) },
                None => run.len() >= 2 && cone::coherent(run),
            };
            if !coherent {
                continue;
            }
            // Lanes past the run's end copy its last ray and stay inactive. Loops, not
            // `array::from_fn`, whose closures stayed calls.
            let (o0, d0) = Self::object_ray(entry, &run[0]);
            // SAFETY: AVX2 (and so AVX) is guaranteed by the caller.
            let leaf0 = L::start(
                &blas.tris,
                unsafe { TriRay::new_for::<true>(o0, d0) },
                run[0].tmin,
            );
            let mut leaves = [leaf0; PACKET_LANES];
            let mut tmax = [run[0].tmax; PACKET_LANES];
            let mut tmin = [run[0].tmin; PACKET_LANES];
            let mut origins = [__m128::from(Vec3A::from(o0)); PACKET_LANES];
            let mut dirs = [__m128::from(Vec3A::from(d0)); PACKET_LANES];
            for i in 1..PACKET_LANES {
                let ray = &run[i.min(run.len() - 1)];
                let (o, d) = Self::object_ray(entry, ray);
                // SAFETY: as above.
                leaves[i] = L::start(
                    &blas.tris,
                    unsafe { TriRay::new_for::<true>(o, d) },
                    ray.tmin,
                );
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
