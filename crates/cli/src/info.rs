//! `aperture info`: what a scene contains and how its cameras resolve.

use std::path::PathBuf;

/// Arguments of `aperture info`.
#[derive(clap::Args)]
pub struct InfoArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
}

/// Runs `aperture info`.
pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let s = aperture_scene::load(&args.scene, &Default::default())?;
    println!("{} triangles drawn", s.drawn_triangle_count());
    Ok(())
}
