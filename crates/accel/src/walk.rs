//! The traversal: the stack, the leaf visitors (closest and any hit, top level and bottom
//! level), the walk of one ray and the interleaved walk of a batch. Two walks:
//! [`ordered`] (children in entry-distance order, pops beyond `tmax` skipped; closest hits, and
//! every batch) and [`group`] (obvhs' node groups in octant order; one-ray occlusion, packets).

use crate::node::{BoxRay, Node};
use crate::triangle::TriRay;
use crate::{Accel, Blas, Entry, Hit, Ray, Tri};
use std::mem::MaybeUninit;

mod group;
mod ordered;

pub(crate) use group::take_child;
use ordered::Walk;

/// A traversal stack entry: a node group (obvhs encoding: child base index, hit mask) in the
/// group walks, a node index and the bits of its entry distance in the ordered walks.
pub(crate) type Group = (u32, u32);

/// Stacks up to this size live on the call stack (trees up to 27 levels deep); deeper trees
/// (degenerate input) get a heap stack sized from the measured depth, so the stack can never
/// overflow.
pub(crate) const INLINE_STACK: usize = 192;

/// The stack entries a walk of a tree of `depth` levels needs: in the ordered walk each node on
/// the current path pushes at most seven of its eight children (the group walks, one entry).
#[inline(always)]
pub(crate) fn stack_len(depth: usize) -> usize {
    depth.saturating_mul(7).saturating_add(1)
}

/// An uninitialised inline stack.
pub(crate) type InlineStack = [MaybeUninit<Group>; INLINE_STACK];

/// The traversal stack for a tree of `depth` levels: `inline` when it fits, else `heap` sized to
/// the depth. A plain function rather than a closure-taking one so that the query stays one
/// function after inlining (closures were separate calls per ray).
///
/// Slots start uninitialised: zeroing 48 entries per query (a `memset` call) cost about 3 % of the
/// instructions of a primary ray. The walks read a slot only below their stack pointer, that
/// is, only after writing it.
#[inline(always)]
pub(crate) fn stack_for<'a>(
    depth: usize,
    inline: &'a mut InlineStack,
    heap: &'a mut Vec<MaybeUninit<Group>>,
) -> &'a mut [MaybeUninit<Group>] {
    let len = stack_len(depth);
    if len <= INLINE_STACK {
        inline
    } else {
        *heap = vec![MaybeUninit::<Group>::uninit(); len];
        heap
    }
}

/// What [`traverse`] does with each primitive of a hit leaf. A trait with `#[inline(always)]`
/// implementations rather than a closure: the compiler left the occlusion closure as a call per
/// triangle once the traversal was inlined into the query.
pub(crate) trait Leaf {
    /// Whether the walk looks for the closest hit (nearest child first, pops beyond `tmax`
    /// skipped) rather than any hit.
    const CLOSEST: bool;
    /// Visits `primitive`; may shrink `tmax`; returns `true` to stop the traversal.
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool;
}

impl<L: Leaf> Leaf for &mut L {
    const CLOSEST: bool = L::CLOSEST;
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
    const CLOSEST: bool = true;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(entry) = self.accel.entries.get(primitive as usize) {
            let hit = self
                .accel
                .walk_entry::<AVX2, ClosestLeaf<AVX2>>(entry, self.ray, tmax, self.stack);
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
    const CLOSEST: bool = false;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, _: &mut f32) -> bool {
        let mut tmax = self.ray.tmax;
        self.accel
            .entries
            .get(primitive as usize)
            .is_some_and(|entry| {
                self.accel
                    .walk_entry::<AVX2, AnyLeaf<AVX2>>(entry, self.ray, &mut tmax, self.stack)
                    == Some(true)
            })
    }
}

/// Closest hit over a bottom-level BVH's triangles: `(triangle index, (t, u, v))`. With `AVX`
/// its triangle test takes the AVX path (`triangle::intersect`): such a leaf is only walked
/// inside the queries compiled for AVX2 (`AVX2` of the walks), as `AnyLeaf`'s.
#[derive(Clone, Copy)]
pub(crate) struct ClosestLeaf<'a, const AVX: bool> {
    pub(crate) tris: &'a [Tri],
    pub(crate) ray: TriRay,
    pub(crate) tmin: f32,
    pub(crate) best: Option<(usize, (f32, f32, f32))>,
}

