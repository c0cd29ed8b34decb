//! A binary tree collapsed into our eight-wide [`Node`]s: obvhs' CWBVH conversion (the SAH
//! cost table of Ylitie et al. 2017, children in octant order), written straight to our nodes.
//!
//! Why not obvhs' `bvh2_to_cwbvh` and a conversion of its nodes: that quantises every child box
//! (which our nodes do not keep), allocates its cost table for every tree, and leaves a second
//! pass to gather the exact boxes. The topology, the slot order and the primitive order are
//! the same as obvhs' (a test compares every node), so images do not change.

use crate::node::Node;
use glam::Vec3A;
use obvhs::bvh2::Bvh2;

/// Cost of a primitive in a leaf against a node visit (obvhs' `PRIM_COST`).
const PRIM_COST: f32 = 0.3;

/// What a binary node becomes for one count of eight-wide slots it may fill.
#[derive(Clone, Copy, Default, PartialEq)]
enum Kind {
    /// One leaf child holding all its primitives.
    Leaf,
    /// One internal child.
    Internal,
    /// Its two children's subtrees spread over the slots.
    #[default]
    Distribute,
}

/// The cheapest way to place a binary node's subtree in `1 + i` slots (entry `i` of the
/// node's seven), the slot counts given to its children when spread, and the subtree's
/// primitive count (up to 255: only "at most 3" is asked).
#[derive(Clone, Copy, Default)]
pub(super) struct Decision {
    cost: f32,
    kind: Kind,
    left: u8,
    right: u8,
    prims: u8,
}

/// The cost table's storage, kept between trees (the pieces of a joined tree).
pub(super) type Decisions = Vec<Decision>;

/// The ray octant directions the slots are ordered by (obvhs' `direction_lut`).
const DIRECTIONS: [Vec3A; 8] = {
    const fn sign(s: usize, bit: usize) -> f32 {
        if s & bit != 0 {
            -1.0
        } else {
            1.0
        }
    }
    let mut d = [Vec3A::ZERO; 8];
    let mut s = 0;
    while s < 8 {
        d[s] = Vec3A::new(sign(s, 0b100), sign(s, 0b010), sign(s, 0b001));
        s += 1;
    }
    d
};

/// Our nodes for `bvh2` (every leaf one primitive, as PLOC builds) with leaves of up to
/// `max_prims_per_leaf` primitives (1 to 3), and the primitive order of the leaves;
/// `decisions` is the cost table's storage. An empty tree gives no nodes.
pub(super) fn collapse(
    bvh2: &Bvh2,
    max_prims_per_leaf: u32,
    decisions: &mut Decisions,
) -> (Vec<Node>, Vec<u32>) {
    if bvh2.nodes.is_empty() {
        return (Vec::new(), Vec::new());
    }
    decisions.clear();
    decisions.resize(bvh2.nodes.len() * 7, Decision::default());
    let mut c = Collapser {
        bvh2,
        decisions,
        nodes: Vec::with_capacity(bvh2.primitive_indices.len() / 2 + 1),
        order: Vec::with_capacity(bvh2.primitive_indices.len()),
    };
    c.costs(max_prims_per_leaf.clamp(1, 3));
    c.nodes.push(Node::EMPTY);
    c.emit(0, 0);
    (c.nodes, c.order)
}

