//! One glTF primitive read: its attributes (from accessors or a Draco stream), checked against
//! its vertex count, and its indices triangulated.

use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};

use crate::accessor::{read_f32, read_indices, read_vec, Buffers};
use crate::draco::Decoded;
use crate::error::Error;
use crate::geometry::Geometry;
use crate::morph::MorphTarget;

/// One `JOINTS_n`/`WEIGHTS_n` pair: 4 joints and 4 weights per vertex.
pub(crate) type SkinSet = (Vec<f32>, Vec<f32>);

/// Texture coordinate sets read (`TEXCOORD_0` … `TEXCOORD_7`).
const MAX_UV_SETS: u32 = 8;

/// One primitive's triangles and attributes before merging.
pub(crate) struct Part {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// True when the primitive had no `NORMAL` (flat normals, recomputed after deformation).
    pub flat: bool,
    pub tangents: Option<Vec<Vec4>>,
    pub uv0: Option<Vec<Vec2>>,
    pub uv1: Option<Vec<Vec2>>,
    /// `TEXCOORD_2` … `TEXCOORD_7` (set k + 2 at k).
    pub uv_more: Vec<Option<Vec<Vec2>>>,
    pub colors: Option<Vec<Vec4>>,
    pub triangles: Vec<[u32; 3]>,
    pub material: u32,
    pub targets: Vec<MorphTarget>,
    /// `JOINTS_n`/`WEIGHTS_n` sets, 4 values per vertex each.
    pub skin_sets: Vec<SkinSet>,
}

/// Where a primitive's data comes from: its accessors, or a Draco stream for the attributes it
/// compresses.
struct Source<'a, 'b> {
    prim: &'a gltf::Primitive<'b>,
    buffers: &'a Buffers<'a>,
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
    ) -> Result<Option<Vec<[f32; N]>>, Error>
    where
        [f32; N]: bytemuck::AnyBitPattern,
    {
        let Some((flat, dims)) = self.flat(&semantic, vertices, at)? else {
            return Ok(None);
        };
        if dims != N {
            return Err(Error::BadAccessor {
                at: format!("{at}.attributes.{}", semantic.to_string()),
                reason: format!("{dims} components per element, {N} expected"),
            });
        }
        Ok(Some(vectors(flat)))
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

fn gather<T: Copy>(v: Vec<T>, remap: &Option<Vec<u32>>) -> Vec<T> {
    match remap {
        Some(r) => r.iter().map(|&i| v[i as usize]).collect(),
        None => v,
    }
}

/// `flat` read as `N`-component vectors: the same allocation where its length and capacity
/// are multiples of `N` (as a read sizes them), else a copy. A scene's attributes are most of
/// its bytes; each copy of them was a pass over fresh memory.
fn vectors<const N: usize>(flat: Vec<f32>) -> Vec<[f32; N]>
where
    [f32; N]: bytemuck::AnyBitPattern,
{
    match bytemuck::allocation::try_cast_vec::<f32, [f32; N]>(flat) {
        Ok(v) => v,
        Err((_, flat)) => flat
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|k| c[k]))
            .collect(),
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

/// One primitive read: its triangles and attributes, checked, with flat normals (one vertex per
/// corner) when it has no `NORMAL`.
pub(crate) fn read_part(
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
    let (positions, pat) = read_positions(&src, at)?;
    let n = positions.len();
    let mut triangles = read_triangles(&src, n, at, &pat)?;

    let normals = src.attribute::<3>(Semantic::Normals, n, at)?;
    let tangents = src.attribute::<4>(Semantic::Tangents, n, at)?;
    let uv0 = src.attribute::<2>(Semantic::TexCoords(0), n, at)?;
    let uv1 = src.attribute::<2>(Semantic::TexCoords(1), n, at)?;
    let uv_more = read_uv_more(&src, n, at)?;
    let colors = read_colors(&src, n, at)?;
    let targets = read_targets(&src, n, at)?;
    let skin_sets = read_skin_sets(&src, n, at)?;

    // Without NORMAL, glTF asks for flat normals: each triangle gets its own three vertices.
    let flat = normals.is_none();
    let (remap, normals) = match normals {
        Some(ns) => (None, ns.into_iter().map(unit).collect::<Vec<_>>()),
        None => {
            let (remap, ns) = flat_normals(&mut triangles, &positions);
            (Some(remap), ns)
        }
    };
    let v2 = |v: Vec<[f32; 2]>| gather(v, &remap).into_iter().map(Vec2::from).collect();
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
        positions: gather(positions, &remap),
        normals,
        flat,
        tangents: tangents.map(|t| gather(t, &remap).into_iter().map(Vec4::from).collect()),
        uv0: uv0.map(v2),
        uv1: uv1.map(v2),
        uv_more: uv_more.into_iter().map(|u| u.map(v2)).collect(),
        colors: colors.map(|c| gather(c, &remap)),
        triangles,
        material,
        targets: targets
            .into_iter()
            .map(|t| remap_target(t, &remap, flat))
            .collect(),
        skin_sets: skin_sets
            .into_iter()
            .map(|(j, w)| (per_vertex(j), per_vertex(w)))
            .collect(),
    })
}