impl<const AVX: bool> Leaf for ClosestLeaf<'_, AVX> {
    const CLOSEST: bool = true;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(tri) = self.tris.get(primitive as usize) {
            if let Some(h) = crate::triangle::intersect::<AVX>(&self.ray, tri, self.tmin, *tmax) {
                return self.record(primitive, h, tmax);
            }
        }
        false
    }
}

/// Any hit over a bottom-level BVH's triangles: stops at the first.
#[derive(Clone, Copy)]
pub(crate) struct AnyLeaf<'a, const AVX: bool> {
    pub(crate) tris: &'a [Tri],
    pub(crate) ray: TriRay,
    pub(crate) tmin: f32,
    /// The primitive that stopped the walk (meaningful once one has).
    pub(crate) blocker: u32,
}

impl<const AVX: bool> Leaf for AnyLeaf<'_, AVX> {
    const CLOSEST: bool = false;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        let hit = self
            .tris
            .get(primitive as usize)
            .and_then(|tri| crate::triangle::intersect::<AVX>(&self.ray, tri, self.tmin, *tmax));
        hit.is_some_and(|h| self.record(primitive, h, tmax))
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
    /// The answer for a ray that meets nothing.
    fn miss() -> Self::Answer;
    /// The primitive that stopped the walk, for leaves whose answer any stopping primitive
    /// gives alike (any hit); `None` for the others.
    fn blocker(&self) -> Option<u32>;
    /// The triangles the leaf tests, its ray's triangle-test constants and `tmin`: what a
    /// packet tests for several leaves at once ([`crate::triangle::lanes`]).
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32);
    /// Takes hit `(t, b1, b2)` of `primitive`, found by the triangle test within
    /// `[tmin, tmax]` (the rest of [`Leaf::visit`]); `true` stops the walk.
    fn record(&mut self, primitive: u32, hit: (f32, f32, f32), tmax: &mut f32) -> bool;
}

impl<'a, const AVX: bool> BlasLeaf<'a> for ClosestLeaf<'a, AVX> {
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

    #[inline(always)]
    fn miss() -> Option<Hit> {
        None
    }

    #[inline(always)]
    fn blocker(&self) -> Option<u32> {
        None
    }

    #[inline(always)]
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32) {
        (self.tris, &self.ray, self.tmin)
    }

    #[inline(always)]
    fn record(&mut self, primitive: u32, h: (f32, f32, f32), tmax: &mut f32) -> bool {
        // A tie in `t` goes to the lower primitive, so the answer does not depend on the
        // order of the visits (packets visit in another order than one ray).
        let first = self
            .best
            .is_none_or(|(best, _)| h.0 < *tmax || (primitive as usize) < best);
        if first {
            *tmax = h.0;
            self.best = Some((primitive as usize, h));
        }
        false
    }
}

impl<'a, const AVX: bool> BlasLeaf<'a> for AnyLeaf<'a, AVX> {
    type Answer = bool;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self {
            tris,
            ray,
            tmin,
            blocker: 0,
        }
    }

    #[inline(always)]
    fn answer(&self, _: &Blas, _: &Entry, stopped: bool) -> bool {
        stopped
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> bool {
        accel.occluded_impl::<AVX2>(ray)
    }

    #[inline(always)]
    fn miss() -> bool {
        false
    }

    #[inline(always)]
    fn blocker(&self) -> Option<u32> {
        Some(self.blocker)
    }

    #[inline(always)]
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32) {
        (self.tris, &self.ray, self.tmin)
    }

    #[inline(always)]
    fn record(&mut self, primitive: u32, _: (f32, f32, f32), _: &mut f32) -> bool {
        self.blocker = primitive;
        true
    }
}

/// Walks a CWBVH (obvhs layout) for `r`, calling `leaf.visit(primitive, &mut tmax)` for every
/// primitive in a hit leaf. Returns whether `leaf` stopped it. `stack` needs [`stack_len`]
/// entries for the tree's depth.
///
/// Closest hits take the ordered walk ([`ordered::traverse`]: nearest child first, children
/// beyond `tmax` skipped); occlusion keeps obvhs' group walk in octant order
/// ([`group::traverse_groups`]), which measured 3–7 % faster for one ray than the ordered walk
/// (interleaved, the ordered walk is faster for both).
#[inline(always)]
pub(crate) fn traverse<const AVX2: bool, L: Leaf>(
    nodes: &[Node],
    r: &BoxRay,
    tmax: &mut f32,
    stack: &mut [MaybeUninit<Group>],
    leaf: L,
) -> bool {
    if L::CLOSEST {
        ordered::traverse::<AVX2, L>(nodes, r, tmax, stack, leaf)
    } else {
        group::traverse_groups::<AVX2>(nodes, r, tmax, stack, leaf)
    }
}

