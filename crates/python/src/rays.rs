//! Ray queries for numpy (SPEC §9): closest hits and occlusion of N rays given as (N, 3)
//! float32 or float64 arrays in any memory order, read in place and answered by the frame's
//! BVH on all threads (or `threads=`) without the GIL ([`crate::ray_input`]); the answers are
//! columns allocated once, filled by the workers and handed to numpy without a copy. `camera_rays` gives the thin-lens rays `aperture bench-rays` times.

use crate::errors::value_error;
use crate::ray_input::{each_batch, RaySource, BATCH, TASK};
use aperture_accel::{Accel, Hit};
use aperture_scene::Scene;
use glam::{Affine3A, Vec3};
use numpy::ndarray::{Array1, Array2};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::mem::MaybeUninit;

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

/// One task's slices of the columns, not yet written.
struct HitSlices<'a> {
    t: &'a mut [MaybeUninit<f32>],
    primitive: &'a mut [MaybeUninit<i32>],
    instance: &'a mut [MaybeUninit<i32>],
    mesh: &'a mut [MaybeUninit<i32>],
    u: &'a mut [MaybeUninit<f32>],
    v: &'a mut [MaybeUninit<f32>],
    normal: &'a mut [MaybeUninit<f32>],
    hit: &'a mut [MaybeUninit<bool>],
}

impl Hits {
    /// Empty columns with room for `n` rays (allocated once; nothing is written here: the
    /// workers write every element, so no pass of zeros either).
    fn with_capacity(n: usize) -> Self {
        Self {
            t: Vec::with_capacity(n),
            primitive: Vec::with_capacity(n),
            instance: Vec::with_capacity(n),
            mesh: Vec::with_capacity(n),
            u: Vec::with_capacity(n),
            v: Vec::with_capacity(n),
            normal: Vec::with_capacity(3 * n),
            hit: Vec::with_capacity(n),
        }
    }

    /// The columns' room for `n` rays cut into the slices of consecutive tasks of `TASK` rays.
    fn tasks(&mut self, n: usize) -> Vec<HitSlices<'_>> {
        let m = TASK;
        self.t.spare_capacity_mut()[..n]
            .chunks_mut(m)
            .zip(self.primitive.spare_capacity_mut()[..n].chunks_mut(m))
            .zip(self.instance.spare_capacity_mut()[..n].chunks_mut(m))
            .zip(self.mesh.spare_capacity_mut()[..n].chunks_mut(m))
            .zip(self.u.spare_capacity_mut()[..n].chunks_mut(m))
            .zip(self.v.spare_capacity_mut()[..n].chunks_mut(m))
            .zip(self.normal.spare_capacity_mut()[..3 * n].chunks_mut(3 * m))
            .zip(self.hit.spare_capacity_mut()[..n].chunks_mut(m))
            .map(
                |(((((((t, primitive), instance), mesh), u), v), normal), hit)| HitSlices {
                    t,
                    primitive,
                    instance,
                    mesh,
                    u,
                    v,
                    normal,
                    hit,
                },
            )
            .collect()
    }

    /// The columns once every element of the first `n` rays has been written.
    ///
    /// # Safety
    /// Elements `..n` of every column (`..3 * n` of `normal`) must have been written.
    unsafe fn written(mut self, n: usize) -> Self {
        // SAFETY: the caller's promise; the capacities are `n` and `3 * n`.
        unsafe {
            self.t.set_len(n);
            self.primitive.set_len(n);
            self.instance.set_len(n);
            self.mesh.set_len(n);
            self.u.set_len(n);
            self.v.set_len(n);
            self.normal.set_len(3 * n);
            self.hit.set_len(n);
        }
        self
    }
}

/// What a hit's columns need of its instance: its mesh's index, triangles and vertices, and
/// where it is.
struct Placed<'a> {
    mesh: i32,
    indices: &'a [[u32; 3]],
    positions: &'a [Vec3],
    world_from_object: Affine3A,
}

