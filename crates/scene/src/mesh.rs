//! glTF meshes to [`Mesh`]: every triangle primitive read, triangulated and merged into one mesh.

use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};

use crate::accessor::{read_f32, read_indices, read_vec, Buffers};
use crate::draco::Decoded;
use crate::morph::MorphTarget;
use crate::skin::{self, Influences};
use crate::{Error, Mesh, SceneStats};

/// One `JOINTS_n`/`WEIGHTS_n` pair: 4 joints and 4 weights per vertex.
type SkinSet = (Vec<f32>, Vec<f32>);

/// One primitive's triangles and attributes before merging.
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// True when the primitive had no `NORMAL` (flat normals, recomputed after deformation).
    flat: bool,
    tangents: Option<Vec<Vec4>>,
    uv0: Option<Vec<Vec2>>,
    uv1: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec4>>,
    triangles: Vec<[u32; 3]>,
    material: u32,
    targets: Vec<MorphTarget>,
    /// `JOINTS_n`/`WEIGHTS_n` sets, 4 values per vertex each.
    skin_sets: Vec<SkinSet>,
}

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
}

/// Where a primitive's data comes from: its accessors, or a Draco stream for the attributes it
/// compresses.
struct Source<'a, 'b> {
    prim: &'a gltf::Primitive<'b>,
    buffers: &'a Buffers,
    draco: Option<Decoded>,
}

impl Source<'_, '_> {
    /// An attribute's values, flat, with its component count; checked to have `vertices` elements.
    fn flat(
        &self,
        semantic: &Semantic,
        vertices: usize,
        at: &str,
    ) -> Result<Option<(Vec<f32>, usize)>, Error> {
        let name = semantic.to_string();
        if let Some((v, dims)) = self.draco.as_ref().and_then(|d| d.attributes.get(&name)) {
            return Ok(Some((v.clone(), *dims)));
        }
        let Some(acc) = self.prim.get(semantic) else {
            return Ok(None);
        };
        let at = format!("{at}.attributes.{name}");
        if acc.count() != vertices {
            return Err(Error::BadAccessor {
                at,
                reason: format!(
                    "accessors[{}] has {} elements, POSITION has {vertices}",
                    acc.index(),
                    acc.count()
                ),
            });
        }
        read_f32(&acc, self.buffers, &at).map(Some)
    }

    /// An attribute as `N`-component vectors.
    fn attribute<const N: usize>(
        &self,
        semantic: Semantic,
        vertices: usize,
        at: &str,
    ) -> Result<Option<Vec<[f32; N]>>, Error> {
        let Some((flat, dims)) = self.flat(&semantic, vertices, at)? else {
            return Ok(None);
        };
        if dims != N {
            return Err(Error::BadAccessor {
                at: format!("{at}.attributes.{}", semantic.to_string()),
                reason: format!("{dims} components per element, {N} expected"),
            });
        }
        Ok(Some(
            flat.chunks_exact(N)
                .map(|c| std::array::from_fn(|k| c[k]))
                .collect(),
        ))
    }
}

/// Triangles from a list of vertex indices in the primitive's mode (glTF 2.0 §3.7.2.1).
fn triangulate(mode: Mode, idx: &[u32], at: &str) -> Result<Vec<[u32; 3]>, Error> {
    Ok(match mode {
        Mode::Triangles => {
            if !idx.len().is_multiple_of(3) {
                return Err(Error::IndexCount {
                    at: at.into(),
                    count: idx.len(),
                });
            }
            idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
        }
        // Every other triangle of a strip is flipped so all face the same way.
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..idx.len().saturating_sub(1))
            .map(|i| [idx[i], idx[i + 1], idx[0]])
            .collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => Vec::new(),
    })
}

fn gather<T: Copy>(v: &[T], remap: &Option<Vec<u32>>) -> Vec<T> {
    match remap {
        Some(r) => r.iter().map(|&i| v[i as usize]).collect(),
        None => v.to_vec(),
    }
}

