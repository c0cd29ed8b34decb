//! A loaded, decoded glTF document that can be posed at any time (SPEC §7): [`Animated`].
//!
//! Loading reads and decodes everything once (buffers, compressed geometry, meshes with their
//! morph targets and joint influences, materials, textures, animations). Posing evaluates the
//! selected animations at a time, composes the node hierarchy, deforms what is skinned or morphed
//! and places meshes, lights and cameras. Meshes that no selected animation deforms are built
//! once, at load, and come first in every posed [`Scene::meshes`], identical at every time; the
//! meshes deformed per pose follow them.

mod edit;
mod framing;
mod lens_images;
mod pose;
mod shapes;
mod variants;
mod visibility;

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use serde_json::Value;

use glam::{DAffine3, DQuat, DVec3, Vec3};

use crate::animation::{self, AnimationInfo, Animations, NodeProperty, Target};
use crate::buffers::load_buffers;
use crate::camera::{self, CameraData};
use crate::edit::{apply_graph_edits, apply_loaded_keys, Edit};
use crate::error::Error;
use crate::material::Materials;
use crate::mesh::LoadedMesh;
use crate::nodes::{node_graph, NodeGraph};
use crate::pointer::Pointer;
use crate::skin::Skin;
use crate::types::{LightKind, LoadOptions, Material, Mesh, Scene, SceneStats, Texture};
use crate::{glb, prepass, skin};
use variants::{resolve_variant, variant_names};

/// Watts per lumen at 555 nm: Blender's importer divides candela and lux by it (SPEC §4).
const LUMENS_PER_WATT: f32 = 683.0;

/// A `KHR_lights_punctual` light as stored.
#[derive(Debug, Clone)]
struct LightData {
    name: Option<String>,
    color: Vec3,
    intensity: f32,
    kind: LightKind,
}

/// How a drawing node's mesh is obtained at a pose.
#[derive(Debug, Clone, Copy)]
enum Shape {
    /// The same for every pose: `Scene::meshes[mesh]`, placed by the node's world transform times
    /// a translation by `offset` (its recentring), or, for a skinned mesh (already in world
    /// space), by the translation alone.
    Static {
        mesh: u32,
        offset: DVec3,
        world_space: bool,
    },
    /// Morphed or skinned differently at every time: deformed per pose.
    Deforming,
}

/// A glTF document loaded and decoded once, ready to be posed at any time.
///
/// ```no_run
/// use aperture_scene::{Animated, LoadOptions};
/// let doc = Animated::load("walk.glb".as_ref(), &LoadOptions::default())?;
/// for frame in 1..=3 {
///     let scene = doc.scene_at(Some(frame as f32 / 24.0))?;
///     // Meshes below doc.static_mesh_count() are the same at every time: reuse their BVHs.
///     println!("{frame}: {} meshes, {} deformed", scene.meshes.len(),
///         scene.meshes.len() - doc.static_mesh_count());
/// }
/// # Ok::<(), aperture_scene::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Animated {
    graph: NodeGraph,
    /// Drawn nodes, depth first from the selected scene's roots.
    order: Vec<usize>,
    meshes: HashMap<usize, LoadedMesh>,
    /// glTF meshes drawing another's geometry (`crate::shared`): that mesh, and their
    /// per-triangle materials when not its own.
    aliases: HashMap<usize, (usize, Option<Vec<u32>>)>,
    /// `Scene::material_sets`, the same at every pose.
    material_sets: Vec<Vec<u32>>,
    /// By node: its instances' `Instance::materials` when not 0.
    node_materials: HashMap<usize, u32>,
    /// `EXT_lights_image_based`, the same at every pose.
    environment: Option<std::sync::Arc<crate::types::ImageEnvironment>>,
    skins: Vec<Skin>,
    cameras: Vec<CameraData>,
    /// The cameras' bokeh images (`aperture_image`), loaded once.
    aperture_images: std::sync::Arc<crate::dof::image::ApertureImages>,
    lights: Vec<LightData>,
    materials: Vec<Material>,
    material_index: HashMap<usize, u32>,
    /// The file's `materials` count (an edit may name one no shown mesh uses yet).
    file_materials: usize,
    textures: Vec<Texture>,
    animations: Animations,
    static_meshes: Vec<Arc<Mesh>>,
    shapes: HashMap<usize, Shape>,
    /// Per node: it or an ancestor is moved by a selected channel.
    moves: Vec<bool>,
    /// Per node: it or an ancestor has its `KHR_node_visibility` flag keyed.
    toggles: Vec<bool>,
    options: LoadOptions,
    stats: SceneStats,
    draws_nothing: bool,
    /// The automatic camera's framing on the stored pose, for an animated file without a
    /// camera; `None` when every pose frames itself alike (nothing animates, or cameras exist).
    framing: Option<crate::auto_camera::Framing>,
    /// `content_hash` of the file's bytes.
    source_hash: u64,
    /// The file's folder, where a `lens_prescription` path starts.
    base_dir: std::path::PathBuf,
}

