//! `--transmission`, `--single-sided`, `--variant` and `--no-energy-compensation` (SPEC §5),
//! shared by `render` and `info`.

use aperture_shading::Convention;
use clap::ValueEnum as _;

/// How materials are interpreted.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct MaterialArgs {
    /// What a transmissive surface is: `gltf` = thin-walled unless KHR_materials_volume gives
    /// it a thickness (the Khronos meaning); `blender` = every transmissive closed mesh
    /// refracts as a volume of its IOR, as Cycles renders a Blender export; `auto` = `blender`
    /// for files written by Blender's glTF exporter, else `gltf`.
    #[arg(long, value_name = "auto|gltf|blender", default_value = "auto", value_parser = convention("transmission"))]
    pub transmission: Convention,
    /// What the back of a `doubleSided: false` face is: `gltf` = invisible to every ray (glTF's
    /// back-face culling); `blender` = a surface like the front, as Cycles renders a Blender
    /// import; `auto` = `blender` for files written by Blender's glTF exporter, else `gltf`.
    #[arg(long, value_name = "auto|gltf|blender", default_value = "auto", value_parser = convention("single-sided"))]
    pub single_sided: Convention,
    /// Draw the materials of this KHR_materials_variants variant (its name, or its index in
    /// the file) [default: the default materials].
    #[arg(long, value_name = "NAME|INDEX")]
    pub variant: Option<String>,
    /// Render glTF's single-scattering formulas literally: no multiple-scattering energy
    /// compensation of rough lobes and no albedo scaling of layers (rough metals darker, and
    /// dielectrics brighter at grazing angles, than Cycles shows them).
    #[arg(long)]
    pub no_energy_compensation: bool,
}

/// The parser of a [`Convention`] flag: its `ValueEnum` values, a refusal in the flag's own
/// words (`unknown single-sided mode "x" (expected auto, gltf or blender)`), and the values
/// left out of the help (its value name lists them).
fn convention(what: &'static str) -> impl Fn(&str) -> Result<Convention, String> + Clone {
    move |s| {
        Convention::from_str(s, false)
            .map_err(|_| format!("unknown {what} mode {s:?} (expected auto, gltf or blender)"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        m: MaterialArgs,
    }

    #[test]
    fn defaults_and_values() {
        let d = Cli::parse_from(["x"]).m;
        assert_eq!(d.transmission, Convention::Auto);
        assert_eq!(d.single_sided, Convention::Auto);
        assert!(!d.no_energy_compensation && d.variant.is_none());
        let a = Cli::parse_from([
            "x",
            "--transmission",
            "blender",
            "--variant",
            "Yellow",
            "--no-energy-compensation",
        ])
        .m;
        assert_eq!(a.transmission, Convention::Blender);
        assert_eq!(a.variant.as_deref(), Some("Yellow"));
        assert!(a.no_energy_compensation);
        assert!(Cli::try_parse_from(["x", "--transmission", "glass"]).is_err());
        let g = Cli::parse_from(["x", "--single-sided", "gltf"]).m;
        assert_eq!(g.single_sided, Convention::Gltf);
        let e = Cli::try_parse_from(["x", "--single-sided", "front"])
            .err()
            .unwrap();
        assert_eq!(
            e.to_string().lines().next(),
            Some(
                "error: invalid value 'front' for '--single-sided <auto|gltf|blender>': \
                 unknown single-sided mode \"front\" (expected auto, gltf or blender)"
            )
        );
        let e = Cli::try_parse_from(["x", "--transmission", "Gltf"])
            .err()
            .unwrap();
        assert!(
            e.to_string()
                .contains("unknown transmission mode \"Gltf\" (expected auto, gltf or blender)"),
            "{e}"
        );
    }
}