/// The vertex indices of a primitive (its own, or 0..n when it has none).
fn read_vertex_indices(
    src: &Source<'_, '_>,
    n: usize,
    at: &str,
    pat: &str,
) -> Result<Vec<u32>, Error> {
    let idx = match (&src.draco, src.prim.indices()) {
        (Some(d), _) => d.indices.clone(),
        (None, Some(acc)) => read_indices(&acc, src.buffers, &format!("{at}.indices"))?,
        (None, None) => {
            let n32 = u32::try_from(n).map_err(|_| Error::BadAccessor {
                at: pat.into(),
                reason: format!("{n} vertices exceed the u32 index range"),
            })?;
            return Ok((0..n32).collect());
        }
    };
    if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
        return Err(Error::IndexOutOfRange {
            at: format!("{at}.indices"),
            index: bad as u64,
            vertices: n,
        });
    }
    Ok(idx)
}

/// Morph targets of a primitive (never Draco-compressed), each attribute checked per vertex.
fn read_targets(src: &Source<'_, '_>, n: usize, at: &str) -> Result<Vec<MorphTarget>, Error> {
    let mut out = Vec::new();
    for (k, target) in src.prim.morph_targets().enumerate() {
        let tat = format!("{at}.targets[{k}]");
        let read = |acc: Option<gltf::Accessor<'_>>, name: &str| -> Result<Vec<Vec3>, Error> {
            let Some(acc) = acc else {
                return Ok(Vec::new());
            };
            let aat = format!("{tat}.{name}");
            if acc.count() != n {
                return Err(Error::BadAccessor {
                    at: aat,
                    reason: format!(
                        "accessors[{}] has {} elements, POSITION has {n}",
                        acc.index(),
                        acc.count()
                    ),
                });
            }
            let v = read_vec::<3>(&acc, src.buffers, &aat)?;
            if let Some(x) = v.iter().flatten().find(|x| !x.is_finite()) {
                return Err(Error::NonFinite {
                    at: aat,
                    value: x.to_string(),
                });
            }
            Ok(v.into_iter().map(Vec3::from).collect())
        };
        out.push(MorphTarget {
            positions: read(target.positions(), "POSITION")?,
            normals: read(target.normals(), "NORMAL")?,
            tangents: read(target.tangents(), "TANGENT")?,
        });
    }
    Ok(out)
}

/// Every `JOINTS_n`/`WEIGHTS_n` pair of a primitive.
fn read_skin_sets(src: &Source<'_, '_>, n: usize, at: &str) -> Result<Vec<SkinSet>, Error> {
    let mut sets = Vec::new();
    for set in 0u32.. {
        let joints = src.flat(&Semantic::Joints(set), n, at)?;
        let weights = src.flat(&Semantic::Weights(set), n, at)?;
        match (joints, weights) {
            (Some((j, 4)), Some((w, 4))) => sets.push((j, w)),
            (None, None) => break,
            (j, w) => {
                return Err(Error::BadAccessor {
                    at: format!("{at}.attributes.JOINTS_{set}"),
                    reason: format!(
                        "JOINTS_{set} and WEIGHTS_{set} must both be VEC4 (found {:?} and {:?} components)",
                        j.map(|j| j.1),
                        w.map(|w| w.1)
                    ),
                })
            }
        }
    }
    Ok(sets)
}

