//! The 4-wide tree from the binary one: each wide node takes a binary node's children, or,
//! for an inner child, that child's two children (pbrt-style BVH collapsing), so the wide tree
//! has half the levels and its nodes bound what the binary nodes bounded.

use super::build::Binary;
use super::tree::{Leaf, LightTree};
use super::wide::{Wide, LEAF_BIT};
use aperture_scene::{Light, LightKind};

impl LightTree {
    /// The wide tree of `binary` (not empty), whose punctual leaves index `lights`; the
    /// caller fills in the lights' leaves and the directional lights.
    pub(super) fn collapse(binary: Binary, lights: &[Light]) -> Self {
        let mut tree = Self {
            root: binary.nodes[0].bounds,
            nodes: Vec::with_capacity(binary.nodes.len() / 3 + 1),
            parents: Vec::with_capacity(binary.nodes.len() / 3 + 1),
            leaves: Vec::new(),
            leaf_at: vec![(u32::MAX, 0); binary.leaves.len()],
            punctual_leaf: Vec::new(),
            triangle_leaf: Vec::new(),
            directional: Vec::new(),
        };
        // A tree of one light: a wide root with that leaf alone.
        let root = if binary.nodes[0].leaf {
            Lanes::one(0)
        } else {
            Lanes::of(&binary, 0)
        };
        tree.wide(&binary, lights, &root, (u32::MAX, 0));
        tree.leaves = binary.leaves;
        tree
    }

    /// Appends the wide node of binary nodes `lanes` below `parent` (node, lane), and its
    /// subtree depth first; returns its index.
    fn wide(&mut self, binary: &Binary, lights: &[Light], lanes: &Lanes, parent: (u32, u8)) -> u32 {
        let at = self.nodes.len() as u32;
        self.nodes.push(Wide::new(&[], 0));
        self.parents.push(parent);
        let mut children = Vec::with_capacity(4);
        let mut spots = 0u8;
        for (k, &b) in lanes.as_slice().iter().enumerate() {
            let node = &binary.nodes[b];
            let child = if node.leaf {
                let leaf = node.second;
                self.leaf_at[leaf as usize] = (at, k as u8);
                if is_spot(binary.leaves[leaf as usize], lights) {
                    spots |= 1 << k;
                }
                leaf | LEAF_BIT
            } else {
                self.wide(binary, lights, &Lanes::of(binary, b), (at, k as u8))
            };
            children.push((node.bounds, child));
        }
        self.nodes[at as usize] = Wide::new(&children, spots);
        at
    }
}

/// The binary nodes a wide node holds, two to four.
struct Lanes {
    nodes: [usize; 4],
    len: usize,
}

impl Lanes {
    fn one(node: usize) -> Self {
        Self {
            nodes: [node, 0, 0, 0],
            len: 1,
        }
    }

    /// The lanes of inner binary node `at`: each child, or an inner child's two children.
    fn of(binary: &Binary, at: usize) -> Self {
        let mut lanes = Self {
            nodes: [0; 4],
            len: 0,
        };
        for c in [at + 1, binary.nodes[at].second as usize] {
            let node = &binary.nodes[c];
            let picked = if node.leaf {
                [Some(c), None]
            } else {
                [Some(c + 1), Some(node.second as usize)]
            };
            for b in picked.into_iter().flatten() {
                lanes.nodes[lanes.len] = b;
                lanes.len += 1;
            }
        }
        lanes
    }

    fn as_slice(&self) -> &[usize] {
        &self.nodes[..self.len]
    }
}

/// Whether `leaf` is a spot light (weighed exactly: its cone's falloff is no bound's).
fn is_spot(leaf: Leaf, lights: &[Light]) -> bool {
    match leaf {
        Leaf::Punctual(l) => lights
            .get(l as usize)
            .is_some_and(|l| matches!(l.kind, LightKind::Spot { .. })),
        Leaf::Triangle(_) => false,
    }
}
