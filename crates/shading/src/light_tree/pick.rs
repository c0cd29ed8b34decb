//! A vertex's choice with the tree: the directional lights (exactly, as the exhaustive choice
//! weighs them) and the tree as one more candidate (its root's importance), then the descent;
//! and the probability of that choice for a given light, for MIS.

use super::sample::Receiver;
use super::tree::{Leaf, LightTree};
use crate::light_choice::{punctual_importance, remap, walk, Choice, Pick};
use aperture_scene::Light;
use glam::Vec3;

impl LightTree {
    /// One light at `p` (normal `n` on the side light is received from; both sides when
    /// `two_sided`) from the uniform `u`, among the scene's `lights` (those the tree was built
    /// with): [`Choice::pick`] is a punctual light or one emissive triangle
    /// ([`Pick::Triangle`]) with its exact probability; [`Choice::emitters`] is unused (0).
    pub fn pick(&self, lights: &[Light], p: Vec3, n: Vec3, two_sided: bool, u: f32) -> Choice {
        let r = Receiver {
            lights,
            p,
            n,
            two_sided,
        };
        let mut choice = Choice {
            pick: None,
            probability: 0.0,
            emitters: 0.0,
            u,
        };
        let Some((top, u)) = self.pick_top(&r, u) else {
            return choice;
        };
        let (pick, probability, u) = match top {
            Top::Directional(i, pr) => (Pick::Punctual(i), pr, u),
            Top::Tree(pr) => {
                let Some((leaf, pl, u)) = self.descend(&r, u) else {
                    return choice;
                };
                let pick = match self.leaves[leaf] {
                    Leaf::Punctual(i) => Pick::Punctual(i as usize),
                    Leaf::Triangle(t) => Pick::Triangle(t as usize),
                };
                (pick, pr * pl, u)
            }
        };
        if probability > 0.0 {
            choice.pick = Some(pick);
            choice.probability = probability;
            choice.u = u;
        }
        choice
    }

    /// The probability that [`LightTree::pick`] at this vertex picks the emissive triangle of
    /// index `triangle` (in [`crate::lights::EmissiveLights::triangles`]).
    pub fn triangle_probability(
        &self,
        lights: &[Light],
        p: Vec3,
        n: Vec3,
        two_sided: bool,
        triangle: usize,
    ) -> f32 {
        let leaf = self.triangle_leaf.get(triangle).copied();
        self.probability_of(lights, p, n, two_sided, leaf)
    }

    /// The probability that [`LightTree::pick`] at this vertex picks the scene's punctual
    /// light of index `light`.
    pub fn punctual_probability(
        &self,
        lights: &[Light],
        p: Vec3,
        n: Vec3,
        two_sided: bool,
        light: usize,
    ) -> f32 {
        let r = Receiver {
            lights,
            p,
            n,
            two_sided,
        };
        if self.directional.contains(&(light as u32)) {
            let total = self.top_total(&r);
            let w = self.directional_importance(&r, light as u32);
            return if total > 0.0 { w / total } else { 0.0 };
        }
        let leaf = self.punctual_leaf.get(light).copied();
        self.probability_of(lights, p, n, two_sided, leaf)
    }

    fn probability_of(
        &self,
        lights: &[Light],
        p: Vec3,
        n: Vec3,
        two_sided: bool,
        leaf: Option<u32>,
    ) -> f32 {
        let Some(leaf) = leaf.filter(|&l| l != u32::MAX) else {
            return 0.0;
        };
        let r = Receiver {
            lights,
            p,
            n,
            two_sided,
        };
        let total = self.top_total(&r);
        let tree = self.root_importance(&r);
        if !(total > 0.0 && tree > 0.0) {
            return 0.0;
        }
        tree / total * self.leaf_probability(&r, leaf as usize)
    }

    /// The importance of the scene's directional light `i` at the receiver.
    fn directional_importance(&self, r: &Receiver<'_>, i: u32) -> f32 {
        r.lights
            .get(i as usize)
            .map_or(0.0, |l| punctual_importance(l, r.p, r.n, r.two_sided))
    }

    /// The sum of the directional lights' importances and the tree's (0 when not finite).
    fn top_total(&self, r: &Receiver<'_>) -> f32 {
        let total = self
            .directional
            .iter()
            .map(|&i| self.directional_importance(r, i))
            .sum::<f32>()
            + self.root_importance(r);
        if total.is_finite() {
            total
        } else {
            0.0
        }
    }

    /// The first choice: a directional light or the tree, with its probability, and `u`
    /// remapped.
    fn pick_top(&self, r: &Receiver<'_>, u: f32) -> Option<(Top, f32)> {
        if self.directional.is_empty() {
            return (self.root_importance(r) > 0.0).then_some((Top::Tree(1.0), u));
        }
        let total = self.top_total(r);
        if total <= 0.0 {
            return None;
        }
        let tree = self.root_importance(r);
        // The same weights in the same order as `total`.
        let all = self
            .directional
            .iter()
            .map(|&i| (Some(i), self.directional_importance(r, i)))
            .chain([(None, tree)]);
        let (light, w, x) = walk(all, u * total)?;
        let u = remap(x, w);
        let pr = w / total;
        Some(match light {
            Some(i) => (Top::Directional(i as usize, pr), u),
            None => (Top::Tree(pr), u),
        })
    }
}

/// The first choice's outcome.
enum Top {
    /// A directional light and its probability.
    Directional(usize, f32),
    /// The tree, with its probability.
    Tree(f32),
}
