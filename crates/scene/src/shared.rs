//! The meshes the drawn nodes use, each read once, and glTF meshes whose primitives share their
//! geometry accessors read once between them (issue 50): a file that draws one sphere with 100
//! materials as 100 glTF meshes over the same accessors stores one [`crate::Mesh`], and its
//! instances name their materials in [`crate::Scene::material_sets`].

use std::collections::HashMap;
use std::sync::Arc;

use crate::accessor::Buffers;
use crate::error::Error;
use crate::geometry::Geometry;
use crate::material::Materials;
use crate::mesh::{self, LoadedMesh};
use crate::types::{Material, Scene, SceneStats};
use rayon::prelude::*;

/// What a primitive's geometry is read from: its mode, indices accessor and attribute
/// accessors by name (sorted).
type PrimitiveKey = (u32, Option<usize>, Vec<(String, usize)>);

/// The meshes read, and the glTF meshes that reuse another's geometry.
pub(crate) struct ReadMeshes {
    /// By glTF mesh index: the meshes read.
    pub meshes: HashMap<usize, LoadedMesh>,
    /// By glTF mesh index: the mesh whose geometry it draws, and its per-triangle materials
    /// when they differ from that mesh's (`None`: the same materials).
    pub aliases: HashMap<usize, (usize, Option<Vec<u32>>)>,
}

/// The geometry key of `mesh`, or `None` when it may not share: morph targets or joints (they
/// deform per glTF mesh), Draco streams, or primitives that are not triangles.
fn geometry_key(mesh: &gltf::Mesh<'_>) -> Option<Vec<PrimitiveKey>> {
    mesh.primitives()
        .map(|p| {
            let not_triangles = mesh::is_not_triangles(p.mode());
            let deforms = p.morph_targets().next().is_some()
                || p.attributes()
                    .any(|(s, _)| s.to_string().starts_with("JOINTS"));
            let draco = p.extension_value("KHR_draco_mesh_compression").is_some();
            if not_triangles || deforms || draco {
                return None;
            }
            let mut attributes: Vec<(String, usize)> = p
                .attributes()
                .map(|(s, a)| (s.to_string(), a.index()))
                .collect();
            attributes.sort();
            Some((
                p.mode().as_gl_enum(),
                p.indices().map(|a| a.index()),
                attributes,
            ))
        })
        .collect()
}

/// How meshes are read: the `KHR_materials_variants` variant chosen, and by glTF mesh index
/// the geometry given in place of a mesh's accessors ([`crate::Edit::MeshGeometry`]).
pub(crate) struct Reading {
    variant: Option<usize>,
    given: HashMap<usize, Arc<[Geometry]>>,
}

impl Reading {
    /// The variant, and the geometry the last [`crate::Edit::MeshGeometry`] of each mesh in
    /// `edits` gives it.
    pub fn new(variant: Option<usize>, edits: &[crate::edit::Edit]) -> Self {
        let given = crate::edit::given_geometry(edits);
        Self { variant, given }
    }

    fn given(&self, mesh: usize) -> Option<&[Geometry]> {
        self.given.get(&mesh).map(|g| &**g)
    }
}

/// [`read_meshes`] for the nodes of `order` that may be shown (`hidden`: hidden at every time,
/// stored hidden and not keyed visible, `KHR_node_visibility`; their meshes are not even read),
/// with tangents generated where normal maps need them.
pub(crate) fn read_shown(
    doc: &gltf::Document,
    order: &[usize],
    hidden: &[bool],
    buffers: &Buffers,
    stats: &mut SceneStats,
    reading: Reading,
    materials: &mut Materials,
) -> Result<ReadMeshes, Error> {
    if let Some(&m) = reading.given.keys().find(|&&m| m >= doc.meshes().len()) {
        return Err(Error::Invalid {
            at: format!("meshes[{m}]"),
            reason: format!(
                "geometry given for a mesh the file lacks (it has {})",
                doc.meshes().len()
            ),
        });
    }
    let shown: Vec<usize> = order.iter().copied().filter(|&i| !hidden[i]).collect();
    let mut read = read_meshes(doc, &shown, buffers, stats, &reading, materials)?;
    generate_tangents(&mut read.meshes, &materials.materials);
    Ok(read)
}

/// A mesh [`read_meshes`] decodes: its glTF index, and our material of each of its triangle
/// primitives, in order (resolved before decoding, in the order a one-by-one read asks).
struct ToRead<'d> {
    mesh: gltf::Mesh<'d>,
    materials: Vec<u32>,
}

