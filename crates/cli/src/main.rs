//! `aperture`: render glTF scenes with physically based depth of field.

use clap::{Parser, Subcommand};

/// Physically based depth-of-field renderer for glTF 2.0 scenes.
#[derive(Parser)]
#[command(name = "aperture", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print what a scene contains and how its cameras resolve.
    Info {
        /// The .gltf or .glb file.
        scene: std::path::PathBuf,
    },
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Info { scene } => {
            let s = aperture_scene::load(&scene, &Default::default())?;
            println!("{} triangles drawn", s.drawn_triangle_count());
        }
    }
    Ok(())
}
