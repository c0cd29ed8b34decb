//! Morph targets (glTF 2.0 §3.7.2.2): a primitive's base attributes plus the weighted sum of its
//! targets' displacements. Weights come from the node, else the mesh (SPEC §7), or an animation.

use glam::{Vec3, Vec4};

use crate::types::Mesh;

/// One morph target of a merged mesh: displacements per vertex (an empty list = the attribute is
/// not displaced by this target).
#[derive(Debug, Clone, Default)]
pub(crate) struct MorphTarget {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub tangents: Vec<Vec3>,
}

/// Adds `weights[k] ×` target `k` to the mesh (missing weights are 0), then renormalises the
/// displaced normals and tangents.
pub(crate) fn apply(mesh: &mut Mesh, targets: &[MorphTarget], weights: &[f32]) {
    let mut touched = (false, false);
    for (target, &w) in targets.iter().zip(weights) {
        if w == 0.0 {
            continue;
        }
        for (p, d) in mesh.positions.iter_mut().zip(&target.positions) {
            *p += w * *d;
        }
        for (n, d) in mesh.normals.iter_mut().zip(&target.normals) {
            *n += w * *d;
            touched.0 = true;
        }
        for (t, d) in mesh.tangents.iter_mut().zip(&target.tangents) {
            *t += Vec4::from((w * *d, 0.0));
            touched.1 = true;
        }
    }
    if touched.0 {
        for n in &mut mesh.normals {
            *n = n.try_normalize().unwrap_or(Vec3::Z);
        }
    }
    if touched.1 {
        for t in &mut mesh.tangents {
            let xyz = t.truncate();
            if xyz != Vec3::ZERO {
                *t = Vec4::from((xyz.normalize_or_zero(), t.w));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_targets_add_up() {
        let mut m = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X],
            normals: vec![Vec3::Z; 2],
            ..Mesh::default()
        };
        let targets = [
            MorphTarget {
                positions: vec![Vec3::Y, Vec3::Y],
                ..MorphTarget::default()
            },
            MorphTarget {
                positions: vec![Vec3::Z, Vec3::ZERO],
                normals: vec![Vec3::X, Vec3::ZERO],
                ..MorphTarget::default()
            },
        ];
        apply(&mut m, &targets, &[0.5, 2.0]);
        assert_eq!(
            m.positions,
            [Vec3::new(0.0, 0.5, 2.0), Vec3::new(1.0, 0.5, 0.0)]
        );
        assert!((m.normals[0] - Vec3::new(2.0, 0.0, 1.0).normalize()).length() < 1e-6);
        assert_eq!(m.normals[1], Vec3::Z);
    }
}
