//! The loader: file → pre-pass → buffers → node hierarchy → meshes, materials, textures, lights,
//! cameras.

use std::collections::HashMap;
use std::path::Path;

use glam::{Affine3A, Mat3, Mat4, Quat, Vec3};
use serde_json::Value;

use crate::accessor::{read_vec, Buffers};
use crate::dof::{self, CameraInput, NodeInfo};
use crate::material::Materials;
use crate::{
    glb, mesh, prepass, uri, Camera, Error, Instance, Light, LightKind, LoadOptions, Projection,
    Scene, SceneStats,
};

/// Watts per lumen at 555 nm: Blender's importer divides candela and lux by it (SPEC §4).
const LUMENS_PER_WATT: f32 = 683.0;

/// Loads a `.gltf` or `.glb` file into a render-ready [`Scene`].
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, Error> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let base_dir = if base_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base_dir
    };
    load_bytes(&bytes, base_dir, options)
}

/// Loads a scene from the bytes of a `.gltf` or `.glb` file; external URIs resolve inside `base_dir`.
pub fn load_bytes(bytes: &[u8], base_dir: &Path, options: &LoadOptions) -> Result<Scene, Error> {
    let glb_is = glb::is_glb(bytes);
    let (json, bin) = if glb_is {
        let g = glb::parse(bytes)?;
        (g.json, g.bin)
    } else {
        (bytes, None)
    };
    let prepared = prepass::prepare(json)?;
    let doc = prepared.document;
    let mut stats = SceneStats {
        skipped_features: prepared.skipped,
        ..SceneStats::default()
    };
    let buffers = load_buffers(&doc, bin, base_dir)?;
    let nodes = world_transforms(&doc)?;

    // The scene to draw.
    let scene = match options.scene {
        Some(i) => Some(doc.scenes().nth(i).ok_or(Error::NoSuchScene {
            index: i,
            count: doc.scenes().len(),
        })?),
        None => doc.default_scene().or_else(|| doc.scenes().next()),
    };
    let mut order = Vec::new();
    match &scene {
        Some(s) => {
            let mut seen = vec![false; nodes.len()];
            let mut stack: Vec<usize> = s.nodes().map(|n| n.index()).collect();
            stack.reverse();
            while let Some(i) = stack.pop() {
                if std::mem::replace(&mut seen[i], true) {
                    continue;
                }
                order.push(i);
                if let Some(n) = doc.nodes().nth(i) {
                    let mut kids: Vec<usize> = n.children().map(|c| c.index()).collect();
                    kids.reverse();
                    stack.extend(kids);
                }
            }
        }
        None => stats
            .warnings
            .push("the file has no scene: nothing is drawn".into()),
    }
    stats.nodes = order.len();

    let mut out = Scene::default();
    let mut materials = Materials::default();
    let mut mesh_of: HashMap<usize, u32> = HashMap::new();
    let all_nodes: Vec<gltf::Node<'_>> = doc.nodes().collect();
    for &ni in &order {
        let node = &all_nodes[ni];
        let world = nodes[ni];
        if let Some(m) = node.mesh() {
            let mesh_index = match mesh_of.get(&m.index()) {
                Some(&i) => i,
                None => {
                    let loaded = mesh::load_mesh(&m, &buffers, &mut stats, &mut |mi| {
                        materials.get(&doc, mi)
                    })?;
                    out.meshes.push(loaded);
                    let i = (out.meshes.len() - 1) as u32;
                    mesh_of.insert(m.index(), i);
                    i
                }
            };
            match node.extension_value("EXT_mesh_gpu_instancing") {
                Some(ext) => {
                    for local in gpu_instances(&doc, &buffers, ext, ni)? {
                        out.instances.push(Instance {
                            mesh: mesh_index,
                            world_from_object: world * local,
                            node: ni as u32,
                        });
                    }
                }
                None => out.instances.push(Instance {
                    mesh: mesh_index,
                    world_from_object: world,
                    node: ni as u32,
                }),
            }
        }
        if let Some(light) = node.light() {
            let color = Vec3::from(light.color());
            let intensity = color * light.intensity() / LUMENS_PER_WATT;
            let kind = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
                gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
                gltf::khr_lights_punctual::Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => LightKind::Spot {
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                },
            };
            if !intensity.is_finite() {
                return Err(Error::NonFinite {
                    at: format!("KHR_lights_punctual.lights[{}]", light.index()),
                    value: format!("{intensity:?}"),
                });
            }
            out.lights.push(Light {
                name: light.name().map(str::to_owned),
                kind,
                position: world.translation.into(),
                direction: world
                    .transform_vector3(Vec3::NEG_Z)
                    .try_normalize()
                    .unwrap_or(Vec3::NEG_Z),
                intensity,
            });
        }
    }

    let names: Vec<Option<String>> = all_nodes
        .iter()
        .map(|n| n.name().map(str::to_owned))
        .collect();
    let origins: Vec<Vec3> = nodes.iter().map(|m| Vec3::from(m.translation)).collect();
    let info = NodeInfo {
        names: &names,
        origins: &origins,
    };
    for &ni in &order {
        let node = &all_nodes[ni];
        if let Some(cam) = node.camera() {
            out.cameras
                .push(camera(&cam, node, nodes[ni], &info, options)?);
        }
    }

    out.materials = std::mem::take(&mut materials.materials);
    out.textures = materials.textures(&doc, &buffers, base_dir, options.skip_textures)?;
    if out.cameras.is_empty() {
        out.cameras.push(automatic_camera(&out, &info, options)?);
    }
    if doc.meshes().len() > 0 && out.instances.is_empty() {
        stats
            .warnings
            .push("the selected scene draws no mesh".into());
    }
    out.stats = stats;
    Ok(out)
}

