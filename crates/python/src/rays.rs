//! Ray queries for numpy (SPEC §9): closest hits and occlusion of N rays given as (N, 3)
//! float32 or float64 arrays in any memory order, answered by the frame's BVH on all threads
//! (or `threads=`) without the GIL; the answers are arrays that own the library's vectors (no
//! copy). `camera_rays` gives the thin-lens rays `aperture bench-rays` times.

use crate::errors::value_error;
use aperture_accel::{Accel, Hit, Ray};
use aperture_scene::Scene;
use glam::Vec3;
use numpy::ndarray::{Array1, Array2, ArrayView2};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Rows of an (N, 3) array view as vectors, each checked by `ok`.
fn rows_of<T: Copy + Into<f64>>(
    view: ArrayView2<'_, T>,
    name: &str,
    ok: fn(Vec3) -> bool,
) -> PyResult<Vec<Vec3>> {
    let to = |r: [T; 3]| Vec3::new(r[0].into() as f32, r[1].into() as f32, r[2].into() as f32);
    let out: Vec<Vec3> = match view.as_slice() {
        Some(flat) => flat
            .chunks_exact(3)
            .map(|c| to([c[0], c[1], c[2]]))
            .collect(),
        None => view
            .rows()
            .into_iter()
            .map(|r| to([r[0], r[1], r[2]]))
            .collect(),
    };
    match out.iter().position(|v| !ok(*v)) {
        None => Ok(out),
        Some(i) => Err(value_error(format!(
            "{name}[{i}] = {} is not allowed: {name} must be finite{}",
            out[i],
            if name == "directions" {
                " and not zero"
            } else {
                ""
            }
        ))),
    }
}

/// An (N, 3) float32 or float64 array (a list is turned into one) as N vectors.
fn vectors(v: &Bound<'_, PyAny>, name: &str, ok: fn(Vec3) -> bool) -> PyResult<Vec<Vec3>> {
    let array = match v.cast::<PyUntypedArray>() {
        Ok(a) => a.clone(),
        Err(_) => {
            let np = v.py().import("numpy")?;
            let a = np.call_method1("asarray", (v, "float64")).map_err(|e| {
                value_error(format!("{name} must be an (N, 3) array of numbers: {e}"))
            })?;
            a.cast_into::<PyUntypedArray>()?
        }
    };
    if array.ndim() != 2 || array.shape()[1] != 3 {
        return Err(value_error(format!(
            "{name} must have shape (N, 3), got {:?}",
            array.shape()
        )));
    }
    if let Ok(a) = array.cast::<PyArray2<f32>>() {
        return rows_of(a.readonly().as_array(), name, ok);
    }
    if let Ok(a) = array.cast::<PyArray2<f64>>() {
        return rows_of(a.readonly().as_array(), name, ok);
    }
    Err(value_error(format!(
        "{name} must be float32 or float64, got {}",
        array.dtype()
    )))
}

/// A ray bound: one number for every ray, or an (N,) array of them.
fn bounds(v: &Bound<'_, PyAny>, name: &str, n: usize) -> PyResult<Vec<f32>> {
    let all: Vec<f64> = match v.extract::<f64>() {
        Ok(x) => vec![x; n],
        Err(_) => v.extract().map_err(|_| {
            value_error(format!(
                "{name} must be a number or an (N,) array of numbers"
            ))
        })?,
    };
    if all.len() != n {
        return Err(value_error(format!(
            "{name} has {} values for {n} rays",
            all.len()
        )));
    }
    match all.iter().position(|x| x.is_nan() || *x < 0.0) {
        None => Ok(all.into_iter().map(|x| x as f32).collect()),
        Some(i) => Err(value_error(format!(
            "{name}[{i}] = {} is not allowed: must be ≥ 0 (inf allowed)",
            all[i]
        ))),
    }
}

/// The rays of the arrays, checked: finite origins, finite non-zero directions, 0 ≤ tmin ≤ tmax.
pub(crate) fn rays(
    origins: &Bound<'_, PyAny>,
    directions: &Bound<'_, PyAny>,
    tmin: &Bound<'_, PyAny>,
    tmax: &Bound<'_, PyAny>,
) -> PyResult<Vec<Ray>> {
    let o = vectors(origins, "origins", |v| v.is_finite())?;
    let d = vectors(directions, "directions", |v| {
        v.is_finite() && v != Vec3::ZERO
    })?;
    if o.len() != d.len() {
        return Err(value_error(format!(
            "{} origins for {} directions",
            o.len(),
            d.len()
        )));
    }
    let lo = bounds(tmin, "tmin", o.len())?;
    let hi = bounds(tmax, "tmax", o.len())?;
    if let Some(i) = (0..o.len()).find(|&i| lo[i] > hi[i] || lo[i].is_infinite()) {
        return Err(value_error(format!(
            "ray {i}: tmin {} must be finite and at most tmax {}",
            lo[i], hi[i]
        )));
    }
    Ok((0..o.len())
        .map(|i| Ray {
            origin: o[i],
            dir: d[i],
            tmin: lo[i],
            tmax: hi[i],
            time: 0.0,
        })
        .collect())
}

