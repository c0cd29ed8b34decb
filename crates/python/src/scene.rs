//! `aperture.Scene`: a loaded file (a render session, SPEC §9) with its renders, edits and
//! ray queries. Every method that works releases the GIL; the session is locked only
//! without it.

use crate::edits::{self, Target};
use crate::errors::{edit_error, load_error, value_error};
use crate::images::RenderResult;
use crate::interrupt::on_threads;
use crate::load_opts::load_options;
use crate::options::Kwargs;
use crate::progressive::Render;
use crate::ray_input::RayArrays;
use crate::render_opts::render_ask;
use crate::state::{lock, Shared, State};
use aperture_scene::{Edit, Scene as Posed};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// A glTF file loaded once: render it (`render`, `start`), edit it in place (`set_*`), and
/// query rays against it (`intersect`, `occluded`, `camera_rays`).
#[pyclass(module = "aperture", frozen)]
pub struct Scene {
    state: Shared,
    /// The file it was loaded from.
    #[pyo3(get)]
    path: PathBuf,
}

/// Loads `path` with the command line's load options.
pub(crate) fn load(
    py: Python<'_>,
    path: PathBuf,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Scene> {
    let mut kw = Kwargs::new(options, "load")?;
    let (load, defaults) = load_options(&mut kw)?;
    let given = match kw.take("geometry")? {
        Some(v) if !v.is_none() => crate::geometry::load_edits(&v)?,
        _ => Vec::new(),
    };
    kw.finish()?;
    // Posed at once, so a file that loads but cannot be posed (a focus object behind the
    // camera) fails here, as the command line fails before rendering.
    let time = defaults.time;
    let session = py
        .detach(|| {
            let mut session = aperture_render::Session::load_edited(&path, &load, given)?;
            session.pose(time)?;
            Ok(session)
        })
        .map_err(load_error)?;
    let state = State {
        session,
        defaults,
        last_spec: None,
    };
    Ok(Scene {
        state: Arc::new(Mutex::new(state)),
        path,
    })
}

impl Scene {
    /// `f` of the scene posed at its time, without the GIL.
    fn with_posed<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&Posed) -> PyResult<T> + Send,
    ) -> PyResult<T> {
        py.detach(|| {
            let mut st = lock(&self.state);
            let time = st.defaults.time;
            f(st.session.pose(time).map_err(load_error)?)
        })
    }

    /// Applies the edits `make` builds from the posed scene.
    fn edit(
        &self,
        py: Python<'_>,
        make: impl FnOnce(&Posed) -> PyResult<Vec<Edit>> + Send,
    ) -> PyResult<()> {
        py.detach(|| {
            let mut st = lock(&self.state);
            let time = st.defaults.time;
            let edits = make(st.session.pose(time).map_err(load_error)?)?;
            for e in edits {
                st.session.edit(e).map_err(edit_error)?;
            }
            Ok(())
        })
    }
}

#[pymethods]
impl Scene {
    /// What the scene holds, as `aperture info --json` reports it (a dict; the same report,
    /// `aperture_render::info`, under the scene's transmission and single-sided conventions;
    /// `motion` is the command line's, for a frame it is given).
    fn info(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let d = py.detach(|| lock(&self.state).defaults.clone());
        let (transmission, sides) = (d.transmission, d.single_sided);
        let report = |s: &_| Ok(aperture_render::info::report(s, transmission, sides).to_string());
        let text = self.with_posed(py, report)?;
        let json = py.import("json")?;
        Ok(json.call_method1("loads", (text,))?.unbind())
    }

    /// Renders the scene with the command line's render options; returns the image and its
    /// passes (`image, passes = scene.render(...)`).
    #[pyo3(signature = (**options))]
    fn render(
        &self,
        py: Python<'_>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<RenderResult> {
        let mut kw = Kwargs::new(options, "render")?;
        let defaults = py.detach(|| lock(&self.state).defaults.clone());
        let ask = render_ask(&mut kw, &defaults)?;
        kw.finish()?;
        crate::render::render(py, &self.state, ask)
    }

    /// Starts a progressive render with `render`'s options; `step(n)` refines it.
    #[pyo3(signature = (**options))]
    fn start(&self, py: Python<'_>, options: Option<&Bound<'_, PyDict>>) -> PyResult<Render> {
        let mut kw = Kwargs::new(options, "start")?;
        let defaults = py.detach(|| lock(&self.state).defaults.clone());
        let ask = render_ask(&mut kw, &defaults)?;
        kw.finish()?;
        Render::start(py, &self.state, ask)
    }

