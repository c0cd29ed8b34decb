//! Shared helpers for the end-to-end tests in `tests/tests/`.

pub mod demo;
pub mod meshopt_writer;

use std::path::PathBuf;

/// The folder of third-party glTF samples: `APERTURE_SAMPLES`, else `../shared/gltf-samples`
/// beside the repository. `None` (with a message) when it is missing outside CI; a panic in CI,
/// where a missing folder must fail the run rather than skip silently.
pub fn samples_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("APERTURE_SAMPLES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/gltf-samples")
        });
    if dir.join("index.json").is_file() {
        return Some(dir);
    }
    let in_ci = std::env::var("CI").is_ok_and(|v| v == "true");
    assert!(
        !in_ci,
        "CI=true but the glTF samples are missing at {}",
        dir.display()
    );
    eprintln!(
        "skipping: glTF samples not found at {} (set APERTURE_SAMPLES)",
        dir.display()
    );
    None
}

/// Builds the scene's BVH, renders it and insists that no sample was dropped as non-finite
/// (issue 6: every test render asserts that count is 0).
pub fn render_checked(
    scene: &aperture_scene::Scene,
    opts: &aperture_render::RenderOptions,
) -> aperture_render::Film {
    let accel = aperture_render::build_accel(scene, Default::default());
    let film = aperture_render::render(scene, &accel, opts, &|_, _| {}).expect("renders");
    assert_eq!(film.dropped_samples(), 0, "non-finite samples were dropped");
    film
}
