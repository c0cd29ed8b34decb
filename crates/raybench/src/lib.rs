//! The traversal benchmark behind `aperture bench-rays`: ray sets made deterministically from a
//! scene's thin-lens camera, and their closest-hit and occlusion throughput per BVH preset.
//!
//! - [`generate_sets`] makes four sets: thin-lens primary rays with several lens samples per
//!   pixel in 16×16-pixel tile order (`primary_tile`) and the same rays shuffled by the seed
//!   (`primary_random`); diffuse bounce rays (`diffuse`) and shadow rays (`shadow`, finite
//!   `tmax`) from the primary rays' first hits.
//! - [`time_sets`] builds each BVH preset and times [`Query::Closest`] and [`Query::Occluded`]
//!   one ray at a time ([`Mode::OneRay`]) and batched ([`Mode::Batch`]) on rayon pools of the
//!   given sizes, reporting the median, least and most Mrays/s ([`Timing`]).
//! - Sets are saved to and read from the Embree anchor's `.rays` files with
//!   [`aperture_accel::rayfile`] ([`save_sets`], [`load_set`]), so Embree can time the identical
//!   rays.
//!
//! The sets are generated once (their first hits found with one structure) and every preset
//! times the same rays.
//!
//! ```
//! use aperture_raybench::{closest_hits, generate_sets, Mode, RaySetOptions};
//! use aperture_render::{build_accel, Camera};
//! use aperture_shading::test_scenes;
//! let scene = test_scenes::lit_plane(1.0);
//! let accel = build_accel(&scene, Default::default());
//! let camera = Camera::new(&scene.cameras[0], 16, 16);
//! let sets = generate_sets(&scene, &accel, &camera, &RaySetOptions { lens_samples: 2, seed: 0 });
//! assert_eq!(sets[0].name, "primary_tile");
//! let mut hits = vec![None; sets[0].rays.len()];
//! closest_hits(&accel, &sets[0].rays, Mode::Batch, &mut hits);
//! assert!(hits.iter().any(Option::is_some));
//! ```

mod sets;
mod timing;

pub use sets::{
    estimated_bytes, generate_sets, primary_ray, primary_samples, shadow_target, shuffled,
    PrimarySample, RaySet, RaySetOptions, BENCH_TILE, BYTES_PER_PRIMARY_SAMPLE, SET_NAMES,
};
pub use timing::{
    closest_hits, occlusions, time_query, time_sets, Mode, QualityRun, Query, RayBenchError,
    Timing, TimingOptions,
};

use aperture_accel::rayfile::{read_rays, write_rays, RayFileError};
use std::path::{Path, PathBuf};

/// Writes each set as `dir/<name>.rays` (and `dir/<name>.tmax` for sets with a finite `tmax`,
/// which the `.rays` format cannot carry; see [`aperture_accel::rayfile`]). Creates `dir`.
/// Returns the `.rays` files written.
pub fn save_sets(dir: &Path, sets: &[RaySet]) -> Result<Vec<PathBuf>, RayFileError> {
    std::fs::create_dir_all(dir).map_err(|source| RayFileError::Io {
        path: dir.to_owned(),
        source,
    })?;
    sets.iter()
        .map(|s| {
            let path = dir.join(format!("{}.rays", s.name));
            write_rays(&path, &s.rays).map(|()| path)
        })
        .collect()
}

/// Reads a ray file as a set named after its stem (with its `.tmax` sidecar if present).
pub fn load_set(path: &Path) -> Result<RaySet, RayFileError> {
    let rays = read_rays(path)?;
    let name = path
        .file_stem()
        .map_or_else(|| "rays".to_owned(), |s| s.to_string_lossy().into_owned());
    Ok(RaySet { name, rays })
}