/// Reads every buffer: the GLB BIN chunk, `data:` URIs or files beside the scene.
fn load_buffers(
    doc: &gltf::Document,
    bin: Option<&[u8]>,
    base_dir: &Path,
) -> Result<Buffers, Error> {
    let mut data = Vec::with_capacity(doc.buffers().len());
    for b in doc.buffers() {
        let at = format!("buffers[{}]", b.index());
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
    Ok(Buffers { data, total })
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

/// A node's local transform, checked for NaN and infinity.
fn local_transform(node: &gltf::Node<'_>) -> Result<Affine3A, Error> {
    let i = node.index();
    let m = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let m = Mat4::from_cols_array_2d(&matrix);
            finite(|| format!("nodes[{i}].matrix"), &m.to_cols_array())?;
            m
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
            let q = Quat::from_array(rotation);
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                return Err(Error::NonFinite {
                    at: format!("nodes[{i}].rotation"),
                    value: "zero quaternion".into(),
                });
            };
            Mat4::from_scale_rotation_translation(scale.into(), q, translation.into())
        }
    };
    Ok(Affine3A::from_mat4(m))
}

/// World transforms of all nodes (not only the drawn scene's: `focus_object` may name any node).
fn world_transforms(doc: &gltf::Document) -> Result<Vec<Affine3A>, Error> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    let mut local = Vec::with_capacity(n);
    for node in doc.nodes() {
        local.push(local_transform(&node)?);
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
    }
    let mut world: Vec<Option<Affine3A>> = vec![None; n];
    let children: Vec<Vec<usize>> = doc
        .nodes()
        .map(|nd| nd.children().map(|c| c.index()).collect())
        .collect();
    let mut stack: Vec<usize> = (0..n).filter(|&i| parent[i].is_none()).collect();
    for &r in &stack {
        world[r] = Some(local[r]);
    }
    while let Some(i) = stack.pop() {
        let w = world[i].unwrap_or(Affine3A::IDENTITY);
        for &c in &children[i] {
            world[c] = Some(w * local[c]);
            stack.push(c);
        }
    }
    world
        .into_iter()
        .enumerate()
        .map(|(i, w)| {
            w.ok_or_else(|| Error::NodeGraph {
                node: i,
                reason: "is part of a cycle in the node hierarchy".into(),
            })
        })
        .collect()
}

/// `EXT_mesh_gpu_instancing`: one local transform per instance (TRS, each optional).
fn gpu_instances(
    doc: &gltf::Document,
    buffers: &Buffers,
    ext: &Value,
    node: usize,
) -> Result<Vec<Affine3A>, Error> {
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
            let tr = t.as_ref().map_or(Vec3::ZERO, |v| Vec3::from(v[k]));
            let q = r
                .as_ref()
                .map_or(Quat::IDENTITY, |v| Quat::from_array(v[k]));
            let sc = s.as_ref().map_or(Vec3::ONE, |v| Vec3::from(v[k]));
            let m = Affine3A::from_scale_rotation_translation(sc, q.normalize(), tr);
            finite(|| format!("{at}[{k}]"), &Mat4::from(m).to_cols_array())?;
            Ok(m)
        })
        .collect()
}

