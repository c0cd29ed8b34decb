//! The traversal: the stack, the leaf visitors (closest and any hit, top level and bottom
//! level), the stepped walk of one ray and the interleaved walk of a batch.

use crate::node::BoxRay;
use crate::triangle::TriRay;
use crate::{Accel, Blas, Entry, Hit, Ray, Tri};
use obvhs::cwbvh::node::CwBvhNode;
use std::mem::MaybeUninit;

/// A traversal stack entry: a node group (obvhs encoding: child base index, hit mask).
pub(crate) type Group = (u32, u32);

/// Stacks up to this depth live on the call stack; deeper trees (degenerate input) get a heap
/// stack sized from the measured depth, so the stack can never overflow.
pub(crate) const INLINE_STACK: usize = 48;

/// An uninitialised inline stack.
pub(crate) type InlineStack = [MaybeUninit<Group>; INLINE_STACK];

/// The traversal stack for a tree of `depth` levels: `inline` when it fits, else `heap` sized to
/// the depth. A plain function rather than a closure-taking one so that the query stays one
/// function after inlining (closures were separate calls per ray).
///
/// Slots start uninitialised: zeroing 48 entries per query (a `memset` call) cost about 3 % of the
/// instructions of a primary ray. [`traverse`] reads a slot only below its stack pointer, that
/// is, only after writing it.
#[inline(always)]
pub(crate) fn stack_for<'a>(
    depth: usize,
    inline: &'a mut InlineStack,
    heap: &'a mut Vec<MaybeUninit<Group>>,
) -> &'a mut [MaybeUninit<Group>] {
    if depth < INLINE_STACK {
        inline
    } else {
        *heap = vec![MaybeUninit::<Group>::uninit(); depth + 1];
        heap
    }
}

/// What [`traverse`] does with each primitive of a hit leaf. A trait with `#[inline(always)]`
/// implementations rather than a closure: the compiler left the occlusion closure as a call per
/// triangle once the traversal was inlined into the query.
pub(crate) trait Leaf {
    /// Visits `primitive`; may shrink `tmax`; returns `true` to stop the traversal.
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool;
}

impl<L: Leaf> Leaf for &mut L {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        (**self).visit(primitive, tmax)
    }
}

/// The top level's leaf for closest hit: each entry is a walk of its bottom-level tree. A
/// struct with an `#[inline(always)]` visit, not a closure: closures do not take the query's
/// target features, and once the walk became a stepped state the compiler kept the closure
/// (and the 8-wide node test inside it) a call (+10 % instructions per instanced query).
pub(crate) struct EntriesClosest<'a, const AVX2: bool> {
    pub(crate) accel: &'a Accel,
    pub(crate) ray: &'a Ray,
    pub(crate) stack: &'a mut [MaybeUninit<Group>],
    pub(crate) best: Option<Hit>,
}

impl<const AVX2: bool> Leaf for EntriesClosest<'_, AVX2> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(entry) = self.accel.entries.get(primitive as usize) {
            let hit = self
                .accel
                .walk_entry::<AVX2, ClosestLeaf>(entry, self.ray, tmax, self.stack);
            if let Some(Some(hit)) = hit {
                self.best = Some(hit);
            }
        }
        false
    }
}

/// The top level's leaf for occlusion ([`EntriesClosest`] for any hit): stops at the first entry
/// that occludes.
pub(crate) struct EntriesAny<'a, const AVX2: bool> {
    pub(crate) accel: &'a Accel,
    pub(crate) ray: &'a Ray,
    pub(crate) stack: &'a mut [MaybeUninit<Group>],
}

impl<const AVX2: bool> Leaf for EntriesAny<'_, AVX2> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, _: &mut f32) -> bool {
        let mut tmax = self.ray.tmax;
        self.accel
            .entries
            .get(primitive as usize)
            .is_some_and(|entry| {
                self.accel
                    .walk_entry::<AVX2, AnyLeaf>(entry, self.ray, &mut tmax, self.stack)
                    == Some(true)
            })
    }
}

/// Closest hit over a bottom-level BVH's triangles: `(triangle index, (t, u, v))`.
#[derive(Clone, Copy)]
pub(crate) struct ClosestLeaf<'a> {
    pub(crate) tris: &'a [Tri],
    pub(crate) ray: TriRay,
    pub(crate) tmin: f32,
    pub(crate) best: Option<(usize, (f32, f32, f32))>,
}

impl Leaf for ClosestLeaf<'_> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(tri) = self.tris.get(primitive as usize) {
            if let Some(h) = crate::triangle::intersect(&self.ray, &tri.p, self.tmin, *tmax) {
                // A tie in `t` goes to the lower primitive, so the answer does not depend on the
                // order of the visits (packets visit in another order than one ray).
                let first = self
                    .best
                    .is_none_or(|(best, _)| h.0 < *tmax || (primitive as usize) < best);
                if first {
                    *tmax = h.0;
                    self.best = Some((primitive as usize, h));
                }
            }
        }
        false
    }
}

