//! Edits of a loaded document (SPEC §9): a value changed as if the file had stored it, so that
//! posing the edited document gives what a cold load of the edited file gives, bit for bit.
//! Here: what an edit is and what it touches, and the node edits a reload applies to the graph
//! before anything is decoded; [`crate::Animated::edit`] applies the others in place.

use std::sync::Arc;

use serde_json::Value;

use crate::error::Error;
use crate::geometry::Geometry;
use crate::nodes::{inherited, LocalTransform, NodeGraph};
use crate::pointer::{self, NodeProperty, Pointer};
/// A change to a loaded document: a value as the file could have stored it.
#[derive(Debug, Clone, PartialEq)]
pub enum Edit {
    /// `nodes[node].matrix`, column-major: replaces the node's stored TRS or matrix.
    NodeMatrix {
        /// The node index.
        node: usize,
        /// Its new local transform.
        matrix: [[f32; 4]; 4],
    },
    /// `nodes[node].extensions.KHR_node_visibility.visible`.
    NodeVisible {
        /// The node index.
        node: usize,
        /// The stored flag.
        visible: bool,
    },
    /// The value at a `KHR_animation_pointer` path, as an animation could key it: node
    /// `translation`/`rotation`/`scale`, material factors and texture transforms, light
    /// `color`/`intensity`/cone angles, camera `yfov`/`xmag`/`ymag` and the numeric
    /// depth-of-field keys at `/cameras/{i}/extras/<key>` (SPEC §3, §7).
    Pointer {
        /// The JSON pointer, e.g. `/materials/0/pbrMetallicRoughness/baseColorFactor`.
        path: String,
        /// Its value: as many numbers as the property has.
        value: Vec<f64>,
    },
    /// A depth-of-field key of SPEC §3 or docs/lenses.md in `cameras[camera].extras`, any
    /// JSON value (`Null` removes it). The key is also removed from the extras of the nodes
    /// carrying the camera, which would otherwise take precedence over it. The value is
    /// checked as posing reads it (a lens file read, a bokeh image read and decoded): a bad
    /// one is refused and changes nothing.
    CameraKey {
        /// The glTF camera index.
        camera: usize,
        /// The key, e.g. `aperture_fstop` or `focus_object`.
        key: String,
        /// Its value.
        value: Value,
    },
    /// `meshes[mesh]`'s primitives drawn from the given triangles, one [`Geometry`] a
    /// primitive in order (as many as the mesh has), as if the file stored them as the
    /// primitives' `POSITION`, `NORMAL`, `TEXCOORD_0` and triangle indices: each keeps its
    /// material and loses its other attributes, morph targets and joints. Loads the file again
    /// ([`Touched::Reload`]); the arrays are shared, not copied, by the edit list that replays it.
    MeshGeometry {
        /// The glTF mesh index.
        mesh: usize,
        /// Its primitives' new geometry.
        primitives: Arc<[Geometry]>,
    },
}

/// What an edit changed in the posed scene, so a renderer redoes only what depends on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Touched {
    /// Cameras only (their keys, or transforms of nodes that carry nothing drawn or lit).
    Cameras,
    /// Punctual lights only.
    Lights,
    /// Material values only (no geometry).
    Materials,
    /// Where things are: the scene must be posed again (meshes keep their bottom-level BVHs).
    Placements,
    /// What the loader decoded: the file must be loaded again with every edit so far
    /// ([`Animated::load_edited`]): visibility (hidden nodes' meshes are never decoded),
    /// morph weights, transforms of skin joints (static skins are posed at load), a bokeh
    /// image naming a texture whose image was not loaded with the file, and a mesh's geometry.
    Reload,
}

/// Edits the loader applies to the node graph before deciding what to decode.
pub(crate) fn graph_edit(e: &Edit) -> bool {
    match e {
        Edit::NodeMatrix { .. } | Edit::NodeVisible { .. } => true,
        Edit::Pointer { path, .. } => path.starts_with("/nodes/"),
        Edit::CameraKey { .. } | Edit::MeshGeometry { .. } => false,
    }
}

/// The key whose value is read with the file (the bokeh image), not when posing.
pub(crate) const LOADED_KEY: &str = "aperture_image";

/// Edits a reload applies while loading: the node edits ([`graph_edit`]) and the camera keys
/// read with the file ([`LOADED_KEY`], by [`apply_loaded_keys`]).
pub(crate) fn load_edit(e: &Edit) -> bool {
    graph_edit(e)
        || matches!(e, Edit::CameraKey { key, .. } if key == LOADED_KEY)
        || matches!(e, Edit::MeshGeometry { .. })
}

/// By glTF mesh index, the geometry the last [`Edit::MeshGeometry`] of each mesh in `edits`
/// gives it.
pub(crate) fn given_geometry(edits: &[Edit]) -> std::collections::HashMap<usize, Arc<[Geometry]>> {
    let given = edits.iter().filter_map(|e| match e {
        Edit::MeshGeometry { mesh, primitives } => Some((*mesh, Arc::clone(primitives))),
        _ => None,
    });
    given.collect()
}

