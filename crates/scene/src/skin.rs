//! Skins (glTF 2.0 §3.7.3): linear blend skinning of a mesh by its joints' world transforms.
//!
//! A skinned vertex is `Σ wᵢ · world(jointᵢ) · inverseBind(jointᵢ) · v`, with every `JOINTS_n` /
//! `WEIGHTS_n` set used and the weights renormalised to sum to one. The result is in world space:
//! the skinned node's own transform is ignored, as glTF says. Positions are blended in f64 and
//! returned relative to their centre, so a character far from the origin keeps its precision.

use glam::{DAffine3, DMat3, DVec3, Vec3, Vec4};

use crate::accessor::Buffers;
use crate::error::Error;
use crate::types::Mesh;

/// Joint influences of a merged mesh's vertices: `per_vertex` (joint, weight) pairs each,
/// weights renormalised (all zero for a vertex no joint moves).
#[derive(Debug, Clone, Default)]
pub(crate) struct Influences {
    pub per_vertex: usize,
    pub joints: Vec<u32>,
    pub weights: Vec<f32>,
}

/// A skin: its joints (node indices) and their inverse bind matrices.
#[derive(Debug, Clone)]
pub(crate) struct Skin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<DAffine3>,
}

/// Reads every skin of the document.
pub(crate) fn read_skins(doc: &gltf::Document, buffers: &Buffers) -> Result<Vec<Skin>, Error> {
    doc.skins()
        .map(|skin| {
            let at = format!("skins[{}]", skin.index());
            let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
            let inverse_bind = match skin.inverse_bind_matrices() {
                None => vec![DAffine3::IDENTITY; joints.len()],
                Some(acc) => {
                    let iat = format!("{at}.inverseBindMatrices");
                    if acc.dimensions() != gltf::accessor::Dimensions::Mat4 {
                        return Err(Error::BadAccessor {
                            at: iat,
                            reason: format!("accessors[{}] is not MAT4", acc.index()),
                        });
                    }
                    if acc.count() < joints.len() {
                        return Err(Error::BadAccessor {
                            at: iat,
                            reason: format!("{} matrices for {} joints", acc.count(), joints.len()),
                        });
                    }
                    let flat = read_matrices(&acc, buffers, &iat)?;
                    flat.chunks_exact(16)
                        .map(|m| {
                            if let Some(v) = m.iter().find(|v| !v.is_finite()) {
                                return Err(Error::NonFinite {
                                    at: iat.clone(),
                                    value: v.to_string(),
                                });
                            }
                            let cols: [f64; 16] = std::array::from_fn(|k| f64::from(m[k]));
                            Ok(DAffine3::from_mat4(glam::DMat4::from_cols_array(&cols)))
                        })
                        .collect::<Result<_, _>>()?
                }
            };
            Ok(Skin {
                joints,
                inverse_bind,
            })
        })
        .collect()
}

/// MAT4 accessors as 16 floats each: read as a VEC4 accessor of four times the count.
fn read_matrices(acc: &gltf::Accessor<'_>, buffers: &Buffers, at: &str) -> Result<Vec<f32>, Error> {
    crate::accessor::read_mat4(acc, buffers, at)
}

/// Renormalises influences in place (weights of each vertex summing to one).
pub(crate) fn renormalise(inf: &mut Influences) {
    if inf.per_vertex == 0 {
        return;
    }
    for w in inf.weights.chunks_exact_mut(inf.per_vertex) {
        let sum: f32 = w.iter().sum();
        if sum > 0.0 && sum.is_finite() {
            for x in w {
                *x /= sum;
            }
        }
    }
}

