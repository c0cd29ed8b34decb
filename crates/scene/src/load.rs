//! The loader's entry points: a file or its bytes to a posed [`Scene`]. [`Animated`] does the
//! work; its shared steps live in `buffers`, `nodes` and `origin`.

use std::path::Path;

use crate::animated::Animated;
use crate::error::Error;
use crate::types::{LoadOptions, Scene};

/// Loads a `.gltf` or `.glb` file into a render-ready [`Scene`], posed at
/// [`LoadOptions::time`] (the stored pose without one).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, Error> {
    Animated::load(path, options)?.into_scene(options.time)
}

/// Loads a scene from the bytes of a `.gltf` or `.glb` file; external URIs resolve inside `base_dir`.
pub fn load_bytes(bytes: &[u8], base_dir: &Path, options: &LoadOptions) -> Result<Scene, Error> {
    Animated::load_bytes(bytes, base_dir, options)?.into_scene(options.time)
}

#[cfg(test)]
mod tests;
