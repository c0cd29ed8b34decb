//! `KHR_node_visibility` keyed by `KHR_animation_pointer` (`/nodes/{i}/extensions/
//! KHR_node_visibility/visible`): which nodes are hidden at a pose, with the stored flag's
//! meaning (a hidden node hides its whole subtree, a visible child of a hidden parent included;
//! cameras and focus objects are placed all the same).

use std::borrow::Cow;

use super::{Animated, Pose};
use crate::animation::{Channel, Target};
use crate::nodes::{inherited, NodeGraph};
use crate::pointer::Pointer;
use crate::types::SceneStats;

/// What loading needs of the keyed flags: per node, whether its visibility may change with
/// time, and whether it is hidden at every time (its mesh is then not read). Counts the
/// selected scene's stored hidden and keyed nodes into `stats`.
pub(super) fn plan(
    graph: &NodeGraph,
    channels: &[Channel],
    order: &[usize],
    stats: &mut SceneStats,
) -> (Vec<bool>, Vec<bool>) {
    let keyed = keyed(channels, graph.nodes.len());
    stats.hidden_nodes = order.iter().filter(|&&i| graph.hidden[i]).count();
    stats.keyed_visibility_nodes = order.iter().filter(|&&i| keyed[i]).count();
    (toggles(graph, &keyed), never_shown(graph, &keyed))
}

/// Per node: a selected channel keys its own `visible` flag.
fn keyed(channels: &[Channel], nodes: usize) -> Vec<bool> {
    let mut keyed = vec![false; nodes];
    for c in channels {
        if let Target::Pointer(Pointer::NodeVisible(i)) = c.target {
            if let Some(k) = keyed.get_mut(i) {
                *k = true;
            }
        }
    }
    keyed
}

/// Per node: its visibility may change with time (it or an ancestor is keyed).
fn toggles(graph: &NodeGraph, keyed: &[bool]) -> Vec<bool> {
    inherited(&graph.topological, &graph.parent, |i| keyed[i])
}

/// Per node: hidden at every time (it or an ancestor is stored hidden and not keyed), so its
/// mesh need not even be read; a node keyed visible at some time is read like a shown one.
fn never_shown(graph: &NodeGraph, keyed: &[bool]) -> Vec<bool> {
    inherited(&graph.topological, &graph.parent, |i| {
        graph.own_hidden[i] && !keyed[i]
    })
}

impl Animated {
    /// Nodes whose visibility may change with time (their own `visible` flag is keyed by a
    /// selected `KHR_animation_pointer` channel, or an ancestor's is), in increasing order:
    /// their instances and lights come and go between frames while their geometry stays the
    /// same, so a renderer keeps those meshes' BVHs and rebuilds only the top level.
    pub fn toggling_nodes(&self) -> Vec<u32> {
        (0..self.toggles.len())
            .filter(|&n| self.toggles[n])
            .map(|n| n as u32)
            .collect()
    }

    /// Per node: hidden at `pose` (the stored flags where nothing is keyed, borrowed).
    pub(super) fn hidden_at(&self, pose: &Pose) -> Cow<'_, [bool]> {
        let keys = pose.pointers.iter().filter_map(|(p, v)| match p {
            Pointer::NodeVisible(i) => Some((*i, v.first().copied().unwrap_or(1.0))),
            _ => None,
        });
        let mut own: Option<Vec<bool>> = None;
        for (i, v) in keys {
            let own = own.get_or_insert_with(|| self.graph.own_hidden.clone());
            if let Some(h) = own.get_mut(i) {
                // KHR_animation_pointer: 0 is false, any other value true.
                *h = v == 0.0;
            }
        }
        let Some(own) = own else {
            return Cow::Borrowed(&self.graph.hidden);
        };
        let g = &self.graph;
        Cow::Owned(inherited(&g.topological, &g.parent, |i| own[i]))
    }
}
