//! The loader's entry points and its shared steps: buffers, the node hierarchy, transforms in
//! f64, `EXT_mesh_gpu_instancing` and the world origin. [`Animated`] does the rest.

use std::collections::HashMap;
use std::path::Path;

use glam::{Affine3A, DAffine3, DMat4, DQuat, DVec3};
use serde_json::Value;

use crate::accessor::{read_vec, Buffers};
use crate::{uri, Animated, Error, LoadOptions, Scene, SceneStats};

/// Loads a `.gltf` or `.glb` file into a render-ready [`Scene`], posed at
/// [`LoadOptions::time`] (the stored pose without one).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, Error> {
    Animated::load(path, options)?.into_scene(options.time)
}

/// A fast 64-bit hash of `bytes` (not cryptographic: it tells files apart, it does not
/// defend against forgery). Eight bytes a step, each mixed by a multiply and a rotation.
pub fn content_hash(bytes: &[u8]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut h = (bytes.len() as u64).wrapping_mul(K) ^ 0x5851_F42D_4C95_7F2D;
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        let mut w = [0u8; 8];
        w.copy_from_slice(c);
        h = (h ^ u64::from_le_bytes(w)).wrapping_mul(K).rotate_left(29);
    }
    let mut tail = [0u8; 8];
    tail[..chunks.remainder().len()].copy_from_slice(chunks.remainder());
    h = (h ^ u64::from_le_bytes(tail)).wrapping_mul(K);
    h ^ (h >> 32)
}

/// Loads a scene from the bytes of a `.gltf` or `.glb` file; external URIs resolve inside `base_dir`.
pub fn load_bytes(bytes: &[u8], base_dir: &Path, options: &LoadOptions) -> Result<Scene, Error> {
    Animated::load_bytes(bytes, base_dir, options)?.into_scene(options.time)
}

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
}

/// Reads every buffer: the GLB BIN chunk, `data:` URIs or files beside the scene.
pub(crate) fn load_buffers(
    doc: &gltf::Document,
    root: &Value,
    bin: Option<&[u8]>,
    base_dir: &Path,
    budget: &aperture_budget::MemoryBudget,
) -> Result<Buffers, Error> {
    let mut data = Vec::with_capacity(doc.buffers().len());
    for b in doc.buffers() {
        let at = format!("buffers[{}]", b.index());
        if crate::meshopt::is_fallback(root, b.index()) {
            // EXT_meshopt_compression's placeholder: no bytes; its views are decoded instead.
            data.push(Vec::new());
            continue;
        }
        let mut bytes = match b.source() {
            gltf::buffer::Source::Bin => bin
                .ok_or_else(|| Error::Invalid {
                    at: at.clone(),
                    reason: "refers to the GLB BIN chunk, which is missing".into(),
                })?
                .to_vec(),
            gltf::buffer::Source::Uri(u) => uri::load(base_dir, u, &format!("{at}.uri"))?,
        };
        let claimed = b.length() as u64;
        if (bytes.len() as u64) < claimed {
            return Err(Error::BufferTooShort {
                buffer: b.index(),
                claimed,
                actual: bytes.len() as u64,
            });
        }
        // Padding past byteLength is not part of the buffer.
        bytes.truncate(b.length());
        data.push(bytes);
    }
    let total = data.iter().map(|d| d.len() as u64).sum();
    Ok(Buffers {
        data,
        total,
        decoded: HashMap::new(),
        charged: Default::default(),
        budget: *budget,
    })
}