    /// Moves the camera (`matrix`: its 4×4 world transform, as math writes it) and sets its
    /// depth-of-field and lens keys (`fstop`, `focus_distance`, `aperture_radius`,
    /// `focus_object`, …, `aperture_image`: a path relative to the glTF file's folder or a
    /// texture index, read by the edit; `lens_prescription`: a lens file's path there or rows
    /// of 4 numbers). `None` removes a key. A bad value or a file that cannot be read raises
    /// `ValueError` naming the camera and the key, and changes nothing.
    #[pyo3(signature = (camera=None, matrix=None, **keys))]
    fn set_camera(
        &self,
        py: Python<'_>,
        camera: Option<&Bound<'_, PyAny>>,
        matrix: Option<&Bound<'_, PyAny>>,
        keys: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let camera = match camera {
            None => None,
            Some(c) => Some(match Target::extract(c, "camera")? {
                Target::Index(i) => i.to_string(),
                Target::Name(n) => n,
            }),
        };
        let matrix = matrix.map(edits::matrix).transpose()?;
        let keys = edits::camera_keys(keys)?;
        self.edit(py, |s| edits::camera(s, camera.as_deref(), matrix, keys))
    }

    /// Replaces node `node`'s local transform by `matrix` (4×4, as math writes it), or
    /// replaces the components given of its stored TRS: `translation` (3), `rotation` (a unit
    /// quaternion x, y, z, w) and `scale` (3), as an animation channel would (the others keep
    /// their values).
    #[pyo3(signature = (node, matrix=None, *, translation=None, rotation=None, scale=None))]
    fn set_transform(
        &self,
        py: Python<'_>,
        node: &Bound<'_, PyAny>,
        matrix: Option<&Bound<'_, PyAny>>,
        translation: Option<&Bound<'_, PyAny>>,
        rotation: Option<&Bound<'_, PyAny>>,
        scale: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let node = Target::extract(node, "node")?;
        let trs = [
            ("translation", translation),
            ("rotation", rotation),
            ("scale", scale),
        ];
        let how = edits::transform_of(matrix, trs)?;
        self.edit(py, |s| edits::transform(s, &node, &how))
    }

    /// Sets material factors: `base_color`, `metallic`, `roughness`, `emissive`,
    /// `emissive_strength`, `alpha_cutoff`, `normal_scale`, `occlusion_strength`, `ior`,
    /// `specular`, `specular_color`.
    #[pyo3(signature = (material, **factors))]
    fn set_material(
        &self,
        py: Python<'_>,
        material: &Bound<'_, PyAny>,
        factors: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let m = Target::extract(material, "material")?;
        // Checked with the GIL (the values are Python objects), applied without it.
        let names = self.with_posed(py, |s| {
            Ok(s.materials
                .iter()
                .map(|m| m.name.clone())
                .collect::<Vec<_>>())
        })?;
        let index = match &m {
            Target::Index(i) => *i,
            Target::Name(n) => names
                .iter()
                .position(|m| m.as_deref() == Some(n.as_str()))
                .ok_or_else(|| value_error(format!("no material is named {n:?}")))?,
        };
        let edits = edits::material(index, factors)?;
        self.edit(py, |_| Ok(edits))
    }

    /// Sets a `KHR_lights_punctual` light's `color`, `intensity`, `range`,
    /// `inner_cone_angle`, `outer_cone_angle`.
    #[pyo3(signature = (light, **values))]
    fn set_light(
        &self,
        py: Python<'_>,
        light: i64,
        values: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let light = in_range("light", light, 0, i64::from(u32::MAX))?;
        let edits = edits::light(light as usize, values)?;
        self.edit(py, |_| Ok(edits))
    }

    /// Gives glTF mesh `mesh` (its index) new geometry, one dict per primitive in order (as
    /// many as the mesh has): `positions` (N×3), `triangles` (M×3 vertex indices), optional
    /// `normals` (N×3; flat without) and `uvs` (N×2, texture coordinates set 0). As if the file
    /// stored them; each primitive keeps its material. The file is loaded again.
    fn set_geometry(
        &self,
        py: Python<'_>,
        mesh: &Bound<'_, PyAny>,
        primitives: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let edit = crate::geometry::mesh_edit(crate::geometry::mesh_index(mesh)?, primitives)?;
        self.edit(py, |_| Ok(vec![edit]))
    }

