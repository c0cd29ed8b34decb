//! What a transmissive surface is: thin-walled or the boundary of a refractive volume
//! (`--transmission auto|gltf|blender`).
//!
//! glTF says a surface with `KHR_materials_transmission` is thin-walled unless
//! `KHR_materials_volume` gives it a thickness. Blender's exporter writes transmission without
//! a volume for an ordinary glass object (the volume needs a special node), and Cycles renders
//! that object as refractive glass after importing the file. So:
//! - `gltf`: the Khronos meaning;
//! - `blender`: every transmissive closed mesh refracts as a volume of the material's IOR (an
//!   open one, such as a single pane, stays thin-walled), as Cycles shows it;
//! - `auto` (the default): `blender` when `asset.generator` names Blender's glTF exporter,
//!   else `gltf`.

use crate::convention::ConventionModel;
use aperture_scene::Scene;
use std::fmt;

/// What a transmissive surface is: a resolved `--transmission`
/// [`Convention`](crate::convention::Convention).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TransmissionModel {
    /// Refractive where `KHR_materials_volume` gives a thickness, thin-walled elsewhere.
    #[default]
    Gltf,
    /// Refractive where the mesh is closed, thin-walled elsewhere.
    Blender,
}

impl ConventionModel for TransmissionModel {
    const FLAG: &'static str = "--transmission";
    /// The Khronos meaning: refractive only with a volume.
    const GLTF: Self = Self::Gltf;
    /// Cycles' meaning: every transmissive closed mesh refracts.
    const BLENDER: Self = Self::Blender;
}

/// How many meshes of `scene` have transmissive triangles, and of those how many are
/// refractive under `model`: `(refractive, thin-walled)` (a mesh counts as refractive when any
/// of its transmissive materials refracts there).
pub fn transmissive_meshes(scene: &Scene, model: TransmissionModel) -> (usize, usize) {
    let (mut refractive, mut thin) = (0, 0);
    let material = |id: u32| scene.materials.get(id as usize);
    let transmissive = |id: u32| material(id).is_some_and(|m| m.is_transmissive() && !m.unlit);
    let has = scene.meshes_with_material(transmissive);
    let volume = scene.meshes_with_material(|id| {
        transmissive(id) && material(id).is_some_and(|m| m.volume.is_some_and(|v| v.is_volume()))
    });
    for (k, mesh) in scene.meshes.iter().enumerate() {
        if !has[k] {
            continue;
        }
        let refracts = match model {
            TransmissionModel::Gltf => volume[k],
            TransmissionModel::Blender => mesh.is_closed(),
        };
        if refracts {
            refractive += 1;
        } else {
            thin += 1;
        }
    }
    (refractive, thin)
}

impl fmt::Display for TransmissionModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Gltf => "gltf",
            Self::Blender => "blender",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convention::Convention;

    #[test]
    fn auto_follows_the_generator() {
        let blender = Some("Khronos glTF Blender I/O v4.2.70");
        let model = |c: Convention, g| c.resolve_for::<TransmissionModel>(g);
        assert_eq!(
            model(Convention::Auto, blender).0,
            TransmissionModel::Blender
        );
        assert_eq!(model(Convention::Auto, None).0, TransmissionModel::Gltf);
        // Explicit modes win, and say so.
        assert_eq!(
            model(Convention::Gltf, blender),
            (TransmissionModel::Gltf, "--transmission gltf".into())
        );
        assert_eq!(
            model(Convention::Blender, None),
            (TransmissionModel::Blender, "--transmission blender".into())
        );
        assert!(model(Convention::Auto, blender).1.contains("Blender I/O"));
    }
}
