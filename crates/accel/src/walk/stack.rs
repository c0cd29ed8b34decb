//! The traversal stack: its entries, its size for a tree's depth, and where it lives.

use std::mem::MaybeUninit;

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