/// Poses `mesh` (object space) by `joint_matrices` (`world(joint) · inverseBind`, one per joint
/// of the skin) and returns the world-space centre its positions are now relative to.
/// `unweighted` places vertices no joint influences (the node's own world transform).
pub(crate) fn apply(
    mesh: &mut Mesh,
    inf: &Influences,
    joint_matrices: &[DAffine3],
    unweighted: DAffine3,
    at: &str,
) -> Result<DVec3, Error> {
    let n = mesh.positions.len();
    let per = inf.per_vertex;
    let mut world = Vec::with_capacity(n);
    for v in 0..n {
        let mut m = DAffine3 {
            matrix3: DMat3::ZERO,
            translation: DVec3::ZERO,
        };
        let mut total = 0.0;
        for k in 0..per {
            let w = f64::from(inf.weights[v * per + k]);
            if w == 0.0 {
                continue;
            }
            let j = inf.joints[v * per + k] as usize;
            let jm = joint_matrices
                .get(j)
                .ok_or_else(|| Error::IndexOutOfRange {
                    at: format!("{at}.attributes.JOINTS_{}", k / 4),
                    index: j as u64,
                    vertices: joint_matrices.len(),
                })?;
            m.matrix3 += jm.matrix3 * w;
            m.translation += jm.translation * w;
            total += w;
        }
        if total == 0.0 {
            m = unweighted;
        }
        world.push(m.transform_point3(mesh.positions[v].as_dvec3()));
        let normal_from = if m.matrix3.determinant().abs() > 0.0 {
            m.matrix3.inverse().transpose()
        } else {
            m.matrix3
        };
        let nrm = normal_from * mesh.normals[v].as_dvec3();
        mesh.normals[v] = nrm.as_vec3().try_normalize().unwrap_or(mesh.normals[v]);
        if let Some(t) = mesh.tangents.get_mut(v) {
            let xyz = (m.matrix3 * t.truncate().as_dvec3()).as_vec3();
            if let Some(u) = xyz.try_normalize() {
                *t = Vec4::from((u, t.w));
            }
        }
    }
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in &world {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let centre = if lo.is_finite() && hi.is_finite() {
        0.5 * (lo + hi)
    } else {
        DVec3::ZERO
    };
    for (p, w) in mesh.positions.iter_mut().zip(&world) {
        *p = (*w - centre).as_vec3();
    }
    if let Some(p) = mesh.positions.iter().find(|p| !p.is_finite()) {
        return Err(Error::NonFinite {
            at: format!("{at} (skinned positions)"),
            value: format!("{p:?}"),
        });
    }
    Ok(centre)
}

/// Flat normals again for the triangles whose vertices came without `NORMAL`, after their
/// positions moved.
pub(crate) fn refresh_flat_normals(mesh: &mut Mesh, flat: &[std::ops::Range<u32>]) {
    if flat.is_empty() {
        return;
    }
    for t in 0..mesh.indices.len() {
        let [a, b, c] = mesh.indices[t];
        if !flat.iter().any(|r| r.contains(&a)) {
            continue;
        }
        let p = |i: u32| mesh.positions[i as usize];
        let n = (p(b) - p(a))
            .cross(p(c) - p(a))
            .try_normalize()
            .unwrap_or(Vec3::Z);
        for i in [a, b, c] {
            mesh.normals[i as usize] = n;
        }
    }
}

/// Reads `JOINTS_n`/`WEIGHTS_n` values (flat, 4 per vertex per set) into influences.
pub(crate) fn influences(sets: Vec<(Vec<f32>, Vec<f32>)>, vertices: usize) -> Influences {
    let per = 4 * sets.len();
    let mut inf = Influences {
        per_vertex: per,
        joints: vec![0; vertices * per],
        weights: vec![0.0; vertices * per],
    };
    for (s, (joints, weights)) in sets.iter().enumerate() {
        for v in 0..vertices {
            for k in 0..4 {
                let dst = v * per + 4 * s + k;
                inf.joints[dst] = joints.get(v * 4 + k).map_or(0, |&j| j.max(0.0) as u32);
                inf.weights[dst] = weights.get(v * 4 + k).copied().unwrap_or(0.0).max(0.0);
            }
        }
    }
    renormalise(&mut inf);
    inf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_joints_blend_and_weights_renormalise() {
        let mut mesh = Mesh {
            positions: vec![Vec3::X],
            normals: vec![Vec3::Y],
            ..Mesh::default()
        };
        // Weights 1 and 1: renormalised to a half each.
        let inf = influences(
            vec![(vec![0.0, 1.0, 0.0, 0.0], vec![1.0, 1.0, 0.0, 0.0])],
            1,
        );
        let a = DAffine3::from_translation(DVec3::new(0.0, 2.0, 0.0));
        let b = DAffine3::from_translation(DVec3::new(0.0, 4.0, 0.0));
        let c = apply(&mut mesh, &inf, &[a, b], DAffine3::IDENTITY, "m").unwrap();
        assert_eq!(c, DVec3::new(1.0, 3.0, 0.0));
        assert_eq!(mesh.positions[0], Vec3::ZERO);
        // A joint index past the skin's joints is an error naming the attribute.
        let bad = influences(
            vec![(vec![5.0, 0.0, 0.0, 0.0], vec![1.0, 0.0, 0.0, 0.0])],
            1,
        );
        let e = apply(&mut mesh, &bad, &[a], DAffine3::IDENTITY, "meshes[0]").unwrap_err();
        assert!(
            e.to_string().contains("meshes[0].attributes.JOINTS_0"),
            "{e}"
        );
    }
}
