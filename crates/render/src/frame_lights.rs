//! What a posed frame lights with, built once per way of shading it and shared by every band,
//! tile, round and pass rendered from it: the emitters' selection table and the light tree.

use aperture_shading::light_tree::{LightTree, TreeMemo};
use aperture_shading::lights::EmissiveLights;
use aperture_shading::surface::Geometry;
use std::sync::Arc;

/// A frame's emissive triangles with their selection table, and its light tree (for many
/// lights; `None` keeps the exhaustive choice).
#[derive(Debug)]
pub struct FrameLights {
    pub(crate) emissive: Option<EmissiveLights>,
    pub(crate) tree: Option<Arc<LightTree>>,
}

impl FrameLights {
    /// The lights of `geom`'s scene, the tree taken from `memo` when it holds the same one (a
    /// sequence's frames in which no light or emitter moved).
    pub fn build(geom: &Geometry<'_>, memo: Option<&TreeMemo>) -> Self {
        let emissive = EmissiveLights::build(geom);
        let tree = match memo {
            Some(m) => m.for_scene(geom, emissive.as_ref()),
            None => TreeMemo::new().for_scene(geom, emissive.as_ref()),
        };
        Self { emissive, tree }
    }

    /// Emissive triangles in the scene's emitters' table.
    pub fn emissive_triangles(&self) -> usize {
        self.emissive.as_ref().map_or(0, |e| e.triangles.len())
    }

    /// True when lights are chosen by the light tree.
    pub fn has_tree(&self) -> bool {
        self.tree.is_some()
    }
}