/// Rotation and translation of a world transform: scale and shear removed (SPEC §1), keeping the
/// view axis (−Z) exact and +Y as close to the node's as possible.
fn orthonormal(world: Affine3A) -> Option<Affine3A> {
    let z = Vec3::from(world.matrix3.z_axis).try_normalize()?;
    let y0 = Vec3::from(world.matrix3.y_axis);
    let y = (y0 - z * z.dot(y0)).try_normalize()?;
    let x = y.cross(z);
    Some(Affine3A {
        matrix3: Mat3::from_cols(x, y, z).into(),
        translation: world.translation,
    })
}

fn camera(
    cam: &gltf::Camera<'_>,
    node: &gltf::Node<'_>,
    world: Affine3A,
    info: &NodeInfo<'_>,
    options: &LoadOptions,
) -> Result<Camera, Error> {
    let name = cam
        .name()
        .or(node.name())
        .map(str::to_owned)
        .unwrap_or_else(|| format!("camera {}", cam.index()));
    let at = format!("cameras[{}]", cam.index());
    let projection = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let yfov = p.yfov();
            if !(yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI) {
                return Err(Error::Invalid {
                    at: format!("{at}.perspective.yfov"),
                    reason: format!("{yfov} is not in (0, π)"),
                });
            }
            Projection::Perspective {
                yfov,
                aspect_ratio: p.aspect_ratio(),
            }
        }
        gltf::camera::Projection::Orthographic(o) => {
            let (xmag, ymag) = (o.xmag(), o.ymag());
            finite(|| format!("{at}.orthographic"), &[xmag, ymag])?;
            Projection::Orthographic { xmag, ymag }
        }
    };
    let world_from_camera = orthonormal(world).ok_or_else(|| Error::NodeGraph {
        node: node.index(),
        reason: "the camera's transform has no rotation (zero scale)".into(),
    })?;
    let raw = |e: &Option<Box<serde_json::value::RawValue>>| {
        e.as_ref()
            .and_then(|r| serde_json::from_str::<Value>(r.get()).ok())
    };
    let camera_extras = raw(cam.extras());
    let node_extras = raw(node.extras());
    let dof = dof::resolve(
        &CameraInput {
            name: &name,
            projection,
            world_from_camera,
            physical: cam.extension_value("EXT_camera_physical"),
            camera_extras: camera_extras.as_ref(),
            node_extras: node_extras.as_ref(),
        },
        &options.dof_overrides,
        info,
    )?;
    Ok(Camera {
        name,
        node: Some(node.index() as u32),
        world_from_camera,
        projection,
        dof,
    })
}

/// Vertical field of view of the automatic camera.
const AUTO_YFOV_DEGREES: f32 = 40.0;

/// A camera that frames the scene's bounding sphere from the +Z side, slightly above; pinhole
/// unless the command line asks for depth of field.
fn automatic_camera(
    scene: &Scene,
    info: &NodeInfo<'_>,
    options: &LoadOptions,
) -> Result<Camera, Error> {
    let b = scene.bounds();
    let (center, radius) = if b.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (b.center(), (0.5 * b.diagonal()).max(1e-3))
    };
    let yfov = AUTO_YFOV_DEGREES.to_radians();
    // The sphere touches the top and bottom of the frame; wider frames have room to spare.
    let distance = radius / (0.5 * yfov).sin();
    let back = Vec3::new(0.0, 0.3, 1.0).normalize();
    let eye = center + back * distance;
    // Camera +Z points back at the eye from the centre; +X right, +Y up.
    let z = back;
    let x = Vec3::Y.cross(z).normalize();
    let y = z.cross(x);
    let world_from_camera = Affine3A::from_mat3_translation(Mat3::from_cols(x, y, z), eye);
    let projection = Projection::Perspective {
        yfov,
        aspect_ratio: None,
    };
    let name = "automatic camera".to_owned();
    let mut dof = dof::resolve(
        &CameraInput {
            name: &name,
            projection,
            world_from_camera,
            physical: None,
            camera_extras: None,
            node_extras: None,
        },
        &options.dof_overrides,
        info,
    )?;
    if options.dof_overrides.focus_distance.is_none()
        && options.dof_overrides.focus_object.is_none()
    {
        // Focus on the scene's centre rather than Blender's 10 m.
        dof.focus_distance = distance;
    }
    Ok(Camera {
        name,
        node: None,
        world_from_camera,
        projection,
        dof,
    })
}
