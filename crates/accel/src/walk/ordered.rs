//! The walk in entry-distance order: nearest child first and pops beyond `tmax` skipped for
//! closest hits, one-ray and interleaved.

use super::leaf::Leaf;
use super::stack::Group;
use crate::node::{child_index, BoxRay, ChildHits, Node};
use std::mem::MaybeUninit;

/// A walk of a tree of [`Node`]s in progress: the traversal of one ray as a state that
/// advances one node at a time, so that several rays' walks can be interleaved on one thread
/// (see [`crate::Accel::intersect_batch`]). [`traverse`] runs one walk to its end.
///
/// Each step visits the primitives of the last tested node's hit leaves, moves to one of its hit
/// internal children (pushing the others with their entry distances) or pops one, and tests that
/// node. For closest hits ([`Leaf::CLOSEST`]) it moves to the nearest child, and children whose
/// entry lies beyond the ray's current `tmax` are skipped, when pushed or popped (a hit found
/// since lies in front of all of them). What a node test yields is used only by the next step:
/// no branch depends on the node just loaded, so an interleaved batch keeps the other rays'
/// work in flight while that load completes.
#[derive(Clone, Copy)]
pub(crate) struct Walk {
    sp: usize,
    /// The last tested node's hit leaves' primitives, as bits above `prim_base`.
    prims: u32,
    prim_base: u32,
    /// The last tested node's hit internal children (slot bits), `imask` and first child.
    inner: u32,
    imask: u32,
    child_base: u32,
    /// The `tmax` the last node was tested with.
    tested: f32,
    /// The last tested node's entry distance per slot.
    enter: [f32; 8],
}

impl Walk {
    /// A walk from the root (as the one internal child, slot 0, of a node before it).
    #[inline(always)]
    pub(super) fn new() -> Self {
        let mut enter = [f32::INFINITY; 8];
        enter[0] = f32::NEG_INFINITY;
        Self {
            sp: 0,
            prims: 0,
            prim_base: 0,
            inner: 1,
            imask: 1,
            child_base: 0,
            tested: f32::INFINITY,
            enter,
        }
    }

    /// Visits the primitives of the last tested node's hit leaves
    /// (`leaf.visit(primitive, &mut tmax)` each), then moves to the next node and tests it.
    /// `Some(stopped)` once the walk has ended, where `stopped` says whether `leaf` stopped it.
    ///
    /// With `AVX2` it must be inlined into a function compiled for AVX2 (`Accel::intersect_avx2`
    /// and its kin), so that the node test and the bit operations become inline instructions.
    #[inline(always)]
    pub(super) fn step<const AVX2: bool, L: Leaf>(
        &mut self,
        nodes: &[Node],
        r: &BoxRay,
        tmax: &mut f32,
        stack: &mut [MaybeUninit<Group>],
        leaf: &mut L,
    ) -> Option<bool> {
        while self.prims != 0 {
            let k = self.prims.trailing_zeros();
            self.prims &= self.prims - 1;
            if leaf.visit(self.prim_base.wrapping_add(k), tmax) {
                return Some(true);
            }
        }
        let mut inner = self.inner;
        if L::CLOSEST && *tmax < self.tested {
            inner = within(inner, &self.enter, *tmax);
        }
        let index = if inner == 0 {
            let Some(index) = pop::<L>(stack, &mut self.sp, *tmax) else {
                return Some(false);
            };
            index
        } else {
            let children = Children {
                inner,
                imask: self.imask,
                base: self.child_base,
                enter: &self.enter,
            };
            children.descend::<L>(stack, &mut self.sp)
        };
        let Some(node) = nodes.get(index as usize) else {
            // Unreachable for a well-formed tree; never read out of bounds.
            return Some(false);
        };
        let hits = child_hits::<AVX2>(node, r, *tmax);
        self.imask = u32::from(node.imask);
        self.inner = hits.hits & self.imask;
        self.child_base = node.child_base_idx;
        self.prims = hits.prims;
        self.prim_base = node.primitive_base_idx;
        // Occlusion reads neither (its order ignores distances, its `tmax` never shrinks).
        if L::CLOSEST {
            self.tested = *tmax;
            self.enter = hits.enter;
        }
        None
    }
}

/// A tested node's hit internal children.
struct Children<'a> {
    /// Slot bits (not empty).
    inner: u32,
    /// The node's `imask` and `child_base_idx`.
    imask: u32,
    base: u32,
    /// Entry distance per slot.
    enter: &'a [f32; 8],
}

