//! The walk of node groups in obvhs' octant order (its traversal, with our box test): the
//! one-ray occlusion queries and the packets' walk.

use super::leaf::Leaf;
use super::stack::Group;

use crate::node::{child_index, BoxRay, Node};
use std::mem::MaybeUninit;

/// A walk of a tree of [`Node`]s in progress, front to back in obvhs' octant order: the
/// traversal of one ray as a state that advances one step at a time (the walk batches took
/// before the ordered walk). [`traverse_groups`] runs one walk to its end.
///
/// Each stack entry holds the unvisited siblings of one level of the current path, so the stack
/// needs one entry per tree level (the depth measured at build time).
#[derive(Clone, Copy)]
pub(crate) struct GroupWalk {
    sp: usize,
    current: Group,
    prims: Group,
}

impl GroupWalk {
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
        nodes: &[Node],
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
            let (index, _) = take_child(&mut self.current, stack, &mut self.sp, r.oct_inv4 & 0xff);
            let Some(node) = nodes.get(index as usize) else {
                // Unreachable for a well-formed tree (and for an empty one, whose root group is
                // never read); never read out of bounds.
                self.current.1 = 0;
                return None;
            };
            let mask = node_mask::<AVX2>(node, r, *tmax);
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

/// The node test of the group walk: AVX2 (x86-64) or NEON (aarch64) with `AVX2`, else SSE2 or
/// scalar.
#[inline(always)]
fn node_mask<const AVX2: bool>(node: &Node, r: &BoxRay, tmax: f32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is true only when `detect_avx2` found AVX2 on this CPU.
        return unsafe { crate::node::intersect_node_avx2(node, r, tmax) };
    }
    #[cfg(target_arch = "aarch64")]
    if AVX2 {
        // NEON is baseline on aarch64; `AVX2` there means the SIMD path (`detect_avx2`).
        return crate::node::neon::intersect_node_neon(node, r, tmax);
    }
    crate::node::intersect_node(node, r, tmax)
}

/// Takes the next internal child of the node group `current` (obvhs' priority order for the
/// octant key `oct`) and returns its node index and its slot in its parent; the group's other
/// children, if any, are pushed on `stack` at `sp`. Shared by the one-ray walk and the packets'
/// walk.
#[inline(always)]
pub(crate) fn take_child(
    current: &mut Group,
    stack: &mut [MaybeUninit<Group>],
    sp: &mut usize,
    oct: u32,
) -> (u32, u32) {
    let hits = current.1;
    let offset = 31 - hits.leading_zeros();
    current.1 &= !(1u32 << offset);
    if current.1 & 0xff00_0000 != 0 {
        stack[*sp] = MaybeUninit::new(*current);
        *sp += 1;
    }
    let slot = (offset - 24) ^ oct;
    // The low byte of a group's bits is its node's `imask`.
    (child_index(current.0, hits, slot), slot)
}

/// Walks a tree of [`Node`]s in obvhs' octant order for `r`, calling
/// `leaf.visit(primitive, &mut tmax)` for every primitive in a hit leaf. Returns whether `leaf`
/// stopped it. `stack` needs one entry per tree level.
#[inline(always)]
pub(crate) fn traverse_groups<const AVX2: bool>(
    nodes: &[Node],
    r: &BoxRay,
    tmax: &mut f32,
    stack: &mut [MaybeUninit<Group>],
    mut leaf: impl Leaf,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let mut walk = GroupWalk::new();
    loop {
        if let Some(stopped) = walk.step::<AVX2>(nodes, r, tmax, stack, &mut leaf) {
            return stopped;
        }
    }
}