/// Any hit over a bottom-level BVH's triangles: stops at the first.
#[derive(Clone, Copy)]
pub(crate) struct AnyLeaf<'a> {
    pub(crate) tris: &'a [Tri],
    pub(crate) ray: TriRay,
    pub(crate) tmin: f32,
}

impl Leaf for AnyLeaf<'_> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        self.tris.get(primitive as usize).is_some_and(|tri| {
            crate::triangle::intersect(&self.ray, &tri.p, self.tmin, *tmax).is_some()
        })
    }
}

/// A bottom-level leaf (closest or any hit): how a ray's leaf starts and what its answer is,
/// for the one-ray walks ([`Accel::walk_entry`]) and the batches ([`Accel::batch_impl`]).
pub(crate) trait BlasLeaf<'a>: Leaf + Copy {
    /// One ray's answer.
    type Answer;
    /// The leaf of a ray with triangle-test constants `ray`, before any visit.
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self;
    /// The answer once the walk has ended (`stopped`: the leaf stopped it).
    fn answer(&self, blas: &Blas, entry: &Entry, stopped: bool) -> Self::Answer;
    /// The one-ray query, for scenes that interleaving does not cover.
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> Self::Answer;
}

impl<'a> BlasLeaf<'a> for ClosestLeaf<'a> {
    type Answer = Option<Hit>;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self {
            tris,
            ray,
            tmin,
            best: None,
        }
    }

    #[inline(always)]
    fn answer(&self, blas: &Blas, entry: &Entry, _: bool) -> Option<Hit> {
        self.best.map(|(i, h)| Accel::make_hit(blas, entry, i, h))
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> Option<Hit> {
        accel.intersect_impl::<AVX2>(ray)
    }
}

impl<'a> BlasLeaf<'a> for AnyLeaf<'a> {
    type Answer = bool;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self { tris, ray, tmin }
    }

    #[inline(always)]
    fn answer(&self, _: &Blas, _: &Entry, stopped: bool) -> bool {
        stopped
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> bool {
        accel.occluded_impl::<AVX2>(ray)
    }
}

/// A walk of a CWBVH (obvhs layout) in progress, front to back: the traversal of one ray as a
/// state that advances one step at a time, so that several rays' walks can be interleaved on
/// one thread (see [`Accel::intersect_batch`]). [`traverse`] runs one walk to its end.
///
/// Each stack entry holds the unvisited siblings of one level of the current path, so the stack
/// needs one entry per tree level (the depth measured at build time).
#[derive(Clone, Copy)]
pub(crate) struct Walk {
    pub(crate) sp: usize,
    pub(crate) current: Group,
    pub(crate) prims: Group,
}

impl Walk {
    /// A walk from the root.
    #[inline(always)]
    fn new() -> Self {
        Self {
            sp: 0,
            // The root as a group of one internal child at priority 7 (obvhs convention).
            current: (0, 0x8000_0000),
            prims: (0, 0),
        }
    }

    /// Visits the pending primitives of the current leaf (`leaf.visit(primitive, &mut tmax)`
    /// each), then tests the next node. `Some(stopped)` once the walk has ended, where
    /// `stopped` says whether `leaf` stopped it.
    ///
    /// With `AVX2` it must be inlined into a function compiled for AVX2 (`Accel::intersect_avx2`
    /// and its kin), so that the node test and `count_ones`/`leading_zeros` become inline vector
    /// and bit instructions.
    #[inline(always)]
    fn step<const AVX2: bool>(
        &mut self,
        nodes: &[CwBvhNode],
        r: &BoxRay,
        tmax: &mut f32,
        stack: &mut [MaybeUninit<Group>],
        leaf: &mut impl Leaf,
    ) -> Option<bool> {
        while self.prims.1 != 0 {
            let local = 31 - self.prims.1.leading_zeros();
            self.prims.1 &= !(1u32 << local);
            if leaf.visit(self.prims.0 + local, tmax) {
                return Some(true);
            }
        }
        if self.current.1 & 0xff00_0000 != 0 {
            let index = take_child(&mut self.current, stack, &mut self.sp, r.oct_inv4 & 0xff);
            let Some(node) = nodes.get(index as usize) else {
                // Unreachable for a well-formed tree (and for an empty one, whose root group is
                // never read); never read out of bounds.
                self.current.1 = 0;
                return None;
            };
            let mask = if AVX2 {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `AVX2` is true only when `detect_avx2` found AVX2 on this CPU.
                unsafe {
                    crate::node::intersect_node_avx2(node, r, *tmax)
                }
                #[cfg(not(target_arch = "x86_64"))]
                crate::node::intersect_node(node, r, *tmax)
            } else {
                crate::node::intersect_node(node, r, *tmax)
            };
            self.current = (
                node.child_base_idx,
                (mask & 0xff00_0000) | node.imask as u32,
            );
            self.prims = (node.primitive_base_idx, mask & 0x00ff_ffff);
        } else {
            self.current = (0, 0);
        }
        if self.prims.1 == 0 && self.current.1 & 0xff00_0000 == 0 {
            if self.sp == 0 {
                return Some(false);
            }
            self.sp -= 1;
            // SAFETY: slots below `sp` were written by the push above before `sp` passed them
            // (`sp` only grows right after a write), so slot `sp` holds an initialised group.
            self.current = unsafe { stack[self.sp].assume_init() };
        }
        None
    }
}

