//! glTF meshes to [`Mesh`]: every triangle primitive read, triangulated and merged into one mesh.

mod part;

use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::Mode;

use crate::accessor::Buffers;
use crate::error::Error;
use crate::geometry::Geometry;
use crate::morph::MorphTarget;
use crate::skin::{self, Influences};
use crate::types::{Mesh, SceneStats};
use part::{given_part, read_part, Part, SkinSet};

/// A merged glTF mesh with what deforms it: morph targets and joint influences, aligned with
/// `mesh`'s vertices.
#[derive(Debug, Clone)]
pub(crate) struct LoadedMesh {
    pub mesh: Mesh,
    pub targets: Vec<MorphTarget>,
    pub influences: Option<Influences>,
    /// Vertex ranges whose normals are flat (primitives without `NORMAL`).
    pub flat: Vec<std::ops::Range<u32>>,
    /// `mesh.weights`, the default morph weights.
    pub weights: Vec<f32>,
    /// Each triangle primitive's material and triangle count, in the order merged.
    pub part_materials: Vec<(u32, usize)>,
}

/// Appends `src` (or `n` copies of `zero` when absent) to `dst` when the merged mesh has the
/// attribute at all.
fn fill<T: Clone>(dst: &mut Vec<T>, wanted: bool, src: Option<Vec<T>>, n: usize, zero: T) {
    if wanted {
        match src {
            // The first primitive's own vector, not a copy of it (a mesh of one primitive).
            Some(v) if dst.is_empty() => *dst = v,
            Some(v) => dst.extend(v),
            None => dst.extend(std::iter::repeat_n(zero, n)),
        }
    }
}

/// Morph targets merged across primitives (a primitive without target `k`, or without one of
/// its attributes, contributes zeros).
fn merge_targets(parts: &[Part]) -> Vec<MorphTarget> {
    let count = parts.iter().map(|p| p.targets.len()).max().unwrap_or(0);
    (0..count)
        .map(|k| {
            let any =
                |f: fn(&MorphTarget) -> bool| parts.iter().any(|p| p.targets.get(k).is_some_and(f));
            let (has_p, has_n, has_t) = (
                any(|t| !t.positions.is_empty()),
                any(|t| !t.normals.is_empty()),
                any(|t| !t.tangents.is_empty()),
            );
            let mut out = MorphTarget::default();
            for p in parts {
                let n = p.positions.len();
                let t = p.targets.get(k);
                let take = |v: Option<&Vec<Vec3>>| v.filter(|v| !v.is_empty()).cloned();
                fill(
                    &mut out.positions,
                    has_p,
                    take(t.map(|t| &t.positions)),
                    n,
                    Vec3::ZERO,
                );
                fill(
                    &mut out.normals,
                    has_n,
                    take(t.map(|t| &t.normals)),
                    n,
                    Vec3::ZERO,
                );
                fill(
                    &mut out.tangents,
                    has_t,
                    take(t.map(|t| &t.tangents)),
                    n,
                    Vec3::ZERO,
                );
            }
            out
        })
        .collect()
}

/// Joint influences merged across primitives (`None` when no primitive is skinned).
fn merge_influences(parts: &[Part]) -> Option<Influences> {
    let sets = parts.iter().map(|p| p.skin_sets.len()).max().unwrap_or(0);
    if sets == 0 {
        return None;
    }
    let mut merged: Vec<SkinSet> = vec![(Vec::new(), Vec::new()); sets];
    for p in parts {
        let n = p.positions.len();
        for (s, (j, w)) in merged.iter_mut().enumerate() {
            match p.skin_sets.get(s) {
                Some((pj, pw)) => {
                    j.extend(pj);
                    w.extend(pw);
                }
                None => {
                    j.extend(std::iter::repeat_n(0.0, 4 * n));
                    w.extend(std::iter::repeat_n(0.0, 4 * n));
                }
            }
        }
    }
    let vertices = parts.iter().map(|p| p.positions.len()).sum();
    Some(skin::influences(merged, vertices))
}

/// The material `KHR_materials_variants` maps to variant `variant` on this primitive, if any.
pub(crate) fn variant_material(prim: &gltf::Primitive<'_>, variant: usize) -> Option<usize> {
    let mappings = prim
        .extension_value("KHR_materials_variants")?
        .get("mappings")?
        .as_array()?;
    mappings.iter().find_map(|m| {
        let listed = m
            .get("variants")?
            .as_array()?
            .iter()
            .any(|v| v.as_u64() == Some(variant as u64));
        let material = usize::try_from(m.get("material")?.as_u64()?).ok()?;
        listed.then_some(material)
    })
}

/// True for the primitive modes that draw no triangles (points and lines), which are skipped.
pub(crate) fn is_not_triangles(mode: Mode) -> bool {
    matches!(
        mode,
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
    )
}