fn read_part(
    doc: &gltf::Document,
    prim: &gltf::Primitive<'_>,
    buffers: &Buffers,
    at: &str,
    material: u32,
) -> Result<Part, Error> {
    let draco = match prim.extension_value("KHR_draco_mesh_compression") {
        Some(ext) => Some(crate::draco::decode(doc, prim, ext, buffers, at)?),
        None => None,
    };
    let src = Source {
        prim,
        buffers,
        draco,
    };
    let pos_acc = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| Error::Invalid {
            at: format!("{at}.attributes.POSITION"),
            reason: "missing".into(),
        })?;
    let pat = format!("{at}.attributes.POSITION");
    let positions: Vec<Vec3> = src
        .attribute::<3>(Semantic::Positions, pos_acc.count(), at)?
        .unwrap_or_default()
        .into_iter()
        .map(Vec3::from)
        .collect();
    if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(Error::NonFinite {
            at: format!("{pat}[{i}] (accessors[{}])", pos_acc.index()),
            value: format!("{p:?}"),
        });
    }
    let n = positions.len();
    let indices = read_vertex_indices(&src, n, at, &pat)?;
    let tat = if prim.indices().is_some() {
        format!("{at}.indices")
    } else {
        format!("{at} (non-indexed, {n} vertices)")
    };
    let mut triangles = triangulate(prim.mode(), &indices, &tat)?;
    drop(indices);

    let normals = src.attribute::<3>(Semantic::Normals, n, at)?;
    let tangents = src.attribute::<4>(Semantic::Tangents, n, at)?;
    let uv0 = src.attribute::<2>(Semantic::TexCoords(0), n, at)?;
    let uv1 = src.attribute::<2>(Semantic::TexCoords(1), n, at)?;
    let colors: Option<Vec<Vec4>> = match src.flat(&Semantic::Colors(0), n, at)? {
        Some((flat, dims)) => Some(match dims {
            3 => flat
                .chunks_exact(3)
                .map(|c| Vec4::new(c[0], c[1], c[2], 1.0))
                .collect(),
            4 => flat.chunks_exact(4).map(Vec4::from_slice).collect(),
            _ => {
                return Err(Error::BadAccessor {
                    at: format!("{at}.attributes.COLOR_0"),
                    reason: format!("COLOR_0 must be VEC3 or VEC4, has {dims} components"),
                })
            }
        }),
        None => None,
    };
    let targets = read_targets(&src, n, at)?;
    let skin_sets = read_skin_sets(&src, n, at)?;

    // Without NORMAL, glTF asks for flat normals: each triangle gets its own three vertices.
    let flat = normals.is_none();
    let (remap, normals) = match normals {
        Some(ns) => (
            None,
            ns.into_iter()
                .map(|v| Vec3::from(v).try_normalize().unwrap_or(Vec3::Z))
                .collect::<Vec<_>>(),
        ),
        None => {
            let remap: Vec<u32> = triangles.iter().flatten().copied().collect();
            let mut ns = Vec::with_capacity(remap.len());
            for t in &triangles {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let nrm = (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z);
                ns.extend([nrm; 3]);
            }
            for (k, t) in triangles.iter_mut().enumerate() {
                let k = k as u32 * 3;
                *t = [k, k + 1, k + 2];
            }
            (Some(remap), ns)
        }
    };
    let v2 = |v: Vec<[f32; 2]>| gather(&v, &remap).into_iter().map(Vec2::from).collect();
    let per_vertex = |v: Vec<f32>| -> Vec<f32> {
        match &remap {
            Some(r) => r
                .iter()
                .flat_map(|&i| v[4 * i as usize..][..4].to_vec())
                .collect(),
            None => v,
        }
    };
    Ok(Part {
        positions: gather(&positions, &remap),
        normals,
        flat,
        tangents: tangents.map(|t| gather(&t, &remap).into_iter().map(Vec4::from).collect()),
        uv0: uv0.map(v2),
        uv1: uv1.map(v2),
        colors: colors.map(|c| gather(&c, &remap)),
        triangles,
        material,
        targets: targets
            .into_iter()
            .map(|t| MorphTarget {
                positions: if t.positions.is_empty() {
                    t.positions
                } else {
                    gather(&t.positions, &remap)
                },
                // Flat normals are recomputed from the morphed positions instead.
                normals: if flat || t.normals.is_empty() {
                    Vec::new()
                } else {
                    gather(&t.normals, &remap)
                },
                tangents: if t.tangents.is_empty() {
                    t.tangents
                } else {
                    gather(&t.tangents, &remap)
                },
            })
            .collect(),
        skin_sets: skin_sets
            .into_iter()
            .map(|(j, w)| (per_vertex(j), per_vertex(w)))
            .collect(),
    })
}

