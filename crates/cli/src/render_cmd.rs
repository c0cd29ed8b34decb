//! `aperture render`: scene in, EXR or PNG out.

use std::path::PathBuf;

/// Arguments of `aperture render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
    /// Output file; the format follows the extension (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `aperture render`.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "rendering {} to {} is not implemented yet",
        args.scene.display(),
        args.output.display()
    )
}