impl Children<'_> {
    /// Pushes all but one child on `stack` at `sp`, with their entry distances, and returns the
    /// node index of that one (the nearest for closest hits).
    #[inline(always)]
    fn descend<L: Leaf>(&self, stack: &mut [MaybeUninit<Group>], sp: &mut usize) -> u32 {
        let next = if L::CLOSEST {
            nearest(self.inner, self.enter)
        } else {
            self.inner.trailing_zeros()
        };
        let mut rest = self.inner & !(1 << next);
        if L::CLOSEST && rest & rest.wrapping_sub(1) != 0 {
            self.push_sorted(rest, stack, sp);
        } else {
            while rest != 0 {
                let c = rest.trailing_zeros();
                rest &= rest - 1;
                let enter = if L::CLOSEST {
                    self.enter[c as usize & 7].to_bits()
                } else {
                    0
                };
                let entry = (self.index(c), enter);
                stack[*sp] = MaybeUninit::new(entry);
                *sp += 1;
            }
        }
        self.index(next)
    }

    /// Pushes the children of `rest` farthest entry first, so that the nearest pops first.
    #[inline(always)]
    fn push_sorted(&self, mut rest: u32, stack: &mut [MaybeUninit<Group>], sp: &mut usize) {
        let mut sorted = [(0u32, 0f32); 8];
        let mut n = 0;
        while rest != 0 {
            let c = rest.trailing_zeros();
            rest &= rest - 1;
            let e = self.enter[c as usize & 7];
            let mut j = n;
            while j > 0 && sorted[j - 1].1 < e {
                sorted[j] = sorted[j - 1];
                j -= 1;
            }
            sorted[j] = (self.index(c), e);
            n += 1;
        }
        for &(node, e) in &sorted[..n] {
            stack[*sp] = MaybeUninit::new((node, e.to_bits()));
            *sp += 1;
        }
    }

    /// The node index of slot `c`.
    #[inline(always)]
    fn index(&self, c: u32) -> u32 {
        child_index(self.base, self.imask, c)
    }
}

/// The last pushed node (for closest hits, the last one whose entry is within `tmax`), taken off
/// `stack` (`sp` entries); `None` when none is left.
#[inline(always)]
fn pop<L: Leaf>(stack: &[MaybeUninit<Group>], sp: &mut usize, tmax: f32) -> Option<u32> {
    while *sp > 0 {
        *sp -= 1;
        // SAFETY: slots below `sp` were written by a push before `sp` passed them (`sp` only
        // grows right after a write), so slot `sp` holds an initialised entry.
        let (node, enter) = unsafe { stack[*sp].assume_init() };
        if !L::CLOSEST || f32::from_bits(enter) <= tmax {
            return Some(node);
        }
    }
    None
}

/// The node test of the walk: AVX2 or SSE2 (x86-64), NEON or scalar (aarch64).
#[inline(always)]
fn child_hits<const AVX2: bool>(node: &Node, r: &BoxRay, tmax: f32) -> ChildHits {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is true only when `detect_avx2` found AVX2 and FMA on this CPU.
        return unsafe { crate::node::child_hits_enter_avx2(node, r, tmax) };
    }
    #[cfg(target_arch = "aarch64")]
    if AVX2 {
        // NEON is baseline on aarch64; `AVX2` there means the SIMD path (`detect_avx2`).
        return crate::node::neon::child_hits_enter_neon(node, r, tmax);
    }
    crate::node::child_hits_enter(node, r, tmax)
}

/// The slots of `slots` whose entry is within `tmax`.
#[inline(always)]
fn within(mut slots: u32, enter: &[f32; 8], tmax: f32) -> u32 {
    let mut kept = 0;
    while slots != 0 {
        let c = slots.trailing_zeros();
        slots &= slots - 1;
        if enter[c as usize & 7] <= tmax {
            kept |= 1 << c;
        }
    }
    kept
}

/// The slot of `slots` (not empty) with the smallest entry (the lowest slot among equals).
#[inline(always)]
fn nearest(slots: u32, enter: &[f32; 8]) -> u32 {
    let mut best = slots.trailing_zeros();
    let mut d = enter[best as usize & 7];
    let mut rest = slots & slots.wrapping_sub(1);
    while rest != 0 {
        let c = rest.trailing_zeros();
        rest &= rest - 1;
        let e = enter[c as usize & 7];
        if e < d {
            d = e;
            best = c;
        }
    }
    best
}

/// Walks a tree of [`Node`]s for `r`, calling `leaf.visit(primitive, &mut tmax)` for every
/// primitive in a hit leaf (nearest child first for closest hits, see [`Walk`]). Returns whether
/// `leaf` stopped it. `stack` needs [`super::stack_len`] entries for the tree's depth.
///
/// The same walk as [`Walk::step`]'s, as one loop that acts on each node test at once: alone,
/// a ray gains nothing from deferring (measured: 4–10 % slower on closest hits).
#[inline(always)]
pub(super) fn traverse<const AVX2: bool, L: Leaf>(
    nodes: &[Node],
    r: &BoxRay,
    tmax: &mut f32,
    stack: &mut [MaybeUninit<Group>],
    mut leaf: L,
) -> bool {
    let mut sp = 0;
    let mut index = 0;
    // An empty tree ends here too.
    while let Some(node) = nodes.get(index as usize) {
        let tested = *tmax;
        let hits = child_hits::<AVX2>(node, r, tested);
        let imask = u32::from(node.imask);
        // The hit leaves one by one rather than `hits.prims` (whose lane-wise encoding adds
        // latency before the first triangle; measured 3–5 % slower here).
        let mut leaves = hits.hits & !imask;
        while leaves != 0 {
            let prims = node.leaf(leaves.trailing_zeros() as usize);
            leaves &= leaves - 1;
            for p in prims {
                if leaf.visit(p, tmax) {
                    return true;
                }
            }
        }
        let mut inner = hits.hits & imask;
        if L::CLOSEST && *tmax < tested {
            inner = within(inner, &hits.enter, *tmax);
        }
        index = if inner == 0 {
            let Some(index) = pop::<L>(stack, &mut sp, *tmax) else {
                return false;
            };
            index
        } else {
            let first = Children {
                inner,
                imask,
                base: node.child_base_idx,
                enter: &hits.enter,
            };
            first.descend::<L>(stack, &mut sp)
        };
    }
    false
}