fn finite(at: impl FnOnce() -> String, values: &[f32]) -> Result<(), Error> {
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

/// Moves a mesh whose vertices sit far from its own origin (farther than its size) to be centred
/// on its bounds, and returns the offset to add back in front of every instance transform.
///
/// Why: vertex coordinates near 1e6 have f32 spacing 0.0625 and every ray transformed into that
/// object space inherits that error. The subtraction is done in f64 and the stored f32 values
/// are exact multiples of their spacing, so the recentred vertices lose nothing that the file
/// held.
pub(crate) fn recentre(mesh: &mut crate::Mesh) -> DVec3 {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in &mesh.positions {
        lo = lo.min(p.as_dvec3());
        hi = hi.max(p.as_dvec3());
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return DVec3::ZERO;
    }
    let centre = 0.5 * (lo + hi);
    if centre.length() <= (hi - lo).length() {
        return DVec3::ZERO;
    }
    for p in &mut mesh.positions {
        *p = (p.as_dvec3() - centre).as_vec3();
    }
    centre
}

/// The world point the loaded scene is expressed relative to (see [`Scene::world_origin`]): the
/// centre of the drawn geometry's bounds when that centre is farther from the file's origin than
/// the geometry is large (a scene placed at geographic coordinates, say), else the file's
/// origin, so scenes modelled around the origin keep the coordinates their files give.
///
/// The geometry's centre, rather than a camera's position, because a file has any number of
/// cameras (or none) and the bounds are what every camera looks at.
pub(crate) fn world_origin(
    meshes: &[crate::Mesh],
    placed: &[(u32, DAffine3, u32)],
    stats: &mut SceneStats,
) -> DVec3 {
    // Per mesh, once (a mesh may be placed thousands of times): object-space bounds and the
    // shortest edge.
    let per_mesh: Vec<Option<(DVec3, DVec3, f64)>> = meshes
        .iter()
        .map(|m| {
            let (mut mlo, mut mhi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for p in &m.positions {
                mlo = mlo.min(p.as_dvec3());
                mhi = mhi.max(p.as_dvec3());
            }
            (mlo.is_finite() && mhi.is_finite()).then(|| (mlo, mhi, shortest_edge(m)))
        })
        .collect();
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (mesh, world, _) in placed {
        let Some(&Some((mlo, mhi, _))) = per_mesh.get(*mesh as usize) else {
            continue;
        };
        for k in 0..8 {
            let corner = DVec3::select(
                glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                mhi,
                mlo,
            );
            let w = world.transform_point3(corner);
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return DVec3::ZERO;
    }
    let centre = 0.5 * (lo + hi);
    let size = (hi - lo).length();
    let origin = if centre.length() > size {
        centre
    } else {
        DVec3::ZERO
    };
    // What recentring cannot fix: a scene so large around its own centre that f32 positions at
    // its edge are coarse next to its smallest triangles.
    let reach = (hi - origin).abs().max((lo - origin).abs()).max_element();
    let spacing = reach * f64::from(f32::EPSILON);
    let detail = placed
        .iter()
        .filter_map(|(mesh, world, _)| {
            let (_, _, edge) = (*per_mesh.get(*mesh as usize)?)?;
            let shrink = [
                world.matrix3.x_axis,
                world.matrix3.y_axis,
                world.matrix3.z_axis,
            ]
            .map(|c| c.length())
            .into_iter()
            .fold(f64::INFINITY, f64::min);
            Some(edge * shrink)
        })
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if spacing * MIN_STEPS_PER_EDGE > detail {
        stats.warnings.push(format!(
            "the scene reaches {reach:.3e} units from its centre, where float32 positions are \
             {spacing:.1e} apart, yet its shortest triangle edge is {detail:.1e}: such details \
             are distorted or cracked (docs/accuracy.md, float32 limits)"
        ));
    }
    if size > 0.0 && size < MIN_EXTENT {
        stats.warnings.push(format!(
            "the scene is only {size:.1e} units across: below {MIN_EXTENT:.0e} squared distances \
             and light falloff near float32's smallest normal numbers change the image; model it \
             in smaller units (docs/accuracy.md, float32 limits)"
        ));
    }
    origin
}

/// Smallest scene diagonal accepted silently. Measured (docs/accuracy.md): the stress scene
/// scaled to 8.6e-8 units across renders its unscaled image (same-seed rmse 0.0000 × the
/// seed-to-seed rmse); at 8.6e-10 across it drifts (0.135).
const MIN_EXTENT: f64 = 1e-8;

/// A triangle edge shorter than this many f32 steps at the scene's edge is reported: vertices
/// round by up to half a step, so such an edge may change length by more than 1/16.
const MIN_STEPS_PER_EDGE: f64 = 16.0;

/// The shortest non-zero edge of a mesh's triangles, in object space (infinity if none).
fn shortest_edge(mesh: &crate::Mesh) -> f64 {
    let p = |i: u32| mesh.positions.get(i as usize).map(|v| v.as_dvec3());
    mesh.indices
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .filter_map(|(a, b)| Some(p(a)?.distance(p(b)?)))
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min)
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
    Ok(NodeGraph {
        nodes,
        names: doc.nodes().map(|n| n.name().map(str::to_owned)).collect(),
        parent,
        children,
        topological,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LightKind;
    use base64::Engine;
    use glam::Vec3;
    use serde_json::json;

    /// One triangle (no normals) plus, from byte 44, instancing translations for 3 instances.
    fn bin() -> Vec<u8> {
        let mut b = Vec::new();
        let floats = [
            0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, // positions
        ];
        for x in floats {
            b.extend(x.to_le_bytes());
        }
        for i in [0u16, 1, 2, 0] {
            b.extend(i.to_le_bytes());
        }
        for x in [0.0f32, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 5.0, 0.0] {
            b.extend(x.to_le_bytes());
        }
        b
    }

    fn gltf(nodes: Value, scene_nodes: Value, extra: Value) -> Vec<u8> {
        let b = bin();
        let mut j = json!({
            "asset": {"version": "2.0"},
            "scenes": [{"nodes": scene_nodes}],
            "nodes": nodes,
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}
            ],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": 36},
                {"buffer": 0, "byteOffset": 36, "byteLength": 6},
                {"buffer": 0, "byteOffset": 44, "byteLength": 36}
            ],
            "buffers": [{"byteLength": b.len(), "uri": format!("data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&b))}]
        });
        if let (Some(o), Some(e)) = (j.as_object_mut(), extra.as_object()) {
            o.extend(e.clone());
        }
        serde_json::to_vec(&j).unwrap()
    }

    fn load_json(bytes: &[u8]) -> Result<Scene, Error> {
        load_bytes(bytes, Path::new("."), &LoadOptions::default())
    }

    #[test]
    fn shared_mesh_is_stored_once_with_hierarchy_transforms() {
        let s = load_json(&gltf(
            json!([
                {"translation": [1, 0, 0], "children": [1, 2]},
                {"mesh": 0, "scale": [2, 2, 2]},
                {"mesh": 0, "matrix": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,3,0,1]}
            ]),
            json!([0]),
            json!({}),
        ))
        .unwrap();
        assert_eq!(s.meshes.len(), 1);
        assert_eq!(s.instances.len(), 2);
        assert_eq!(s.drawn_triangle_count(), 2);
        assert_eq!(s.stats.nodes, 3);
        let a = s.instances[0].world_from_object;
        assert_eq!(a.transform_point3(Vec3::X), Vec3::new(3.0, 0.0, 0.0));
        let b = s.instances[1];
        assert_eq!(
            b.world_from_object.transform_point3(Vec3::X),
            Vec3::new(0.0, 3.0, 0.0)
        );
        assert!(b.is_mirrored() && !s.instances[0].is_mirrored());
        // No NORMAL: flat normals, one vertex per corner, facing +Z for this CCW triangle.
        assert_eq!(s.meshes[0].positions.len(), 3);
        assert!(s.meshes[0].normals.iter().all(|n| *n == Vec3::Z));
        // No material: the glTF default one.
        assert_eq!(s.materials, vec![crate::Material::default()]);
    }

    #[test]
    fn far_scenes_are_recentred_in_f64() {
        // A root at 1e6 (f32 spacing 0.0625 there) with children 0.3 apart: in f32 the
        // composition would round 1e6 + 0.3 to 1e6 + 0.3125.
        let s = load_json(&gltf(
            json!([
                {"translation": [1e6, 0, -1e6], "children": [1, 2, 3]},
                {"mesh": 0, "translation": [0.3, 0, 0]},
                {"mesh": 0, "translation": [-0.3, 0, 0]},
                {"camera": 0, "translation": [0.3, 0, 2]}
            ]),
            json!([0]),
            json!({"cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}]}),
        ))
        .unwrap();
        // Geometry spans x in [-0.3, 1.3], y in [0, 1] around the root.
        assert_eq!(s.world_origin, DVec3::new(1e6 + 0.5, 0.5, -1e6));
        let o = |i: usize| {
            s.instances[i]
                .world_from_object
                .transform_point3(Vec3::ZERO)
        };
        assert!(
            (o(0) - Vec3::new(-0.2, -0.5, 0.0)).length() < 1e-6,
            "{}",
            o(0)
        );
        assert!(
            (o(1) - Vec3::new(-0.8, -0.5, 0.0)).length() < 1e-6,
            "{}",
            o(1)
        );
        let eye = Vec3::from(s.cameras[0].world_from_camera.translation);
        assert!((eye - Vec3::new(-0.2, -0.5, 2.0)).length() < 1e-6, "{eye}");
        assert!(s.stats.warnings.is_empty(), "{:?}", s.stats.warnings);

        // Vertices far from their own mesh origin move into the instance transform.
        let mut b: Value =
            serde_json::from_slice(&gltf(json!([{"mesh": 0}]), json!([0]), json!({}))).unwrap();
        let far: Vec<u8> = [1e6f32, 0.0, 0.0, 1e6 + 1.0, 0.0, 0.0, 1e6, 1.0, 0.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .chain(bin()[36..].iter().copied())
            .collect();
        b["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&far)
        ));
        b["accessors"][0]["min"] = json!([1e6, 0, 0]);
        b["accessors"][0]["max"] = json!([1e6 + 1.0, 1, 0]);
        let s = load_json(&serde_json::to_vec(&b).unwrap()).unwrap();
        assert_eq!(s.world_origin, DVec3::new(1e6 + 0.5, 0.5, 0.0));
        assert_eq!(s.meshes[0].positions[1], Vec3::new(0.5, -0.5, 0.0));
        assert_eq!(s.bounds().min, Vec3::new(-0.5, -0.5, 0.0));

        // A scene whose own extent f32 cannot hold at millimetres is loaded with a warning.
        let s = load_json(&gltf(
            json!([{"mesh": 0}, {"mesh": 0, "translation": [3e4, 0, 0], "scale": [1e-3, 1e-3, 1e-3]}]),
            json!([0, 1]),
            json!({}),
        ))
        .unwrap();
        assert!(
            s.stats.warnings.iter().any(|w| w.contains("float32")),
            "{:?}",
            s.stats.warnings
        );
    }

    #[test]
    fn gpu_instancing_multiplies_instances_not_geometry() {
        let s = load_json(&gltf(
            json!([{"mesh": 0, "translation": [0, 0, 1],
                "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 2}}}}]),
            json!([0]),
            json!({"extensionsUsed": ["EXT_mesh_gpu_instancing"], "extensionsRequired": ["EXT_mesh_gpu_instancing"]}),
        ))
        .unwrap();
        assert_eq!(s.meshes.len(), 1);
        assert_eq!(s.unique_triangle_count(), 1);
        assert_eq!(s.drawn_triangle_count(), 3);
        let origins: Vec<Vec3> = s
            .instances
            .iter()
            .map(|i| i.world_from_object.transform_point3(Vec3::ZERO))
            .collect();
        assert_eq!(
            origins,
            [
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(5.0, 0.0, 1.0),
                Vec3::new(0.0, 5.0, 1.0)
            ]
        );
    }

    #[test]
    fn lights_in_blender_units_placed_by_nodes() {
        let s = load_json(&gltf(
            json!([
                {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0],
                 "rotation": [-std::f32::consts::FRAC_1_SQRT_2, 0, 0, std::f32::consts::FRAC_1_SQRT_2]},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}}
            ]),
            json!([0, 1]),
            json!({"extensionsUsed": ["KHR_lights_punctual"], "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "spot", "intensity": 683, "color": [1, 0.5, 0], "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}},
                {"type": "directional", "intensity": 1366}
            ]}}}),
        ))
        .unwrap();
        assert_eq!(s.lights.len(), 2);
        let spot = &s.lights[0];
        assert!(
            (spot.intensity - Vec3::new(1.0, 0.5, 0.0))
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(
            (spot.direction - Vec3::NEG_Y).length() < 1e-5,
            "{}",
            spot.direction
        );
        assert_eq!(spot.position, Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(
            spot.kind,
            LightKind::Spot {
                inner_cone: 0.1,
                outer_cone: 0.5
            }
        );
        assert!(
            (s.lights[1].intensity - Vec3::splat(2.0))
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn camera_scale_is_removed_and_automatic_camera_frames_bounds() {
        let cam = json!({"cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}]});
        let s = load_json(&gltf(
            json!([{"mesh": 0}, {"camera": 0, "scale": [3, 3, 3], "translation": [0, 0, 4]}]),
            json!([0, 1]),
            cam,
        ))
        .unwrap();
        let c = &s.cameras[0];
        assert_eq!(c.node, Some(1));
        assert!((c.world_from_camera.matrix3.determinant() - 1.0).abs() < 1e-5);
        assert_eq!(
            Vec3::from(c.world_from_camera.translation),
            Vec3::new(0.0, 0.0, 4.0)
        );

        let s = load_json(&gltf(json!([{"mesh": 0}]), json!([0]), json!({}))).unwrap();
        assert_eq!(s.cameras.len(), 1);
        let c = &s.cameras[0];
        assert_eq!(c.node, None);
        let eye = Vec3::from(c.world_from_camera.translation);
        let forward = Vec3::from(-c.world_from_camera.matrix3.z_axis);
        let to_center = (s.bounds().center() - eye).normalize();
        assert!(forward.dot(to_center) > 0.9999);
        assert!(eye.z > s.bounds().max.z && eye.y > s.bounds().center().y);
        assert!(!c.dof.enabled);
    }

    #[test]
    fn dof_sources_reach_the_camera() {
        let extra = json!({"cameras": [{"name": "Lens", "type": "perspective",
            "perspective": {"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1},
            "extensions": {"EXT_camera_physical": {"focalLength": 0.05, "fStop": 4.0, "focusDistance": 2.0}},
            "extras": {"aperture_blades": 6}}]});
        let nodes = json!([
            {"mesh": 0, "name": "Target", "translation": [0, 0, -3]},
            {"camera": 0, "translation": [0, 0, 4], "extras": {"focus_object": {"name": "Target", "type": "Object"}}}
        ]);
        let s = load_json(&gltf(nodes.clone(), json!([0, 1]), extra.clone())).unwrap();
        let d = &s.cameras[0].dof;
        assert!(d.enabled);
        assert_eq!(d.lens_mm, 50.0);
        assert!((d.aperture_radius - 0.05 / 8.0).abs() < 1e-7);
        assert!((d.focus_distance - 7.0).abs() < 1e-5);
        assert_eq!(d.focus_object.as_deref(), Some("Target"));
        assert_eq!(d.blades, 6);
        // The command line wins over every file source.
        let opts = LoadOptions {
            dof_overrides: crate::DofOverrides {
                aperture_radius: Some(0.5),
                focus_distance: Some(1.5),
                ..Default::default()
            },
            ..LoadOptions::default()
        };
        let s = load_bytes(&gltf(nodes, json!([0, 1]), extra), Path::new("."), &opts).unwrap();
        assert_eq!(
            (
                s.cameras[0].dof.aperture_radius,
                s.cameras[0].dof.focus_distance
            ),
            (0.5, 1.5)
        );
        assert_eq!(s.cameras[0].dof.focus_object, None);
    }

    #[test]
    fn only_images_of_drawn_materials_are_decoded() {
        // Material 1 is used by no primitive; its image file does not exist.
        let extra = json!({
            "images": [{"uri": "does-not-exist.png"}],
            "textures": [{"source": 0}],
            "materials": [{"name": "used"}, {"name": "unused", "emissiveTexture": {"index": 0}}]
        });
        let mut bytes: Value =
            serde_json::from_slice(&gltf(json!([{"mesh": 0}]), json!([0]), extra)).unwrap();
        bytes["meshes"][0]["primitives"][0]["material"] = json!(0);
        let s = load_json(&serde_json::to_vec(&bytes).unwrap()).unwrap();
        assert_eq!(s.materials.len(), 1);
        assert_eq!(s.materials[0].name.as_deref(), Some("used"));
        assert!(s.textures.is_empty());
        // Used, the same file is an error that names the image.
        bytes["meshes"][0]["primitives"][0]["material"] = json!(1);
        let e = load_json(&serde_json::to_vec(&bytes).unwrap()).unwrap_err();
        assert!(e.to_string().contains("images[0].uri"), "{e}");
    }

    #[test]
    fn material_extensions_are_read_without_warnings() {
        let extra = json!({
            "materials": [{"name": "Glass", "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_volume": {"thicknessFactor": 0.5, "attenuationDistance": 2.0,
                                         "attenuationColor": [0.5, 0.5, 1.0]},
                "KHR_materials_ior": {"ior": 1.4},
                "KHR_materials_clearcoat": {"clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.2},
                "KHR_materials_sheen": {"sheenColorFactor": [0.1, 0.2, 0.3], "sheenRoughnessFactor": 0.4},
                "KHR_materials_dispersion": {"dispersion": 0.5}
            }}]
        });
        let mut bytes: Value = serde_json::from_slice(&gltf(
            json!([{"mesh": 0}, {"mesh": 0}]),
            json!([0, 1]),
            extra,
        ))
        .unwrap();
        bytes["meshes"][0]["primitives"][0]["material"] = json!(0);
        let s = load_json(&serde_json::to_vec(&bytes).unwrap()).unwrap();
        assert!(
            !s.stats.warnings.iter().any(|w| w.contains("Glass")),
            "{:?}",
            s.stats.warnings
        );
        let m = &s.materials[0];
        assert_eq!(m.ior, 1.4);
        assert_eq!(m.transmission.map(|t| t.factor), Some(1.0));
        let v = m.volume.unwrap();
        assert!(v.is_volume() && v.attenuation_distance == 2.0);
        assert_eq!(
            m.clearcoat.map(|c| (c.factor, c.roughness_factor)),
            Some((0.7, 0.2))
        );
        assert_eq!(
            m.sheen.map(|c| c.color_factor),
            Some(glam::Vec3::new(0.1, 0.2, 0.3))
        );
        assert_eq!(m.dispersion, 0.5);
        assert!(m.has_extended_lobes());
    }
}
