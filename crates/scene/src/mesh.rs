//! glTF meshes to [`Mesh`]: every triangle primitive read, triangulated and merged into one mesh.

use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};

use crate::accessor::{read_f32, read_indices, read_vec, Buffers};
use crate::{Error, Mesh, SceneStats};

/// One primitive's triangles and attributes before merging.
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    tangents: Option<Vec<Vec4>>,
    uv0: Option<Vec<Vec2>>,
    uv1: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec4>>,
    triangles: Vec<[u32; 3]>,
    material: u32,
}

/// Reads one attribute, checking that it has one element per vertex.
fn attribute<const N: usize>(
    prim: &gltf::Primitive<'_>,
    semantic: Semantic,
    vertices: usize,
    buffers: &Buffers,
    at: &str,
) -> Result<Option<Vec<[f32; N]>>, Error> {
    let Some(acc) = prim.get(&semantic) else {
        return Ok(None);
    };
    let at = format!("{at}.attributes.{}", semantic.to_string());
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
    read_vec::<N>(&acc, buffers, &at).map(Some)
}

/// Triangles from a list of vertex indices in the primitive's mode (glTF 2.0 §3.7.2.1).
fn triangulate(mode: Mode, idx: &[u32], at: &str) -> Result<Vec<[u32; 3]>, Error> {
    Ok(match mode {
        Mode::Triangles => {
            if idx.len() % 3 != 0 {
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

fn read_part(
    prim: &gltf::Primitive<'_>,
    buffers: &Buffers,
    at: &str,
    material: u32,
) -> Result<Part, Error> {
    let pos_acc = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| Error::Invalid {
            at: format!("{at}.attributes.POSITION"),
            reason: "missing".into(),
        })?;
    let pat = format!("{at}.attributes.POSITION");
    let positions: Vec<Vec3> = read_vec::<3>(&pos_acc, buffers, &pat)?
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
    let indices = match prim.indices() {
        Some(acc) => {
            let iat = format!("{at}.indices");
            let idx = read_indices(&acc, buffers, &iat)?;
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
                return Err(Error::IndexOutOfRange {
                    at: iat,
                    index: bad as u64,
                    vertices: n,
                });
            }
            idx
        }
        None => {
            let n32 = u32::try_from(n).map_err(|_| Error::BadAccessor {
                at: pat.clone(),
                reason: format!("{n} vertices exceed the u32 index range"),
            })?;
            (0..n32).collect()
        }
    };
    let tat = if prim.indices().is_some() {
        format!("{at}.indices")
    } else {
        format!("{at} (non-indexed, {n} vertices)")
    };
    let mut triangles = triangulate(prim.mode(), &indices, &tat)?;
    drop(indices);

    let normals = attribute::<3>(prim, Semantic::Normals, n, buffers, at)?;
    let tangents = attribute::<4>(prim, Semantic::Tangents, n, buffers, at)?;
    let uv0 = attribute::<2>(prim, Semantic::TexCoords(0), n, buffers, at)?;
    let uv1 = attribute::<2>(prim, Semantic::TexCoords(1), n, buffers, at)?;
    let colors: Option<Vec<Vec4>> = match prim.get(&Semantic::Colors(0)) {
        Some(acc) => {
            let cat = format!("{at}.attributes.COLOR_0");
            if acc.count() != n {
                return Err(Error::BadAccessor {
                    at: cat,
                    reason: format!("{} colours for {n} vertices", acc.count()),
                });
            }
            let (flat, dims) = read_f32(&acc, buffers, &cat)?;
            Some(match dims {
                3 => flat
                    .chunks_exact(3)
                    .map(|c| Vec4::new(c[0], c[1], c[2], 1.0))
                    .collect(),
                4 => flat.chunks_exact(4).map(Vec4::from_slice).collect(),
                _ => {
                    return Err(Error::BadAccessor {
                        at: cat,
                        reason: format!("COLOR_0 must be VEC3 or VEC4, has {dims} components"),
                    })
                }
            })
        }
        None => None,
    };

    // Without NORMAL, glTF asks for flat normals: each triangle gets its own three vertices.
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
    Ok(Part {
        positions: gather(&positions, &remap),
        normals,
        tangents: tangents.map(|t| gather(&t, &remap).into_iter().map(Vec4::from).collect()),
        uv0: uv0.map(v2),
        uv1: uv1.map(v2),
        colors: colors.map(|c| gather(&c, &remap)),
        triangles,
        material,
    })
}

/// Reads a glTF mesh: triangle primitives merged, points and lines skipped with a warning.
/// `material_of` maps a primitive's material index (None = the default material) to ours.
pub(crate) fn load_mesh(
    mesh: &gltf::Mesh<'_>,
    buffers: &Buffers,
    stats: &mut SceneStats,
    material_of: &mut dyn FnMut(Option<usize>) -> u32,
) -> Result<Mesh, Error> {
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
        parts.push(read_part(&prim, buffers, &at, material)?);
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
    let mut m = Mesh {
        name: mesh.name().map(str::to_owned),
        positions: Vec::with_capacity(vertices),
        normals: Vec::with_capacity(vertices),
        indices: Vec::with_capacity(triangles),
        material_ids: Vec::with_capacity(triangles),
        ..Mesh::default()
    };
    for p in parts {
        let base = m.positions.len() as u32;
        let count = p.positions.len();
        m.positions.extend(p.positions);
        m.normals.extend(p.normals);
        fn fill<T: Clone>(dst: &mut Vec<T>, wanted: bool, src: Option<Vec<T>>, n: usize, zero: T) {
            if wanted {
                match src {
                    Some(v) => dst.extend(v),
                    None => dst.extend(std::iter::repeat_n(zero, n)),
                }
            }
        }
        fill(&mut m.tangents, has_t, p.tangents, count, Vec4::ZERO);
        fill(&mut m.uv0, has_uv0, p.uv0, count, Vec2::ZERO);
        fill(&mut m.uv1, has_uv1, p.uv1, count, Vec2::ZERO);
        fill(&mut m.colors, has_c, p.colors, count, Vec4::ONE);
        m.indices
            .extend(p.triangles.iter().map(|t| t.map(|i| i + base)));
        m.material_ids
            .extend(std::iter::repeat_n(p.material, p.triangles.len()));
    }
    Ok(m)
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
