//! The descent: from the root, a child in proportion to its importance at the vertex, down to
//! one leaf; and the same choices' probabilities gathered again from a leaf's ancestors.

use super::tree::{Leaf, LightTree};
use super::wide::{self, Wide, LEAF_BIT};
use crate::light_choice::punctual_importance;
use aperture_scene::Light;
use glam::Vec3;

/// Levels a leaf's probability can gather: the wide tree has at most half the binary tree's
/// levels, which stay below 64 ([`super::split`]).
const MAX_DEPTH: usize = 64;

/// Where the descent is: the point, its normal on the side light is received from, and
/// whether light from both sides counts.
#[derive(Debug, Clone, Copy)]
pub(super) struct Receiver<'a> {
    pub lights: &'a [Light],
    pub p: Vec3,
    pub n: Vec3,
    pub two_sided: bool,
}

impl LightTree {
    /// The importances of a node's four children at the receiver: their bounds', a spot
    /// light's leaf its exact irradiance.
    #[inline]
    fn weights(&self, node: &Wide, r: &Receiver<'_>) -> [f32; 4] {
        let mut w = node.importance(r.p, r.n, r.two_sided).to_array();
        if node.spots != 0 {
            for (k, wk) in w.iter_mut().enumerate() {
                if node.spots >> k & 1 == 1 {
                    *wk = self.exact(node.children[k], r);
                }
            }
        }
        w
    }

    /// The exact importance of a punctual light's leaf (child code `child`).
    fn exact(&self, child: u32, r: &Receiver<'_>) -> f32 {
        match self.leaves.get((child & !LEAF_BIT) as usize) {
            Some(Leaf::Punctual(l)) => r.lights.get(*l as usize).map_or(0.0, |light| {
                punctual_importance(light, r.p, r.n, r.two_sided)
            }),
            _ => 0.0,
        }
    }

    /// The importance of the whole tree at the receiver.
    pub(super) fn root_importance(&self, r: &Receiver<'_>) -> f32 {
        self.root.importance(r.p, r.n, r.two_sided)
    }

    /// One leaf for the receiver from the uniform `u`: the leaf's index, its probability
    /// given the tree, and `u` remapped; `None` when no leaf can light the receiver.
    pub(super) fn descend(&self, r: &Receiver<'_>, mut u: f32) -> Option<(usize, f32, f32)> {
        let mut at = 0usize;
        let mut probability = 1.0f32;
        for _ in 0..MAX_DEPTH {
            let node = self.nodes.get(at)?;
            let (k, pk, next) = wide::choose(self.weights(node, r), u)?;
            probability *= pk;
            u = next;
            if probability <= 0.0 {
                return None;
            }
            let child = node.children[k];
            if child & LEAF_BIT != 0 {
                return Some(((child & !LEAF_BIT) as usize, probability, u));
            }
            at = child as usize;
        }
        None
    }

    /// The probability that [`LightTree::descend`] reaches `leaf` at the receiver: the same
    /// choices' probabilities, multiplied in the descent's order.
    pub(super) fn leaf_probability(&self, r: &Receiver<'_>, leaf: usize) -> f32 {
        let Some(&(mut at, mut lane)) = self.leaf_at.get(leaf) else {
            return 0.0;
        };
        let mut chances = [0.0f32; MAX_DEPTH];
        let mut depth = 0;
        while at != u32::MAX {
            let Some(node) = self.nodes.get(at as usize) else {
                return 0.0;
            };
            if depth == MAX_DEPTH {
                return 0.0;
            }
            chances[depth] = wide::lane_probability(self.weights(node, r), lane as usize);
            depth += 1;
            (at, lane) = self.parents[at as usize];
        }
        if depth == 0 {
            return 0.0;
        }
        chances[..depth].iter().rev().fold(1.0, |p, &c| p * c)
    }
}