/// Closest hits as columns: what `intersect` returns.
pub(crate) struct Hits {
    t: Vec<f32>,
    primitive: Vec<i32>,
    instance: Vec<i32>,
    mesh: Vec<i32>,
    u: Vec<f32>,
    v: Vec<f32>,
    normal: Vec<f32>,
    hit: Vec<bool>,
}

/// The world-space geometric normal of a hit (unit length; `(p1 - p0) × (p2 - p0)`).
fn normal(scene: &Scene, h: &Hit) -> Vec3 {
    let Some(inst) = scene.instances.get(h.instance as usize) else {
        return Vec3::ZERO;
    };
    let Some(mesh) = scene.meshes.get(inst.mesh as usize) else {
        return Vec3::ZERO;
    };
    let Some(tri) = mesh.indices.get(h.triangle as usize) else {
        return Vec3::ZERO;
    };
    let p = tri.map(|k| {
        let local = mesh
            .positions
            .get(k as usize)
            .copied()
            .unwrap_or(Vec3::ZERO);
        inst.world_from_object.transform_point3(local)
    });
    (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
}

/// The closest hits of `rays` (on the current rayon pool) as columns.
pub(crate) fn intersect(scene: &Scene, accel: &Accel, rays: &[Ray]) -> Hits {
    let mut found = vec![None; rays.len()];
    // Packets of coherent runs (a pixel's lens samples), incoherent runs interleaved as in the
    // batch query: the same answers as one ray at a time, the fastest of bench-rays' modes.
    aperture_raybench::closest_hits(accel, rays, aperture_raybench::Mode::Packet, &mut found);
    let n = rays.len();
    let mut h = Hits {
        t: vec![f32::INFINITY; n],
        primitive: vec![-1; n],
        instance: vec![-1; n],
        mesh: vec![-1; n],
        u: vec![0.0; n],
        v: vec![0.0; n],
        normal: vec![0.0; 3 * n],
        hit: vec![false; n],
    };
    for (i, hit) in found.iter().enumerate() {
        let Some(x) = hit else { continue };
        h.t[i] = x.t;
        h.primitive[i] = x.triangle as i32;
        h.instance[i] = x.instance as i32;
        h.mesh[i] = scene
            .instances
            .get(x.instance as usize)
            .map_or(-1, |inst| inst.mesh as i32);
        h.u[i] = x.u;
        h.v[i] = x.v;
        h.normal[3 * i..3 * i + 3].copy_from_slice(&normal(scene, x).to_array());
        h.hit[i] = true;
    }
    h
}

impl Hits {
    /// The columns as a dict of numpy arrays that own them.
    pub fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        let n = self.t.len();
        d.set_item("t", self.t.into_pyarray(py))?;
        d.set_item("primitive", self.primitive.into_pyarray(py))?;
        d.set_item("instance", self.instance.into_pyarray(py))?;
        d.set_item("mesh", self.mesh.into_pyarray(py))?;
        d.set_item("u", self.u.into_pyarray(py))?;
        d.set_item("v", self.v.into_pyarray(py))?;
        let normal =
            Array2::from_shape_vec((n, 3), self.normal).map_err(|e| value_error(e.to_string()))?;
        d.set_item("normal", normal.into_pyarray(py))?;
        d.set_item("hit", self.hit.into_pyarray(py))?;
        Ok(d)
    }
}

/// Whether each of `rays` is blocked (on the current rayon pool).
pub(crate) fn occluded(accel: &Accel, rays: &[Ray]) -> Vec<bool> {
    let mut out = vec![false; rays.len()];
    aperture_raybench::occlusions(accel, rays, aperture_raybench::Mode::Packet, &mut out);
    out
}

/// Thin-lens primary rays as `bench-rays` makes them (its `primary_tile` set).
pub(crate) struct CameraRays {
    pub origins: Vec<f32>,
    pub directions: Vec<f32>,
    pub pixels: Vec<u32>,
    pub samples: Vec<u32>,
}

/// The rays of `camera`'s image of `width`×`height` pixels, `lens_samples` per pixel.
pub(crate) fn camera_rays(
    camera: &aperture_render::Camera,
    lens_samples: u32,
    seed: u32,
) -> CameraRays {
    let opts = aperture_raybench::RaySetOptions { lens_samples, seed };
    let samples = aperture_raybench::primary_samples(camera, &opts);
    let mut out = CameraRays {
        origins: Vec::with_capacity(samples.len() * 3),
        directions: Vec::with_capacity(samples.len() * 3),
        pixels: Vec::with_capacity(samples.len() * 2),
        samples: Vec::with_capacity(samples.len()),
    };
    for s in &samples {
        let Some(ray) = aperture_raybench::primary_ray(camera, s) else {
            continue;
        };
        out.origins.extend_from_slice(&ray.origin.to_array());
        out.directions.extend_from_slice(&ray.dir.to_array());
        out.pixels.extend_from_slice(&[s.x, s.y]);
        out.samples.push(s.index);
    }
    out
}

