//! `aperture.write(path, image_or_render)`: a render result (or a plain numpy image with its
//! passes) written by the library's writer, EXR or PNG by the extension: a render result's EXR
//! has the passes and the header `aperture render` writes; a PNG gets the exposure and view
//! transform, opaque unless `transparent` (as the command line's).

use crate::errors::value_error;
use crate::images::RenderResult;
use aperture_imageio::{Image, Layer, PngOptions, ViewTransform};
use numpy::{PyArray3, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A float32 (H, W, C) array's shape and values (read in C order, whatever its layout).
fn hwc(v: &Bound<'_, PyAny>, name: &str) -> PyResult<(usize, usize, usize, Vec<f32>)> {
    let np = v.py().import("numpy")?;
    let a = np
        .call_method1("asarray", (v, "float32"))
        .map_err(|e| value_error(format!("{name} must be an array of numbers: {e}")))?;
    let a = a.cast_into::<PyUntypedArray>()?;
    let shape = a.shape().to_vec();
    let a = match shape.len() {
        3 => a.cast_into::<PyArray3<f32>>()?,
        2 => np
            .call_method1("expand_dims", (&a, 2))?
            .cast_into::<PyArray3<f32>>()?,
        _ => {
            return Err(value_error(format!(
                "{name} must be H×W or H×W×C, got {shape:?}"
            )))
        }
    };
    let s = a.shape().to_vec();
    let data = a.readonly().as_array().iter().copied().collect();
    Ok((s[0], s[1], s[2], data))
}

/// The channel names of a plain pass of `c` channels.
fn channel_names(c: usize) -> Vec<String> {
    match c {
        1 => vec!["Z".into()],
        2..=4 => ["R", "G", "B", "A"][..c]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        _ => (0..c).map(|i| i.to_string()).collect(),
    }
}

/// A plain image from a numpy beauty (H×W×3 or ×4) and passes (name → H×W×C).
fn plain_image(image: &Bound<'_, PyAny>, passes: Option<&Bound<'_, PyDict>>) -> PyResult<Image> {
    let (h, w, c, data) = hwc(image, "image")?;
    if !(c == 3 || c == 4) || h == 0 || w == 0 || h > 65536 || w > 65536 {
        return Err(value_error(format!(
            "image must be H×W×3 or H×W×4 (at most 65536 a side), got {h}×{w}×{c}"
        )));
    }
    let mut out = Image::new(w as u32, h as u32);
    for (p, px) in out.rgba.iter_mut().enumerate() {
        let v = &data[p * c..p * c + c];
        *px = [v[0], v[1], v[2], if c == 4 { v[3] } else { 1.0 }];
    }
    for (name, array) in passes.into_iter().flat_map(|d| d.iter()) {
        let name: String = name.extract()?;
        let (ph, pw, pc, data) = hwc(&array, &name)?;
        if (ph, pw) != (h, w) {
            return Err(value_error(format!(
                "pass {name:?} is {ph}×{pw}, the image {h}×{w}"
            )));
        }
        let names = channel_names(pc);
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        out.layers.push(Layer::new(&name, &refs, data));
    }
    Ok(out)
}

/// Writes `image` (a render result, or a numpy image with `passes`) to `path`.
#[pyfunction]
#[pyo3(signature = (path, image, passes=None, *, exposure=0.0, view="standard", transparent=false, sixteen_bit=false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn write(
    py: Python<'_>,
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    passes: Option<&Bound<'_, PyDict>>,
    exposure: f64,
    view: &str,
    transparent: bool,
    sixteen_bit: bool,
) -> PyResult<()> {
    let mut out = match image.cast::<RenderResult>() {
        Ok(r) => {
            if passes.is_some() {
                return Err(value_error("a render result carries its own passes"));
            }
            r.get().to_image(py)?
        }
        Err(_) => plain_image(image, passes)?,
    };
    let view = match view.to_ascii_lowercase().as_str() {
        "standard" => ViewTransform::Standard,
        "agx" => ViewTransform::AgX,
        v => return Err(value_error(format!("invalid view {v:?}: standard or agx"))),
    };
    if !exposure.is_finite() {
        return Err(value_error("exposure must be finite"));
    }
    let png = PngOptions {
        exposure: exposure as f32,
        view,
        sixteen_bit,
    };
    let is_png = aperture_imageio::Format::from_path(&path)
        .map_err(|e| value_error(e.to_string()))?
        == aperture_imageio::Format::Png;
    if is_png && !transparent {
        for p in &mut out.rgba {
            p[3] = 1.0;
        }
    }
    py.detach(|| aperture_imageio::write_image(&path, &out, &png))
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))
}