impl Placed<'_> {
    /// The world-space geometric normal of `triangle` (unit length; `(p1 - p0) × (p2 - p0)`).
    #[inline(always)]
    fn normal(&self, triangle: u32) -> Vec3 {
        let Some(tri) = self.indices.get(triangle as usize) else {
            return Vec3::ZERO;
        };
        let p = tri.map(|k| {
            let local = self
                .positions
                .get(k as usize)
                .copied()
                .unwrap_or(Vec3::ZERO);
            self.world_from_object.transform_point3(local)
        });
        (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
    }
}

/// Every instance of `scene` as [`Placed`] (`None` when its mesh is missing).
fn placed(scene: &Scene) -> Vec<Option<Placed<'_>>> {
    scene
        .instances
        .iter()
        .map(|inst| {
            let mesh = scene.meshes.get(inst.mesh as usize)?;
            Some(Placed {
                mesh: inst.mesh as i32,
                indices: &mesh.indices,
                positions: &mesh.positions,
                world_from_object: inst.world_from_object,
            })
        })
        .collect()
}

/// Writes the answers `found` of rays `at..` of a task into its columns: every element of
/// those rays.
#[inline(always)]
fn write_hits(places: &[Option<Placed<'_>>], found: &[Option<Hit>], at: usize, h: &mut HitSlices) {
    for (k, f) in found.iter().enumerate() {
        let i = at + k;
        let (t, primitive, instance, u, v, hit) = match f {
            Some(x) => (x.t, x.triangle as i32, x.instance as i32, x.u, x.v, true),
            None => (f32::INFINITY, -1, -1, 0.0, 0.0, false),
        };
        let (mesh, normal) = match f.map(|x| (x, places.get(x.instance as usize))) {
            Some((x, Some(Some(p)))) => (p.mesh, p.normal(x.triangle)),
            _ => (-1, Vec3::ZERO),
        };
        h.t[i].write(t);
        h.primitive[i].write(primitive);
        h.instance[i].write(instance);
        h.mesh[i].write(mesh);
        h.u[i].write(u);
        h.v[i].write(v);
        h.hit[i].write(hit);
        for (slot, c) in h.normal[3 * i..3 * i + 3].iter_mut().zip(normal.to_array()) {
            slot.write(c);
        }
    }
}

/// The closest hits of `src`'s rays as columns, read, checked and answered batch by batch (on
/// the caller's thread when `serial`, else on the current rayon pool), or the flag of a ray
/// not allowed (`None`). Packets of coherent runs (a pixel's lens samples), incoherent runs interleaved
/// as in the batch query: the same answers as one ray at a time, the fastest of bench-rays'
/// modes.
pub(crate) fn intersect(
    scene: &Scene,
    accel: &Accel,
    src: &RaySource<'_>,
    serial: bool,
) -> Option<Hits> {
    let places = placed(scene);
    let mut hits = Hits::with_capacity(src.n);
    let allowed = each_batch(src, hits.tasks(src.n), serial, |rays, at, out| {
        let mut found = [None; BATCH];
        let found = &mut found[..rays.len()];
        accel.intersect_packets(rays, found);
        write_hits(&places, found, at, out);
    });
    // SAFETY: `each_batch` answered every batch of every task (it would have returned false
    // otherwise), the tasks cover rays `..n` and `write_hits` writes every element of the rays
    // it is given.
    allowed.then(|| unsafe { hits.written(src.n) })
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

/// Whether each of `src`'s rays is blocked, as [`intersect`] answers.
pub(crate) fn occluded(accel: &Accel, src: &RaySource<'_>, serial: bool) -> Option<Vec<bool>> {
    let mut out = vec![false; src.n];
    let tasks: Vec<&mut [bool]> = out.chunks_mut(TASK).collect();
    let allowed = each_batch(src, tasks, serial, |rays, at, task| {
        accel.occluded_packets(rays, &mut task[at..at + rays.len()]);
    });
    allowed.then_some(out)
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