/// Applies the [`LOADED_KEY`] edits of `edits` to freshly read cameras and their nodes, before
/// the loader reads what they name.
pub(crate) fn apply_loaded_keys(
    cameras: &mut [crate::camera::CameraData],
    graph: &mut NodeGraph,
    edits: &[Edit],
) -> Result<(), Error> {
    for e in edits {
        if let Edit::CameraKey { camera, key, value } = e {
            if key != LOADED_KEY {
                continue;
            }
            let count = cameras.len();
            let data = cameras.get_mut(*camera).ok_or_else(|| Error::Invalid {
                at: format!("cameras[{camera}]"),
                reason: format!("no such camera (the file has {count})"),
            })?;
            set_extra(&mut data.extras, key, value.clone());
            clear_node_key(graph, *camera, key);
        }
    }
    Ok(())
}

/// Sets `key` of a JSON object (creating it), or removes it when `value` is `Null`.
pub(crate) fn set_extra(extras: &mut Option<Value>, key: &str, value: Value) {
    if !matches!(extras, Some(Value::Object(_))) {
        *extras = Some(Value::Object(serde_json::Map::new()));
    }
    if let Some(Value::Object(map)) = extras {
        match value {
            Value::Null => map.remove(key),
            v => map.insert(key.to_owned(), v),
        };
    }
}

/// Removes `key` from the extras of the nodes carrying camera `camera` (they take precedence
/// over the camera's own, SPEC §3).
pub(crate) fn clear_node_key(graph: &mut NodeGraph, camera: usize, key: &str) {
    for node in &mut graph.nodes {
        if node.camera == Some(camera) {
            if let Some(Value::Object(map)) = &mut node.extras {
                map.remove(key);
            }
        }
    }
}

/// Applies the node edits of `edits` (matrices, TRS, visibility) to a freshly read graph.
pub(crate) fn apply_graph_edits(mut graph: NodeGraph, edits: &[Edit]) -> Result<NodeGraph, Error> {
    for e in edits {
        let count = graph.nodes.len();
        let node_of = |node: usize| {
            (node < count)
                .then_some(node)
                .ok_or_else(|| Error::Invalid {
                    at: format!("nodes[{node}]"),
                    reason: "no such node".into(),
                })
        };
        match e {
            Edit::NodeMatrix { node, matrix } => {
                graph.nodes[node_of(*node)?].transform = LocalTransform::Matrix(*matrix);
            }
            Edit::NodeVisible { node, visible } => graph.own_hidden[node_of(*node)?] = !visible,
            Edit::Pointer { path, value } => apply_node_pointer(&mut graph, path, value)?,
            Edit::CameraKey { .. } | Edit::MeshGeometry { .. } => {}
        }
    }
    let own = graph.own_hidden.clone();
    graph.hidden = inherited(&graph.topological, &graph.parent, |i| own[i]);
    Ok(graph)
}

/// A `/nodes/...` pointer edit applied to the graph (TRS replaced component by component,
/// visibility set; weights are read from the edited document elsewhere).
fn apply_node_pointer(graph: &mut NodeGraph, path: &str, v: &[f64]) -> Result<(), Error> {
    let root = serde_json::json!({ "nodes": vec![Value::Null; graph.nodes.len()] });
    match pointer::parse(path, &root) {
        Some(Pointer::NodeVisible(i)) => graph.own_hidden[i] = v.first() == Some(&0.0),
        Some(Pointer::Node(i, NodeProperty::Weights)) => {
            graph.nodes[i].weights = Some(v.iter().map(|&w| w as f32).collect());
        }
        Some(Pointer::Node(i, prop)) => {
            graph.nodes[i].transform = with_component(graph.nodes[i].transform, prop, v);
        }
        _ => {
            return Err(Error::Invalid {
                at: path.to_owned(),
                reason: "not a node pointer aperture edits".into(),
            })
        }
    }
    Ok(())
}

/// `t` with the component `prop` (translation, rotation or scale) replaced by `v`, as an
/// animation channel or a pointer edit replaces it: a stored matrix is decomposed first.
pub(crate) fn with_component(t: LocalTransform, prop: NodeProperty, v: &[f64]) -> LocalTransform {
    let (mut s, mut r, mut tr) = match t {
        LocalTransform::Trs(t, r, s) => (s, r, t),
        m @ LocalTransform::Matrix(_) => {
            let (s, r, t) = m.trs();
            let (s, r, t) = (s.as_vec3(), r.as_quat(), t.as_vec3());
            (s.to_array(), r.to_array(), t.to_array())
        }
    };
    let f = |k: usize| v.get(k).copied().unwrap_or(0.0) as f32;
    match prop {
        NodeProperty::Translation => tr = [f(0), f(1), f(2)],
        NodeProperty::Rotation => r = [f(0), f(1), f(2), f(3)],
        _ => s = [f(0), f(1), f(2)],
    }
    LocalTransform::Trs(tr, r, s)
}