/// Appends `src` (or `n` copies of `zero` when absent) to `dst` when the merged mesh has the
/// attribute at all.
fn fill<T: Clone>(dst: &mut Vec<T>, wanted: bool, src: Option<Vec<T>>, n: usize, zero: T) {
    if wanted {
        match src {
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

/// Reads a glTF mesh: triangle primitives merged, points and lines skipped with a warning.
/// `material_of` maps a primitive's material index (None = the default material) to ours.
pub(crate) fn load_mesh(
    doc: &gltf::Document,
    mesh: &gltf::Mesh<'_>,
    buffers: &Buffers,
    stats: &mut SceneStats,
    material_of: &mut dyn FnMut(Option<usize>) -> u32,
) -> Result<LoadedMesh, Error> {
    let mut parts = Vec::new();
    for prim in mesh.primitives() {
        let at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        if matches!(
            prim.mode(),
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            stats.skipped_primitives += 1;
            stats.warnings.push(format!(
                "{at}: {:?} primitive skipped (not triangles)",
                prim.mode()
            ));
            continue;
        }
        let material = material_of(prim.material().index());
        parts.push(read_part(doc, &prim, buffers, &at, material)?);
        stats.primitives += 1;
    }
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
    let targets = merge_targets(&parts);
    let influences = merge_influences(&parts);
    let mut m = Mesh {
        name: mesh.name().map(str::to_owned),
        positions: Vec::with_capacity(vertices),
        normals: Vec::with_capacity(vertices),
        indices: Vec::with_capacity(triangles),
        material_ids: Vec::with_capacity(triangles),
        ..Mesh::default()
    };
    let mut flat = Vec::new();
    for p in parts {
        let base = m.positions.len() as u32;
        let count = p.positions.len();
        if p.flat {
            flat.push(base..base + count as u32);
        }
        m.positions.extend(p.positions);
        m.normals.extend(p.normals);
        fill(&mut m.tangents, has_t, p.tangents, count, Vec4::ZERO);
        fill(&mut m.uv0, has_uv0, p.uv0, count, Vec2::ZERO);
        fill(&mut m.uv1, has_uv1, p.uv1, count, Vec2::ZERO);
        fill(&mut m.colors, has_c, p.colors, count, Vec4::ONE);
        m.indices
            .extend(p.triangles.iter().map(|t| t.map(|i| i + base)));
        m.material_ids
            .extend(std::iter::repeat_n(p.material, p.triangles.len()));
    }
    Ok(LoadedMesh {
        mesh: m,
        targets,
        influences,
        flat,
        weights: mesh.weights().map(<[f32]>::to_vec).unwrap_or_default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_one_winding() {
        let strip = triangulate(Mode::TriangleStrip, &[0, 1, 2, 3, 4], "x").unwrap();
        assert_eq!(strip, vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]]);
        let fan = triangulate(Mode::TriangleFan, &[0, 1, 2, 3], "x").unwrap();
        assert_eq!(fan, vec![[1, 2, 0], [2, 3, 0]]);
        assert!(triangulate(Mode::TriangleStrip, &[0, 1], "x")
            .unwrap()
            .is_empty());
    }

    #[test]
    fn triangle_list_needs_a_multiple_of_three() {
        let e = triangulate(
            Mode::Triangles,
            &[0, 1, 2, 3],
            "meshes[0].primitives[0].indices",
        );
        assert!(matches!(e, Err(Error::IndexCount { count: 4, .. })));
    }
}
