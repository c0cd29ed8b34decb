//! A mesh's primitives given as numpy arrays (`Scene.set_geometry`, `aperture.load(geometry=)`):
//! per primitive a dict of `positions` (N×3), `triangles` (M×3 vertex indices), and optional
//! `normals` (N×3) and `uvs` (N×2), in any float or integer dtype and memory order (a list
//! works too). They become the library's [`Geometry`], checked there.

use crate::errors::value_error;
use aperture_scene::{Edit, Geometry};
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::sync::Arc;

/// `v` as a C-ordered (rows, `N`) array of `dtype`, each row read as an array.
fn rows<'py, T: numpy::Element + Copy, const N: usize>(
    v: &Bound<'py, PyAny>,
    dtype: &str,
    at: &str,
) -> PyResult<Vec<[T; N]>> {
    let np = v.py().import("numpy")?;
    let a = np
        .call_method1("ascontiguousarray", (v, dtype))
        .map_err(|e| value_error(format!("{at}: not an array of numbers ({e})")))?;
    let a: PyReadonlyArray2<'py, T> = a
        .extract()
        .map_err(|_| value_error(format!("{at}: must be a 2-D array (rows of {N})")))?;
    if a.shape()[1] != N {
        return Err(value_error(format!(
            "{at}: must have {N} columns, has {}",
            a.shape()[1]
        )));
    }
    let flat = a
        .as_slice()
        .map_err(|e| value_error(format!("{at}: {e}")))?;
    Ok(flat
        .chunks_exact(N)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect())
}

/// Triangle indices: an integer array (a float one is refused), each below 2³². uint32 and
/// int32 (what Blender's arrays hold) are read as they are; other widths through int64.
fn triangles(v: &Bound<'_, PyAny>, at: &str) -> PyResult<Vec<[u32; 3]>> {
    let a = v.py().import("numpy")?.call_method1("asarray", (v,))?;
    let dtype = a.getattr("dtype")?;
    let (kind, size): (String, usize) = (
        dtype.getattr("kind")?.extract()?,
        dtype.getattr("itemsize")?.extract()?,
    );
    if kind != "i" && kind != "u" {
        return Err(value_error(format!(
            "{at}: must be integers, got dtype kind {kind:?}"
        )));
    }
    match (kind.as_str(), size) {
        ("u", 4) => rows::<u32, 3>(&a, "uint32", at),
        ("i", 4) => narrowed(rows::<i32, 3>(&a, "int32", at)?, at),
        _ => narrowed(rows::<i64, 3>(&a, "int64", at)?, at),
    }
}

/// `wide` as u32 indices, or the error naming the first that is not one (int32's are
/// narrowed in place: the collect reuses the allocation of a same-sized item).
fn narrowed<T>(wide: Vec<[T; 3]>, at: &str) -> PyResult<Vec<[u32; 3]>>
where
    T: Copy + std::fmt::Display,
    u32: TryFrom<T>,
{
    if let Some(i) = wide.iter().flatten().find(|&&i| u32::try_from(i).is_err()) {
        return Err(value_error(format!(
            "{at}: index {i} is not a vertex index"
        )));
    }
    Ok(wide
        .into_iter()
        .map(|t| t.map(|i| u32::try_from(i).unwrap_or(0)))
        .collect())
}

/// One primitive's dict.
fn primitive(d: &Bound<'_, PyAny>, at: &str) -> PyResult<Geometry> {
    let d = d
        .cast::<PyDict>()
        .map_err(|_| PyTypeError::new_err(format!("{at}: must be a dict of arrays")))?;
    for key in d.keys() {
        let name: String = key.extract()?;
        if !["positions", "triangles", "normals", "uvs"].contains(&name.as_str()) {
            return Err(value_error(format!(
                "{at}: unknown key {name:?} (positions, triangles, normals, uvs)"
            )));
        }
    }
    let need = |k: &str| {
        d.get_item(k)?
            .ok_or_else(|| value_error(format!("{at}: {k} is missing")))
    };
    let positions = rows::<f32, 3>(&need("positions")?, "float32", &format!("{at}.positions"))?;
    let tris = triangles(&need("triangles")?, &format!("{at}.triangles"))?;
    let optional = |k: &str| d.get_item(k).map(|v| v.filter(|v| !v.is_none()));
    let normals = match optional("normals")? {
        Some(v) => Some(rows::<f32, 3>(&v, "float32", &format!("{at}.normals"))?),
        None => None,
    };
    let uvs = match optional("uvs")? {
        Some(v) => Some(rows::<f32, 2>(&v, "float32", &format!("{at}.uvs"))?),
        None => None,
    };
    Geometry::new(positions, tris, normals, uvs).map_err(|e| value_error(format!("{at}.{e}")))
}

/// The edit giving mesh `mesh` the primitives of `list` (a list of dicts, one per primitive).
pub(crate) fn mesh_edit(mesh: usize, list: &Bound<'_, PyAny>) -> PyResult<Edit> {
    let at = format!("meshes[{mesh}]");
    if list.is_instance_of::<PyString>() || list.is_instance_of::<PyDict>() {
        return Err(PyTypeError::new_err(format!(
            "{at}: give a list of primitive dicts"
        )));
    }
    let items: Vec<Bound<'_, PyAny>> = list
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{at}: give a list of primitive dicts")))?
        .collect::<PyResult<_>>()?;
    let primitives = (items.iter().enumerate())
        .map(|(k, p)| primitive(p, &format!("{at}.primitives[{k}]")))
        .collect::<PyResult<Vec<_>>>()?;
    Ok(Edit::MeshGeometry {
        mesh,
        primitives: Arc::from(primitives),
    })
}

/// `load(geometry=...)`: a dict from mesh index to its primitives' list.
pub(crate) fn load_edits(v: &Bound<'_, PyAny>) -> PyResult<Vec<Edit>> {
    let d = v.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err("geometry must be a dict {mesh index: [primitive dicts]}")
    })?;
    let mut edits = Vec::new();
    for (k, list) in d.iter() {
        let mesh = mesh_index(&k)?;
        edits.push(mesh_edit(mesh, &list)?);
    }
    Ok(edits)
}

/// A glTF mesh index (an `int` ≥ 0).
pub(crate) fn mesh_index(v: &Bound<'_, PyAny>) -> PyResult<usize> {
    let i: i64 = v.extract().map_err(|_| {
        PyTypeError::new_err(format!("a mesh is named by its index (int), got {v}"))
    })?;
    usize::try_from(i).map_err(|_| value_error(format!("invalid mesh {i}: an index is ≥ 0")))
}
