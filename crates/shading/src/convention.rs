//! Whose reading of a file a setting follows where glTF and Blender's Cycles differ
//! (`auto|gltf|blender`): what a transmissive surface is (`crate::transmission`) and what the
//! back of a single-sided face is (`crate::sides`). Each setting resolves a [`Convention`] to
//! its own model; `auto` decides the same way for all of them: Blender's meaning for a file
//! written by Blender's glTF exporter (its author saw it in Cycles), glTF's for any other.

use aperture_scene::Scene;

/// Which meaning a setting follows: `--transmission` and `--single-sided` take one each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Convention {
    /// Decide from the file's `asset.generator`: Blender's exporter wrote it, or not.
    #[default]
    Auto,
    /// The Khronos meaning.
    Gltf,
    /// Cycles' meaning, as Blender renders the file after importing it.
    Blender,
}

/// A setting's model under each meaning, for [`Convention::resolve`].
pub trait ConventionModel: Sized {
    /// The command-line flag that chooses the convention (the reason an explicit choice
    /// gives, as `--transmission gltf`).
    const FLAG: &'static str;
    /// The model under glTF's meaning.
    const GLTF: Self;
    /// The model under Cycles' meaning.
    const BLENDER: Self;
}

/// Substring of `asset.generator` that Blender's glTF exporter writes
/// ("Khronos glTF Blender I/O vX.Y.Z").
const BLENDER_EXPORTER: &str = "glTF Blender I/O";

impl Convention {
    /// The model of setting `M` that applies to a file written by `generator`
    /// (`asset.generator`), and why in words.
    pub fn resolve_for<M: ConventionModel>(self, generator: Option<&str>) -> (M, String) {
        let (blender, why) = match self {
            Self::Gltf => (false, format!("{} gltf", M::FLAG)),
            Self::Blender => (true, format!("{} blender", M::FLAG)),
            Self::Auto => blender_export(generator),
        };
        (if blender { M::BLENDER } else { M::GLTF }, why)
    }

    /// [`Convention::resolve_for`] the scene's file.
    pub fn resolve<M: ConventionModel>(self, scene: &Scene) -> (M, String) {
        self.resolve_for(scene.stats.generator.as_deref())
    }
}

/// Whether `generator` (`asset.generator`) is Blender's glTF exporter, and why in words.
fn blender_export(generator: Option<&str>) -> (bool, String) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A setting whose models are the meanings themselves.
    #[derive(Debug, PartialEq)]
    enum Meaning {
        Gltf,
        Blender,
    }

    impl ConventionModel for Meaning {
        const FLAG: &'static str = "--test";
        const GLTF: Self = Meaning::Gltf;
        const BLENDER: Self = Meaning::Blender;
    }

    #[test]
    fn auto_follows_the_exporter() {
        let blender = Some("Khronos glTF Blender I/O v4.2.70");
        let (m, why) = Convention::Auto.resolve_for::<Meaning>(blender);
        assert_eq!(m, Meaning::Blender);
        assert_eq!(
            why,
            "asset.generator \"Khronos glTF Blender I/O v4.2.70\" is Blender's glTF exporter"
        );
        // Naming Blender is not enough: the exporter writes the file.
        let other = Some("glTF-Transform v3.0.4, and Blender 3.3, and VSCode glTF-Tools");
        assert_eq!(
            Convention::Auto.resolve_for::<Meaning>(other).0,
            Meaning::Gltf
        );
        assert_eq!(
            Convention::Auto.resolve_for::<Meaning>(None),
            (Meaning::Gltf, "the file names no asset.generator".into())
        );
    }

    #[test]
    fn explicit_choices_win_and_say_so() {
        let blender = Some("Khronos glTF Blender I/O v4.2.70");
        assert_eq!(
            Convention::Gltf.resolve_for::<Meaning>(blender),
            (Meaning::Gltf, "--test gltf".into())
        );
        assert_eq!(
            Convention::Blender.resolve_for::<Meaning>(None),
            (Meaning::Blender, "--test blender".into())
        );
    }
}
