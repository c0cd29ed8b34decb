//! A binary tree collapsed into our eight-wide [`Node`]s: obvhs' CWBVH conversion (the SAH
//! cost table of Ylitie et al. 2017, children in octant order), written straight to our nodes.
//!
//! Why not obvhs' `bvh2_to_cwbvh` and a conversion of its nodes: that quantises every child box
//! (which our nodes do not keep), allocates its cost table for every tree, and leaves a second
//! pass to gather the exact boxes. The topology, the slot order and the primitive order are
//! the same as obvhs' (a test compares every node), so images do not change.

use crate::node::Node;
use crate::prefetch::prefetch;
use glam::Vec3A;
use obvhs::bvh2::Bvh2;

/// Cost of a primitive in a leaf against a node visit (obvhs' `PRIM_COST`).
const PRIM_COST: f32 = 0.3;

/// What a binary node becomes for one count of eight-wide slots it may fill.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// One leaf child holding all its primitives.
    Leaf,
    /// One internal child.
    Internal,
    /// Its two children's subtrees spread over the slots.
    Distribute,
}

/// The cheapest way to place a binary node's subtree in `1 + i` slots, packed in a byte (entry
/// `i` of the node's [`Plan`]): its [`Kind`] and the slot counts given to its children when
/// spread (3 bits each; 7 stands for "none found", read as 6 as obvhs reads `u8::MAX`).
#[derive(Clone, Copy, PartialEq)]
struct Choice(u8);

impl Choice {
    const LEAF: Self = Self(0);

    fn new(kind: Kind, left: u8, right: u8) -> Self {
        Self(kind as u8 | left.min(7) << 2 | right.min(7) << 5)
    }

    fn kind(self) -> Kind {
        match self.0 & 3 {
            0 => Kind::Leaf,
            1 => Kind::Internal,
            _ => Kind::Distribute,
        }
    }

    /// Slots (minus one) for the first and the second child.
    fn split(self) -> (usize, usize) {
        (usize::from(self.0 >> 2 & 7), usize::from(self.0 >> 5))
    }
}

/// What the emit reads of a binary node, 16 bytes (two siblings share a cache line): its
/// children (or primitives), its primitive count (0: internal) and its seven choices. The walk
/// down from a node to the slots of its eight-wide node is a chain of dependent reads; with the
/// links apart from obvhs' nodes and the costs, each step is one miss, not two.
#[derive(Clone, Copy)]
struct Link {
    first: u32,
    prim_count: u32,
    plan: [Choice; 8],
}

/// The cost table's storage, kept between trees (the pieces of a joined tree): per binary node,
/// the cost of each slot count, the subtree's primitive count (up to 255: only "at most 3" is
/// asked; 0 until the node's decisions are filled) and its [`Link`].
#[derive(Default)]
pub(super) struct Decisions {
    costs: Vec<[f32; 7]>,
    prims: Vec<u8>,
    links: Vec<Link>,
}

impl Decisions {
    pub(super) fn new() -> Self {
        Self::default()
    }

    fn reset(&mut self, n: usize) {
        self.costs.clear();
        self.costs.resize(n, [0.0; 7]);
        self.prims.clear();
        self.prims.resize(n, 0);
        self.links.clear();
        self.links.resize(
            n,
            Link {
                first: 0,
                prim_count: 0,
                plan: [Choice::LEAF; 8],
            },
        );
    }

