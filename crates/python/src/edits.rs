//! The scene's edits (SPEC §9) as the library takes them ([`Edit`]): a node's matrix or
//! visibility, a camera's depth-of-field keys, and material and light factors through
//! `KHR_animation_pointer` paths. Each leaves the session as if the file had stored the value.

use crate::errors::value_error;
use aperture_scene::{Edit, Scene};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};
use serde_json::Value;

/// A node, material or camera named by index or by name, resolved against the posed scene.
#[derive(Debug, Clone)]
pub(crate) enum Target {
    Index(usize),
    Name(String),
}

impl Target {
    /// An `int` index or a `str` name.
    pub fn extract(v: &Bound<'_, PyAny>, what: &str) -> PyResult<Self> {
        if v.is_instance_of::<PyString>() {
            return Ok(Self::Name(v.extract()?));
        }
        if !v.is_instance_of::<PyBool>() {
            if let Ok(i) = v.extract::<i64>() {
                return usize::try_from(i)
                    .map(Self::Index)
                    .map_err(|_| value_error(format!("invalid {what} {i}: an index is ≥ 0")));
            }
        }
        Err(PyTypeError::new_err(format!(
            "{what} must be an index (int) or a name (str), got {v}"
        )))
    }

    /// The index among `names` (a name must be there; an index is checked by the library).
    fn resolve<'a>(
        &self,
        what: &str,
        mut names: impl Iterator<Item = Option<&'a str>>,
    ) -> PyResult<usize> {
        match self {
            Self::Index(i) => Ok(*i),
            Self::Name(n) => names
                .position(|m| m == Some(n.as_str()))
                .ok_or_else(|| value_error(format!("no {what} is named {n:?}"))),
        }
    }
}

/// A 4×4 matrix as math writes it (rows of columns, `M @ p`, the translation in the last
/// column; what numpy shows), as glTF stores it: column-major.
pub(crate) fn matrix(v: &Bound<'_, PyAny>) -> PyResult<[[f32; 4]; 4]> {
    let rows: Vec<Vec<f64>> = v
        .extract()
        .map_err(|_| value_error("matrix must be 4×4 numbers"))?;
    if rows.len() != 4 || rows.iter().any(|r| r.len() != 4) {
        return Err(value_error("matrix must be 4×4 numbers"));
    }
    if rows.iter().flatten().any(|x| !x.is_finite()) {
        return Err(value_error("matrix must be finite"));
    }
    Ok(std::array::from_fn(|c| {
        std::array::from_fn(|r| rows[r][c] as f32)
    }))
}

