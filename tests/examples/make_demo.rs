//! Writes the demo scene `assets/demo.glb` (or the path given as the only argument).
//!
//! ```text
//! cargo run -p aperture-tests --example make_demo
//! ```
//!
//! The bytes are a pure function of `tests/src/demo.rs` (and `tests/src/demo/`); the test
//! `demo_scene` fails when the committed asset differs from them, so rerun this after changing
//! the scene.

use std::path::PathBuf;

fn main() -> std::io::Result<()> {
    let path = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(aperture_tests::demo::asset_path);
    let demo = aperture_tests::demo::build();
    let glb = aperture_tests::demo::to_glb(&demo.json, &demo.bin);
    std::fs::write(&path, &glb)?;
    println!(
        "wrote {} ({} bytes, {} nodes, {} triangles drawn)",
        path.display(),
        glb.len(),
        demo.stats.nodes,
        demo.stats.drawn_triangles
    );
    Ok(())
}
