//! Helpers shared by the criterion benchmarks in `benches/benches/`.

use std::path::PathBuf;

/// The glTF samples folder (`APERTURE_SAMPLES`, else `../shared/gltf-samples`).
pub fn samples_dir() -> PathBuf {
    std::env::var_os("APERTURE_SAMPLES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/gltf-samples")
        })
}
