//! One source of depth-of-field values (SPEC §3) parsed into a [`Layer`]: Blender's keys in
//! `extras`, the draft `EXT_camera_physical`, or the command line. Each value is checked where it
//! is read, and a bad one is an error naming its source, key and value.

use serde_json::Value;

use crate::error::Error;
use crate::types::{DofOverrides, SensorFit};

/// What an `aperture_image` value names.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) enum ImageRef {
    /// A path relative to the glTF file (a URI as the file's images take).
    Uri(String),
    /// `textures[i]` of the file.
    Texture(usize),
    /// A command-line path (relative to the working directory).
    File(std::path::PathBuf),
}

impl std::fmt::Display for ImageRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Uri(u) => write!(f, "{u:?}"),
            Self::Texture(i) => write!(f, "{i}"),
            Self::File(p) => write!(f, "{:?}", p.display().to_string()),
        }
    }
}

/// The node a `focus_object` names.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum FocusTarget {
    Name(String),
    Index(usize),
}

/// One source's values; `None` = not given by this source.
#[derive(Debug, Clone, Default)]
pub(crate) struct Layer {
    pub use_dof: Option<bool>,
    pub aperture_radius: Option<f32>,
    pub aperture_fstop: Option<f32>,
    pub lens: Option<f32>,
    pub sensor_width: Option<f32>,
    pub sensor_height: Option<f32>,
    pub sensor_fit: Option<SensorFit>,
    pub focus_distance: Option<f32>,
    pub focus_object: Option<FocusTarget>,
    pub blades: Option<u32>,
    pub rotation: Option<f32>,
    pub ratio: Option<f32>,
    /// `aperture_vignetting`.
    pub vignetting: Option<f32>,
    /// `distortion_k1`, `_k2`, `_k3`, `_p1`, `_p2`.
    pub distortion: [Option<f32>; 5],
    /// `lens_prescription`, read and checked.
    pub prescription: Option<super::prescription::Rows>,
    /// `aperture_image`.
    pub aperture_image: Option<ImageRef>,
    /// `chromatic_lateral`, `chromatic_longitudinal`.
    pub chromatic: [Option<f32>; 2],
}

/// The chromatic aberration keys, in the order of [`Layer::chromatic`].
pub(crate) const CHROMATIC_KEYS: [&str; 2] = ["chromatic_lateral", "chromatic_longitudinal"];

/// The distortion keys, in the order of [`Layer::distortion`].
const DISTORTION_KEYS: [&str; 5] = [
    "distortion_k1",
    "distortion_k2",
    "distortion_k3",
    "distortion_p1",
    "distortion_p2",
];

/// Where a source's values come from, for error messages: the camera and the key's prefix.
pub(crate) struct Ctx<'a> {
    pub camera: &'a str,
    pub prefix: &'a str,
    /// The glTF file's folder: where a lens file's path starts.
    pub base_dir: &'a std::path::Path,
}