struct Collapser<'a> {
    bvh2: &'a Bvh2,
    decisions: &'a mut Decisions,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Collapser<'_> {
    /// Fills the cost table. PLOC stores every child after its parent, so a walk from the last
    /// node back meets children first and reads the table in memory order (a tree that breaks
    /// this takes the recursive walk); either way each node's decisions are the same.
    fn costs(&mut self, max_prims: u32) {
        let nodes = &self.bvh2.nodes;
        let ordered = nodes
            .iter()
            .enumerate()
            .all(|(n, node)| node.prim_count != 0 || node.first_index as usize > n);
        if ordered {
            for n in (0..nodes.len()).rev() {
                self.node_cost(n, max_prims);
            }
        } else {
            self.cost(0, max_prims);
        }
    }

    /// Fills the decisions of binary node `n` and of those below it, children first.
    fn cost(&mut self, n: usize, max_prims: u32) {
        let node = &self.bvh2.nodes[n];
        if node.prim_count == 0 {
            let first = node.first_index as usize;
            self.cost(first, max_prims);
            self.cost(first + 1, max_prims);
        }
        self.node_cost(n, max_prims);
    }

    /// The seven decisions of binary node `n`, its children's filled: the same sums in the
    /// same order as obvhs' `calculate_cost_impl`.
    fn node_cost(&mut self, n: usize, max_prims: u32) {
        let node = &self.bvh2.nodes[n];
        let half_area = node.aabb().half_area();
        let d = n * 7;
        if node.prim_count != 0 {
            let leaf = Decision {
                cost: half_area * node.prim_count as f32 * PRIM_COST,
                kind: Kind::Leaf,
                prims: node.prim_count.min(255) as u8,
                ..Decision::default()
            };
            self.decisions[d..d + 7].fill(leaf);
            return;
        }
        let (a, b) = (node.first_index as usize, node.first_index as usize + 1);
        let row = |t: &[Decision], n: usize| -> [f32; 7] {
            std::array::from_fn(|k| t.get(n * 7 + k).map_or(f32::INFINITY, |d| d.cost))
        };
        let (ca, cb) = (row(self.decisions, a), row(self.decisions, b));
        let count = |n: usize| self.decisions.get(n * 7).map_or(255, |d| d.prims);
        let prims = count(a).saturating_add(count(b));
        // One slot: a leaf of everything, or an internal node spreading both children.
        let cost_leaf = if u32::from(prims) <= max_prims {
            prims as f32 * half_area * PRIM_COST
        } else {
            f32::INFINITY
        };
        let (mut spread, mut left, mut right) = (f32::INFINITY, u8::MAX, u8::MAX);
        for k in 0..7 {
            let c = ca[k] + cb[6 - k];
            if c < spread {
                (spread, left, right) = (c, k as u8, 6 - k as u8);
            }
        }
        let internal = spread + half_area;
        let (kind, cost) = if cost_leaf < internal {
            (Kind::Leaf, cost_leaf)
        } else {
            (Kind::Internal, internal)
        };
        let mut out = [Decision {
            cost,
            kind,
            left,
            right,
            prims,
        }; 7];
        // 1 + i slots: as with i slots, or the children's subtrees spread over them.
        for i in 1..7 {
            let mut best = out[i - 1].cost;
            let mut split = None;
            for k in 0..i {
                let c = ca[k] + cb[i - k - 1];
                if c < best {
                    best = c;
                    split = Some(k as u8);
                }
            }
            out[i] = match split {
                Some(k) => Decision {
                    cost: best,
                    kind: Kind::Distribute,
                    left: k,
                    right: i as u8 - k - 1,
                    prims,
                },
                None => out[i - 1],
            };
        }
        self.decisions[d..d + 7].copy_from_slice(&out);
    }

    /// The binary nodes that become the slots of the eight-wide node for binary node `n` with
    /// `1 + i` slots, appended to `children` (obvhs' `get_children`).
    fn children(&self, n: usize, i: usize, children: &mut [u32; 8], count: &mut usize) {
        let node = &self.bvh2.nodes[n];
        if node.prim_count != 0 {
            children[*count] = n as u32;
            *count += 1;
            return;
        }
        let dec = self.decisions[n * 7 + i];
        for (child, slots) in [
            (node.first_index, dec.left),
            (node.first_index + 1, dec.right),
        ] {
            let slots = usize::from(slots.min(6));
            if self.decisions[child as usize * 7 + slots].kind == Kind::Distribute {
                self.children(child as usize, slots, children, count);
            } else {
                children[*count] = child;
                *count += 1;
            }
        }
    }

    /// Puts each child in a slot by the octant its centre lies in from `n`'s (obvhs'
    /// `order_children`: greedily, the cheapest pair of a free child and a free slot first, the
    /// first in (child, slot) order on ties; a pair costing `f32::MAX` or more is never taken).
    ///
    /// Each pair is a key whose high half orders as its cost and whose low bits are its child
    /// and slot, so a round is a minimum over 64 integers without a branch on the data (the
    /// scan with a compare per pair mispredicted most of the time, and took a fifth of a
    /// build); a pick retires its child's row and its slot's column.
    fn order_slots(&self, n: usize, children: &mut [u32; 8], count: usize) {
        let p = self.bvh2.nodes[n].aabb().center();
        let mut keys = [u64::MAX; 64];
        for (c, &child) in children.iter().enumerate().take(count) {
            let v = self.bvh2.nodes[child as usize].aabb().center() - p;
            for (s, d) in DIRECTIONS.iter().enumerate() {
                // `+ 0.0`: -0 and +0 tie, as they compare equal.
                let cost = d.dot(v) + 0.0;
                if cost < f32::MAX {
                    let bits = cost.to_bits();
                    let ordered = if bits >> 31 != 0 {
                        !bits
                    } else {
                        bits | 1 << 31
                    };
                    keys[c * 8 + s] = u64::from(ordered) << 32 | (c * 8 + s) as u64;
                }
            }
        }
        let given = std::mem::replace(children, [u32::MAX; 8]);
        let mut placed = [false; 8];
        for _ in 0..count {
            // Four running minima: independent chains of conditional moves.
            let mut m = [u64::MAX; 4];
            for row in keys.chunks_exact(4) {
                for k in 0..4 {
                    m[k] = m[k].min(row[k]);
                }
            }
            let min = m[0].min(m[1]).min(m[2].min(m[3]));
            if min == u64::MAX {
                break;
            }
            let (c, s) = ((min as usize & 63) >> 3, min as usize & 7);
            children[s] = given[c];
            placed[c] = true;
            keys[c * 8..c * 8 + 8].fill(u64::MAX);
            for k in 0..8 {
                keys[k * 8 + s] = u64::MAX;
            }
        }
        // A child no slot was cheaper than `f32::MAX` for (never, for finite boxes) takes the
        // first free slot rather than being lost.
        for c in (0..count).filter(|&c| !placed[c]) {
            if let Some(free) = children.iter().position(|&x| x == u32::MAX) {
                children[free] = given[c];
            }
        }
    }

    /// Writes eight-wide node `at` for binary node `n`, then its internal children after it
    /// (obvhs' `convert_to_cwbvh_impl`, keeping the exact child boxes instead of quantising).
    fn emit(&mut self, at: usize, n: usize) {
        let mut children = [u32::MAX; 8];
        let mut count = 0;
        self.children(n, 0, &mut children, &mut count);
        self.order_slots(n, &mut children, count);
        let mut node = Node::EMPTY;
        node.primitive_base_idx = self.order.len() as u32;
        node.child_base_idx = self.nodes.len() as u32;
        let mut prims = 0u32;
        for (slot, &child) in children.iter().enumerate() {
            if child == u32::MAX {
                continue;
            }
            let b = self.bvh2.nodes[child as usize].aabb();
            for a in 0..3 {
                node.bounds[2 * a][slot] = b.min[a];
                node.bounds[2 * a + 1][slot] = b.max[a];
            }
            if self.decisions[child as usize * 7].kind == Kind::Leaf {
                let count = self.push_primitives(child as usize);
                node.child_meta[slot] = prims as u8 | ((1u8 << count.min(3)) - 1) << 5;
                prims += count;
            } else {
                node.imask |= 1 << slot;
                node.child_meta[slot] = (24 + slot as u8) | 0b0010_0000;
            }
        }
        let internal = node.imask.count_ones() as usize;
        self.nodes.resize(self.nodes.len() + internal, Node::EMPTY);
        self.nodes[at] = node;
        let mut next = node.child_base_idx as usize;
        for (slot, &child) in children.iter().enumerate() {
            if node.imask & (1 << slot) != 0 {
                self.emit(next, child as usize);
                next += 1;
            }
        }
    }

    /// Appends the primitives below binary node `n` to the order, left to right; their count.
    fn push_primitives(&mut self, n: usize) -> u32 {
        let node = self.bvh2.nodes[n];
        if node.prim_count != 0 {
            let first = node.first_index as usize;
            let range = first..first + node.prim_count as usize;
            self.order
                .extend_from_slice(&self.bvh2.primitive_indices[range]);
            return node.prim_count;
        }
        self.push_primitives(node.first_index as usize)
            + self.push_primitives(node.first_index as usize + 1)
    }
}