    /// Node `n`'s choice for `1 + i` slots.
    #[inline]
    fn choice(&self, n: usize, i: usize) -> Choice {
        self.links[n].plan[i]
    }
}

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
    decisions.reset(bvh2.nodes.len());
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
    /// Fills the cost table from the last node back. PLOC stores every child after its
    /// parent, so the walk meets children first and reads the table in memory order; a child
    /// that reinsertion moved before its parent is filled first, when the parent asks for it
    /// (a node's primitive count is 0 until its decisions are filled). Each node's decisions
    /// are those of a children-first walk from the root.
    fn costs(&mut self, max_prims: u32) {
        // The children's rows are far from their parent's: ask for them some nodes ahead.
        const AHEAD: usize = 16;
        let nodes = &self.bvh2.nodes;
        for n in (0..nodes.len()).rev() {
            if let Some(ahead) = n.checked_sub(AHEAD).map(|k| &nodes[k]) {
                let first = ahead.first_index as usize;
                if ahead.prim_count == 0 {
                    prefetch(self.decisions.costs.as_ptr().wrapping_add(first));
                    prefetch(self.decisions.costs.as_ptr().wrapping_add(first + 1));
                    prefetch(self.decisions.prims.as_ptr().wrapping_add(first));
                }
            }
            self.cost(n, max_prims);
        }
    }

    /// Fills the decisions of binary node `n` and of those below it not filled yet, children
    /// first.
    fn cost(&mut self, n: usize, max_prims: u32) {
        if self.decisions.prims[n] != 0 {
            return;
        }
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
        let t = &mut *self.decisions;
        if node.prim_count != 0 {
            t.costs[n] = [half_area * node.prim_count as f32 * PRIM_COST; 7];
            t.prims[n] = node.prim_count.min(255) as u8;
            t.links[n] = Link {
                first: node.first_index,
                prim_count: node.prim_count,
                plan: [Choice::LEAF; 8],
            };
            return;
        }
        let (a, b) = (node.first_index as usize, node.first_index as usize + 1);
        let row = |n: usize| t.costs.get(n).copied().unwrap_or([f32::INFINITY; 7]);
        let (ca, cb) = (row(a), row(b));
        let count = |n: usize| t.prims.get(n).copied().unwrap_or(255);
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
        let mut costs = [cost; 7];
        let mut plan = [Choice::new(kind, left, right); 8];
        // 1 + i slots: as with i slots, or the children's subtrees spread over them.
        for i in 1..7 {
            let mut best = costs[i - 1];
            let mut split = None;
            for k in 0..i {
                let c = ca[k] + cb[i - k - 1];
                if c < best {
                    best = c;
                    split = Some(k as u8);
                }
            }
            (costs[i], plan[i]) = match split {
                Some(k) => (best, Choice::new(Kind::Distribute, k, i as u8 - k - 1)),
                None => (costs[i - 1], plan[i - 1]),
            };
        }
        t.costs[n] = costs;
        t.prims[n] = prims;
        t.links[n] = Link {
            first: node.first_index,
            prim_count: 0,
            plan,
        };
    }

    /// The binary nodes that become the slots of the eight-wide node for binary node `n` with
    /// `1 + i` slots, appended to `children` (obvhs' `get_children`).
    fn children(&self, n: usize, i: usize, children: &mut [u32; 8], count: &mut usize) {
        let link = &self.decisions.links[n];
        if link.prim_count != 0 {
            children[*count] = n as u32;
            *count += 1;
            return;
        }
        let (left, right) = link.plan[i].split();
        let links = &self.decisions.links;
        let spread = [(link.first, left), (link.first + 1, right)].map(|(child, slots)| {
            let slots = slots.min(6);
            let c = &links[child as usize];
            let spread = c.plan[slots].kind() == Kind::Distribute;
            // Whatever the child becomes, its children (or primitives) are read next: ask for
            // them now, so that the second's arrive while the first's are walked.
            if c.prim_count == 0 {
                prefetch(links.as_ptr().wrapping_add(c.first as usize));
            } else {
                prefetch(
                    self.bvh2
                        .primitive_indices
                        .as_ptr()
                        .wrapping_add(c.first as usize),
                );
            }
            (child, slots, spread)
        });
        for (child, slots, spread) in spread {
            if spread {
                self.children(child as usize, slots, children, count);
            } else {
                // Its box is read when the slots are ordered: ask for it now.
                prefetch(self.bvh2.nodes.as_ptr().wrapping_add(child as usize));
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
            if self.decisions.choice(child as usize, 0).kind() == Kind::Leaf {
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
        let link = self.decisions.links[n];
        if link.prim_count != 0 {
            let first = link.first as usize;
            let range = first..first + link.prim_count as usize;
            self.order
                .extend_from_slice(&self.bvh2.primitive_indices[range]);
            return link.prim_count;
        }
        self.push_primitives(link.first as usize) + self.push_primitives(link.first as usize + 1)
    }
}