impl Ctx<'_> {
    /// The error naming this source's `key` and its bad `value`.
    pub fn err(&self, key: &str, value: impl std::fmt::Display, reason: &str) -> Error {
        Error::InvalidDof {
            camera: self.camera.into(),
            key: format!("{}{key}", self.prefix),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// `v` as a finite f32.
    pub fn number(&self, key: &str, v: &Value) -> Result<f32, Error> {
        let x = v
            .as_f64()
            .ok_or_else(|| self.err(key, v, "expected a number"))?;
        let x = x as f32;
        if !x.is_finite() {
            return Err(self.err(key, v, "not a finite 32-bit number"));
        }
        Ok(x)
    }

    /// `v` as a finite f32 > 0.
    pub fn positive(&self, key: &str, v: &Value) -> Result<f32, Error> {
        let x = self.number(key, v)?;
        if x <= 0.0 {
            return Err(self.err(key, v, "must be > 0"));
        }
        Ok(x)
    }

    /// `x` if finite and > 0.
    pub fn check_positive(&self, key: &str, x: f32) -> Result<f32, Error> {
        if !x.is_finite() || x <= 0.0 {
            return Err(self.err(key, x, "must be a finite number > 0"));
        }
        Ok(x)
    }
}

/// Parses Blender's keys from an `extras` object. Unknown keys are ignored; a non-object `extras`
/// carries no depth-of-field keys.
pub(crate) fn parse_extras(extras: Option<&Value>, ctx: &Ctx<'_>) -> Result<Layer, Error> {
    let mut l = Layer::default();
    let Some(map) = extras.and_then(Value::as_object) else {
        return Ok(l);
    };
    for (key, v) in map {
        match key.as_str() {
            "use_dof" => l.use_dof = Some(use_dof(key, v, ctx)?),
            "aperture_radius" => {
                let x = ctx.number(key, v)?;
                if x < 0.0 {
                    return Err(ctx.err(key, v, "must be >= 0"));
                }
                l.aperture_radius = Some(x);
            }
            "aperture_fstop" => l.aperture_fstop = Some(ctx.positive(key, v)?),
            "lens" => l.lens = Some(ctx.positive(key, v)?),
            "sensor_width" => l.sensor_width = Some(ctx.positive(key, v)?),
            "sensor_height" => l.sensor_height = Some(ctx.positive(key, v)?),
            "sensor_fit" => l.sensor_fit = Some(sensor_fit(key, v, ctx)?),
            "focus_distance" => l.focus_distance = Some(ctx.positive(key, v)?),
            "focus_object" => l.focus_object = Some(focus_object(key, v, ctx)?),
            "aperture_blades" => l.blades = Some(blades(key, v, ctx)?),
            "aperture_rotation" => l.rotation = Some(ctx.number(key, v)?),
            "aperture_ratio" => l.ratio = Some(ctx.positive(key, v)?),
            "aperture_vignetting" => {
                let x = ctx.number(key, v)?;
                if !(0.0..=1.0).contains(&x) {
                    return Err(ctx.err(key, v, "must be between 0 and 1"));
                }
                l.vignetting = Some(x);
            }
            "lens_prescription" => {
                l.prescription = Some(
                    super::prescription::from_value(key, v, ctx.base_dir)
                        .map_err(|(shown, why)| ctx.err(key, shown, &why))?,
                );
            }
            "aperture_image" => l.aperture_image = Some(aperture_image(key, v, ctx)?),
            k => {
                if let Some(i) = DISTORTION_KEYS.iter().position(|d| *d == k) {
                    l.distortion[i] = Some(ctx.number(key, v)?);
                }
                if let Some(i) = CHROMATIC_KEYS.iter().position(|d| *d == k) {
                    l.chromatic[i] = Some(chromatic(ctx, key, ctx.number(key, v)?)?);
                }
            }
        }
    }
    Ok(l)
}

/// Parses the draft `EXT_camera_physical` (metres) into Blender's units (mm for lens and sensor).
pub(crate) fn parse_physical(ext: Option<&Value>, ctx: &Ctx<'_>) -> Result<Layer, Error> {
    let mut l = Layer::default();
    let Some(map) = ext.and_then(Value::as_object) else {
        return Ok(l);
    };
    if let Some(v) = map.get("focalLength") {
        l.lens = Some(ctx.positive("focalLength", v)? * 1000.0);
    }
    if let Some(v) = map.get("sensorSize") {
        let pair = v
            .as_array()
            .filter(|a| a.len() == 2)
            .ok_or_else(|| ctx.err("sensorSize", v, "expected [width, height] in metres"))?;
        l.sensor_width = Some(ctx.positive("sensorSize", &pair[0])? * 1000.0);
        l.sensor_height = Some(ctx.positive("sensorSize", &pair[1])? * 1000.0);
    }
    if let Some(v) = map.get("fStop") {
        l.aperture_fstop = Some(ctx.positive("fStop", v)?);
    }
    if let Some(v) = map.get("focusDistance") {
        l.focus_distance = Some(ctx.positive("focusDistance", v)?);
    }
    Ok(l)
}

/// The command-line layer, validated like the file's values.
pub(crate) fn parse_overrides(o: &DofOverrides, ctx: &Ctx<'_>) -> Result<Layer, Error> {
    let mut l = Layer {
        use_dof: o.use_dof,
        ..Layer::default()
    };
    if let Some(r) = o.aperture_radius {
        if !r.is_finite() || r < 0.0 {
            return Err(ctx.err("aperture_radius", r, "must be a finite number >= 0"));
        }
        l.aperture_radius = Some(r);
    }
    if let Some(f) = o.aperture_fstop {
        l.aperture_fstop = Some(ctx.check_positive("aperture_fstop", f)?);
    }
    if let Some(d) = o.focus_distance {
        l.focus_distance = Some(ctx.check_positive("focus_distance", d)?);
    }
    if let Some(name) = &o.focus_object {
        l.focus_object = Some(match name.parse::<usize>() {
            Ok(i) if name.bytes().all(|b| b.is_ascii_digit()) => FocusTarget::Index(i),
            _ => FocusTarget::Name(name.clone()),
        });
    }
    if let Some(v) = o.vignetting {
        if !(0.0..=1.0).contains(&v) {
            return Err(ctx.err("aperture_vignetting", v, "must be between 0 and 1"));
        }
        l.vignetting = Some(v);
    }
    if let Some(d) = o.distortion {
        for (k, (slot, c)) in l.distortion.iter_mut().zip(d).enumerate() {
            if !c.is_finite() {
                return Err(ctx.err(DISTORTION_KEYS[k], c, "must be a finite number"));
            }
            *slot = Some(c);
        }
    }
    if let Some(path) = &o.lens_prescription {
        let shown = format!("{:?}", path.display().to_string());
        l.prescription = Some(
            super::prescription::from_file(path, &shown)
                .map_err(|(shown, why)| ctx.err("lens_prescription", shown, &why))?,
        );
    }
    if let Some(p) = &o.aperture_image {
        if p.as_os_str().is_empty() {
            return Err(ctx.err("aperture_image", "\"\"", "expected an image path"));
        }
        l.aperture_image = Some(ImageRef::File(p.clone()));
    }
    for (i, c) in [o.chromatic_lateral, o.chromatic_longitudinal]
        .into_iter()
        .enumerate()
    {
        if let Some(c) = c {
            l.chromatic[i] = Some(chromatic(ctx, CHROMATIC_KEYS[i], c)?);
        }
    }
    if l.use_dof.is_none() && (l.aperture_radius.is_some() || l.aperture_fstop.is_some()) {
        l.use_dof = Some(true);
    }
    Ok(l)
}

/// `use_dof`: Blender stores booleans of older custom properties as 0/1 integers.
fn use_dof(key: &str, v: &Value, ctx: &Ctx<'_>) -> Result<bool, Error> {
    Ok(match v {
        Value::Bool(b) => *b,
        Value::Number(n) if n.as_u64() == Some(0) => false,
        Value::Number(n) if n.as_u64() == Some(1) => true,
        _ => return Err(ctx.err(key, v, "expected true or false")),
    })
}

/// `sensor_fit`: `AUTO`, `HORIZONTAL` or `VERTICAL`, in any case.
fn sensor_fit(key: &str, v: &Value, ctx: &Ctx<'_>) -> Result<SensorFit, Error> {
    Ok(match v.as_str().map(str::to_ascii_uppercase).as_deref() {
        Some("AUTO") => SensorFit::Auto,
        Some("HORIZONTAL") => SensorFit::Horizontal,
        Some("VERTICAL") => SensorFit::Vertical,
        _ => return Err(ctx.err(key, v, "expected \"AUTO\", \"HORIZONTAL\" or \"VERTICAL\"")),
    })
}

/// `focus_object`: a node name, a node index or Blender's `{"name": ..., "type": "Object"}`.
fn focus_object(key: &str, v: &Value, ctx: &Ctx<'_>) -> Result<FocusTarget, Error> {
    Ok(match v {
        Value::String(s) => FocusTarget::Name(s.clone()),
        Value::Number(n) => FocusTarget::Index(
            n.as_u64()
                .and_then(|i| usize::try_from(i).ok())
                .ok_or_else(|| ctx.err(key, v, "a node index must be an integer >= 0"))?,
        ),
        Value::Object(o) => match o.get("name") {
            Some(Value::String(s)) => FocusTarget::Name(s.clone()),
            _ => return Err(ctx.err(key, v, "expected {\"name\": \"...\", \"type\": \"Object\"}")),
        },
        _ => return Err(ctx.err(key, v, "expected a node name, index or {\"name\": ...}")),
    })
}

/// `aperture_blades`: 0 (round) or a polygon of at least 3 blades.
fn blades(key: &str, v: &Value, ctx: &Ctx<'_>) -> Result<u32, Error> {
    let n = v
        .as_f64()
        .filter(|x| x.fract() == 0.0 && *x >= 0.0 && *x <= u32::MAX as f64)
        .ok_or_else(|| ctx.err(key, v, "expected an integer 0 or >= 3"))? as u32;
    if n == 1 || n == 2 {
        return Err(ctx.err(key, v, "a polygon needs at least 3 blades (0 = round)"));
    }
    Ok(n)
}

/// A chromatic aberration value: finite and between −0.5 and 0.5 (a channel's image or focus
/// distance stays between half and one and a half times green's).
fn chromatic(ctx: &Ctx<'_>, key: &str, x: f32) -> Result<f32, Error> {
    if !x.is_finite() || !(-0.5..=0.5).contains(&x) {
        return Err(ctx.err(key, x, "must be between -0.5 and 0.5"));
    }
    Ok(x)
}

/// `aperture_image`: a non-empty path relative to the glTF file, or a texture index.
pub(crate) fn aperture_image(key: &str, v: &Value, ctx: &Ctx<'_>) -> Result<ImageRef, Error> {
    Ok(match v {
        Value::String(s) if !s.is_empty() => ImageRef::Uri(s.clone()),
        Value::Number(n) => ImageRef::Texture(
            n.as_u64()
                .and_then(|i| usize::try_from(i).ok())
                .ok_or_else(|| ctx.err(key, v, "a texture index must be an integer >= 0"))?,
        ),
        _ => return Err(ctx.err(key, v, "expected an image path or a texture index")),
    })
}