/// Takes the next internal child of the node group `current` (obvhs' priority order for the
/// octant key `oct`) and returns its node index; the group's other children, if any, are pushed
/// on `stack` at `sp`. Shared by the one-ray walk and the packets' walk.
#[inline(always)]
pub(crate) fn take_child(
    current: &mut Group,
    stack: &mut [MaybeUninit<Group>],
    sp: &mut usize,
    oct: u32,
) -> u32 {
    let hits = current.1;
    let offset = 31 - hits.leading_zeros();
    current.1 &= !(1u32 << offset);
    if current.1 & 0xff00_0000 != 0 {
        stack[*sp] = MaybeUninit::new(*current);
        *sp += 1;
    }
    let slot = (offset - 24) ^ oct;
    current.0 + (hits & !(u32::MAX << slot)).count_ones()
}

/// Walks a CWBVH (obvhs layout) front to back for `r`, calling `leaf.visit(primitive, &mut tmax)`
/// for every primitive in a hit leaf. Returns whether `leaf` stopped it. `stack` needs one entry
/// per tree level.
#[inline(always)]
pub(crate) fn traverse<const AVX2: bool>(
    nodes: &[CwBvhNode],
    r: &BoxRay,
    tmax: &mut f32,
    stack: &mut [MaybeUninit<Group>],
    mut leaf: impl Leaf,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let mut walk = Walk::new();
    loop {
        if let Some(stopped) = walk.step::<AVX2>(nodes, r, tmax, stack, &mut leaf) {
            return stopped;
        }
    }
}

/// Rays walked at once, interleaved, by [`Accel::intersect_batch`] and [`Accel::occluded_batch`].
/// Measured on thin-lens primary rays (`benches/`, closest hit, 1 thread): 2 and 4 gain alike
/// in tile order, 4 gains more in random order, 8 less in tile order.
pub const BATCH_LANES: usize = 4;

/// Runs the walks of rays `0..n` over `nodes`, [`BATCH_LANES`] at a time, interleaved step by
/// step. `start(i)` gives ray `i`'s box ray, `tmax` and leaf; `finish(i, leaf, stopped)` takes
/// them back when its walk ends. Each ray's walk is exactly [`traverse`]'s, so the results are
/// too; only the order of work between rays changes.
///
/// Why: one ray's walk is a chain of dependent loads and tests (a node's address comes out of
/// its parent's test) that leaves most of the core idle; independent chains fill it.
#[inline(always)]
pub(crate) fn interleave<const AVX2: bool, L: Leaf + Copy>(
    nodes: &[CwBvhNode],
    n: usize,
    mut start: impl FnMut(usize) -> (BoxRay, f32, L),
    mut finish: impl FnMut(usize, &L, bool),
) {
    if n == 0 {
        return;
    }
    // Lanes are updated in place (no moves of whole lanes), and idle ones are marked by their
    // index: both measured faster than `Option`s of lanes.
    struct Lane<L> {
        /// The ray walked, or `usize::MAX` when the lane is idle.
        index: usize,
        walk: Walk,
        br: BoxRay,
        tmax: f32,
        leaf: L,
        stack: InlineStack,
    }
    let mut next = 0;
    let mut lanes: [Lane<L>; BATCH_LANES] = std::array::from_fn(|_| {
        // Lanes beyond `n` start idle, on a copy of the last ray.
        let index = if next < n { next } else { usize::MAX };
        let (br, tmax, leaf) = start(next.min(n - 1));
        next += 1;
        Lane {
            index,
            walk: Walk::new(),
            br,
            tmax,
            leaf,
            stack: [MaybeUninit::uninit(); INLINE_STACK],
        }
    });
    next = next.min(n);
    let mut active = lanes.iter().filter(|l| l.index != usize::MAX).count();
    while active > 0 {
        for lane in &mut lanes {
            if lane.index == usize::MAX {
                continue;
            }
            let done = lane.walk.step::<AVX2>(
                nodes,
                &lane.br,
                &mut lane.tmax,
                &mut lane.stack,
                &mut lane.leaf,
            );
            if let Some(stopped) = done {
                finish(lane.index, &lane.leaf, stopped);
                if next < n {
                    let (br, tmax, leaf) = start(next);
                    lane.index = next;
                    lane.walk = Walk::new();
                    lane.br = br;
                    lane.tmax = tmax;
                    lane.leaf = leaf;
                    next += 1;
                } else {
                    lane.index = usize::MAX;
                    active -= 1;
                }
            }
        }
    }
}

/// Whether this CPU can take the AVX2 (+ FMA) traversal. `APERTURE_NO_AVX2` forces the SSE2 path (to
/// compare the two, or to rule the AVX2 path out when debugging).
pub(crate) fn detect_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::env::var_os("APERTURE_NO_AVX2").is_none()
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
