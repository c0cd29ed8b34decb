//! The Python module `aperture` (SPEC §9, issue 60): one abi3 wheel for CPython ≥ 3.11
//! (Blender's Python included), built by maturin (`tools/python/test.sh`, README).
//!
//! ```python
//! import aperture, numpy as np
//!
//! scene = aperture.load("assets/demo.glb")             # aperture render's load options
//! image, passes = scene.render(width=320, spp=16)      # float32 H×W×4, {"Depth": H×W×1, …}
//! scene.set_camera(fstop=5.6)                          # an edit: as if the file said so
//! r = scene.start(width=320, spp=64)                   # progressive
//! while not r.done:
//!     r.step()                                         # 1, 1, 2, 4, … samples
//! aperture.write("out.exr", r.image())                 # the command line's EXR
//! rays = scene.camera_rays(320, lens_samples=4)        # bench-rays' thin-lens rays
//! hits = scene.intersect(rays["origins"], rays["directions"])
//! ```
//!
//! Everything is the library's: a [`aperture_render::Session`] holds the scene, renders are
//! its frames' films turned into the EXR's image by [`aperture_output::film_to_image`], ray
//! queries are the frame's BVH. Work runs without the GIL and Ctrl-C cancels a render within
//! a batch of samples (renders of at most 128×128 samples are not watched: the interrupt is
//! raised when they return, milliseconds later). Bad input raises `ValueError`, `TypeError`, `aperture.LoadError` or
//! `aperture.RenderError` with the library's message.

mod edits;
mod errors;
mod geometry;
mod images;
mod interrupt;
mod load_opts;
mod options;
mod progressive;
mod ray_input;
mod rays;
mod render;
mod render_opts;
mod scene;
mod state;
mod write;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Loads a glTF file (`.gltf`/`.glb`) with `aperture render`'s load options: `scene`,
/// `variant`, `time`/`frame`/`fps`, `animation`, `aperture_radius`, `fstop`,
/// `focus_distance`, `focus_object`, `no_dof`, `max_memory`, and the material conventions
/// `transmission` and `single_sided` that its renders start from.
#[pyfunction]
#[pyo3(signature = (path, **options))]
fn load(
    py: Python<'_>,
    path: PathBuf,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<scene::Scene> {
    scene::load(py, path, options)
}

/// The module.
#[pymodule]
fn aperture(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(write::write, m)?)?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<images::RenderResult>()?;
    m.add_class::<progressive::Render>()?;
    m.add("LoadError", py.get_type::<errors::LoadError>())?;
    m.add("RenderError", py.get_type::<errors::RenderError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
