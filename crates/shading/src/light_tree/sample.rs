//! The descent: from the root, a child in proportion to its importance at the vertex, down to
//! one leaf, and the same choices followed again along a leaf's trail for its probability.

use super::{Leaf, LightTree, Node};
use crate::light_choice::punctual_importance;
use aperture_scene::Light;
use glam::Vec3;

/// Largest f32 below 1: a remapped uniform number stays in `[0, 1)`.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

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
    /// A node's importance at the receiver: a punctual leaf's exact irradiance, else its
    /// bound's.
    #[inline]
    fn node_importance(&self, node: &Node, r: &Receiver<'_>) -> f32 {
        if node.leaf {
            if let Some(Leaf::Punctual(l)) = self.leaves.get(node.second as usize) {
                return r.lights.get(*l as usize).map_or(0.0, |light| {
                    punctual_importance(light, r.p, r.n, r.two_sided)
                });
            }
        }
        node.bounds.importance(r.p, r.n, r.two_sided)
    }

    /// The importance of the whole tree at the receiver.
    pub(super) fn root_importance(&self, r: &Receiver<'_>) -> f32 {
        self.nodes
            .first()
            .map_or(0.0, |n| self.node_importance(n, r))
    }

    /// The probability of the first child of inner node `at`; `None` when neither child can
    /// light the receiver.
    #[inline]
    fn first_probability(&self, at: usize, r: &Receiver<'_>) -> Option<f32> {
        let node = &self.nodes[at];
        let a = self.node_importance(self.nodes.get(at + 1)?, r);
        let b = self.node_importance(self.nodes.get(node.second as usize)?, r);
        let total = a + b;
        (total > 0.0 && total.is_finite()).then(|| a / total)
    }

    /// One leaf for the receiver from the uniform `u`: the leaf's index, its probability
    /// given the tree, and `u` remapped; `None` when no leaf can light the receiver.
    pub(super) fn descend(&self, r: &Receiver<'_>, mut u: f32) -> Option<(usize, f32, f32)> {
        let mut at = 0usize;
        let mut probability = 1.0f32;
        loop {
            let node = self.nodes.get(at)?;
            if node.leaf {
                return Some((node.second as usize, probability, u));
            }
            let pa = self.first_probability(at, r)?;
            if u < pa {
                probability *= pa;
                u = (u / pa).min(ONE_BELOW);
                at += 1;
            } else {
                let pb = 1.0 - pa;
                probability *= pb;
                u = ((u - pa) / pb).clamp(0.0, ONE_BELOW);
                at = node.second as usize;
            }
            if probability <= 0.0 {
                return None;
            }
        }
    }

    /// The probability that [`LightTree::descend`] reaches `leaf` at the receiver.
    pub(super) fn leaf_probability(&self, r: &Receiver<'_>, leaf: usize) -> f32 {
        let Some(&trail) = self.trails.get(leaf) else {
            return 0.0;
        };
        let mut at = 0usize;
        let mut probability = 1.0f32;
        for depth in 0..64 {
            let Some(node) = self.nodes.get(at) else {
                return 0.0;
            };
            if node.leaf {
                return if node.second as usize == leaf {
                    probability
                } else {
                    0.0
                };
            }
            let Some(pa) = self.first_probability(at, r) else {
                return 0.0;
            };
            if trail >> depth & 1 == 0 {
                probability *= pa;
                at += 1;
            } else {
                probability *= 1.0 - pa;
                at = node.second as usize;
            }
        }
        0.0
    }
}