    /// Shows or hides node `node` (and what it carries), as `KHR_node_visibility` stores it.
    fn set_visible(&self, py: Python<'_>, node: &Bound<'_, PyAny>, visible: bool) -> PyResult<()> {
        let node = Target::extract(node, "node")?;
        self.edit(py, |s| edits::visible(s, &node, visible))
    }

    /// Closest hits of N rays: a dict of arrays `t`, `primitive`, `instance`, `mesh`, `u`,
    /// `v`, `normal` (N, 3), `hit`.
    #[pyo3(signature = (origins, directions, tmin=None, tmax=None, threads=None))]
    fn intersect<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: Option<&Bound<'py, PyAny>>,
        tmax: Option<&Bound<'py, PyAny>>,
        threads: Option<i64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let threads = threads_of(threads)?;
        let arrays = RayArrays::new(origins, directions, tmin, tmax)?;
        let src = arrays.source();
        let hits = py.detach(|| -> PyResult<_> {
            let mut st = lock(&self.state);
            let frame = st.query_frame()?;
            on_threads(threads, |serial| {
                crate::rays::intersect(frame.scene(), frame.accel(), &src, serial)
            })
        })?;
        hits.ok_or_else(|| arrays.error())?.into_dict(py)
    }

    /// Whether each of N rays is blocked between `tmin` and `tmax`: a bool array.
    #[pyo3(signature = (origins, directions, tmax=None, tmin=None, threads=None))]
    fn occluded<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmax: Option<&Bound<'py, PyAny>>,
        tmin: Option<&Bound<'py, PyAny>>,
        threads: Option<i64>,
    ) -> PyResult<Bound<'py, numpy::PyArray1<bool>>> {
        let threads = threads_of(threads)?;
        let arrays = RayArrays::new(origins, directions, tmin, tmax)?;
        let src = arrays.source();
        let answers = py.detach(|| -> PyResult<_> {
            let mut st = lock(&self.state);
            let frame = st.query_frame()?;
            on_threads(threads, |serial| {
                crate::rays::occluded(frame.accel(), &src, serial)
            })
        })?;
        Ok(answers.ok_or_else(|| arrays.error())?.into_pyarray(py))
    }

    /// The thin-lens primary rays of `aperture bench-rays` (its `primary_tile` set): a dict of
    /// `origins`, `directions`, `pixels`, `samples`.
    #[pyo3(signature = (width, height=None, lens_samples=16, seed=0, camera=None))]
    fn camera_rays<'py>(
        &self,
        py: Python<'py>,
        width: i64,
        height: Option<i64>,
        lens_samples: i64,
        seed: i64,
        camera: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let width = in_range("width", width, 1, 16384)?;
        let height = height
            .map(|h| in_range("height", h, 1, 16384))
            .transpose()?;
        let lens_samples = in_range("lens_samples", lens_samples, 1, 65536)?;
        let seed = in_range("seed", seed, 0, i64::from(u32::MAX))?;
        let camera = camera.map(|c| Target::extract(c, "camera")).transpose()?;
        let rays = self.with_posed(py, |s| {
            crate::rays::camera_rays_of(s, camera.as_ref(), (width, height), lens_samples, seed)
        })?;
        rays.into_dict(py)
    }

    /// The scene's triangles in world space, one copy per instance: `vertices`, `indices`,
    /// and each triangle's `instance` and `primitive` (to hand the same geometry to another
    /// ray library).
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let soup = self.with_posed(py, |s| Ok(crate::rays::triangles(s)))?;
        soup.into_dict(py)
    }

    fn __repr__(&self) -> String {
        format!("<aperture.Scene {:?}>", self.path)
    }
}

/// `v` as a `u32` within `lo..=hi`, else a `ValueError` naming it.
fn in_range(name: &str, v: i64, lo: i64, hi: i64) -> PyResult<u32> {
    match (lo..=hi).contains(&v) {
        true => Ok(v as u32),
        false => Err(value_error(format!(
            "invalid {name} = {v}: must be in {lo}..={hi}"
        ))),
    }
}

/// `threads=`: 1 to 4096 workers, `None` for all cores.
fn threads_of(threads: Option<i64>) -> PyResult<Option<usize>> {
    threads
        .map(|n| in_range("threads", n, 1, 4096).map(|n| n as usize))
        .transpose()
}
