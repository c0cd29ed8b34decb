//! The node hierarchy: local transforms checked and kept as stored, widened to f64 when composed,
//! and `EXT_mesh_gpu_instancing` instance transforms.

use glam::{Affine3A, DAffine3, DMat4, DQuat, DVec3};
use serde_json::Value;

use crate::accessor::{read_vec, Buffers};
use crate::error::Error;

/// A node's local transform as the file stores it (checked finite, with a non-zero rotation),
/// widened to f64 when used: 68 bytes a node rather than the 176 of the f64 matrix and its
/// decomposition (two million nodes: 216 MB).
#[derive(Debug, Clone, Copy)]
pub(crate) enum LocalTransform {
    /// `matrix`, column-major.
    Matrix([[f32; 4]; 4]),
    /// `translation`, `rotation`, `scale`.
    Trs([f32; 3], [f32; 4], [f32; 3]),
}

impl LocalTransform {
    /// The local transform in f64. The file's f32 values are widened so that composing a deep
    /// hierarchy rounds once, at the end, relative to the world origin.
    pub fn local(&self) -> DAffine3 {
        let m = match self {
            LocalTransform::Matrix(matrix) => {
                DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
            }
            LocalTransform::Trs(translation, rotation, scale) => {
                DMat4::from_scale_rotation_translation(
                    DVec3::from_array(scale.map(f64::from)),
                    DQuat::from_array(rotation.map(f64::from)).normalize(),
                    DVec3::from_array(translation.map(f64::from)),
                )
            }
        };
        DAffine3::from_mat4(m)
    }

    /// The same as scale, rotation, translation (decomposed from a matrix), which animation
    /// channels replace component by component.
    pub fn trs(&self) -> (DVec3, DQuat, DVec3) {
        match self {
            LocalTransform::Trs(translation, rotation, scale) => (
                DVec3::from_array(scale.map(f64::from)),
                DQuat::from_array(rotation.map(f64::from)).normalize(),
                DVec3::from_array(translation.map(f64::from)),
            ),
            LocalTransform::Matrix(_) => self.local().to_scale_rotation_translation(),
        }
    }
}

/// A node as stored: what posing needs of it.
#[derive(Debug, Clone)]
pub(crate) struct NodeData {
    /// Local transform as stored.
    pub transform: LocalTransform,
    pub mesh: Option<usize>,
    pub skin: Option<usize>,
    pub camera: Option<usize>,
    pub light: Option<usize>,
    /// `weights` (morph weights overriding the mesh's).
    pub weights: Option<Vec<f32>>,
    /// `extras`, for a camera node's depth of field.
    pub extras: Option<Value>,
    /// `EXT_mesh_gpu_instancing` local transforms.
    pub instances: Option<Vec<DAffine3>>,
}

/// The node hierarchy, checked to be a forest.
#[derive(Debug, Clone)]
pub(crate) struct NodeGraph {
    pub nodes: Vec<NodeData>,
    pub names: Vec<Option<String>>,
    pub parent: Vec<Option<usize>>,
    pub children: Vec<Vec<usize>>,
    /// Every node, parents before their children.
    pub topological: Vec<usize>,
    /// `KHR_node_visibility`: the node or an ancestor is stored `visible: false`. Hidden nodes
    /// draw nothing and light nothing; their transforms still place cameras and focus objects.
    pub hidden: Vec<bool>,
    /// The node's own stored flag is `visible: false` (what an animated flag replaces).
    pub own_hidden: Vec<bool>,
}

/// Per node: `own` holds for it or for an ancestor (`topological`: parents first), as a
/// hidden node hides its subtree.
pub(crate) fn inherited(
    topological: &[usize],
    parent: &[Option<usize>],
    own: impl Fn(usize) -> bool,
) -> Vec<bool> {
    let mut out = vec![false; parent.len()];
    for &i in topological {
        out[i] = own(i) || parent[i].is_some_and(|p| out[p]);
    }
    out
}

/// A node's own `KHR_node_visibility` flag (visible unless it says `false`).
fn visible(node: &gltf::Node<'_>) -> bool {
    node.extension_value("KHR_node_visibility")
        .and_then(|e| e.get("visible"))
        .and_then(Value::as_bool)
        .unwrap_or(true)
}

pub(crate) fn finite(at: impl FnOnce() -> String, values: &[f32]) -> Result<(), Error> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(v) => Err(Error::NonFinite {
            at: at(),
            value: v.to_string(),
        }),
        None => Ok(()),
    }
}

/// A node's local transform, checked for NaN, infinity and a zero rotation.
fn local_transform(node: &gltf::Node<'_>) -> Result<LocalTransform, Error> {
    let i = node.index();
    Ok(match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            finite(|| format!("nodes[{i}].matrix"), matrix.as_flattened())?;
            LocalTransform::Matrix(matrix)
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            finite(|| format!("nodes[{i}].translation"), &translation)?;
            finite(|| format!("nodes[{i}].rotation"), &rotation)?;
            finite(|| format!("nodes[{i}].scale"), &scale)?;
            // Exporters write slightly denormalised quaternions; zero cannot be normalised.
            if DQuat::from_array(rotation.map(f64::from)).length_squared() <= 0.0 {
                return Err(Error::NonFinite {
                    at: format!("nodes[{i}].rotation"),
                    value: "zero quaternion".into(),
                });
            }
            LocalTransform::Trs(translation, rotation, scale)
        }
    })
}

/// `m` if every entry is finite: each node's values are, but their composition may overflow
/// f32 (a scale of 1e30 under another of 1e30).
pub(crate) fn finite_world(node: usize, m: Affine3A) -> Result<Affine3A, Error> {
    if m.is_finite() {
        Ok(m)
    } else {
        Err(Error::NonFinite {
            at: format!("nodes[{node}] (its world transform, composed with its parents')"),
            value: "beyond the float32 range".into(),
        })
    }
}