/// A primitive drawn from `given` instead of its accessors ([`crate::Edit::MeshGeometry`]):
/// normals normalised as read ones are, flat ones made where none are given.
pub(crate) fn given_part(given: &Geometry, material: u32) -> Part {
    let positions: Vec<Vec3> = given.positions().iter().map(|&p| Vec3::from(p)).collect();
    let mut triangles = given.triangles().to_vec();
    let (remap, normals) = match given.normals() {
        Some(ns) => (None, ns.iter().map(|&v| unit(v)).collect()),
        None => {
            let (remap, ns) = flat_normals(&mut triangles, &positions);
            (Some(remap), ns)
        }
    };
    let uvs = given
        .uvs()
        .map(|u| u.iter().map(|&v| Vec2::from(v)).collect());
    Part {
        flat: remap.is_some(),
        positions: gather(positions, &remap),
        normals,
        tangents: None,
        uv0: uvs.map(|u| gather(u, &remap)),
        uv1: None,
        uv_more: Vec::new(),
        colors: None,
        triangles,
        material,
        targets: Vec::new(),
        skin_sets: Vec::new(),
    }
}

/// A read normal as shading uses it: unit length, +Z where it has none.
fn unit(v: [f32; 3]) -> Vec3 {
    Vec3::from(v).try_normalize().unwrap_or(Vec3::Z)
}

/// `POSITION`, checked present and finite, with the path naming it.
fn read_positions(src: &Source<'_, '_>, at: &str) -> Result<(Vec<Vec3>, String), Error> {
    let pos_acc = src
        .prim
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
    Ok((positions, pat))
}

/// The primitive's triangles, its indices (or 0..n) triangulated in its mode.
fn read_triangles(
    src: &Source<'_, '_>,
    n: usize,
    at: &str,
    pat: &str,
) -> Result<Vec<[u32; 3]>, Error> {
    let indices = read_vertex_indices(src, n, at, pat)?;
    let tat = if src.prim.indices().is_some() {
        format!("{at}.indices")
    } else {
        format!("{at} (non-indexed, {n} vertices)")
    };
    triangulate(src.prim.mode(), &indices, &tat)
}

/// `TEXCOORD_2` … `TEXCOORD_7`, without the absent sets at the end.
fn read_uv_more(
    src: &Source<'_, '_>,
    n: usize,
    at: &str,
) -> Result<Vec<Option<Vec<[f32; 2]>>>, Error> {
    let mut uv_more = Vec::new();
    for set in 2..MAX_UV_SETS {
        uv_more.push(src.attribute::<2>(Semantic::TexCoords(set), n, at)?);
    }
    while uv_more.last().is_some_and(Option::is_none) {
        uv_more.pop();
    }
    Ok(uv_more)
}

/// `COLOR_0` as RGBA (alpha 1 for a VEC3 colour).
fn read_colors(src: &Source<'_, '_>, n: usize, at: &str) -> Result<Option<Vec<Vec4>>, Error> {
    Ok(match src.flat(&Semantic::Colors(0), n, at)? {
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
    })
}

/// Flat normals: every triangle gets three vertices of its own (`triangles` renumbered), the
/// returned remap naming the original vertex of each, and the face normal at each.
fn flat_normals(triangles: &mut [[u32; 3]], positions: &[Vec3]) -> (Vec<u32>, Vec<Vec3>) {
    let remap: Vec<u32> = triangles.iter().flatten().copied().collect();
    let mut ns = Vec::with_capacity(remap.len());
    for t in triangles.iter() {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let nrm = (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z);
        ns.extend([nrm; 3]);
    }
    for (k, t) in triangles.iter_mut().enumerate() {
        let k = k as u32 * 3;
        *t = [k, k + 1, k + 2];
    }
    (remap, ns)
}

/// A morph target following the primitive's vertices through `remap`.
fn remap_target(t: MorphTarget, remap: &Option<Vec<u32>>, flat: bool) -> MorphTarget {
    MorphTarget {
        positions: if t.positions.is_empty() {
            t.positions
        } else {
            gather(t.positions, remap)
        },
        // Flat normals are recomputed from the morphed positions instead.
        normals: if flat || t.normals.is_empty() {
            Vec::new()
        } else {
            gather(t.normals, remap)
        },
        tangents: if t.tangents.is_empty() {
            t.tangents
        } else {
            gather(t.tangents, remap)
        },
    }
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
