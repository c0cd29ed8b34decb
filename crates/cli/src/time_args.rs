//! `--time`, `--frame`, `--fps` and `--animation` (SPEC §7), shared by `render` and `info`.

use crate::number_args::{finite_f32, positive_f32};
use aperture_scene::AnimationSelection;

/// When to pose the scene, and which animations to play.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct TimeArgs {
    /// Pose the scene at this time, in seconds (every selected animation evaluated) [default:
    /// the pose stored in the file].
    #[arg(long, value_parser = finite_f32, allow_hyphen_values = true, conflicts_with = "frame")]
    pub time: Option<f32>,
    /// Pose the scene at Blender's frame N: time N / fps, as Blender's glTF exporter writes it.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub frame: Option<i64>,
    /// Frames per second for --frame and --frames (Blender's default 24).
    #[arg(long, default_value_t = 24.0, value_parser = positive_f32)]
    pub fps: f32,
    /// Play only this animation (its name, or its index in the file) [default: all together, as
    /// Blender's timeline plays every object's action].
    #[arg(long, value_name = "NAME|INDEX")]
    pub animation: Option<String>,
}

impl TimeArgs {
    /// The time in seconds (`None`: the stored pose).
    pub fn seconds(&self) -> Option<f32> {
        match (self.time, self.frame) {
            (Some(t), _) => Some(t),
            (None, Some(n)) => Some((n as f64 / f64::from(self.fps)) as f32),
            (None, None) => None,
        }
    }

    /// The animation selection: digits name an index, anything else a name.
    pub fn selection(&self) -> AnimationSelection {
        match &self.animation {
            None => AnimationSelection::All,
            Some(s) => match s.parse::<usize>() {
                Ok(i) => AnimationSelection::Index(i),
                Err(_) => AnimationSelection::Name(s.clone()),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_blender_frames_over_fps() {
        let t = TimeArgs {
            frame: Some(12),
            fps: 24.0,
            ..TimeArgs::default()
        };
        assert_eq!(t.seconds(), Some(0.5));
        let t = TimeArgs {
            time: Some(1.25),
            ..TimeArgs::default()
        };
        assert_eq!(t.seconds(), Some(1.25));
        assert_eq!(TimeArgs::default().seconds(), None);
        let named = TimeArgs {
            animation: Some("Walk".into()),
            ..TimeArgs::default()
        };
        assert_eq!(named.selection(), AnimationSelection::Name("Walk".into()));
        let index = TimeArgs {
            animation: Some("2".into()),
            ..TimeArgs::default()
        };
        assert_eq!(index.selection(), AnimationSelection::Index(2));
    }
}
