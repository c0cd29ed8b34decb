//! The traversal: the stack, the leaf visitors (closest and any hit, top level and bottom
//! level), the walk of one ray and the interleaved walk of a batch. Two walks:
//! [`ordered`] (children in entry-distance order, pops beyond `tmax` skipped; closest hits, and
//! every batch) and [`group`] (obvhs' node groups in octant order; one-ray occlusion, packets).

use crate::node::{BoxRay, Node};
use std::mem::MaybeUninit;

mod group;
mod leaf;
mod ordered;
mod stack;

#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) use group::take_child;
pub(crate) use leaf::{
    AnyLeaf, BlasLeaf, ClosestLeaf, EntriesAny, EntriesBlocker, EntriesClosest, Leaf,
};
use ordered::Walk;
pub(crate) use stack::{stack_for, stack_len, Group, InlineStack, INLINE_STACK};

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

/// One lane of [`interleave`]. Lanes are updated in place (no moves of whole lanes), and idle
/// ones are marked by their index: both faster than `Option`s of lanes.
struct Lane<L> {
    /// The ray walked, or `usize::MAX` when the lane is idle.
    index: usize,
    walk: Walk,
    br: BoxRay,
    tmax: f32,
    leaf: L,
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
///
/// On aarch64 the same flag selects the NEON kernels (baseline there, so always available):
/// `APERTURE_NO_AVX2` forces the scalar path, the one other targets take (to measure NEON
/// against it on one binary, or to rule NEON out when debugging).
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
    #[cfg(target_arch = "aarch64")]
    {
        std::env::var_os("APERTURE_NO_AVX2").is_none()
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        false
    }
}
