//! What the back of a single-sided face is (`--single-sided auto|gltf|blender`, a
//! [`Convention`](crate::convention::Convention) resolved as transmission's meaning is).
//!
//! glTF asks for back-face culling where a material is not `doubleSided`: the back of such a
//! face is seen by no ray (camera, shadow or bounce), as if it were not there. Cycles, after
//! Blender imports the file, renders both sides (Blender's "Backface Culling" setting is a
//! viewport and EEVEE option). So:
//! - `gltf`: the back of a `doubleSided: false` face is invisible to every ray;
//! - `blender`: both sides are surfaces, as Cycles shows them;
//! - `auto` (the command line's default): `blender` when `asset.generator` names Blender's
//!   glTF exporter, else `gltf`.

use crate::convention::ConventionModel;
use crate::surface::{Geometry, Surface};
use aperture_scene::Scene;
use glam::Vec3;
use std::fmt;

/// What the back of a single-sided face is: a resolved `--single-sided`
/// [`Convention`](crate::convention::Convention).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SidesModel {
    /// Backs of single-sided faces are seen by no ray.
    Gltf,
    /// Every face has two sides (what renders of scenes built by hand have always had).
    #[default]
    Both,
}

impl ConventionModel for SidesModel {
    const FLAG: &'static str = "--single-sided";
    /// glTF's meaning: the back of a single-sided face is invisible.
    const GLTF: Self = Self::Gltf;
    /// Cycles' meaning: both sides are seen.
    const BLENDER: Self = Self::Both;
}

impl Geometry<'_> {
    /// The same, with the backs of single-sided faces invisible under `model`
    /// ([`SidesModel::Both`], the default, sees both sides).
    pub fn with_sides(mut self, model: SidesModel) -> Self {
        self.has_culled =
            model == SidesModel::Gltf && self.scene.materials.iter().any(|m| !m.double_sided);
        self
    }

    /// True when a ray along `dir` meets the back of a single-sided face at `s` and so does
    /// not see it (glTF's back-face culling; never under [`SidesModel::Both`]).
    #[inline]
    pub fn is_culled(&self, s: &Surface, dir: Vec3) -> bool {
        s.ng.dot(dir) > 0.0 && self.has_back_culled(s)
    }

    /// True when no ray sees the back of the face at `s`: only the side its `ng` points to is
    /// there (a culled single-sided face; never under [`SidesModel::Both`]).
    #[inline]
    pub fn has_back_culled(&self, s: &Surface) -> bool {
        self.has_culled && !self.material(s.material).double_sided
    }
}

/// How many of `scene`'s materials are single-sided (not `doubleSided`).
pub fn single_sided_materials(scene: &Scene) -> usize {
    scene.materials.iter().filter(|m| !m.double_sided).count()
}

impl fmt::Display for SidesModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Gltf => "gltf",
            Self::Both => "blender",
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
        let sides = |c: Convention, g| c.resolve_for::<SidesModel>(g);
        assert_eq!(sides(Convention::Auto, blender).0, SidesModel::Both);
        assert_eq!(
            sides(Convention::Auto, Some("Khronos Sample")).0,
            SidesModel::Gltf
        );
        assert_eq!(sides(Convention::Auto, None).0, SidesModel::Gltf);
        assert_eq!(
            sides(Convention::Gltf, blender),
            (SidesModel::Gltf, "--single-sided gltf".into())
        );
        assert_eq!(
            sides(Convention::Blender, None),
            (SidesModel::Both, "--single-sided blender".into())
        );
    }
}
