//! Which drawn meshes are static (built once, at the rest pose) and which deform with time
//! (morphed or skinned per pose), and the deforming itself.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::DVec3;

use super::{Animated, Pose, Shape};
use crate::animation::{NodeProperty, Target};
use crate::error::Error;
use crate::origin::recentre;
use crate::pointer::Pointer;
use crate::types::Mesh;
use crate::{morph, skin};

/// What makes a static deformed mesh unique: the glTF mesh, the skin posing it and the bits of
/// its morph weights.
type StaticKey = (usize, Option<usize>, Vec<u32>);

impl Animated {
    /// Decides, per drawing node, whether its mesh is static (built now) or deformed per pose.
    /// A decoded mesh no deforming node draws is moved (not copied) into its last static
    /// shape, and then dropped: each static mesh is held once.
    pub(super) fn classify(&mut self) -> Result<(), Error> {
        let n = self.graph.nodes.len();
        let mut moved = vec![false; n];
        let mut weights_animated = vec![false; n];
        let mut mesh_weights_animated: Vec<usize> = Vec::new();
        for c in &self.animations.channels {
            match &c.target {
                Target::Node(i, NodeProperty::Weights) => weights_animated[*i] = true,
                Target::Node(i, _) => moved[*i] = true,
                Target::Pointer(Pointer::MeshWeights(m)) => mesh_weights_animated.push(*m),
                Target::Pointer(_) => {}
            }
        }
        for &i in &self.graph.topological {
            let parent_moves = self.graph.parent[i].is_some_and(|p| self.moves[p]);
            self.moves[i] = moved[i] || parent_moves;
        }
        let rest = self.pose(None);
        let plans = self.plan_shapes(&rest, &weights_animated, &mesh_weights_animated);
        let deforming: HashSet<usize> = (plans.iter())
            .filter_map(|(_, mi, key)| key.is_none().then_some(*mi))
            .collect();
        // The last distinct static shape of each mesh: the one its decoded data moves into.
        let mut last: HashMap<usize, &StaticKey> = HashMap::new();
        for (_, mi, key) in &plans {
            if let Some(k) = key {
                last.insert(*mi, k);
            }
        }
        let last: HashMap<usize, StaticKey> =
            last.into_iter().map(|(mi, k)| (mi, k.clone())).collect();
        let mut cache: HashMap<StaticKey, (u32, DVec3, bool)> = HashMap::new();
        for (ni, mi, key) in plans {
            let Some(key) = key else {
                self.shapes.insert(ni, Shape::Deforming);
                continue;
            };
            let (mesh, offset, world_space) = match cache.get(&key) {
                Some(&v) => v,
                None => {
                    let take = !deforming.contains(&mi) && last.get(&mi) == Some(&key);
                    let (mut m, centre) = self.deform_rest(ni, mi, &rest, take)?;
                    let (offset, world_space) = match centre {
                        Some(c) => (c, true),
                        None => (recentre(&mut m), false),
                    };
                    self.static_meshes.push(Arc::new(m));
                    let v = ((self.static_meshes.len() - 1) as u32, offset, world_space);
                    cache.insert(key, v);
                    v
                }
            };
            let shape = Shape::Static {
                mesh,
                offset,
                world_space,
            };
            self.shapes.insert(ni, shape);
        }
        // Only deforming nodes read a decoded mesh from here on.
        self.meshes.retain(|mi, _| deforming.contains(mi));
        Ok(())
    }

    /// Per drawing node (in draw order): its node, its geometry's mesh, and the key of its
    /// static shape (`None`: it deforms with time).
    fn plan_shapes(
        &mut self,
        rest: &Pose,
        weights_animated: &[bool],
        mesh_weights_animated: &[usize],
    ) -> Vec<(usize, usize, Option<StaticKey>)> {
        let mut plans = Vec::new();
        for &ni in &self.order.clone() {
            let Some(mi) = self.graph.nodes[ni].mesh.map(|m| self.geometry_of(ni, m)) else {
                continue;
            };
            let node = &self.graph.nodes[ni];
            let Some(lm) = self.meshes.get(&mi) else {
                continue;
            };
            let skin = node.skin.filter(|_| lm.influences.is_some());
            let skin_moves = skin.and_then(|s| self.skins.get(s)).is_some_and(|s| {
                s.joints
                    .iter()
                    .any(|&j| self.moves.get(j).copied().unwrap_or(false))
            });
            let morph_moves = !lm.targets.is_empty()
                && (weights_animated[ni]
                    || (node.weights.is_none() && mesh_weights_animated.contains(&mi)));
            if skin_moves || morph_moves {
                plans.push((ni, mi, None));
                continue;
            }
            let weights = match lm.targets.is_empty() {
                true => Vec::new(),
                false => (rest.weights(ni, mi, node, lm).iter())
                    .map(|w| w.to_bits())
                    .collect(),
            };
            plans.push((ni, mi, Some((mi, skin, weights))));
        }
        plans
    }

    /// The mesh of node `ni` at `pose`: morphed and skinned. For a skinned mesh, also the world
    /// centre its positions are relative to.
    pub(super) fn deform(
        &self,
        ni: usize,
        mi: usize,
        pose: &Pose,
    ) -> Result<(Mesh, Option<DVec3>), Error> {
        self.deform_mesh(ni, mi, pose, self.meshes[&mi].mesh.clone())
    }

    /// [`Animated::deform`] at the rest pose for a static shape; with `take`, the decoded
    /// mesh is moved in rather than copied (its last use).
    fn deform_rest(
        &mut self,
        ni: usize,
        mi: usize,
        rest: &Pose,
        take: bool,
    ) -> Result<(Mesh, Option<DVec3>), Error> {
        let m = match (take, self.meshes.get_mut(&mi)) {
            (true, Some(lm)) => std::mem::take(&mut lm.mesh),
            (_, lm) => lm.map(|lm| lm.mesh.clone()).unwrap_or_default(),
        };
        self.deform_mesh(ni, mi, rest, m)
    }

    /// `m` (node `ni`'s decoded mesh `mi`, or its copy) morphed and skinned at `pose`.
    fn deform_mesh(
        &self,
        ni: usize,
        mi: usize,
        pose: &Pose,
        mut m: Mesh,
    ) -> Result<(Mesh, Option<DVec3>), Error> {
        let node = &self.graph.nodes[ni];
        let lm = &self.meshes[&mi];
        let at = format!("meshes[{mi}]");
        if !lm.targets.is_empty() {
            let w = pose.weights(ni, mi, node, lm);
            morph::apply(&mut m, &lm.targets, &w);
        }
        let skin = node.skin.and_then(|s| self.skins.get(s).map(|k| (s, k)));
        let centre = match (skin, &lm.influences) {
            (Some((s, skin)), Some(inf)) => {
                let mut joints = Vec::with_capacity(skin.joints.len());
                for (k, &j) in skin.joints.iter().enumerate() {
                    let world = pose.world.get(j).ok_or_else(|| Error::Invalid {
                        at: format!("skins[{s}].joints[{k}]"),
                        reason: format!("node {j} does not exist"),
                    })?;
                    joints.push(*world * skin.inverse_bind[k]);
                }
                Some(skin::apply(&mut m, inf, &joints, pose.world[ni], &at)?)
            }
            _ => None,
        };
        skin::refresh_flat_normals(&mut m, &lm.flat);
        Ok((m, centre))
    }
}
