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

use aperture_scene::Scene;
use std::fmt;
use std::str::FromStr;

/// The `--transmission` choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TransmissionMode {
    /// Decide from the file's `asset.generator`.
    #[default]
    Auto,
    /// The Khronos meaning: refractive only with a volume.
    Gltf,
    /// Cycles' meaning: every transmissive closed mesh refracts.
    Blender,
}

/// A resolved [`TransmissionMode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TransmissionModel {
    /// Refractive where `KHR_materials_volume` gives a thickness, thin-walled elsewhere.
    #[default]
    Gltf,
    /// Refractive where the mesh is closed, thin-walled elsewhere.
    Blender,
}

/// Substring of `asset.generator` that Blender's glTF exporter writes
/// ("Khronos glTF Blender I/O vX.Y.Z").
const BLENDER_EXPORTER: &str = "glTF Blender I/O";

/// Whether `generator` (`asset.generator`) is Blender's glTF exporter, and why in words: what
/// the `auto` choices (`--transmission`, `--single-sided`) decide by.
pub fn blender_export(generator: Option<&str>) -> (bool, String) {
    match generator {
        Some(g) if g.contains(BLENDER_EXPORTER) => (
            true,
            format!("asset.generator \"{g}\" is Blender's glTF exporter"),
        ),
        Some(g) => (
            false,
            format!("asset.generator \"{g}\" is not Blender's glTF exporter"),
        ),
        None => (false, "the file names no asset.generator".into()),
    }
}

impl TransmissionMode {
    /// The model that applies to a file written by `generator`, and why.
    pub fn resolve_for(self, generator: Option<&str>) -> (TransmissionModel, String) {
        match self {
            Self::Gltf => (TransmissionModel::Gltf, "--transmission gltf".into()),
            Self::Blender => (TransmissionModel::Blender, "--transmission blender".into()),
            Self::Auto => match blender_export(generator) {
                (true, why) => (TransmissionModel::Blender, why),
                (false, why) => (TransmissionModel::Gltf, why),
            },
        }
    }

    /// [`TransmissionMode::resolve_for`] the scene's file.
    pub fn resolve(self, scene: &Scene) -> (TransmissionModel, String) {
        self.resolve_for(scene.stats.generator.as_deref())
    }
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

/// A `--transmission` value that is not `auto`, `gltf` or `blender`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown transmission mode {0:?} (expected auto, gltf or blender)")]
pub struct ParseTransmissionError(pub String);

impl FromStr for TransmissionMode {
    type Err = ParseTransmissionError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Self::Auto),
            "gltf" => Ok(Self::Gltf),
            "blender" => Ok(Self::Blender),
            _ => Err(ParseTransmissionError(s.to_owned())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_follows_the_generator() {
        let blender = Some("Khronos glTF Blender I/O v4.2.70");
        assert_eq!(
            TransmissionMode::Auto.resolve_for(blender).0,
            TransmissionModel::Blender
        );
        // Naming Blender is not enough: the exporter writes the file.
        let other = Some("glTF-Transform v3.0.4, and Blender 3.3, and VSCode glTF-Tools");
        assert_eq!(
            TransmissionMode::Auto.resolve_for(other).0,
            TransmissionModel::Gltf
        );
        assert_eq!(
            TransmissionMode::Auto.resolve_for(None).0,
            TransmissionModel::Gltf
        );
        // Explicit modes win.
        assert_eq!(
            TransmissionMode::Gltf.resolve_for(blender).0,
            TransmissionModel::Gltf
        );
        assert_eq!(
            TransmissionMode::Blender.resolve_for(None).0,
            TransmissionModel::Blender
        );
        assert!(TransmissionMode::Auto
            .resolve_for(blender)
            .1
            .contains("Blender I/O"));
        assert_eq!("blender".parse(), Ok(TransmissionMode::Blender));
        assert!("glass".parse::<TransmissionMode>().is_err());
    }
}