/// Every mesh the nodes in `order` use, read once each (by glTF mesh index), its materials
/// gathered into `materials`; a mesh with the geometry key of one read before is an alias of
/// it (when its materials need the same tangents). The meshes are decoded in parallel (issue
/// 59); materials are numbered, and errors and warnings reported, as a read in `order` does.
fn read_meshes(
    doc: &gltf::Document,
    order: &[usize],
    buffers: &Buffers,
    stats: &mut SceneStats,
    reading: &Reading,
    materials: &mut Materials,
) -> Result<ReadMeshes, Error> {
    let variant = reading.variant;
    let mut out = ReadMeshes {
        meshes: HashMap::new(),
        aliases: HashMap::new(),
    };
    // Which meshes to decode, and which may alias one of them (with their own materials).
    let mut by_key: HashMap<Vec<PrimitiveKey>, usize> = HashMap::new();
    let mut seen = std::collections::HashSet::new();
    let mut to_read: Vec<ToRead<'_>> = Vec::new();
    let mut alias_candidates: Vec<(gltf::Mesh<'_>, usize, Vec<u32>)> = Vec::new();
    for &ni in order {
        let Some(m) = doc.nodes().nth(ni).and_then(|n| n.mesh()) else {
            continue;
        };
        if !seen.insert(m.index()) {
            continue;
        }
        // Given geometry is the mesh's own: it shares with nothing.
        let key = geometry_key(&m).filter(|_| reading.given(m.index()).is_none());
        if let Some(&canon) = key.as_ref().and_then(|k| by_key.get(k)) {
            let own = primitive_materials(doc, &m, variant, materials);
            alias_candidates.push((m, canon, own));
            continue;
        }
        if let Some(k) = key {
            by_key.insert(k, m.index());
        }
        let own = m
            .primitives()
            .filter(|p| !mesh::is_not_triangles(p.mode()))
            .map(|p| primitive_material(doc, &p, variant, materials))
            .collect();
        to_read.push(ToRead {
            mesh: m,
            materials: own,
        });
    }
    let read: Vec<(Result<LoadedMesh, Error>, SceneStats)> = to_read
        .par_iter()
        .map(|r| read_one(doc, r, buffers, reading))
        .collect();
    for (r, (loaded, local)) in to_read.iter().zip(read) {
        stats.primitives += local.primitives;
        stats.skipped_primitives += local.skipped_primitives;
        stats.warnings.extend(local.warnings);
        out.meshes.insert(r.mesh.index(), loaded?);
    }
    for (m, canon, own) in alias_candidates {
        if let Some(set) = alias_materials(&out.meshes[&canon], &own, materials) {
            stats.primitives += own.len();
            out.aliases.insert(m.index(), (canon, set));
            continue;
        }
        let of = &mut |i| materials.get(doc, i);
        let loaded = mesh::load_mesh(doc, &m, buffers, stats, variant, of, None)?;
        out.meshes.insert(m.index(), loaded);
    }
    Ok(out)
}

/// One mesh of [`read_meshes`], its warnings and counts in stats of its own.
fn read_one(
    doc: &gltf::Document,
    r: &ToRead<'_>,
    buffers: &Buffers,
    reading: &Reading,
) -> (Result<LoadedMesh, Error>, SceneStats) {
    let mut local = SceneStats::default();
    let mut next = r.materials.iter().copied();
    let of = &mut |_: Option<usize>| next.next().unwrap_or(0);
    let given = reading.given(r.mesh.index());
    let loaded = mesh::load_mesh(
        doc,
        &r.mesh,
        buffers,
        &mut local,
        reading.variant,
        of,
        given,
    );
    (loaded, local)
}

/// Our material of `prim` (its variant's, else its own), numbered on first use.
fn primitive_material(
    doc: &gltf::Document,
    prim: &gltf::Primitive<'_>,
    variant: Option<usize>,
    materials: &mut Materials,
) -> u32 {
    let index = variant
        .and_then(|v| mesh::variant_material(prim, v))
        .or(prim.material().index());
    materials.get(doc, index)
}

/// Our material of each primitive of `mesh` ([`primitive_material`]).
fn primitive_materials(
    doc: &gltf::Document,
    mesh: &gltf::Mesh<'_>,
    variant: Option<usize>,
    materials: &mut Materials,
) -> Vec<u32> {
    mesh.primitives()
        .map(|p| primitive_material(doc, &p, variant, materials))
        .collect()
}

/// The per-triangle materials of a mesh drawing `canon`'s geometry with primitive materials
/// `own`: `Some(None)` when they are `canon`'s, `Some(Some(list))` otherwise, `None` when the
/// two need tangents differently (generated for `canon`'s materials only).
fn alias_materials(
    canon: &LoadedMesh,
    own: &[u32],
    materials: &Materials,
) -> Option<Option<Vec<u32>>> {
    if own.len() != canon.part_materials.len() {
        return None;
    }
    let uv_set = |id: u32| {
        materials
            .materials
            .get(id as usize)
            .and_then(crate::tangents::tangent_uv_set)
    };
    let pairs = canon.part_materials.iter().zip(own);
    if pairs.clone().any(|(&(c, _), &o)| uv_set(c) != uv_set(o)) {
        return None;
    }
    if pairs.clone().all(|(&(c, _), &o)| c == o) {
        return Some(None);
    }
    let list = pairs
        .flat_map(|(&(_, n), &o)| std::iter::repeat_n(o, n))
        .collect();
    Some(Some(list))
}

/// MikkTSpace tangents for normal-mapped meshes, on the rest shape (deformed with it).
fn generate_tangents(meshes: &mut HashMap<usize, LoadedMesh>, materials: &[Material]) {
    let mut keys: Vec<usize> = meshes.keys().copied().collect();
    keys.sort_unstable();
    let mut tmp = Scene {
        meshes: keys
            .iter()
            .filter_map(|k| {
                meshes
                    .get_mut(k)
                    .map(|m| Arc::new(std::mem::take(&mut m.mesh)))
            })
            .collect(),
        materials: materials.to_vec(),
        ..Scene::default()
    };
    crate::tangents::generate_missing_tangents(&mut tmp);
    for (k, m) in keys.iter().zip(tmp.meshes) {
        if let Some(l) = meshes.get_mut(k) {
            l.mesh = Arc::unwrap_or_clone(m);
        }
    }
}
