//! A light BVH for scenes with many lights (pbrt-v4's `BVHLightSampler`, Cycles' light tree:
//! Conty Estevez & Kulla 2018): its leaves are the point and spot lights and the emissive
//! triangles (one leaf per triangle of each instance: instanced lamps share their mesh), its
//! inner nodes hold the [`LightBounds`] of their subtree.
//!
//! A vertex descends from the root, choosing a child in proportion to its importance there;
//! the pick's probability is the product of these choices, exact, and evaluated again for a
//! light met by a BSDF-sampled ray from the leaf's ancestors
//! ([`LightTree::triangle_probability`]), so MIS sees the same probability. The tree is built
//! binary (pbrt's splits) and read 4-wide: each node weighs four children at once
//! ([`wide`]). Directional lights have no position: they are picked beside the tree
//! ([`pick`]).
//!
//! Below [`PUNCTUAL_THRESHOLD`] point and spot lights the exhaustive choice
//! ([`crate::light_choice`]) is kept: it evaluates every punctual light exactly and takes the
//! emitters as one candidate (a triangle by power), which for fewer lights gives less noise per
//! unit of time than the descent; its images stay as they were. From it on, the tree holds
//! every point and spot light and every emissive triangle, each its own leaf.

mod build;
mod collapse;
pub mod pick;
mod reuse;
mod sample;
mod split;
mod wide;

pub use reuse::TreeMemo;

use crate::light_bounds::LightBounds;
use crate::lights::EmissiveLights;
use crate::surface::Geometry;
use aperture_scene::Light;

/// Point and spot lights from which a scene uses the tree: below it the exhaustive choice's
/// exact importances give less noise per unit of time (street grids of
/// `tools/bench/many_lights.py`, two layouts: the tree's variance × time 1.3–1.8× the
/// exhaustive choice's at 64 lights, 0.84–1.24× at 100, 0.84–0.88× at 128, 0.37 at 400;
/// see BENCHMARKS.md). Emissive triangles alone never ask for the tree: on the sample files
/// with most of them (the demo, StainedGlassLamp, ToyCar, LightsPunctualLamp) the tree's
/// variance × time was 1.07–1.43× the exhaustive choice's, whose cost does not grow with them
/// (one candidate, an alias table), though it won on panels spread over a street (0.77–0.86×).
pub const PUNCTUAL_THRESHOLD: usize = 128;

/// A leaf of the tree: one light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Leaf {
    /// The scene's punctual light of this index (point or spot).
    Punctual(u32),
    /// The emissive triangle of this index in [`EmissiveLights::triangles`].
    Triangle(u32),
}

/// The light tree of a scene.
#[derive(Debug)]
pub struct LightTree {
    /// The whole tree's bound: its importance beside the directional lights.
    root: LightBounds,
    /// The wide nodes, the root first.
    nodes: Vec<wide::Wide>,
    /// Each node's parent and its lane there (the root's parent: `u32::MAX`).
    parents: Vec<(u32, u8)>,
    /// Every leaf's light.
    leaves: Vec<Leaf>,
    /// Each leaf's node and lane.
    leaf_at: Vec<(u32, u8)>,
    /// Leaf of each scene light (`u32::MAX`: not in the tree).
    punctual_leaf: Vec<u32>,
    /// Leaf of each emissive triangle.
    triangle_leaf: Vec<u32>,
    /// The directional lights, picked beside the tree.
    directional: Vec<u32>,
}

impl LightTree {
    /// Whether a scene with these lights uses the tree (see [`PUNCTUAL_THRESHOLD`]).
    pub fn wanted(lights: &[Light]) -> bool {
        let positional = lights
            .iter()
            .filter(|l| !matches!(l.kind, aperture_scene::LightKind::Directional))
            .count();
        positional >= PUNCTUAL_THRESHOLD
    }

    /// The tree when the scene [wants](LightTree::wanted) one, else `None` (the exhaustive
    /// choice serves it).
    pub fn for_scene(geom: &Geometry<'_>, emissive: Option<&EmissiveLights>) -> Option<Self> {
        if !Self::wanted(&geom.scene.lights) {
            return None;
        }
        Self::build(geom, emissive)
    }

    /// The number of leaves.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    /// The light of each leaf.
    pub fn leaves(&self) -> &[Leaf] {
        &self.leaves
    }
}
