//! The light tree itself: its leaves, its 4-wide nodes and where each light sits in them (built
//! in `build`, read in `sample` and `pick`).

use super::wide;
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
    pub(super) root: LightBounds,
    /// The wide nodes, the root first.
    pub(super) nodes: Vec<wide::Wide>,
    /// Each node's parent and its lane there (the root's parent: `u32::MAX`).
    pub(super) parents: Vec<(u32, u8)>,
    /// Every leaf's light.
    pub(super) leaves: Vec<Leaf>,
    /// Each leaf's node and lane.
    pub(super) leaf_at: Vec<(u32, u8)>,
    /// Leaf of each scene light (`u32::MAX`: not in the tree).
    pub(super) punctual_leaf: Vec<u32>,
    /// Leaf of each emissive triangle.
    pub(super) triangle_leaf: Vec<u32>,
    /// The directional lights, picked beside the tree.
    pub(super) directional: Vec<u32>,
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