impl CameraRays {
    /// As a dict: `origins`, `directions` (N, 3) float32, `pixels` (N, 2) and `samples` (N,)
    /// uint32.
    pub fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let n = self.samples.len();
        let shape = |v: Vec<f32>| Array2::from_shape_vec((n, 3), v);
        let bad = |e: numpy::ndarray::ShapeError| value_error(e.to_string());
        let d = PyDict::new(py);
        d.set_item(
            "origins",
            shape(self.origins).map_err(bad)?.into_pyarray(py),
        )?;
        d.set_item(
            "directions",
            shape(self.directions).map_err(bad)?.into_pyarray(py),
        )?;
        let pixels = Array2::from_shape_vec((n, 2), self.pixels).map_err(bad)?;
        d.set_item("pixels", pixels.into_pyarray(py))?;
        d.set_item("samples", Array1::from_vec(self.samples).into_pyarray(py))?;
        Ok(d)
    }
}

/// `camera_rays`: the camera `camera` selects (as `render(camera=)`; the first by default) at
/// `width`×`height` (the height from the camera's aspect by default), checked against the
/// machine's memory as `bench-rays` checks it.
pub(crate) fn camera_rays_of(
    s: &Scene,
    camera: Option<&crate::edits::Target>,
    (width, height): (u32, Option<u32>),
    lens_samples: u32,
    seed: u32,
) -> PyResult<CameraRays> {
    let index = match camera {
        None => 0,
        Some(t) => {
            let c = match t {
                crate::edits::Target::Index(i) => i.to_string(),
                crate::edits::Target::Name(n) => n.clone(),
            };
            s.select_camera(&c)
                .map_err(|e| value_error(format!("invalid camera {c:?}: {e}")))?
        }
    };
    let cam = s
        .cameras
        .get(index)
        .ok_or_else(|| value_error("the scene has no camera"))?;
    let bad =
        |name: &str, n: u32| value_error(format!("invalid {name} = {n}: must be in 1..=16384"));
    if !(1..=16384).contains(&width) {
        return Err(bad("width", width));
    }
    let height = height.unwrap_or_else(|| aperture_render::default_height(cam, width));
    if !(1..=16384).contains(&height) {
        return Err(bad("height", height));
    }
    if lens_samples == 0 {
        return Err(value_error("lens_samples must be ≥ 1"));
    }
    let camera = aperture_render::Camera::new(cam, width, height);
    let opts = aperture_raybench::RaySetOptions { lens_samples, seed };
    let bytes = aperture_raybench::estimated_bytes(&camera, &opts);
    aperture_budget::MemoryBudget::from_system()
        .check("the camera rays", bytes)
        .map_err(|e| pyo3::exceptions::PyMemoryError::new_err(e.to_string()))?;
    Ok(camera_rays(&camera, lens_samples, seed))
}

/// The posed scene's triangles in world space, one copy per instance (what another ray
/// library is given to answer the same queries), with each triangle's `instance` and
/// `primitive` as `intersect` names them.
pub(crate) struct Soup {
    vertices: Vec<f32>,
    instance: Vec<i32>,
    primitive: Vec<i32>,
}

/// The triangles of `s`.
pub(crate) fn triangles(s: &Scene) -> Soup {
    let mut soup = Soup {
        vertices: Vec::new(),
        instance: Vec::new(),
        primitive: Vec::new(),
    };
    for (k, inst) in s.instances.iter().enumerate() {
        let Some(mesh) = s.meshes.get(inst.mesh as usize) else {
            continue;
        };
        for (t, tri) in mesh.indices.iter().enumerate() {
            for &v in tri {
                let p = mesh.positions.get(v as usize).copied().unwrap_or(Vec3::NAN);
                let w = inst.world_from_object.transform_point3(p);
                soup.vertices.extend_from_slice(&w.to_array());
            }
            soup.instance.push(k as i32);
            soup.primitive.push(t as i32);
        }
    }
    soup
}

impl Soup {
    /// `vertices` (3T, 3) float32, `indices` (T, 3) uint32, `instance`, `primitive` (T,).
    pub fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let n = self.instance.len();
        let indices: Vec<u32> = (0..3 * n as u32).collect();
        let bad = |e: numpy::ndarray::ShapeError| value_error(e.to_string());
        let d = PyDict::new(py);
        let vertices = Array2::from_shape_vec((3 * n, 3), self.vertices).map_err(bad)?;
        d.set_item("vertices", vertices.into_pyarray(py))?;
        let indices = Array2::from_shape_vec((n, 3), indices).map_err(bad)?;
        d.set_item("indices", indices.into_pyarray(py))?;
        d.set_item("instance", self.instance.into_pyarray(py))?;
        d.set_item("primitive", self.primitive.into_pyarray(py))?;
        Ok(d)
    }
}

/// An occlusion answer as a numpy bool array.
pub(crate) fn bool_array(py: Python<'_>, v: Vec<bool>) -> Bound<'_, PyArray1<bool>> {
    v.into_pyarray(py)
}
