//! A rendered image in Python: the film as the EXR would hold it ([`aperture_output::film_to_image`]:
//! the beauty `R,G,B,A` linear and premultiplied, each pass a layer under its EXR name, the
//! header), handed to numpy without copying the pixels.

use aperture_imageio::{Image, MetaValue};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray3, PyArrayMethods};
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// The result of `scene.render()` or `render.result()`: unpacks as `image, passes = ...`.
///
/// `image` is a float32 H×W×4 array (linear, premultiplied `R,G,B,A`), `passes` a dict of
/// float32 H×W×C arrays named as the EXR's layers (`"Depth"`, `"Denoising Albedo"`, …);
/// `channels` names each pass's channels, `header` is the EXR header, `samples` the samples
/// taken. `aperture.write(path, result)` writes it as the command line would.
#[pyclass(module = "aperture", frozen)]
pub struct RenderResult {
    #[pyo3(get)]
    image: Py<PyArray3<f32>>,
    #[pyo3(get)]
    passes: Py<PyDict>,
    #[pyo3(get)]
    channels: Py<PyDict>,
    #[pyo3(get)]
    header: Py<PyDict>,
    #[pyo3(get)]
    samples: u64,
    /// The image as the library writes it, pixels taken out (they live in the arrays).
    shell: Image,
    /// The names of the arrays' layers, in the file's order.
    layer_names: Vec<String>,
}

impl RenderResult {
    /// The image's pixels moved into numpy arrays (no copy), the rest kept for writing.
    pub(crate) fn new(py: Python<'_>, mut image: Image, samples: u64) -> PyResult<Self> {
        let (w, h) = (image.width as usize, image.height as usize);
        let rgba = std::mem::take(&mut image.rgba);
        let flat: Vec<f32> = rgba.into_iter().flatten().collect();
        let beauty = Array3::from_shape_vec((h, w, 4), flat)
            .map_err(|e| crate::errors::RenderError::new_err(e.to_string()))?;
        let passes = PyDict::new(py);
        let channels = PyDict::new(py);
        let mut layer_names = Vec::new();
        for layer in &mut image.layers {
            let c = layer.channels.len();
            let data = std::mem::take(&mut layer.data);
            let array = Array3::from_shape_vec((h, w, c), data)
                .map_err(|e| crate::errors::RenderError::new_err(e.to_string()))?;
            passes.set_item(&layer.name, array.into_pyarray(py))?;
            channels.set_item(&layer.name, PyList::new(py, &layer.channels)?)?;
            layer_names.push(layer.name.clone());
        }
        let header = header_dict(py, &image)?;
        Ok(Self {
            image: beauty.into_pyarray(py).unbind(),
            passes: passes.unbind(),
            channels: channels.unbind(),
            header: header.unbind(),
            samples,
            shell: image,
            layer_names,
        })
    }

    /// The whole image again, its pixels read back from the arrays (as they are now).
    pub(crate) fn to_image(&self, py: Python<'_>) -> PyResult<Image> {
        let mut image = self.shell.clone();
        let beauty = self.image.bind(py).readonly();
        let view = beauty.as_array();
        image.rgba = view
            .rows()
            .into_iter()
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect();
        let passes = self.passes.bind(py);
        for (layer, name) in image.layers.iter_mut().zip(&self.layer_names) {
            let item = passes
                .get_item(name)?
                .ok_or_else(|| crate::errors::value_error(format!("pass {name:?} was removed")))?;
            let array = item.cast::<PyArray3<f32>>()?.readonly();
            layer.data = array.as_array().iter().copied().collect();
        }
        Ok(image)
    }
}

#[pymethods]
impl RenderResult {
    fn __len__(&self) -> usize {
        2
    }

    fn __getitem__(&self, py: Python<'_>, i: isize) -> PyResult<Py<PyAny>> {
        match i {
            0 | -2 => Ok(self.image.clone_ref(py).into_any()),
            1 | -1 => Ok(self.passes.clone_ref(py).into_any()),
            _ => Err(PyIndexError::new_err("a render unpacks as (image, passes)")),
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "<aperture.RenderResult {}x{}, passes {:?}, {} samples>",
            self.shell.width, self.shell.height, self.layer_names, self.samples
        )
    }
}

/// The header as a dict of Python values.
fn header_dict<'py>(py: Python<'py>, image: &Image) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (key, value) in &image.metadata {
        match value {
            MetaValue::Int(n) => d.set_item(key, n)?,
            MetaValue::Float(x) => d.set_item(key, x)?,
            MetaValue::Text(s) => d.set_item(key, s)?,
            // EXR's m44f: row-major, the translation in the last row (Imath's convention).
            MetaValue::Matrix(m) => {
                let rows = Array2::from_shape_fn((4, 4), |(r, c)| m[r * 4 + c]);
                d.set_item(key, rows.into_pyarray(py))?
            }
            MetaValue::Chromaticities(c) => d.set_item(key, c.to_vec())?,
        }
    }
    Ok(d)
}
