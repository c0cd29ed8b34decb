//! Helpers shared by the scene crate's sample tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The glTF samples folder (`APERTURE_SAMPLES`, else `../shared/gltf-samples` beside the
/// repository). Missing: `None` with a message, but a panic under `CI=true`, where a silent skip
/// would hide that the test never ran.
pub fn samples_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("APERTURE_SAMPLES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/gltf-samples")
        });
    if dir.join("index.json").is_file() {
        return Some(dir);
    }
    assert!(
        !std::env::var("CI").is_ok_and(|v| v == "true"),
        "CI=true but the glTF samples are missing at {}",
        dir.display()
    );
    eprintln!("skipping: glTF samples not found at {}", dir.display());
    None
}

pub mod glb;
pub mod reference;