/// Reads a glTF mesh: triangle primitives merged, points and lines skipped with a warning.
/// `material_of` maps a primitive's material index (None = the default material) to ours;
/// `variant` selects `KHR_materials_variants` mappings (the default material where a primitive
/// maps none for it). `given`: geometry to draw instead of the accessors, one per primitive
/// ([`crate::Edit::MeshGeometry`]).
pub(crate) fn load_mesh(
    doc: &gltf::Document,
    mesh: &gltf::Mesh<'_>,
    buffers: &Buffers,
    stats: &mut SceneStats,
    variant: Option<usize>,
    material_of: &mut dyn FnMut(Option<usize>) -> u32,
    given: Option<&[Geometry]>,
) -> Result<LoadedMesh, Error> {
    let count = mesh.primitives().len();
    if let Some(g) = given.filter(|g| g.len() != count) {
        return Err(Error::Invalid {
            at: format!("meshes[{}]", mesh.index()),
            reason: format!(
                "geometry given for {} primitives, the mesh has {count}",
                g.len()
            ),
        });
    }
    let mut parts = Vec::new();
    for prim in mesh.primitives() {
        let at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let given = given.map(|g| &g[prim.index()]);
        if given.is_some() && is_not_triangles(prim.mode()) {
            return Err(Error::Invalid {
                at,
                reason: format!(
                    "draws {:?}: its geometry is not given as triangles",
                    prim.mode()
                ),
            });
        }
        if is_not_triangles(prim.mode()) {
            stats.skipped_primitives += 1;
            stats.warnings.push(format!(
                "{at}: {:?} primitive skipped (not triangles)",
                prim.mode()
            ));
            continue;
        }
        let material = material_of(
            variant
                .and_then(|v| variant_material(&prim, v))
                .or(prim.material().index()),
        );
        parts.push(match given {
            Some(g) => given_part(g, material),
            None => read_part(doc, &prim, buffers, &at, material)?,
        });
        stats.primitives += 1;
    }
    merge_parts(mesh, parts)
}

/// `src` appended to `dst`, which ends up holding `total` values: the first part's vector is
/// taken over, not copied (a mesh of one primitive is never held twice).
fn append<T>(dst: &mut Vec<T>, src: Vec<T>, total: usize) {
    if dst.is_empty() {
        *dst = src;
        dst.reserve_exact(total.saturating_sub(dst.len()));
    } else {
        dst.extend(src);
    }
}

/// The primitives of `mesh` merged into one mesh: attributes any primitive has are filled
/// with defaults where others lack them, indices offset, morph targets and influences merged.
fn merge_parts(mesh: &gltf::Mesh<'_>, parts: Vec<Part>) -> Result<LoadedMesh, Error> {
    let vertices: usize = parts.iter().map(|p| p.positions.len()).sum();
    if u32::try_from(vertices).is_err() {
        return Err(Error::BadAccessor {
            at: format!("meshes[{}]", mesh.index()),
            reason: format!("{vertices} vertices exceed the u32 index range"),
        });
    }
    let triangles: usize = parts.iter().map(|p| p.triangles.len()).sum();
    let any = |f: fn(&Part) -> bool| parts.iter().any(f);
    let (has_t, has_uv0, has_uv1, has_c) = (
        any(|p| p.tangents.is_some()),
        any(|p| p.uv0.is_some()),
        any(|p| p.uv1.is_some()),
        any(|p| p.colors.is_some()),
    );
    let more_sets = parts.iter().map(|p| p.uv_more.len()).max().unwrap_or(0);
    let has_more: Vec<bool> = (0..more_sets)
        .map(|k| {
            parts
                .iter()
                .any(|p| p.uv_more.get(k).is_some_and(Option::is_some))
        })
        .collect();
    let targets = merge_targets(&parts);
    let influences = merge_influences(&parts);
    let mut m = Mesh {
        name: mesh.name().map(str::to_owned),
        material_ids: Vec::with_capacity(triangles),
        uv_more: vec![Vec::new(); more_sets],
        ..Mesh::default()
    };
    let mut flat = Vec::new();
    let part_materials = parts
        .iter()
        .map(|p| (p.material, p.triangles.len()))
        .collect();
    for p in parts {
        let base = m.positions.len() as u32;
        let count = p.positions.len();
        if p.flat {
            flat.push(base..base + count as u32);
        }
        append(&mut m.positions, p.positions, vertices);
        append(&mut m.normals, p.normals, vertices);
        fill(&mut m.tangents, has_t, p.tangents, count, Vec4::ZERO);
        fill(&mut m.uv0, has_uv0, p.uv0, count, Vec2::ZERO);
        fill(&mut m.uv1, has_uv1, p.uv1, count, Vec2::ZERO);
        let mut more = p.uv_more;
        more.resize(more_sets, None);
        for ((dst, has), src) in m.uv_more.iter_mut().zip(&has_more).zip(more) {
            fill(dst, *has, src, count, Vec2::ZERO);
        }
        fill(&mut m.colors, has_c, p.colors, count, Vec4::ONE);
        let n = p.triangles.len();
        if base == 0 {
            append(&mut m.indices, p.triangles, triangles);
        } else {
            m.indices
                .extend(p.triangles.iter().map(|t| t.map(|i| i + base)));
        }
        m.material_ids.extend(std::iter::repeat_n(p.material, n));
    }
    Ok(LoadedMesh {
        mesh: m,
        targets,
        influences,
        flat,
        weights: mesh.weights().map(<[f32]>::to_vec).unwrap_or_default(),
        part_materials,
    })
}
