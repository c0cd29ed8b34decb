//! [`Node`]: obvhs' CWBVH node with its children's boxes in floats, and (for tests) the
//! conversion from obvhs' nodes.
//!
//! Why not obvhs' 80-byte node as it is: its boxes are quantised to 8 bits relative to the
//! parent, so every node test first rebuilds them (a frame of nine values per ray and node, six
//! byte-to-float conversions), and the quantised boxes are looser than the children's, so more
//! of them are entered. The 256-byte node is Embree's BVH8 layout: six rows of eight floats, and
//! the topology obvhs built.

#[cfg(test)]
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;

/// One node of the tree: up to eight children, each an internal node or a leaf of up to three
/// primitives, in obvhs' CWBVH encoding (`child_meta`, `imask`, the two base indices), with each
/// child's box in floats.
#[derive(Clone, Copy, Debug, bytemuck::Zeroable)]
#[repr(C, align(64))]
pub(crate) struct Node {
    /// Rows `2a` and `2a + 1`: the children's box minimum and maximum along axis `a`, by slot.
    /// An empty slot holds an empty box (minimum `+inf`, maximum `-inf`) that no ray enters.
    pub bounds: [[f32; 8]; 6],
    /// Index of the first internal child in the node array; the others follow in slot order.
    pub child_base_idx: u32,
    /// Index of the first primitive of this node's leaves in the primitive order.
    pub primitive_base_idx: u32,
    /// Per slot, as obvhs: `0` for an empty slot; a leaf's first primitive offset (low 5 bits)
    /// and count in unary (top 3 bits); `24 + slot` with the top bits `001` for an internal child.
    pub child_meta: [u8; 8],
    /// Bit `c` for each internal child slot `c`.
    pub imask: u8,
}

impl Node {
    /// A node with every slot empty: each child box empty (minimum `+inf`, maximum `-inf`),
    /// which no ray enters.
    pub const EMPTY: Node = Node {
        bounds: [
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
        ],
        child_base_idx: 0,
        primitive_base_idx: 0,
        child_meta: [0; 8],
        imask: 0,
    };

    /// obvhs' `CwBvhNode::get_child_and_index_bits` of this node: per slot byte, the bits a hit
    /// child sets in the node hit mask and the index they are shifted to (for internal
    /// children, the slot XOR the ray's octant `oct_inv4`, biased by 24). It reads only
    /// `child_meta`.
    #[inline(always)]
    pub fn child_and_index_bits(&self, oct_inv4: u32) -> (u64, u64) {
        let meta = CwBvhNode {
            child_meta: self.child_meta,
            ..CwBvhNode::default()
        };
        meta.get_child_and_index_bits(oct_inv4)
    }

    /// The node index of the internal child in `slot` ([`child_index`]).
    #[inline(always)]
    pub fn child(&self, slot: u32) -> u32 {
        child_index(self.child_base_idx, u32::from(self.imask), slot)
    }

    /// The positions in the primitive order of the primitives of the leaf in `slot` (its meta
    /// byte holds the first one's offset in its low 5 bits and their count in unary in its top
    /// 3; an empty slot has none).
    #[inline(always)]
    pub fn leaf(&self, slot: usize) -> std::ops::Range<u32> {
        let meta = self.child_meta[slot & 7];
        let first = self.primitive_base_idx.wrapping_add(u32::from(meta & 0x1f));
        first..first.wrapping_add((meta >> 5).count_ones())
    }
}

/// The node index of the internal child in `slot` of a node whose first internal child is
/// `base` and whose internal slots are the low bits of `imask` (higher bits are ignored):
/// internal children are stored in slot order.
#[inline(always)]
pub(crate) fn child_index(base: u32, imask: u32, slot: u32) -> u32 {
    base.wrapping_add((imask & !(u32::MAX << slot)).count_ones())
}

