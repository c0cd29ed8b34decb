//! `aperture.load(path, **options)`: the command line's load options (`scene`, `variant`,
//! `time`/`frame`/`fps`, `animation`, the depth-of-field overrides, `max_memory`) and the
//! material conventions every render of the scene starts from (`transmission`,
//! `single_sided`, as `aperture render` defaults them).

use crate::errors::value_error;
use crate::options::{finite, non_negative, positive, Kwargs};
use aperture_scene::{AnimationSelection, DofOverrides, LoadOptions};
use aperture_shading::Convention;
use pyo3::prelude::*;

/// What a scene keeps of its load options for every render of it.
#[derive(Debug, Clone)]
pub(crate) struct SceneDefaults {
    /// The time the scene was loaded at (`None`: the stored pose).
    pub time: Option<f64>,
    /// Frames per second (`frame=` and motion blur).
    pub fps: f32,
    /// `transmission=` of every render unless it says otherwise.
    pub transmission: Convention,
    /// `single_sided=` of every render unless it says otherwise.
    pub single_sided: Convention,
}

/// The loader's options and the scene's defaults from `load`'s keyword options.
pub(crate) fn load_options(kw: &mut Kwargs<'_>) -> PyResult<(LoadOptions, SceneDefaults)> {
    let scene = kw.int("scene", 0, i64::from(u32::MAX))?.map(|n| n as usize);
    let (time, fps) = time_options(kw, 24.0)?;
    let animation = match kw.name_or_index("animation")? {
        None => AnimationSelection::All,
        Some(s) => match s.parse::<usize>() {
            Ok(i) => AnimationSelection::Index(i),
            Err(_) => AnimationSelection::Name(s),
        },
    };
    let variant = kw.name_or_index("variant")?;
    let memory = match kw.take("max_memory")? {
        None => aperture_budget::MemoryBudget::from_system(),
        Some(v) => {
            let bytes = match v.extract::<u64>() {
                Ok(n) => n,
                Err(_) => aperture_budget::parse_bytes(&v.extract::<String>().map_err(|_| {
                    value_error(format!(
                        "invalid max_memory = {v}: bytes (int) or e.g. \"8G\""
                    ))
                })?)
                .map_err(|e| value_error(format!("invalid max_memory: {e}")))?,
            };
            aperture_budget::MemoryBudget::fixed(bytes)
        }
    };
    let options = LoadOptions {
        scene,
        dof_overrides: dof_overrides(kw)?,
        skip_textures: false,
        variant,
        time: time.map(|t| t as f32),
        animation,
        memory,
    };
    let defaults = SceneDefaults {
        time,
        fps,
        transmission: kw.convention("transmission")?.unwrap_or_default(),
        single_sided: kw.convention("single_sided")?.unwrap_or_default(),
    };
    Ok((options, defaults))
}

/// `time=` (seconds) or `frame=` (Blender's frame N at `fps`), and `fps=` (else `default_fps`).
pub(crate) fn time_options(kw: &mut Kwargs<'_>, default_fps: f32) -> PyResult<(Option<f64>, f32)> {
    let fps = kw.float("fps", positive, "must be finite and > 0")?;
    let fps = match fps {
        Some(f) => f as f32,
        None => default_fps,
    };
    let time = kw.float("time", finite, "must be finite")?;
    let frame = kw.int("frame", i64::from(i32::MIN), i64::from(i32::MAX))?;
    match (time, frame) {
        (Some(_), Some(_)) => Err(value_error("time and frame cannot both be given")),
        (Some(t), None) => Ok((Some(f64::from(t as f32)), fps)),
        // As the command line: N / fps, in f32 seconds.
        (None, Some(n)) => Ok((Some(f64::from((n as f64 / f64::from(fps)) as f32)), fps)),
        (None, None) => Ok((None, fps)),
    }
}

/// `aperture_radius=`, `fstop=`, `focus_distance=`, `focus_object=`, `no_dof=`.
fn dof_overrides(kw: &mut Kwargs<'_>) -> PyResult<DofOverrides> {
    let radius = kw.float("aperture_radius", non_negative, "must be finite and ≥ 0")?;
    let fstop = kw.float("fstop", positive, "must be finite and > 0")?;
    let focus = kw.float("focus_distance", positive, "must be finite and > 0")?;
    let object = kw.name_or_index("focus_object")?;
    let no_dof = kw.flag("no_dof")?.unwrap_or(false);
    if radius.is_some() && fstop.is_some() {
        return Err(value_error(
            "aperture_radius and fstop cannot both be given",
        ));
    }
    if no_dof && (radius.is_some() || fstop.is_some()) {
        return Err(value_error(
            "no_dof cannot be given with aperture_radius or fstop",
        ));
    }
    if focus.is_some() && object.is_some() {
        return Err(value_error(
            "focus_distance and focus_object cannot both be given",
        ));
    }
    Ok(DofOverrides {
        use_dof: no_dof.then_some(false),
        aperture_radius: radius.map(|r| r as f32),
        aperture_fstop: fstop.map(|f| f as f32),
        focus_distance: focus.map(|d| d as f32),
        focus_object: object,
        ..DofOverrides::default()
    })
}
