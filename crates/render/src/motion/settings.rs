//! Whether a render has motion blur and with which shutter: the file's `scenes[i].extras`
//! (SPEC §7), overridden by the command line.

use super::shutter::{RollingShutter, Shutter, ShutterPosition};
use aperture_scene::MotionExtras;

/// Motion steps when neither the file nor the command line says: open, middle and close.
pub const DEFAULT_MOTION_STEPS: u32 = 3;

/// The most motion steps a render takes (each is a pose of the scene).
pub const MAX_MOTION_STEPS: u32 = 64;

/// What the command line says of motion blur; `None` where it says nothing.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotionOverrides {
    /// `--motion-blur` (true) or `--no-motion-blur` (false).
    pub enabled: Option<bool>,
    /// `--shutter FRAMES`.
    pub shutter: Option<f32>,
    /// `--shutter-position`.
    pub position: Option<ShutterPosition>,
    /// `--motion-steps N`.
    pub steps: Option<u32>,
}

/// The resolved settings: the shutter when motion blur is on, and the motion steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSettings {
    /// `None`: motion blur off (every sample at the frame's instant).
    pub shutter: Option<Shutter>,
    /// Poses over the shutter (≥ 2) for what moves: keys interpolated per ray.
    pub steps: u32,
}

impl MotionSettings {
    /// The file's keys under the command line's: off unless one of them turns it on.
    pub fn resolve(file: &MotionExtras, cli: &MotionOverrides) -> Self {
        let on = cli.enabled.or(file.use_motion_blur).unwrap_or(false);
        let rolling = match file.rolling.unwrap_or_default() {
            RollingShutter::None => None,
            RollingShutter::Top => Some(file.rolling_duration.unwrap_or(0.1)),
        };
        let shutter = on.then(|| Shutter {
            frames: cli
                .shutter
                .or(file.shutter)
                .unwrap_or(super::shutter::DEFAULT_SHUTTER_FRAMES),
            position: cli.position.or(file.position).unwrap_or_default(),
            rolling,
        });
        Self {
            shutter,
            steps: cli
                .steps
                .unwrap_or(DEFAULT_MOTION_STEPS)
                .clamp(2, MAX_MOTION_STEPS),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_wins_and_off_is_the_default() {
        let none = MotionSettings::resolve(&MotionExtras::default(), &MotionOverrides::default());
        assert_eq!(none.shutter, None);
        let file = MotionExtras {
            use_motion_blur: Some(true),
            shutter: Some(0.25),
            position: Some(ShutterPosition::End),
            ..MotionExtras::default()
        };
        let s = MotionSettings::resolve(&file, &MotionOverrides::default());
        assert_eq!(
            s.shutter.map(|s| (s.frames, s.position)),
            Some((0.25, ShutterPosition::End))
        );
        let cli = MotionOverrides {
            shutter: Some(1.0),
            steps: Some(5),
            ..MotionOverrides::default()
        };
        let s = MotionSettings::resolve(&file, &cli);
        assert_eq!((s.shutter.map(|s| s.frames), s.steps), (Some(1.0), 5));
        let off = MotionOverrides {
            enabled: Some(false),
            ..MotionOverrides::default()
        };
        assert_eq!(MotionSettings::resolve(&file, &off).shutter, None);
    }
}