/// Our nodes for obvhs' `nodes` over primitives whose boxes are `prim_boxes`, in the order
/// `primitive_indices` (the primitive order obvhs returns). Builds collapse obvhs' binary
/// trees straight to our nodes (`build::collapse`); this conversion of obvhs' own CWBVH is the
/// reference the tests hold that to. Children follow their parent in
/// obvhs' array, so the boxes are gathered from the last node back; an index out of range
/// (never so for obvhs' trees) leaves that child's box empty.
#[cfg(test)]
pub(crate) fn nodes_from_cwbvh(
    nodes: &[CwBvhNode],
    primitive_indices: &[u32],
    prim_boxes: &[Aabb],
) -> Vec<Node> {
    let empty = Node::EMPTY;
    let mut out = vec![empty; nodes.len()];
    // Each node's own box, as its parent's row entries need it.
    let mut own = vec![Aabb::empty(); nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        let mut node = Node {
            child_base_idx: n.child_base_idx,
            primitive_base_idx: n.primitive_base_idx,
            child_meta: n.child_meta,
            imask: n.imask,
            ..empty
        };
        let mut total = Aabb::empty();
        for slot in 0..8 {
            let b = if n.child_meta[slot] == 0 {
                continue;
            } else if n.imask & (1 << slot) != 0 {
                let child = node.child(slot as u32) as usize;
                own.get(child).copied().unwrap_or_else(Aabb::empty)
            } else {
                node.leaf(slot).fold(Aabb::empty(), |acc, p| {
                    primitive_indices
                        .get(p as usize)
                        .and_then(|&p| prim_boxes.get(p as usize))
                        .map_or(acc, |b| acc.union(b))
                })
            };
            for a in 0..3 {
                node.bounds[2 * a][slot] = b.min[a];
                node.bounds[2 * a + 1][slot] = b.max[a];
            }
            total = total.union(&b);
        }
        own[i] = total;
        out[i] = node;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;
    use obvhs::{cwbvh::builder::build_cwbvh, BvhBuildParams};
    use std::time::Duration;

    /// 700 scattered boxes far from the origin, obvhs' tree over them, and our nodes of it.
    fn sample_tree() -> (Vec<Aabb>, obvhs::cwbvh::CwBvh, Vec<Node>) {
        let mut s = 3u32;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        let boxes: Vec<Aabb> = (0..700)
            .map(|_| {
                let c = Vec3A::new(next(), next(), next()) * 50.0 + 1e4;
                let h = Vec3A::new(next(), next(), next());
                Aabb::new(c - h, c + h)
            })
            .collect();
        let cw = build_cwbvh(
            &boxes,
            BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        let nodes = nodes_from_cwbvh(&cw.nodes, &cw.primitive_indices, &boxes);
        (boxes, cw, nodes)
    }

    /// The primitives below node `i`, by a walk of its own; checks on the way that each child
    /// box is exactly the union of the primitive boxes below it.
    fn below(nodes: &[Node], order: &[u32], boxes: &[Aabb], i: usize) -> Aabb {
        let n = &nodes[i];
        let mut b = Aabb::empty();
        for slot in 0..8 {
            let meta = n.child_meta[slot];
            if meta == 0 {
                continue;
            }
            // Decoded here on its own, not with `Node::child`/`Node::leaf`: the check of them.
            let child = if n.imask & (1 << slot) != 0 {
                let rank = (n.imask as u32 & ((1 << slot) - 1)).count_ones();
                below(nodes, order, boxes, (n.child_base_idx + rank) as usize)
            } else {
                let first = n.primitive_base_idx + u32::from(meta & 0x1f);
                (0..(meta >> 5).count_ones()).fold(Aabb::empty(), |acc, k| {
                    acc.union(&boxes[order[(first + k) as usize] as usize])
                })
            };
            let row = |a: usize| (n.bounds[2 * a][slot], n.bounds[2 * a + 1][slot]);
            for a in 0..3 {
                assert_eq!(row(a), (child.min[a], child.max[a]), "node {i} slot {slot}");
            }
            b = b.union(&child);
        }
        b
    }

    /// Every child box is the union of the primitive boxes below it, exactly.
    #[test]
    fn child_boxes_are_the_unions_of_their_primitives() {
        let (boxes, cw, nodes) = sample_tree();
        assert_eq!(nodes.len(), cw.nodes.len());
        assert_eq!(std::mem::size_of::<Node>(), 256);
        let all = below(&nodes, &cw.primitive_indices, &boxes, 0);
        let want = boxes.iter().fold(Aabb::empty(), |acc, b| acc.union(b));
        assert_eq!((all.min, all.max), (want.min, want.max));
    }

    /// Every child box holds inside obvhs' quantised box of the same child (up to the rounding
    /// its quantiser does not cover), and empty slots hold empty boxes.
    #[test]
    fn child_boxes_hold_inside_the_quantised_boxes() {
        let (_, cw, nodes) = sample_tree();
        let mut empty_slots = 0;
        for (n, q) in nodes.iter().zip(&cw.nodes) {
            for slot in 0..8 {
                if q.child_meta[slot] == 0 {
                    empty_slots += 1;
                    assert!(n.bounds[0][slot] > n.bounds[1][slot]);
                    continue;
                }
                let e = q.e.map(|e| f32::from_bits((e as u32) << 23));
                let qb = [
                    (q.child_min_x[slot], q.child_max_x[slot]),
                    (q.child_min_y[slot], q.child_max_y[slot]),
                    (q.child_min_z[slot], q.child_max_z[slot]),
                ];
                for a in 0..3 {
                    let lo = q.p[a] + qb[a].0 as f32 * e[a];
                    let hi = q.p[a] + qb[a].1 as f32 * e[a];
                    let tol = (255.0 * e[a] + q.p[a].abs()) * 2.0 * f32::EPSILON;
                    assert!(
                        n.bounds[2 * a][slot] >= lo - tol,
                        "node slot {slot} axis {a}"
                    );
                    assert!(
                        n.bounds[2 * a + 1][slot] <= hi + tol,
                        "node slot {slot} axis {a}"
                    );
                }
            }
        }
        assert!(empty_slots > 0);
    }
}