/// What `set_transform` replaces: the whole matrix, or TRS components (name, values).
pub(crate) enum NewTransform {
    Matrix([[f32; 4]; 4]),
    Components(Vec<(&'static str, Vec<f64>)>),
}

/// `set_transform`'s arguments checked: a matrix or TRS components, not both, not neither;
/// 3 numbers for translation and scale, 4 for rotation.
pub(crate) fn transform_of(
    matrix: Option<&Bound<'_, PyAny>>,
    trs: [(&'static str, Option<&Bound<'_, PyAny>>); 3],
) -> PyResult<NewTransform> {
    let mut parts = Vec::new();
    for (name, v) in trs {
        if let Some(v) = v {
            let values = numbers(name, v)?;
            let want = if name == "rotation" { 4 } else { 3 };
            if values.len() != want {
                return Err(value_error(format!("{name} must be {want} numbers")));
            }
            parts.push((name, values));
        }
    }
    match (matrix, parts.is_empty()) {
        (Some(m), true) => Ok(NewTransform::Matrix(self::matrix(m)?)),
        (None, false) => Ok(NewTransform::Components(parts)),
        (Some(_), false) => Err(value_error(
            "give a matrix or translation/rotation/scale, not both",
        )),
        (None, true) => Err(value_error("give a matrix or translation/rotation/scale")),
    }
}

/// `set_transform(node, …)`.
pub(crate) fn transform(s: &Scene, node: &Target, how: &NewTransform) -> PyResult<Vec<Edit>> {
    let node = node.resolve("node", s.node_names.iter().map(|n| n.as_deref()))?;
    Ok(match how {
        NewTransform::Matrix(m) => vec![Edit::NodeMatrix { node, matrix: *m }],
        NewTransform::Components(parts) => parts
            .iter()
            .map(|(name, values)| Edit::Pointer {
                path: format!("/nodes/{node}/{name}"),
                value: values.clone(),
            })
            .collect(),
    })
}

/// `set_visible(node, visible)`.
pub(crate) fn visible(s: &Scene, node: &Target, visible: bool) -> PyResult<Vec<Edit>> {
    let node = node.resolve("node", s.node_names.iter().map(|n| n.as_deref()))?;
    Ok(vec![Edit::NodeVisible { node, visible }])
}

/// Numbers of one pointer value: a number or a sequence of them, all finite.
fn numbers(name: &str, v: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let list: Vec<f64> = match v.extract::<f64>() {
        Ok(x) => vec![x],
        Err(_) => v
            .extract()
            .map_err(|_| value_error(format!("{name} must be a number or a list of numbers")))?,
    };
    if list.iter().any(|x| !x.is_finite()) {
        return Err(value_error(format!("{name} must be finite")));
    }
    Ok(list)
}

/// `set_material(material, **factors)`: the glTF property of each factor.
const MATERIAL: &[(&str, &str)] = &[
    ("base_color", "pbrMetallicRoughness/baseColorFactor"),
    ("metallic", "pbrMetallicRoughness/metallicFactor"),
    ("roughness", "pbrMetallicRoughness/roughnessFactor"),
    ("emissive", "emissiveFactor"),
    (
        "emissive_strength",
        "extensions/KHR_materials_emissive_strength/emissiveStrength",
    ),
    ("alpha_cutoff", "alphaCutoff"),
    ("normal_scale", "normalTexture/scale"),
    ("occlusion_strength", "occlusionTexture/strength"),
    ("ior", "extensions/KHR_materials_ior/ior"),
    (
        "specular",
        "extensions/KHR_materials_specular/specularFactor",
    ),
    (
        "specular_color",
        "extensions/KHR_materials_specular/specularColorFactor",
    ),
];

/// `set_light(light, **values)`: the glTF property of each value.
const LIGHT: &[(&str, &str)] = &[
    ("color", "color"),
    ("intensity", "intensity"),
    ("range", "range"),
    ("inner_cone_angle", "spot/innerConeAngle"),
    ("outer_cone_angle", "spot/outerConeAngle"),
];

/// Pointer edits `prefix/<property>` of `values`, named as `table` says.
pub(crate) fn pointers(
    prefix: &str,
    table: &[(&str, &str)],
    values: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<Edit>> {
    let mut edits = Vec::new();
    for (k, v) in values.into_iter().flat_map(|d| d.iter()) {
        let key: String = k.extract()?;
        let Some((_, prop)) = table.iter().find(|(n, _)| *n == key) else {
            let known: Vec<&str> = table.iter().map(|(n, _)| *n).collect();
            return Err(PyTypeError::new_err(format!(
                "unknown value {key:?} (known: {})",
                known.join(", ")
            )));
        };
        edits.push(Edit::Pointer {
            path: format!("{prefix}/{prop}"),
            value: numbers(&key, &v)?,
        });
    }
    Ok(edits)
}

/// `set_material`'s edits of material `i`.
pub(crate) fn material(i: usize, f: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<Edit>> {
    pointers(&format!("/materials/{i}"), MATERIAL, f)
}

/// `set_light`'s edits of `KHR_lights_punctual` light `i`.
pub(crate) fn light(i: usize, values: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<Edit>> {
    pointers(
        &format!("/extensions/KHR_lights_punctual/lights/{i}"),
        LIGHT,
        values,
    )
}

/// `set_camera`'s short names of SPEC §3's keys (the keys themselves are taken too).
const CAMERA_KEYS: &[(&str, &str)] = &[
    ("fstop", "aperture_fstop"),
    ("blades", "aperture_blades"),
    ("rotation", "aperture_rotation"),
    ("ratio", "aperture_ratio"),
    ("aperture_radius", "aperture_radius"),
    ("focus_distance", "focus_distance"),
    ("focus_object", "focus_object"),
    ("lens", "lens"),
    ("sensor_width", "sensor_width"),
    ("sensor_height", "sensor_height"),
    ("sensor_fit", "sensor_fit"),
    ("use_dof", "use_dof"),
    ("aperture_fstop", "aperture_fstop"),
    ("aperture_blades", "aperture_blades"),
    ("aperture_rotation", "aperture_rotation"),
    ("aperture_ratio", "aperture_ratio"),
    // Issue 61's lens options (docs/lenses.md), under their extras names only.
    ("aperture_vignetting", "aperture_vignetting"),
    ("distortion_k1", "distortion_k1"),
    ("distortion_k2", "distortion_k2"),
    ("distortion_k3", "distortion_k3"),
    ("distortion_p1", "distortion_p1"),
    ("distortion_p2", "distortion_p2"),
    ("chromatic_lateral", "chromatic_lateral"),
    ("chromatic_longitudinal", "chromatic_longitudinal"),
    // A bokeh image (a path relative to the glTF file's folder, or a texture index), read by
    // the edit; a lens prescription (a lens file's path there, or rows of 4 numbers).
    ("aperture_image", "aperture_image"),
    ("lens_prescription", "lens_prescription"),
];

/// A camera key's value as JSON: a bool, a finite number, a string, rows of finite numbers
/// (a list of lists: a lens prescription's), or `None` (removes it).
fn json_value(key: &str, v: &Bound<'_, PyAny>) -> PyResult<Value> {
    if v.is_none() {
        return Ok(Value::Null);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(v.extract()?));
    }
    if let Ok(i) = v.extract::<i64>() {
        return Ok(Value::from(i));
    }
    let bad = || {
        value_error(format!(
            "invalid {key} = {v}: a finite number, a bool, a string, a list of lists of finite \
             numbers (rows) or None"
        ))
    };
    if let Ok(x) = v.extract::<f64>() {
        return x.is_finite().then(|| Value::from(x)).ok_or_else(bad);
    }
    let rows: Vec<Vec<f64>> = v.extract().map_err(|_| bad())?;
    if rows.iter().flatten().any(|x| !x.is_finite()) {
        return Err(bad());
    }
    Ok(Value::Array(
        rows.into_iter()
            .map(|r| Value::Array(r.into_iter().map(Value::from).collect()))
            .collect(),
    ))
}

/// The camera keys of `set_camera(**keys)`, as SPEC §3 names them.
pub(crate) fn camera_keys(keys: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, Value)>> {
    let mut out = Vec::new();
    for (k, v) in keys.into_iter().flat_map(|d| d.iter()) {
        let key: String = k.extract()?;
        let Some((_, spec_key)) = CAMERA_KEYS.iter().find(|(n, _)| *n == key) else {
            return Err(PyTypeError::new_err(format!(
                "set_camera() got an unexpected option {key:?}"
            )));
        };
        out.push((spec_key.to_string(), json_value(&key, &v)?));
    }
    Ok(out)
}

/// `set_camera`'s edits: the camera's node matrix and its keys; `camera` selects as
/// `render(camera=)` does (a name, a glTF camera index, `node:J`).
pub(crate) fn camera(
    s: &Scene,
    camera: Option<&str>,
    matrix: Option<[[f32; 4]; 4]>,
    keys: Vec<(String, Value)>,
) -> PyResult<Vec<Edit>> {
    let i = match camera {
        None => 0,
        Some(c) => s
            .select_camera(c)
            .map_err(|e| value_error(format!("invalid camera {c:?}: {e}")))?,
    };
    let cam = s
        .cameras
        .get(i)
        .ok_or_else(|| value_error("the scene has no camera"))?;
    let mut edits = Vec::new();
    if let Some(m) = matrix {
        let node = cam.node.ok_or_else(|| {
            value_error("this camera is aperture's automatic one: it has no node to move")
        })?;
        edits.push(Edit::NodeMatrix {
            node: node as usize,
            matrix: m,
        });
    }
    if !keys.is_empty() {
        let index = cam.index.ok_or_else(|| {
            value_error("this camera is aperture's automatic one: it has no keys")
        })?;
        for (key, value) in keys {
            edits.push(Edit::CameraKey {
                camera: index as usize,
                key,
                value,
            });
        }
    }
    Ok(edits)
}