/// Rays walked at once, interleaved, by [`Accel::intersect_batch`] and [`Accel::occluded_batch`].
/// Measured on thin-lens primary rays (`benches/`, closest hit, 1 thread): 2 and 4 gain alike
/// in tile order, 4 gains more in random order, 8 less in tile order; 6 and 8 again with the
/// steady phase of [`interleave`] on BlenderIO's diffuse and shadow rays: no gain over 4.
pub const BATCH_LANES: usize = 4;

/// The walks of an interleaved batch ([`interleave`]): how each starts and where its answer
/// goes. A trait with `#[inline(always)]` implementations rather than closures: closures do
/// not take the query's target features, and the start (the box and triangle set-ups of a
/// ray) stayed a call compiled without AVX2, returning them through the stack.
pub(crate) trait Walks<L> {
    /// Walk `i`'s box ray, `tmax` and leaf.
    fn start(&mut self, i: usize) -> (BoxRay, f32, L);
    /// Takes walk `i`'s leaf back when the walk has ended (`stopped`: the leaf stopped it).
    fn finish(&mut self, i: usize, leaf: &L, stopped: bool);
}

/// Runs walks `0..n` of `walks` over `nodes`, [`BATCH_LANES`] at a time, interleaved step by
/// step. Each ray's walk is exactly [`traverse`]'s, so the results are too; only the order of
/// work between rays changes.
///
/// Why: one ray's walk is a chain of dependent loads and tests (a node's address comes out of
/// its parent's test) that leaves most of the core idle; independent chains fill it.
#[inline(always)]
pub(crate) fn interleave<const AVX2: bool, L: Leaf + Copy>(
    nodes: &[Node],
    n: usize,
    walks: &mut impl Walks<L>,
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
    }
    // The stacks stay out of the lanes: `from_fn` builds its array and then moves it, which
    // copied four 1.5 KiB stacks per call (2 % of a render in `memmove`).
    let mut stacks: [InlineStack; BATCH_LANES] =
        [[MaybeUninit::uninit(); INLINE_STACK]; BATCH_LANES];
    let mut next = 0;
    let mut lanes: [Lane<L>; BATCH_LANES] = std::array::from_fn(|_| {
        // Lanes beyond `n` start idle, on a copy of the last ray.
        let index = if next < n { next } else { usize::MAX };
        let (br, tmax, leaf) = walks.start(next.min(n - 1));
        next += 1;
        Lane {
            index,
            walk: Walk::new(),
            br,
            tmax,
            leaf,
        }
    });
    next = next.min(n);
    // While rays remain to start, every lane walks: the four steps are written out (a macro,
    // not a loop or closure), so each lane's state sits at a fixed offset and no step checks
    // for an idle lane (9 instructions a step of the generic loop below).
    const _: () = assert!(BATCH_LANES == 4, "the steady phase steps four lanes");
    macro_rules! step_lane {
        ($k:expr) => {{
            let (lane, stack) = (&mut lanes[$k], &mut stacks[$k]);
            let done =
                lane.walk
                    .step::<AVX2, _>(nodes, &lane.br, &mut lane.tmax, stack, &mut lane.leaf);
            if let Some(stopped) = done {
                walks.finish(lane.index, &lane.leaf, stopped);
                if next < n {
                    let (br, tmax, leaf) = walks.start(next);
                    lane.index = next;
                    lane.walk = Walk::new();
                    lane.br = br;
                    lane.tmax = tmax;
                    lane.leaf = leaf;
                    next += 1;
                } else {
                    lane.index = usize::MAX;
                }
            }
        }};
    }
    // Every lane is active here: a lane goes idle only once no ray is left to start.
    while next < n {
        step_lane!(0);
        step_lane!(1);
        step_lane!(2);
        step_lane!(3);
    }
    // The last walks: lanes go idle one by one.
    let mut active = lanes.iter().filter(|l| l.index != usize::MAX).count();
    while active > 0 {
        for k in 0..BATCH_LANES {
            if lanes[k].index == usize::MAX {
                continue;
            }
            step_lane!(k);
            if lanes[k].index == usize::MAX {
                active -= 1;
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
