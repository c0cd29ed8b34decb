//! Blender's motion-blur settings as the add-on writes them in `scenes[i].extras` (SPEC §7):
//! read and checked here, resolved against the command line by the renderer.

use serde_json::Value;

use crate::error::Error;

/// Where the shutter interval sits around the frame (Blender's `motion_blur_position`;
/// `--shutter-position`, where the first paragraph of each value's comment is its help).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ShutterPosition {
    /// The shutter opens at the frame.
    Start,
    /// Centred on the frame.
    ///
    /// Blender's default.
    #[default]
    Center,
    /// The shutter closes at the frame.
    End,
}

impl ShutterPosition {
    /// Parses Blender's names (`START`, `CENTER`, `END`), case-insensitively.
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_uppercase().as_str() {
            "START" => Some(Self::Start),
            "CENTER" | "CENTRE" => Some(Self::Center),
            "END" => Some(Self::End),
            _ => None,
        }
    }
}

/// Blender/Cycles' `rolling_shutter_type`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RollingShutter {
    /// Every row sees the whole interval.
    #[default]
    None,
    /// Rows open one after another from the top.
    Top,
}

/// The motion-blur keys of the selected scene's `extras`; `None` where the file says nothing.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotionExtras {
    /// `use_motion_blur`.
    pub use_motion_blur: Option<bool>,
    /// `motion_blur_shutter`, frames (> 0).
    pub shutter: Option<f32>,
    /// `motion_blur_position`.
    pub position: Option<ShutterPosition>,
    /// `rolling_shutter_type`.
    pub rolling: Option<RollingShutter>,
    /// `rolling_shutter_duration`, a fraction of the shutter in `[0, 1]`.
    pub rolling_duration: Option<f32>,
    /// `fps` (Blender's fps / fps_base, > 0).
    pub fps: Option<f32>,
    /// `frame_current`.
    pub frame_current: Option<i64>,
}

impl MotionExtras {
    /// Reads the keys of `extras` (the `extras` of `scenes[scene]`); unknown keys are ignored,
    /// a known one of the wrong type or out of range is an error naming scene, key and value.
    pub fn parse(scene: usize, extras: Option<&Value>) -> Result<Self, Error> {
        let Some(map) = extras.and_then(Value::as_object) else {
            return Ok(Self::default());
        };
        let bad = |key: &str, v: &Value, reason: &str| Error::InvalidSceneExtra {
            scene,
            key: key.to_owned(),
            value: v.to_string(),
            reason: reason.to_owned(),
        };
        let number = |key: &str, ok: &dyn Fn(f64) -> bool, why: &str| match map.get(key) {
            None => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() && ok(x) => Ok(Some(x as f32)),
                _ => Err(bad(key, v, why)),
            },
        };
        let use_motion_blur = match map.get("use_motion_blur") {
            None => None,
            // Blender's IDProperties store booleans as 0/1 integers in older exports.
            Some(v) => Some(
                v.as_bool()
                    .or_else(|| v.as_i64().filter(|i| *i == 0 || *i == 1).map(|i| i == 1))
                    .ok_or_else(|| bad("use_motion_blur", v, "expected true or false"))?,
            ),
        };
        let position =
            match map.get("motion_blur_position") {
                None => None,
                Some(v) => Some(v.as_str().and_then(ShutterPosition::parse).ok_or_else(|| {
                    bad("motion_blur_position", v, "expected START, CENTER or END")
                })?),
            };
        let rolling = match map.get("rolling_shutter_type") {
            None => None,
            Some(v) => Some(match v.as_str().map(str::to_ascii_uppercase).as_deref() {
                Some("NONE") => RollingShutter::None,
                Some("TOP") => RollingShutter::Top,
                _ => return Err(bad("rolling_shutter_type", v, "expected NONE or TOP")),
            }),
        };
        let frame_current = match map.get("frame_current") {
            None => None,
            Some(v) => Some(
                v.as_i64()
                    .ok_or_else(|| bad("frame_current", v, "expected a whole frame number"))?,
            ),
        };
        Ok(Self {
            use_motion_blur,
            shutter: number("motion_blur_shutter", &|x| x > 0.0, "must be a number > 0")?,
            position,
            rolling,
            rolling_duration: number(
                "rolling_shutter_duration",
                &|x| (0.0..=1.0).contains(&x),
                "must be a number in [0, 1]",
            )?,
            fps: number("fps", &|x| x > 0.0, "must be a number > 0")?,
            frame_current,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn keys_are_read_and_checked() {
        let e = json!({
            "use_motion_blur": true, "motion_blur_shutter": 0.25,
            "motion_blur_position": "START", "rolling_shutter_type": "TOP",
            "rolling_shutter_duration": 0.1, "fps": 30.0, "frame_current": 7, "other": 1
        });
        let m = MotionExtras::parse(0, Some(&e)).unwrap();
        assert_eq!(m.use_motion_blur, Some(true));
        assert_eq!(m.shutter, Some(0.25));
        assert_eq!(m.position, Some(ShutterPosition::Start));
        assert_eq!(m.rolling, Some(RollingShutter::Top));
        assert_eq!(m.rolling_duration, Some(0.1));
        assert_eq!(m.fps, Some(30.0));
        assert_eq!(m.frame_current, Some(7));
        assert_eq!(
            MotionExtras::parse(0, None).unwrap(),
            MotionExtras::default()
        );
        for (key, v) in [
            ("motion_blur_shutter", json!(-1)),
            ("motion_blur_shutter", json!("x")),
            ("motion_blur_position", json!("MIDDLE")),
            ("rolling_shutter_duration", json!(2)),
            ("use_motion_blur", json!("yes")),
            ("fps", json!(0)),
        ] {
            let err = MotionExtras::parse(2, Some(&json!({ key: v }))).unwrap_err();
            let text = err.to_string();
            assert!(text.contains("scenes[2]") && text.contains(key), "{text}");
        }
    }
}