/// Node transforms and morph weights at one time, plus the pointer values.
struct Pose {
    world: Vec<DAffine3>,
    node_weights: HashMap<usize, Vec<f32>>,
    mesh_weights: HashMap<usize, Vec<f32>>,
    pointers: Vec<(Pointer, Vec<f64>)>,
}

/// Runs a step of the loader. The parsing crates keep overflow checks in release builds
/// (Cargo.toml): a size from a hostile header that wraps, or any other panic of the loader, is
/// an error here.
fn guard(step: impl FnOnce() -> Result<Animated, Error>) -> Result<Animated, Error> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(step)).unwrap_or_else(|panic| {
        let message = crate::error::panic_message(&*panic);
        Err(Error::Panicked { message })
    })
}

impl Animated {
    /// Loads and decodes a `.gltf` or `.glb` file once.
    pub fn load(path: &Path, options: &LoadOptions) -> Result<Self, Error> {
        Self::load_path(path, options, &[])
    }

    /// [`Animated::load`] with node edits applied to the graph before anything is decoded, and
    /// the camera keys read with the file set before they are read (`crate::edit::load_edit`).
    fn load_path(path: &Path, options: &LoadOptions, graph_edits: &[Edit]) -> Result<Self, Error> {
        let bytes = std::fs::read(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let base_dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let named_glb = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        if named_glb && !glb::is_glb(&bytes) {
            // A .glb without the magic is a damaged container, not JSON: say so.
            glb::parse(&bytes)?;
        }
        let read = Self::decode(&bytes, base_dir, options, graph_edits)?;
        // Everything is decoded: the file's bytes go before the static shapes are built
        // (for a big scene, as many bytes again as its meshes; issue 59).
        drop(bytes);
        guard(|| read.prepare())
    }

    /// Loads from the bytes of a `.gltf` or `.glb` file; external URIs resolve inside `base_dir`.
    pub fn load_bytes(bytes: &[u8], base_dir: &Path, options: &LoadOptions) -> Result<Self, Error> {
        let read = Self::decode(bytes, base_dir, options, &[])?;
        guard(|| read.prepare())
    }

    /// [`Animated::unguarded`] under the panic guard, with the file's hash computed beside it
    /// (the decoding leaves a thread idle at times).
    fn decode(
        bytes: &[u8],
        base_dir: &Path,
        options: &LoadOptions,
        graph_edits: &[Edit],
    ) -> Result<Self, Error> {
        let (read, source_hash) = rayon::join(
            || guard(|| Self::unguarded(bytes, base_dir, options, graph_edits)),
            || crate::hash::content_hash(bytes),
        );
        Ok(Self {
            source_hash,
            ..read?
        })
    }

    /// Reads and decodes the file: an [`Animated`] not yet prepared ([`Animated::prepare`]),
    /// its `source_hash` left to [`Animated::decode`].
    fn unguarded(
        bytes: &[u8],
        base_dir: &Path,
        options: &LoadOptions,
        graph_edits: &[Edit],
    ) -> Result<Self, Error> {
        let (json, bin) = glb::split(bytes)?;
        let prepared = prepass::prepare(json)?;
        let (doc, root) = (prepared.document, prepared.root);
        let (mut stats, variant) =
            first_stats(prepared.skipped, prepared.extensions, &doc, &root, options)?;
        let mut buffers = load_buffers(&doc, &root, bin, base_dir, &options.memory)?;
        crate::meshopt::decode_views(&root, &mut buffers)?;
        let mut graph = apply_graph_edits(node_graph(&doc, &buffers)?, graph_edits)?;
        let order = drawn_order(&doc, options, &graph, &mut stats)?;
        stats.nodes = order.len();

        let animations = animation::parse(&doc, &buffers, &root, &options.animation)?;
        pointer_warnings(&animations, &mut stats.warnings);
        stats.animations = animations.info.clone();
        let (toggles, never_shown) =
            visibility::plan(&graph, &animations.channels, &order, &mut stats);

        let mut materials = Materials::default();
        let read = crate::shared::read_shown(
            &doc,
            &order,
            &never_shown,
            &buffers,
            &mut stats,
            crate::shared::Reading::new(variant, graph_edits),
            &mut materials,
        )?;
        let material_index = materials.gltf_indices();
        let material_list = std::mem::take(&mut materials.materials);
        stats.warnings.append(&mut materials.warnings);
        let textures = materials.textures(
            &doc,
            &buffers,
            base_dir,
            options.skip_textures,
            &options.memory,
        )?;
        let environment = crate::ibl::scene_environment(&doc, &root, options, &buffers, base_dir)?;
        let skins = skin::read_skins(&doc, &buffers)?;
        let mut cameras = camera::read_cameras(&doc)?;
        apply_loaded_keys(&mut cameras, &mut graph, graph_edits)?;
        let images = lens_images::load(&doc, &buffers, base_dir, &cameras, &graph, options)?;
        let animated = Animated {
            aperture_images: images,
            moves: vec![false; graph.nodes.len()],
            toggles,
            graph,
            order,
            meshes: read.meshes,
            aliases: read.aliases,
            material_sets: Vec::new(),
            node_materials: HashMap::new(),
            environment,
            skins,
            cameras,
            lights: read_lights(&doc)?,
            materials: material_list,
            material_index,
            file_materials: doc.materials().len(),
            textures,
            animations,
            static_meshes: Vec::new(),
            shapes: HashMap::new(),
            options: options.clone(),
            stats,
            draws_nothing: doc.meshes().len() > 0,
            framing: None,
            source_hash: 0,
            base_dir: base_dir.to_path_buf(),
        };
        // Done with: freed before posing (with two million nodes, 0.5 GB less at the peak).
        drop((doc, root, buffers));
        Ok(animated)
    }

    /// What loading does once the document is read and its buffers are freed: classifies the
    /// meshes (building the static ones), then frames the automatic camera on the stored pose.
    fn prepare(mut self) -> Result<Self, Error> {
        self.classify()?;
        self.frame_stored_pose()?;
        Ok(self)
    }

    /// The file's animations (every one, with whether this load evaluates it).
    pub fn animations(&self) -> &[AnimationInfo] {
        &self.animations.info
    }

    /// True when a selected animation changes anything (else every time gives the stored pose).
    pub fn is_animated(&self) -> bool {
        !self.animations.channels.is_empty()
    }

    /// How many meshes at the start of every posed [`Scene::meshes`] are the same at every time
    /// (nothing deforms them): a renderer may keep their BVHs from one time to the next. The
    /// meshes after them are deformed per pose (skinned or morphed by a selected animation).
    pub fn static_mesh_count(&self) -> usize {
        self.static_meshes.len()
    }

    /// Nodes whose world transform changes with time (moved by a selected channel, or below
    /// such a node): their instances, lights and cameras move; nothing else does.
    pub fn moving_nodes(&self) -> Vec<u32> {
        (0..self.moves.len())
            .filter(|&n| self.moves[n])
            .map(|n| n as u32)
            .collect()
    }

    /// The scene at `time` seconds (`None`: the stored pose, no animation evaluated).
    pub fn scene_at(&self, time: Option<f32>) -> Result<Scene, Error> {
        self.build(time, self.static_meshes.clone(), self.textures.clone())
    }

    /// [`Animated::scene_at`], consuming the document (no copy of the geometry and textures).
    pub fn into_scene(mut self, time: Option<f32>) -> Result<Scene, Error> {
        let meshes = std::mem::take(&mut self.static_meshes);
        let textures = std::mem::take(&mut self.textures);
        self.build(time, meshes, textures)
    }

    /// The glTF mesh whose geometry node `ni` draws for its mesh `mi` (`mi` unless it shares
    /// another's accessors), noting the node's materials when they are not that mesh's.
    fn geometry_of(&mut self, ni: usize, mi: usize) -> usize {
        let Some((canon, set)) = self.aliases.get(&mi) else {
            return mi;
        };
        if let Some(list) = set {
            let k = match self.material_sets.iter().position(|s| s == list) {
                Some(k) => k,
                None => {
                    self.material_sets.push(list.clone());
                    self.material_sets.len() - 1
                }
            };
            self.node_materials.insert(ni, k as u32 + 1);
        }
        *canon
    }

    /// Node transforms and weights at `time` (`None`: stored).
    fn pose(&self, time: Option<f32>) -> Pose {
        let n = self.graph.nodes.len();
        // Per node, its animated scale, rotation and translation: only when something is
        // animated (88 bytes a node, 176 MB for two million nodes, for nothing otherwise).
        let animated = time.is_some() && !self.animations.channels.is_empty();
        let mut trs: Vec<Option<(DVec3, DQuat, DVec3)>> = vec![None; if animated { n } else { 0 }];
        let mut pose = Pose {
            world: vec![DAffine3::IDENTITY; n],
            node_weights: HashMap::new(),
            mesh_weights: HashMap::new(),
            pointers: Vec::new(),
        };
        if let Some(t) = time {
            for c in &self.animations.channels {
                let rotation = matches!(c.target, Target::Node(_, NodeProperty::Rotation));
                let v = c.sampler.sample(t, rotation);
                match &c.target {
                    Target::Node(i, NodeProperty::Weights) => {
                        pose.node_weights
                            .insert(*i, v.iter().map(|&x| x as f32).collect());
                    }
                    Target::Node(i, prop) => {
                        let slot =
                            trs[*i].get_or_insert_with(|| self.graph.nodes[*i].transform.trs());
                        match prop {
                            NodeProperty::Translation => slot.2 = animation::vec3(&v),
                            NodeProperty::Rotation => {
                                if let Some(q) = animation::quat(&v) {
                                    slot.1 = q;
                                }
                            }
                            NodeProperty::Scale => slot.0 = animation::vec3(&v),
                            NodeProperty::Weights => {}
                        }
                    }
                    Target::Pointer(Pointer::MeshWeights(m)) => {
                        pose.mesh_weights
                            .insert(*m, v.iter().map(|&x| x as f32).collect());
                    }
                    Target::Pointer(p) => pose.pointers.push((p.clone(), v)),
                }
            }
        }
        for &i in &self.graph.topological {
            let local = match trs.get(i).copied().flatten() {
                Some((s, r, t)) => DAffine3::from_scale_rotation_translation(s, r, t),
                None => self.graph.nodes[i].transform.local(),
            };
            pose.world[i] = match self.graph.parent[i] {
                Some(p) => pose.world[p] * local,
                None => local,
            };
        }
        pose
    }
}

/// What the load knows before reading any buffer: skipped features, extensions and the
/// warnings for those ignored, the generator, the variants and the one chosen.
fn first_stats(
    skipped: Vec<String>,
    extensions: Vec<(String, crate::types::ExtensionStatus)>,
    doc: &gltf::Document,
    root: &Value,
    options: &LoadOptions,
) -> Result<(SceneStats, Option<usize>), Error> {
    let mut stats = SceneStats {
        skipped_features: skipped,
        warnings: ignored_extension_warnings(&prepass::ignored(&extensions)),
        extensions,
        ..SceneStats::default()
    };
    stats.generator = doc.as_json().asset.generator.clone();
    stats.variants = variant_names(root);
    let variant = resolve_variant(&stats.variants, options.variant.as_deref())?;
    stats.variant = variant.map(|v| stats.variants[v].clone());
    Ok((stats, variant))
}

/// The drawn nodes of the selected scene, depth first.
fn drawn_order(
    doc: &gltf::Document,
    options: &LoadOptions,
    graph: &NodeGraph,
    stats: &mut SceneStats,
) -> Result<Vec<usize>, Error> {
    let scene = match options.scene {
        Some(i) => Some(doc.scenes().nth(i).ok_or(Error::NoSuchScene {
            index: i,
            count: doc.scenes().len(),
        })?),
        None => doc.default_scene().or_else(|| doc.scenes().next()),
    };
    if let Some(s) = &scene {
        let extras = crate::camera::raw(s.extras());
        stats.motion = crate::shutter_extras::MotionExtras::parse(s.index(), extras.as_ref())?;
    }
    let mut order = Vec::new();
    match &scene {
        Some(s) => {
            let mut seen = vec![false; graph.nodes.len()];
            let mut stack: Vec<usize> = s.nodes().map(|n| n.index()).collect();
            stack.reverse();
            while let Some(i) = stack.pop() {
                if std::mem::replace(&mut seen[i], true) {
                    continue;
                }
                order.push(i);
                let mut kids = graph.children[i].clone();
                kids.reverse();
                stack.extend(kids);
            }
        }
        None => stats
            .warnings
            .push("the file has no scene: nothing is drawn".into()),
    }
    Ok(order)
}

/// Every `KHR_lights_punctual` light.
fn read_lights(doc: &gltf::Document) -> Result<Vec<LightData>, Error> {
    let Some(lights) = doc.lights() else {
        return Ok(Vec::new());
    };
    Ok(lights
        .map(|light| LightData {
            name: light.name().map(str::to_owned),
            color: Vec3::from(light.color()),
            intensity: light.intensity(),
            kind: match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
                gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
                gltf::khr_lights_punctual::Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => LightKind::Spot {
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                },
            },
        })
        .collect())
}

/// The warnings for extensions the file uses that aperture ignores.
fn ignored_extension_warnings(ignored: &[&str]) -> Vec<String> {
    ignored
        .iter()
        .map(|e| format!("extension {e} is used but not implemented: ignored"))
        .collect()
}

/// What the user should know of the `KHR_animation_pointer` pointers aperture ignores, and
/// of channels evaluated otherwise than keyed.
fn pointer_warnings(animations: &Animations, out: &mut Vec<String>) {
    let ignored = &animations.ignored_pointers;
    if !ignored.is_empty() {
        out.push(format!(
            "KHR_animation_pointer: {} pointer(s) at what aperture does not animate, ignored: {}",
            ignored.len(),
            ignored.join(", ")
        ));
    }
    out.extend(animations.warnings.iter().cloned());
}