/// An f64 transform rounded to f32 (call it on world-origin-relative transforms only).
pub(crate) fn to_f32(m: DAffine3) -> Affine3A {
    Affine3A::from_mat3_translation(m.matrix3.as_mat3(), m.translation.as_vec3())
}

/// Every node (not only the drawn scene's: `focus_object` may name any node), its hierarchy
/// checked to be a forest.
pub(crate) fn node_graph(doc: &gltf::Document, buffers: &Buffers) -> Result<NodeGraph, Error> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    let mut nodes = Vec::with_capacity(n);
    let mut children = Vec::with_capacity(n);
    for node in doc.nodes() {
        let transform = local_transform(&node)?;
        for c in node.children() {
            if c.index() == node.index() {
                return Err(Error::NodeGraph {
                    node: c.index(),
                    reason: "is its own child".into(),
                });
            }
            if let Some(p) = parent[c.index()].replace(node.index()) {
                return Err(Error::NodeGraph {
                    node: c.index(),
                    reason: format!("has two parents (nodes {p} and {})", node.index()),
                });
            }
        }
        children.push(node.children().map(|c| c.index()).collect::<Vec<_>>());
        let instances = match node.extension_value("EXT_mesh_gpu_instancing") {
            Some(ext) if node.mesh().is_some() => {
                Some(gpu_instances(doc, buffers, ext, node.index())?)
            }
            _ => None,
        };
        nodes.push(NodeData {
            transform,
            mesh: node.mesh().map(|m| m.index()),
            skin: node.skin().map(|s| s.index()),
            camera: node.camera().map(|c| c.index()),
            light: node.light().map(|l| l.index()),
            weights: node.weights().map(<[f32]>::to_vec),
            extras: crate::camera::raw(node.extras()),
            instances,
        });
    }
    let mut topological = Vec::with_capacity(n);
    let mut stack: Vec<usize> = (0..n).filter(|&i| parent[i].is_none()).collect();
    while let Some(i) = stack.pop() {
        topological.push(i);
        stack.extend(&children[i]);
    }
    if topological.len() < n {
        let mut seen = vec![false; n];
        for &i in &topological {
            seen[i] = true;
        }
        let node = seen.iter().position(|s| !s).unwrap_or(0);
        return Err(Error::NodeGraph {
            node,
            reason: "is part of a cycle in the node hierarchy".into(),
        });
    }
    let own: Vec<bool> = doc.nodes().map(|n| !visible(&n)).collect();
    let hidden = inherited(&topological, &parent, |i| own[i]);
    Ok(NodeGraph {
        nodes,
        names: doc.nodes().map(|n| n.name().map(str::to_owned)).collect(),
        parent,
        children,
        topological,
        hidden,
        own_hidden: own,
    })
}

/// `EXT_mesh_gpu_instancing`: one local transform per instance (TRS, each optional).
pub(crate) fn gpu_instances(
    doc: &gltf::Document,
    buffers: &Buffers,
    ext: &Value,
    node: usize,
) -> Result<Vec<DAffine3>, Error> {
    let at = format!("nodes[{node}].extensions.EXT_mesh_gpu_instancing.attributes");
    let attrs = ext
        .get("attributes")
        .and_then(Value::as_object)
        .ok_or_else(|| Error::Invalid {
            at: at.clone(),
            reason: "missing".into(),
        })?;
    let accessor = |key: &str| -> Result<Option<gltf::Accessor<'_>>, Error> {
        let Some(v) = attrs.get(key) else {
            return Ok(None);
        };
        let i = v.as_u64().ok_or_else(|| Error::Invalid {
            at: format!("{at}.{key}"),
            reason: format!("{v} is not an accessor index"),
        })?;
        doc.accessors()
            .nth(i as usize)
            .map(Some)
            .ok_or_else(|| Error::Invalid {
                at: format!("{at}.{key}"),
                reason: format!("accessor {i} does not exist"),
            })
    };
    let t = match accessor("TRANSLATION")? {
        Some(a) => Some(read_vec::<3>(&a, buffers, &format!("{at}.TRANSLATION"))?),
        None => None,
    };
    let r = match accessor("ROTATION")? {
        Some(a) => Some(read_vec::<4>(&a, buffers, &format!("{at}.ROTATION"))?),
        None => None,
    };
    let s = match accessor("SCALE")? {
        Some(a) => Some(read_vec::<3>(&a, buffers, &format!("{at}.SCALE"))?),
        None => None,
    };
    let counts: Vec<usize> = [
        t.as_ref().map(Vec::len),
        r.as_ref().map(Vec::len),
        s.as_ref().map(Vec::len),
    ]
    .into_iter()
    .flatten()
    .collect();
    let count = counts.first().copied().unwrap_or(0);
    if counts.iter().any(|&c| c != count) {
        return Err(Error::Invalid {
            at,
            reason: format!("attribute counts differ: {counts:?}"),
        });
    }
    (0..count)
        .map(|k| {
            let wide = |v: [f32; 3]| DVec3::from_array(v.map(f64::from));
            let tr = t.as_ref().map_or(DVec3::ZERO, |v| wide(v[k]));
            let q = r
                .as_ref()
                .map_or(DQuat::IDENTITY, |v| DQuat::from_array(v[k].map(f64::from)));
            let sc = s.as_ref().map_or(DVec3::ONE, |v| wide(v[k]));
            let m = DAffine3::from_scale_rotation_translation(sc, q.normalize(), tr);
            let values = DMat4::from(m).to_cols_array().map(|x| x as f32);
            finite(|| format!("{at}[{k}]"), &values)?;
            Ok(m)
        })
        .collect()
}
